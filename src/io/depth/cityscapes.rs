//! Cityscapes: `{name}_disparity.png` with its `{name}_camera.json`.
//!
//! What the dataset's README says: the disparity maps are 16-bit grey PNGs in which a
//! pixel value p > 0 stands for the disparity d = (p − 1)/256 px and p = 0 is invalid; the
//! camera file gives the stereo baseline in metres (`extrinsic.baseline`) and the left
//! camera's intrinsics in pixels (`intrinsic.fx`, `fy`, `u0`, `v0`), so that the depth is
//! Z = baseline·fx/d metres. brume then stretches depth to range along each pixel's ray
//! with those intrinsics ([`crate::io::camera`]). A disparity d ≤ 0 (p = 1) gives no
//! depth and is unknown, like p = 0.
//!
//! The camera file is found, when not given, beside the disparity (`{name}_camera.json`)
//! or in the dataset's own layout, where the `disparity` folder of
//! `disparity/{split}/{city}/{name}_disparity.png` becomes `camera`.

use std::path::{Component, Path, PathBuf};

use serde_json::Value;

use super::{DepthFormat, DepthOptions};
use crate::io::camera::{to_range, Intrinsics, Mount, MOUNT_HEIGHT_RANGE_M, MOUNT_TILT_RANGE_RAD};
use crate::io::limits::MAX_SIDE;
use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

/// The suffix of a Cityscapes disparity file's name.
const DISPARITY_SUFFIX: &str = "_disparity";
/// The suffix of a Cityscapes camera file's name.
const CAMERA_SUFFIX: &str = "_camera.json";
/// The shape of a camera file, for messages.
const EXPECTED: &str = "a Cityscapes camera file {\"extrinsic\": {\"baseline\": METRES, …}, \
                        \"intrinsic\": {\"fx\": PX, \"fy\": PX, \"u0\": PX, \"v0\": PX}}";

/// The stereo baselines accepted, in metres (`extrinsic.baseline`): 1 mm (a phone's
/// dual camera is about 10 mm) to 1 km. Cityscapes' rig has 0.21 m, KITTI's 0.54 m.
pub const BASELINE_RANGE_M: (f64, f64) = (1e-3, 1e3);

/// The focal lengths accepted, in pixels (`intrinsic.fx`, `fy`): 1 px to 10⁶ px (a field
/// of view under 1° across the widest image brume reads, 16384 px). Cityscapes has about
/// 2262 px.
pub const FOCAL_RANGE_PX: (f64, f64) = (1.0, 1e6);

/// The principal points accepted, in pixels (`intrinsic.u0`, `v0`): within one largest
/// image ([`MAX_SIDE`] pixels) of the largest image, −16384 to 32768. A crop's principal
/// point may lie outside it; 10¹² is no camera's.
pub const PRINCIPAL_POINT_RANGE_PX: (f64, f64) = (-(MAX_SIDE as f64), 2.0 * MAX_SIDE as f64);

/// The camera heights above the ground accepted, in metres (`extrinsic.z`): 1 cm to 10 km.
/// Cityscapes' car has 1.18 to 1.22 m.
pub const HEIGHT_RANGE_M: (f64, f64) = MOUNT_HEIGHT_RANGE_M;

/// The pitches and rolls accepted, in radians (`extrinsic.pitch`, `roll`): a quarter turn
/// either way. Cityscapes' are 0.038 to 0.05 (pitch) and 0 (roll).
pub const TILT_RANGE_RAD: (f64, f64) = MOUNT_TILT_RANGE_RAD;

