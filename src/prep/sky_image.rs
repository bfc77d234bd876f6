//! Sky from the colour image and the range together: the image-guided detector.
//!
//! Its rules, and why, are in the module docs of [`crate::prep`] (step 2); the thresholds
//! are [`ImageSkyRules`]. In short: per-pixel evidence (luminance, 3 x 3 texture, a range
//! class), seeds in the top rows, breadth-first growth over smooth, bright, blue-or-grey
//! pixels in small colour steps (jumping thin occluders), edge refinement, regions that
//! are large enough and do not reach the bottom row, then the gaps in the sky and a stereo
//! matcher's streaks in it.

use super::colour_step::{luminance, relative_step, texture};
use super::components::{label_mask, neighbours4};
use super::range_class::RangeClass;
use super::ImageSkyRules;
use crate::raster::RgbImage;
use rayon::prelude::*;

/// Edge refinement rounds: the radius of the texture window plus one.
const REFINE_ROUNDS: usize = 2;
/// The sky may be this much darker than the seeds' median luminance.
const SEED_DIMMING: f32 = 0.5;

/// What a pixel's luminance, colour, texture and range say, a bit each, in
/// [`Evidence::signs`]: the growth asks several of them of each pixel it looks at.
const BRIGHT: u8 = 1;
/// Blue or grey: its blue at least [`ImageSkyRules::min_blue_ratio`] of its red and green.
const BLUE_OR_GREY: u8 = 2;
/// Its texture at most [`ImageSkyRules::max_texture`].
const SMOOTH: u8 = 4;
/// Its range [`RangeClass::Confident`].
const CONFIDENT: u8 = 8;

/// `bit` if `holds`, else nothing.
fn sign(holds: bool, bit: u8) -> u8 {
    if holds {
        bit
    } else {
        0
    }
}

/// The per-pixel evidence of the detector.
struct Evidence<'a> {
    colour: &'a [[f32; 3]],
    lum: Vec<f32>,
    texture: Vec<f32>,
    range: &'a [RangeClass],
    /// Luminance floor of the sky.
    floor: f32,
    /// Each pixel's [`BRIGHT`], [`BLUE_OR_GREY`], [`SMOOTH`] and [`CONFIDENT`] bits for
    /// this floor.
    signs: Vec<u8>,
    /// Smallest luminance a relative step is measured against.
    eps: f32,
    rules: &'a ImageSkyRules,
}

impl Evidence<'_> {
    /// Sets every pixel's signs, with `floor` as the sky's luminance floor.
    fn set_signs(&mut self, floor: f32) {
        self.floor = floor;
        let mut signs = vec![0u8; self.lum.len()];
        signs
            .par_iter_mut()
            .with_min_len(1 << 16)
            .enumerate()
            .for_each(|(p, s)| *s = self.signs_of(p));
        self.signs = signs;
    }

    /// Raises the sky's luminance floor to `floor`: only [`BRIGHT`] changes.
    fn raise_floor(&mut self, floor: f32) {
        self.floor = floor;
        self.signs
            .par_iter_mut()
            .zip(&self.lum)
            .with_min_len(1 << 16)
            .for_each(|(s, &l)| *s = (*s & !BRIGHT) | sign(l >= floor, BRIGHT));
    }

    /// The signs of pixel `p` for the current floor.
    fn signs_of(&self, p: usize) -> u8 {
        let c = self.colour[p];
        let blue = f64::from(c[2]) >= self.rules.min_blue_ratio * f64::from(c[0].max(c[1]));
        let smooth = f64::from(self.texture[p]) <= self.rules.max_texture;
        sign(self.lum[p] >= self.floor, BRIGHT)
            | sign(blue, BLUE_OR_GREY)
            | sign(smooth, SMOOTH)
            | sign(self.range[p] == RangeClass::Confident, CONFIDENT)
    }

    /// Whether `p` has every sign of `all` and none of `none`.
    #[inline]
    fn has(&self, p: usize, all: u8, none: u8) -> bool {
        self.signs[p] & (all | none) == all
    }

    /// Bright enough and blue or grey, and its range not confident.
    fn looks_like_sky(&self, p: usize) -> bool {
        self.has(p, BRIGHT | BLUE_OR_GREY, CONFIDENT)
    }

    /// Bright enough and smooth, whatever its hue: the orange of a sunset's sky near the
    /// horizon, under the blue.
    fn glows(&self, p: usize) -> bool {
        self.has(p, BRIGHT | SMOOTH, 0)
    }

    /// Looks like sky, is smooth, and its range does not say otherwise.
    fn admissible(&self, p: usize) -> bool {
        self.has(p, BRIGHT | BLUE_OR_GREY | SMOOTH, CONFIDENT)
    }

    /// The colours of `p` and `q` differ by at most `max_step`, relative.
    fn step_ok(&self, p: usize, q: usize) -> bool {
        f64::from(relative_step(self.colour, &self.lum, p, q, self.eps)) <= self.rules.max_step
    }
}

