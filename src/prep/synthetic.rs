//! Synthetic outdoor data, for tests and benchmarks of [`crate::prep`]: a range map with a
//! complicated horizon ([`outdoor_scene`]) and a street frame with colour, true sky and
//! the faults of real stereo data ([`street_scene`]).

use crate::raster::{Grid, RgbImage, ScalarMap};
use crate::rng::SplitMix64;

/// Camera height above the ground plane, metres.
const CAMERA_HEIGHT: f64 = 1.6;

/// A deterministic outdoor range map of `width x height` pixels (range in metres, NaN =
/// unknown), the same for the same `seed`:
///
/// - a ground plane seen from 1.6 m up, its horizon at 42 % of the height;
/// - a tree line about 300 m away whose top is a ragged "foliage" horizon (two sines, a
///   per-column random walk and triangular tree crowns, 8 to 30 % of the height above the
///   horizon), with ragged unknown pockets along it, so the sky interface is complicated;
/// - NaN sky above it, touching the whole top row (plus a few known "leaf" pixels just
///   above the tree line);
/// - a few closer objects: planar building fronts (tilted, their tops at most 25 % of the
///   height above the horizon, so the sky stays one region along the top row) and spheres;
/// - small round holes (radius 2 to 10 px, scaled with the image) below the horizon until
///   they cover about 5 % of the image;
/// - a small deterministic measurement noise (about 0.2 %).
///
/// Every dimension scales with the image size (reference 1600 x 1120), so small maps for
/// tests look like the large one for the benchmark. Both sizes must be at least 16.
pub fn outdoor_scene(width: usize, height: usize, seed: u64) -> ScalarMap {
    assert!(
        width >= 16 && height >= 16,
        "outdoor_scene needs at least 16x16 pixels"
    );
    let mut rng = SplitMix64::new(seed);
    let s = Scale::new(width, height);
    let top = tree_line(&s, &mut rng);
    let far: Vec<f64> = (0..width).map(|_| rng.range(290.0, 310.0)).collect();
    let mut r = vec![f32::NAN; width * height];
    for y in 0..height {
        for x in 0..width {
            if (y as f64) >= top[x] {
                r[y * width + x] = background(&s, x, y, far[x]) as f32;
            }
        }
    }
    ragged_interface(&mut r, &s, &top, &far, &mut rng);
    objects(&mut r, &s, &mut rng);
    noise(&mut r, &mut rng);
    holes(&mut r, &s, &mut rng);
    ScalarMap::from_vec(width, height, r)
}

/// Image size and derived scales.
struct Scale {
    w: usize,
    h: usize,
    /// Pixels per reference pixel (1600 x 1120 reference).
    k: f64,
    /// Focal length in pixels.
    f: f64,
    /// Row of the ground horizon.
    yv: f64,
}

impl Scale {
    fn new(w: usize, h: usize) -> Self {
        let k = (w as f64 / 1600.0).min(h as f64 / 1120.0);
        Scale {
            w,
            h,
            k,
            f: w as f64,
            yv: 0.42 * h as f64,
        }
    }
}

/// Row where the sky ends, per column (real-valued).
fn tree_line(s: &Scale, rng: &mut SplitMix64) -> Vec<f64> {
    let (p1, p2) = (rng.range(0.0, 6.3), rng.range(0.0, 6.3));
    let trees: Vec<(f64, f64, f64)> = (0..12)
        .map(|_| {
            let cx = rng.range(0.0, s.w as f64);
            (
                cx,
                rng.range(20.0, 90.0) * s.k,
                rng.range(0.03, 0.12) * s.h as f64,
            )
        })
        .collect();
    let mut walk = 0.0f64;
    (0..s.w)
        .map(|x| {
            let xf = x as f64;
            walk = (walk + rng.range(-1.5, 1.5) * s.k).clamp(-6.0 * s.k, 6.0 * s.k);
            let crowns: f64 = trees
                .iter()
                .map(|&(cx, hw, ht)| ht * (1.0 - (xf - cx).abs() / hw).max(0.0))
                .fold(0.0, f64::max);
            let base = 0.12 * s.h as f64
                + 0.02 * s.h as f64 * (xf / (90.0 * s.k) + p1).sin()
                + 0.01 * s.h as f64 * (xf / (23.0 * s.k) + p2).sin();
            let above = (base + walk + crowns).clamp(0.08 * s.h as f64, 0.30 * s.h as f64);
            s.yv - above
        })
        .collect()
}

