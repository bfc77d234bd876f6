//! Paper 003's arbitrary height profiles (sec. 3.2): a density given as a table of
//! heights and extinctions, linear between rows and constant beyond the ends, integrated
//! along rays through a precomputed integral texture.
//!
//! **The optical depth.** With K(y) = ∫_{y_first}^{y} κ the cumulative integral of the
//! extinction over height, the optical depth of a segment of length l rising from y0 to
//! y1 is F = (l/(y1 − y0))·(K(y1) − K(y0)) = l·κ̄ (paper 003, eq. 8 with a tabulated
//! antiderivative). K of a piecewise-linear κ is piecewise quadratic, so a linear
//! interpolation of K between texels would add an error of (spacing²/8)·|κ′| per texel;
//! instead the texture stores, at every node of a uniform grid in height, both κ and the
//! exact K (computed in f64 from the rows), and the shader (`glsl/medium/layered_table.glsl`)
//! fetches them with `texelFetch` and interpolates itself (texture units filter with
//! reduced-precision weights on most GPUs; a fetch is exact) as
//!
//! ```text
//! ∫_a^b κ = (n_a − a)·(κ(a) + κ_{a+1})/2 + (K_{b} − K_{a+1}) + (b − n_b)·(κ_{b} + κ(b))/2
//! ```
//!
//! with n_a the first node above a and n_b the last node below b, and (b − a)·(κ(a) + κ(b))/2
//! when a and b share a cell. Every part is exact for a κ linear within each cell, and the
//! mean κ̄ = ∫/(b − a) has no cancellation at small b − a: a horizontal ray (b = a) gets
//! κ(a), its limit, as the analytic profiles do. Beyond the table's ends κ is constant,
//! which adds (length outside)·κ_end to the integral.
//!
//! **The grid.** When the rows are equally spaced, or all lie on a lattice of a common
//! spacing (found by halving the smallest gap up to six times), the grid's nodes are the
//! rows' heights and the texture represents the table exactly: the only error is f32's
//! (K's differences lose about ε·K_max, so F about l·ε·K_max/|Δy| with |Δy| ≥ one cell).
//! Otherwise the grid has the finest spacing allowed ([`MAX_NODES`] nodes over the
//! table's span, the smallest gap at most) and a row between two nodes is smoothed over
//! its cell: K stays exact at the nodes, so the error stays within that cell, at most
//! g²·|Δs|/8 for a jump Δs of κ's slope at the row and grid spacing g.
//! [`DensityTable::on_grid`] says which case holds.
//!
//! **The error of a sampled profile.** A table sampled every Δ from a smooth profile δ is
//! its piecewise-linear interpolant, off by at most (Δ²/8)·max|δ″| over a cell (the error
//! of linear interpolation), so the mean density and the optical depth F are off by at
//! most that relative to δ, and τ = e^(−F) by τ·F·(that) ≤ e^(−1)·(that): the error is
//! O(Δ²), halving Δ divides it by 4. Relative to δ: Δ²/(8H²) for an exponential of scale
//! height H (3.1e-4 at H = 20 m, Δ = 1 m); for a sine band of thickness T up to
//! (πΔ/T)²/6 at its edges, where δ → 0 (6.6 % for the default 5 m band at Δ = 1 m: that
//! band needs Δ = 0.25 m for 1/255); a ramp whose kinks are rows is represented exactly.
//! `table_tests.rs` measures the law.

use super::super::lookup::{Lookup, Wrap};
use super::super::UniformValue;
use crate::error::{Error, Result};
use std::sync::Arc;

/// The most grid nodes a table's texture may have (two `R32F` textures of 4 MiB each).
pub const MAX_NODES: usize = 1 << 20;

/// Texels per row of the textures: a grid longer than this wraps onto further rows, so
/// that GLES 3's smallest `GL_MAX_TEXTURE_SIZE` (2048) is never exceeded.
pub const TEXTURE_WIDTH: usize = 2048;

/// A row is on the grid if its height is within this fraction of a spacing of a node.
const LATTICE_TOLERANCE: f64 = 1e-9;

