"""Tests of the engine fogs (brume.distance_fog, brume.layered_fog with brume.Camera and
brume.MatrixCamera), of brume.aerial, brume.turbidity_from_sky and brume.render_sky:
equality with the `brume scene`, `brume render --medium aerial`, `brume turbidity` and
`brume sky` programs, an engine's
matrices written out in numpy, and the errors."""

import json
import math
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pytest

import brume
from shared import assert_threads_match_serial, brume_bin, sky_over_ground

SIZE = (96, 64)  # W, H: small, llvmpipe on 2 cores
CAMERA = dict(position=(0.0, 1.7, 0.0), yaw_deg=20.0, pitch_deg=-3.0, fov_y_deg=60.0,
              near=0.1, far=1000.0)  # fmt: skip




def read_pfm(path):
    """A PFM file (colour `PF` or grey `Pf`) as float32, row 0 at the top."""
    data = Path(path).read_bytes()
    header, rest = [], data
    while len(header) < 3:
        line, rest = rest.split(b"\n", 1)
        header.append(line.decode())
    channels = 3 if header[0] == "PF" else 1
    width, height = map(int, header[1].split())
    endian = "<" if float(header[2]) < 0 else ">"
    pixels = np.frombuffer(rest, dtype=endian + "f4", count=width * height * channels)
    shape = (height, width, 3) if channels == 3 else (height, width)
    return np.flipud(pixels.reshape(shape)).astype(np.float32)  # PFM is bottom row first


def srgb_to_linear(c):
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb8(v):
    v = np.clip(np.asarray(v, dtype=np.float64), 0.0, 1.0)
    s = np.where(v <= 0.0031308, v * 12.92, 1.055 * v ** (1 / 2.4) - 0.055)
    return np.round(s * 255.0).astype(np.int32)


def camera_flags(camera):
    x, y, z = camera["position"]
    return [
        "--size", f"{SIZE[0]}x{SIZE[1]}", f"--position={x},{y},{z}",
        f"--yaw={camera['yaw_deg']}", f"--pitch={camera['pitch_deg']}",
        f"--fov={camera['fov_y_deg']}", f"--near={camera['near']}", f"--far={camera['far']}",
    ]  # fmt: skip


def scene(tmp_path, name, flags, time=0.0):
    """Runs `brume scene` with the test camera, returns the path of its --out."""
    out = tmp_path / name
    cmd = [str(brume_bin()), "scene", *camera_flags(CAMERA), f"--time={time}", *flags,
           "--out", str(out)]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True)
    return out


def clear_frame(tmp_path, time=0.0):
    """The fog-free frame (linear float, as rendered) and its depth buffer."""
    colour = scene(tmp_path, f"clear_{time}.pfm", ["--fog", "none", "--depth-out",
                   str(tmp_path / f"depth_{time}.pfm")], time)  # fmt: skip
    return read_pfm(colour), read_pfm(tmp_path / f"depth_{time}.pfm")


def png(path):
    Image = pytest.importorskip("PIL.Image")
    return np.asarray(Image.open(path).convert("RGB")).astype(np.int32)


# --- equality with `brume scene` -------------------------------------------------------


@pytest.mark.parametrize(
    "profile, blur, flags, kwargs",
    [
        ("exponential", "diffusion", ["--density", "0.03"], dict(density=0.03)),
        ("band", "none", ["--thickness", "8", "--base", "-1"], dict(thickness=8.0, base=-1.0)),
        ("ramp", "gauss-separate", ["--top", "2.5"], dict(top=2.5)),
    ],
)
def test_layered_fog_equals_brume_scene(tmp_path, profile, blur, flags, kwargs):
    colour, depth = clear_frame(tmp_path)
    assert colour.shape == (SIZE[1], SIZE[0], 3) and depth.shape == (SIZE[1], SIZE[0])
    assert 0.0 <= depth.min() and depth.max() <= 1.0
    ref = scene(tmp_path, "layered.png",
                ["--fog", "layered", "--profile", profile, "--blur", blur, *flags])  # fmt: skip
    camera = brume.Camera(**CAMERA)
    ours = brume.layered_fog(colour, depth, camera=camera, profile=profile, blur=blur, **kwargs)
    assert ours.dtype == np.float32 and ours.shape == colour.shape
    diff = np.abs(linear_to_srgb8(ours) - png(ref))
    assert diff.max() <= 1, (diff.max(), np.argwhere(diff > 1)[:5])
    # The fog did something the comparison could have missed.
    assert np.abs(linear_to_srgb8(ours) - linear_to_srgb8(colour)).max() > 20


@pytest.mark.parametrize(
    "blur, time, flags, kwargs",
    [
        ("diffusion", 0.0, [], dict()),
        ("gauss-single", 1.5, ["--noise-colour-strength", "0.3", "--noise-seed", "3"],
         dict(noise_colour_strength=0.3, noise_seed=3)),
        ("none", 4.0, ["--fog-start", "5", "--max-density", "0.7", "--noise", "none"],
         dict(start_distance=5.0, max_density=0.7, noise="none")),
    ],
)  # fmt: skip
def test_distance_fog_equals_brume_scene(tmp_path, blur, time, flags, kwargs):
    colour, depth = clear_frame(tmp_path, time)
    # The scene's light is its sun; the library's default light is another direction.
    light = ["--light-dir", "0.3,0.2,-1"]
    ref = scene(tmp_path, "distance.png", ["--fog", "distance", "--blur", blur, *light, *flags],
                time)  # fmt: skip
    renderer = brume.Renderer()
    ours = renderer.distance_fog(colour, depth, camera=brume.Camera(**CAMERA), time=time,
                                 blur=blur, **kwargs)  # fmt: skip
    diff = np.abs(linear_to_srgb8(ours) - png(ref))
    assert diff.max() <= 1, (diff.max(), np.argwhere(diff > 1)[:5])
    assert np.abs(linear_to_srgb8(ours) - linear_to_srgb8(colour)).max() > 20