/// Range of the ground, or of the tree line where the ground is farther.
fn background(s: &Scale, x: usize, y: usize, far: f64) -> f64 {
    let dy = y as f64 + 0.5 - s.yv;
    let ground = if dy > 0.0 {
        s.f * CAMERA_HEIGHT / dy
    } else {
        f64::INFINITY
    };
    let dx = (x as f64 - 0.5 * s.w as f64) / s.f;
    if ground < far {
        ground * (1.0 + dx * dx).sqrt()
    } else {
        far + 3.0 * ((x as f64 * 0.37).sin() + (y as f64 * 0.23).cos())
    }
}

/// Foliage: unknown pockets just below the tree line, known leaves just above it.
fn ragged_interface(r: &mut [f32], s: &Scale, top: &[f64], far: &[f64], rng: &mut SplitMix64) {
    let band = (4.0 * s.k).max(2.0);
    for x in 0..s.w {
        let t = top[x];
        let y0 = (t - band).max(1.0) as usize;
        let y1 = ((t + band) as usize).min(s.h - 1);
        for y in y0..=y1 {
            let i = y * s.w + x;
            let u = rng.unit();
            if (y as f64) >= t && u < 0.25 {
                r[i] = f32::NAN;
            } else if (y as f64) < t && u < 0.08 {
                r[i] = (far[x] + rng.range(-5.0, 5.0)) as f32;
            }
        }
    }
}

/// Building fronts (tilted planes) and spheres in front of the background.
fn objects(r: &mut [f32], s: &Scale, rng: &mut SplitMix64) {
    for _ in 0..3 {
        let (cx, bw) = (
            rng.range(0.1, 0.9) * s.w as f64,
            rng.range(80.0, 220.0) * s.k,
        );
        let d = rng.range(25.0, 80.0);
        let (gx, gy) = (rng.range(-0.05, 0.05), rng.range(-0.02, 0.02));
        let foot = s.yv + s.f * CAMERA_HEIGHT / d;
        let y_top = (foot - s.f * rng.range(6.0, 15.0) / d).max(s.yv - 0.25 * s.h as f64);
        paint(r, s, cx - bw / 2.0, y_top, cx + bw / 2.0, foot, |x, y| {
            d + gx * (x - cx) + gy * (y - foot)
        });
    }
    for _ in 0..3 {
        let d = rng.range(8.0, 40.0);
        let rad_m = rng.range(1.0, 3.0);
        let rad = s.f * rad_m / d;
        let (cx, cy) = (
            rng.range(0.1, 0.9) * s.w as f64,
            s.yv + s.f * (CAMERA_HEIGHT) / d - rad,
        );
        paint(r, s, cx - rad, cy - rad, cx + rad, cy + rad, |x, y| {
            let q = ((x - cx).powi(2) + (y - cy).powi(2)) / (rad * rad);
            if q <= 1.0 {
                d - rad_m * (1.0 - q).sqrt()
            } else {
                f64::INFINITY
            }
        });
    }
}

/// Writes `min(r, f(x, y))` over a box (clipped to the image); NaN pixels are covered too.
fn paint(
    r: &mut [f32],
    s: &Scale,
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    f: impl Fn(f64, f64) -> f64,
) {
    let cx = |v: f64| (v.max(0.0) as usize).min(s.w);
    let cy = |v: f64| (v.max(0.0) as usize).min(s.h);
    for y in cy(y0)..cy(y1) {
        for x in cx(x0)..cx(x1) {
            let v = f(x as f64, y as f64);
            let i = y * s.w + x;
            if v.is_finite() && (r[i].is_nan() || (v as f32) < r[i]) {
                r[i] = v as f32;
            }
        }
    }
}