/// How many times the smallest gap is halved in search of a lattice through every row.
const MAX_HALVINGS: u32 = 6;

/// The sampler of κ at the grid's nodes in `glsl/medium/layered_table.glsl`.
pub const DENSITY_SAMPLER: &str = "u_table_density";
/// The sampler of K at the grid's nodes.
pub const INTEGRAL_SAMPLER: &str = "u_table_integral";

/// A density profile given as a table: extinction κ (per world unit) at increasing
/// heights (world units), linear between rows and constant beyond the first and the
/// last (module docs). Cheap to clone: the rows, the grid and its textures are shared.
#[derive(Clone)]
pub struct DensityTable {
    data: Arc<Data>,
}

impl std::fmt::Debug for DensityTable {
    /// The rows, not the grid (up to `MAX_NODES` values twice).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DensityTable")
            .field("heights", &self.data.heights)
            .field("extinction", &self.data.extinction)
            .field("grid_spacing", &self.data.grid.spacing)
            .field("on_grid", &self.data.grid.exact)
            .finish()
    }
}

struct Data {
    heights: Vec<f64>,
    extinction: Vec<f64>,
    /// K at each row: ∫ κ from the first row.
    cumulative: Vec<f64>,
    grid: Grid,
    density_lookup: Lookup,
    integral_lookup: Lookup,
}

/// The uniform grid the GPU sees: κ and K at heights origin + j·spacing.
struct Grid {
    origin: f64,
    spacing: f64,
    density: Vec<f64>,
    integral: Vec<f64>,
    exact: bool,
}

impl PartialEq for DensityTable {
    /// Equal rows.
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.data, &other.data)
            || (self.data.heights == other.data.heights
                && self.data.extinction == other.data.extinction)
    }
}

impl DensityTable {
    /// A table from rows `(height, extinction)`: at least 2 rows, heights finite and
    /// strictly increasing, extinctions finite and ≥ 0. Errors name the row (from 0).
    pub fn from_rows(rows: &[(f64, f64)]) -> Result<Self> {
        let (heights, extinction): (Vec<f64>, Vec<f64>) = rows.iter().copied().unzip();
        Self::new(heights, extinction)
    }

    /// A table from its columns (see [`DensityTable::from_rows`]).
    pub fn new(heights: Vec<f64>, extinction: Vec<f64>) -> Result<Self> {
        check_rows(&heights, &extinction)?;
        let cumulative = cumulative_integral(&heights, &extinction);
        let grid = Grid::build(&heights, &extinction, &cumulative);
        let (density_lookup, integral_lookup) = grid.lookups()?;
        Ok(DensityTable {
            data: Arc::new(Data {
                heights,
                extinction,
                cumulative,
                grid,
                density_lookup,
                integral_lookup,
            }),
        })
    }

