//! What `render`, `prep` and `batch` read from their arguments before any work: the depth
//! map, the masks of pre-processing and its options, so that the commands share them
//! without importing one another.

use super::args::{DepthArgs, DepthReadingArgs, PrepOptionArgs};
use brume::io::depth::{self, DepthOptions, LoadedDepth};
use brume::io::mask::{self, RangeMasks};
use brume::prep::PrepOptions;
use brume::{Error, Result};
use std::path::{Path, PathBuf};

/// Loads the depth named by `args` (which must have one) as a range map.
pub fn load_depth(args: &DepthArgs) -> Result<LoadedDepth> {
    let path = args
        .depth
        .as_ref()
        .ok_or_else(|| Error::invalid("--depth", "(missing)", "a depth, range or disparity map"))?;
    let mut loaded = depth::load_range(path, &depth_options(args))?;
    show_depth_notes(path, &mut loaded);
    Ok(loaded)
}

/// How `args` say the depth is read.
pub fn depth_options(args: &DepthArgs) -> DepthOptions {
    DepthOptions {
        calib: args.calib.clone(),
        camera: args.camera.clone(),
        ..reading_options(&args.reading)
    }
}

/// How `args` say depth files are read, without a calibration or camera file of their
/// own (`batch`'s frames bring theirs).
pub fn reading_options(args: &DepthReadingArgs) -> DepthOptions {
    DepthOptions {
        format: args.depth_format,
        kind: args.depth_kind,
        scale: args.depth_scale,
        focal: args.focal,
        baseline: args.baseline,
        disparity_offset: args.disparity_offset,
        near: args.near,
        far: args.far,
        reversed_z: args.reversed_z,
        fov: args.fov,
        min_confidence: args.min_confidence,
        sky_beyond: args.sky_beyond,
        layout: args.depth_layout,
        camera_mount: args.camera_mount,
        stereo_view: args.stereo_view,
        ..DepthOptions::default()
    }
}

/// Says the loader's notes on the depth at `path`, with the options they name as flags
/// (in the notes kept for `--json` too): an option given and not used where the user
/// looks (a warning), not only in `--json`.
pub fn show_depth_notes(path: &Path, loaded: &mut LoadedDepth) {
    for warning in loaded.warnings() {
        log::warn!("{}: {}", path.display(), super::flags_in(&warning));
    }
    for note in &mut loaded.notes {
        *note = super::flags_in(note);
        if !depth::is_ignored_option_note(note) {
            log::info!("{}: {note}", path.display());
        }
    }
}

/// The files a depth argument set reads.
pub fn depth_inputs(args: &DepthArgs) -> Vec<PathBuf> {
    args.depth
        .iter()
        .chain(args.calib.iter())
        .chain(args.camera.iter())
        .cloned()
        .collect()
}

/// Builds the pre-processing options from the command line over the library defaults.
pub fn prep_options(args: &PrepOptionArgs) -> Result<PrepOptions> {
    if args.no_sky {
        use super::options::shown;
        let sky = [
            ("--sky-factor", shown(args.sky_factor)),
            ("--sky-min-area", shown(args.sky_min_area)),
            ("--margin", shown(args.margin)),
        ];
        let expected = "sky with it, not --no-sky (the sky's range, area and horizon margin)";
        super::options::refuse_given(&sky, expected)?;
    }
    let mut opts = PrepOptions::default();
    if let Some(m) = args.margin {
        opts.margin_px = m;
    }
    if let Some(f) = args.sky_factor {
        opts.sky_range_factor = f;
    }
    if let Some(a) = args.sky_min_area {
        opts.sky.min_area_fraction = a;
    }
    if let Some(k) = args.far_outlier_factor {
        opts.far_outlier_factor = k;
    }
    if let Some(f) = args.local_outliers {
        opts.local_outlier_factor = f;
    }
    if let Some(s) = args.seed {
        opts.seed = u64::try_from(s)
            .map_err(|_| Error::invalid("seed", s, "a whole number from 0 to 2^64 - 1"))?;
    }
    opts.detect_sky = !args.no_sky;
    opts.validate()?;
    Ok(opts)
}

/// Loads the `--sky-mask` and `--ego-mask` of `args`, if any, which must have the size of
/// the range of `depth` (named `range_name` in messages), turned as it was, and not be
/// set everywhere.
pub fn load_masks(
    args: &PrepOptionArgs,
    depth: &LoadedDepth,
    range_name: &str,
) -> Result<RangeMasks> {
    let sky = args.sky_mask.as_deref().map(|p| (p, args.sky_mask_format));
    mask::load_range_masks(sky, args.ego_mask.as_deref(), depth, range_name)
}