/// Upper median of the finite values of `values` at the pixels where `include` is true;
/// `None` without any.
fn median(values: &[f32], include: impl Fn(usize) -> bool + Sync) -> Option<f32> {
    super::rank::nth_kept(values, |i, v| v.is_finite() && include(i), |n| n / 2)
}

/// What the image-guided detector found.
pub(crate) struct ImageSky {
    /// The sky mask.
    pub sky: Vec<bool>,
    /// Known pixels outside the sky that look like sky and whose range is unsupported:
    /// matcher noise in slivers of sky the growth could not enter (between a wire and a
    /// roof, between leaves). Far values are left to the far-outlier rule. Empty when no
    /// sky was found.
    pub noise: Vec<usize>,
    /// Unknown pixels the depth rules took for sky that the image does not join to the
    /// sky it found: the scene beyond the sensor's reach. Empty when the image found no
    /// sky (the depth rules' sky is then kept whole: a sunset's orange sky is not blue or
    /// grey).
    pub beyond_reach: Vec<usize>,
}

/// The sky from the image, the range classes and the depth rules' sky (see the module
/// docs of `prep`). `image`, `range` and `depth_sky` are `width x height`.
pub(crate) fn image_sky(
    image: &RgbImage,
    range: &[RangeClass],
    depth_sky: &[bool],
    rules: &ImageSkyRules,
    min_area_fraction: f64,
) -> ImageSky {
    let (width, height) = (image.width(), image.height());
    let colour = image.as_slice();
    let lum = luminance(colour);
    let depth_only = || ImageSky {
        sky: depth_sky.to_vec(),
        noise: Vec::new(),
        beyond_reach: Vec::new(),
    };
    // The floor is set by the scene (the pixels of confident range), not by the whole
    // image: in a frame mostly of sky the image's median is the sky's own, and the darker
    // half of it (the zenith) would fall below.
    let scene = |p: usize| range[p] == RangeClass::Confident;
    let Some(lum_median) = median(&lum, scene).or_else(|| median(&lum, |_| true)) else {
        return depth_only();
    };
    let eps = (0.01 * lum_median).max(1e-6);
    let mut ev = Evidence {
        colour,
        texture: texture(colour, &lum, width, height, eps),
        lum,
        range,
        floor: 0.0,
        signs: Vec::new(),
        eps,
        rules,
    };
    ev.set_signs((rules.min_brightness * f64::from(lum_median)) as f32);
    let seeds = seeds(&ev, depth_sky, width, height);
    let seed_lums: Vec<f32> = seeds.iter().map(|&p| ev.lum[p]).collect();
    let Some(seed_lum) = median(&seed_lums, |_| true) else {
        return depth_only();
    };
    ev.raise_floor(ev.floor.max(SEED_DIMMING * seed_lum));
    let mut sky = grow_regions(&ev, &seeds, width, height, min_area_fraction);
    // A sensor that does not reach the far scene (a phone's time-of-flight camera stops at
    // 8 m) leaves it unknown and joined to the sky, and the depth rules take it all for
    // sky: where the image found sky, only what the sky reaches in its own colour is.
    if sky.iter().any(|&s| s) {
        join_depth_sky(&ev, &mut sky, depth_sky, width, height);
    } else {
        sky.copy_from_slice(depth_sky);
    }
    fill_gaps(&ev, &mut sky, width, height);
    let reclaimed = reclaim_vetoed(&ev, &mut sky, width, height);
    grow_past_reclaimed(&ev, &mut sky, &reclaimed, width, height);
    let beyond_reach = super::reach::beyond_reach(ev.rules, &mut sky, depth_sky, width, height);
    let noise = if sky.iter().any(|&s| s) {
        crate::parallel::indices_in_order(sky.len(), |p| {
            !sky[p] && range[p] == RangeClass::Unsupported && ev.looks_like_sky(p)
        })
    } else {
        Vec::new()
    };
    ImageSky {
        sky,
        noise,
        beyond_reach,
    }
}

