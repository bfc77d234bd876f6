//! Foggy Cityscapes' conventions on the command line (`--compat foggy-cityscapes`,
//! `--transmittance-map`); the conventions themselves are `brume::compat`.

use super::args::RenderArgs;
use brume::io::output::Outputs;
use brume::medium::physical::{self, PhysicalFog};
use brume::photo::Photo as Scene;
use brume::raster::ScalarMap;
use brume::refine::RefineMode;
use brume::Result;
use serde_json::json;
use std::path::Path;

/// `args` for a render from a transmittance map ([`Scene::load_transmittance`]): physical
/// fog at β = 1 on the optical depth (so τ is the map's and the blur follows βR = −ln τ, as it would from the range),
/// no refinement (the map is what it is) and no pre-processing of the optical depth (the
/// sky is still found for the airlight, from the image).
pub fn transmittance_map_args(args: &RenderArgs) -> RenderArgs {
    let mut args = args.clone();
    args.beta = Some(1.0);
    args.refine.mode = Some(RefineMode::None);
    args
}

/// `--compat foggy-cityscapes`: Foggy Cityscapes' blend in sRGB code values of the image
/// and the dark-channel airlight (or `--airlight`, linear, encoded) by τ = exp(−βR) of the
/// (refined) range in metres, no blur ([`brume::compat`]).
pub fn run_foggy_cityscapes(
    args: &RenderArgs,
    scene: &Scene,
    range: &ScalarMap,
    fog: &PhysicalFog,
    out: &Path,
) -> Result<()> {
    let (metres, _) = physical::metric_range(range)?;
    let (rgba, airlight, source) =
        brume::compat::foggy_cityscapes(&scene.image, &metres, fog.beta, args.airlight);
    let mut outputs = Outputs::new();
    outputs.stage_photo(out, &rgba, &scene.metadata)?;
    super::commit(outputs)?;
    let report = json!({
        "out": out.display().to_string(),
        "compat": "foggy-cityscapes",
        "beta": fog.beta,
        "visibility_m": fog.visibility_m(),
        "airlight_srgb": airlight,
        "airlight_source": source,
        "width": scene.image.width(),
        "height": scene.image.height(),
    });
    if args.json {
        outln!("{}", super::stamped(report));
    } else {
        outln!(
            "wrote {} (Foggy Cityscapes' conventions: β = {} m⁻¹, blend in sRGB code values, \
             airlight {:.3},{:.3},{:.3} ({source}), no blur)",
            out.display(),
            fog.beta,
            airlight[0],
            airlight[1],
            airlight[2]
        );
    }
    Ok(())
}
