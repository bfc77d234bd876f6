//! Depth, range and disparity maps in the formats users bring, turned into one thing: a
//! range map (distance from the camera centre to the surface seen at each pixel) with NaN
//! where the distance is unknown.
//!
//! Units: every conversion that knows the physical scale returns metres. Baselines are
//! taken in millimetres everywhere (the Middlebury convention), so disparity-based ranges
//! are computed in millimetres and divided by 1000. Float depth or range maps keep the
//! units of the file. For haze only relative range matters, so a wrong absolute scale
//! changes the look only through the haze density the user picks.

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use crate::io::camera::{to_range, Stereo};
use crate::io::codec::png::{self, GreyPng};
use crate::io::codec::{exr::parse_exr_scalar, npy::parse_npy_scalar, tiff::parse_tiff_scalar};
use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

// The file readers live with their writers in `io::codec`; they stay reachable here, where
// callers loading depth have always found them.
pub use crate::io::codec::exr::read_exr_scalar;
pub use crate::io::codec::npy::read_npy_scalar;
pub use crate::io::codec::pfm::{parse_pfm, read_pfm, Pfm};
pub use crate::io::codec::tiff::read_tiff_scalar;

pub use crate::io::camera::Intrinsics;

/// Focal length in pixels assumed for Middlebury 2006 full-size images when `--focal` is
/// not given. Approximate, quoted from memory of the dataset page, not read from a file.
pub const MIDDLEBURY2006_FOCAL_PX: f64 = 3740.0;
/// Baseline in millimetres assumed for Middlebury 2006 when `--baseline` is not given.
/// Approximate, from memory, not from a file.
pub const MIDDLEBURY2006_BASELINE_MM: f64 = 160.0;
/// Disparity offset in pixels (the scene's `dmin`) assumed for Middlebury 2006 when
/// `--disparity-offset` is not given. Each scene has its own; this is a typical value from
/// memory, not from a file. Only relative range matters for haze.
pub const MIDDLEBURY2006_DISPARITY_OFFSET_PX: f64 = 270.0;

/// What the values of a map measure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthKind {
    /// Distance along the optical axis (the z coordinate in camera space).
    Depth,
    /// Distance from the camera centre to the surface (what haze needs).
    Range,
    /// Stereo disparity in pixels; depth = focal * baseline / (disparity + offset).
    Disparity,
}

impl DepthKind {
    const NAMES: &'static str = "depth, range or disparity";
}

impl FromStr for DepthKind {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "depth" => Ok(DepthKind::Depth),
            "range" => Ok(DepthKind::Range),
            "disparity" => Ok(DepthKind::Disparity),
            _ => Err(Error::invalid("--depth-kind", s, DepthKind::NAMES)),
        }
    }
}

impl fmt::Display for DepthKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DepthKind::Depth => "depth",
            DepthKind::Range => "range",
            DepthKind::Disparity => "disparity",
        })
    }
}

/// How a depth file is laid out and scaled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthFormat {
    /// Guess from the extension, bit depth and the presence of a calibration file.
    Auto,
    /// Middlebury 2014: `disp0.pfm` disparity plus `calib.txt`.
    Middlebury2014,
    /// Middlebury 2005/2006: 8-bit disparity PNG, `0` unknown, no calibration file.
    Middlebury2006,
    /// KITTI depth: 16-bit PNG, metres = value / 256, `0` unknown.
    Kitti,
    /// NYU Depth v2: 16-bit PNG in millimetres, `0` unknown.
    Nyu,
    /// TUM RGB-D: 16-bit PNG, metres = value / 5000, `0` unknown.
    Tum,
    /// Any 16-bit PNG, metres = value * `--depth-scale`, `0` unknown.
    Png16,
    /// Float map (`.exr`, float `.tif`, `.npy`, `.pfm` without calibration); NaN, infinite
    /// or non-positive values are unknown.
    Float,
}

impl DepthFormat {
    const NAMES: &'static str =
        "one of auto, middlebury2014, middlebury2006, kitti, nyu, tum, png16, float";
}

