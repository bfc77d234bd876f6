//! Hole filling by RANSAC over constants and planes sampled from the hole boundary.
//!
//! See the module docs of [`crate::prep`] for the method and its justification.

use crate::rng::SplitMix64;
use crate::{Error, Result};

/// Boundaries longer than this are scored on an evenly strided subset of this many edges.
const MAX_SCORED: usize = 1024;
/// Plane candidates are only tried when the boundary has at least this many edges.
const MIN_PLANE_EDGES: usize = 4;
/// 1.4826 x MAD estimates the standard deviation of Gaussian data.
const MAD_TO_SIGMA: f64 = 1.4826;

/// One boundary edge: a known pixel `(x, y)` with range `r`, 4-adjacent to a hole pixel.
#[derive(Clone, Copy, Debug)]
struct Edge {
    x: i32,
    y: i32,
    r: f32,
}

/// A candidate fill surface, in coordinates relative to the hole's origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Model {
    /// R = c.
    Constant(f64),
    /// R = a + b (x - ox) + c (y - oy).
    Plane { a: f64, b: f64, c: f64 },
}

impl Model {
    #[inline]
    fn eval(&self, dx: f64, dy: f64) -> f64 {
        match *self {
            Model::Constant(c) => c,
            Model::Plane { a, b, c } => a + b * dx + c * dy,
        }
    }
}

/// Reusable buffers for filling holes one after the other.
#[derive(Default)]
pub(crate) struct HoleFiller {
    edges: Vec<Edge>,
    scratch: Vec<f64>,
}

impl HoleFiller {
    /// Fills the hole made of `pixels` in `work` (known pixels finite, the hole's pixels
    /// not finite), drawing candidates with `rng`, `trials` constants and `trials` planes.
    pub(crate) fn fill(
        &mut self,
        work: &mut [f32],
        width: usize,
        height: usize,
        pixels: &[u32],
        trials: usize,
        rng: &mut SplitMix64,
    ) -> Result<()> {
        self.collect_edges(work, width, height, pixels);
        if self.edges.is_empty() {
            return Err(Error::Prep(format!(
                "a hole of {} pixels has no known pixel on its boundary (nothing to fill it from)",
                pixels.len()
            )));
        }
        let origin = self.origin();
        let delta = self.robust_scale();
        let model = self.ransac(origin, delta, trials, rng);
        let (lo, hi) = self.value_range();
        for &p in pixels {
            let p = p as usize;
            let (dx, dy) = ((p % width) as f64 - origin.0, (p / width) as f64 - origin.1);
            work[p] = model.eval(dx, dy).clamp(lo, hi) as f32;
        }
        Ok(())
    }

    /// Every (hole pixel, known 4-neighbour) pair, as the known pixel's position and value.
    fn collect_edges(&mut self, work: &[f32], width: usize, height: usize, pixels: &[u32]) {
        self.edges.clear();
        for &p in pixels {
            let p = p as usize;
            let (x, y) = (p % width, p / width);
            for q in super::components::neighbours4(p, x, y, width, height)
                .into_iter()
                .flatten()
            {
                let r = work[q];
                if r.is_finite() {
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
                if let Some(m) = plane_through(&t, origin) {
                    consider(m);
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
        if !matches!(m, Model::Plane { .. }) {
            return None;
        }
        let mut ata = [[0.0f64; 3]; 3];
        let mut atb = [0.0f64; 3];
        for e in &self.edges {
            let (dx, dy) = (e.x as f64 - origin.0, e.y as f64 - origin.1);
            if (m.eval(dx, dy) - e.r as f64).abs() < delta {
                let row = [1.0, dx, dy];
                for i in 0..3 {
                    for j in 0..3 {
                        ata[i][j] += row[i] * row[j];
                    }
                    atb[i] += row[i] * e.r as f64;
                }
            }
        }
        let [a, b, c] = solve3(ata, atb)?;
        Some(Model::Plane { a, b, c })
    }
}

/// The plane through three boundary edges, or `None` if they are collinear (integer
/// coordinates: the doubled triangle area is then exactly 0).
fn plane_through(t: &[Edge; 3], origin: (f64, f64)) -> Option<Model> {
    let rows = t.map(|e| [1.0, e.x as f64 - origin.0, e.y as f64 - origin.1]);
    let area2 = (t[1].x - t[0].x) as i64 * (t[2].y - t[0].y) as i64
        - (t[2].x - t[0].x) as i64 * (t[1].y - t[0].y) as i64;
    if area2 == 0 {
        return None;
    }
    let [a, b, c] = solve3(rows, t.map(|e| e.r as f64))?;
    Some(Model::Plane { a, b, c })
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
        let mut f = HoleFiller::default();
        f.fill(&mut m, w, h, &[12], 8, &mut SplitMix64::new(1))
            .unwrap();
        assert_eq!(m[12], 3.0);
    }
}
