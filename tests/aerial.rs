//! Paper 002's aerial perspective on the GPU against the f64 CPU reference, on a range map
//! of a ground plane seen by a pitched camera (kilometres), and the colour shift the model
//! exists for: distant ground turns blue in clear air and grey in haze.
//!
//! Tolerance: the GPU reads Γ from the same table with the same bilinear filter as the
//! reference (`AttenuationTable::sample`), but computes the table coordinate
//! ln(1 + s/s0)/Λ and ζ's e^(B/cos θ) in f32: a few ulps of u (1e-7 of 1024 texels, a
//! 1e-4 texel shift on a slope below 0.05 per texel) and of ζ — 2e-6 in all, plus the
//! pipeline's own 4e-7 per pass (tests/gpu_vs_cpu.rs).
use crate::common;

use brume::atmosphere::{AttenuationTable, Channel, Sensitivity};
use brume::camera::Camera;
use brume::medium::AerialPerspective;
use brume::raster::{Grid, ScalarMap};
use brume::{reference, Blur};
use common::*;
use std::sync::Arc;

const F32_PER_PASS: f64 = 4e-7;
const FOG_PASS: f64 = 2e-6;

fn camera() -> Camera {
    Camera {
        pitch_deg: -3.0,
        fov_y_deg: 40.0,
        ..Camera::default()
    }
}

/// Range (km) to the ground 100 m below the camera, and 60 km for the sky.
fn ground_range_km(w: usize, h: usize) -> ScalarMap {
    let c = camera();
    Grid::from_fn(w, h, |x, row| {
        let ray = c.pixel_ray(x, h - 1 - row, w, h).normalize();
        if ray.y < -1e-3 {
            ((100.0 / -ray.y) / 1000.0).min(60.0) as f32
        } else {
            60.0
        }
    })
}

fn aerial(turbidity: f64, lambda: f64) -> AerialPerspective {
    let table =
        AttenuationTable::new(&Sensitivity::cie_srgb(), turbidity, 100.0, 80_000.0).unwrap();
    AerialPerspective {
        metres_per_unit: 1000.0,
        lambda,
        ..AerialPerspective::new(Arc::new(table), camera(), [0.7, 0.8, 0.95])
    }
}

#[test]
fn aerial_perspective_matches_the_reference() {
    let (w, h) = (48, 32);
    let image = noise_image(w, h, 3);
    let range = ground_range_km(w, h);
    let (_lock, mut r) = renderer();
    for (t, lambda) in [(2.0, 0.0), (4.0, 0.0), (8.0, 5.0)] {
        let medium = aerial(t, lambda);
        let blur = Blur::default();
        let gpu = r.render(&image, &range, &medium, &blur).unwrap();
        let cpu = reference::render(&image, &range, &medium, &blur).unwrap();
        let e = reference::rgb_error(&gpu.image, &cpu, 0);
        let tol = FOG_PASS + F32_PER_PASS * f64::from(gpu.schedule.steps + 2);
        eprintln!(
            "T {t} λ {lambda}: N {} max {:.2e} (tolerance {tol:.1e})",
            gpu.schedule.steps, e.max_abs
        );
        assert!(e.max_abs <= tol, "T {t}: {e:?}");
        if lambda > 0.0 {
            assert!(gpu.schedule.steps > 0);
        }
    }
}

#[test]
fn distant_ground_turns_blue_in_clear_air_and_grey_in_haze() {
    // How much more blue than red is scattered away over 1 km: Rayleigh's λ⁻⁴ dominates
    // clear air, haze's flatter Mie term (λ⁻² with ν = 4) makes the veil greyer.
    let spread = |t: f64| {
        let a = brume::atmosphere::Aerial::new(&Sensitivity::cie_srgb(), t, 0.0).unwrap();
        a.scattering_optical_depth(Channel::B, 1000.0)
            / a.scattering_optical_depth(Channel::R, 1000.0)
    };
    let (clear, haze) = (spread(2.0), spread(8.0));
    assert!(clear > 1.3, "T 2: blue/red optical depth {clear}");
    assert!(
        haze < clear && haze > 1.0,
        "T 8 is greyer: {haze} vs {clear}"
    );
}

