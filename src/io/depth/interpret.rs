//! From a decoded file to a range map: settle the format and what the values measure,
//! then apply the dataset's convention and the camera geometry. The rules for one
//! dataset live in its own module; this is where they are chosen.

use std::path::{Path, PathBuf};

use super::android::ConfidenceTally;
use super::cityscapes::{self, CityscapesCamera};
use super::gdepth::EmbeddedDepth;
use super::middlebury::{self, Calib};
use super::raw::Raw;
use super::{android, png16};
use super::{finite_option, positive_option, DepthFormat, DepthKind, DepthOptions, LoadedDepth};
use crate::camera::{Camera, DepthModel};
use crate::io::camera::{to_range, Intrinsics, Mount, Stereo};
use crate::io::codec::NPZ_FOCAL_ARRAY;
use crate::raster::Orientation;
use crate::{Error, Result};

/// The camera files that came with a depth map, parsed, with their paths.
#[derive(Default)]
pub(super) struct SideFiles {
    /// A Middlebury 2014 `calib.txt`.
    pub calib: Option<(Calib, PathBuf)>,
    /// A Cityscapes `{name}_camera.json`.
    pub camera: Option<(CityscapesCamera, PathBuf)>,
}

fn resolve_format(
    requested: DepthFormat,
    raw: &Raw,
    side: &SideFiles,
    opts: &DepthOptions,
    path: &Path,
) -> Result<DepthFormat> {
    use DepthFormat as F;
    let (has_calib, has_camera) = (side.calib.is_some(), side.camera.is_some());
    let format = match (requested, raw) {
        (F::Auto, Raw::Float { from_pfm: true, .. }) if has_calib => F::Middlebury2014,
        (F::Auto, Raw::Float { .. }) => F::Float,
        (F::Auto, Raw::Grey8(_)) => F::Middlebury2006,
        (F::Auto, Raw::Embedded(e)) => e.format,
        // A camera file was given, or found for a `*_disparity.png`.
        (F::Auto, Raw::Grey16(_)) if has_camera => F::Cityscapes,
        (F::Auto, Raw::Grey16(_))
            if opts.scale.is_some()
                || matches!(
                    opts.kind,
                    Some(DepthKind::ZBuffer | DepthKind::Inverse | DepthKind::Affine)
                ) =>
        {
            F::Png16
        }
        (F::Auto, Raw::Grey16(_)) => {
            return Err(Error::format(
                path,
                "16-bit depth (a PNG, a 16-bit TIFF or a uint16 array) has no standard scale: \
                 give `depth_format` kitti, nyu or tum, or `depth_scale` with the metres per \
                 unit (a Cityscapes disparity: `depth_format` cityscapes with `camera`; a \
                 monocular model's relative inverse depth, Depth Anything or MiDaS: \
                 `depth_kind` inverse; its affine-invariant depth, Marigold: `depth_kind` \
                 affine with `near` and `far`)",
            ))
        }
        (f, _) => f,
    };
    let layout = format.rule().layout;
    if !layout.fits(raw) {
        return Err(Error::format(
            path,
            format!(
                "`depth_format` {format} expects {}, found {}",
                layout.expected(),
                raw.describe()
            ),
        ));
    }
    if format == F::Middlebury2014 && !has_calib {
        return Err(Error::format(
            path,
            "Middlebury 2014 disparity needs its calib.txt: none next to the file; give it as \
             `calib`",
        ));
    }
    if format == F::Cityscapes && !has_camera {
        return Err(Error::format(
            path,
            "a Cityscapes disparity needs its camera file ({name}_camera.json): give it as \
             `camera` (or read both with load_cityscapes_from_bytes)",
        ));
    }
    Ok(format)
}