def test_a_float16_depth_buffer_reads_as_its_float32_values(tmp_path):
    colour, depth = clear_frame(tmp_path)
    camera = brume.Camera(**CAMERA)
    half = depth.astype(np.float16)
    np.testing.assert_array_equal(
        brume.distance_fog(colour, half, camera=camera, blur="none"),
        brume.distance_fog(colour, half.astype(np.float32), camera=camera, blur="none"),
    )


def test_distance_noise_keywords(tmp_path):
    colour, depth = clear_frame(tmp_path)
    camera = brume.Camera(**CAMERA)
    kw = dict(blur="none", max_density=0.8)
    default = brume.distance_fog(colour, depth, camera=camera, **kw)
    np.testing.assert_array_equal(
        default, brume.distance_fog(colour, depth, camera=camera, noise="generated", **kw)
    )
    off = brume.distance_fog(colour, depth, camera=camera, noise="none", **kw)
    np.testing.assert_array_equal(
        off, brume.distance_fog(colour, depth, camera=camera, noise=False, **kw)
    )
    assert not np.array_equal(default, off)
    later = brume.distance_fog(colour, depth, camera=camera, time=30.0, **kw)
    assert not np.array_equal(default, later)  # the noise drifts with time
    np.testing.assert_array_equal(
        off, brume.distance_fog(colour, depth, camera=camera, noise="none", time=30.0, **kw)
    )


def test_one_colour_value_is_a_grey(tmp_path):
    colour, depth = clear_frame(tmp_path)
    camera = brume.Camera(**CAMERA)
    for fog, kw in ((brume.distance_fog, dict(noise="none")), (brume.layered_fog, dict())):
        grey = fog(colour, depth, camera=camera, blur="none", colour=0.6, **kw)
        np.testing.assert_array_equal(
            grey, fog(colour, depth, camera=camera, blur="none", colour=[0.6] * 3, **kw)
        )


def test_uint8_frame_is_the_float_path_encoded(tmp_path):
    colour, depth = clear_frame(tmp_path)
    camera = brume.Camera(**CAMERA)
    frame8 = linear_to_srgb8(colour).astype(np.uint8)
    out8 = brume.layered_fog(frame8, depth, camera=camera, blur="none")
    assert out8.dtype == np.uint8
    out32 = brume.layered_fog(srgb_to_linear(frame8 / 255.0).astype(np.float32), depth,
                              camera=camera, blur="none")  # fmt: skip
    assert np.abs(out8.astype(np.int32) - linear_to_srgb8(out32)).max() <= 1


# --- an engine's matrices --------------------------------------------------------------


def view_matrix(position, yaw_deg, pitch_deg):
    """World to eye, right-handed, y up (gluLookAt along the camera's forward)."""
    yaw, pitch = np.radians(yaw_deg), np.radians(pitch_deg)
    f = np.array([np.sin(yaw) * np.cos(pitch), np.sin(pitch), -np.cos(yaw) * np.cos(pitch)])
    s = np.cross(f, [0.0, 1.0, 0.0])
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    eye = np.asarray(position, dtype=np.float64)
    return np.array([
        [*s, -s @ eye],
        [*u, -u @ eye],
        [*-f, f @ eye],
        [0.0, 0.0, 0.0, 1.0],
    ])  # fmt: skip


def gl_projection(fov_y_deg, aspect, near, far):
    """gluPerspective: clip z in [-w, w]."""
    t = 1.0 / np.tan(np.radians(fov_y_deg) / 2.0)
    return np.array([
        [t / aspect, 0.0, 0.0, 0.0],
        [0.0, t, 0.0, 0.0],
        [0.0, 0.0, (far + near) / (near - far), 2.0 * far * near / (near - far)],
        [0.0, 0.0, -1.0, 0.0],
    ])  # fmt: skip