impl FromStr for DepthFormat {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(DepthFormat::Auto),
            "middlebury2014" => Ok(DepthFormat::Middlebury2014),
            "middlebury2006" => Ok(DepthFormat::Middlebury2006),
            "kitti" => Ok(DepthFormat::Kitti),
            "nyu" => Ok(DepthFormat::Nyu),
            "tum" => Ok(DepthFormat::Tum),
            "png16" => Ok(DepthFormat::Png16),
            "float" => Ok(DepthFormat::Float),
            _ => Err(Error::invalid("--depth-format", s, DepthFormat::NAMES)),
        }
    }
}

impl fmt::Display for DepthFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DepthFormat::Auto => "auto",
            DepthFormat::Middlebury2014 => "middlebury2014",
            DepthFormat::Middlebury2006 => "middlebury2006",
            DepthFormat::Kitti => "kitti",
            DepthFormat::Nyu => "nyu",
            DepthFormat::Tum => "tum",
            DepthFormat::Png16 => "png16",
            DepthFormat::Float => "float",
        })
    }
}

/// How to read a depth file. `Default` guesses everything.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthOptions {
    /// Layout and scale of the file; `Auto` guesses.
    pub format: DepthFormat,
    /// What the values measure; `None` takes the format's usual kind.
    pub kind: Option<DepthKind>,
    /// Middlebury 2014 `calib.txt`; `None` looks for `calib.txt` next to a `.pfm`.
    pub calib: Option<PathBuf>,
    /// Multiplier from raw 16-bit PNG values to metres (or to pixels of disparity).
    pub scale: Option<f64>,
    /// Focal length in pixels.
    pub focal: Option<f64>,
    /// Stereo baseline in millimetres.
    pub baseline: Option<f64>,
    /// Added to disparity before dividing (Middlebury `doffs`/`dmin`), in pixels.
    pub disparity_offset: Option<f64>,
}

impl Default for DepthOptions {
    fn default() -> Self {
        DepthOptions {
            format: DepthFormat::Auto,
            kind: None,
            calib: None,
            scale: None,
            focal: None,
            baseline: None,
            disparity_offset: None,
        }
    }
}

/// A range map and how it was obtained.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedDepth {
    /// Range per pixel, row 0 at the top; NaN where unknown.
    pub range: ScalarMap,
    /// The format actually used (never `Auto`).
    pub format: DepthFormat,
    /// What the file's values measured.
    pub kind: DepthKind,
    /// Units of `range`: `m`, or `file units` for float maps of depth or range.
    pub units: String,
    /// Intrinsics used to turn depth into range, if any.
    pub intrinsics: Option<Intrinsics>,
    /// Remarks for the user: assumptions made, options ignored.
    pub notes: Vec<String>,
    /// Number of NaN pixels in `range`.
    pub unknown_pixels: usize,
}

/// The content of a Middlebury 2014 `calib.txt`.
#[derive(Clone, Debug, PartialEq)]
pub struct Calib {
    /// Left camera matrix `[f 0 cx; 0 f cy; 0 0 1]`, row-major.
    pub cam0: [[f64; 3]; 3],
    /// Right camera matrix.
    pub cam1: [[f64; 3]; 3],
    /// Disparity offset `cx1 - cx0`, pixels.
    pub doffs: f64,
    /// Baseline, millimetres.
    pub baseline: f64,
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Conservative bound on the number of disparity levels.
    pub ndisp: u32,
    /// Whether the disparities are integers.
    pub isint: bool,
    /// Tight lower bound on the disparities.
    pub vmin: f64,
    /// Tight upper bound on the disparities.
    pub vmax: f64,
    /// Average vertical disparity (imperfect rectification), if given.
    pub dyavg: Option<f64>,
    /// Maximum vertical disparity, if given.
    pub dymax: Option<f64>,
}

