//! The GPU pipeline against the f64 CPU reference, pass for pass the same arithmetic.
mod common;

use brume::haze::{Haze, RenderSpec};
use brume::reference;
use brume::{Precision, Scheme};
use common::*;

fn compare(spec: &RenderSpec, w: usize, h: usize) -> reference::ErrorStats {
    let image = noise_image(w, h, 7);
    let range = ramp_range(w, h);
    let (_lock, mut r) = renderer();
    let gpu = r.render(&image, &range, spec).expect("GPU render");
    let cpu = reference::render(&image, &range, spec).expect("CPU render");
    let e = reference::rgb_error(&gpu.image, &cpu, 0);
    eprintln!(
        "{:?} {:?}: steps {} rms {:.3e} max {:.3e}",
        spec.scheme, spec.precision, gpu.schedule.steps, e.rms, e.max_abs
    );
    e
}

#[test]
fn haze_f32_matches_reference_for_every_scheme() {
    for scheme in Scheme::ALL {
        let haze = Haze {
            lambda: 6.0,
            ..Haze::default()
        };
        let spec = RenderSpec::haze(&haze, scheme, Precision::F32);
        let e = compare(&spec, 48, 40);
        assert!(e.max_abs < 1e-3, "{scheme}: {e:?}");
    }
}
