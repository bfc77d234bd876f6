//! Step 4's holes: every component of unknown pixels outside the sky is filled from the
//! range round it ([`super::fill`]), a stereo occlusion from its background alone
//! ([`super::occlusion`]).

use super::{colour_guide, components, fill, ground, occlusion, PrepOptions, PrepStats};
use crate::Result;

/// The masks [`fill_holes`] reads and extends. `ego` is empty without an ego mask.
pub(super) struct Holes<'m> {
    pub(super) filled: &'m mut [bool],
    pub(super) sky: &'m mut [bool],
    pub(super) ego: &'m mut [bool],
}

/// Fills every component of unknown pixels outside the sky and marks it in `filled`. A
/// component with no known pixel round it (sky all round: a bird, a wire, outliers in the
/// sky) has nothing to be filled from and is sky; with the ego vehicle round it (and no
/// sky), it is the ego vehicle. With [`PrepOptions::stereo_focal_baseline`], a component
/// holding a stereo occlusion is filled without its edges to the occluders
/// ([`occlusion::find`]).
pub(super) fn fill_holes(
    work: &mut [f32],
    m: &mut Holes,
    (w, h): (usize, usize),
    guide: Option<&colour_guide::ColourGuide>,
    opts: &PrepOptions,
    stats: &mut PrepStats,
) -> Result<()> {
    // Sky pixels are not boundary values: +inf is neither NaN (a hole) nor finite (data).
    work.iter_mut()
        .zip(m.sky.iter())
        .filter(|(_, &s)| s)
        .for_each(|(v, _)| *v = f32::INFINITY);
    // Before labelling, which marks the unknown pixels visited (+inf).
    let occlusions = opts
        .stereo_focal_baseline
        .map(|fb| {
            occlusion::find(
                work,
                m.filled,
                (w, h),
                (fb, opts.stereo_view.unwrap_or_default()),
            )
        })
        .unwrap_or_default();
    stats.occluded = occlusions.count;
    let comps = components::label_unknown(work, w, h);
    let mut filler = fill::HoleFiller::new(f64::from(stats.r_max), occlusions)
        .with_road(opts.ground.as_ref().map(ground::Road::of));
    let mut state = vec![colour_guide::Pixel::Other; if guide.is_some() { w * h } else { 0 }];
    for c in &comps.list {
        let pixels = comps.pixels_of(c);
        if !has_known_neighbour(work, w, h, pixels) {
            let touches = |mask: &[bool]| {
                !mask.is_empty()
                    && pixels.iter().any(|&p| {
                        let p = p as usize;
                        components::neighbours4(p, p % w, p / w, w, h)
                            .into_iter()
                            .flatten()
                            .any(|q| mask[q])
                    })
            };
            let into: &mut [bool] = if touches(m.ego) && !touches(m.sky) {
                m.ego
            } else {
                m.sky
            };
            pixels.iter().for_each(|&p| into[p as usize] = true);
            continue;
        }
        let mut rng = crate::rng::SplitMix64::for_stream(opts.seed, pixels[0] as u64);
        filler.begin_hole(pixels);
        match guide {
            Some(guide) => {
                stats.colour_regions += filler.fill_by_colour(
                    work,
                    (w, h),
                    pixels,
                    guide,
                    &mut state,
                    opts.ransac_samples,
                    &mut rng,
                )?
            }
            None => filler.fill(work, w, h, pixels, opts.ransac_samples, &mut rng)?,
        }
        pixels.iter().for_each(|&p| m.filled[p as usize] = true);
        stats.holes += 1;
        stats.hole_pixels += pixels.len();
    }
    Ok(())
}

/// Whether any 4-neighbour of `pixels` holds a finite value.
fn has_known_neighbour(work: &[f32], w: usize, h: usize, pixels: &[u32]) -> bool {
    pixels.iter().any(|&p| {
        let p = p as usize;
        components::neighbours4(p, p % w, p / w, w, h)
            .into_iter()
            .flatten()
            .any(|q| work[q].is_finite())
    })
}

#[cfg(test)]
mod tests {
    use super::super::{prepare_guided, Guides, PrepOptions};
    use crate::raster::Grid;

