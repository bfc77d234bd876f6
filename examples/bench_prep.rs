//! Benchmark of `brume::prep::prepare` on the synthetic outdoor scene.
//!
//! `cargo run --release --example bench_prep -- [WIDTH HEIGHT RUNS]` (default 1600 1120 5).
//! Prints every run's time, the median and the scene statistics. Measure peak memory with
//! `/usr/bin/time -v target/release/examples/bench_prep`.

use brume::prep::{prepare, synthetic::outdoor_scene, PrepOptions};

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("a number"))
        .collect();
    let (w, h, runs) = match args[..] {
        [w, h, n] => (w, h, n),
        [w, h] => (w, h, 5),
        _ => (1600, 1120, 5),
    };
    let map = outdoor_scene(w, h, 7);
    let unknown = map.as_slice().iter().filter(|v| v.is_nan()).count();
    println!(
        "{w}x{h}, {unknown} unknown pixels ({:.1} %)",
        100.0 * unknown as f64 / map.len() as f64
    );
    if runs == 0 {
        return; // baseline for the peak-RSS measurement: the scene alone
    }
    let opts = PrepOptions::default();
    let mut times = Vec::new();
    let mut last = None; // stats only: a held `Prepared` would inflate the peak memory
    for run in 0..runs {
        let p = prepare(&map, &opts).expect("prepare");
        let s = &p.stats;
        println!(
            "run {run}: total {:.1} ms (fill {:.1}, sky {:.1}, margin {:.1})",
            s.total_ms, s.fill_ms, s.sky_ms, s.margin_ms
        );
        times.push(s.total_ms);
        last = Some(p.stats);
    }
    times.sort_by(f64::total_cmp);
    let s = last.expect("at least one run");
    println!("median of {runs}: {:.1} ms", times[runs / 2]);
    println!(
        "holes {} ({} px), sky components {} ({} px), margin {} px, Rmax {:.1}, Smax {:?}",
        s.holes, s.hole_pixels, s.sky_components, s.sky_pixels, s.margin_pixels, s.r_max, s.s_max
    );
    println!(
        "one float copy of the map: {:.1} MiB",
        (w * h * 4) as f64 / (1 << 20) as f64
    );
}