/// The horizon's light by azimuth sector (paper 002 sec. 4) on the GPU against the CPU
/// reference: the shader's atan/mod placement and bilinear lookup of the gains, for a
/// camera turned so that the sectors straddle the ±180° seam.
#[test]
fn horizon_sectors_match_the_reference() {
    use brume::medium::aerial::HorizonSectors;
    let (w, h) = (48, 32);
    let image = noise_image(w, h, 5);
    let range = ground_range_km(w, h);
    let (_lock, mut r) = renderer();
    for yaw in [0.0f64, 178.0] {
        let mut medium = aerial(4.0, 0.0);
        medium.camera.yaw_deg = yaw;
        let gains = vec![
            [0.6, 0.7, 0.8],
            [1.0, 1.0, 1.0],
            [1.6, 1.4, 1.2],
            [0.9, 1.1, 1.3],
        ];
        let centre = yaw.to_radians();
        medium.horizon_sectors = HorizonSectors::new(gains, centre, 0.25).unwrap();
        let blur = Blur::default();
        let gpu = r.render(&image, &range, &medium, &blur).unwrap();
        let cpu = reference::render(&image, &range, &medium, &blur).unwrap();
        let e = reference::rgb_error(&gpu.image, &cpu, 0);
        // The gains' slope is at most 0.6 per sector: an f32 azimuth (1e-6 rad on 0.25)
        // moves them by 3e-6 of I∞.
        let tol = 2.0 * FOG_PASS + F32_PER_PASS * f64::from(gpu.schedule.steps + 2) + 5e-6;
        eprintln!("yaw {yaw}: max {:.2e} (tolerance {tol:.1e})", e.max_abs);
        assert!(e.max_abs <= tol, "yaw {yaw}: {e:?}");
        // And the sectors do show: the left and right edges differ.
        let row = h / 2;
        let (l, rt) = (cpu.get(0, row), cpu.get(w - 1, row));
        assert!((l[0] - rt[0]).abs() > 0.05, "{l:?} {rt:?}");
    }
    // One sector is one gain everywhere (the shader skips the azimuth): a tinted one.
    let mut medium = aerial(4.0, 0.0);
    medium.horizon_sectors = HorizonSectors::new(vec![[1.3, 1.1, 0.7]], 0.5, 1.0).unwrap();
    let blur = Blur::default();
    let gpu = r.render(&image, &range, &medium, &blur).unwrap();
    let cpu = reference::render(&image, &range, &medium, &blur).unwrap();
    let e = reference::rgb_error(&gpu.image, &cpu, 0);
    let tol = FOG_PASS + F32_PER_PASS * f64::from(gpu.schedule.steps + 2);
    assert!(e.max_abs <= tol, "one sector: {e:?}");
    let plain = reference::render(&image, &range, &aerial(4.0, 0.0), &blur).unwrap();
    let (tinted, untinted) = (cpu.get(0, h / 2), plain.get(0, h / 2));
    assert!(
        tinted[0] > untinted[0] && tinted[2] < untinted[2],
        "{tinted:?}"
    );
}

/// One sector compiles without the sectors' code (no arc tangent, no lookup per pixel):
/// its GLSL leaves `AERIAL_HORIZON_SECTORS` undefined and it sets neither the sectors'
/// uniform nor their lookup; several sectors have all three.
#[test]
fn one_sector_leaves_the_sectors_code_out() {
    use brume::medium::aerial::HorizonSectors;
    use brume::medium::Medium;
    let frame = brume::FrameInputs::default();
    for (gains, several) in [
        (vec![[1.0; 3]], false),
        (vec![[1.3, 1.1, 0.7]], false),
        (vec![[0.6, 0.7, 0.8], [1.6, 1.4, 1.2]], true),
    ] {
        let mut medium = aerial(4.0, 0.0);
        medium.horizon_sectors = HorizonSectors::new(gains, 0.0, 0.5).unwrap();
        let defined = medium.glsl().contains("#define AERIAL_HORIZON_SECTORS");
        let uniform = medium
            .uniforms(&frame)
            .iter()
            .any(|(name, _)| name == "u_horizon_sectors");
        let lookup = medium
            .lookups()
            .iter()
            .any(|(name, _)| name == "u_horizon_gain");
        assert_eq!(
            [defined, uniform, lookup],
            [several; 3],
            "several: {several}"
        );
    }
}