fn resolve_kind(format: DepthFormat, requested: Option<DepthKind>) -> Result<DepthKind> {
    let rule = format.rule();
    let kind = requested.unwrap_or(rule.default_kind);
    if !rule.accepts(kind) {
        let mut expected = if rule.default_kind == DepthKind::Disparity {
            format!("disparity for `depth_format` {format}")
        } else {
            format!("depth or range for `depth_format` {format}")
        };
        if matches!(kind, DepthKind::Inverse | DepthKind::Affine) {
            // An 8-bit PNG is read as Middlebury 2006's disparity: a monocular model's
            // output saved as one (its visualisation) has lost most of its levels.
            expected.push_str(&format!(
                " (a monocular model's {kind} depth is read from a 16-bit PNG or a float \
                 map, .npy, .npz, .pfm, .exr or float TIFF: save its output as one of those)"
            ));
        }
        return Err(Error::invalid("depth_kind", kind, expected));
    }
    Ok(kind)
}

// The geometry is in `io::camera`; which options supply it, and the messages naming
// them, belong to the depth front end.
impl Stereo {
    /// Focal, baseline and offset from the options, for disparity maps without a calib.
    fn from_options(opts: &DepthOptions, format: DepthFormat) -> Result<Self> {
        let missing = |name: &str| {
            Error::invalid(
                name,
                "nothing",
                format!(
                    "a value: `depth_format` {format} with `depth_kind` disparity needs `focal` \
                     (px) and `baseline` (mm)"
                ),
            )
        };
        let focal = opts.focal.ok_or_else(|| missing("focal"))?;
        let baseline = opts.baseline.ok_or_else(|| missing("baseline"))?;
        Ok(Stereo {
            focal: positive_option(focal, "focal", "a positive focal length in pixels")?,
            baseline_mm: positive_option(baseline, "baseline", "a positive length in mm")?,
            offset: finite_option(opts.disparity_offset.unwrap_or(0.0), "disparity_offset")?,
        })
    }
}

