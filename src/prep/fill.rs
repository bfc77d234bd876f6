//! Hole filling by RANSAC over constants, planes in range and planes of the scene (planes
//! in inverse range) sampled from the hole boundary.
//!
//! See the module docs of [`crate::prep`] for the method and its justification.

use super::colour_guide::{split, ColourGuide, Pixel};
use super::ground::Road;
use super::occlusion::Occlusions;
use crate::rng::SplitMix64;
use crate::{Error, Result};

/// Boundaries longer than this are scored on an evenly strided subset of this many edges.
const MAX_SCORED: usize = 1024;
/// A plane sloped across a line of edges wins over the best plane level along one only
/// when its score is lower by this many truncation scales δ: its slope across the line
/// rests on the few edges off it, and one (a pole's edge beside a column of a wall's, a
/// table's edge beside a band's column) tilted a whole band or row into a ramp.
const SLOPE_ACROSS_COST: f64 = 2.0;
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
    /// The level road under a camera of known mount; `origin` is the hole's.
    Road { road: Road, origin: (f64, f64) },
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
            Model::Road { road, origin } => road.range_at(origin.0 + dx, origin.1 + dy),
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
    /// The level road, a candidate for every hole, when the camera's mount is known.
    road: Option<Road>,
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
            road: None,
        }
    }

    /// Offers the level road (a vehicle camera's, [`super::PrepOptions::ground`]) to every
    /// hole as a candidate beside the planes drawn from its boundary.
    pub(crate) fn with_road(mut self, road: Option<Road>) -> Self {
        self.road = road;
        self
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
            let fit = self.fit_region(trials, rng);
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

    /// The RANSAC fit to the collected edges (at least one) of a whole hole, a sloped plane
    /// paying [`SLOPE_ACROSS_COST`] against a level one.
    fn fit(&mut self, trials: usize, rng: &mut SplitMix64) -> Fit {
        self.fit_with(trials, rng, SLOPE_ACROSS_COST)
    }

    /// [`HoleFiller::fit`] for a region of one colour: its edges are its own colour's, and
    /// a sloped plane competes with a level one on its score alone.
    fn fit_region(&mut self, trials: usize, rng: &mut SplitMix64) -> Fit {
        self.fit_with(trials, rng, 0.0)
    }

    /// The RANSAC fit, a sloped plane paying `slope_cost` truncation scales against the
    /// best level one, clamped to the edges' values.
    fn fit_with(&mut self, trials: usize, rng: &mut SplitMix64, slope_cost: f64) -> Fit {
        let origin = self.origin();
        let delta = self.robust_scale();
        let model = self.ransac(origin, delta, trials, rng, slope_cost);
        let (lo, mut hi) = self.value_range();
        // A plane of the scene continued past its farthest edge recedes (the ground toward
        // the horizon, where the sky and not a known pixel bounds the hole): as far as
        // the scene's farthest range, not only the boundary's. In a hole enclosed by
        // known pixels an affine 1/R lies between its values on the boundary anyway.
        if matches!(model, Model::InversePlane { .. } | Model::Road { .. }) {
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
    /// first, so a plane must be strictly better to win; a plane sloped across a line of
    /// edges must also beat the best plane level along one (three edges on one column or
    /// row) by [`SLOPE_ACROSS_COST`] truncation scales.
    fn ransac(
        &self,
        origin: (f64, f64),
        delta: f64,
        trials: usize,
        rng: &mut SplitMix64,
        slope_cost: f64,
    ) -> Model {
        let n = self.edges.len();
        let none = (f64::INFINITY, Model::Constant(self.edges[0].r as f64));
        let (mut constant, mut level, mut sloped) = (none, none, none);
        let consider = |best: &mut (f64, Model), m: Model| {
            let s = self.score(&m, origin, delta);
            if s < best.0 {
                *best = (s, m);
            }
        };
        if n <= trials {
            (self.edges.iter()).for_each(|e| consider(&mut constant, Model::Constant(e.r as f64)));
        } else {
            (0..trials).for_each(|_| {
                consider(
                    &mut constant,
                    Model::Constant(self.edges[rng.below(n)].r as f64),
                )
            });
        }
        if n >= MIN_PLANE_EDGES {
            for _ in 0..trials {
                let t = [rng.below(n), rng.below(n), rng.below(n)].map(|i| self.edges[i]);
                for inverse in [false, true] {
                    match plane_through(&t, origin, inverse) {
                        Some((m, true)) => consider(&mut level, m),
                        Some((m, false)) => consider(&mut sloped, m),
                        None => {}
                    }
                }
            }
        }
        // The road is level across every line, as a plane through a line of edges is.
        if let Some(road) = self.road {
            consider(&mut level, Model::Road { road, origin });
        }
        if sloped.0 < constant.0 && sloped.0 + slope_cost * delta < level.0 {
            let (score, model) = sloped;
            return match self.refit_plane(&model, origin, delta) {
                Some(m) if self.score(&m, origin, delta) <= score => m,
                _ => model,
            };
        }
        // A level plane is kept as drawn: a least-squares refit would slope it again.
        if level.0 < constant.0 {
            level.1
        } else {
            constant.1
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
            Model::Constant(_) | Model::Road { .. } => return None,
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

/// The plane through three boundary edges, and whether it is level across a line: for
/// three on one column (or one row), the plane through the two farthest apart that is
/// level across it (a band along a side of the image has edges on one column only: a
/// plane through three of them, one elsewhere or none, could not follow the surface down
/// the column); `None` if they are otherwise collinear (integer coordinates: the doubled
/// triangle area is then exactly 0).
fn plane_through(t: &[Edge; 3], origin: (f64, f64), inverse: bool) -> Option<(Model, bool)> {
    if inverse && t.iter().any(|e| e.r <= 0.0) {
        return None;
    }
    let rows = t.map(|e| [1.0, e.x as f64 - origin.0, e.y as f64 - origin.1]);
    let area2 = (t[1].x - t[0].x) as i64 * (t[2].y - t[0].y) as i64
        - (t[2].x - t[0].x) as i64 * (t[1].y - t[0].y) as i64;
    if area2 == 0 {
        return level_plane_along_a_line(t, origin, inverse).map(|m| (m, true));
    }
    let m = Model::affine(inverse, solve3(rows, t.map(|e| e.fitted(inverse)))?);
    Some((m, false))
}

/// The plane through three edges on one column that does not change along the rows (or
/// on one row, down the columns): through the two farthest apart. `None` for other
/// collinear edges, and for three at one place.
fn level_plane_along_a_line(t: &[Edge; 3], origin: (f64, f64), inverse: bool) -> Option<Model> {
    let column = t.iter().all(|e| e.x == t[0].x);
    let row = t.iter().all(|e| e.y == t[0].y);
    if column == row {
        return None;
    }
    let along = |e: &Edge| if column { e.y } else { e.x };
    let (lo, hi) = (
        t.iter().min_by_key(|e| along(e))?,
        t.iter().max_by_key(|e| along(e))?,
    );
    let slope = (hi.fitted(inverse) - lo.fitted(inverse)) / f64::from(along(hi) - along(lo));
    let at = if column {
        lo.y as f64 - origin.1
    } else {
        lo.x as f64 - origin.0
    };
    let a = lo.fitted(inverse) - slope * at;
    let (b, c) = if column { (0.0, slope) } else { (slope, 0.0) };
    Some(Model::affine(inverse, [a, b, c]))
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
#[path = "fill_tests.rs"]
mod tests;
