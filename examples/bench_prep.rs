//! Benchmark of `brume::prep::prepare` on the synthetic outdoor scene.
//!
//! `cargo run --release --example bench_prep -- [WIDTH HEIGHT RUNS]` (default 1600 1120 5).
//! Prints every run's time, the median and the scene statistics. Measure peak memory with
//! `/usr/bin/time -v target/release/examples/bench_prep`.
//!
//! `... --example bench_prep -- street [WIDTH HEIGHT RUNS]` (default 2048 1024 5) runs the
//! image-guided detector on the synthetic street frame instead, and prints how much of the
//! true sky it found.

use brume::prep::synthetic::{outdoor_scene, street_scene};
use brume::prep::{prepare, prepare_guided, Guides, PrepOptions};

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("street") {
        args.remove(0);
        return street(&numbers(&args));
    }
    let args = numbers(&args);
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

fn numbers(args: &[String]) -> Vec<usize> {
    args.iter().map(|a| a.parse().expect("a number")).collect()
}

/// The street frame with its image: times and the share of the true sky found.
fn street(args: &[usize]) {
    let (w, h, runs) = match args[..] {
        [w, h, n] => (w, h, n.max(1)),
        [w, h] => (w, h, 5),
        _ => (2048, 1024, 5),
    };
    let s = street_scene(w, h, 7);
    let guides = Guides {
        image: Some(&s.image),
        sky_mask: None,
        ego_mask: None,
    };
    let mut times = Vec::new();
    let mut last = None;
    for run in 0..runs {
        let p = prepare_guided(&s.range, guides, &PrepOptions::default()).expect("prepare");
        println!(
            "run {run}: total {:.1} ms (sky {:.1}, fill {:.1}, margin {:.1})",
            p.stats.total_ms, p.stats.sky_ms, p.stats.fill_ms, p.stats.margin_ms
        );
        times.push(p.stats.total_ms);
        last = Some(p);
    }
    times.sort_by(f64::total_cmp);
    let p = last.expect("at least one run");
    let (truth, found) = (s.sky.as_slice(), p.sky.as_slice());
    let sky = truth.iter().filter(|&&t| t).count();
    let hit = truth.iter().zip(found).filter(|(&t, &f)| t && f).count();
    let false_sky = truth.iter().zip(found).filter(|(&t, &f)| !t && f).count();
    println!("{w}x{h}, median of {runs}: {:.1} ms", times[runs / 2]);
    println!(
        "sky found {:.2} % of {sky} px, false sky {:.3} % of the other {} px; {:?}",
        100.0 * hit as f64 / sky as f64,
        100.0 * false_sky as f64 / (w * h - sky) as f64,
        w * h - sky,
        p.stats
    );
}
