//! Hole filling by RANSAC over constants, planes in range and planes of the scene (planes
//! in inverse range) sampled from the hole boundary.
//!
//! See the module docs of [`crate::prep`] for the method and its justification.

use super::colour_guide::{split, ColourGuide, Pixel};
use super::occlusion::Occlusions;
use crate::rng::SplitMix64;
use crate::{Error, Result};

/// Boundaries longer than this are scored on an evenly strided subset of this many edges.
const MAX_SCORED: usize = 1024;
/// Plane candidates are only tried when the boundary has at least this many edges.
const MIN_PLANE_EDGES: usize = 4;
/// 1.4826 x MAD estimates the standard deviation of Gaussian data.
pub(crate) const MAD_TO_SIGMA: f64 = 1.4826;

/// One boundary edge: a known pixel `(x, y)` with range `r`, 4-adjacent to a hole pixel.
#[derive(Clone, Copy, Debug)]
struct Edge {
    x: i32,
    y: i32,
    r: f32,
}

impl Edge {
    /// The value a plane is fitted to: the range, or its inverse for a plane of the scene.
    fn fitted(&self, inverse: bool) -> f64 {
        match inverse {
            false => f64::from(self.r),
            true => 1.0 / f64::from(self.r),
        }
    }
}

/// A candidate fill surface, in coordinates relative to the hole's origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Model {
    /// R = c.
    Constant(f64),
    /// R = a + b (x - ox) + c (y - oy).
    Plane { a: f64, b: f64, c: f64 },
    /// 1/R = a + b (x - ox) + c (y - oy): a plane of the scene (in a pinhole camera its
    /// inverse depth is affine in the pixel's position), infinitely far where it reaches
    /// its horizon.
    InversePlane { a: f64, b: f64, c: f64 },
}

impl Model {
    /// The plane `a + b dx + c dy` in range, or in inverse range for a plane of the scene.
    fn affine(inverse: bool, [a, b, c]: [f64; 3]) -> Model {
        match inverse {
            false => Model::Plane { a, b, c },
            true => Model::InversePlane { a, b, c },
        }
    }

    #[inline]
    fn eval(&self, dx: f64, dy: f64) -> f64 {
        match *self {
            Model::Constant(c) => c,
            Model::Plane { a, b, c } => a + b * dx + c * dy,
            Model::InversePlane { a, b, c } => match a + b * dx + c * dy {
                d if d > 0.0 => 1.0 / d,
                _ => f64::INFINITY,
            },
        }
    }
}

/// Reusable buffers for filling holes one after the other.
pub(crate) struct HoleFiller {
    edges: Vec<Edge>,
    scratch: Vec<f64>,
    /// The farthest a plane of the scene may be continued to: the farthest known range
    /// outside the sky.
    far_limit: f64,
    /// The stereo occlusions: their unknown pixels and the known pixels that occlude them
    /// (empty: none).
    occlusions: Occlusions,
    /// Whether the hole being filled leaves its edges to the occluders out.
    skip_occluders: bool,
}

/// A hole that holds a stereo occlusion is filled without its edges to the occluders when
/// at least this many others are left (else with all of them, as any hole).
const MIN_EDGES_BESIDE_OCCLUDERS: usize = 4;

/// A region of one colour in such a hole is filled from its edges to known pixels of its
/// own colour without those to the occluders when any others are left (the background of
/// its colour beside it), else with them: a region whose colour only the occluder shows is
/// the part of it the matcher missed. (Falling back below [`MIN_OWN_EDGES`] instead gave
/// the rows of a textured wall, one edge to the wall each, the pole's fattened edge of the
/// wall's colour, and a ramp.)
const MIN_OWN_EDGES_BESIDE_OCCLUDERS: usize = 1;