/// What brume reads from a Cityscapes `{name}_camera.json`. [`parse_camera_str`] accepts
/// only values within [`BASELINE_RANGE_M`], [`FOCAL_RANGE_PX`] and
/// [`PRINCIPAL_POINT_RANGE_PX`], so that depth baseline·fx/d and the ray stretch stay
/// finite and meaningful for every disparity a PNG can store.
#[derive(Clone, Debug, PartialEq)]
pub struct CityscapesCamera {
    /// Stereo baseline in metres (`extrinsic.baseline`), within [`BASELINE_RANGE_M`].
    pub baseline_m: f64,
    /// The left camera's intrinsics in pixels (`intrinsic.fx`, `fy` within
    /// [`FOCAL_RANGE_PX`]; `u0`, `v0` within [`PRINCIPAL_POINT_RANGE_PX`]).
    pub intrinsics: Intrinsics,
    /// How the left camera is mounted over the road (`extrinsic.z`, `pitch` and `roll`,
    /// the last 0 when absent), when the file gives its height and pitch: the level
    /// ground's range along each ray bounds what a stereo matcher may measure below the
    /// horizon ([`crate::prep::PrepOptions::ground`]).
    pub mount: Option<Mount>,
    /// Why the mount the file gives is not used (a value out of its range or not a
    /// number): the rest of the file is read all the same, as before brume read it.
    pub mount_note: Option<String>,
}

impl CityscapesCamera {
    /// Depth in metres of disparity `d` px: baseline·fx/d, `None` for d ≤ 0.
    pub fn depth_m(&self, d: f64) -> Option<f64> {
        (d > 0.0).then(|| self.baseline_m * self.intrinsics.fx / d)
    }
}

/// The disparity in pixels of a stored value: (p − 1)/256; `None` for p = 0 (invalid) and
/// p = 1 (d = 0, no depth).
pub fn disparity_px(p: u16) -> Option<f64> {
    (p > 1).then(|| (f64::from(p) - 1.0) / 256.0)
}

/// Reads and checks a Cityscapes camera file.
pub fn parse_camera(path: &Path) -> Result<CityscapesCamera> {
    let text = crate::io::limits::read_text(path)?;
    parse_camera_str(&text, path)
}

/// Parses the text of a Cityscapes camera file; `path` names it in errors. Keys brume does
/// not use (yaw, the position along and across the car …) are ignored. A value outside its
/// range ([`BASELINE_RANGE_M`], [`FOCAL_RANGE_PX`], [`PRINCIPAL_POINT_RANGE_PX`]) is an
/// error naming the file, the key, the value and the range; a mount's
/// ([`HEIGHT_RANGE_M`], [`TILT_RANGE_RAD`]) leaves the mount out and says so in
/// [`CityscapesCamera::mount_note`].
pub fn parse_camera_str(text: &str, path: &Path) -> Result<CityscapesCamera> {
    let json: Value = serde_json::from_str(text)
        .map_err(|e| Error::format(path, format!("not JSON ({e}): expected {EXPECTED}")))?;
    let baseline = ("a baseline in metres", "m", BASELINE_RANGE_M);
    let focal = ("a focal length in pixels", "px", FOCAL_RANGE_PX);
    let centre = (
        "a principal point in pixels",
        "px",
        PRINCIPAL_POINT_RANGE_PX,
    );
    let baseline_m = within(&json, path, "extrinsic", "baseline", baseline)?;
    let fx = within(&json, path, "intrinsic", "fx", focal)?;
    let fy = within(&json, path, "intrinsic", "fy", focal)?;
    let cx = within(&json, path, "intrinsic", "u0", centre)?;
    let cy = within(&json, path, "intrinsic", "v0", centre)?;
    let (mount, mount_note) = match parse_mount(&json, path) {
        Ok(mount) => (mount, None),
        Err(e) => (
            None,
            Some(format!("camera height and pitch not used ({e})")),
        ),
    };
    Ok(CityscapesCamera {
        baseline_m,
        intrinsics: Intrinsics { fx, fy, cx, cy },
        mount,
        mount_note,
    })
}

/// The camera's mount over the road, when the file gives `extrinsic.z` and `pitch`; a
/// value given out of its range is an error, which the caller turns into a note.
fn parse_mount(json: &Value, path: &Path) -> Result<Option<Mount>> {
    let given = |key: &str| json.get("extrinsic").and_then(|g| g.get(key)).is_some();
    if !(given("z") && given("pitch")) {
        return Ok(None);
    }
    let height = ("a height above the ground in metres", "m", HEIGHT_RANGE_M);
    let tilt = ("an angle in radians", "rad", TILT_RANGE_RAD);
    Ok(Some(Mount {
        height_m: within(json, path, "extrinsic", "z", height)?,
        pitch: within(json, path, "extrinsic", "pitch", tilt)?,
        roll: match given("roll") {
            true => within(json, path, "extrinsic", "roll", tilt)?,
            false => 0.0,
        },
    }))
}