impl Calib {
    /// The left camera's intrinsics, which `disp0.pfm` is aligned with.
    pub fn intrinsics(&self) -> Intrinsics {
        Intrinsics {
            fx: self.cam0[0][0],
            fy: self.cam0[1][1],
            cx: self.cam0[0][2],
            cy: self.cam0[1][2],
        }
    }
}

/// Reads and checks a Middlebury 2014 `calib.txt`.
pub fn parse_calib(path: &Path) -> Result<Calib> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_calib_str(&text, path)
}

/// Parses the text of a `calib.txt`; `path` names it in errors. Missing or non-numeric
/// keys are errors naming the key; unknown keys are ignored.
pub fn parse_calib_str(text: &str, path: &Path) -> Result<Calib> {
    let mut pairs: Vec<(&str, &str)> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            return Err(Error::format(
                path,
                format!("line {}: `{line}` is not `key=value`", n + 1),
            ));
        };
        pairs.push((key.trim(), value.trim()));
    }
    let lookup = |key: &str| pairs.iter().rev().find(|(k, _)| *k == key).map(|p| p.1);
    let required = |key: &str| {
        lookup(key).ok_or_else(|| {
            Error::format(
                path,
                format!("missing key `{key}`; a Middlebury 2014 calib.txt has it"),
            )
        })
    };
    let number = |key: &str| parse_number(required(key)?, key, path);
    let integer = |key: &str| -> Result<u64> {
        let v = required(key)?;
        v.parse::<u64>().map_err(|_| {
            Error::format(
                path,
                format!("`{key}={v}`: expected a non-negative integer"),
            )
        })
    };
    let optional = |key: &str| lookup(key).map(|v| parse_number(v, key, path)).transpose();

    let calib = Calib {
        cam0: parse_matrix(required("cam0")?, "cam0", path)?,
        cam1: parse_matrix(required("cam1")?, "cam1", path)?,
        doffs: number("doffs")?,
        baseline: number("baseline")?,
        width: integer("width")? as usize,
        height: integer("height")? as usize,
        ndisp: integer("ndisp")? as u32,
        isint: integer("isint")? != 0,
        vmin: number("vmin")?,
        vmax: number("vmax")?,
        dyavg: optional("dyavg")?,
        dymax: optional("dymax")?,
    };
    check_calib(&calib, path)?;
    Ok(calib)
}

fn check_calib(c: &Calib, path: &Path) -> Result<()> {
    let k = c.intrinsics();
    if k.fx <= 0.0 || k.fy <= 0.0 {
        return Err(Error::format(
            path,
            format!(
                "cam0 focal lengths are {} and {}; expected positive values",
                k.fx, k.fy
            ),
        ));
    }
    if c.baseline <= 0.0 {
        return Err(Error::format(
            path,
            format!("baseline={}; expected a positive length in mm", c.baseline),
        ));
    }
    if c.width == 0 || c.height == 0 {
        return Err(Error::format(
            path,
            format!(
                "width={} height={}; expected positive sizes",
                c.width, c.height
            ),
        ));
    }
    Ok(())
}

fn parse_number(value: &str, key: &str, path: &Path) -> Result<f64> {
    match value.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(Error::format(
            path,
            format!("`{key}={value}`: expected a finite number"),
        )),
    }
}

fn parse_matrix(value: &str, key: &str, path: &Path) -> Result<[[f64; 3]; 3]> {
    let bad = || {
        Error::format(
            path,
            format!("`{key}={value}`: expected a 3x3 matrix like `[f 0 cx; 0 f cy; 0 0 1]`"),
        )
    };
    let inner = value
        .strip_prefix('[')
        .and_then(|v| v.strip_suffix(']'))
        .ok_or_else(bad)?;
    let rows: Vec<&str> = inner.split(';').collect();
    if rows.len() != 3 {
        return Err(bad());
    }
    let mut m = [[0.0; 3]; 3];
    for (r, row) in rows.iter().enumerate() {
        let cells: Vec<&str> = row.split_whitespace().collect();
        if cells.len() != 3 {
            return Err(bad());
        }
        for (c, cell) in cells.iter().enumerate() {
            m[r][c] = cell
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(bad)?;
        }
    }
    Ok(m)
}