/// Admissible pixels of the top rows, and the depth rules' sky where it looks like sky.
fn seeds(ev: &Evidence, depth_sky: &[bool], width: usize, height: usize) -> Vec<usize> {
    let rows = ((ev.rules.seed_rows * height as f64).ceil() as usize).clamp(1, height);
    crate::parallel::indices_in_order(width * height, |p| {
        (p < rows * width && ev.admissible(p)) || (depth_sky[p] && ev.looks_like_sky(p))
    })
}

/// Grows one region from every seed not yet reached (see the module docs) and returns the
/// union of the regions that are large enough and do not reach the bottom row.
fn grow_regions(
    ev: &Evidence,
    seeds: &[usize],
    width: usize,
    height: usize,
    min_area_fraction: f64,
) -> Vec<bool> {
    let min_area = min_area_fraction * (width * height) as f64;
    let mut reached = vec![false; width * height];
    let mut sky = vec![false; width * height];
    let mut region = Vec::new();
    for &seed in seeds {
        if reached[seed] {
            continue;
        }
        region.clear();
        region.push(seed);
        reached[seed] = true;
        grow_and_refine(ev, &mut reached, &mut region, width, height);
        let bottom = height > 1 && reaches_bottom(&region, width, height);
        if region.len() as f64 >= min_area && !bottom {
            region.iter().for_each(|&p| sky[p] = true);
        }
    }
    sky
}

/// Breadth-first growth of `region` (its seeds already in it and `reached`), with jumps
/// over thin occluders.
fn grow(ev: &Evidence, reached: &mut [bool], region: &mut Vec<usize>, width: usize, height: usize) {
    let jump = ev.rules.bridge_px + 1;
    let mut head = 0;
    while head < region.len() {
        let p = region[head];
        head += 1;
        let (x, y) = (p % width, p / width);
        // Left, right, up, down: how far the image goes, and the index's step.
        let ways = [
            (x, 1usize.wrapping_neg()),
            (width - 1 - x, 1),
            (y, width.wrapping_neg()),
            (height - 1 - y, width),
        ];
        for (room, stride) in ways {
            let mut q = p;
            for _ in 0..jump.min(room) {
                q = q.wrapping_add(stride);
                if reached[q] {
                    break;
                }
                if ev.admissible(q) && ev.step_ok(p, q) {
                    reached[q] = true;
                    region.push(q);
                    break;
                }
            }
        }
    }
}

/// Breadth-first spread of `region` (its pixels already `reached`), at most `rounds`
/// rounds, each adding the 4-neighbours `q` of the last round's pixels that `admit(p, q)`
/// lets in from the region's pixel `p`; it stops early once a round adds nothing. The edge
/// refinement is [`REFINE_ROUNDS`] rounds with the growth's tests but the texture test
/// (the texture window of a pixel next to the horizon sees the horizon); `usize::MAX`
/// rounds is a flood fill.
fn spread(
    reached: &mut [bool],
    region: &mut Vec<usize>,
    width: usize,
    height: usize,
    rounds: usize,
    admit: impl Fn(usize, usize) -> bool,
) {
    if rounds == 0 {
        return;
    }
    // The first round from the pixels with a neighbour not reached: the others (a whole
    // sky's inside) can add nothing, and finding them in parallel, in the region's order,
    // saves testing every neighbour of millions of pixels on one core.
    let first = open_pixels(reached, region, width, height);
    let mut from = region.len();
    add_neighbours(&first, reached, region, width, height, &admit);
    for _ in 1..rounds {
        let to = region.len();
        if from == to {
            break;
        }
        for i in from..to {
            add_neighbours(&[region[i]], reached, region, width, height, &admit);
        }
        from = to;
    }
}

