//! The fit of T to one estimation's ratios: root finding for RANSAC's hypotheses,
//! Levenberg-Marquardt, and a bracketing search when it does not converge.

use super::*;

/// The samples of one estimation and the reference patch: the ratios, residuals and fits.
pub(super) struct Fit<'a> {
    pub(super) pts: &'a [Usable],
    pub(super) patch: &'a [Geom],
    pub(super) patch_y: f64,
    /// The patch's mean F at the root-finding grid's T values ([`grid_t`]).
    pub(super) patch_grid: &'a [f64],
    /// Fit the level s of the model ratios instead of fixing it to 1.
    pub(super) free_level: bool,
}

/// A least-squares fit of T.
pub(super) struct LeastSquares {
    pub(super) t: f64,
    pub(super) std: f64,
    /// The level s of the model ratios (1 unless fitted).
    pub(super) level: f64,
}

impl Fit<'_> {
    /// F of the reference and its T-derivative.
    pub(super) fn ref_f_d(&self, p: &Perez, slopes: &Perez, reference: Ref) -> (f64, f64) {
        match reference {
            Ref::Patch => {
                let (mut f, mut d) = (0.0, 0.0);
                for g in self.patch {
                    let (a, b) = g.f_d(p, slopes);
                    f += a;
                    d += b;
                }
                let n = self.patch.len() as f64;
                (f / n, d / n)
            }
            Ref::Sample(j) => self.pts[j].geom.f_d(p, slopes),
        }
    }

    pub(super) fn ref_f(&self, p: &Perez, reference: Ref) -> f64 {
        match reference {
            Ref::Patch => self.patch.iter().map(|g| g.f(p)).sum::<f64>() / self.patch.len() as f64,
            Ref::Sample(j) => self.pts[j].geom.f(p),
        }
    }

    pub(super) fn ref_y(&self, reference: Ref) -> f64 {
        match reference {
            Ref::Patch => self.patch_y,
            Ref::Sample(j) => self.pts[j].y,
        }
    }

    /// The observed ratio q_i.
    pub(super) fn q(&self, i: usize, reference: Ref) -> f64 {
        self.pts[i].y / self.ref_y(reference)
    }

    /// Every T in [1, 20] where m_i(T) = q_i, approximately: the sign changes of
    /// m_i(T) − q_i on the grid of [`grid_t`], each root interpolated linearly in its
    /// interval. A hypothesis only has to be close enough to sort inliers from clouds
    /// (a relative error in T of 10⁻³ moves the ratios far less than the 3 % threshold);
    /// the refinement then fits T exactly, and the grid needs no evaluation of the
    /// reference patch off its precomputed values.
    pub(super) fn solve_one(&self, i: usize, reference: Ref) -> Vec<f64> {
        let q = self.q(i, reference);
        let g = |k: usize| {
            let p = Perez::luminance(grid_t(k));
            let fr = match reference {
                Ref::Patch => self.patch_grid[k],
                Ref::Sample(j) => self.pts[j].geom.f(&p),
            };
            self.pts[i].geom.f(&p) / fr - q
        };
        let mut roots = Vec::new();
        let mut ga = g(0);
        if ga == 0.0 {
            roots.push(grid_t(0));
        }
        for k in 1..=GRID_STEPS {
            let gb = g(k);
            if gb == 0.0 {
                roots.push(grid_t(k));
            } else if ga * gb < 0.0 {
                let (a, b) = (grid_t(k - 1), grid_t(k));
                roots.push(a + (b - a) * ga / (ga - gb));
            }
            ga = gb;
        }
        roots
    }

    /// Relative residuals s·m_k(T)/q_k − 1 of every sample (0 for the reference sample).
    pub(super) fn relative_residuals(&self, t: f64, reference: Ref, level: f64) -> Vec<f64> {
        let p = Perez::luminance(t);
        let fr = self.ref_f(&p, reference);
        let yr = self.ref_y(reference);
        self.pts
            .iter()
            .enumerate()
            .map(|(k, s)| {
                if Ref::Sample(k) == reference {
                    0.0
                } else {
                    level * (s.geom.f(&p) / fr) / (s.y / yr) - 1.0
                }
            })
            .collect()
    }

    /// The inliers of hypothesis T and the sum of their |relative residuals|.
    pub(super) fn inliers(&self, t: f64, reference: Ref, threshold: f64) -> (Vec<usize>, f64) {
        let residuals = self.relative_residuals(t, reference, 1.0);
        let mut spread = 0.0;
        let inliers = (0..self.pts.len())
            .filter(|&k| Ref::Sample(k) != reference && residuals[k].abs() < threshold)
            .inspect(|&k| spread += residuals[k].abs())
            .collect();
        (inliers, spread)
    }

    /// Σ (s·m_i(T) − q_i)² over `set`, its gradient part Σ J r, curvature Σ J², and the
    /// level s: 1, or with `free_level` the least-squares s(T) = Σ m q / Σ m² (variable
    /// projection: s is eliminated, T stays the only parameter, and J includes ds/dT).
    pub(super) fn cost(&self, set: &[usize], reference: Ref, t: f64) -> (f64, f64, f64, f64) {
        let p = Perez::luminance(t);
        let slopes = Perez::luminance_slopes();
        let (fr, dfr) = self.ref_f_d(&p, &slopes, reference);
        let yr = self.ref_y(reference);
        let mq: Vec<(f64, f64, f64)> = set
            .iter()
            .map(|&i| {
                let (f, df) = self.pts[i].geom.f_d(&p, &slopes);
                (f / fr, (df * fr - f * dfr) / (fr * fr), self.pts[i].y / yr)
            })
            .collect();
        let (level, dlevel) = if self.free_level {
            let (mut mq_sum, mut mm, mut dmq, mut mdm) = (0.0, 0.0, 0.0, 0.0);
            for &(m, dm, q) in &mq {
                mq_sum += m * q;
                mm += m * m;
                dmq += dm * q;
                mdm += m * dm;
            }
            let level = mq_sum / mm;
            (level, (dmq * mm - mq_sum * 2.0 * mdm) / (mm * mm))
        } else {
            (1.0, 0.0)
        };
        let (mut cost, mut jr, mut jj) = (0.0, 0.0, 0.0);
        for &(m, dm, q) in &mq {
            let r = level * m - q;
            let j = level * dm + dlevel * m;
            cost += r * r;
            jr += j * r;
            jj += j * j;
        }
        (cost, jr, jj, level)
    }

    /// Levenberg-Marquardt on T from `t0`, within [1, 20]; a bracketing search instead
    /// when it does not converge.
    pub(super) fn least_squares(&self, set: &[usize], reference: Ref, t0: f64) -> LeastSquares {
        let clamp = |t: f64| t.clamp(MIN_TURBIDITY, MAX_TURBIDITY);
        let mut t = clamp(t0);
        let (mut cost, mut jr, mut jj, mut level) = self.cost(set, reference, t);
        let mut lambda = 1e-3;
        let mut converged = false;
        for _ in 0..100 {
            if jj <= 0.0 {
                break;
            }
            let tn = clamp(t - jr / (jj * (1.0 + lambda)));
            let (cn, jrn, jjn, ln) = self.cost(set, reference, tn);
            if cn <= cost {
                let step = (tn - t).abs();
                (t, cost, jr, jj, level) = (tn, cn, jrn, jjn, ln);
                lambda = (lambda * 0.1).max(1e-12);
                if step <= 1e-10 * t {
                    converged = true;
                    break;
                }
            } else {
                lambda *= 10.0;
                if lambda > 1e8 {
                    // No decrease along the gradient: a minimum (or a bound) is reached.
                    converged = true;
                    break;
                }
            }
        }
        if !converged {
            t = self.bracket(set, reference);
            (cost, _, jj, level) = self.cost(set, reference, t);
        }
        let free = if self.free_level { 2.0 } else { 1.0 };
        let dof = (set.len() as f64 - free).max(1.0);
        let std = if jj > 0.0 {
            (cost / dof / jj).sqrt()
        } else {
            f64::INFINITY
        };
        LeastSquares { t, std, level }
    }

    /// The global minimum of the cost on [1, 20]: a grid scan, then golden-section
    /// search between the neighbours of the best grid point.
    pub(super) fn bracket(&self, set: &[usize], reference: Ref) -> f64 {
        let cost = |t: f64| self.cost(set, reference, t).0;
        let step = 0.25;
        let n = ((MAX_TURBIDITY - MIN_TURBIDITY) / step).round() as usize;
        let at = |k: usize| MIN_TURBIDITY + step * k as f64;
        let best = (0..=n)
            .min_by(|&a, &b| cost(at(a)).total_cmp(&cost(at(b))))
            .unwrap_or(0);
        let (mut lo, mut hi) = (at(best.saturating_sub(1)), at((best + 1).min(n)));
        let phi = (5f64.sqrt() - 1.0) / 2.0;
        let (mut c, mut d) = (hi - phi * (hi - lo), lo + phi * (hi - lo));
        let (mut fc, mut fd) = (cost(c), cost(d));
        while hi - lo > 1e-9 {
            if fc < fd {
                (hi, d, fd) = (d, c, fc);
                c = hi - phi * (hi - lo);
                fc = cost(c);
            } else {
                (lo, c, fc) = (c, d, fd);
                d = lo + phi * (hi - lo);
                fd = cost(d);
            }
        }
        0.5 * (lo + hi)
    }
}

/// Intervals of the grid on which the minimal equations are bracketed: steps of 0.5.
pub(super) const GRID_STEPS: usize = 38;

/// T at point `k` of that grid, from 1 to 20.
pub(super) fn grid_t(k: usize) -> f64 {
    MIN_TURBIDITY + (MAX_TURBIDITY - MIN_TURBIDITY) * k as f64 / GRID_STEPS as f64
}
