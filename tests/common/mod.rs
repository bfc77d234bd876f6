//! Shared helpers for the integration tests: one GL renderer at a time (EGL contexts are
//! per thread and llvmpipe is CPU-bound), deterministic synthetic inputs, the real Aloe
//! sample, and checks on range maps.
#![allow(dead_code)]

use brume::camera::{FrameCamera, FrameInputs};
use brume::medium::{Lookup, MediumSample, Pixel, UniformValue};
use brume::raster::{Grid, RgbImage, ScalarMap};
use brume::Headless;
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fs;
use std::path::Path;
use std::sync::{Mutex, MutexGuard};

static GL_LOCK: Mutex<()> = Mutex::new(());

/// Serialises GL tests and gives each its own context. A missing EGL is a test failure,
/// never a skip: CI must prove the GL path.
pub fn renderer() -> (MutexGuard<'static, ()>, Headless) {
    let guard = gl_lock();
    (guard, headless())
}

/// The lock that serialises GL tests.
pub fn gl_lock() -> MutexGuard<'static, ()> {
    GL_LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

/// Runs the `brume` program with `args` in `dir`, one GL user at a time.
pub fn brume(dir: &Path, args: &[&str]) -> std::process::Output {
    let _gl = gl_lock();
    std::process::Command::new(env!("CARGO_BIN_EXE_brume"))
        .args(args)
        .current_dir(dir)
        .env_remove("RUST_LOG")
        .output()
        .expect("run brume")
}

/// Runs `brume render --image photo --beta B --json` with no `--depth` (a portrait photo
/// is its own depth file), asserts that it succeeds, and returns its folder (where it
/// wrote `out.png`) and its report.
pub fn render_photo_alone(photo: &Path, beta: &str) -> (tempfile::TempDir, serde_json::Value) {
    let dir = tempfile::tempdir().unwrap();
    let image = photo.to_str().unwrap();
    let args = [
        "render", "--image", image, "--beta", beta, "--out", "out.png", "--json",
    ];
    let run = brume(dir.path(), &args);
    assert!(run.status.success(), "{}", stderr(&run));
    let report = serde_json::from_slice(&run.stdout).unwrap();
    (dir, report)
}

/// An image file's decoder, opened (its format told by its bytes), for its metadata.
pub fn image_decoder(path: &Path) -> impl ::image::ImageDecoder {
    ::image::ImageReader::open(path)
        .unwrap()
        .with_guessed_format()
        .unwrap()
        .into_decoder()
        .unwrap()
}

/// Writes `r.pfm` in `dir`: a range of 10 m everywhere, `w x h` (as a photo is stored).
pub fn write_flat_range(dir: &Path, w: usize, h: usize) {
    let map = brume::raster::Grid::filled(w, h, 10.0f32);
    brume::io::output::write_scalar(&dir.join("r.pfm"), &map).unwrap();
}

/// Runs `brume render --image image --depth r.pfm` (range in metres, in `dir`) with
/// `fog` (`--beta` ...) into `out`, asserting that it succeeds; returns its stderr.
pub fn render_over_range(dir: &Path, image: &Path, out: &str, fog: &[&str]) -> String {
    let image = image.to_str().unwrap();
    let depth = [
        "--depth",
        "r.pfm",
        "--depth-kind",
        "range",
        "--depth-scale",
        "1",
    ];
    let args = [
        &["render", "--image", image][..],
        &depth,
        fog,
        &["--out", out],
    ]
    .concat();
    let run = brume(dir, &args);
    assert!(run.status.success(), "{}", stderr(&run));
    stderr(&run)
}

/// Runs `brume render` on a small image with `flag path` (and nothing else but `--out`)
/// and asserts that it is refused: exit 1, stderr holding every one of `needles`, and no
/// output written.
pub fn assert_render_refuses(flag: &str, path: &Path, needles: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let image = dir.path().join("im.png");
    ::image::RgbImage::from_pixel(8, 6, ::image::Rgb([90, 120, 150]))
        .save(&image)
        .unwrap();
    let (image, path) = (image.to_str().unwrap(), path.to_str().unwrap());
    assert_render_refused(
        dir.path(),
        &["render", "--image", image, flag, path],
        needles,
    );
}