def test_matrix_camera_equals_camera(tmp_path):
    colour, depth = clear_frame(tmp_path)
    c = CAMERA
    view = view_matrix(c["position"], c["yaw_deg"], c["pitch_deg"])
    projection = gl_projection(c["fov_y_deg"], SIZE[0] / SIZE[1], c["near"], c["far"])
    # The matrices put a world point where brume's camera sees it: 50 m along the view.
    yaw, pitch = np.radians(c["yaw_deg"]), np.radians(c["pitch_deg"])
    ahead = np.array([np.sin(yaw) * np.cos(pitch), np.sin(pitch), -np.cos(yaw) * np.cos(pitch)])
    eye_point = view @ np.array([*(np.array(c["position"]) + 50.0 * ahead), 1.0])
    np.testing.assert_allclose(eye_point[:3], [0.0, 0.0, -50.0], atol=1e-9)

    by_camera = brume.Camera(**CAMERA)
    by_matrices = brume.MatrixCamera(view, projection, clip="minus_one_to_one")
    assert by_matrices.near == pytest.approx(0.1) and by_matrices.far == pytest.approx(1000.0)
    assert not by_matrices.reversed
    for fog, kwargs in [
        (brume.layered_fog, dict(blur="none", density=0.03)),
        (brume.distance_fog, dict(blur="gauss-single", time=2.0)),
    ]:
        a = fog(colour, depth, camera=by_camera, **kwargs)
        b = fog(colour, depth, camera=by_matrices, **kwargs)
        assert np.abs(a - b).max() <= 1.0 / 255.0
        assert np.abs(linear_to_srgb8(a) - linear_to_srgb8(b)).max() <= 1

    # A column-major engine matrix (GLM's value_ptr, glam's to_cols_array) flattened to
    # 16 numbers maps by order='F', as the docstring says.
    view_cols, projection_cols = view.T.ravel(), projection.T.ravel()
    from_cols = brume.MatrixCamera(view_cols.reshape(4, 4, order="F"),
                                   projection_cols.reshape(4, 4, order="F"))  # fmt: skip
    kwargs = dict(blur="none", density=0.03)
    np.testing.assert_array_equal(
        brume.layered_fog(colour, depth, camera=from_cols, **kwargs),
        brume.layered_fog(colour, depth, camera=by_matrices, **kwargs),
    )
    # Read row by row unchanged, the view has its translation in the last row: refused,
    # naming the fix.
    with pytest.raises(ValueError, match="view: last row .* order='F'"):
        brume.MatrixCamera(view_cols.reshape(4, 4), projection)
    # The transposed projection alone is another (valid-looking) projection: another image.
    wrong = brume.MatrixCamera(view, projection_cols.reshape(4, 4))
    assert np.abs(
        brume.layered_fog(colour, depth, camera=wrong, **kwargs)
        - brume.layered_fog(colour, depth, camera=by_matrices, **kwargs)
    ).max() > 10.0 / 255.0

    # The same depth buffer described by a zero-to-one projection: clip z' = (z + w)/2.
    zero_to_one = projection.copy()
    zero_to_one[2] = 0.5 * (projection[2] + projection[3])
    z01 = brume.MatrixCamera(view, zero_to_one, clip="zero_to_one")
    np.testing.assert_allclose(
        brume.layered_fog(colour, depth, camera=z01, **kwargs),
        brume.layered_fog(colour, depth, camera=by_matrices, **kwargs),
        atol=1.0 / 255.0,
    )


def test_table_profile_from_array_and_csv(tmp_path):
    colour, depth = clear_frame(tmp_path)
    camera = brume.Camera(**CAMERA)
    rows = np.array([[0.0, 0.0], [1.0, 0.02], [6.0, 0.05], [30.0, 0.0]])
    csv = tmp_path / "profile.csv"
    csv.write_text("height_m,extinction_per_m\n" + "".join(f"{h},{k}\n" for h, k in rows))
    a = brume.layered_fog(colour, depth, camera=camera, profile="table", table=rows, blur="none")
    b = brume.layered_fog(colour, depth, camera=camera, profile="table", table=str(csv),
                          blur="none")  # fmt: skip
    np.testing.assert_array_equal(a, b)
    assert np.abs(a - colour).max() > 0.05


# --- aerial perspective: equality with `brume render --medium aerial` ------------------


@pytest.fixture(scope="module")
def photo():
    h, w = 48, 64
    rng = np.random.default_rng(7)
    y, x = np.mgrid[0:h, 0:w]
    base = np.stack([x / w, y / h, 0.5 + 0.3 * np.sin(x / 5.0)], axis=-1)
    image = np.clip((base * 0.7 + rng.random((h, w, 3)) * 0.2) * 255, 0, 255).astype(np.uint8)
    # 200 m at the left to 6 km at the right.
    range_m = (200.0 + 5800.0 * x / (w - 1) + 5.0 * y).astype(np.float32)
    return image, range_m


@pytest.mark.parametrize(
    "flags, kwargs",
    [
        (["--fov", "50", "--pitch", "2", "--refine", "none"],
         dict(fov_y_deg=50.0, pitch_deg=2.0, refine="none")),
        (["--fov", "50", "--blur", "none", "--refine", "none", "--from-turbidity", "2",
          "--retarget", "radiance", "--airlight", "0.6,0.65,0.7"],
         dict(fov_y_deg=50.0, blur=False, refine="none", from_turbidity=2.0,
              retarget="radiance", airlight=(0.6, 0.65, 0.7))),
        (["--focal", "60", "--horizon-row", "20", "--refine", "repair", "--altitude", "800",
          "--horizon-sectors", "1"],
         dict(focal_px=60.0, horizon_row=20.0, refine="repair", altitude_m=800.0,
              horizon_sectors=1)),
    ],
)  # fmt: skip
def test_aerial_equals_brume_render(tmp_path, photo, flags, kwargs):
    Image = pytest.importorskip("PIL.Image")
    image, range_m = photo
    Image.fromarray(image).save(tmp_path / "image.png")
    np.save(tmp_path / "range.npy", range_m)
    turbidity = 4.0
    cmd = [
        str(brume_bin()), "render", "--image", str(tmp_path / "image.png"),
        "--depth", str(tmp_path / "range.npy"), "--depth-kind", "range", "--depth-scale", "1",
        "--medium", "aerial", "--turbidity", str(turbidity), *flags,
        "--out", str(tmp_path / "cli.png"),
    ]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True)
    cli = png(tmp_path / "cli.png")
    ours = brume.aerial(image, range_m, turbidity=turbidity, **kwargs)
    assert ours.dtype == np.uint8 and ours.shape == image.shape
    diff = np.abs(ours.astype(np.int32) - cli)
    assert diff.max() <= 1, (diff.max(), np.argwhere(diff > 1)[:5])
    # The far right is veiled: it moved away from the photo.
    assert np.abs(ours[:, -8:].astype(int) - image[:, -8:].astype(int)).mean() > 10