impl HoleFiller {
    /// A filler whose planes of the scene go no farther than `far_limit`, the farthest
    /// known range outside the sky (as the border bands' continuation), and that leaves
    /// the occluders of `occlusions` (of the image's size, or none) out of the holes that
    /// hold an occlusion ([`HoleFiller::begin_hole`]).
    pub(crate) fn new(far_limit: f64, occlusions: Occlusions) -> Self {
        HoleFiller {
            edges: Vec::new(),
            scratch: Vec::new(),
            far_limit,
            occlusions,
            skip_occluders: false,
        }
    }

    /// Applies `fit`, a fit to a whole hole or a piece of it, to `pixels`, except to a
    /// pixel of a stereo occlusion while the hole's occluders are skipped: that continues
    /// the background beside its run, the range of the run's known end on its row on the
    /// background's side (left in a left view, right in a right view).
    /// A plane fitted to an occlusion along a pole is fitted to edges on one vertical line
    /// (the background's, the occluders left out), which leave its slope across the run
    /// to a few edges elsewhere: on a Cityscapes frame one sloped 0.38 m a pixel, and 13
    /// rows of the wall beside a pole ramped from the wall's 24 m to the pole's 12.
    fn apply_beside_occlusions(&self, fit: &Fit, work: &mut [f32], width: usize, pixels: &[u32]) {
        let occluded = &self.occlusions.occluded;
        for &p in pixels {
            let p = p as usize;
            work[p] = if self.skip_occluders && occluded[p] {
                let row_start = p - p % width;
                let end = if self.occlusions.background_right {
                    (p..row_start + width).find(|&q| !occluded[q])
                } else {
                    (row_start..p).rev().find(|&q| !occluded[q])
                };
                // `occlusion::find` takes a run only with a known pixel on its background's side.
                end.map_or(f32::NAN, |q| work[q])
            } else {
                fit.at((p % width) as f64, (p / width) as f64) as f32
            };
        }
    }

    /// Sets whether the hole of `pixels` filled next holds a stereo occlusion: then its
    /// occluders are not boundary values (unless fewer than [`MIN_EDGES_BESIDE_OCCLUDERS`]
    /// other edges are left to a whole hole), and its occluded pixels that no region of
    /// their own colour fills continue their row's background
    /// ([`HoleFiller::apply_beside_occlusions`]).
    pub(crate) fn begin_hole(&mut self, pixels: &[u32]) {
        let occluded = &self.occlusions.occluded;
        self.skip_occluders = !occluded.is_empty() && pixels.iter().any(|&p| occluded[p as usize]);
    }

    /// Fills the hole made of `pixels` in `work` (known pixels finite, the hole's pixels
    /// not finite), drawing candidates with `rng`: `trials` constants, `trials` planes in
    /// range and `trials` planes of the scene.
    pub(crate) fn fill(
        &mut self,
        work: &mut [f32],
        width: usize,
        height: usize,
        pixels: &[u32],
        trials: usize,
        rng: &mut SplitMix64,
    ) -> Result<()> {
        let all = |_, _| true;
        self.collect_edges_beside_occluders(
            work,
            (width, height),
            pixels,
            all,
            MIN_EDGES_BESIDE_OCCLUDERS,
        );
        no_boundary_error(&self.edges, pixels)?;
        let fit = self.fit(trials, rng);
        self.apply_beside_occlusions(&fit, work, width, pixels);
        Ok(())
    }

