//! The image-guided refinement of a scene's range, shared by `render`, `batch` and
//! `view`: the left-right check (`--right`), joint bilateral upsampling of a depth map
//! smaller than the image, and the guided filter (`--refine`), on the GPU or by their CPU
//! references (see `brume::refine`).

use super::args::{RefineArgs, RenderArgs};
use brume::io::depth::DepthFormat;
use brume::photo::{Photo as Scene, PreparedPhoto as PrepReport};
use brume::raster::ScalarMap;
use brume::refine::{RangeFilter, RefineMode, RefineOptions, RefinePlan};
use brume::{Error, Refine, Result};
use std::path::Path;
use std::time::Instant;

/// Takes the disparities that fail the left-right check against `right` (`--right`) as
/// unknown ([`Scene::drop_left_right_mismatches`]), with a warning when most failed.
pub fn drop_left_right_mismatches(
    scene: &mut Scene,
    disparity: Option<&ScalarMap>,
    right: &Path,
) -> Result<()> {
    let check = scene.drop_left_right_mismatches(disparity, right)?;
    if check.mostly_failed() {
        log::warn!(
            "{}: {} of {} px failed the left-right check against {}: is that the pair's \
             other view, is this the {} view's disparity (--stereo-view), and in the \
             image's pixels?",
            scene.depth_name,
            check.failed,
            check.checked,
            right.display(),
            scene.depth.stereo_view,
        );
    }
    Ok(())
}

impl RefineArgs {
    /// The refinement these arguments ask for, for a depth map of `format` (whose
    /// default mode is [`RefineMode::default_for`]); a depth map smaller than the image is
    /// always upsampled, guided by it.
    pub fn options(&self, format: DepthFormat) -> Result<RefineOptions> {
        let mode = self.mode.unwrap_or(RefineMode::default_for(format));
        // A batch's format is each frame's (Auto here): only --refine none is known.
        if mode == RefineMode::None && (self.mode.is_some() || format != DepthFormat::Auto) {
            let why = match self.mode {
                Some(_) => "--refine none does not filter".to_string(),
                None => format!("a {format} depth is not refined by default"),
            };
            use super::options::shown;
            let window = [
                ("--refine-radius", shown(self.radius)),
                ("--refine-eps", shown(self.eps)),
            ];
            super::options::refuse_given(
                &window,
                &format!("--refine repair, guided or unreliable with it ({why})"),
            )?;
        }
        let opts = RefineOptions {
            mode,
            filter: Refine {
                radius_px: self.radius.unwrap_or(brume::refine::DEFAULT_RADIUS_PX),
                epsilon: self.eps.unwrap_or(brume::refine::DEFAULT_EPSILON),
                ..Refine::default()
            },
            ..RefineOptions::default()
        };
        opts.validate()?;
        Ok(opts)
    }
}

/// Whether and how the guided filter ran, as reports print it.
pub fn guided_text(plan: &RefinePlan) -> String {
    match plan.guided {
        Some(o) => format!("refined (r = {} px, ε = {})", o.radius_px, o.epsilon),
        None => "not refined".into(),
    }
}

/// Refines the scene's range with its image, in place ([`brume::refine::refine_prepared`]):
/// the prepared range (or, with --no-prep, the loaded one) is upsampled to the image's
/// size and/or guided-filtered, and the masks and measured range that go with it are
/// brought to that size. Returns the plan that ran and its wall time in ms (0 for none).
pub fn refine_scene(
    args: &RenderArgs,
    scene: &mut Scene,
    prep: &mut PrepReport,
    filter: &mut dyn RangeFilter,
) -> Result<(RefinePlan, f64)> {
    let opts = args.refine.options(scene.depth.format)?;
    let (w, h) = (scene.image.width(), scene.image.height());
    let range = &scene.depth.range;
    let plan = opts.plan((w, h), (range.width(), range.height()));
    if plan.is_empty() {
        return Ok((plan, 0.0));
    }
    let started = Instant::now();
    prep.refine(scene, &opts, filter).map_err(|mut e| {
        // The library says what needs the range filled; the flag that chose the mode is ours.
        if let (Error::InvalidParameter { name, expected, .. }, Some(_), None) =
            (&mut e, plan.guided, args.refine.mode)
        {
            if name == "prep" {
                let mode = opts.mode.name();
                let format = scene.depth.format;
                expected.push_str(&format!(
                    "; {mode} is --refine's default for a {format} depth"
                ));
            }
        }
        e
    })?;
    if prep.prepared.is_some() {
        // The measured range at the image's size, for the report's known pixels (already
        // there where the depth map has the image's size).
        if (range.width(), range.height()) != (w, h) {
            let measured = brume::refine::nearest_to_image_size(range, w, h);
            scene.depth.replace_range(measured);
        }
    } else {
        scene.depth.replace_range(prep.range.clone());
    }
    let ms = started.elapsed().as_secs_f64() * 1e3;
    log::info!(
        "range {}{} in {ms:.1} ms",
        if plan.upsample { "upsampled, " } else { "" },
        guided_text(&plan),
    );
    Ok((plan, ms))
}