def test_aerial_info_gives_the_labels_the_render_used(photo):
    """return_info: without blur the image is J·t + A·(1 - t) per channel with the labels reported
    (the medium's CPU side against the GPU's render); J is the photo, or with
    from_turbidity the photo with its own haze removed."""
    image, range_m = photo
    linear = srgb_to_linear(image / 255.0).astype(np.float32)
    kw = dict(turbidity=4.0, fov_y_deg=50.0, pitch_deg=2.0, blur=False, refine="none")
    for extra in (dict(), dict(from_turbidity=2.0)):
        out, info = brume.aerial(linear, range_m, return_info=True, **kw, **extra)
        assert set(info) == {"clear", "transmittance", "airlight", "turbidity", "sigma_max_px"}
        j, t, a = info["clear"], info["transmittance"], info["airlight"]
        assert j.shape == t.shape == a.shape == linear.shape and t.dtype == np.float32
        assert 0.0 < t.min() and t.max() <= 1.0 and (a > 0.0).all()
        # Bluer light is attenuated more, and the far right more than the near left.
        assert (t[..., 2] <= t[..., 0] + 1e-6).all()
        assert t[:, -1].mean() < t[:, 0].mean()
        np.testing.assert_allclose(out, j * t + a * (1.0 - t), atol=1e-5)
        if extra:
            assert np.abs(j - linear).max() > 0.01
        else:
            np.testing.assert_allclose(j, linear, atol=1e-6)
        assert info["turbidity"] == 4.0
    np.testing.assert_array_equal(out, brume.aerial(linear, range_m, **kw, from_turbidity=2.0))


def test_aerial_masks(tmp_path, photo):
    """The masks as brume.fog takes them: the hood of an ego mask is left as it was (no
    blur), and a sky mask gives the same pixels as `render --medium aerial --sky-mask`."""
    Image = pytest.importorskip("PIL.Image")
    image, range_m = photo
    h, w = range_m.shape
    linear = srgb_to_linear(image / 255.0).astype(np.float32)
    ego = np.zeros((h, w), bool)
    ego[-6:, 40:60] = True  # under the far right, which the veil covers most
    kw = dict(turbidity=4.0, fov_y_deg=50.0, blur=False, refine="none")
    out = brume.aerial(linear, range_m, ego_mask=ego, **kw)
    np.testing.assert_allclose(out[ego], linear[ego], atol=1e-6)
    assert np.abs(out[~ego] - linear[~ego]).max() > 0.1
    sky = np.zeros((h, w), np.uint8)
    sky[:8] = 1
    Image.fromarray(image).save(tmp_path / "image.png")
    Image.fromarray(sky * 255).save(tmp_path / "sky.png")
    np.save(tmp_path / "range.npy", range_m)
    cmd = [
        str(brume_bin()), "render", "--image", str(tmp_path / "image.png"),
        "--depth", str(tmp_path / "range.npy"), "--depth-kind", "range", "--depth-scale", "1",
        "--medium", "aerial", "--turbidity", "4", "--fov", "50", "--refine", "none",
        "--sky-mask", str(tmp_path / "sky.png"), "--out", str(tmp_path / "cli.png"),
    ]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True)
    ours = brume.aerial(image, range_m, turbidity=4.0, fov_y_deg=50.0, refine="none", sky_mask=sky)
    assert np.abs(ours.astype(np.int32) - png(tmp_path / "cli.png")).max() <= 1
    with pytest.raises(ValueError, match="ego_mask: .*shape"):
        brume.aerial(image, range_m, ego_mask=ego[:, :10], **kw)


def test_aerial_finds_a_monocular_models_sky_with_monocular():
    """monocular=True as brume.fog takes it: a sky at a small positive disparity is found
    in the far tail, and veiled as the same range with the sky unknown; without, it is a
    surface some 150 m away."""
    h, w = 48, 64
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    eye = 2.0 + 0.5 * x + 0.1 * y
    image, disparity = sky_over_ground(eye, 0.006 + 0.00002 * np.arange(w))
    range_m, _ = brume.range_from_depth(disparity, kind="inverse", fov_y_deg=50.0)
    unknown_sky = range_m.copy()
    unknown_sky[:12] = np.nan
    kw = dict(turbidity=6.0, fov_y_deg=50.0, refine="none")
    want = brume.aerial(image, unknown_sky, **kw)
    got = brume.aerial(image, range_m, monocular=True, **kw)
    assert np.abs(got.astype(int) - want.astype(int)).max() <= 1
    plain = brume.aerial(image, range_m, **kw)
    assert np.abs(plain.astype(int) - want.astype(int)).max() > 8
    renderer = brume.Renderer()
    np.testing.assert_array_equal(renderer.aerial(image, range_m, monocular=True, **kw), got)