/// `json[group][key]` as a finite number; the error names the key, the value found and
/// the file's expected shape.
fn number(json: &Value, path: &Path, group: &str, key: &str) -> Result<f64> {
    let Some(value) = json.get(group).and_then(|g| g.get(key)) else {
        return Err(Error::format(
            path,
            format!("missing {group}.{key}: expected {EXPECTED}"),
        ));
    };
    value
        .as_f64()
        .filter(|v| v.is_finite())
        .ok_or_else(|| Error::format(path, format!("{group}.{key} = {value}: expected a number")))
}

/// [`number`], which must also lie in `range` (inclusive); `what` says what it is and
/// its unit, for the message. A value ≤ 0 where the range is positive says `> 0`.
fn within(
    json: &Value,
    path: &Path,
    group: &str,
    key: &str,
    (what, unit, (lo, hi)): (&str, &str, (f64, f64)),
) -> Result<f64> {
    let v = number(json, path, group, key)?;
    if (lo..=hi).contains(&v) {
        return Ok(v);
    }
    let positive = if lo > 0.0 && v <= 0.0 { ", > 0" } else { "" };
    Err(Error::format(
        path,
        format!(
            "{group}.{key} = {}: expected {what}{positive}, from {lo} to {hi} {unit}",
            short(v)
        ),
    ))
}

/// `v` as written in a message: 1e300 and 1e-300 in scientific notation rather than as 300
/// digits.
fn short(v: f64) -> String {
    if v != 0.0 && !(1e-4..1e7).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}

/// Where the camera file of disparity `path` may be, in the order they are tried: beside
/// it (`X_camera.json` for `X_disparity.png`), then in the Cityscapes layout (the last
/// folder called `disparity` on its path replaced by `camera`), when there is one.
pub fn camera_candidates(path: &Path) -> Vec<PathBuf> {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = format!(
        "{}{CAMERA_SUFFIX}",
        stem.strip_suffix(DISPARITY_SUFFIX).unwrap_or(&stem)
    );
    let mut candidates = vec![path.with_file_name(&name)];
    if let Some(folder) = path.parent().and_then(camera_folder) {
        candidates.push(folder.join(&name));
    }
    candidates
}

/// `folder` with its last component called `disparity` replaced by `camera`, if any.
fn camera_folder(folder: &Path) -> Option<PathBuf> {
    let parts: Vec<Component> = folder.components().collect();
    let last = parts.iter().rposition(|c| c.as_os_str() == "disparity")?;
    let mut out = PathBuf::new();
    for (i, part) in parts.iter().enumerate() {
        if i == last {
            out.push("camera");
        } else {
            out.push(part.as_os_str());
        }
    }
    Some(out)
}

/// Whether a file read with `opts` may be a Cityscapes disparity whose camera file is
/// looked for: `DepthFormat::Cityscapes`, or `auto` for a `*_disparity.png` (a plain
/// 16-bit PNG beside some JSON file is not taken for one).
fn wants_camera(path: &Path, ext: &str, opts: &DepthOptions) -> bool {
    let named = path
        .file_stem()
        .is_some_and(|s| s.to_string_lossy().ends_with(DISPARITY_SUFFIX));
    ext == "png"
        && match opts.format {
            DepthFormat::Cityscapes => true,
            DepthFormat::Auto => named || opts.camera.is_some(),
            _ => false,
        }
}

/// The camera file to read for `path`: [`DepthOptions::camera`], or else the first of
/// [`camera_candidates`] that exists. `Ok(None)` when this format uses none;
/// `DepthFormat::Cityscapes` with none found is an error naming every path tried.
pub(super) fn camera_file(path: &Path, ext: &str, opts: &DepthOptions) -> Result<Option<PathBuf>> {
    if !wants_camera(path, ext, opts) {
        return Ok(None);
    }
    if let Some(given) = &opts.camera {
        return Ok(Some(given.clone()));
    }
    let candidates = camera_candidates(path);
    if let Some(found) = candidates.iter().find(|c| c.is_file()) {
        return Ok(Some(found.clone()));
    }
    if opts.format != DepthFormat::Cityscapes {
        return Ok(None);
    }
    let tried: Vec<String> = candidates.iter().map(|c| c.display().to_string()).collect();
    Err(Error::format(
        path,
        format!(
            "a Cityscapes disparity needs its camera file: none at {}; give it as `camera`",
            tried.join(" or ")
        ),
    ))
}