/// Adds to `region` (and `reached`) the 4-neighbours `q` of the pixels of `from` not yet
/// reached that `admit(p, q)` lets in from `p`.
fn add_neighbours(
    from: &[usize],
    reached: &mut [bool],
    region: &mut Vec<usize>,
    width: usize,
    height: usize,
    admit: &impl Fn(usize, usize) -> bool,
) {
    for &p in from {
        for q in neighbours4(p, p % width, p / width, width, height)
            .into_iter()
            .flatten()
        {
            if !reached[q] && admit(p, q) {
                reached[q] = true;
                region.push(q);
            }
        }
    }
}

/// The pixels of `region` with a 4-neighbour not `reached`, in the region's order.
fn open_pixels(reached: &[bool], region: &[usize], width: usize, height: usize) -> Vec<usize> {
    let open = |p: usize| {
        neighbours4(p, p % width, p / width, width, height)
            .into_iter()
            .flatten()
            .any(|q| !reached[q])
    };
    crate::parallel::filter_in_order(region, |_, p| open(p))
}

/// Turns the gaps of `sky` into sky (see the module docs).
fn fill_gaps(ev: &Evidence, sky: &mut [bool], width: usize, height: usize) {
    if !sky.iter().any(|&s| s) {
        return;
    }
    let not_sky: Vec<bool> = sky.iter().map(|s| !s).collect();
    let comps = label_mask(&not_sky, width, height);
    let max_gap = ev.rules.max_gap_fraction * (width * height) as f64;
    for c in &comps.list {
        if c.reaches_bottom(height) {
            continue;
        }
        let pixels = comps.pixels_of(c);
        let confident = pixels.iter().any(|&p| ev.has(p as usize, CONFIDENT, 0));
        if confident {
            continue;
        }
        let bright = pixels
            .iter()
            .filter(|&&p| ev.has(p as usize, BRIGHT, 0))
            .count();
        if c.len as f64 <= max_gap || 2 * bright >= c.len {
            pixels.iter().for_each(|&p| sky[p as usize] = true);
        }
    }
}

/// Turns into sky the pixels whose range alone kept them out of it: a stereo matcher's
/// streaks, where semi-global matching carries an object's disparity along the rows of a
/// textureless sky as smooth, backed-up values (the range calls them confident, so the
/// growth stops at them, and fogged at the object's range they show as a band of clear
/// sky). Each 4-connected set of such pixels next to the sky, reached from the sky in
/// colour steps of at most half [`ImageSkyRules::max_step`], that are smooth, bright and
/// blue or grey, with the edge refinement of the growth (the texture window of a pixel
/// next to the object sees the object), becomes sky unless it reaches the bottom row. A
/// real object in front of the sky stops the flood at its outline, where the colour
/// changes.
/// Returns the pixels it turned into sky.
fn reclaim_vetoed(ev: &Evidence, sky: &mut [bool], width: usize, height: usize) -> Vec<usize> {
    let vetoed: Vec<bool> = (0..width * height)
        .into_par_iter()
        .map(|p| !sky[p] && ev.has(p, BRIGHT | BLUE_OR_GREY | CONFIDENT, 0))
        .collect();
    let mut reclaimed = Vec::new();
    if !vetoed.contains(&true) {
        return reclaimed;
    }
    let smooth = |p: usize| ev.has(p, SMOOTH, 0);
    let small_step = |p: usize, q: usize| {
        let step = relative_step(ev.colour, &ev.lum, p, q, ev.eps);
        f64::from(step) <= ev.rules.max_step / 2.0
    };
    let neighbours = |p: usize| neighbours4(p, p % width, p / width, width, height);
    let mut seen = vec![false; width * height];
    let mut set = Vec::new();
    for start in 0..width * height {
        if !sky[start] {
            continue;
        }
        for q in neighbours(start).into_iter().flatten() {
            if seen[q] || !vetoed[q] || !smooth(q) || !small_step(start, q) {
                continue;
            }
            set.clear();
            set.push(q);
            seen[q] = true;
            spread(&mut seen, &mut set, width, height, usize::MAX, |p, r| {
                vetoed[r] && smooth(r) && small_step(p, r)
            });
            spread(&mut seen, &mut set, width, height, REFINE_ROUNDS, |p, r| {
                vetoed[r] && small_step(p, r)
            });
            if !reaches_bottom(&set, width, height) {
                set.iter().for_each(|&p| sky[p] = true);
                reclaimed.extend_from_slice(&set);
            }
        }
    }
    reclaimed
}