def test_aerial_turbidity_thickens_the_veil(photo):
    image, range_m = photo
    linear = srgb_to_linear(image / 255.0).astype(np.float32)
    kw = dict(fov_y_deg=50.0, blur=False, refine="none", airlight=(0.7, 0.75, 0.8))
    clear, hazy = (brume.aerial(linear, range_m, turbidity=t, **kw) for t in (2.0, 8.0))
    # Far pixels approach the airlight more at the higher turbidity.
    far = range_m > 4000
    air = np.array([0.7, 0.75, 0.8])
    assert np.abs(hazy[far] - air).mean() < np.abs(clear[far] - air).mean()


def test_a_sequence_of_turbidities_gives_one_output_each(photo):
    """turbidity=[...]: one output each (with its labels), from one pre-processing and
    refinement, each equal to the call with that turbidity alone, the capture's noise
    included; a one-element list is a list, a number is not."""
    image, range_m = photo
    kw = dict(fov_y_deg=50.0, pitch_deg=2.0, refine="repair", shot_noise_gain=0.002, seed=5)
    turbidities = [2.0, 4.5, 9.0]
    many = brume.aerial(image, range_m, turbidity=turbidities, return_info=True, **kw)
    assert isinstance(many, list) and len(many) == 3
    for t, (out, info) in zip(turbidities, many):
        alone, info_alone = brume.aerial(image, range_m, turbidity=t, return_info=True, **kw)
        np.testing.assert_array_equal(out, alone)
        assert info["turbidity"] == t
        for label in ("clear", "transmittance", "airlight"):
            np.testing.assert_array_equal(info[label], info_alone[label])
    # Each turbidity is its own veil: the outputs differ.
    assert np.abs(many[0][0].astype(int) - many[2][0].astype(int)).max() > 10
    one = brume.aerial(image, range_m, turbidity=np.array([4.5]), **kw)
    assert isinstance(one, list) and len(one) == 1
    np.testing.assert_array_equal(one[0], many[1][0])
    assert isinstance(brume.aerial(image, range_m, turbidity=4.5, **kw), np.ndarray)
    with pytest.raises(ValueError, match=r"invalid turbidity = \[\]: expected a number, or a non-empty"):
        brume.aerial(image, range_m, turbidity=[], **kw)
    with pytest.raises(ValueError, match="invalid turbidity = 30"):
        brume.aerial(image, range_m, turbidity=[4.0, 30.0], **kw)
    with pytest.raises(TypeError, match="'4' is not a number"):
        brume.aerial(image, range_m, turbidity="4", **kw)


def test_aerial_sun_brightens_the_fog_toward_it(photo):
    # With the airlight given (no sky light measured), the sun shapes the horizon's light
    # by azimuth (sec. 4): the veil on the side of the sun is brighter.
    image, range_m = photo
    linear = srgb_to_linear(image / 255.0).astype(np.float32)
    kw = dict(turbidity=6.0, fov_y_deg=50.0, blur=False, refine="none", airlight=(0.6, 0.6, 0.6))
    right = brume.aerial(linear, range_m, sun=(70.0, 40.0), **kw)
    left = brume.aerial(linear, range_m, sun=(70.0, -40.0), **kw)
    far = range_m > 4000  # the right of the photo
    assert right[far].mean() > left[far].mean() * 1.02
    with pytest.raises(ValueError, match="invalid sun"):
        brume.aerial(linear, range_m, sun=(200.0, 0.0), **kw)


def test_engine_fog_renderer_shared_by_threads(tmp_path):
    import threading

    colour, depth = clear_frame(tmp_path)
    camera = brume.Camera(**CAMERA)
    renderer = brume.Renderer()
    times = [0.0, 1.0, 2.0, 3.0]
    assert_threads_match_serial(
        [lambda t=t: renderer.distance_fog(colour, depth, camera=camera, time=t, blur="none")
         for t in times]
    )  # fmt: skip


# --- errors ----------------------------------------------------------------------------