/// A depth file decoded but not yet interpreted.
enum Raw {
    Grey8(Grid<u8>),
    Grey16(Grid<u16>),
    Float { map: ScalarMap, from_pfm: bool },
}

impl Raw {
    fn describe(&self) -> &'static str {
        match self {
            Raw::Grey8(_) => "an 8-bit PNG",
            Raw::Grey16(_) => "a 16-bit PNG",
            Raw::Float { from_pfm: true, .. } => "a float PFM",
            Raw::Float { .. } => "a float map",
        }
    }

    fn size(&self) -> (usize, usize) {
        match self {
            Raw::Grey8(g) => (g.width(), g.height()),
            Raw::Grey16(g) => (g.width(), g.height()),
            Raw::Float { map, .. } => (map.width(), map.height()),
        }
    }
}

/// Loads a depth, range or disparity file and returns a range map with NaN for unknown
/// pixels. See [`DepthFormat`] for the layouts and [`DepthOptions`] for the knobs.
pub fn load_range(path: &Path, opts: &DepthOptions) -> Result<LoadedDepth> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let mut notes = Vec::new();
    let ext = extension_of(path);
    let calib = find_calib(path, &ext, opts, &mut notes)?;
    let raw = decode_raw(&bytes, path, &ext)?;
    interpret(raw, path, opts, calib, notes, 1.0)
}

/// Decodes embedded depth bytes as if read from a file with extension `ext`. `pixel_scale`
/// is how many full-size pixels one pixel of this map spans: a Middlebury 2006 map
/// downsampled by 2 keeps full-size disparities but its pixels see twice the angle.
pub(crate) fn range_from_bytes(
    bytes: &[u8],
    name: &Path,
    ext: &str,
    opts: &DepthOptions,
    pixel_scale: f64,
) -> Result<LoadedDepth> {
    let raw = decode_raw(bytes, name, ext)?;
    interpret(raw, name, opts, None, Vec::new(), pixel_scale)
}