/// Multiplicative noise of about 0.2 % on every known value.
fn noise(r: &mut [f32], rng: &mut SplitMix64) {
    for v in r.iter_mut().filter(|v| v.is_finite()) {
        *v *= (1.0 + 0.002 * rng.range(-1.0, 1.0)) as f32;
    }
}

/// Round holes below the horizon until about 5 % of the image is covered.
fn holes(r: &mut [f32], s: &Scale, rng: &mut SplitMix64) {
    let target = (0.05 * (s.w * s.h) as f64) as usize;
    let y_min = s.yv + 4.0;
    let mut made = 0;
    let mut attempts = 0;
    while made < target && attempts < 100_000 {
        attempts += 1;
        let rad = (rng.range(2.0, 10.0) * s.k).max(1.0);
        let (cx, cy) = (rng.range(0.0, s.w as f64), rng.range(y_min, s.h as f64));
        let (x0, x1) = (
            (cx - rad).max(0.0) as usize,
            ((cx + rad) as usize).min(s.w - 1),
        );
        let (y0, y1) = (
            (cy - rad).max(y_min) as usize,
            ((cy + rad) as usize).min(s.h - 1),
        );
        for y in y0..=y1 {
            for x in x0..=x1 {
                let i = y * s.w + x;
                let inside = (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2) <= rad * rad;
                if inside && r[i].is_finite() {
                    r[i] = f32::NAN;
                    made += 1;
                }
            }
        }
    }
}

/// Camera height above the street, metres.
const STREET_CAMERA_HEIGHT: f64 = 1.4;

/// A synthetic street frame with the traits that defeat sky detection from the range alone
/// on real stereo data (a Cityscapes frame): see [`street_scene`].
#[derive(Clone, Debug)]
pub struct StreetScene {
    /// The colour image, linear RGB in [0, 1].
    pub image: RgbImage,
    /// The range as a stereo matcher delivers it, in metres (NaN = unknown).
    pub range: ScalarMap,
    /// Where the sky truly is (rays that hit nothing; the overhead wire is not sky).
    pub sky: Grid<bool>,
    /// Width of the unknown band along the left border, pixels.
    pub band_width: usize,
    /// Largest true range of the scene (not sky), before noise.
    pub scene_max: f32,
    /// The pixels (linear indices, outside the sky) given bogus far values.
    pub outliers: Vec<usize>,
    /// The true range of the scene, without noise, everywhere a ray hits it (the left
    /// band and the holes included); NaN in the sky and on the wire.
    pub truth: ScalarMap,
}

impl StreetScene {
    /// Plants `count` stereo mismatches: compact blotches (radius 1.5 to 3.5 px, scaled
    /// with the width from 512 px) of far values drawn from `far` (metres), on near
    /// surfaces (true range under 15 m) outside the left band, as a matcher gives them on
    /// a van or the road 5-10 m away (200-550 m on a Cityscapes frame). Deterministic for
    /// `seed`; returns the pixels changed.
    pub fn plant_mismatches(
        &mut self,
        count: usize,
        far: std::ops::Range<f64>,
        seed: u64,
    ) -> Vec<usize> {
        let (w, h) = (self.range.width(), self.range.height());
        let mut rng = SplitMix64::new(seed);
        let k = w as f64 / 512.0;
        let mut out = Vec::new();
        let mut placed = 0;
        for _ in 0..100_000 {
            if placed == count {
                break;
            }
            let (cx, cy) = (
                rng.range(self.band_width as f64 + 8.0 * k, w as f64 - 8.0 * k),
                rng.range(0.0, h as f64 - 4.0 * k),
            );
            let c = (cy as usize) * w + cx as usize;
            let (truth, range) = (self.truth.as_slice(), &mut self.range);
            let near =
                |range: &ScalarMap, p: usize| truth[p] < 15.0 && range.as_slice()[p].is_finite();
            if !near(range, c) {
                continue;
            }
            let rad = rng.range(1.5, 3.5) * k;
            let v = rng.range(far.start, far.end);
            for y in (cy - rad).max(0.0) as usize..((cy + rad) as usize + 1).min(h) {
                for x in (cx - rad).max(0.0) as usize..((cx + rad) as usize + 1).min(w) {
                    let p = y * w + x;
                    let inside = (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2) <= rad * rad;
                    if inside && near(range, p) && !out.contains(&p) {
                        range.as_mut_slice()[p] = (v * (1.0 + 0.01 * rng.range(-1.0, 1.0))) as f32;
                        out.push(p);
                    }
                }
            }
            placed += 1;
        }
        out
    }