def test_engine_fog_errors():
    h, w = 8, 12
    image = np.zeros((h, w, 3), np.float32)
    depth = np.full((h, w), 0.5, np.float32)
    camera = brume.Camera()
    cases = [
        (dict(depth=depth[:4]), "depth: expected shape 8x12"),
        (dict(depth=depth.astype(np.int32)), "depth: expected dtype float32"),
        (dict(depth=np.full((h, w), 1.5, np.float32)), r"depth: value 1.5 at pixel \(x 0, y 0\)"),
        (dict(camera="camera"), "camera: expected a brume.Camera"),
        (dict(blur="box"), "invalid blur"),
        (dict(time=float("nan")), "invalid time"),
        (dict(scheme="rk4"), "invalid scheme"),
        (dict(precision="f64"), "invalid precision"),
        (dict(lambda_px=-1.0), "invalid lambda_px"),
        (dict(blur="gauss-single", blur_max=2.0), "blur_max"),
        (dict(blur="diffusion", sigma0=0.0), "invalid sigma0 = 0"),
        (dict(blur="diffusion", rho_max=0.3), r"invalid rho_max = 0.3: expected a rate in \(0, 0.25\]"),
        # A blur's settings with another blur cannot take effect: refused, as by `brume scene`.
        (dict(blur="none", sigma0=2.0), "invalid sigma0 = 2: expected blur diffusion with it, not blur none"),
        (dict(blur="diffusion", blur_max=0.5), "invalid blur_max = 0.5: expected blur gauss-single"),
        (dict(blur="none", precision="f16"), "invalid precision = f16: expected a blur with it"),
        (dict(blur="gauss-single", lambda_px=4.0), "invalid lambda_px = 4: expected blur diffusion with it, not blur gauss-single"),
    ]
    for fog in (brume.distance_fog, brume.layered_fog):
        for change, message in cases:
            args = dict(dict(depth=depth, camera=camera), **change)
            with pytest.raises(ValueError, match=message):
                fog(image, args.pop("depth"), **args)
    distance_cases = [
        (dict(max_density=1.5), "invalid max_density"),
        (dict(noise_size=-1.0), "invalid noise_size"),
        (dict(noise_colour_strength=2.0), "noise_colour_strength"),
        (dict(colour=(1.0, 1.0)), "invalid colour"),
        (dict(light_direction=(0.0, 0.0, 0.0)), "light_direction"),
        (dict(noise="missing_tile.png"), "noise.*missing_tile.png"),
        (dict(noise=3), "invalid noise"),
        (dict(noise_seed=-1), "invalid noise_seed = -1"),
    ]
    for kwargs, message in distance_cases:
        with pytest.raises(ValueError, match=message):
            brume.distance_fog(image, depth, camera=camera, **kwargs)
    layered_cases = [
        (dict(profile="cloud"), "invalid profile"),
        (dict(profile="table"), "without table"),
        (dict(table=[[0, 0.01], [1, 0.02]]), "invalid table"),
        (dict(profile="table", table=[[1, 0.01], [0, 0.02]]), "table"),
        (dict(profile="band", scale_height=5.0), "invalid scale_height"),
        (dict(profile="table", table=[[0, 0.01], [1, 0.02]], density=2.0), "invalid density"),
        (dict(albedo=2.0), "albedo"),
        (dict(density=-1.0), "density"),
    ]
    for kwargs, message in layered_cases:
        with pytest.raises(ValueError, match=message):
            brume.layered_fog(image, depth, camera=camera, **kwargs)
    with pytest.raises(TypeError):
        brume.layered_fog(image, depth)  # camera is required
    # The camera's errors name its keywords.
    with pytest.raises(ValueError, match="invalid pitch_deg = 95"):
        brume.Camera(pitch_deg=95.0)
    with pytest.raises(ValueError, match="invalid fov_y_deg = 0"):
        brume.Camera(fov_y_deg=0.0)
    with pytest.raises(ValueError, match="invalid yaw_deg = NaN"):
        brume.Camera(yaw_deg=float("nan"))
    with pytest.raises(ValueError, match="far"):
        brume.Camera(near=10.0, far=5.0)
    with pytest.raises(ValueError, match="view: expected a 4x4"):
        brume.MatrixCamera(np.eye(3), np.eye(4))
    with pytest.raises(ValueError, match="invalid clip"):
        brume.MatrixCamera(np.eye(4), gl_projection(60, 1.5, 0.1, 100), clip="d3d")
    with pytest.raises(ValueError, match="sky_depth"):
        brume.MatrixCamera(np.eye(4), gl_projection(60, 1.5, 0.1, 100), sky_depth=0.01)


def test_aerial_errors(photo):
    image, range_m = photo
    ok = dict(turbidity=4.0, fov_y_deg=50.0)
    cases = [
        (dict(turbidity=4.0), "invalid fov_y_deg = \\(missing\\)"),
        (dict(ok, focal_px=60.0), "both given"),
        (dict(ok, turbidity=30.0), "invalid turbidity = 30"),
        (dict(ok, from_turbidity=0.5), "invalid from_turbidity"),
        (dict(ok, retarget="radiance"), "invalid retarget"),
        (dict(ok, from_turbidity=2.0, retarget="sideways"), "invalid retarget"),
        (dict(ok, horizon_sectors=0), "invalid horizon_sectors"),
        (dict(ok, altitude_m=1e6), "invalid altitude_m"),
        (dict(ok, pitch_deg=89.0), "invalid pitch_deg"),
        (dict(ok, pitch_deg=1.0, horizon_row=3.0), "horizon_row = 3: expected no pitch_deg"),
        (dict(ok, metres_per_unit=0.0), "invalid metres_per_unit"),
        (dict(ok, horizon_zenith_deg=120.0), "invalid horizon_zenith_deg"),
        (dict(ok, airlight=(1.0, 1.0)), "invalid airlight"),
        (dict(ok, refine="sometimes"), "invalid refine"),
        (dict(ok, sigma0=0.0), "invalid sigma0 = 0"),
        (dict(ok, sigma0=float("nan")), "invalid sigma0"),
        (dict(ok, seed=-3), "invalid seed = -3"),
    ]
    for kwargs, message in cases:
        with pytest.raises(ValueError, match=message):
            brume.aerial(image, range_m, **kwargs)
    with pytest.raises(ValueError, match="range_m: expected shape"):
        brume.aerial(image, np.dstack([range_m, range_m]), **ok)
    # A channel axis of one is the map itself.
    np.testing.assert_array_equal(
        brume.aerial(image, range_m[..., None], **ok), brume.aerial(image, range_m, **ok)
    )
    with pytest.raises(ValueError, match="^range_m: no valid depth value"):
        brume.aerial(image, np.full(range_m.shape, np.nan, np.float32), **ok)


