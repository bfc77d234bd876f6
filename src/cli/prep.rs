//! `brume prep`: pre-process a range map on its own and show what happened.

use super::args::{PrepArgs, RefineArgs};
use super::inputs::{
    depth_inputs, depth_options, load_depth, load_masks, prep_options, show_depth_notes,
};
use brume::io::output::{self, Outputs};
use brume::photo::{Photo, PrepareOptions};
use brume::prep::{self, Guides};
use brume::raster::{Grid, Orientation};
use brume::refine::{CpuFilter, RefineMode};
use brume::{Error, Result};
use serde_json::json;
use std::path::Path;
use std::time::Instant;

pub fn run(args: &PrepArgs) -> Result<()> {
    let opts = prep_options(&args.prep)?;
    super::options::check_depth_options(&args.depth.reading)?;
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
    // With an image, the depth is turned upright with it (its EXIF orientation).
    let stages = super::stages::Stages::start("reading the depth");
    let (photo, loaded) = match &args.image {
        Some(path) => {
            let mut photo = Photo::load(path, depth_path(args)?, &depth_options(&args.depth))?;
            show_depth_notes(depth_path(args)?, &mut photo.depth);
            let depth = photo.depth.clone();
            (Some(photo), depth)
        }
        None => {
            refuse_refinement_without_image(&args.refine)?;
            (None, load_depth(&args.depth)?)
        }
    };
    let depth_name = depth_path(args)?.display().to_string();
    let refine = args.refine.options(loaded.format)?;
    let masks = load_masks(&args.prep, &loaded, &depth_name)?;
    let mask_format = masks.sky_format;
    stages.at("pre-processing the depth");
    let mut refine_ms = 0.0;
    let (loaded, prepared, airlight, plan) = match photo {
        Some(photo) => {
            let opts = PrepareOptions {
                prep: Some(opts),
                sky_mask: masks.sky,
                ego_mask: masks.ego,
                refine,
                airlight: None,
            };
            let mut prepared = brume::photo::preprocess(&photo, &opts)?;
            stages.at("refining the depth");
            let started = Instant::now();
            let plan = prepared.refine(&photo, &refine, &mut CpuFilter)?;
            refine_ms = started.elapsed().as_secs_f64() * 1e3;
            let airlight = (prepared.airlight, prepared.airlight_from.name());
            let p = prepared.prepared.expect("pre-processing ran");
            (photo.depth, p, Some(airlight), Some(plan))
        }
        None => {
            let guides = Guides {
                image: None,
                sky_mask: masks.sky.as_ref(),
                ego_mask: masks.ego.as_ref(),
            };
            let prepared = prep::prepare_guided(&loaded.range, guides, &opts.for_depth(&loaded))?;
            (loaded, prepared, None, None)
        }
    };
    let (w, h) = (prepared.range.width(), prepared.range.height());
    stages.at(&format!("writing {}", args.out.display()));
    let mut outputs = Outputs::new();
    // Laid out as the --depth file, which it stands in for: a render with the photo turns
    // it upright again.
    let as_stored = loaded.turned.inverse();
    match as_stored {
        Orientation::Upright => outputs.stage_scalar(&args.out, &prepared.range)?,
        o => outputs.stage_scalar(&args.out, &prepared.range.oriented(o))?,
    }
    if let Some(vis) = &args.vis {
        let measured = brume::refine::at_image_size(&loaded.range, w, h);
        let (w, h, rgb) = prep::visualize(&measured, &prepared);
        let rgb = Grid::from_vec(w, h, rgb).into_oriented(as_stored);
        let (w, h) = (rgb.width(), rgb.height());
        outputs.stage_png_rgb8(vis, w, h, rgb.as_slice())?;
    }
    super::commit(outputs)?;

    let s = &prepared.stats;
    if args.json {
        let mut report = serde_json::to_value(s).expect("statistics serialise");
        let extra = json!({
            "width": w, "height": h,
            "depth_width": loaded.range.width(), "depth_height": loaded.range.height(),
            "upsampled": plan.is_some_and(|p| p.upsample),
            "refine": plan.map(|_| args.refine.mode.unwrap_or(RefineMode::default_for(loaded.format)).name()),
            "refine_ms": refine_ms,
            "out": args.out.display().to_string(),
            "vis": args.vis.as_ref().map(|p| p.display().to_string()),
            "depth_format": loaded.format.to_string(), "depth_kind": loaded.kind.to_string(),
            "depth_notes": loaded.notes, "unknown_pixels": loaded.unknown_pixels,
            "camera_mount": loaded.mount,
            "stereo_view": loaded.stereo_focal_baseline.map(|_| loaded.stereo_view),
            "airlight": airlight.map(|a| a.0),
            "airlight_source": airlight.map(|a| a.1),
            "sky_mask": args.prep.sky_mask.as_ref().map(|p| p.display().to_string()),
            "sky_mask_format": mask_format.map(|f| f.name()),
            "ego_mask": args.prep.ego_mask.as_ref().map(|p| p.display().to_string()),
        });
        if let (Some(map), serde_json::Value::Object(more)) = (report.as_object_mut(), extra) {
            map.extend(more);
        }
        outln!("{}", super::stamped(report));
    } else {
        outln!(
            "{} unknown px: {} holes ({} px; {} regions from their own colour, {} px stereo occlusions{}) filled, {} sky components ({} px), {} margin px; Rmax {:.4}, Smax {}",
            loaded.unknown_pixels,
            s.holes,
            s.hole_pixels,
            s.colour_regions,
            s.occluded,
            match (loaded.stereo_focal_baseline, loaded.stereo_view) {
                (Some(_), brume::io::depth::StereoView::Right) => " of a right view",
                _ => "",
            },
            s.sky_components,
            s.sky_pixels,
            s.margin_pixels,
            s.r_max,
            s.s_max.map_or("-".to_string(), |v| format!("{v:.4}"))
        );
        let road = loaded.mount.map_or("no level road known".into(), |m| {
            let (pitch, roll) = (m.pitch.to_degrees(), m.roll.to_degrees());
            format!(
                "the camera {:.2} m over the road, {pitch:.2}° down, roll {roll:.2}°: {} px \
                 beyond the level road",
                m.height_m, s.below_ground
            )
        });
        outln!(
            "sky from {}; {road}, {} far outliers removed{}, {} local outliers, {} px of \
             matcher noise by the sky; {} known px in the sky replaced",
            sky_method_name(s.sky_method),
            s.far_outliers,
            s.far_cut
                .map_or(String::new(), |c| format!(" (cut {c:.4})")),
            s.local_outliers,
            s.sky_noise,
            s.sky_known_pixels
        );
        outln!(
            "border bands: {} px continued ({} px of specks farther than their band \
             dropped, {} px brought onto the level road), {} px sky; {} px beyond the \
             depth's reach; ego vehicle {} px (range 0)",
            s.border_filled,
            s.border_islands,
            s.border_on_road,
            s.border_sky,
            s.beyond_reach,
            s.ego_pixels
        );
        if s.scan_gaps > 0 {
            outln!(
                "scan lines: {} px between them filled, {} px unlike their colour round \
                 them dropped",
                s.scan_gaps,
                s.scan_unlike
            );
        }
        outln!(
            "CPU time: fill {:.1} ms, sky {:.1} ms, margin {:.1} ms, total {:.1} ms",
            s.fill_ms,
            s.sky_ms,
            s.margin_ms,
            s.total_ms
        );
        if let Some(plan) = plan.filter(|p| !p.is_empty()) {
            outln!(
                "range {}{} at {w}x{h}, {refine_ms:.1} ms CPU",
                if plan.upsample {
                    format!(
                        "upsampled from {}x{}, ",
                        loaded.range.width(),
                        loaded.range.height()
                    )
                } else {
                    String::new()
                },
                super::refine::guided_text(&plan)
            );
        }
        if let Some((rgb, from)) = airlight {
            outln!(
                "airlight {:.3},{:.3},{:.3} (from {from})",
                rgb[0],
                rgb[1],
                rgb[2]
            );
        }
        outln!("wrote {}", args.out.display());
        if let Some(vis) = &args.vis {
            outln!("wrote {}", vis.display());
        }
    }
    Ok(())
}

/// `--refine` and its window need the image as guide.
fn refuse_refinement_without_image(args: &RefineArgs) -> Result<()> {
    let given = [
        ("--refine", args.mode.is_some_and(|m| m != RefineMode::None)),
        ("--refine-radius", args.radius.is_some()),
        ("--refine-eps", args.eps.is_some()),
    ];
    match given.iter().find(|(_, g)| *g) {
        Some((flag, _)) => Err(Error::invalid(
            *flag,
            "given",
            "--image with it: the refinement is guided by the colour image",
        )),
        None => Ok(()),
    }
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

/// The `--depth` that `prep` requires.
fn depth_path(args: &PrepArgs) -> Result<&Path> {
    let path = args.depth.depth.as_deref();
    path.ok_or_else(|| Error::invalid("--depth", "(missing)", "a depth, range or disparity map"))
}