    /// Blanks the top `rows` rows as rectification leaves them: no range and a black
    /// image.
    pub fn blank_top_rows(&mut self, rows: usize) {
        let w = self.range.width();
        let n = (rows * w).min(self.range.len());
        self.range.as_mut_slice()[..n].fill(f32::NAN);
        self.image.as_mut_slice()[..n].fill([0.0; 3]);
    }
}

/// A deterministic street frame of `width x height` pixels (both at least 64), the same
/// for the same `seed`, seen from 1.4 m up with the horizon at 45 % of the height and a
/// focal length of 1.1 x the width (Cityscapes' geometry):
///
/// - **scene**: a street with textured facades (windows, five wall colours): tall on the
///   right from 6 m, low on the left beyond a hedge from 20 m, a row of buildings closing
///   the street 90 m away, a tree crown, tarmac;
/// - **sky**: a smooth gradient from a pale horizon to a blue zenith with a soft brighter
///   cloud, 0.6 % sensor noise; a dark 1-px overhead wire crosses it;
/// - **range**: 0.5 % noise on the scene; **unknown** over the whole sky, the wire, a band
///   along the left border 7 % of the width wide from the top row to the bottom row (it
///   joins the sky's unknown region), and small round occlusion holes in the scene;
///   **matcher noise** in the sky: 4 % of its pixels scattered with values from 60 m to
///   3 km, and three small blobs of consistent far values (300-800 m);
/// - **outliers**: one value of 100 km on the street, two neighbouring values of 5 km on
///   a facade ([`StreetScene::outliers`]).
///
/// # Panics
/// If a size is below 64.
pub fn street_scene(width: usize, height: usize, seed: u64) -> StreetScene {
    assert!(
        width >= 64 && height >= 64,
        "street_scene needs at least 64x64 pixels"
    );
    let mut rng = SplitMix64::new(seed);
    let cam = StreetCamera::new(width, height);
    let street = Street::generate(&mut rng);
    let n = width * height;
    let (mut image, mut range, mut sky) = (vec![[0.0f32; 3]; n], vec![f32::NAN; n], vec![false; n]);
    let mut truth = vec![f32::NAN; n];
    let mut scene_max = 0.0f64;
    for p in 0..n {
        let (x, y) = (p % width, p / width);
        let d = cam.ray(x, y);
        let grain = rng.range(-1.0, 1.0);
        match street.cast(d) {
            Some((t, surface)) => {
                let r = t * (d[0] * d[0] + d[1] * d[1] + 1.0).sqrt();
                scene_max = scene_max.max(r);
                truth[p] = r as f32;
                range[p] = (r * (1.0 + 0.005 * rng.range(-1.0, 1.0))) as f32;
                image[p] = surface.colour(grain);
            }
            None => {
                sky[p] = true;
                image[p] = sky_colour(&cam, d, x, y, grain);
            }
        }
    }
    let band_width = (0.07 * width as f64).round() as usize;
    draw_wire(&mut image, &mut range, &mut sky, width, height);
    for (t, r) in truth.iter_mut().zip(&range) {
        if r.is_nan() {
            *t = f32::NAN; // the wire
        }
    }
    for y in 0..height {
        range[y * width..y * width + band_width].fill(f32::NAN);
    }
    occlusions(&mut range, &sky, width, height, &mut rng);
    sky_noise(&mut range, &sky, width, height, &mut rng);
    let outliers = plant_outliers(&mut range, &sky, width, height, band_width);
    StreetScene {
        image: Grid::from_vec(width, height, image),
        range: Grid::from_vec(width, height, range),
        sky: Grid::from_vec(width, height, sky),
        band_width,
        scene_max: scene_max as f32,
        outliers,
        truth: Grid::from_vec(width, height, truth),
    }
}

