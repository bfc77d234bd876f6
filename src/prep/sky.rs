//! Sky from the range alone (the depth rules): which components of unknown pixels are sky;
//! and the sky pre-processing settles on ([`find_sky`]): the user's mask, the depth rules,
//! or the depth rules joined by the image-guided detector.

use super::components::{label_mask, Component, Components};
use super::scan::ScanLines;
use super::{outliers, range_class, sky_image, Guides, PrepOptions, SkyMethod, SkyRules};

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

/// What [`find_sky`] decided.
pub(super) struct FoundSky {
    /// The sky mask before hole filling.
    pub(super) sky: Vec<bool>,
    /// How it was decided.
    pub(super) method: SkyMethod,
    /// Known pixels that are matcher noise in slivers of sky (image-guided only).
    pub(super) noise: Vec<usize>,
    /// Unknown pixels of the scene beyond the sensor's reach (image-guided only).
    pub(super) beyond_reach: Vec<usize>,
}

/// The sky: the user's mask; else, unless detection is off, the depth rules (which read a
/// scanned map's unknown pixels below its top line as known, [`ScanLines::closed`]),
/// joined by the image-guided detector when there is an image.
pub(super) fn find_sky(
    work: &[f32],
    lines: Option<&ScanLines>,
    (w, h): (usize, usize),
    guides: Guides,
    opts: &PrepOptions,
) -> FoundSky {
    let found = |sky, method| FoundSky {
        sky,
        method,
        noise: Vec::new(),
        beyond_reach: Vec::new(),
    };
    if let Some(mask) = guides.sky_mask {
        return found(mask.as_slice().to_vec(), SkyMethod::Mask);
    }
    if !opts.detect_sky || opts.sky.max_components == 0 {
        return found(vec![false; w * h], SkyMethod::Off);
    }
    let closed = lines.map(|l| l.closed(work));
    let rules_input = closed.as_deref().unwrap_or(work);
    let Some(image) = guides.image else {
        return found(depth_sky(rules_input, &opts.sky, w, h), SkyMethod::Depth);
    };
    // Independent: the depth rules' flood fill runs on one core beside the per-pixel
    // range classes.
    let (depth_sky, classes) = rayon::join(
        || depth_sky(rules_input, &opts.sky, w, h),
        || {
            let cut = outliers::sky_candidate_cut(work, opts);
            range_class::range_classes(work, w, h, cut)
        },
    );
    let image_sky = sky_image::image_sky(
        image,
        &classes,
        &depth_sky,
        &opts.image_sky,
        opts.sky.min_area_fraction,
    );
    FoundSky {
        sky: image_sky.sky,
        method: SkyMethod::DepthAndImage,
        noise: image_sky.noise,
        beyond_reach: image_sky.beyond_reach,
    }
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