/// Runs `brume render` with `args` and `--out out.png` in `dir` and asserts that it is
/// refused: exit 1, stderr holding every one of `needles`, and no output written.
pub fn assert_render_refused(dir: &Path, args: &[&str], needles: &[&str]) {
    let out = dir.join("out.png");
    let run = brume(dir, &[args, &["--out", out.to_str().unwrap()]].concat());
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    for needle in needles {
        assert!(err.contains(needle), "`{err}` should mention `{needle}`");
    }
    assert!(!out.exists());
}

/// A program's stderr as text.
pub fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A new headless context and renderer; a missing EGL fails the test.
pub fn headless() -> Headless {
    Headless::new(None).unwrap_or_else(|e| panic!("cannot open a GL context: {e}"))
}

/// A small xorshift generator so that synthetic images are the same on every machine.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn next_f32(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Random colours in [0, 1] with a few hard edges: the worst case for diffusion error.
pub fn noise_image(w: usize, h: usize, seed: u64) -> RgbImage {
    let mut rng = Rng::new(seed);
    Grid::from_fn(w, h, |x, _| {
        let band = if x < w / 3 { 0.2 } else { 0.0 };
        [
            (rng.next_f32() * 0.8 + band).min(1.0),
            rng.next_f32(),
            rng.next_f32() * 0.5,
        ]
    })
}

/// A normalised range map: a slanted ramp with a near box in front (a depth edge).
pub fn ramp_range(w: usize, h: usize) -> ScalarMap {
    Grid::from_fn(w, h, |x, y| {
        let near_box = x > w / 4 && x < w / 2 && y > h / 4 && y < 3 * h / 4;
        if near_box {
            0.1
        } else {
            (0.3 + 0.7 * (x + y) as f32 / (w + h) as f32).min(1.0)
        }
    })
}

/// A file of the real Middlebury Aloe sample, kept in the repository (`tests/data/aloe/`).
pub fn aloe_path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/aloe")
        .join(name)
}

/// The real Middlebury Aloe disparity as a range map through the real loader (NaN where
/// the disparity is 0). The sample is part of the repository; missing is a failure.
pub fn aloe_range() -> ScalarMap {
    brume::io::depth::load_range(&aloe_path("disparity.png"), &Default::default())
        .unwrap_or_else(|e| panic!("{e} (the sample belongs in tests/data/aloe/)"))
        .range
}

/// Asserts that every finite pixel of `before` has exactly the same bits in `after`.
pub fn assert_known_unchanged(before: &ScalarMap, after: &ScalarMap) {
    assert_eq!(
        (before.width(), before.height()),
        (after.width(), after.height())
    );
    for (i, (b, a)) in before.as_slice().iter().zip(after.as_slice()).enumerate() {
        if b.is_finite() {
            assert_eq!(
                b.to_bits(),
                a.to_bits(),
                "known pixel {i} changed: {b} -> {a}"
            );
        }
    }
}

/// Asserts that every pixel is finite.
pub fn assert_all_finite(m: &ScalarMap) {
    if let Some(i) = m.as_slice().iter().position(|v| !v.is_finite()) {
        panic!("pixel {i} is {}", m.as_slice()[i]);
    }
}

/// Writes an RGB picture as PNG (for looking at test output by hand).
pub fn save_png(path: &str, w: usize, h: usize, px: &[[u8; 3]]) {
    let buf: Vec<u8> = px.iter().flatten().copied().collect();
    image::save_buffer(path, &buf, w as u32, h as u32, image::ColorType::Rgb8).expect("save png");
}

/// A version-1.0 .npy file written by hand, as numpy does.
pub fn npy_bytes(descr: &str, shape: &str, fortran: bool, data: &[u8]) -> Vec<u8> {
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
        if fortran { "True" } else { "False" }
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend_from_slice(&(header.len() as u16).to_le_bytes());
    b.extend_from_slice(header.as_bytes());
    b.extend_from_slice(data);
    b
}

/// A `.npz` as numpy's `np.savez` (stored) or `np.savez_compressed` (deflated) writes it:
/// one `.npy` member per array.
pub fn npz_bytes(arrays: &[(&str, Vec<u8>)], deflated: bool) -> Vec<u8> {
    use std::io::Write;
    let method = if deflated {
        zip::CompressionMethod::Deflated
    } else {
        zip::CompressionMethod::Stored
    };
    let options = zip::write::SimpleFileOptions::default().compression_method(method);
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    for (name, npy) in arrays {
        zip.start_file(format!("{name}.npy"), options).unwrap();
        zip.write_all(npy).unwrap();
    }
    zip.finish().unwrap().into_inner()
}