/// Turns a decoded file into a range map, with the notes gathered so far (a calib.txt
/// found) and those added here.
pub(super) fn interpret(
    raw: Raw,
    path: &Path,
    opts: &DepthOptions,
    side: SideFiles,
    mut notes: Vec<String>,
    pixel_scale: f64,
) -> Result<LoadedDepth> {
    let format = resolve_format(opts.format, &raw, &side, opts, path)?;
    let kind = resolve_kind(format, opts.kind.or(raw.measured_kind()))?;
    let SideFiles { calib, camera } = side;
    if let (Some((_, camera_path)), false) = (&camera, format == DepthFormat::Cityscapes) {
        notes.push(format!(
            "camera file {} ignored: the file was read as {format}",
            camera_path.display()
        ));
    }
    let has_planes = matches!(kind, DepthKind::ZBuffer | DepthKind::Affine);
    if !has_planes && (opts.near.is_some() || opts.far.is_some()) {
        notes.push(format!(
            "`near` and `far` ignored: only a z-buffer's projection has clipping planes and \
             only affine-invariant depth a nearest and farthest depth, and the file was read \
             as {kind}"
        ));
    }
    if kind != DepthKind::ZBuffer && opts.reversed_z {
        notes.push(format!(
            "`reversed_z` ignored: only a z-buffer's depth is reversed, and the file was \
             read as {kind}"
        ));
    }
    let min_confidence = android::min_confidence(format, opts, &mut notes)?;
    let (width, height) = raw.size();
    let turn = super::orient::turn_for_photo(opts, width, height, &mut notes);
    // `fov` is the upright photo's: across the stored map's width when turning swaps them.
    let fov_height = if turn.swaps_axes() { width } else { height };
    let metres = "m".to_string();
    let mut stereo_focal_baseline = None;
    let view = super::stereo_view_for(format, path, opts);
    let mut mount = None;
    let (mut range, units, intrinsics) = match (format, raw) {
        (DepthFormat::Middlebury2014, Raw::Float { map, .. }) => {
            let (calib, calib_path) = calib.expect("checked by resolve_format");
            let (range, k, fb) =
                middlebury::range_2014(&map, (path, view), &calib, &calib_path, opts, &mut notes)?;
            stereo_focal_baseline = Some(fb);
            (range, metres, Some(k))
        }
        (DepthFormat::Cityscapes, Raw::Grey16(disp)) => {
            let (camera, _) = camera.expect("checked by resolve_format");
            let range = cityscapes::range(&disp, &camera, opts, &mut notes);
            stereo_focal_baseline = Some(camera.baseline_m * camera.intrinsics.fx);
            mount = camera.mount;
            (range, metres, Some(camera.intrinsics))
        }
        (DepthFormat::Middlebury2006, Raw::Grey8(disp)) => {
            let (range, k, fb) = middlebury::range_2006(&disp, opts, pixel_scale, &mut notes)?;
            stereo_focal_baseline = Some(fb);
            (range, metres, Some(k))
        }
        (_, Raw::Grey16(raw)) if kind == DepthKind::ZBuffer => {
            let (depth, k, units) = zbuffer(opts, (width, height), fov_height, &mut notes)?;
            let window = 1.0 / f64::from(u16::MAX);
            let range = to_range(&raw, |v| depth(f64::from(v) * window), Some(&k));
            (range, units, Some(k))
        }
        (_, Raw::Float { map, .. }) if kind == DepthKind::ZBuffer => {
            let (depth, k, units) = zbuffer(opts, (width, height), fov_height, &mut notes)?;
            let range = to_range(&map, |v| depth(f64::from(v)), Some(&k));
            (range, units, Some(k))
        }
        (_, Raw::Grey16(raw)) if kind.is_monocular() => {
            let k = depth_intrinsics(kind, opts, (width, height), fov_height, &mut notes)?;
            let (model, units) = Monocular::of(kind, opts, &mut notes)?;
            let code = model.code_value();
            let range = to_range(&raw, |v| model.depth(f64::from(v) * code), k.as_ref());
            (range, units, k)
        }
        (_, Raw::Float { map, .. }) if kind.is_monocular() => {
            let k = depth_intrinsics(kind, opts, (width, height), fov_height, &mut notes)?;
            let (model, units) = Monocular::of(kind, opts, &mut notes)?;
            let range = to_range(&map, |v| model.depth(f64::from(v)), k.as_ref());
            (range, units, k)
        }
        (DepthFormat::Png16, Raw::Grey16(raw)) if kind == DepthKind::Disparity => {
            let scale = png16::given_scale(opts)?;
            let stereo = Stereo::from_options(opts, format)?;
            stereo_focal_baseline = Some(stereo.focal_baseline());
            let k = Intrinsics::centred(stereo.focal, width, height);
            notes.push("principal point assumed at the image centre".to_string());
            let depth = |v: u16| {
                (v != 0)
                    .then(|| stereo.depth_m(f64::from(v) * scale))
                    .flatten()
            };
            (to_range(&raw, depth, Some(&k)), metres, Some(k))
        }
        (DepthFormat::AndroidDepth16, Raw::Grey16(raw)) => {
            android::check_confidence(&raw, min_confidence, path, &mut notes)?;
            let scale = png16::scale(format, opts, &mut notes)?;
            let k = depth_intrinsics(kind, opts, (width, height), fov_height, &mut notes)?;
            let depth = |v: u16| android::metres(v, min_confidence, scale);
            (to_range(&raw, depth, k.as_ref()), metres, k)
        }
        (_, Raw::Grey16(raw)) => {
            let scale = png16::scale(format, opts, &mut notes)?;
            let k = depth_intrinsics(kind, opts, (width, height), fov_height, &mut notes)?;
            let depth = |v: u16| (v != 0).then_some(f64::from(v) * scale);
            (to_range(&raw, depth, k.as_ref()), metres, k)
        }
        (_, Raw::Float { map, .. }) if kind == DepthKind::Disparity => {
            let stereo = Stereo::from_options(opts, format)?;
            stereo_focal_baseline = Some(stereo.focal_baseline());
            let k = Intrinsics::centred(stereo.focal, width, height);
            notes.push("principal point assumed at the image centre".to_string());
            let range = to_range(&map, |d| stereo.depth_m(f64::from(d)), Some(&k));
            (range, metres, Some(k))
        }
        (
            _,
            Raw::Float {
                mut map, focal_px, ..
            },
        ) => {
            if opts.sky_beyond.is_none() {
                drop_clamp(&mut map, &mut notes);
            }
            let held = focal_px.map(|f| {
                let said = format!(
                    "focal length from the archive's '{NPZ_FOCAL_ARRAY}': {f:.2} px; \
                     principal point assumed at the image centre"
                );
                (Intrinsics::centred(f, width, height), said)
            });
            let source = format!("archive's '{NPZ_FOCAL_ARRAY}'");
            let size = (width, height);
            let k = held_or_given(held, &source, kind, opts, size, fov_height, &mut notes)?;
            let (scale, units) = vouched_scale(opts, "values", FILE_UNITS, &mut notes)?;
            let range = to_range(&map, |v| Some(f64::from(v) * scale), k.as_ref());
            (range, units, k)
        }
        (_, Raw::Embedded(mut e)) => {
            notes.extend(std::mem::take(&mut e.notes));
            drop_unconfident(&mut e, opts.min_confidence, path, &mut notes)?;
            let source = format!("file's {}", calibration_name(e.format));
            let held = e.intrinsics.map(|k| {
                let said = format!(
                    "intrinsics from the {source}: fx {:.2} fy {:.2} px on the map's grid",
                    k.fx, k.fy
                );
                (k, said)
            });
            let size = (width, height);
            let k = held_or_given(held, &source, kind, opts, size, fov_height, &mut notes)?;
            // A relative map's metres (an iPhone's dual camera) may be rescaled by one who
            // knows a distance in the scene; a map in file units is made metric so.
            let (scale, units) = vouched_scale(opts, "the file's depth", &e.units, &mut notes)?;
            let range = to_range(
                &e.map,
                |v| v.is_finite().then_some(f64::from(v) * scale),
                k.as_ref(),
            );
            (range, units, k)
        }
        (_, Raw::Grey8(_)) => unreachable!("resolve_format sends 8-bit PNGs to Middlebury 2006"),
    };
    if let Some(beyond) = opts.sky_beyond {
        drop_sky_beyond(&mut range, beyond, &units, &mut notes)?;
    }
    let range = range.into_oriented(turn);
    let intrinsics = intrinsics.map(|k| k.oriented(turn, width, height));
    let unknown_pixels = range.as_slice().iter().filter(|v| v.is_nan()).count();
    if unknown_pixels == range.len() {
        return Err(Error::NoValidDepth {
            path: path.to_path_buf(),
        });
    }
    let metric = is_metric(format, &units, opts);
    // A turned map's file mount is the stored view's; the one given is the upright photo's.
    let mount = mount.filter(|_| turn == Orientation::Upright);
    let mount = given_mount(opts, mount, intrinsics.is_some() && metric, &mut notes);
    // A turned map's occlusions lie along its columns, not its rows.
    let stereo_focal_baseline = stereo_focal_baseline.filter(|_| turn == Orientation::Upright);
    let stereo_view =
        super::kept_stereo_view(view, stereo_focal_baseline.is_some(), opts, &mut notes);
    Ok(LoadedDepth {
        range,
        format,
        kind,
        metric,
        units,
        intrinsics,
        notes,
        unknown_pixels,
        turned: turn,
        stereo_focal_baseline,
        stereo_view,
        mount,
    })
}

