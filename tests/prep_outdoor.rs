//! Outdoor synthetic scene: sky, holes, horizon margin, airlight, reproducibility.

mod common;

use brume::prep::{
    estimate_airlight, prepare, synthetic::outdoor_scene, visualize, AirlightSource, PrepOptions,
};
use brume::raster::Grid;
use common::*;

const W: usize = 400;
const H: usize = 280;

#[test]
fn outdoor_scene_sky_holes_margin() {
    let map = outdoor_scene(W, H, 3);
    let opts = PrepOptions::default();
    let p = prepare(&map, &opts).unwrap();
    let s = &p.stats;
    if let Ok(dir) = std::env::var("PREP_VIS_DIR") {
        let (w, h, px) = visualize(&map, &p);
        save_png(&format!("{dir}/outdoor.png"), w, h, &px);
    }
    println!("{s:?}");
    assert_eq!(s.sky_components, 1, "{s:?}");
    assert!((0..W).all(|x| *p.sky.get(x, 0)), "top row is sky");
    assert!(s.holes > 10 && s.hole_pixels > W * H / 25, "{s:?}");
    assert_all_finite(&p.range);
    assert_known_unchanged(&map, &p.range);
    let s_max = s.s_max.unwrap();
    assert_eq!(s_max, 1.5 * s.r_max);
    for i in 0..map.len() {
        let unknown = map.as_slice()[i].is_nan();
        assert_eq!(
            unknown,
            p.sky.as_slice()[i] || p.filled.as_slice()[i],
            "pixel {i}"
        );
    }
    assert_eq!(
        s.sky_pixels + s.hole_pixels,
        map.as_slice().iter().filter(|v| v.is_nan()).count()
    );
}