/// Grows the sky on from the streaks [`reclaim_vetoed`] gave it, as the first growth grew
/// it from its seeds: a gap of sky between far towers, closed off by a streak across its
/// top, is reached only through the streak, and left out it was filled as a hole from the
/// scene round it, nearer than the towers (a clear blotch in the fog). A region that
/// reaches the bottom row leaked and is dropped, as in [`grow_regions`].
fn grow_past_reclaimed(
    ev: &Evidence,
    sky: &mut [bool],
    reclaimed: &[usize],
    width: usize,
    height: usize,
) {
    let mut reached = sky.to_vec();
    let mut region = Vec::new();
    for &seed in reclaimed {
        region.clear();
        region.push(seed);
        grow_and_refine(ev, &mut reached, &mut region, width, height);
        if !reaches_bottom(&region, width, height) {
            region.iter().for_each(|&p| sky[p] = true);
        }
    }
}

/// Adds to `sky` the pixels of the depth rules' sky that are admissible (smooth, bright,
/// blue or grey, in a region too small to be kept on its own), and those reached from
/// the sky over pixels of that sky that look like sky or glow (bright and smooth, whatever
/// the hue: a sunset's orange under the blue), in the growth's colour steps (a textured
/// cloud, the sky's rim at the skyline whose texture window sees the skyline), then
/// [`REFINE_ROUNDS`] rounds more over bright pixels in those steps (the glow's rim); of
/// all these, only the ones open to the sky above them ([`keep_open_to_the_sky`]: a light
/// grey face beyond the reach is admissible, but has its top edge above it).
fn join_depth_sky(
    ev: &Evidence,
    sky: &mut [bool],
    depth_sky: &[bool],
    width: usize,
    height: usize,
) {
    let mut reached: Vec<bool> = (0..sky.len())
        .into_par_iter()
        .map(|p| sky[p] || (depth_sky[p] && ev.admissible(p)))
        .collect();
    let mut region = crate::parallel::indices_in_order(sky.len(), |p| reached[p]);
    spread(
        &mut reached,
        &mut region,
        width,
        height,
        usize::MAX,
        |p, q| depth_sky[q] && ev.step_ok(p, q) && (ev.looks_like_sky(q) || ev.glows(q)),
    );
    // The edge refinement of the growth: the texture window of the glow's last rows sees
    // the skyline.
    spread(
        &mut reached,
        &mut region,
        width,
        height,
        REFINE_ROUNDS,
        |p, q| depth_sky[q] && ev.step_ok(p, q) && ev.has(q, BRIGHT, 0),
    );
    keep_open_to_the_sky(ev, sky, &reached, width, height);
}

/// Adds to `sky` the pixels of `joined` open to the sky above them: in each column, those
/// with only joined pixels above them up to the sky found (or the top row), each within
/// the growth's colour step of the one above. Sky-coloured water beyond the reach (the
/// sky's reflection, reached from the sky round the far city's towers or through a pale
/// building standing in it) is under the far city, or under a building of another
/// colour: it is the scene beyond the reach receding to the horizon, not sky. A sunset's
/// glow, a cloud, the sky's rim are open; a patch of sky between branches is not (beyond
/// the reach, it has the sky's range above the horizon all the same).
fn keep_open_to_the_sky(
    ev: &Evidence,
    sky: &mut [bool],
    joined: &[bool],
    width: usize,
    height: usize,
) {
    // Row by row (each column's state apart), as the pixels lie in memory.
    let mut open = vec![true; width];
    for y in 0..height {
        for (x, open) in open.iter_mut().enumerate() {
            let p = y * width + x;
            if sky[p] {
                *open = true;
            } else if joined[p] && *open && (y == 0 || ev.step_ok(p - width, p)) {
                sky[p] = true;
            } else {
                *open = false;
            }
        }
    }
}