    /// `profile` sampled every `spacing` from `from` to `to` (the last row at `to`, or the
    /// last node below it): the way to turn any δ(y) into a table, and the test of the
    /// error law (module docs).
    pub fn sampled(profile: impl Fn(f64) -> f64, from: f64, to: f64, spacing: f64) -> Result<Self> {
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(Error::invalid(
                "spacing",
                spacing,
                "a finite height step > 0",
            ));
        }
        if !(from.is_finite() && to.is_finite() && to > from) {
            return Err(Error::invalid(
                "sampled heights",
                format!("{from}..{to}"),
                "finite heights, the second above the first",
            ));
        }
        let steps = ((to - from) / spacing + 1e-9).floor();
        if steps + 1.0 > MAX_NODES as f64 {
            return Err(Error::invalid(
                "spacing",
                spacing,
                format!("at most {MAX_NODES} rows over {from}..{to}"),
            ));
        }
        let heights: Vec<f64> = (0..=steps as usize)
            .map(|i| from + i as f64 * spacing)
            .collect();
        let extinction = heights.iter().map(|&y| profile(y)).collect();
        Self::new(heights, extinction)
    }

    /// The rows' heights (world units), increasing.
    pub fn heights(&self) -> &[f64] {
        &self.data.heights
    }

    /// The rows' extinctions (per world unit).
    pub fn extinction(&self) -> &[f64] {
        &self.data.extinction
    }

    /// κ(y) of the table: linear between rows, constant beyond the ends.
    pub fn density(&self, y: f64) -> f64 {
        self.rows().density(y)
    }

    /// K(y) = ∫_{first height}^{y} κ of the table, exactly (piecewise quadratic; linear
    /// beyond the ends, negative below the first row).
    pub fn integral(&self, y: f64) -> f64 {
        self.rows().integral(y)
    }

    fn rows(&self) -> RowView<'_> {
        RowView {
            heights: &self.data.heights,
            extinction: &self.data.extinction,
            cumulative: &self.data.cumulative,
        }
    }

    /// The largest extinction of the table: its supremum over all heights.
    pub fn max_density(&self) -> f64 {
        self.data.extinction.iter().copied().fold(0.0, f64::max)
    }

    /// Whether the GPU's grid has a node at every row, so that it represents the table
    /// exactly (module docs).
    pub fn on_grid(&self) -> bool {
        self.data.grid.exact
    }

    /// The spacing of the GPU's grid (world units).
    pub fn grid_spacing(&self) -> f64 {
        self.data.grid.spacing
    }

    /// The number of nodes of the GPU's grid.
    pub fn grid_nodes(&self) -> usize {
        self.data.grid.density.len()
    }

    /// The mean of κ over the heights from `y0` to `y0 + dy` (κ(y0) for dy = 0), as the
    /// shader computes it from the grid (module docs), in f64: the CPU reference.
    pub fn mean_density(&self, y0: f64, dy: f64) -> f64 {
        let g = &self.data.grid;
        let y1 = y0 + dy;
        let (low, high) = (y0.min(y1), y0.max(y1));
        let (lo, hi) = (g.origin, g.top());
        let (first, last) = (g.density[0], g.density[g.density.len() - 1]);
        let below = (high.min(lo) - low.min(lo)) * first;
        let above = (high.max(hi) - low.max(hi)) * last;
        let (a, b) = (low.max(lo).min(hi), high.max(lo).min(hi));
        if high > low {
            (below + g.integral_between(a, b) + above) / (high - low)
        } else {
            g.density_at(a)
        }
    }

    /// The shader's uniforms (`glsl/medium/layered_table.glsl`).
    pub(crate) fn uniforms(&self) -> Vec<(&'static str, UniformValue)> {
        let g = &self.data.grid;
        let last = g.density.len() - 1;
        let f = |v: f64| v as f32;
        vec![
            (
                "u_table_grid",
                UniformValue::Vec4([f(g.origin), f(1.0 / g.spacing), f(g.spacing), last as f32]),
            ),
            (
                "u_table_ends",
                UniformValue::Vec3([f(g.top()), f(g.density[0]), f(g.density[last])]),
            ),
            (
                "u_table_width",
                UniformValue::Float(TEXTURE_WIDTH.min(g.density.len()) as f32),
            ),
        ]
    }

    /// The two textures: κ and K at the grid's nodes.
    pub(crate) fn lookups(&self) -> Vec<(&'static str, Lookup)> {
        vec![
            (DENSITY_SAMPLER, self.data.density_lookup.clone()),
            (INTEGRAL_SAMPLER, self.data.integral_lookup.clone()),
        ]
    }
}

/// The index i of the row segment [h_i, h_{i+1}] holding `y` (h_0 < y < h_last).
fn segment(h: &[f64], y: f64) -> usize {
    (h.partition_point(|&v| v <= y) - 1).min(h.len() - 2)
}