/// The mount of the map: [`DepthOptions::camera_mount`] where given and `usable` (the
/// map has intrinsics and metres: the level road's range needs both), else the file's.
fn given_mount(
    opts: &DepthOptions,
    from_file: Option<Mount>,
    usable: bool,
    notes: &mut Vec<String>,
) -> Option<Mount> {
    match opts.camera_mount {
        Some(_) if !usable => {
            notes.push(
                "`camera_mount` ignored: the level road's range needs the map's intrinsics \
                 (`focal`, `fov` or its calibration) and range in metres"
                    .to_string(),
            );
            from_file
        }
        Some(given) => Some(given),
        None => from_file,
    }
}

/// The multiplier to metres of a map whose unit nothing says (a float map, a z-buffer's
/// near and far planes, inverse depth) and the units it leaves: `depth_scale` where given
/// (1 for metres), the caller vouching for the unit as for a 16-bit PNG, with a note that
/// `what` was scaled, and metres; 1 and `unscaled` without it.
fn vouched_scale(
    opts: &DepthOptions,
    what: &str,
    unscaled: &str,
    notes: &mut Vec<String>,
) -> Result<(f64, String)> {
    if opts.scale.is_none() {
        return Ok((1.0, unscaled.to_string()));
    }
    let scale = png16::given_scale(opts)?;
    notes.push(format!("{what} x {scale} = metres (depth scale)"));
    Ok((scale, "m".to_string()))
}

