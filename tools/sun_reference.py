"""Writes tests/data/sun/pvlib_spa.csv: reference sun positions from pvlib's own
implementation of NREL's SPA (pvlib.spa.solar_position, numpy mode), which
tests/sun_position.rs compares brume's implementation against.

    pip install pvlib && python3 tools/sun_reference.py > tests/data/sun/pvlib_spa.csv

Places and times are drawn with a fixed seed: latitudes in [-89, 89], longitudes in
[-180, 180], altitudes in [0, 4000] m, pressure 600-1050 hPa, temperature -30..40 C,
instants uniform over 2000-01-01 .. 2100-12-31 UTC (whole seconds). ΔT comes from
pvlib.spa.calculate_deltat (Espenak & Meeus) and is written out, so the test checks
the position algorithm and the ΔT estimate separately.
"""
import datetime as dt
import sys

import numpy as np
import pvlib
import pvlib.spa as spa

ROWS = 400
rng = np.random.default_rng(20040101)
t0 = dt.datetime(2000, 1, 1, tzinfo=dt.timezone.utc).timestamp()
t1 = dt.datetime(2101, 1, 1, tzinfo=dt.timezone.utc).timestamp()

print(f"# pvlib {pvlib.__version__}, tools/sun_reference.py, seed 20040101")
print("time,latitude_deg,longitude_deg,altitude_m,pressure_hpa,temperature_c,"
      "delta_t_s,zenith_deg,apparent_zenith_deg,azimuth_deg")
for _ in range(ROWS):
    unix = float(np.floor(rng.uniform(t0, t1)))
    lat = round(float(rng.uniform(-89, 89)), 4)
    lon = round(float(rng.uniform(-180, 180)), 4)
    elev = round(float(rng.uniform(0, 4000)), 1)
    pressure = round(float(rng.uniform(600, 1050)), 1)
    temp = round(float(rng.uniform(-30, 40)), 1)
    when = dt.datetime.fromtimestamp(unix, dt.timezone.utc)
    delta_t = float(spa.calculate_deltat(np.array([when.year]), np.array([when.month]))[0])
    out = spa.solar_position(np.array([unix]), lat, lon, elev, pressure, temp,
                             delta_t, 0.5667, sst=False, esd=False)
    theta, theta0, azimuth = out[0][0], out[1][0], out[4][0]
    print(f"{when.strftime('%Y-%m-%dT%H:%M:%SZ')},{lat},{lon},{elev},{pressure},{temp},"
          f"{delta_t:.6f},{theta0:.10f},{theta:.10f},{azimuth:.10f}")