/// Rejects tables that are too short, unordered, negative or not finite, naming the row.
fn check_rows(heights: &[f64], extinction: &[f64]) -> Result<()> {
    if heights.len() != extinction.len() {
        return Err(Error::invalid(
            "density table",
            format!(
                "{} heights and {} extinctions",
                heights.len(),
                extinction.len()
            ),
            "one extinction per height",
        ));
    }
    if heights.len() < 2 {
        return Err(Error::invalid(
            "density table",
            format!("{} row(s)", heights.len()),
            "at least 2 rows (height, extinction)",
        ));
    }
    for (i, (&h, &k)) in heights.iter().zip(extinction).enumerate() {
        if !h.is_finite() {
            return Err(Error::invalid(
                format!("height of row {i}"),
                h,
                "a finite height",
            ));
        }
        if !(k.is_finite() && k >= 0.0) {
            return Err(Error::invalid(
                format!("extinction of row {i}"),
                k,
                "a finite extinction ≥ 0 (per world unit)",
            ));
        }
        if i > 0 && h <= heights[i - 1] {
            return Err(Error::invalid(
                format!("height of row {i}"),
                h,
                format!("a height above the previous row's ({})", heights[i - 1]),
            ));
        }
    }
    let span = heights[heights.len() - 1] - heights[0];
    if !span.is_finite() {
        return Err(Error::invalid(
            "density table",
            format!("heights {}..{}", heights[0], heights[heights.len() - 1]),
            "a finite span of heights",
        ));
    }
    Ok(())
}

/// K at each row by the trapezoid rule, exact for a piecewise-linear κ.
fn cumulative_integral(heights: &[f64], extinction: &[f64]) -> Vec<f64> {
    let mut total = 0.0;
    let mut out = Vec::with_capacity(heights.len());
    out.push(0.0);
    for i in 1..heights.len() {
        total += (heights[i] - heights[i - 1]) * 0.5 * (extinction[i] + extinction[i - 1]);
        out.push(total);
    }
    out
}

impl Grid {
    /// The grid through every row if a lattice holds them all, else the finest allowed.
    fn build(heights: &[f64], extinction: &[f64], cumulative: &[f64]) -> Grid {
        let lo = heights[0];
        let span = heights[heights.len() - 1] - lo;
        let gap = heights
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        let nodes = |s: f64| (span / s).round() + 1.0;
        let on_lattice = |s: f64| {
            heights.iter().all(|&h| {
                let t = (h - lo) / s;
                (t - t.round()).abs() <= LATTICE_TOLERANCE * t.abs().max(1.0)
            })
        };
        let mut spacing = gap;
        let mut exact = nodes(spacing) <= MAX_NODES as f64 && on_lattice(spacing);
        let mut halvings = 0;
        while !exact && halvings < MAX_HALVINGS && nodes(spacing / 2.0) <= MAX_NODES as f64 {
            spacing /= 2.0;
            halvings += 1;
            exact = on_lattice(spacing);
        }
        let count = nodes(spacing).min(MAX_NODES as f64) as usize;
        // The spacing that puts the last node on the last row exactly.
        let spacing = span / (count - 1) as f64;
        let node = |j: usize| {
            if j == count - 1 {
                heights[heights.len() - 1]
            } else {
                lo + j as f64 * spacing
            }
        };
        let table = RowView {
            heights,
            extinction,
            cumulative,
        };
        let density = (0..count).map(|j| table.density(node(j))).collect();
        let integral = (0..count).map(|j| table.integral(node(j))).collect();
        Grid {
            origin: lo,
            spacing,
            density,
            integral,
            exact,
        }
    }

    fn top(&self) -> f64 {
        self.origin + self.spacing * (self.density.len() - 1) as f64
    }

    /// The cell (from 0) holding `y` in [origin, top] and the fraction of it below `y`.
    fn cell(&self, y: f64) -> (usize, f64) {
        let t = (y - self.origin) / self.spacing;
        let i = (t.floor().max(0.0) as usize).min(self.density.len() - 2);
        (i, t - i as f64)
    }

    /// κ at `y` in [origin, top], linear in its cell (GLSL's `mix`).
    fn density_at(&self, y: f64) -> f64 {
        let (i, f) = self.cell(y);
        self.density[i] * (1.0 - f) + self.density[i + 1] * f
    }