/// The window-depth buffer a GL renderer would write for a simple world seen by `camera`
/// (top row first, as the renderer takes buffers): the ground plane y = 0, a wall of
/// height 6 at z = −40 for |x| < 8, a pillar at (−3, −12), and sky (depth 1) elsewhere.
pub fn synthetic_depth_buffer(camera: &brume::camera::Camera, w: usize, h: usize) -> ScalarMap {
    use glam::DVec3;
    let eye = camera.eye();
    Grid::from_fn(w, h, |x, row| {
        let dir = camera.pixel_ray(x, h - 1 - row, w, h);
        let mut t_hit = f64::INFINITY;
        let mut consider = |t: f64, ok: &dyn Fn(DVec3) -> bool| {
            if t > 0.0 && t < t_hit && ok(eye + dir * t) {
                t_hit = t;
            }
        };
        if dir.y != 0.0 {
            consider(-eye.y / dir.y, &|_| true);
        }
        if dir.z != 0.0 {
            consider((-40.0 - eye.z) / dir.z, &|p| p.x.abs() < 8.0 && p.y < 6.0);
            consider((-12.0 - eye.z) / dir.z, &|p| {
                (p.x + 3.0).abs() < 0.5 && p.y < 4.0
            });
        }
        match camera.project_depth(eye + dir * t_hit) {
            Some((d, _)) if t_hit.is_finite() && d < 1.0 => d as f32,
            _ => 1.0,
        }
    })
}

/// One part of an OpenEXR file for [`exr_bytes`]: its name (`None`: unnamed) and its
/// channels, each a name and samples with the top row first.
pub type ExrPart<'a> = (Option<&'a str>, Vec<(&'a str, exr::prelude::FlatSamples)>);

/// The bytes of a `w` x `h` OpenEXR file of ZIP-compressed scan lines: one part per entry of
/// `parts` (a multi-part file when there are several), as renderers and engines write
/// them.
pub fn exr_bytes(w: usize, h: usize, parts: Vec<ExrPart>) -> Vec<u8> {
    exr_sized_parts_bytes(parts.into_iter().map(|p| ((w, h), p)).collect())
}

/// [`exr_bytes`] with a size for each part (`(width, height)`, pixels from the display
/// window's corner); the display window is the largest.
pub fn exr_sized_parts_bytes(parts: Vec<((usize, usize), ExrPart)>) -> Vec<u8> {
    use exr::prelude::*;
    let w = parts.iter().map(|((w, _), _)| *w).max().unwrap_or(1);
    let h = parts.iter().map(|((_, h), _)| *h).max().unwrap_or(1);
    let layers: Vec<Layer<AnyChannels<FlatSamples>>> = parts
        .into_iter()
        .map(|(size, (name, channels))| {
            let attributes = match name {
                Some(name) => LayerAttributes::named(name),
                None => LayerAttributes::default(),
            };
            let list = channels
                .into_iter()
                .map(|(name, samples)| AnyChannel::new(name, samples))
                .collect();
            Layer::new(
                size,
                attributes,
                Encoding::SMALL_LOSSLESS,
                AnyChannels::sort(list),
            )
        })
        .collect();
    let bounds = IntegerBounds::new((0, 0), (w, h));
    let mut bytes = Vec::new();
    Image::from_layers(ImageAttributes::new(bounds), layers)
        .write()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .unwrap();
    bytes
}

/// Float samples for [`exr_bytes`].
pub fn f32s(values: &[f32]) -> exr::prelude::FlatSamples {
    exr::prelude::FlatSamples::F32(values.to_vec())
}

/// Half-float samples for [`exr_bytes`] (Blender's default for EXR output).
pub fn f16s(values: &[f32]) -> exr::prelude::FlatSamples {
    exr::prelude::FlatSamples::F16(values.iter().map(|&v| half::f16::from_f32(v)).collect())
}

/// Every entry under `dir`: file bytes, link targets, folders.
pub fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut all = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            let name = path.strip_prefix(dir).unwrap().display().to_string();
            let meta = fs::symlink_metadata(&path).unwrap();
            let content = if meta.file_type().is_symlink() {
                let target = fs::read_link(&path).unwrap();
                format!("-> {}", target.display()).into_bytes()
            } else if meta.is_dir() {
                stack.push(path);
                b"(folder)".to_vec()
            } else {
                fs::read(&path).unwrap()
            };
            all.insert(name, content);
        }
    }
    all
}

