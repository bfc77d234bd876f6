//! Sky from the range alone (the depth rules): which components of unknown pixels are sky.

use super::components::{label_mask, Component, Components};
use super::SkyRules;

/// The sky mask under the depth rules: every pixel of the components of unknown (NaN)
/// pixels of `work` that [`select_sky`] keeps.
pub(crate) fn depth_sky(work: &[f32], rules: &SkyRules, width: usize, height: usize) -> Vec<bool> {
    let unknown: Vec<bool> = work.iter().map(|v| v.is_nan()).collect();
    let comps = label_mask(&unknown, width, height);
    let mut sky = vec![false; work.len()];
    for i in select_sky(&comps, rules, width, height) {
        for &p in comps.pixels_of(&comps.list[i]) {
            sky[p as usize] = true;
        }
    }
    sky
}

/// Indices (into `comps.list`) of the components that are sky under `rules`, largest first.
pub(crate) fn select_sky(
    comps: &Components,
    rules: &SkyRules,
    width: usize,
    height: usize,
) -> Vec<usize> {
    let mut chosen: Vec<usize> = (0..comps.list.len())
        .filter(|&i| is_sky_candidate(&comps.list[i], rules, width, height))
        .collect();
    // Largest first; ties by raster order so the choice is deterministic.
    chosen.sort_by_key(|&i| (std::cmp::Reverse(comps.list[i].len), i));
    chosen.truncate(rules.max_components);
    chosen
}

/// True if one component passes every rule of `rules` (see the module docs of `prep`).
pub(crate) fn is_sky_candidate(
    c: &Component,
    rules: &SkyRules,
    width: usize,
    height: usize,
) -> bool {
    let area = (width * height) as f64;
    let touches_top = c.top_pixels > 0;
    (!rules.must_touch_top || touches_top)
        && c.len as f64 >= rules.min_area_fraction * area
        && c.top_pixels as f64 >= rules.min_top_fraction * width as f64
        && c.len as f64 >= rules.min_bbox_fill * c.bbox_area() as f64
        && !(rules.reject_bottom && c.reaches_bottom(height))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn comp(len: usize, top: usize, bbox: [usize; 4]) -> Component {
        Component {
            start: 0,
            len,
            top_pixels: top,
            bbox,
        }
    }

    #[test]
    fn frame_and_strip_are_not_sky() {
        let r = SkyRules::default();
        // 3-px frame round a 1000x800 image: touches the whole top row but is thin.
        let frame = comp(2 * 3 * 1000 + 2 * 3 * 794, 1000, [0, 0, 999, 799]);
        assert!(!is_sky_candidate(&frame, &r, 1000, 800));
        // Full-height occlusion band on the left, 25 % wide.
        let band = comp(250 * 800, 250, [0, 0, 249, 799]);
        assert!(!is_sky_candidate(&band, &r, 1000, 800));
        // Sky: top 40 %, ragged.
        let sky = comp(280_000, 1000, [0, 0, 999, 420]);
        assert!(is_sky_candidate(&sky, &r, 1000, 800));
    }
}
