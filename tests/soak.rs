//! Long-running use: 1,000 renders in one context, alternating sizes, precisions and grey
//! or chromatic media, must leave resident memory and brume's GL object count flat.
//! Small images keep it to seconds on llvmpipe, so it runs with every `cargo test`
//! (`--nocapture` prints the figures).
mod common;

use brume::{gpu, Blur, Haze, Precision, Scheme};
use common::*;

/// Resident memory of this process (bytes), from /proc/self/statm.
fn resident_bytes() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").expect("/proc/self/statm");
    let pages: u64 = statm.split_whitespace().nth(1).unwrap().parse().unwrap();
    pages * 4096
}

#[test]
fn a_thousand_renders_leak_nothing() {
    const RENDERS: usize = 1000;
    const WARM_UP: usize = 40;
    let (_lock, mut r) = renderer();
    let sizes = [(64, 48), (96, 80), (50, 70)];
    let inputs: Vec<_> = sizes
        .iter()
        .map(|&(w, h)| (noise_image(w, h, 7), ramp_range(w, h)))
        .collect();
    let grey = Haze::default();
    let chromatic = Haze {
        tint: [0.7, 1.0, 1.4],
        ..grey
    };
    let mut baseline = None;
    let mut rss = Vec::new();
    for i in 0..WARM_UP + RENDERS {
        let (image, range) = &inputs[i % sizes.len()];
        let blur = Blur {
            precision: Precision::ALL[(i / 3) % 2],
            scheme: [Scheme::Matched, Scheme::Invariant][(i / 7) % 2],
            ..Blur::default()
        };
        let medium = if (i / 5) % 2 == 0 { &grey } else { &chromatic };
        let out = r.render(image, range, medium, &blur).expect("render");
        assert_eq!(out.image.width(), image.width());
        if i + 1 == WARM_UP {
            // Every program variant is compiled by now; targets come and go with the size.
            baseline = Some((gpu::live_objects(), resident_bytes()));
        }
        if i >= WARM_UP && i % 100 == 0 {
            rss.push(resident_bytes());
        }
    }
    let (objects, rss_start) = baseline.unwrap();
    let rss_end = resident_bytes();
    let growth = rss_end as i64 - rss_start as i64;
    eprintln!(
        "{RENDERS} renders: GL objects {objects} -> {}, resident {:.1} -> {:.1} MB \
         (growth {:+.2} MB; every 100: {:?} MB)",
        gpu::live_objects(),
        rss_start as f64 / 1e6,
        rss_end as f64 / 1e6,
        growth as f64 / 1e6,
        rss.iter().map(|b| b / 1_000_000).collect::<Vec<_>>()
    );
    // Objects: exact. The targets of the last size are kept, as after the warm-up.
    assert_eq!(gpu::live_objects(), objects);
    // Memory: allocator noise only. A leak of one small target per render would be
    // 1000 x 64x48x16 B = 49 MB.
    assert!(growth < 4_000_000, "resident memory grew by {growth} bytes");
}
