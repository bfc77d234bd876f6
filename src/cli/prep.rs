//! `brume prep`: pre-process a range map on its own and show what happened.

use super::args::PrepArgs;
use super::render::{
    airlight_source_name, check_same_size, depth_inputs, load_depth, prep_options,
};
use brume::io::image;
use brume::io::output::{self, Outputs};
use brume::prep;
use brume::Result;
use serde_json::json;
use std::path::Path;

pub fn run(args: &PrepArgs) -> Result<()> {
    let opts = prep_options(&args.prep)?;
    output::check_scalar_output(&args.out, "--out")?;
    let mut outs: Vec<(&str, &Path)> = vec![("--out", &args.out)];
    if let Some(vis) = &args.vis {
        output::check_png_output(vis, "--vis")?;
        outs.push(("--vis", vis));
    }
    let mut inputs = depth_inputs(&args.depth);
    inputs.extend(args.image.iter().cloned());
    super::refuse_overlaps(&outs, &inputs)?;

    // Everything is read and computed before the first output is staged: a bad input
    // leaves every output as it was.
    let loaded = load_depth(&args.depth)?;
    let colour = match &args.image {
        Some(path) => {
            let img = image::load_linear_rgb(path)?;
            let depth_name = args.depth.depth.as_ref().map(|p| p.display().to_string());
            check_same_size(
                &img,
                &path.display().to_string(),
                &loaded.range,
                &depth_name.unwrap_or_default(),
            )?;
            Some(img)
        }
        None => None,
    };
    let prepared = prep::prepare(&loaded.range, &opts)?;
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
        });
        if let (Some(map), serde_json::Value::Object(more)) = (report.as_object_mut(), extra) {
            map.extend(more);
        }
        println!("{report}");
    } else {
        println!(
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
        println!(
            "CPU time: fill {:.1} ms, sky {:.1} ms, margin {:.1} ms, total {:.1} ms",
            s.fill_ms, s.sky_ms, s.margin_ms, s.total_ms
        );
        if let Some(a) = &airlight {
            println!(
                "airlight {:.3},{:.3},{:.3} (from {})",
                a.rgb[0],
                a.rgb[1],
                a.rgb[2],
                airlight_source_name(a.source)
            );
        }
        println!("wrote {}", args.out.display());
        if let Some(vis) = &args.vis {
            println!("wrote {}", vis.display());
        }
    }
    Ok(())
}
