//! The image-guided refinement of a scene's range, shared by `render`, `batch` and
//! `view`: the left-right check (`--right`), joint bilateral upsampling of a depth map
//! smaller than the image, and the guided filter (`--refine`), on the GPU or by their CPU
//! references (see `brume::refine`).

use super::args::{RefineMode, RenderArgs};
use super::render::{PrepReport, Scene};
use brume::io::depth::DepthFormat;
use brume::io::image;
use brume::raster::{Grid, RgbImage, ScalarMap};
use brume::{Error, Refine, Result};
use std::time::Instant;

/// With a right image (`--right`), takes the disparities that fail the left-right
/// photoconsistency check as unknown ([`brume::prep::stereo`]), for pre-processing to fill
/// from reliable neighbours. Only when asked for: on brume's scene matched by StereoSGBM it
/// flagged correct pixels too and made τ worse (README, "Real depth").
pub fn drop_left_right_mismatches(args: &RenderArgs, scene: &mut Scene) -> Result<()> {
    let Some(right) = args.right.clone() else {
        return Ok(());
    };
    if scene.depth.format != DepthFormat::Cityscapes {
        return Err(Error::invalid(
            "--right",
            right.display(),
            "a Cityscapes disparity as --depth with it (the left-right check reads the \
             disparity in pixels)",
        ));
    }
    let depth_path = args.depth.depth.as_ref().expect("a depth was loaded");
    let raw = ::image::open(depth_path)
        .map_err(|e| Error::format(depth_path, format!("{e}")))?
        .to_luma16();
    let disparity = Grid::from_vec(
        raw.width() as usize,
        raw.height() as usize,
        raw.pixels()
            .map(|p| brume::io::depth::cityscapes_disparity_px(p[0]).map_or(f32::NAN, |d| d as f32))
            .collect(),
    );
    let right_image = image::load_linear_rgb(&right)?;
    let bad = brume::prep::stereo::inconsistent_pixels(
        &scene.image,
        &right_image,
        &disparity,
        brume::prep::stereo::DEFAULT_THRESHOLD,
    )
    .map_err(|e| match e {
        Error::SizeMismatch { .. } => Error::invalid(
            "--right",
            right.display(),
            format!(
                "a right image of the left image's size, {}x{}",
                scene.image.width(),
                scene.image.height()
            ),
        ),
        e => e,
    })?;
    let mut dropped = 0;
    for (v, _) in scene
        .depth
        .range
        .as_mut_slice()
        .iter_mut()
        .zip(bad.as_slice())
        .filter(|(v, &b)| b && v.is_finite())
    {
        *v = f32::NAN;
        dropped += 1;
    }
    scene.depth.unknown_pixels += dropped;
    scene.depth.notes.push(format!(
        "{dropped} px failed the left-right check against {} (> 12/255) and are unknown",
        right.display()
    ));
    Ok(())
}

/// What refinement a scene gets.
#[derive(Clone, Copy, Debug)]
pub struct RefinePlan {
    /// The depth map is smaller than the image: joint bilateral upsampling first.
    pub upsample: bool,
    /// The guided filter at the image's size, if on.
    pub guided: Option<Refine>,
    /// The guided filter's range only where pre-processing filled the range
    /// (`--refine unreliable`); elsewhere the range as measured.
    pub only_unreliable: bool,
}

/// The refinement `args` ask for: the guided filter with `--refine guided`; a depth map
/// smaller than the image is always upsampled, guided by it.
pub fn refine_plan(args: &RenderArgs, scene: &Scene) -> Result<RefinePlan> {
    let opts = Refine {
        radius_px: args
            .refine_radius
            .unwrap_or(brume::refine::DEFAULT_RADIUS_PX),
        epsilon: args.refine_eps.unwrap_or(brume::refine::DEFAULT_EPSILON),
        ..Refine::default()
    };
    opts.validate()?;
    let (image, range) = (&scene.image, &scene.depth.range);
    // Off unless asked for: on SGBM disparity of brume's scene with a known truth
    // (tools/stereo_refine_eval.py) it repairs the sky and the matcher's blunders but
    // blurs the pixels the matcher got right (README, "Real depth").
    let guided = matches!(
        args.refine,
        Some(RefineMode::Guided | RefineMode::Unreliable)
    );
    Ok(RefinePlan {
        upsample: (range.width(), range.height()) != (image.width(), image.height()),
        guided: guided.then_some(opts),
        only_unreliable: args.refine == Some(RefineMode::Unreliable),
    })
}

/// How a refinement runs: the GPU's passes, or their CPU reference.
pub trait Refiner {
    /// [`brume::Renderer::upsample`].
    fn upsample(&mut self, image: &RgbImage, range: &ScalarMap) -> Result<ScalarMap>;
    /// [`brume::Renderer::refine`].
    fn refine(&mut self, image: &RgbImage, range: &ScalarMap, opts: &Refine) -> Result<ScalarMap>;
}