    /// ∫_a^b κ for origin ≤ a ≤ b ≤ top (module docs' formula).
    fn integral_between(&self, a: f64, b: f64) -> f64 {
        let (ia, _) = self.cell(a);
        let (ib, _) = self.cell(b);
        let (ka, kb) = (self.density_at(a), self.density_at(b));
        if ia == ib {
            return (b - a) * 0.5 * (ka + kb);
        }
        let node_a = self.origin + (ia + 1) as f64 * self.spacing;
        let node_b = self.origin + ib as f64 * self.spacing;
        (node_a - a) * 0.5 * (ka + self.density[ia + 1])
            + (self.integral[ib] - self.integral[ia + 1])
            + (b - node_b) * 0.5 * (self.density[ib] + kb)
    }

    /// κ and K as `R32F` textures of [`TEXTURE_WIDTH`] texels per row, node j at
    /// (j mod width, j div width); the last row is padded with the last node.
    fn lookups(&self) -> Result<(Lookup, Lookup)> {
        let n = self.density.len();
        let width = TEXTURE_WIDTH.min(n);
        let rows = n.div_ceil(width);
        let texture = |values: &[f64]| {
            let mut v: Vec<f32> = values.iter().map(|&x| x as f32).collect();
            v.resize(width * rows, values[n - 1] as f32);
            Lookup::new(width, rows, v, Wrap::ClampToEdge)
        };
        Ok((texture(&self.density)?, texture(&self.integral)?))
    }
}

/// The rows before the table exists, for building its grid.
struct RowView<'a> {
    heights: &'a [f64],
    extinction: &'a [f64],
    cumulative: &'a [f64],
}

impl RowView<'_> {
    fn density(&self, y: f64) -> f64 {
        let (h, k) = (self.heights, self.extinction);
        let last = h.len() - 1;
        if y.is_nan() {
            return f64::NAN;
        }
        if y <= h[0] {
            return k[0];
        }
        if y >= h[last] {
            return k[last];
        }
        let i = segment(h, y);
        k[i] + (k[i + 1] - k[i]) * ((y - h[i]) / (h[i + 1] - h[i]))
    }

    fn integral(&self, y: f64) -> f64 {
        let (h, k, c) = (self.heights, self.extinction, self.cumulative);
        let last = h.len() - 1;
        if y <= h[0] {
            return (y - h[0]) * k[0];
        }
        if y >= h[last] {
            return c[last] + (y - h[last]) * k[last];
        }
        let i = segment(h, y);
        // The trapezoid of a linear piece is exact.
        c[i] + (y - h[i]) * 0.5 * (k[i] + self.density(y))
    }
}

/// The analytic profiles' shader: no table code, no samplers.
const ANALYTIC_GLSL: &str = include_str!("../../../glsl/medium/layered.glsl");

/// The table profile's shader: the table's functions, then the layered fog, which calls
/// them under `LAYERED_TABLE`.
const TABLE_GLSL: &str = concat!(
    include_str!("../../../glsl/medium/layered_table.glsl"),
    include_str!("../../../glsl/medium/layered.glsl")
);

/// The medium's name: a table profile compiles another program (with its samplers).
pub(super) fn medium_name(profile: &super::HeightProfile) -> &'static str {
    match profile {
        super::HeightProfile::Table(_) => "layered_table",
        _ => "layered",
    }
}

/// The medium's GLSL for `profile`.
pub(super) fn medium_glsl(profile: &super::HeightProfile) -> &'static str {
    match profile {
        super::HeightProfile::Table(_) => TABLE_GLSL,
        _ => ANALYTIC_GLSL,
    }
}

/// The table's uniforms, none for an analytic profile.
pub(super) fn profile_uniforms(
    profile: &super::HeightProfile,
) -> Vec<(&'static str, UniformValue)> {
    match profile {
        super::HeightProfile::Table(table) => table.uniforms(),
        _ => Vec::new(),
    }
}

/// The table's textures, none for an analytic profile.
pub(super) fn profile_lookups(profile: &super::HeightProfile) -> Vec<(&'static str, Lookup)> {
    match profile {
        super::HeightProfile::Table(table) => table.lookups(),
        _ => Vec::new(),
    }
}

#[cfg(test)]
#[path = "table_tests.rs"]
mod tests;
