//! `brume render`'s capture after the fog and its inserted object: options from their
//! flags, and their part of the text and JSON reports (also `batch`'s and the aerial
//! path's).

use super::args::{CaptureArgs, RenderArgs};
use super::photo_args::{PrepReport, Scene};
use brume::io::depth::DepthKind;
use brume::photo::{self, CaptureOptions, Insertion, VirtualObject};
use brume::{Error, Result};
use serde_json::json;

/// The capture after the fog that `capture` asks for (all off by default), its noise
/// seeded by `seed` (--seed, which also seeds the hole filling).
pub(super) fn capture_options(capture: &CaptureArgs, seed: Option<i128>) -> Result<CaptureOptions> {
    let seed = u64::try_from(seed.unwrap_or(0)).map_err(|_| {
        Error::invalid(
            "--seed",
            seed.unwrap_or(0),
            "a whole number from 0 to 2^64 - 1",
        )
    })?;
    // The library names its fields, which `name_flags` shows as the flags.
    CaptureOptions::from_parts(
        capture.exposure_stops.unwrap_or(0.0),
        capture.shot_noise_gain,
        capture.read_noise,
        capture.jpeg_quality,
        seed,
    )
}

/// Loads --insert and composites it into the photo and its prepared range (at the
/// image's size by now), before the fog; `None` without --insert.
pub(super) fn insert_object(
    args: &RenderArgs,
    scene: &mut Scene,
    prep: &mut PrepReport,
) -> Result<Option<Insertion>> {
    let Some(path) = &args.insert.insert else {
        return Ok(None);
    };
    if let Some(t) = args.from_turbidity {
        return Err(Error::invalid(
            "--from-turbidity",
            t,
            "no --insert with it: retargeting first removes the photo's haze, which the \
             object, rendered clear, does not have",
        ));
    }
    let kind = args.insert.insert_depth_kind.unwrap_or(DepthKind::Depth);
    let intrinsics = scene.image_intrinsics(args.depth.reading.focal, args.depth.reading.fov);
    let object = VirtualObject::load(
        path,
        args.insert.insert_depth.as_deref(),
        kind,
        intrinsics.as_ref(),
    )?;
    Ok(Some(photo::insert(scene, prep, &object)?))
}

/// --insert's report (`null` without it).
pub(super) fn insert_json(args: &RenderArgs, inserted: Option<&Insertion>) -> serde_json::Value {
    match (inserted, &args.insert.insert) {
        (Some(i), Some(path)) => json!({
            "object": path.display().to_string(),
            "pixels_in_front": i.in_front,
            "pixels_partial": i.partial,
            "pixels_hidden": i.hidden,
        }),
        _ => serde_json::Value::Null,
    }
}

/// The text report's lines for --insert and the capture.
pub(super) fn print_insert_and_capture(
    args: &RenderArgs,
    inserted: Option<&Insertion>,
    capture: &CaptureOptions,
) {
    if let (Some(i), Some(path)) = (inserted, &args.insert.insert) {
        outln!(
            "inserted {}: {} px in front ({} partly covered), {} px hidden by the photo",
            path.display(),
            i.in_front + i.partial,
            i.partial,
            i.hidden
        );
    }
    if !capture.is_off() {
        outln!("capture: {}", capture.to_json());
    }
}
