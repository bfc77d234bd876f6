//! Middlebury stereo datasets. 2014: `disp0.pfm` float disparity with a `calib.txt`
//! beside it giving the cameras, baseline and disparity offset. 2005/2006: 8-bit
//! disparity PNGs with no calibration file, for which approximate defaults stand in.

use std::path::{Path, PathBuf};

use super::{finite_option, positive_option, DepthFormat, DepthOptions, StereoView};
use crate::io::camera::{to_range, Intrinsics, Stereo};
use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

/// Focal length in pixels assumed for Middlebury 2006 full-size images when
/// `DepthOptions::focal` is `None`. Approximate, quoted from memory of the dataset page,
/// not read from a file.
pub const MIDDLEBURY2006_FOCAL_PX: f64 = 3740.0;
/// Baseline in millimetres assumed for Middlebury 2006 when `DepthOptions::baseline` is
/// `None`. Approximate, from memory, not from a file.
pub const MIDDLEBURY2006_BASELINE_MM: f64 = 160.0;
/// Disparity offset in pixels (the scene's `dmin`) assumed for Middlebury 2006 when
/// `DepthOptions::disparity_offset` is `None`. Each scene has its own; this is a typical
/// value from memory, not from a file. Only relative range matters for haze.
pub const MIDDLEBURY2006_DISPARITY_OFFSET_PX: f64 = 270.0;

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
        intrinsics_of(&self.cam0)
    }

    /// The right camera's intrinsics, which `disp1.pfm` is aligned with: its principal
    /// point is `doffs` pixels right of the left one's.
    pub fn right_intrinsics(&self) -> Intrinsics {
        intrinsics_of(&self.cam1)
    }
}

fn intrinsics_of(cam: &[[f64; 3]; 3]) -> Intrinsics {
    Intrinsics {
        fx: cam[0][0],
        fy: cam[1][1],
        cx: cam[0][2],
        cy: cam[1][2],
    }
}

/// Whether `path`, read as `format`, names a right view's disparity as the Middlebury
/// datasets name it: 2014's `disp1.pfm` (or `disp1GT.pfm`, an algorithm's
/// `disp1NAME.pfm`; not `disp0.pfm` nor `disp10.pfm`), 2005 and 2006's `disp5.png` (their
/// views are numbered 1 to 5 from left to right, and their left one is `disp1.png`).
pub(super) fn names_right_view(format: DepthFormat, path: &Path) -> bool {
    let prefix = match format {
        DepthFormat::Middlebury2014 => "disp1",
        DepthFormat::Middlebury2006 => "disp5",
        _ => return false,
    };
    let stem = path.file_stem().map(|s| s.to_string_lossy());
    stem.as_deref()
        .and_then(|s| s.strip_prefix(prefix))
        .is_some_and(|rest| !rest.starts_with(|c: char| c.is_ascii_digit()))
}

