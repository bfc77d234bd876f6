//! `brume prep`: pre-process a range map on its own and show what happened.

use super::args::{PrepArgs, PrepOptionArgs};
use super::render::{
    airlight_source_name, check_same_size, depth_inputs, load_depth, prep_options,
};
use brume::io::image;
use brume::io::mask::{self, SkyMaskFormat};
use brume::io::output::{self, Outputs};
use brume::prep::{self, Guides, PrepOptions, Prepared};
use brume::raster::{Grid, RgbImage, ScalarMap};
use brume::{Error, Result};
use serde_json::json;
use std::path::Path;

pub fn run(args: &PrepArgs) -> Result<()> {
    let opts = prep_options(&args.prep)?;
    super::options::check_depth_options(&args.depth)?;
    output::check_scalar_output(&args.out, "--out")?;
    let mut outs: Vec<(&str, &Path)> = vec![("--out", &args.out)];
    if let Some(vis) = &args.vis {
        output::check_png_output(vis, "--vis")?;
        outs.push(("--vis", vis));
    }
    let mut inputs = depth_inputs(&args.depth);
    inputs.extend(args.image.iter().cloned());
    inputs.extend(args.prep.sky_mask.iter().cloned());
    inputs.extend(args.prep.ego_mask.iter().cloned());
    super::refuse_overlaps(&outs, &inputs)?;

    // Everything is read and computed before the first output is staged: a bad input
    // leaves every output as it was.
    let loaded = load_depth(&args.depth)?;
    let depth_name = args
        .depth
        .depth
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_default();
    let colour = match &args.image {
        Some(path) => {
            let img = image::load_linear_rgb(path)?;
            check_same_size(
                &img,
                &path.display().to_string(),
                &loaded.range,
                &depth_name,
            )?;
            Some(img)
        }
        None => None,
    };
    let (prepared, mask_format) = prepare_inputs(
        &args.prep,
        &opts,
        &loaded.range,
        &depth_name,
        colour.as_ref(),
    )?;
    let airlight = colour
        .as_ref()
        .map(|img| prep::estimate_airlight(img, &prepared));
    let mut outputs = Outputs::new();
    outputs.stage_scalar(&args.out, &prepared.range)?;
    if let Some(vis) = &args.vis {
        let (w, h, rgb) = prep::visualize(&loaded.range, &prepared);
        outputs.stage_png_rgb8(vis, w, h, &rgb)?;
    }
    super::commit(outputs)?;

    let s = &prepared.stats;
    if args.json {
        let mut report = serde_json::to_value(s).expect("statistics serialise");
        let extra = json!({
            "width": loaded.range.width(), "height": loaded.range.height(),
            "out": args.out.display().to_string(),
            "vis": args.vis.as_ref().map(|p| p.display().to_string()),
            "depth_format": loaded.format.to_string(), "depth_kind": loaded.kind.to_string(),
            "depth_notes": loaded.notes, "unknown_pixels": loaded.unknown_pixels,
            "airlight": airlight.as_ref().map(|a| a.rgb),
            "airlight_source": airlight.as_ref().map(|a| airlight_source_name(a.source)),
            "sky_mask": args.prep.sky_mask.as_ref().map(|p| p.display().to_string()),
            "sky_mask_format": mask_format.map(|f| f.name()),
            "ego_mask": args.prep.ego_mask.as_ref().map(|p| p.display().to_string()),
        });
        if let (Some(map), serde_json::Value::Object(more)) = (report.as_object_mut(), extra) {
            map.extend(more);
        }
        outln!("{report}");
    } else {
        outln!(
            "{} unknown px: {} holes ({} px) filled, {} sky components ({} px), {} margin px; Rmax {:.4}, Smax {}",
            loaded.unknown_pixels,
            s.holes,
            s.hole_pixels,
            s.sky_components,
            s.sky_pixels,
            s.margin_pixels,
            s.r_max,
            s.s_max.map_or("-".to_string(), |v| format!("{v:.4}"))
        );
        outln!(
            "sky from {}; {} far outliers removed{}, {} local outliers, {} px of matcher noise \
             by the sky; {} known px in the sky replaced",
            sky_method_name(s.sky_method),
            s.far_outliers,
            s.far_cut
                .map_or(String::new(), |c| format!(" (cut {c:.4})")),
            s.local_outliers,
            s.sky_noise,
            s.sky_known_pixels
        );
        outln!(
            "border bands: {} px continued, {} px sky; ego vehicle {} px (range 0)",
            s.border_filled,
            s.border_sky,
            s.ego_pixels
        );
        outln!(
            "CPU time: fill {:.1} ms, sky {:.1} ms, margin {:.1} ms, total {:.1} ms",
            s.fill_ms,
            s.sky_ms,
            s.margin_ms,
            s.total_ms
        );
        if let Some(a) = &airlight {
            outln!(
                "airlight {:.3},{:.3},{:.3} (from {})",
                a.rgb[0],
                a.rgb[1],
                a.rgb[2],
                airlight_source_name(a.source)
            );
        }
        outln!("wrote {}", args.out.display());
        if let Some(vis) = &args.vis {
            outln!("wrote {}", vis.display());
        }
    }
    Ok(())
}