/// The growth of one region from its seeds (already in it and `reached`), then its edge
/// refinement: [`REFINE_ROUNDS`] rounds with the growth's tests but the texture test.
fn grow_and_refine(
    ev: &Evidence,
    reached: &mut [bool],
    region: &mut Vec<usize>,
    width: usize,
    height: usize,
) {
    grow(ev, reached, region, width, height);
    spread(reached, region, width, height, REFINE_ROUNDS, |p, q| {
        ev.looks_like_sky(q) && ev.step_ok(p, q)
    });
}

/// Whether any pixel of `region` is on the bottom row.
fn reaches_bottom(region: &[usize], width: usize, height: usize) -> bool {
    let bottom_row = (height - 1) * width;
    region.iter().any(|&p| p >= bottom_row)
}

#[cfg(test)]
mod tests {
    use super::super::range_class::range_classes;
    use super::*;
    use crate::raster::Grid;

    /// 80 % of the frame is sky, darker at the zenith than its median: still all sky.
    #[test]
    fn a_frame_mostly_of_sky_keeps_its_dark_zenith() {
        let (w, h) = (40, 50);
        let image = Grid::from_fn(w, h, |_, y| {
            if y < 40 {
                let t = y as f32 / 40.0;
                [0.2 + 0.4 * t, 0.3 + 0.4 * t, 0.6 + 0.3 * t]
            } else {
                [0.15, 0.1, 0.05]
            }
        });
        let range: Vec<f32> = (0..w * h)
            .map(|p| if p / w < 40 { f32::NAN } else { 10.0 })
            .collect();
        let classes = range_classes(&range, w, h, None);
        let found = image_sky(
            &image,
            &classes,
            &vec![false; w * h],
            &ImageSkyRules::default(),
            0.01,
        );
        for (p, &s) in found.sky.iter().enumerate() {
            assert_eq!(s, p / w < 40, "pixel ({}, {})", p % w, p / w);
        }
    }

    /// A smooth blue sky over rows 0..20, lighter toward the horizon.
    fn sky_colour(y: usize) -> [f32; 3] {
        let t = y as f32 / 20.0;
        [0.4 + 0.1 * t, 0.5 + 0.1 * t, 0.8 + 0.05 * t]
    }

    /// Textured, brownish ground.
    fn ground_colour(x: usize, y: usize) -> [f32; 3] {
        let k = ((x * 7 + y * 13) % 5) as f32 / 5.0;
        [0.2 + 0.2 * k, 0.15 + 0.1 * k, 0.1]
    }

    /// A sky over a textured ground; an unknown band on the left through both; a one-pixel
    /// dark wire across the sky.
    #[test]
    fn sky_crosses_a_wire_and_stops_at_the_band_scene() {
        let (w, h) = (60, 40);
        let image = Grid::from_fn(w, h, |x, y| match y {
            8 => [0.05, 0.05, 0.05],
            0..20 => sky_colour(y),
            _ => ground_colour(x, y),
        });
        let range: Vec<f32> = (0..w * h)
            .map(|p| {
                let (x, y) = (p % w, p / w);
                if x < 8 || y < 20 {
                    f32::NAN
                } else {
                    50.0 - y as f32
                }
            })
            .collect();
        let classes = range_classes(&range, w, h, None);
        let sky = image_sky(
            &image,
            &classes,
            &vec![false; w * h],
            &ImageSkyRules::default(),
            0.01,
        )
        .sky;
        // The wire itself is a long dark gap: not sky here (`prepare` then finds it a
        // hole with nothing but sky round it, and makes it sky).
        for (p, &s) in sky.iter().enumerate() {
            let y = p / w;
            assert_eq!(s, y < 20 && y != 8, "pixel ({}, {y})", p % w);
        }
    }