/// How far below 1 an affine-invariant depth is taken as the far plane: the model clamps
/// what lies beyond its farthest depth, the sky above all, to 1 (65535 in its 16-bit PNG),
/// and the sky, unknown, is then found by pre-processing with the image, as inverse
/// depth's is. 13 codes of the PNG; float16's last step below 1 (4.9e-4) stays known.
const AFFINE_FAR_MARGIN: f64 = 2e-4;

/// How a monocular estimator's relative map becomes depth.
#[derive(Clone, Copy, Debug)]
enum Monocular {
    /// Relative inverse depth d (MiDaS, Depth Anything): depth = `scale`/(d + `offset`).
    Inverse { offset: f64, scale: f64 },
    /// Affine-invariant depth d (Marigold): depth = `scale`·(`near` + d·(`far` − `near`)).
    Affine { near: f64, far: f64, scale: f64 },
}

impl DepthKind {
    /// Whether the values are a monocular estimator's relative map ([`Monocular`]).
    fn is_monocular(self) -> bool {
        matches!(self, DepthKind::Inverse | DepthKind::Affine)
    }
}

impl Monocular {
    /// The conversion of a map of `kind` (inverse or affine) with its options, and the
    /// units it leaves: `depth_scale` (metres: metric) or 1 (relative or file units).
    /// Inverse depth's shift is `disparity_offset` (default 0); affine depth needs `near`
    /// and `far`, which nothing in the map says.
    fn of(kind: DepthKind, opts: &DepthOptions, notes: &mut Vec<String>) -> Result<(Self, String)> {
        if kind == DepthKind::Inverse {
            let offset = match opts.disparity_offset {
                Some(o) => finite_option(o, "disparity_offset")?,
                None => 0.0,
            };
            let (scale, units) = vouched_scale(opts, "1/(d + offset)", "relative units", notes)?;
            notes.push(format!(
                "relative inverse depth: depth = {scale}/(d + {offset}), unknown where \
                 d + {offset} ≤ 0"
            ));
            return Ok((Monocular::Inverse { offset, scale }, units));
        }
        let (near, far) = affine_planes(opts)?;
        let (scale, units) = vouched_scale(opts, "near and far", FILE_UNITS, notes)?;
        notes.push(format!(
            "affine-invariant depth: depth = {near} + d·({far} − {near}) (0 the nearest depth \
             in the scene, 1 the farthest); unknown where not finite, and at the far plane \
             (d ≥ {}), where the model puts the sky",
            1.0 - AFFINE_FAR_MARGIN
        ));
        Ok((Monocular::Affine { near, far, scale }, units))
    }

    /// The depth of value `d`, `None` where unknown (not finite, not in front of the
    /// camera, or at affine depth's far plane).
    fn depth(self, d: f64) -> Option<f64> {
        let depth = match self {
            Monocular::Inverse { offset, scale } => scale / (d + offset),
            Monocular::Affine { .. } if d >= 1.0 - AFFINE_FAR_MARGIN => return None,
            Monocular::Affine { near, far, scale } => scale * (near + d * (far - near)),
        };
        (depth.is_finite() && depth > 0.0).then_some(depth)
    }

    /// The value one code of a 16-bit PNG stands for: affine depth is stored as d·65535
    /// (Marigold's PNG); inverse depth keeps its codes, whose scale does not matter.
    fn code_value(self) -> f64 {
        match self {
            Monocular::Inverse { .. } => 1.0,
            Monocular::Affine { .. } => 1.0 / f64::from(u16::MAX),
        }
    }
}