    /// Fills the hole made of `pixels` as [`HoleFiller::fill`] does, but each region of one
    /// colour in it that has at least [`MIN_OWN_EDGES`] boundary edges to known pixels of
    /// its own colour, most of which agree with one surface, from those edges alone (a
    /// surface seen in the image continues its own range, not that of whatever else
    /// borders the hole). Regions whose edges disagree and large pieces of the rest take
    /// the whole hole's surface, small pieces of the rest the range round them once the
    /// regions are filled (see [`crate::prep`], step 4). `state` is scratch of `work`'s
    /// length, not [`Pixel::InHole`] anywhere. Returns the number of regions filled on
    /// their own.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn fill_by_colour(
        &mut self,
        work: &mut [f32],
        size: (usize, usize),
        pixels: &[u32],
        guide: &ColourGuide,
        state: &mut [Pixel],
        trials: usize,
        rng: &mut SplitMix64,
    ) -> Result<usize> {
        let all = |_, _| true;
        self.collect_edges_beside_occluders(work, size, pixels, all, MIN_EDGES_BESIDE_OCCLUDERS);
        no_boundary_error(&self.edges, pixels)?;
        // The whole hole's surface, for what is not filled otherwise; among that, a region
        // whose own colour's edges disagree (a column of false matches on a face without
        // texture among the right ones).
        let whole = self.fit(trials, rng);
        let mut fits = Vec::new();
        let (mut ambiguous, mut rest) = (Vec::new(), Vec::new());
        let regions = guide.regions(size, pixels, state);
        for region in regions.iter() {
            let own = |p, q| guide.own_colour(p, q);
            self.collect_edges_beside_occluders(
                work,
                size,
                region,
                own,
                MIN_OWN_EDGES_BESIDE_OCCLUDERS,
            );
            if self.edges.len() < MIN_OWN_EDGES {
                rest.extend_from_slice(region);
                continue;
            }
            let fit = self.fit(trials, rng);
            if self.agreement(&fit) >= MIN_AGREEMENT {
                fits.push((fit, region));
            } else {
                ambiguous.extend_from_slice(region);
            }
        }
        if fits.is_empty() {
            self.apply_beside_occlusions(&whole, work, size.0, pixels);
            return Ok(0);
        }
        // Applied once all are fitted: a filled region is not the boundary of the next.
        for (fit, region) in &fits {
            fit.apply(work, size.0, region);
        }
        self.apply_beside_occlusions(&whole, work, size.0, &ambiguous);
        // The rest (regions too small to have edges of their own colour: texture), in
        // pieces. A speck amid regions of the background is the background, not the mean
        // of the whole hole; a large piece (a textured surface the matcher missed whole)
        // has only other guesses round it and takes the whole hole's surface.
        let pieces = split(size, &rest, state, |_, _| true);
        for piece in pieces.iter() {
            if piece.len() > MAX_SPECK {
                self.apply_beside_occlusions(&whole, work, size.0, piece);
            } else {
                self.fill(work, size.0, size.1, piece, trials, rng)?;
            }
        }
        Ok(fits.len())
    }

    /// The RANSAC fit to the collected edges (at least one).
    fn fit(&mut self, trials: usize, rng: &mut SplitMix64) -> Fit {
        let origin = self.origin();
        let delta = self.robust_scale();
        let model = self.ransac(origin, delta, trials, rng);
        let (lo, mut hi) = self.value_range();
        // A plane of the scene continued past its farthest edge recedes (the ground toward
        // the horizon, where the sky and not a known pixel bounds the hole): as far as
        // the scene's farthest range, not only the boundary's. In a hole enclosed by
        // known pixels an affine 1/R lies between its values on the boundary anyway.
        if matches!(model, Model::InversePlane { .. }) {
            hi = hi.max(self.far_limit);
        }
        Fit {
            model,
            origin,
            lo,
            hi,
        }
    }

    /// The fraction of the collected edges within [`AGREEMENT_TOLERANCE`] of `fit`.
    fn agreement(&self, fit: &Fit) -> f64 {
        let close = self
            .edges
            .iter()
            .filter(|e| {
                let v = fit.at(e.x as f64, e.y as f64);
                (v - f64::from(e.r)).abs() <= AGREEMENT_TOLERANCE * f64::from(e.r)
            })
            .count();
        close as f64 / self.edges.len() as f64
    }

    /// The edges `keep` accepts (see [`HoleFiller::collect_edges`]): without those to
    /// occluders when the hole holds an occlusion and at least `enough` others are left,
    /// else all.
    fn collect_edges_beside_occluders(
        &mut self,
        work: &[f32],
        size: (usize, usize),
        pixels: &[u32],
        keep: impl Fn(usize, usize) -> bool + Copy,
        enough: usize,
    ) {
        self.collect_edges(work, size, pixels, keep);
        if self.skip_occluders && self.edges.len() < enough {
            self.skip_occluders = false;
            self.collect_edges(work, size, pixels, keep);
            self.skip_occluders = true;
        }
    }

    /// Every (hole pixel `p`, known 4-neighbour `q`) pair that `keep(p, q)` accepts, as the
    /// known pixel's position and value; `q` an occluder is left out while
    /// [`HoleFiller::skip_occluders`] says so.
    fn collect_edges(
        &mut self,
        work: &[f32],
        (width, height): (usize, usize),
        pixels: &[u32],
        keep: impl Fn(usize, usize) -> bool,
    ) {
        self.edges.clear();
        for &p in pixels {
            let p = p as usize;
            let (x, y) = (p % width, p / width);
            for q in super::components::neighbours4(p, x, y, width, height)
                .into_iter()
                .flatten()
            {
                let r = work[q];
                let occluder = self.skip_occluders && self.occlusions.occluders[q];
                if r.is_finite() && !occluder && keep(p, q) {
                    let (qx, qy) = ((q % width) as i32, (q / width) as i32);
                    self.edges.push(Edge { x: qx, y: qy, r });
                }
            }
        }
    }

    /// Mean position of the boundary, the origin of the plane coordinates (conditioning).
    fn origin(&self) -> (f64, f64) {
        let n = self.edges.len() as f64;
        let sx: f64 = self.edges.iter().map(|e| e.x as f64).sum();
        let sy: f64 = self.edges.iter().map(|e| e.y as f64).sum();
        (sx / n, sy / n)
    }

    /// Min and max of the boundary values: the fill is clamped to them.
    fn value_range(&self) -> (f64, f64) {
        self.edges
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), e| {
                (lo.min(e.r as f64), hi.max(e.r as f64))
            })
    }

    /// The truncation scale delta = 1.4826 MAD of the boundary values, floored at a few ulps
    /// of their median so that it is never zero.
    fn robust_scale(&mut self) -> f64 {
        self.scratch.clear();
        self.scratch.extend(self.edges.iter().map(|e| e.r as f64));
        let med = median_in_place(&mut self.scratch);
        for v in self.scratch.iter_mut() {
            *v = (*v - med).abs();
        }
        let mad = median_in_place(&mut self.scratch);
        (MAD_TO_SIGMA * mad).max(med.abs().max(f64::MIN_POSITIVE) * 8.0 * f32::EPSILON as f64)
    }

    /// RANSAC: the candidate with the lowest truncated-L1 boundary jump. Constants are tried
    /// first, so a plane must be strictly better to win.
    fn ransac(&self, origin: (f64, f64), delta: f64, trials: usize, rng: &mut SplitMix64) -> Model {
        let n = self.edges.len();
        let mut best = (f64::INFINITY, Model::Constant(self.edges[0].r as f64));
        let mut consider = |m: Model| {
            let s = self.score(&m, origin, delta);
            if s < best.0 {
                best = (s, m);
            }
        };
        if n <= trials {
            self.edges
                .iter()
                .for_each(|e| consider(Model::Constant(e.r as f64)));
        } else {
            (0..trials).for_each(|_| consider(Model::Constant(self.edges[rng.below(n)].r as f64)));
        }
        if n >= MIN_PLANE_EDGES {
            for _ in 0..trials {
                let t = [rng.below(n), rng.below(n), rng.below(n)].map(|i| self.edges[i]);
                for inverse in [false, true] {
                    if let Some(m) = plane_through(&t, origin, inverse) {
                        consider(m);
                    }
                }
            }
        }
        let (score, model) = best;
        match self.refit_plane(&model, origin, delta) {
            Some(m) if self.score(&m, origin, delta) <= score => m,
            _ => model,
        }
    }

    /// Sum over (a strided subset of at most `MAX_SCORED`) boundary edges of
    /// `min(|model(b) - R(b)|, delta)`.
    fn score(&self, m: &Model, origin: (f64, f64), delta: f64) -> f64 {
        let step = self.edges.len().div_ceil(MAX_SCORED);
        self.edges
            .iter()
            .step_by(step)
            .map(|e| {
                let v = m.eval(e.x as f64 - origin.0, e.y as f64 - origin.1);
                (v - e.r as f64).abs().min(delta)
            })
            .sum()
    }

    /// Least-squares plane through the inliers (residual < delta) of a winning plane.
    fn refit_plane(&self, m: &Model, origin: (f64, f64), delta: f64) -> Option<Model> {
        let inverse = match m {
            Model::Constant(_) => return None,
            Model::Plane { .. } => false,
            Model::InversePlane { .. } => true,
        };
        let mut ata = [[0.0f64; 3]; 3];
        let mut atb = [0.0f64; 3];
        for e in &self.edges {
            let (dx, dy) = (e.x as f64 - origin.0, e.y as f64 - origin.1);
            if (m.eval(dx, dy) - e.r as f64).abs() < delta {
                let row = [1.0, dx, dy];
                let v = e.fitted(inverse);
                for i in 0..3 {
                    for j in 0..3 {
                        ata[i][j] += row[i] * row[j];
                    }
                    atb[i] += row[i] * v;
                }
            }
        }
        Some(Model::affine(inverse, solve3(ata, atb)?))
    }
}