fn extension_of(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

fn find_calib(
    path: &Path,
    ext: &str,
    opts: &DepthOptions,
    notes: &mut Vec<String>,
) -> Result<Option<(Calib, PathBuf)>> {
    let wants_calib =
        matches!(opts.format, DepthFormat::Auto | DepthFormat::Middlebury2014) && ext == "pfm";
    if let Some(given) = &opts.calib {
        if !wants_calib {
            notes.push(format!(
                "--calib {} ignored: only Middlebury 2014 .pfm disparities use it",
                given.display()
            ));
            return Ok(None);
        }
        return Ok(Some((parse_calib(given)?, given.clone())));
    }
    if !wants_calib {
        return Ok(None);
    }
    let beside = path.with_file_name("calib.txt");
    if !beside.is_file() {
        return Ok(None);
    }
    let calib = parse_calib(&beside)?;
    notes.push(format!("calibration read from {}", beside.display()));
    Ok(Some((calib, beside)))
}

fn decode_raw(bytes: &[u8], path: &Path, ext: &str) -> Result<Raw> {
    match ext {
        "png" => Ok(match png::decode_grey(bytes, path)? {
            GreyPng::Grey8(g) => Raw::Grey8(g),
            GreyPng::Grey16(g) => Raw::Grey16(g),
        }),
        "pfm" => match parse_pfm(bytes, path)? {
            Pfm::Grey(map) => Ok(Raw::Float {
                map,
                from_pfm: true,
            }),
            Pfm::Rgb(_) => Err(Error::format(
                path,
                "PFM is `PF` (3 colour channels); a depth or disparity PFM must be `Pf` (1 channel)",
            )),
        },
        "exr" => Ok(float(parse_exr_scalar(bytes, path)?)),
        "tif" | "tiff" => Ok(float(parse_tiff_scalar(bytes, path)?)),
        "npy" => Ok(float(parse_npy_scalar(bytes, path)?)),
        "jpg" | "jpeg" => Err(Error::format(
            path,
            "JPEG is lossy and cannot hold depth; expected .png, .pfm, .exr, .tif, .tiff or .npy",
        )),
        _ => Err(Error::format(
            path,
            format!(
                "unknown depth file extension `{ext}`; expected .png, .pfm, .exr, .tif, .tiff or .npy"
            ),
        )),
    }
}

fn float(map: ScalarMap) -> Raw {
    Raw::Float {
        map,
        from_pfm: false,
    }
}

fn resolve_format(
    requested: DepthFormat,
    raw: &Raw,
    has_calib: bool,
    opts: &DepthOptions,
    path: &Path,
) -> Result<DepthFormat> {
    use DepthFormat as F;
    let format = match (requested, raw) {
        (F::Auto, Raw::Float { from_pfm: true, .. }) if has_calib => F::Middlebury2014,
        (F::Auto, Raw::Float { .. }) => F::Float,
        (F::Auto, Raw::Grey8(_)) => F::Middlebury2006,
        (F::Auto, Raw::Grey16(_)) if opts.scale.is_some() => F::Png16,
        (F::Auto, Raw::Grey16(_)) => {
            return Err(Error::format(
                path,
                "16-bit PNG depth has no standard scale: pass --depth-format kitti|nyu|tum, \
                 or --depth-scale with the metres per unit",
            ))
        }
        (f, _) => f,
    };
    let fits = match format {
        F::Middlebury2014 => matches!(raw, Raw::Float { from_pfm: true, .. }),
        F::Middlebury2006 => matches!(raw, Raw::Grey8(_)),
        F::Kitti | F::Nyu | F::Tum | F::Png16 => matches!(raw, Raw::Grey16(_)),
        F::Float => matches!(raw, Raw::Float { .. }),
        F::Auto => unreachable!("Auto resolved above"),
    };
    if !fits {
        let expected = match format {
            F::Middlebury2014 => "a `Pf` PFM disparity (disp0.pfm)",
            F::Middlebury2006 => "an 8-bit grey PNG disparity",
            F::Float => "a float map (.pfm, .exr, .tif, .tiff or .npy)",
            _ => "a 16-bit grey PNG",
        };
        return Err(Error::format(
            path,
            format!(
                "--depth-format {format} expects {expected}, found {}",
                raw.describe()
            ),
        ));
    }
    if format == F::Middlebury2014 && !has_calib {
        return Err(Error::format(
            path,
            "Middlebury 2014 disparity needs its calib.txt: none next to the file; pass --calib",
        ));
    }
    Ok(format)
}

fn resolve_kind(format: DepthFormat, requested: Option<DepthKind>) -> Result<DepthKind> {
    use DepthFormat as F;
    use DepthKind as K;
    let default = match format {
        F::Middlebury2014 | F::Middlebury2006 => K::Disparity,
        _ => K::Depth,
    };
    let kind = requested.unwrap_or(default);
    let allowed = match format {
        F::Middlebury2014 | F::Middlebury2006 => kind == K::Disparity,
        F::Kitti | F::Nyu | F::Tum => kind != K::Disparity,
        _ => true,
    };
    if !allowed {
        let expected = if default == K::Disparity {
            format!("disparity for --depth-format {format}")
        } else {
            format!("depth or range for --depth-format {format}")
        };
        return Err(Error::invalid("--depth-kind", kind, expected));
    }
    Ok(kind)
}

fn positive_option(value: f64, name: &str, what: &str) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Error::invalid(name, value, what))
    }
}

fn finite_option(value: f64, name: &str) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::invalid(name, value, "a finite number of pixels"))
    }
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
                format!("a value: --depth-format {format} with --depth-kind disparity needs --focal (px) and --baseline (mm)"),
            )
        };
        let focal = opts.focal.ok_or_else(|| missing("--focal"))?;
        let baseline = opts.baseline.ok_or_else(|| missing("--baseline"))?;
        Ok(Stereo {
            focal: positive_option(focal, "--focal", "a positive focal length in pixels")?,
            baseline_mm: positive_option(baseline, "--baseline", "a positive length in mm")?,
            offset: finite_option(opts.disparity_offset.unwrap_or(0.0), "--disparity-offset")?,
        })
    }
}