/// The pinhole camera of [`street_scene`].
struct StreetCamera {
    f: f64,
    cx: f64,
    cy: f64,
    w: f64,
    h: f64,
}

impl StreetCamera {
    fn new(width: usize, height: usize) -> Self {
        let (w, h) = (width as f64, height as f64);
        StreetCamera {
            f: 1.1 * w,
            cx: 0.5 * w,
            cy: 0.45 * h,
            w,
            h,
        }
    }

    /// The ray through the centre of pixel `(x, y)` (row 0 at the top) as `(dx, dy, 1)`:
    /// x right, y up, z forward.
    fn ray(&self, x: usize, y: usize) -> [f64; 3] {
        [
            (x as f64 + 0.5 - self.cx) / self.f,
            (self.cy - y as f64 - 0.5) / self.f,
            1.0,
        ]
    }
}

/// Wall colours of the facades, linear RGB.
const WALLS: [[f32; 3]; 5] = [
    [0.45, 0.38, 0.30],
    [0.35, 0.35, 0.37],
    [0.40, 0.20, 0.13],
    [0.50, 0.47, 0.35],
    [0.30, 0.33, 0.38],
];

/// What a ray hit.
#[derive(Clone, Copy, Debug)]
enum Surface {
    Tarmac,
    Foliage,
    /// A facade of wall colour `wall`, at `(along, up)` metres on its plane, shaded by
    /// `light`.
    Facade {
        wall: usize,
        along: f64,
        up: f64,
        light: f32,
    },
}

impl Surface {
    /// The colour, with `grain` in [-1, 1] for the texture.
    fn colour(self, grain: f64) -> [f32; 3] {
        let g = grain as f32;
        match self {
            Surface::Tarmac => [0.10, 0.10, 0.11].map(|c| c * (1.0 + 0.25 * g)),
            Surface::Foliage => [0.05, 0.11, 0.03].map(|c| c * (1.0 + 0.4 * g)),
            Surface::Facade {
                wall,
                along,
                up,
                light,
            } => {
                let window = up > 2.5
                    && (0.8..2.2).contains(&along.rem_euclid(3.0))
                    && (1.0..2.4).contains(&up.rem_euclid(3.2));
                let base = if window {
                    [0.05, 0.06, 0.08]
                } else {
                    WALLS[wall]
                };
                base.map(|c| c * light * (1.0 + 0.12 * g))
            }
        }
    }
}

/// One building: its extent along the street (or across it, for the far row), its height
/// and its wall colour.
#[derive(Clone, Copy, Debug)]
struct Building {
    from: f64,
    to: f64,
    height: f64,
    wall: usize,
}

/// The street: buildings on the right (plane x = 8, z from 6 m, 9 to 18 m high), low ones
/// on the left (x = -10, z from 20 m, 3.5 to 5.5 m high, so that the sky reaches the left
/// border), a row across the end (z = 90), a hedge on the left (x = -5, up to 1.2 m, z
/// from 2 to 20) and a tree crown. Every ray below the horizon hits something within
/// about 100 m.
struct Street {
    right: Vec<Building>,
    left: Vec<Building>,
    end: Vec<Building>,
}