/// Parses the camera file found by [`camera_file`] (its path and text) if this format uses
/// one, noting where it came from when it was found rather than given, or that `camera`
/// was ignored.
pub(super) fn take_camera(
    path: &Path,
    ext: &str,
    opts: &DepthOptions,
    camera: Option<(&Path, &str)>,
    notes: &mut Vec<String>,
) -> Result<Option<(CityscapesCamera, PathBuf)>> {
    if !wants_camera(path, ext, opts) {
        if let Some(given) = opts.camera.as_deref().or(camera.map(|c| c.0)) {
            notes.push(format!(
                "`camera` {} ignored: only Cityscapes disparity PNGs use it",
                given.display()
            ));
        }
        return Ok(None);
    }
    let Some((camera_path, text)) = camera else {
        return Ok(None);
    };
    let parsed = parse_camera_str(text, camera_path)?;
    if opts.camera.as_deref() != Some(camera_path) {
        notes.push(format!("camera read from {}", camera_path.display()));
    }
    Ok(Some((parsed, camera_path.to_path_buf())))
}

/// Range in metres from Cityscapes disparity samples and their camera (module docs).
pub(super) fn range(
    raw: &Grid<u16>,
    camera: &CityscapesCamera,
    opts: &DepthOptions,
    notes: &mut Vec<String>,
) -> ScalarMap {
    if opts.focal.is_some()
        || opts.baseline.is_some()
        || opts.disparity_offset.is_some()
        || opts.scale.is_some()
        || opts.fov.is_some()
    {
        notes.push(
            "`focal`, `baseline`, `disparity_offset`, `depth_scale` and `fov` ignored: the \
             Cityscapes camera file gives the geometry"
                .to_string(),
        );
    }
    notes.extend(camera.mount_note.clone());
    let flat = raw.as_slice().iter().filter(|&&p| p == 1).count();
    if flat > 0 {
        notes.push(format!(
            "{flat} disparities of 0 (stored value 1) give no depth: taken as unknown"
        ));
    }
    let depth = |p: u16| disparity_px(p).and_then(|d| camera.depth_m(d));
    to_range(raw, depth, Some(&camera.intrinsics))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stored_values_are_disparity_plus_one_times_256() {
        assert_eq!(disparity_px(0), None);
        assert_eq!(disparity_px(1), None);
        assert_eq!(disparity_px(257), Some(1.0));
        assert_eq!(disparity_px(65535), Some(65534.0 / 256.0));
    }

    /// A camera file with these values for baseline, fx, fy, u0 and v0.
    fn camera_json(b: &str, fx: &str, fy: &str, u0: &str, v0: &str) -> String {
        format!(
            r#"{{"extrinsic": {{"baseline": {b}}},
                "intrinsic": {{"fx": {fx}, "fy": {fy}, "u0": {u0}, "v0": {v0}}}}}"#
        )
    }

    #[test]
    fn absurd_camera_values_are_refused_naming_the_file_the_key_and_the_range() {
        let path = Path::new("data/aachen_1_camera.json");
        let ok = parse_camera_str(
            &camera_json("0.209", "2262.5", "2265.3", "1097", "513"),
            path,
        );
        assert_eq!(ok.unwrap().baseline_m, 0.209);
        // The limits themselves are accepted.
        let edges = camera_json("0.001", "1", "1e6", "-16384", "32768");
        assert!(parse_camera_str(&edges, path).is_ok());
        let edges = camera_json("1000", "1e6", "1", "32768", "-16384");
        assert!(parse_camera_str(&edges, path).is_ok());
        let cases = [
            (
                camera_json("1e300", "2262", "2262", "1", "1"),
                "extrinsic.baseline = 1e300: expected a baseline in metres, from 0.001 to 1000 m",
            ),
            (
                camera_json("1e-300", "2262", "2262", "1", "1"),
                "extrinsic.baseline = 1e-300: expected a baseline in metres, from 0.001 to 1000 m",
            ),
            (
                camera_json("0.2", "1e300", "2262", "1", "1"),
                "intrinsic.fx = 1e300: expected a focal length in pixels, from 1 to 1000000 px",
            ),
            (
                camera_json("0.2", "2262", "1e-300", "1", "1"),
                "intrinsic.fy = 1e-300: expected a focal length in pixels, from 1 to 1000000 px",
            ),
            (
                camera_json("0.2", "2262", "2262", "1e12", "1"),
                "intrinsic.u0 = 1e12: expected a principal point in pixels, from -16384 to \
                 32768 px",
            ),
            (
                camera_json("0.2", "2262", "2262", "1", "-20000.5"),
                "intrinsic.v0 = -20000.5: expected a principal point in pixels, from -16384 to \
                 32768 px",
            ),
            (
                camera_json("-0.2", "2262", "2262", "1", "1"),
                "extrinsic.baseline = -0.2: expected a baseline in metres, > 0, from 0.001",
            ),
        ];
        for (json, needle) in cases {
            let e = parse_camera_str(&json, path).unwrap_err().to_string();
            assert!(
                e.starts_with("data/aachen_1_camera.json: ") && e.contains(needle),
                "`{e}` should name the file and say `{needle}`"
            );
        }
    }

    /// The mount is read when the file gives the height and the pitch (roll 0 when
    /// absent), is absent otherwise, and a value out of its range is named in a note.
    #[test]
    fn the_mount_is_read_when_given() {
        let path = Path::new("c.json");
        let with = |extrinsic: &str| {
            let json = format!(
                r#"{{"extrinsic": {{"baseline": 0.21{extrinsic}}},
                    "intrinsic": {{"fx": 2262, "fy": 2265, "u0": 1097, "v0": 513}}}}"#
            );
            parse_camera_str(&json, path)
        };
        let mount = with(r#", "z": 1.22, "pitch": 0.038, "roll": -0.01, "yaw": 0.02"#);
        let want = Mount {
            height_m: 1.22,
            pitch: 0.038,
            roll: -0.01,
        };
        assert_eq!(mount.unwrap().mount, Some(want));
        let no_roll = with(r#", "z": 1.22, "pitch": 0.038"#)
            .unwrap()
            .mount
            .unwrap();
        assert_eq!(no_roll.roll, 0.0);
        assert_eq!(with(r#", "z": 1.22"#).unwrap().mount, None);
        assert_eq!(with("").unwrap().mount, None);
        // A mount out of its range (a camera at the vehicle frame's origin) is not used,
        // and says why; the file is read all the same.
        let at_origin = with(r#", "z": 0, "pitch": 0.04"#).unwrap();
        assert_eq!((at_origin.mount, at_origin.baseline_m), (None, 0.21));
        let note = at_origin.mount_note.unwrap();
        assert!(
            note.contains("extrinsic.z = 0: expected a height"),
            "{note}"
        );
        let note = with(r#", "z": 1.2, "pitch": 3"#)
            .unwrap()
            .mount_note
            .unwrap();
        assert!(
            note.contains("extrinsic.pitch = 3: expected an angle in radians"),
            "{note}"
        );
        let note = with(r#", "z": 1.2, "pitch": "up""#)
            .unwrap()
            .mount_note
            .unwrap();
        assert!(note.contains("expected a number"), "{note}");
        assert_eq!(
            with(r#", "z": 1.2, "pitch": 0.1"#).unwrap().mount_note,
            None
        );
    }

    #[test]
    fn candidates_are_beside_then_in_the_dataset_layout() {
        let p = Path::new("data/disparity/train/aachen/aachen_000000_000019_disparity.png");
        assert_eq!(
            camera_candidates(p),
            [
                PathBuf::from("data/disparity/train/aachen/aachen_000000_000019_camera.json"),
                PathBuf::from("data/camera/train/aachen/aachen_000000_000019_camera.json"),
            ]
        );
        // No `disparity` folder: only beside; a name without the suffix keeps its stem.
        assert_eq!(
            camera_candidates(Path::new("x/frame.png")),
            [PathBuf::from("x/frame_camera.json")]
        );
    }
}