impl Refiner for brume::Renderer {
    fn upsample(&mut self, image: &RgbImage, range: &ScalarMap) -> Result<ScalarMap> {
        let sigma = brume::refine::DEFAULT_UPSAMPLE_SIGMA_COLOUR;
        Ok(brume::Renderer::upsample(self, image, range, sigma)?.0)
    }
    fn refine(&mut self, image: &RgbImage, range: &ScalarMap, opts: &Refine) -> Result<ScalarMap> {
        Ok(brume::Renderer::refine(self, image, range, opts)?.0)
    }
}

/// The CPU references of the GPU passes (the same results within 1e-4), for the viewer,
/// whose pipeline is the fog's alone.
#[cfg(all(feature = "viewer", not(target_os = "android")))]
pub struct CpuRefiner;

#[cfg(all(feature = "viewer", not(target_os = "android")))]
impl Refiner for CpuRefiner {
    fn upsample(&mut self, image: &RgbImage, range: &ScalarMap) -> Result<ScalarMap> {
        let sigma = brume::refine::DEFAULT_UPSAMPLE_SIGMA_COLOUR;
        brume::refine::joint_bilateral_upsample_reference(image, range, sigma)
    }
    fn refine(&mut self, image: &RgbImage, range: &ScalarMap, opts: &Refine) -> Result<ScalarMap> {
        brume::refine::guided_range_reference(image, range, opts)
    }
}

/// Refines the scene's range with its image, in place (see [`refine_plan`]): the prepared
/// range (or, with --no-prep, the loaded one) is upsampled to the image's size and/or
/// guided-filtered, and the masks and measured range that go with it are brought to that
/// size. Returns the plan that ran.
pub fn refine_scene(
    args: &RenderArgs,
    scene: &mut Scene,
    prep: &mut PrepReport,
    refiner: &mut dyn Refiner,
) -> Result<RefinePlan> {
    let plan = refine_plan(args, scene)?;
    if !plan.upsample && plan.guided.is_none() {
        return Ok(plan);
    }
    let (w, h) = (scene.image.width(), scene.image.height());
    let started = Instant::now();
    // `filled`: where pre-processing filled the range, on the range's grid.
    let mut run = |range: &ScalarMap, filled: Option<&Grid<bool>>| -> Result<ScalarMap> {
        // The ego vehicle's range 0 (never fogged) is not a range to filter: the filter
        // reads log range. It is kept out (at the nearest range) and put back after.
        let ego = range.map(|&v| v == 0.0);
        let nearest = range
            .as_slice()
            .iter()
            .copied()
            .filter(|&v| v > 0.0)
            .fold(f32::INFINITY, f32::min);
        let positive = range.map(|&v| if v == 0.0 { nearest } else { v });
        let mut range = if plan.upsample {
            refiner.upsample(&scene.image, &positive)?
        } else {
            positive
        };
        if let Some(opts) = &plan.guided {
            let refined = refiner.refine(&scene.image, &range, opts)?;
            range = match filled.filter(|_| plan.only_unreliable) {
                Some(filled) => {
                    let filled = brume::refine::nearest_to_image_size(filled, w, h);
                    Grid::from_fn(w, h, |x, y| {
                        *if *filled.get(x, y) { &refined } else { &range }.get(x, y)
                    })
                }
                None => refined,
            };
        }
        let ego = brume::refine::nearest_to_image_size(&ego, w, h);
        for (v, _) in range
            .as_mut_slice()
            .iter_mut()
            .zip(ego.as_slice())
            .filter(|(_, &e)| e)
        {
            *v = 0.0;
        }
        Ok(range)
    };
    match &mut prep.prepared {
        Some(p) => {
            p.range = run(&p.range, Some(&p.filled))?;
            p.sky = brume::refine::nearest_to_image_size(&p.sky, w, h);
            p.filled = brume::refine::nearest_to_image_size(&p.filled, w, h);
            scene.depth.range = brume::refine::nearest_to_image_size(&scene.depth.range, w, h);
        }
        None => {
            brume::refine::check_positive(&scene.depth.range).map_err(|_| {
                Error::invalid(
                    "--no-prep",
                    "given",
                    "pre-processing with --refine guided or a depth map smaller than the \
                     image: refinement reads a range known at every pixel, which \
                     pre-processing fills (or give --refine none)",
                )
            })?;
            scene.depth.range = run(&scene.depth.range, None)?;
        }
    }
    log::info!(
        "range {}{} in {:.1} ms",
        if plan.upsample { "upsampled, " } else { "" },
        match plan.guided {
            Some(o) => format!("refined (r = {} px, ε = {})", o.radius_px, o.epsilon),
            None => "not refined".into(),
        },
        started.elapsed().as_secs_f64() * 1e3
    );
    Ok(plan)
}