fn interpret(
    raw: Raw,
    path: &Path,
    opts: &DepthOptions,
    calib: Option<(Calib, PathBuf)>,
    mut notes: Vec<String>,
    pixel_scale: f64,
) -> Result<LoadedDepth> {
    let format = resolve_format(opts.format, &raw, calib.is_some(), opts, path)?;
    let kind = resolve_kind(format, opts.kind)?;
    let (width, height) = raw.size();
    let metres = "m".to_string();
    let (range, units, intrinsics) = match (format, raw) {
        (DepthFormat::Middlebury2014, Raw::Float { map, .. }) => {
            let (calib, calib_path) = calib.expect("checked by resolve_format");
            check_calib_size(&calib, &calib_path, &map, path)?;
            note_ignored_stereo_options(opts, &mut notes);
            let stereo = Stereo {
                focal: calib.cam0[0][0],
                baseline_mm: calib.baseline,
                offset: calib.doffs,
            };
            let k = calib.intrinsics();
            let range = to_range(&map, |d| stereo.depth_m(f64::from(d)), Some(&k));
            (range, metres, Some(k))
        }
        (DepthFormat::Middlebury2006, Raw::Grey8(disp)) => {
            let stereo = middlebury2006_stereo(opts, &disp, &mut notes)?;
            let k = Intrinsics::centred(stereo.focal / pixel_scale, width, height);
            notes.push("principal point assumed at the image centre".to_string());
            let depth = |d: u8| (d != 0).then(|| stereo.depth_m(f64::from(d))).flatten();
            (to_range(&disp, depth, Some(&k)), metres, Some(k))
        }
        (DepthFormat::Png16, Raw::Grey16(raw)) if kind == DepthKind::Disparity => {
            let scale = png16_scale(opts)?;
            let stereo = Stereo::from_options(opts, format)?;
            let k = Intrinsics::centred(stereo.focal, width, height);
            notes.push("principal point assumed at the image centre".to_string());
            let depth = |v: u16| {
                (v != 0)
                    .then(|| stereo.depth_m(f64::from(v) * scale))
                    .flatten()
            };
            (to_range(&raw, depth, Some(&k)), metres, Some(k))
        }
        (_, Raw::Grey16(raw)) => {
            let scale = match format {
                DepthFormat::Kitti => 1.0 / 256.0,
                DepthFormat::Nyu => 1.0 / 1000.0,
                DepthFormat::Tum => 1.0 / 5000.0,
                _ => png16_scale(opts)?,
            };
            if format != DepthFormat::Png16 && opts.scale.is_some() {
                notes.push(format!("--depth-scale ignored: {format} has a fixed scale"));
            }
            let k = depth_intrinsics(kind, opts, width, height, &mut notes)?;
            let depth = |v: u16| (v != 0).then_some(f64::from(v) * scale);
            (to_range(&raw, depth, k.as_ref()), metres, k)
        }
        (_, Raw::Float { map, .. }) if kind == DepthKind::Disparity => {
            let stereo = Stereo::from_options(opts, format)?;
            let k = Intrinsics::centred(stereo.focal, width, height);
            notes.push("principal point assumed at the image centre".to_string());
            let range = to_range(&map, |d| stereo.depth_m(f64::from(d)), Some(&k));
            (range, metres, Some(k))
        }
        (_, Raw::Float { map, .. }) => {
            let k = depth_intrinsics(kind, opts, width, height, &mut notes)?;
            let range = to_range(&map, |v| Some(f64::from(v)), k.as_ref());
            (range, "file units".to_string(), k)
        }
        (_, Raw::Grey8(_)) => unreachable!("resolve_format sends 8-bit PNGs to Middlebury 2006"),
    };
    let unknown_pixels = range.as_slice().iter().filter(|v| v.is_nan()).count();
    if unknown_pixels == range.len() {
        return Err(Error::NoValidDepth {
            path: path.to_path_buf(),
        });
    }
    Ok(LoadedDepth {
        range,
        format,
        kind,
        units,
        intrinsics,
        notes,
        unknown_pixels,
    })
}