/// The `sky_method` of the JSON report, in words.
fn sky_method_name(m: prep::SkyMethod) -> &'static str {
    match m {
        prep::SkyMethod::Off => "nowhere (--no-sky)",
        prep::SkyMethod::Depth => "the range alone",
        prep::SkyMethod::DepthAndImage => "the range and the image",
        prep::SkyMethod::Mask => "--sky-mask",
    }
}

/// Checks a mask read for `flag` (`path`, a `what`) against the range it goes with: the
/// range's size, and not every pixel set (`all_set` says what that means); logs its count.
fn check_mask(
    (flag, path, what): (&str, &Path, &str),
    mask: &Grid<bool>,
    range: &ScalarMap,
    range_name: &str,
    all_set: &str,
) -> Result<()> {
    if (mask.width(), mask.height()) != (range.width(), range.height()) {
        return Err(Error::SizeMismatch {
            a: path.display().to_string(),
            aw: mask.width() as u32,
            ah: mask.height() as u32,
            b: range_name.to_string(),
            bw: range.width() as u32,
            bh: range.height() as u32,
        });
    }
    let set = mask.as_slice().iter().filter(|&&s| s).count();
    log::info!(
        "{}: {what}, {set} pixels ({:.1} %)",
        path.display(),
        100.0 * set as f64 / mask.len().max(1) as f64
    );
    if set == mask.len() {
        return Err(Error::invalid(flag, path.display(), all_set));
    }
    Ok(())
}

/// Pre-processes `range` (named `range_name` in messages) with the colour image, if any,
/// and the `--sky-mask` and `--ego-mask` of `args`, if any (which must have the range's
/// size). Returns the result and the sky mask's format.
pub fn prepare_inputs(
    args: &PrepOptionArgs,
    opts: &PrepOptions,
    range: &ScalarMap,
    range_name: &str,
    image: Option<&RgbImage>,
) -> Result<(Prepared, Option<SkyMaskFormat>)> {
    let loaded = match &args.sky_mask {
        Some(path) => {
            let (m, format) = mask::load_sky_mask(path, args.sky_mask_format)?;
            check_mask(
                ("--sky-mask", path, "sky mask"),
                &m,
                range,
                range_name,
                &format!(
                    "a mask with ground in it: every pixel is sky as read ({format}); is it \
                     inverted, or of another --sky-mask-format?"
                ),
            )?;
            Some((m, format))
        }
        None => None,
    };
    let ego = match &args.ego_mask {
        Some(path) => {
            let (m, format) = mask::load_ego_mask(path, None)?;
            check_mask(
                ("--ego-mask", path, "ego-vehicle mask"),
                &m,
                range,
                range_name,
                &format!(
                    "a mask with the scene in it: every pixel is the ego vehicle as read \
                     ({format}); is it inverted, or a label image not named *_labelIds.png?"
                ),
            )?;
            Some(m)
        }
        None => None,
    };
    let guides = Guides {
        image,
        sky_mask: loaded.as_ref().map(|(m, _)| m),
        ego_mask: ego.as_ref(),
    };
    let prepared = prep::prepare_guided(range, guides, opts)?;
    Ok((prepared, loaded.map(|(_, f)| f)))
}