def test_turbidity_from_sky_equals_brume_turbidity(tmp_path):
    """A Preetham sky from `brume sky` (T 5): the estimate is `brume turbidity --json`'s
    number for number, near 5; a display-encoded PNG warns (UserWarning), the EXR does
    not; bad values raise ValueError, a missing file OSError."""
    sun = ("58.4", "-179.4")
    for name in ["sky.exr", "sky.png"]:
        subprocess.run(
            [str(brume_bin()), "sky", "--turbidity", "5", "--sun-zenith", sun[0],
             "--sun-azimuth", sun[1], "--size", "160", "--out", str(tmp_path / name)],
            check=True, capture_output=True)  # fmt: skip
    cli = subprocess.run(
        [str(brume_bin()), "turbidity", str(tmp_path / "sky.exr"), "--sun-zenith", sun[0],
         "--sun-azimuth", sun[1], "--json"],
        check=True, capture_output=True, text=True)  # fmt: skip
    want = json.loads(cli.stdout)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = brume.turbidity_from_sky(tmp_path / "sky.exr", sun=(58.4, -179.4))
    for key in ["turbidity", "std", "inliers", "sun_zenith_deg", "usable_pixels",
                "luminance_weights", "linear_light", "colour_profile", "sun_source"]:  # fmt: skip
        assert got[key] == want[key], (key, got[key], want[key])
    assert abs(got["turbidity"] - 5.0) < 0.01 and got["linear_light"]
    assert got["image_circle"] is None and want["image_circle"] is None
    with pytest.warns(UserWarning, match="display-encoded sky photo"):
        png = brume.turbidity_from_sky(str(tmp_path / "sky.png"), sun=(58.4, -179.4))
    assert abs(png["turbidity"] - 5.0) < 0.05 and not png["linear_light"]
    with pytest.raises(ValueError, match="repeats"):
        brume.turbidity_from_sky(tmp_path / "sky.exr", repeats=0)
    with pytest.raises(ValueError, match="invalid repeats = -2"):
        brume.turbidity_from_sky(tmp_path / "sky.exr", repeats=-2)
    with pytest.raises(ValueError, match="invalid seed = -1"):
        brume.turbidity_from_sky(tmp_path / "sky.exr", seed=-1)
    with pytest.raises(ValueError, match="sun"):
        brume.turbidity_from_sky(tmp_path / "sky.exr", sun=(95.0, 0.0))
    with pytest.raises(OSError, match="missing.exr"):
        brume.turbidity_from_sky(tmp_path / "missing.exr")


def preetham_zenith_luminance(t, sun_zenith_deg):
    """Preetham, Shirley and Smits (1999), appendix: the zenith luminance Y_z in kcd/m²."""
    chi = (4.0 / 9.0 - t / 120.0) * (math.pi - 2.0 * math.radians(sun_zenith_deg))
    return (4.0453 * t - 4.9710) * math.tan(chi) - 0.2155 * t + 2.4192