/// Slab test: the ray parameter where `o + t·r` enters the axis-aligned box [min, max],
/// if it does (t > 0).
pub fn ray_enters_box(
    o: glam::DVec3,
    r: glam::DVec3,
    min: glam::DVec3,
    max: glam::DVec3,
) -> Option<f64> {
    let (mut near, mut far) = (0.0f64, f64::INFINITY);
    for axis in 0..3 {
        let (lo, hi) = ((min - o)[axis], (max - o)[axis]);
        if r[axis] == 0.0 {
            if lo > 0.0 || hi < 0.0 {
                return None;
            }
            continue;
        }
        let (t0, t1) = (lo / r[axis], hi / r[axis]);
        near = near.max(t0.min(t1));
        far = far.min(t0.max(t1));
    }
    (near <= far && near > 0.0).then_some(near)
}

/// The medium's pixel at column `x` and row `row` counted from the top, as image buffers
/// are (a medium counts rows from the bottom, as GL stores them), of a `width x height`
/// frame, with σ0 = 1.
pub fn pixel_top_first(x: usize, row: usize, width: usize, height: usize, depth: f64) -> Pixel {
    Pixel {
        x,
        y: height - 1 - row,
        width,
        height,
        depth,
        sigma0: 1.0,
    }
}

/// `M` as a medium that keeps to itself what the pipeline uses to go faster:
/// `Medium::uniform_inscatter` (so it renders in paper 000's pre-multiplied layout,
/// F = (τ·E, τ) and ρ in targets of their own, which the offset layout must match) and,
/// unless `sigma_min`, `Medium::sigma_min` (left at σ0, as a haze's: the coarse stage then
/// starts where σmax reaches `coarse_from`, never at step 0). Everything else is `M`'s.
pub struct Withheld<M> {
    pub medium: M,
    /// Whether `Medium::sigma_min` is `M`'s.
    pub sigma_min: bool,
}

/// `medium` in the pre-multiplied layout, otherwise as it is.
pub fn premultiplied<M>(medium: M) -> Withheld<M> {
    Withheld {
        medium,
        sigma_min: true,
    }
}

/// `medium` in the pre-multiplied layout, promising no σ above σ0 either.
pub fn unpromised<M>(medium: M) -> Withheld<M> {
    Withheld {
        medium,
        sigma_min: false,
    }
}

impl<M: brume::Medium> brume::Medium for Withheld<M> {
    fn name(&self) -> Cow<'static, str> {
        self.medium.name()
    }
    fn glsl(&self) -> Cow<'static, str> {
        self.medium.glsl()
    }
    fn uniforms(&self, frame: &FrameInputs) -> Vec<(Cow<'static, str>, UniformValue)> {
        self.medium.uniforms(frame)
    }
    fn chromatic(&self) -> bool {
        self.medium.chromatic()
    }
    fn sigma_max(&self, sigma0: f64) -> f64 {
        self.medium.sigma_max(sigma0)
    }
    fn sigma_min(&self, sigma0: f64) -> f64 {
        if self.sigma_min {
            self.medium.sigma_min(sigma0)
        } else {
            sigma0
        }
    }
    fn sample(&self, pixel: Pixel, frame: &FrameInputs) -> MediumSample {
        self.medium.sample(pixel, frame)
    }
    fn validate(&self) -> brume::Result<()> {
        self.medium.validate()
    }
    fn needs_camera(&self) -> bool {
        self.medium.needs_camera()
    }
    fn frame_camera(&self, frame: &FrameInputs) -> Option<FrameCamera> {
        self.medium.frame_camera(frame)
    }
    fn validate_frame(&self, frame: &FrameInputs) -> brume::Result<()> {
        self.medium.validate_frame(frame)
    }
    fn lookups(&self) -> Vec<(Cow<'static, str>, Lookup)> {
        self.medium.lookups()
    }
}
