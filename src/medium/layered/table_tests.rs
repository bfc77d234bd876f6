//! The table profile against independent calculations: composite Simpson on the
//! linearly interpolated rows (written here, not the table's code), the analytic
//! profiles it samples (the error law), and the CSV format's errors.

use super::super::HeightProfile;
use super::*;
use std::path::Path;

/// κ of `rows` at `y`: linear between rows, constant beyond (the definition, by a scan).
fn interpolate(rows: &[(f64, f64)], y: f64) -> f64 {
    let (first, last) = (rows[0], rows[rows.len() - 1]);
    if y <= first.0 {
        return first.1;
    }
    if y >= last.0 {
        return last.1;
    }
    let w = rows.windows(2).find(|w| y <= w[1].0).expect("inside");
    let t = (y - w[0].0) / (w[1].0 - w[0].0);
    w[0].1 + t * (w[1].1 - w[0].1)
}

/// ∫_a^b κ by composite Simpson, split at every row between a and b (κ is smooth, in
/// fact linear, between them, so each piece is exact up to rounding).
fn simpson(rows: &[(f64, f64)], a: f64, b: f64) -> f64 {
    let (low, high) = (a.min(b), a.max(b));
    let mut cuts: Vec<f64> = vec![low, high];
    cuts.extend(rows.iter().map(|r| r.0).filter(|&h| h > low && h < high));
    cuts.sort_by(f64::total_cmp);
    let panels = 8;
    let mut sum = 0.0;
    for w in cuts.windows(2) {
        let h = (w[1] - w[0]) / (2 * panels) as f64;
        let f = |i: usize| interpolate(rows, w[0] + i as f64 * h);
        let mut s = f(0) + f(2 * panels);
        for i in 1..2 * panels {
            s += f(i) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        sum += s * h / 3.0;
    }
    sum
}

/// A profile with an inversion: clear air at the ground, a dense layer from 20 to 40 m,
/// thinner above; rows unevenly spaced but on a 0.5 m lattice.
fn inversion_rows() -> Vec<(f64, f64)> {
    vec![
        (0.0, 0.002),
        (10.0, 0.003),
        (20.0, 0.03),
        (22.5, 0.05),
        (30.0, 0.045),
        (40.0, 0.01),
        (80.0, 0.001),
        (200.0, 0.0),
    ]
}

#[test]
fn mean_density_matches_simpson_on_the_rows() {
    for rows in [
        inversion_rows(),
        // Off any lattice: the grid smooths the middle row over its cell.
        vec![(0.0, 0.0), (0.3, 0.3), (1.0, 0.1), (2.7, 0.2)],
    ] {
        let table = DensityTable::from_rows(&rows).unwrap();
        let exact = table.on_grid();
        let g = table.grid_spacing();
        // The bound of the module docs for rows off the grid: g²·|Δs|/8 per row, with
        // the slopes here below 1.
        let off_grid = if exact { 0.0 } else { 2.0 * g * g / 8.0 * 2.0 };
        for (y0, y1) in [
            (1.7, 1.7),
            (1.7, 25.0),
            (25.0, 1.7),
            (-30.0, 250.0),
            (21.0, 21.0 + 1e-9),
            (22.5, 30.0),
            (0.2, 0.9),
            (-5.0, -1.0),
            (190.0, 400.0),
            (0.1, 2.0),
        ] {
            let mean = table.mean_density(y0, y1 - y0);
            let want = if y1 != y0 {
                simpson(&rows, y0, y1) / (y1 - y0).abs()
            } else {
                interpolate(&rows, y0)
            };
            let tol = 1e-12 + off_grid / (y1 - y0).abs().max(g);
            assert!(
                (mean - want).abs() <= tol.max(1e-12 * want.abs()),
                "{y0}..{y1} (on grid {exact}): {mean} vs Simpson {want}"
            );
        }
    }
}

#[test]
fn lattice_rows_are_nodes_of_the_grid() {
    let table = DensityTable::from_rows(&inversion_rows()).unwrap();
    assert!(table.on_grid());
    // Every row is a multiple of the smallest gap, 2.5 m.
    assert_eq!(table.grid_spacing(), 2.5);
    assert_eq!(table.grid_nodes(), 81);
    let uneven = DensityTable::from_rows(&[(0.0, 1.0), (0.1, 0.0), (1.0, 2.0)]).unwrap();
    assert!(
        uneven.on_grid(),
        "0.1 divides 1.0: {}",
        uneven.grid_spacing()
    );
    let off = DensityTable::from_rows(&[(0.0, 0.0), (0.3, 0.3), (1.0, 0.1)]).unwrap();
    assert!(!off.on_grid());
}

#[test]
fn integral_is_the_antiderivative_of_density() {
    let table = DensityTable::from_rows(&inversion_rows()).unwrap();
    for (a, b) in [(0.0, 22.5), (3.0, 150.0), (-10.0, 300.0)] {
        let k = table.integral(b) - table.integral(a);
        let s = simpson(&inversion_rows(), a, b);
        assert!((k - s).abs() < 1e-12, "{a}..{b}: {k} vs {s}");
    }
}

/// The largest relative error of the mean density of `profile` sampled every `spacing`
/// against the analytic profile, over horizontal rays at heights every cm from 0 to 10 m
/// (the sup of the interpolation error, (Δ²/8)·|δ″| at a cell's middle) and over rising
/// rays from those heights to 37 m (an average of it).
fn sampled_error(profile: &HeightProfile, spacing: f64) -> f64 {
    let table = DensityTable::sampled(|y| profile.density(y), 0.0, 100.0, spacing).unwrap();
    let mut worst: f64 = 0.0;
    for i in 0..=1000 {
        let y0 = i as f64 * 0.01;
        for y1 in [y0, 37.0] {
            let want = profile.mean_density(y0, y1);
            if want > 0.0 {
                let got = table.mean_density(y0, y1 - y0);
                worst = worst.max((got - want).abs() / want);
            }
        }
    }
    worst
}

#[test]
fn sampled_profiles_converge_as_the_square_of_the_spacing() {
    let band = HeightProfile::SineBand {
        density: 0.01,
        base: 0.0,
        thickness: 5.0,
    };
    // (profile, c): the relative error is at most c·Δ², the module docs' (Δ²/8)·|δ″|/δ
    // over a cell: 1/(8H²) times e^(Δ/2H) ≤ 1.03 for the exponential; (π/T)²/6 for the
    // band, whose relative error peaks at its edges, where δ → 0 (sin x/x = 1 − x²/6).
    let pi_t = std::f64::consts::PI / 5.0;
    for (profile, c) in [
        (HeightProfile::EXPONENTIAL, 1.03 / (8.0 * 400.0)),
        (band, pi_t * pi_t / 6.0),
    ] {
        let mut errors = Vec::new();
        for spacing in [1.0, 0.5, 0.25, 0.125] {
            let e = sampled_error(&profile, spacing);
            let bound = c * spacing * spacing;
            assert!(e <= bound, "{profile:?} Δ {spacing}: {e} > {bound}");
            errors.push(e);
        }
        let ratios: Vec<f64> = errors.windows(2).map(|w| w[0] / w[1]).collect();
        eprintln!(
            "{profile:?}: errors {errors:?} at Δ = 1, 0.5, 0.25, 0.125 m; ratios {ratios:.2?}"
        );
        // Halving Δ divides the error by 4 once Δ resolves the profile.
        let last = ratios[ratios.len() - 1];
        assert!((3.8..4.2).contains(&last), "{profile:?}: ratios {ratios:?}");
    }
    // A ramp whose kinks are rows is exact.
    let ramp = sampled_error(&HeightProfile::LINEAR_RAMP, 0.25);
    assert!(ramp < 1e-12, "ramp {ramp}");
}

fn parse(text: &str) -> Result<DensityTable> {
    DensityTable::parse_csv(text, Path::new("fog.csv"))
}

#[test]
fn csv_reads_rows_comments_and_a_byte_order_mark() {
    let table = parse(
        "\u{feff}# an inversion\nheight_m,extinction_per_m\n0,0.001\n\n 50 , 0.02 # top\n100,0\n",
    )
    .unwrap();
    assert_eq!(table.heights(), &[0.0, 50.0, 100.0]);
    assert_eq!(table.extinction(), &[0.001, 0.02, 0.0]);
    assert!((table.density(25.0) - 0.0105).abs() < 1e-15);
    assert_eq!(table.density(-5.0), 0.001);
    assert_eq!(table.density(500.0), 0.0);
}

#[test]
fn bad_csv_names_file_line_and_value() {
    let cases = [
        ("0,0.01\n1,0.02\n", "line 1", "header"),
        ("", "fog.csv", "header"),
        (
            "height_m,extinction_per_m\n0,0.01\n",
            "fog.csv",
            "at least 2",
        ),
        (
            "height_m,extinction_per_m\n0,0.01\n1,abc\n",
            "line 3",
            "`abc`",
        ),
        (
            "height_m,extinction_per_m\n0,0.01\n1,nan\n",
            "line 3",
            "finite",
        ),
        (
            "height_m,extinction_per_m\n0,0.01\n0,0.02\n",
            "line 3",
            "increase",
        ),
        (
            "height_m,extinction_per_m\n5,0.01\n2,0.02\n",
            "line 3",
            "height_m = 2",
        ),
        (
            "height_m,extinction_per_m\n0,0.01\n1,-0.5\n",
            "line 3",
            "-0.5",
        ),
        (
            "height_m,extinction_per_m\n0,0.01,7\n",
            "line 2",
            "3 fields",
        ),
    ];
    for (text, place, what) in cases {
        let e = parse(text).expect_err(text).to_string();
        assert!(e.contains("fog.csv"), "{text:?}: {e}");
        assert!(e.contains(place) && e.contains(what), "{text:?}: {e}");
    }
    let missing = DensityTable::from_csv("no/such/table.csv")
        .unwrap_err()
        .to_string();
    assert!(missing.contains("no/such/table.csv"), "{missing}");
}

#[test]
fn bad_rows_are_refused_by_row() {
    let e = DensityTable::from_rows(&[(0.0, 1.0)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("at least 2"), "{e}");
    let e = DensityTable::from_rows(&[(0.0, 1.0), (2.0, -1.0)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("row 1") && e.contains("≥ 0"), "{e}");
    let e = DensityTable::from_rows(&[(0.0, 1.0), (0.0, 1.0)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("row 1") && e.contains("above"), "{e}");
    assert!(DensityTable::sampled(|_| 1.0, 0.0, 1.0, 0.0).is_err());
}

#[test]
fn textures_hold_the_grid_row_by_row() {
    let table = DensityTable::sampled(|y| y, 0.0, 5000.0, 1.0).unwrap();
    let lookups = table.lookups();
    let (density, integral) = (&lookups[0].1, &lookups[1].1);
    assert_eq!((density.width(), density.height()), (TEXTURE_WIDTH, 3));
    // Node j at (j mod width, j div width).
    let j = 4321;
    assert_eq!(
        density.texel((j % TEXTURE_WIDTH) as i64, (j / TEXTURE_WIDTH) as i64),
        j as f64
    );
    let k = integral.texel((j % TEXTURE_WIDTH) as i64, (j / TEXTURE_WIDTH) as i64);
    assert!((k - (j * j) as f64 / 2.0).abs() <= 1.0, "{k}");
}