    /// Sky between two grey towers, closed off at the top by a matcher's streak (the
    /// towers' range carried across it): reached only through the streak, it is sky once
    /// the streak is; the towers and the ground are not.
    #[test]
    fn a_gap_of_sky_closed_off_by_a_streak_is_sky() {
        let (w, h) = (60, 40);
        let tower = |x: usize, y: usize| {
            ((20..26).contains(&x) || (34..40).contains(&x)) && (3..20).contains(&y)
        };
        // Thicker than the growth's jump over thin occluders (6 px).
        let streak = |x: usize, y: usize| (26..34).contains(&x) && (3..12).contains(&y);
        // Slivers within 2 px of a tower and of the ground may stay out, as in open sky
        // (the texture window sees the object).
        let gap = |x: usize, y: usize| (28..32).contains(&x) && (12..18).contains(&y);
        let image = Grid::from_fn(w, h, |x, y| match () {
            _ if tower(x, y) => [0.3, 0.3, 0.3],
            _ if y < 20 => sky_colour(y),
            _ => ground_colour(x, y),
        });
        let range: Vec<f32> = (0..w * h)
            .map(|p| {
                let (x, y) = (p % w, p / w);
                match () {
                    _ if tower(x, y) || streak(x, y) => 80.0,
                    _ if y < 20 => f32::NAN,
                    _ => 50.0 - y as f32,
                }
            })
            .collect();
        let classes = range_classes(&range, w, h, None);
        let rules = ImageSkyRules::default();
        let sky = image_sky(&image, &classes, &vec![false; w * h], &rules, 0.01).sky;
        for (p, &s) in sky.iter().enumerate() {
            let (x, y) = (p % w, p / w);
            if streak(x, y) || gap(x, y) {
                assert!(s, "sky at ({x}, {y})");
            }
            if tower(x, y) || y >= 20 {
                assert!(!s, "not sky at ({x}, {y})");
            }
        }
    }

    #[test]
    fn a_matchers_streak_in_the_sky_is_sky_and_the_tower_it_came_from_is_not() {
        // A smooth blue sky over rows 0..20 and textured ground below; a grey tower (x
        // 30..36, from row 5 down) and a sky-coloured wall (x 45..52, from row 12 down),
        // both standing on the ground; and a semi-global matcher's streak, the tower's
        // range carried along rows 8..11 of the sky.
        let (w, h) = (60, 40);
        let tower = |x: usize, y: usize| (30..36).contains(&x) && y >= 5;
        let wall = |x: usize, y: usize| (45..52).contains(&x) && y >= 12;
        let streak = |x: usize, y: usize| (5..30).contains(&x) && (8..11).contains(&y);
        let image = Grid::from_fn(w, h, |x, y| {
            if tower(x, y) {
                [0.3, 0.3, 0.3]
            } else if wall(x, y) {
                sky_colour(12)
            } else if y < 20 {
                sky_colour(y)
            } else {
                ground_colour(x, y)
            }
        });
        let range: Vec<f32> = (0..w * h)
            .map(|p| {
                let (x, y) = (p % w, p / w);
                match () {
                    _ if tower(x, y) || streak(x, y) => 80.0,
                    _ if wall(x, y) => 60.0,
                    _ if y < 20 => f32::NAN,
                    _ => 50.0 - y as f32,
                }
            })
            .collect();
        let classes = range_classes(&range, w, h, None);
        assert_eq!(classes[9 * w + 15], RangeClass::Confident, "the streak");
        let rules = ImageSkyRules::default();
        let sky = image_sky(&image, &classes, &vec![false; w * h], &rules, 0.01).sky;
        // Slivers of sky within 2 px of an object and of the ground may stay out, as
        // without a streak (the texture window sees the object).
        let open_sky = |x: usize, y: usize| {
            (y < 18 && !(28..38).contains(&x) && !(43..54).contains(&x)) || (x < 28 && y < 20)
        };
        for (p, &s) in sky.iter().enumerate() {
            let (x, y) = (p % w, p / w);
            if streak(x, y) || open_sky(x, y) {
                assert!(s, "sky at ({x}, {y})");
            }
            if tower(x, y) || wall(x, y) || y >= 20 {
                assert!(!s, "not sky at ({x}, {y})");
            }
        }
    }
}