    const W: usize = 48;
    const H: usize = 40;
    /// f·B: a pole at 5 m before a wall at 20 m is 100·(1/5 − 1/20) = 15 px of disparity
    /// nearer, so the right camera cannot see the 15 px of wall left of it.
    const FB: f64 = 100.0;
    const POLE: std::ops::Range<usize> = 30..36;
    const OCCLUDED: std::ops::Range<usize> = 15..30;

    /// The wall at 20 m, the pole at 5 m, the occlusion unknown as a matcher leaves it:
    /// with a jagged edge, the pole's range reaching 2 px into it on every other row (a
    /// matcher's fattened silhouette), so that the pole has more edges to the hole than
    /// the wall; the image is the wall's grey and the pole's black, and the pole's colour
    /// reaches `missed` px into the occlusion (pole the matcher left unknown).
    fn frame(missed: usize) -> (Grid<f32>, Grid<[f32; 3]>) {
        let range = Grid::from_fn(W, H, |x, y| {
            let fattened = if y % 2 == 1 { 2 } else { 0 };
            if POLE.contains(&x) || (x >= POLE.start - fattened && x < POLE.start) {
                5.0
            } else if OCCLUDED.contains(&x) {
                f32::NAN
            } else {
                20.0
            }
        });
        let image = Grid::from_fn(W, H, |x, _| {
            if POLE.contains(&x) || (x >= POLE.start - missed && x < POLE.start) {
                [0.02; 3]
            } else {
                [0.4, 0.35, 0.3]
            }
        });
        (range, image)
    }

    fn prepare(missed: usize, fb: Option<f64>) -> super::super::Prepared {
        let (range, image) = frame(missed);
        let opts = PrepOptions {
            detect_sky: false,
            margin_px: 0.0,
            local_outlier_factor: 0.0,
            border_band_fraction: 0.0,
            stereo_focal_baseline: fb,
            ..PrepOptions::default()
        };
        let guides = Guides {
            image: Some(&image),
            ..Guides::default()
        };
        prepare_guided(&range, guides, &opts).unwrap()
    }

    /// The occlusion's pixels of the wall's colour, between the wall and the pole's jagged
    /// edge.
    fn walls_pixels(missed: usize) -> impl Iterator<Item = (usize, usize)> {
        (0..H).flat_map(move |y| {
            let end = if y % 2 == 1 {
                POLE.start - 2
            } else {
                POLE.start
            };
            (OCCLUDED.start..end.min(POLE.start - missed)).map(move |x| (x, y))
        })
    }

    /// Filled as any hole, the occlusion is a ramp from the wall's range to the pole's (a
    /// plane through both sides' edges); as an occlusion, it is the wall.
    #[test]
    fn an_occlusion_is_filled_from_its_background() {
        let as_hole = prepare(0, None);
        let as_occlusion = prepare(0, Some(FB));
        assert_eq!(as_hole.stats.occluded, 0);
        assert!(
            as_occlusion.stats.occluded >= 13 * H,
            "{:?}",
            as_occlusion.stats
        );
        let mean_error = |p: &super::super::Prepared| {
            let n = walls_pixels(0).count() as f32;
            walls_pixels(0)
                .map(|(x, y)| (p.range.get(x, y) - 20.0).abs())
                .sum::<f32>()
                / n
        };
        assert!(mean_error(&as_hole) > 3.0, "{}", mean_error(&as_hole));
        assert!(
            mean_error(&as_occlusion) < 0.01,
            "{}",
            mean_error(&as_occlusion)
        );
        // The pole and the wall beyond are kept.
        assert_eq!(*as_occlusion.range.get(POLE.start, 0), 5.0);
        assert_eq!(*as_occlusion.range.get(POLE.end, 0), 20.0);
    }

    /// Pixels of the pole's colour in the occlusion, whose only edges of their colour are
    /// the pole's, are the pole the matcher missed: they keep its range, the rest of the
    /// occlusion the wall's.
    #[test]
    fn the_occluders_own_colour_keeps_its_range() {
        let missed = 4;
        let p = prepare(missed, Some(FB));
        for y in (0..H).step_by(2) {
            for x in POLE.start - missed..POLE.start {
                let r = *p.range.get(x, y);
                assert!((r - 5.0).abs() < 0.05, "({x}, {y}): {r}");
            }
        }
        for (x, y) in walls_pixels(missed) {
            let r = *p.range.get(x, y);
            assert!((r - 20.0).abs() < 0.2, "({x}, {y}): {r}");
        }
    }
}