fn check_calib_size(calib: &Calib, calib_path: &Path, map: &ScalarMap, path: &Path) -> Result<()> {
    if (calib.width, calib.height) == (map.width(), map.height()) {
        return Ok(());
    }
    Err(Error::SizeMismatch {
        a: format!("{} (width=, height=)", calib_path.display()),
        aw: calib.width as u32,
        ah: calib.height as u32,
        b: path.display().to_string(),
        bw: map.width() as u32,
        bh: map.height() as u32,
    })
}

fn note_ignored_stereo_options(opts: &DepthOptions, notes: &mut Vec<String>) {
    if opts.focal.is_some() || opts.baseline.is_some() || opts.disparity_offset.is_some() {
        notes.push(
            "--focal, --baseline and --disparity-offset ignored: calib.txt gives them".to_string(),
        );
    }
}

fn middlebury2006_stereo(
    opts: &DepthOptions,
    disp: &Grid<u8>,
    notes: &mut Vec<String>,
) -> Result<Stereo> {
    let focal = opts.focal.unwrap_or(MIDDLEBURY2006_FOCAL_PX);
    let baseline = opts.baseline.unwrap_or(MIDDLEBURY2006_BASELINE_MM);
    let offset = opts
        .disparity_offset
        .unwrap_or(MIDDLEBURY2006_DISPARITY_OFFSET_PX);
    if opts.focal.is_none() || opts.baseline.is_none() || opts.disparity_offset.is_none() {
        notes.push(format!(
            "Middlebury 2006 geometry: focal {focal} px, baseline {baseline} mm, disparity \
             offset {offset} px (defaults are approximate full-size values; only relative \
             range matters for haze)"
        ));
    }
    let stereo = Stereo {
        focal: positive_option(focal, "--focal", "a positive focal length in pixels")?,
        baseline_mm: positive_option(baseline, "--baseline", "a positive length in mm")?,
        offset: finite_option(offset, "--disparity-offset")?,
    };
    if let Some(&smallest) = disp.as_slice().iter().filter(|&&d| d != 0).min() {
        if f64::from(smallest) + stereo.offset <= 0.0 {
            return Err(Error::invalid(
                "--disparity-offset",
                offset,
                format!("a value above -{smallest} (the smallest known disparity) so that disparity + offset > 0"),
            ));
        }
    }
    Ok(stereo)
}

fn png16_scale(opts: &DepthOptions) -> Result<f64> {
    let scale = opts.scale.ok_or_else(|| {
        Error::invalid(
            "--depth-scale",
            "nothing",
            "a positive multiplier for --depth-format png16 (e.g. 0.001 for millimetres)",
        )
    })?;
    positive_option(scale, "--depth-scale", "a positive finite multiplier")
}

/// Intrinsics for a depth map without calibration: only if `--focal` is given.
fn depth_intrinsics(
    kind: DepthKind,
    opts: &DepthOptions,
    width: usize,
    height: usize,
    notes: &mut Vec<String>,
) -> Result<Option<Intrinsics>> {
    match (kind, opts.focal) {
        (DepthKind::Range, Some(_)) => {
            notes.push("--focal ignored: the map already holds range".to_string());
            Ok(None)
        }
        (DepthKind::Range, None) => Ok(None),
        (_, Some(f)) => {
            let f = positive_option(f, "--focal", "a positive focal length in pixels")?;
            notes.push("principal point assumed at the image centre".to_string());
            Ok(Some(Intrinsics::centred(f, width, height)))
        }
        (_, None) => {
            notes.push("no intrinsics: depth used as range".to_string());
            Ok(None)
        }
    }
}
