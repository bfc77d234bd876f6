//! Exact Euclidean distance transform in linear time.
//!
//! Method: the separable algorithm of Felzenszwalb and Huttenlocher ("Distance transforms
//! of sampled functions", Theory of Computing 8, 2012), which, like Maurer, Qi and
//! Raghavan (PAMI 2003), is exact and O(width x height):
//!
//! 1. Columns: the distance `g` from each pixel to the nearest site in its column, by one
//!    downward and one upward scan (row-major, cache friendly).
//! 2. Rows: for each row, the lower envelope of the parabolas `(x - q)^2 + g(q)^2` over the
//!    columns `q` that have a site, then one sweep reading the envelope. The squared
//!    distance is an integer; envelope intersections are computed in `f64`, exact for all
//!    image sizes below 2^26 pixels a side.
//!
//! Distances are returned squared, as `u32` (exact, saturating at [`NO_SITE`]).

use crate::raster::Grid;

/// The squared distance reported when the image has no site at all.
pub const NO_SITE: u32 = u32::MAX;

/// Squared Euclidean distance from every pixel to the nearest pixel where `sites` is true
/// (0 on the sites themselves); [`NO_SITE`] everywhere if there is no site.
pub fn squared_edt(sites: &Grid<bool>) -> Grid<u32> {
    let (w, h) = (sites.width(), sites.height());
    let s = sites.as_slice();
    Grid::from_vec(w, h, squared_edt_with(w, h, |x, y| s[y * w + x]))
}

/// [`squared_edt`] for a `width x height` window whose sites are given by `is_site(x, y)`.
pub(crate) fn squared_edt_with(
    width: usize,
    height: usize,
    is_site: impl Fn(usize, usize) -> bool,
) -> Vec<u32> {
    let mut d = column_distances(width, height, is_site);
    let mut env = Envelope::with_capacity(width);
    for row in d.chunks_exact_mut(width.max(1)) {
        env.transform_row(row);
    }
    d
}

/// Pass 1: per-column distance to the nearest site (not squared), [`NO_SITE`] if none.
fn column_distances(
    width: usize,
    height: usize,
    is_site: impl Fn(usize, usize) -> bool,
) -> Vec<u32> {
    let mut g = vec![NO_SITE; width * height];
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            g[i] = if is_site(x, y) {
                0
            } else if y > 0 {
                g[i - width].saturating_add(1)
            } else {
                NO_SITE
            };
        }
    }
    for y in (0..height.saturating_sub(1)).rev() {
        for x in 0..width {
            let i = y * width + x;
            g[i] = g[i].min(g[i + width].saturating_add(1));
        }
    }
    g
}

/// Scratch buffers of the 1D lower-envelope transform.
struct Envelope {
    /// Columns of the parabolas on the envelope.
    v: Vec<usize>,
    /// Boundaries between envelope parabolas (`z[k]..z[k+1]` belongs to `v[k]`).
    z: Vec<f64>,
    /// The row's squared column distances.
    f: Vec<u64>,
}

impl Envelope {
    fn with_capacity(n: usize) -> Self {
        Envelope {
            v: Vec::with_capacity(n),
            z: Vec::with_capacity(n + 1),
            f: Vec::with_capacity(n),
        }
    }

    /// Replaces the column distances `row` by exact squared 2D distances.
    fn transform_row(&mut self, row: &mut [u32]) {
        self.f.clear();
        self.f.extend(row.iter().map(|&g| {
            if g == NO_SITE {
                u64::MAX
            } else {
                (g as u64) * (g as u64)
            }
        }));
        self.build();
        if self.v.is_empty() {
            row.fill(NO_SITE);
            return;
        }
        let mut k = 0;
        for (q, out) in row.iter_mut().enumerate() {
            while self.z[k + 1] < q as f64 {
                k += 1;
            }
            let dq = q.abs_diff(self.v[k]) as u64;
            *out = (dq * dq + self.f[self.v[k]]).min(NO_SITE as u64) as u32;
        }
    }

    /// Lower envelope of the parabolas of the finite entries of `f`.
    fn build(&mut self) {
        self.v.clear();
        self.z.clear();
        self.z.push(f64::NEG_INFINITY);
        for q in 0..self.f.len() {
            if self.f[q] == u64::MAX {
                continue;
            }
            let mut s = f64::NEG_INFINITY;
            while let Some(&p) = self.v.last() {
                s = self.intersect(p, q);
                if s > self.z[self.v.len() - 1] {
                    break;
                }
                self.v.pop();
                self.z.pop();
                s = f64::NEG_INFINITY;
            }
            if !self.v.is_empty() {
                self.z.push(s);
            }
            self.v.push(q);
        }
        self.z.push(f64::INFINITY);
    }

    /// Abscissa where the parabolas rooted at columns `p < q` intersect.
    #[inline]
    fn intersect(&self, p: usize, q: usize) -> f64 {
        let fp = self.f[p] as f64 + (p * p) as f64;
        let fq = self.f[q] as f64 + (q * q) as f64;
        (fq - fp) / (2.0 * (q - p) as f64)
    }
}