def test_render_sky_equals_brume_sky_and_gives_its_turbidity_back(tmp_path):
    """render_sky (T 4, clouds, a sun disc) equals `brume sky`'s EXR (float32, kcd/m²) and
    PNG (uint8, exposed) and its JSON; the zenith pixel's Rec. 709 luminance is Preetham's
    Y_z written here; saved by save_photo, turbidity_from_sky gives T back; bad values raise
    ValueError naming the keyword."""
    Image = pytest.importorskip("PIL.Image")
    sun, size = (50.0, 30.0), 161  # odd: the centre pixel looks at the zenith
    options = ["--turbidity", "4", "--sun-zenith", "50", "--sun-azimuth", "30",
               "--size", str(size), "--clouds", "0.2", "--cloud-seed", "3",
               "--sun-disc", "0.5", "--json"]  # fmt: skip
    kw = dict(sun=sun, size=size, clouds=0.2, cloud_seed=3, sun_disc_deg=0.5)
    for name, dtype in [("sky.exr", "float32"), ("sky.png", "uint8")]:
        cli = subprocess.run(
            [str(brume_bin()), "sky", *options, "--out", str(tmp_path / name)],
            check=True, capture_output=True, text=True)  # fmt: skip
        report = json.loads(cli.stdout)
        image, info = brume.render_sky(4.0, dtype=dtype, **kw)
        assert image.dtype == np.dtype(dtype) and image.shape == (size, size, 3)
        if dtype == "uint8":
            written = np.asarray(Image.open(tmp_path / name).convert("RGB"))
            np.testing.assert_array_equal(image, written)
            assert info["exposure"] == pytest.approx(report["exposure"], rel=1e-12)
        else:
            written, _ = brume.load_photo(tmp_path / name, dtype="float32")
            np.testing.assert_allclose(image, written, rtol=1e-6)
            assert info["exposure"] is None
        assert info["clouds"] == report["clouds"]
        assert info["sun_disc_pixels"] == report["sun_disc_pixels"] >= 1
        assert info["zenith_luminance_kcd_m2"] == report["zenith_luminance_kcd_m2"]

    clear, info = brume.render_sky(4.0, sun=sun, size=size)
    y_z = preetham_zenith_luminance(4.0, sun[0])
    centre = clear[size // 2, size // 2].astype(np.float64)
    assert centre @ np.array([0.2126, 0.7152, 0.0722]) == pytest.approx(y_z, rel=1e-4)
    assert info["zenith_luminance_kcd_m2"] == pytest.approx(y_z, rel=1e-9)
    assert (clear[0, 0] == 0).all(), "black outside the horizon circle"
    brume.save_photo(tmp_path / "mine.exr", clear)
    t = brume.turbidity_from_sky(tmp_path / "mine.exr", sun=sun)["turbidity"]
    assert abs(t - 4.0) < 0.01, t

    for keyword, value, named in [
        ("sun", (95.0, 0.0), "sun"),
        ("sun_disc_deg", 50.0, "sun_disc_deg"),
        ("clouds", 2.0, "clouds"),
        ("size", 0, "size"),
        ("size", -5, "size"),
        ("cloud_seed", -1, "cloud_seed"),
        ("lens", "fish", "lens"),
        ("dtype", "uint16", "dtype"),
        ("azimuth_offset_deg", float("nan"), "azimuth_offset_deg"),
    ]:
        args = {"sun": sun, "size": 16, keyword: value}
        with pytest.raises(ValueError, match=named):
            brume.render_sky(4.0, **args)
    with pytest.raises(ValueError, match="turbidity"):
        brume.render_sky(0.5, sun=sun, size=16)


def test_sun_position_is_the_spa_papers_example_and_brume_sun(tmp_path):
    """sun_position at Reda and Andreas' worked example (Golden, Colorado, 2003-10-17
    12:30:30 UTC−7, 1830.14 m, 820 hPa, 11 °C, ΔT 67 s) gives their apparent zenith
    50.11162° and azimuth 194.34024° (1e-5), from a string or an aware datetime; pvlib's
    SPA at 400 random places and instants to 1e-6°; elsewhere it equals `brume sun --json`
    number for number, and its sun in render_sky draws `brume sky --latitude … --heading`'s
    sky; bad values raise ValueError naming the keyword."""
    from datetime import datetime, timedelta, timezone

    place = dict(altitude_m=1830.14, pressure_hpa=820.0, temperature_c=11.0, delta_t_s=67.0)
    local = datetime(2003, 10, 17, 12, 30, 30, tzinfo=timezone(timedelta(hours=-7)))
    for time in ["2003-10-17T12:30:30-07:00", local]:
        s = brume.sun_position(39.742476, -105.1786, time, **place)
        assert abs(s["apparent_zenith_deg"] - 50.11162) < 1e-5, s
        assert abs(s["azimuth_deg"] - 194.34024) < 1e-5, s
        assert abs(s["declination_deg"] - -9.316179) < 1e-6, s
        assert s["zenith_deg"] > s["apparent_zenith_deg"] and s["delta_t_s"] == 67.0

    # pvlib's SPA at 400 random places and instants (tests/data/sun, from
    # tools/sun_reference.py): within 1e-6 degrees.
    rows = (Path(__file__).resolve().parents[2] / "tests/data/sun/pvlib_spa.csv").read_text()
    header, *rows = [r.split(",") for r in rows.splitlines() if not r.startswith("#")]
    worst = 0.0
    for row in map(dict, (zip(header, r) for r in rows)):
        keywords = {k: float(row[k]) for k in ["altitude_m", "pressure_hpa", "temperature_c",
                                                "delta_t_s"]}  # fmt: skip
        s = brume.sun_position(
            float(row["latitude_deg"]), float(row["longitude_deg"]), row["time"], **keywords
        )
        for key in ["zenith_deg", "apparent_zenith_deg", "azimuth_deg"]:
            worst = max(worst, abs(s[key] - float(row[key])))
    assert len(rows) == 400 and worst < 1e-6, worst

    time = "2024-06-21T10:00:00+02:00"
    cli = subprocess.run(
        [str(brume_bin()), "sun", "--latitude", "48.85", "--longitude", "2.35",
         "--time", time, "--json"],
        check=True, capture_output=True, text=True)  # fmt: skip
    want = json.loads(cli.stdout)
    got = brume.sun_position(48.85, 2.35, time)
    for key in got:
        assert got[key] == want[key], key

    # The sun of a place in render_sky: the heading at the fisheye's top as its azimuth
    # offset, as `brume sky --latitude … --heading` draws it.
    sky = tmp_path / "sky.exr"
    subprocess.run(
        [str(brume_bin()), "sky", "--turbidity", "3", "--latitude", "48.85", "--longitude",
         "2.35", "--time", time, "--heading", "30", "--size", "65", "--out", str(sky)],
        check=True, capture_output=True)  # fmt: skip
    sun = (got["apparent_zenith_deg"], got["azimuth_deg"])
    drawn, _ = brume.render_sky(3.0, sun=sun, size=65, azimuth_offset_deg=30.0)
    np.testing.assert_array_equal(drawn, brume.load_photo(sky, dtype="float32")[0])

    for args, named in [
        ((95.0, 0.0, time), "latitude_deg"),
        ((0.0, 200.0, time), "longitude_deg"),
        ((0.0, 0.0, "2024-06-21 10:00"), "time"),
        ((0.0, 0.0, datetime(2024, 6, 21, 10)), "naive"),
        ((0.0, 0.0, 1718956800), "time"),
    ]:
        with pytest.raises(ValueError, match=named):
            brume.sun_position(*args)
    with pytest.raises(ValueError, match="delta_t_s"):
        brume.sun_position(0.0, 0.0, time, delta_t_s=1e6)