/// Affine-invariant depth's `near` and `far`, required and checked (0 < near < far, both
/// finite).
fn affine_planes(opts: &DepthOptions) -> Result<(f64, f64)> {
    let needs = |name: &str, what: &str| {
        Error::invalid(
            name,
            "nothing",
            format!(
                "{what}: `depth_kind` affine maps 0 to `near` and 1 to `far`, which the model \
                 chose for this image and does not give; give both (a guess serves: 2 and \
                 200 for a street, 1 and 10 for a room; metres with `depth_scale` 1, and \
                 without it only their ratio matters)"
            ),
        )
    };
    let near = opts
        .near
        .ok_or_else(|| needs("near", "the nearest depth in the scene"))?;
    let far = opts
        .far
        .ok_or_else(|| needs("far", "the farthest depth in the scene"))?;
    let near = positive_option(near, "near", "a positive depth, the scene's nearest")?;
    if !(far.is_finite() && far > near) {
        return Err(Error::invalid(
            "far",
            far,
            format!("a finite depth greater than near ({near}), the scene's farthest"),
        ));
    }
    Ok((near, far))
}

/// The least share of a float map's samples at its largest value that make it a clamp.
const CLAMP_MIN_FRACTION: f64 = 0.01;
/// How many times the mean of the other values a clamp lies beyond, at least.
const CLAMP_MIN_RATIO: f64 = 10.0;

/// Makes unknown the samples of a float depth or range map at its largest value when that
/// value is a clamp, not a surface: held exactly by at least [`CLAMP_MIN_FRACTION`] of the
/// samples and [`CLAMP_MIN_RATIO`] times the mean of the other known values or more. A
/// model that clamps the sky (Depth Pro, at 10 km) or a renderer's background (Blender's
/// 1e10) would otherwise be fogged as a wall that far, the sky not found and the airlight
/// not taken from it. A note says how many and why.
fn drop_clamp(map: &mut crate::raster::ScalarMap, notes: &mut Vec<String>) {
    let known = |v: f32| v.is_finite() && v > 0.0;
    let samples = map.as_slice();
    let Some(top) = samples
        .iter()
        .copied()
        .filter(|&v| known(v))
        .reduce(f32::max)
    else {
        return;
    };
    let (mut at_top, mut others, mut sum) = (0usize, 0usize, 0.0f64);
    for &v in samples.iter().filter(|&&v| known(v)) {
        if v == top {
            at_top += 1;
        } else {
            others += 1;
            sum += f64::from(v);
        }
    }
    let mean = sum / others.max(1) as f64;
    let share = at_top as f64 / samples.len() as f64;
    if share < CLAMP_MIN_FRACTION || others == 0 || f64::from(top) < CLAMP_MIN_RATIO * mean {
        return;
    }
    map.as_mut_slice()
        .iter_mut()
        .filter(|v| **v == top)
        .for_each(|v| *v = f32::NAN);
    notes.push(format!(
        "{at_top} samples ({:.1} %) hold the map's largest value, {top}, {:.0} times the mean \
         of the others: a clamp (a model's sky, a renderer's background), taken as unknown, \
         the sky (`sky_beyond` sets where the sky begins instead; inf keeps every value)",
        100.0 * share,
        f64::from(top) / mean
    ));
}

/// Makes unknown the range at or beyond `beyond` (`sky_beyond`), with a note.
fn drop_sky_beyond(
    range: &mut crate::raster::ScalarMap,
    beyond: f64,
    units: &str,
    notes: &mut Vec<String>,
) -> Result<()> {
    if beyond.is_nan() || beyond <= 0.0 {
        return Err(Error::invalid(
            "sky_beyond",
            beyond,
            "a positive range (the range's units), or inf to keep every value",
        ));
    }
    if beyond.is_infinite() {
        notes.push("`sky_beyond` inf: every value kept, no clamp looked for".to_string());
        return Ok(());
    }
    let mut dropped = 0usize;
    for v in range.as_mut_slice() {
        if f64::from(*v) >= beyond {
            *v = f32::NAN;
            dropped += 1;
        }
    }
    notes.push(format!(
        "{dropped} samples at or beyond `sky_beyond` {beyond} {units}: unknown (the sky)"
    ));
    Ok(())
}