/// A fitted fill surface, clamped to the range of the values it was fitted to.
struct Fit {
    model: Model,
    origin: (f64, f64),
    lo: f64,
    hi: f64,
}

impl Fit {
    /// The surface at pixel `(x, y)`.
    fn at(&self, x: f64, y: f64) -> f64 {
        let (dx, dy) = (x - self.origin.0, y - self.origin.1);
        self.model.eval(dx, dy).clamp(self.lo, self.hi)
    }

    /// Writes the surface into `pixels` of `work`.
    fn apply(&self, work: &mut [f32], width: usize, pixels: &[u32]) {
        for &p in pixels {
            let p = p as usize;
            work[p] = self.at((p % width) as f64, (p / width) as f64) as f32;
        }
    }
}

/// The error for a hole with no known pixel round it.
fn no_boundary_error(edges: &[Edge], pixels: &[u32]) -> Result<()> {
    if edges.is_empty() {
        return Err(Error::Prep(format!(
            "a hole of {} pixels has no known pixel on its boundary (nothing to fill it from)",
            pixels.len()
        )));
    }
    Ok(())
}

/// A region of one colour is filled on its own from at least this many edges of its colour.
const MIN_OWN_EDGES: usize = 8;
/// ... when at least this fraction of them agree with its fit ...
const MIN_AGREEMENT: f64 = 0.7;
/// ... to within this fraction of their range.
const AGREEMENT_TOLERANCE: f64 = 0.25;
/// Pieces of the rest of at most this many pixels are filled from what is round them.
const MAX_SPECK: usize = 256;