impl Street {
    fn generate(rng: &mut SplitMix64) -> Self {
        let mut row = |from: f64, to: f64, step: f64, lo: f64, hi: f64| {
            let mut out = Vec::new();
            let mut a = from;
            while a < to {
                let b = (a + step * rng.range(0.7, 1.3)).min(to);
                out.push(Building {
                    from: a,
                    to: b,
                    height: rng.range(lo, hi),
                    wall: rng.below(WALLS.len()),
                });
                a = b;
            }
            out
        };
        Street {
            right: row(6.0, 90.0, 10.0, 9.0, 18.0),
            left: row(20.0, 90.0, 10.0, 3.5, 5.5),
            end: row(-30.0, 30.0, 6.0, 6.0, 11.0),
        }
    }

    /// The nearest hit of the ray `d` from the camera: its parameter `t` (the depth along
    /// z) and the surface.
    fn cast(&self, d: [f64; 3]) -> Option<(f64, Surface)> {
        let mut best: Option<(f64, Surface)> = None;
        let mut take = |t: f64, s: Surface| {
            if t > 0.0 && best.is_none_or(|(b, _)| t < b) {
                best = Some((t, s));
            }
        };
        let up = |t: f64| STREET_CAMERA_HEIGHT + t * d[1];
        if d[1] < 0.0 {
            take(STREET_CAMERA_HEIGHT / -d[1], Surface::Tarmac);
        }
        for (plane, row, light) in [(8.0, &self.right, 0.8f32), (-10.0, &self.left, 1.0)] {
            let t = plane / d[0];
            if let Some(b) = row.iter().find(|b| (b.from..b.to).contains(&t)) {
                if (0.0..b.height).contains(&up(t)) {
                    let (along, up) = (t, up(t));
                    take(
                        t,
                        Surface::Facade {
                            wall: b.wall,
                            along,
                            up,
                            light,
                        },
                    );
                }
            }
        }
        let t = -5.0 / d[0];
        if (2.0..20.0).contains(&t) && (0.0..1.2).contains(&up(t)) {
            take(t, Surface::Foliage);
        }
        let t = 90.0;
        if let Some(b) = self
            .end
            .iter()
            .find(|b| (b.from..b.to).contains(&(t * d[0])))
        {
            if (0.0..b.height).contains(&up(t)) {
                let (along, up) = (t * d[0], up(t));
                take(
                    t,
                    Surface::Facade {
                        wall: b.wall,
                        along,
                        up,
                        light: 0.9,
                    },
                );
            }
        }
        if let Some(t) = crown_hit(d) {
            take(t, Surface::Foliage);
        }
        best
    }
}

/// The tree crown, a sphere of radius 2 m centred 4 m up at (-7, 30): the ray's parameter
/// at its near side.
fn crown_hit(d: [f64; 3]) -> Option<f64> {
    let (c, r) = ([-7.0, 4.0 - STREET_CAMERA_HEIGHT, 30.0], 2.0);
    let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let dc = d[0] * c[0] + d[1] * c[1] + d[2] * c[2];
    let cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    let disc = dc * dc - dd * (cc - r * r);
    (disc >= 0.0).then(|| (dc - disc.sqrt()) / dd)
}

/// The sky: pale at the horizon, blue at the zenith, a soft brighter cloud, sensor grain.
fn sky_colour(cam: &StreetCamera, d: [f64; 3], x: usize, y: usize, grain: f64) -> [f32; 3] {
    const HORIZON: [f64; 3] = [0.78, 0.82, 0.90];
    const ZENITH: [f64; 3] = [0.30, 0.45, 0.80];
    let s = (d[1] / 0.22).clamp(0.0, 1.0).powf(0.7);
    let (dx, dy) = (x as f64 - 0.55 * cam.w, y as f64 - 0.12 * cam.h);
    let sigma = 0.06 * cam.w;
    let cloud = 0.12 * (-(dx * dx + dy * dy) / (2.0 * sigma * sigma)).exp();
    let mut c = [0.0f32; 3];
    for i in 0..3 {
        let v = HORIZON[i] + (ZENITH[i] - HORIZON[i]) * s + cloud;
        c[i] = (v * (1.0 + 0.006 * grain)).min(1.0) as f32;
    }
    c
}