/// Reads and checks a Middlebury 2014 `calib.txt`.
pub fn parse_calib(path: &Path) -> Result<Calib> {
    let text = crate::io::limits::read_text(path)?;
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

/// `k`, the intrinsics of `cam` in the `calib.txt` at `path`, if its focal lengths are
/// positive.
fn check_focal(k: &Intrinsics, cam: &str, path: &Path) -> Result<Intrinsics> {
    if k.fx <= 0.0 || k.fy <= 0.0 {
        return Err(Error::format(
            path,
            format!(
                "{cam} focal lengths are {} and {}; expected positive values",
                k.fx, k.fy
            ),
        ));
    }
    Ok(*k)
}

fn check_calib(c: &Calib, path: &Path) -> Result<()> {
    check_focal(&c.intrinsics(), "cam0", path)?;
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

/// Whether a file with extension `ext` read with `opts` may be a Middlebury 2014 disparity,
/// the only kind that uses a `calib.txt`.
fn wants_calib(ext: &str, opts: &DepthOptions) -> bool {
    matches!(opts.format, DepthFormat::Auto | DepthFormat::Middlebury2014) && ext == "pfm"
}

/// The `calib.txt` to read for `path`: `DepthOptions::calib`, or else one beside the file; none for
/// formats that do not use one (an ignored `calib` is not read, so it need not exist).
pub(super) fn calib_file(path: &Path, ext: &str, opts: &DepthOptions) -> Option<PathBuf> {
    if !wants_calib(ext, opts) {
        return None;
    }
    if let Some(given) = &opts.calib {
        return Some(given.clone());
    }
    Some(path.with_file_name("calib.txt")).filter(|beside| beside.is_file())
}

/// Parses the `calib.txt` found by [`calib_file`] (its path and text) if this format uses
/// one, noting where it came from, or that `calib` was ignored.
pub(super) fn take_calib(
    ext: &str,
    opts: &DepthOptions,
    calib: Option<(&Path, &str)>,
    notes: &mut Vec<String>,
) -> Result<Option<(Calib, PathBuf)>> {
    if !wants_calib(ext, opts) {
        if let Some(given) = opts.calib.as_deref().or(calib.map(|c| c.0)) {
            notes.push(format!(
                "`calib` {} ignored: only Middlebury 2014 .pfm disparities use it",
                given.display()
            ));
        }
        return Ok(None);
    }
    let Some((calib_path, text)) = calib else {
        return Ok(None);
    };
    let parsed = parse_calib_str(text, calib_path)?;
    if opts.calib.as_deref() != Some(calib_path) {
        notes.push(format!("calibration read from {}", calib_path.display()));
    }
    Ok(Some((parsed, calib_path.to_path_buf())))
}

/// Range in metres from a Middlebury 2014 disparity map at `path`, of `view`: focal,
/// baseline, disparity offset and principal point all come from its `calib.txt`, the right
/// camera's `cam1` for a right view's map; with the stereo pair's f·B (px·m) for its
/// occlusions.
pub(super) fn range_2014(
    map: &ScalarMap,
    (path, view): (&Path, StereoView),
    calib: &Calib,
    calib_path: &Path,
    opts: &DepthOptions,
    notes: &mut Vec<String>,
) -> Result<(ScalarMap, Intrinsics, f64)> {
    check_calib_size(calib, calib_path, map, path)?;
    note_ignored_stereo_options(opts, notes);
    let k = if view == StereoView::Right {
        notes.push("the right view's disparity: cam1's intrinsics".to_string());
        check_focal(&calib.right_intrinsics(), "cam1", calib_path)?
    } else {
        calib.intrinsics()
    };
    let stereo = Stereo {
        focal: k.fx,
        baseline_mm: calib.baseline,
        offset: calib.doffs,
    };
    check_doffs(map, calib, calib_path, path, notes)?;
    let range = to_range(map, |d| stereo.depth_m(f64::from(d)), Some(&k));
    Ok((range, k, stereo.focal_baseline()))
}

/// Z = baseline·f/(d + doffs) needs d + doffs > 0. When calib.txt's doffs makes that
/// fail for every known disparity, the fault is calib.txt's, and the error says so
/// (instead of "no valid depth" about the disparity file); when it fails for some, a note.
fn check_doffs(
    map: &ScalarMap,
    calib: &Calib,
    calib_path: &Path,
    path: &Path,
    notes: &mut Vec<String>,
) -> Result<()> {
    let known: Vec<f64> = map
        .as_slice()
        .iter()
        .filter(|d| d.is_finite())
        .map(|&d| f64::from(d))
        .collect();
    let behind = known.iter().filter(|&&d| d + calib.doffs <= 0.0).count();
    if behind == 0 {
        return Ok(());
    }
    let largest = known.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if behind == known.len() {
        return Err(Error::format(
            calib_path,
            format!(
                "doffs = {} makes every disparity of {} (the largest is {largest}) give no \
                 positive depth, Z = baseline·f/(d + doffs): doffs is the x-offset of the \
                 principal points (cx1 − cx0), ≥ 0 in Middlebury's calibrations",
                calib.doffs,
                path.display()
            ),
        ));
    }
    notes.push(format!(
        "{behind} disparities d ≤ −doffs = {} give no positive depth: taken as unknown",
        -calib.doffs
    ));
    Ok(())
}

/// Range in metres from a Middlebury 2006 8-bit disparity map (`0` unknown). The options
/// or the 2006 defaults give the geometry; `pixel_scale` is how many full-size pixels one
/// pixel of this map spans.
pub(super) fn range_2006(
    disp: &Grid<u8>,
    opts: &DepthOptions,
    pixel_scale: f64,
    notes: &mut Vec<String>,
) -> Result<(ScalarMap, Intrinsics, f64)> {
    let (width, height) = (disp.width(), disp.height());
    let stereo = middlebury2006_stereo(opts, disp, notes)?;
    let k = Intrinsics::centred(stereo.focal / pixel_scale, width, height);
    notes.push("principal point assumed at the image centre".to_string());
    let depth = |d: u8| (d != 0).then(|| stereo.depth_m(f64::from(d))).flatten();
    Ok((to_range(disp, depth, Some(&k)), k, stereo.focal_baseline()))
}

fn check_calib_size(calib: &Calib, calib_path: &Path, map: &ScalarMap, path: &Path) -> Result<()> {
    if (calib.width, calib.height) == (map.width(), map.height()) {
        return Ok(());
    }
    Err(Error::size_mismatch(
        format!("{} (width=, height=)", calib_path.display()),
        (calib.width, calib.height),
        path.display(),
        (map.width(), map.height()),
    ))
}

fn note_ignored_stereo_options(opts: &DepthOptions, notes: &mut Vec<String>) {
    if opts.focal.is_some() || opts.baseline.is_some() || opts.disparity_offset.is_some() {
        notes.push(
            "`focal`, `baseline` and `disparity_offset` ignored: calib.txt gives them".to_string(),
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
        focal: positive_option(focal, "focal", "a positive focal length in pixels")?,
        baseline_mm: positive_option(baseline, "baseline", "a positive length in mm")?,
        offset: finite_option(offset, "disparity_offset")?,
    };
    if let Some(&smallest) = disp.as_slice().iter().filter(|&&d| d != 0).min() {
        if f64::from(smallest) + stereo.offset <= 0.0 {
            return Err(Error::invalid(
                "disparity_offset",
                offset,
                format!("a value above -{smallest} (the smallest known disparity) so that disparity + offset > 0"),
            ));
        }
    }
    Ok(stereo)
}