/// With `min_confidence` given, the samples of a portrait photo's depth whose confidence
/// map puts them below it are unknown (none without it: the devices' scales of confidence
/// differ); a note says how many, or that the file has no confidence map. A threshold that
/// leaves no sample is refused, naming the highest confidence found, as for DEPTH16.
fn drop_unconfident(
    e: &mut EmbeddedDepth,
    min_confidence: Option<f64>,
    path: &Path,
    notes: &mut Vec<String>,
) -> Result<()> {
    let Some(threshold) = min_confidence else {
        return Ok(());
    };
    let Some(confidence) = &e.confidence else {
        notes.push(format!(
            "`min_confidence` ignored: this {} file has no confidence map",
            e.format
        ));
        return Ok(());
    };
    let mut tally = ConfidenceTally::new(threshold);
    for (v, &c) in e.map.as_mut_slice().iter_mut().zip(confidence.as_slice()) {
        if v.is_finite() && tally.drops(f64::from(c)) {
            *v = f32::NAN;
        }
    }
    tally.refuse_if_none_left("depth samples", " in the file's confidence map", "", path)?;
    notes.push(format!(
        "{} samples below `min_confidence` {threshold} in the confidence map: unknown",
        tally.dropped
    ));
    Ok(())
}

/// What a phone's JPEG calls the depth camera's intrinsics, for notes.
fn calibration_name(format: DepthFormat) -> &'static str {
    match format {
        DepthFormat::AppleDepth => "IntrinsicMatrix",
        _ => "ImagingModel",
    }
}

/// The units of a map whose unit nothing says (a float map, a z-buffer's planes).
pub(super) const FILE_UNITS: &str = "file units";

/// Whether a range in `units` read as `format` is in trustworthy metres
/// ([`LoadedDepth::metric`]): every conversion that yields metres does, except Middlebury
/// 2006 with any of its approximate default geometry.
fn is_metric(format: DepthFormat, units: &str, opts: &DepthOptions) -> bool {
    let guessed_geometry = format == DepthFormat::Middlebury2006
        && (opts.focal.is_none() || opts.baseline.is_none() || opts.disparity_offset.is_none());
    units == "m" && !guessed_geometry
}

/// A z-buffer's conversion: window depth → eye depth by the near and far planes (one
/// addition and one division, [`DepthModel::of_planes`]: standard or reversed-Z, finite or
/// infinite far plane) times `depth_scale` where given ([`vouched_scale`]), unknown where
/// nothing was drawn (1, or 0 reversed) and outside [0, 1]; the intrinsics of its vertical
/// field of view, and the range's units.
fn zbuffer(
    opts: &DepthOptions,
    (width, height): (usize, usize),
    fov_height: usize,
    notes: &mut Vec<String>,
) -> Result<(impl Fn(f64) -> Option<f64>, Intrinsics, String)> {
    let needs = |name: &str, what: &str| {
        Error::invalid(
            name,
            "nothing",
            format!("{what}: `depth_kind` zbuffer needs `near`, `far` and `fov`"),
        )
    };
    let near = opts.near.ok_or_else(|| needs("near", "the near plane"))?;
    let far = opts.far.ok_or_else(|| needs("far", "the far plane"))?;
    let fov = opts
        .fov
        .ok_or_else(|| needs("fov", "the vertical field of view (degrees)"))?;
    // The camera checks the near plane and the field of view (its own far plane stands
    // in); the camera names its field of view `fov_y_deg`, here the option `fov`.
    let camera = Camera {
        near,
        far: f64::MAX,
        fov_y_deg: fov,
        ..Camera::default()
    };
    camera
        .validate()
        .map_err(|e| e.rename_options(|f| (f == "fov_y_deg").then(|| "fov".into())))?;
    if far.is_nan() || far <= near {
        return Err(Error::invalid(
            "far",
            far,
            format!("a distance greater than near ({near}), or inf for an infinite far plane"),
        ));
    }
    let reversed = opts.reversed_z;
    let sky = if reversed { 0.0 } else { 1.0 };
    notes.push(format!(
        "{} z-buffer of a perspective projection, near {near} far {far}, vertical field of \
         view {fov}°; window depth {sky} (nothing drawn) is unknown",
        if reversed { "reversed-Z" } else { "standard" },
    ));
    // The range is in the units of the near and far planes.
    let (scale, units) = vouched_scale(opts, "near and far", FILE_UNITS, notes)?;
    let model = DepthModel::of_planes(near, far, reversed);
    let k = Intrinsics::centred(focal_from_fov(fov, fov_height), width, height);
    let depth = move |d: f64| {
        let drawn = d.is_finite() && (0.0..=1.0).contains(&d) && d != sky;
        drawn.then(|| model.eye_depth(d) * scale)
    };
    Ok((depth, k, units))
}