/// A dark 1-px overhead wire from the left border to the right facades: unknown range,
/// not sky.
fn draw_wire(image: &mut [[f32; 3]], range: &mut [f32], sky: &mut [bool], w: usize, h: usize) {
    let (y0, y1) = (0.089 * h as f64, 0.184 * h as f64);
    let x1 = 0.793 * w as f64;
    for x in 0..(x1 as usize).min(w) {
        let y = (y0 + (y1 - y0) * x as f64 / x1).round() as usize;
        let p = y.min(h - 1) * w + x;
        image[p] = [0.04, 0.04, 0.04];
        range[p] = f32::NAN;
        sky[p] = false;
    }
}

/// Round occlusion holes (radius 1.5 to 4 px, scaled) in the scene.
fn occlusions(range: &mut [f32], sky: &[bool], w: usize, h: usize, rng: &mut SplitMix64) {
    let k = w as f64 / 512.0;
    for _ in 0..30 {
        let (cx, cy) = (
            rng.range(0.0, w as f64),
            rng.range(0.45 * h as f64, h as f64),
        );
        let rad = rng.range(1.5, 4.0) * k;
        for y in (cy - rad).max(0.0) as usize..((cy + rad) as usize + 1).min(h) {
            for x in (cx - rad).max(0.0) as usize..((cx + rad) as usize + 1).min(w) {
                let inside = (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2) <= rad * rad;
                if inside && !sky[y * w + x] {
                    range[y * w + x] = f32::NAN;
                }
            }
        }
    }
}

/// Matcher noise in the sky: 4 % of its pixels get a value from 60 m to 3 km (log-uniform),
/// and three blobs of 4 to 7 px get consistent values from 300 to 800 m.
fn sky_noise(range: &mut [f32], sky: &[bool], w: usize, h: usize, rng: &mut SplitMix64) {
    let sky_px: Vec<usize> = (0..w * h).filter(|&p| sky[p]).collect();
    if sky_px.is_empty() {
        return;
    }
    for &p in &sky_px {
        if rng.unit() < 0.04 {
            range[p] = 10f64.powf(rng.range(60f64.log10(), 3000f64.log10())) as f32;
        }
    }
    for _ in 0..3 {
        let c = sky_px[rng.below(sky_px.len())];
        let (cx, cy) = (c % w, c / w);
        let size = 4 + rng.below(4);
        let v = rng.range(300.0, 800.0);
        for y in cy..(cy + size).min(h) {
            for x in cx..(cx + size).min(w) {
                if sky[y * w + x] {
                    range[y * w + x] = (v * (1.0 + 0.02 * rng.range(-1.0, 1.0))) as f32;
                }
            }
        }
    }
}

/// One bogus value of 100 km on the street near the bottom centre and two of 5 km side by
/// side on the first known facade pixels from the right of the row at 30 % of the height.
fn plant_outliers(range: &mut [f32], sky: &[bool], w: usize, h: usize, band: usize) -> Vec<usize> {
    let mut out = Vec::new();
    let street = (h * 9 / 10) * w + w / 2;
    if range[street].is_finite() {
        range[street] = 1.0e5;
        out.push(street);
    }
    let row = h * 3 / 10;
    let known = |p: usize| !sky[p] && range[p].is_finite();
    if let Some(x) = (band + 1..w)
        .rev()
        .find(|&x| known(row * w + x) && known(row * w + x - 1))
    {
        for p in [row * w + x - 1, row * w + x] {
            range[p] = 5.0e3;
            out.push(p);
        }
    }
    out
}