/// The plane through three boundary edges, or `None` if they are collinear (integer
/// coordinates: the doubled triangle area is then exactly 0).
fn plane_through(t: &[Edge; 3], origin: (f64, f64), inverse: bool) -> Option<Model> {
    let rows = t.map(|e| [1.0, e.x as f64 - origin.0, e.y as f64 - origin.1]);
    let area2 = (t[1].x - t[0].x) as i64 * (t[2].y - t[0].y) as i64
        - (t[2].x - t[0].x) as i64 * (t[1].y - t[0].y) as i64;
    if area2 == 0 {
        return None;
    }
    if inverse && t.iter().any(|e| e.r <= 0.0) {
        return None;
    }
    Some(Model::affine(
        inverse,
        solve3(rows, t.map(|e| e.fitted(inverse)))?,
    ))
}

/// Solves the 3x3 system `m x = v` by Cramer's rule; `None` if (nearly) singular.
fn solve3(m: [[f64; 3]; 3], v: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&m);
    let scale: f64 = m.iter().flatten().map(|x| x.abs()).fold(0.0, f64::max);
    if !d.is_finite() || d.abs() <= 1e-12 * scale.powi(3) {
        return None;
    }
    let mut x = [0.0; 3];
    for (k, xk) in x.iter_mut().enumerate() {
        let mut mk = m;
        for i in 0..3 {
            mk[i][k] = v[i];
        }
        *xk = det(&mk) / d;
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Median of `v` (the upper median for even lengths), reordering `v`. `v` must not be empty.
pub(crate) fn median_in_place(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::RgbImage;

    #[test]
    fn solve3_identity() {
        let x = solve3(
            [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 4.0]],
            [1.0, 2.0, 4.0],
        )
        .unwrap();
        assert_eq!(x, [1.0, 1.0, 1.0]);
        assert!(solve3(
            [[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            [1.0, 1.0, 1.0]
        )
        .is_none());
    }

    #[test]
    fn constant_hole_in_constant_map() {
        let (w, h) = (5, 5);
        let mut m = vec![3.0f32; w * h];
        m[12] = f32::INFINITY;
        let mut f = HoleFiller::new(100.0, Occlusions::default());
        f.fill(&mut m, w, h, &[12], 8, &mut SplitMix64::new(1))
            .unwrap();
        assert_eq!(m[12], 3.0);
    }

    /// Row 0: a wall (20 m, 21 m at its end), a run of 4 unknown pixels taken as a stereo
    /// occlusion, its occluder (5 m); row 1: unknown pixels of no occlusion.
    fn wall_pole_and_run() -> (Vec<f32>, Occlusions, Fit) {
        let n = f32::NAN;
        let work = vec![
            20.0, 21.0, n, n, n, n, 5.0, 5.0, //
            20.0, n, n, n, n, n, 5.0, 5.0,
        ];
        let occlusions = Occlusions {
            occluded: (0..16).map(|p| (2..6).contains(&p)).collect(),
            occluders: (0..16).map(|p| p == 6 || p == 7).collect(),
            background_right: false,
            count: 4,
        };
        // A plane sloped across the run, as one fitted to a whole hole along a pole.
        let sloped = Fit {
            model: Model::Plane {
                a: 20.0,
                b: -3.0,
                c: 0.0,
            },
            origin: (1.0, 0.0),
            lo: 0.0,
            hi: 100.0,
        };
        (work, occlusions, sloped)
    }

    #[test]
    fn an_occlusion_continues_its_rows_background_not_a_plane_across_it() {
        let (mut work, occlusions, sloped) = wall_pole_and_run();
        let run = [2u32, 3, 4, 5];
        let other = [9u32, 10, 11, 12, 13];
        let mut filler = HoleFiller::new(100.0, occlusions);
        filler.begin_hole(&run);
        filler.apply_beside_occlusions(&sloped, &mut work, 8, &[&run[..], &other[..]].concat());
        assert_eq!(&work[2..6], &[21.0; 4]);
        for p in other {
            let expected = sloped.at(f64::from(p % 8), 1.0) as f32;
            assert_eq!(work[p as usize], expected, "pixel {p}");
        }
        // The same pixels in a hole holding no occlusion take the plane.
        let (mut work, occlusions, sloped) = wall_pole_and_run();
        let mut filler = HoleFiller::new(100.0, occlusions);
        filler.begin_hole(&other);
        filler.apply_beside_occlusions(&sloped, &mut work, 8, &run);
        assert_eq!(work[2], sloped.at(2.0, 0.0) as f32);
        assert_eq!(work[5], 8.0);
    }

    /// A right view's occlusion, the row mirrored: its background is right of the run.
    #[test]
    fn a_right_views_occlusion_continues_the_background_right_of_it() {
        let (mut work, mut occlusions, sloped) = wall_pole_and_run();
        work[..8].reverse();
        occlusions.occluded[..8].reverse();
        occlusions.occluders[..8].reverse();
        occlusions.background_right = true;
        let run = [2u32, 3, 4, 5];
        let mut filler = HoleFiller::new(100.0, occlusions);
        filler.begin_hole(&run);
        filler.apply_beside_occlusions(&sloped, &mut work, 8, &run);
        assert_eq!(&work[2..6], &[21.0; 4]);
    }

    /// The range of the ground 1.5 m below a level pinhole camera (focal 500 px, principal
    /// point at the centre of a 64 x 48 frame whose horizon is row -10, above it): depth
    /// Z = f H / (y - y_h), range Z sqrt(1 + ((x - cx)² + (y - cy)²) / f²).
    fn ground(x: usize, y: usize) -> f64 {
        let (f, height, horizon) = (500.0, 1.5, -10.0);
        let (dx, dy) = (x as f64 - 31.5, y as f64 - 23.5);
        let z = f * height / (y as f64 - horizon);
        z * (1.0 + (dx * dx + dy * dy) / (f * f)).sqrt()
    }

    // A hole in the ground was filled with a plane in range, a ramp that puts its middle
    // rows much farther than the ground they show (range grows as 1 / (y - y_h) toward the
    // horizon, not linearly). A plane of the scene is affine in inverse depth, and nearly
    // so in inverse range: that plane fills it.
    #[test]
    fn a_hole_in_the_ground_is_filled_with_the_ground() {
        let (w, h) = (64, 48);
        let mut work: Vec<f32> = (0..w * h).map(|p| ground(p % w, p / w) as f32).collect();
        let inside = |x: usize, y: usize| (8..56).contains(&x) && (4..44).contains(&y);
        let hole: Vec<u32> = (0..w * h)
            .filter(|&p| inside(p % w, p / w))
            .map(|p| p as u32)
            .collect();
        hole.iter().for_each(|&p| work[p as usize] = f32::INFINITY);
        HoleFiller::new(100.0, Occlusions::default())
            .fill(&mut work, w, h, &hole, 32, &mut SplitMix64::new(5))
            .unwrap();
        let worst = hole.iter().fold(0.0f64, |m, &p| {
            let (x, y) = (p as usize % w, p as usize / w);
            m.max((f64::from(work[p as usize]) / ground(x, y) - 1.0).abs())
        });
        assert!(worst < 0.01, "worst relative error {worst}");
        // The ramp a plane in range would be: rows 4 and 43 at the centre, linear between.
        let (top, bottom) = (ground(32, 3), ground(32, 44));
        let ramp = top + (bottom - top) * (23.5 - 3.0) / 41.0;
        assert!(
            ramp / ground(32, 23) - 1.0 > 0.4,
            "{ramp} {}",
            ground(32, 23)
        );
    }

    // The ground's unknown far part below the sky (+inf, not a boundary value) continues
    // the ground past the boundary's farthest value, up to the filler's far limit.
    #[test]
    fn the_ground_below_the_sky_recedes_up_to_the_far_limit() {
        let (w, h) = (64, 48);
        // Sky above row 4, a hole from there down to row 20 (left half) or 24 (right half):
        // the step gives the boundary a second row, so planes can be fitted.
        let bottom = |x: usize| if x < 32 { 20 } else { 24 };
        let start: Vec<f32> = (0..w * h)
            .map(|p| match (p % w, p / w) {
                (_, y) if y < 4 => f32::INFINITY,
                (x, y) if y < bottom(x) => f32::NAN,
                (x, y) => ground(x, y) as f32,
            })
            .collect();
        let hole: Vec<u32> = (0..w * h)
            .filter(|&p| start[p].is_nan())
            .map(|p| p as u32)
            .collect();
        let farthest_edge = (0..w).map(|x| ground(x, bottom(x))).fold(0.0, f64::max);
        let top = 4 * w + 20;
        assert!(ground(20, 4) > 2.0 * farthest_edge);
        for far_limit in [100.0, 40.0] {
            let mut work = start.clone();
            HoleFiller::new(far_limit, Occlusions::default())
                .fill(&mut work, w, h, &hole, 32, &mut SplitMix64::new(5))
                .unwrap();
            let want = ground(20, 4).min(far_limit);
            let got = f64::from(work[top]);
            assert!(
                (got / want - 1.0).abs() < 0.01,
                "limit {far_limit}: {got} / {want}"
            );
        }
    }

    /// A 20 x 10 frame: grey 0.2 left of x = 10, grey 0.8 right of it; range 10 left of
    /// x = 5, 50 from x = 15, a hole between (infinite, as `label_unknown` leaves holes).
    fn two_faces() -> (RgbImage, Vec<f32>, Vec<u32>) {
        let (w, h) = (20, 10);
        let image = RgbImage::from_fn(w, h, |x, _| if x < 10 { [0.2; 3] } else { [0.8; 3] });
        let work: Vec<f32> = (0..w * h)
            .map(|p| match p % w {
                x if x < 5 => 10.0,
                x if x >= 15 => 50.0,
                _ => f32::INFINITY,
            })
            .collect();
        let hole = (0..w * h)
            .filter(|&p| !work[p].is_finite())
            .map(|p| p as u32)
            .collect();
        (image, work, hole)
    }

    fn fill_by_colour(image: &RgbImage, work: &mut [f32], hole: &[u32], seed: u64) -> usize {
        let guide = ColourGuide::new(image, 0.08);
        let mut state = vec![Pixel::Other; work.len()];
        HoleFiller::new(100.0, Occlusions::default())
            .fill_by_colour(
                work,
                (image.width(), image.height()),
                hole,
                &guide,
                &mut state,
                8,
                &mut SplitMix64::new(seed),
            )
            .unwrap()
    }

    #[test]
    fn each_colour_continues_its_own_surface() {
        let (image, mut work, hole) = two_faces();
        let mut plain = work.clone();
        HoleFiller::new(100.0, Occlusions::default())
            .fill(&mut plain, 20, 10, &hole, 8, &mut SplitMix64::new(3))
            .unwrap();
        // Without the image the plane through both sides wins: a ramp across the hole.
        assert!(
            (20.0..40.0).contains(&plain[5 * 20 + 9]),
            "{}",
            plain[5 * 20 + 9]
        );

        assert_eq!(fill_by_colour(&image, &mut work, &hole, 3), 2);
        for &p in &hole {
            let expected = if p % 20 < 10 { 10.0 } else { 50.0 };
            assert_eq!(work[p as usize], expected, "pixel {p}");
        }
    }

    #[test]
    fn a_speck_of_another_colour_takes_what_is_round_it() {
        let (mut image, mut work, hole) = two_faces();
        *image.get_mut(7, 5) = [0.5, 0.1, 0.1];
        fill_by_colour(&image, &mut work, &hole, 3);
        assert_eq!(work[5 * 20 + 7], 10.0);
    }

    #[test]
    fn a_colour_whose_known_pixels_disagree_takes_the_whole_holes_surface() {
        // The left face's known pixels say 10 in its top half and 100 in its bottom half
        // (false matches on a face without texture): no fit of them is trusted.
        let (image, mut work, hole) = two_faces();
        (5 * 20..10 * 20)
            .filter(|p| p % 20 < 5)
            .for_each(|p| work[p] = 100.0);
        let mut plain = work.clone();
        HoleFiller::new(100.0, Occlusions::default())
            .fill(&mut plain, 20, 10, &hole, 8, &mut SplitMix64::new(3))
            .unwrap();
        assert_eq!(fill_by_colour(&image, &mut work, &hole, 3), 1);
        for &p in hole.iter().filter(|&&p| p % 20 < 10) {
            assert_eq!(work[p as usize], plain[p as usize], "pixel {p}");
        }
        assert_eq!(work[5 * 20 + 12], 50.0);
    }
}