/// The intrinsics a file holds beside its map (`held`, with the note saying so), for depth
/// along the optical axis; `focal` or `fov` given wins over them, with a note naming
/// their `source`; without them, [`depth_intrinsics`].
fn held_or_given(
    held: Option<(Intrinsics, String)>,
    source: &str,
    kind: DepthKind,
    opts: &DepthOptions,
    size: (usize, usize),
    fov_height: usize,
    notes: &mut Vec<String>,
) -> Result<Option<Intrinsics>> {
    let given = opts.focal.is_some() || opts.fov.is_some();
    match held {
        Some((k, said)) if !given && kind == DepthKind::Depth => {
            notes.push(said);
            Ok(Some(k))
        }
        Some(_) if given => {
            notes.push(format!(
                "`focal` or `fov` given: used instead of the {source}"
            ));
            depth_intrinsics(kind, opts, size, fov_height, notes)
        }
        _ => depth_intrinsics(kind, opts, size, fov_height, notes),
    }
}

/// The focal length in pixels of a vertical field of view over `height` pixels.
fn focal_from_fov(fov_deg: f64, height: usize) -> f64 {
    height as f64 / 2.0 / (fov_deg.to_radians() / 2.0).tan()
}

/// Intrinsics for a depth map without calibration: from `focal` or `fov` where given, else
/// from the photo's EXIF 35 mm equivalent focal length
/// ([`crate::io::image::PhotoExif::focal_35mm`]).
fn depth_intrinsics(
    kind: DepthKind,
    opts: &DepthOptions,
    (width, height): (usize, usize),
    fov_height: usize,
    notes: &mut Vec<String>,
) -> Result<Option<Intrinsics>> {
    let from_fov = match opts.fov {
        Some(fov) if opts.focal.is_none() => {
            if !(fov.is_finite() && fov > 0.0 && fov < 180.0) {
                return Err(Error::invalid(
                    "fov",
                    fov,
                    "a vertical field of view strictly between 0 and 180 degrees",
                ));
            }
            Some(focal_from_fov(fov, fov_height))
        }
        _ => None,
    };
    let given = opts.focal.or(from_fov);
    let from_exif = opts.photo.and_then(|p| p.exif.focal_35mm);
    match (kind, given, from_exif) {
        (DepthKind::Range, Some(_), _) => {
            // `fov` may still serve the camera (aerial perspective): only `focal`, which
            // has no other use here, is ignored.
            notes.push(if opts.focal.is_some() {
                "`focal` ignored: the map already holds range".to_string()
            } else {
                "the map already holds range: `fov` not needed to convert it".to_string()
            });
            Ok(None)
        }
        (DepthKind::Range, None, _) => Ok(None),
        (_, None, Some(f35)) => {
            let k = Intrinsics::of_35mm_equivalent(f35, width, height);
            let f = k.fy;
            notes.push(format!(
                "focal length from the photo's EXIF: {f35} mm in 35 mm terms (the diagonal's \
                 angle), {f:.2} px on the map's grid, a vertical field of view of {:.1}° \
                 upright; principal point assumed at the image centre",
                2.0 * (fov_height as f64 / 2.0 / f).atan().to_degrees()
            ));
            Ok(Some(k))
        }
        (_, Some(f), _) => {
            let f = positive_option(f, "focal", "a positive focal length in pixels")?;
            notes.push("principal point assumed at the image centre".to_string());
            Ok(Some(Intrinsics::centred(f, width, height)))
        }
        (_, None, None) => {
            notes.push("no intrinsics: depth used as range".to_string());
            Ok(None)
        }
    }
}
