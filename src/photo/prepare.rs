//! A photo's range made ready for fog: holes, sky, the airlight ([`preprocess`], CPU) and
//! the image-guided refinement ([`PreparedPhoto::refine`], GPU or CPU).

use super::Photo;
use crate::error::{Error, Result};
use crate::medium::haze::DEFAULT_AIRLIGHT;
use crate::prep::{self, AirlightSource, Guides, PrepOptions, Prepared};
use crate::raster::{Grid, ScalarMap};
use crate::refine::{self, RangeFilter, RefineMode, RefineOptions, RefinePlan};

/// How a photo's range is made ready for fog.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PrepareOptions {
    /// Hole filling, sky detection and the horizon margin ([`prep::prepare_guided`]);
    /// `None` uses the range as loaded (unknown pixels are then taken as the farthest).
    pub prep: Option<PrepOptions>,
    /// A sky mask on the depth map's grid (true = sky), e.g. from segmentation: replaces
    /// the sky detection. Not serialised (nor the ego mask): a photo's data, not a
    /// setting.
    #[serde(skip)]
    pub sky_mask: Option<Grid<bool>>,
    /// An ego-vehicle mask on the depth map's grid (true = the car's hood): range 0,
    /// never fogged.
    #[serde(skip)]
    pub ego_mask: Option<Grid<bool>>,
    /// The image-guided refinement (upsampling of a smaller depth map always runs).
    pub refine: RefineOptions,
    /// The airlight (linear RGB); `None` estimates it from the sky found (or a neutral
    /// grey without sky; [`DEFAULT_AIRLIGHT`] without pre-processing).
    pub airlight: Option<[f32; 3]>,
}

impl Default for PrepareOptions {
    /// Pre-processing with its defaults, no masks, no guided filter, the airlight
    /// estimated.
    fn default() -> Self {
        PrepareOptions {
            prep: Some(PrepOptions::default()),
            sky_mask: None,
            ego_mask: None,
            refine: RefineOptions::default(),
            airlight: None,
        }
    }
}

impl PrepareOptions {
    /// The defaults for `photo`: as [`Default`], with the refinement its depth format
    /// gets by default ([`RefineMode::default_for`]: `repair` for Cityscapes disparity).
    pub fn for_photo(photo: &Photo) -> PrepareOptions {
        let mut opts = PrepareOptions::default();
        opts.refine.mode = RefineMode::default_for(photo.depth.format);
        opts
    }
}

/// Where a prepared photo's airlight came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AirlightFrom {
    /// [`PrepareOptions::airlight`].
    Given,
    /// The median colour of the sky found.
    Sky,
    /// No sky: a grey as bright as the scene's bright end.
    Neutral,
    /// No pre-processing and none given: [`DEFAULT_AIRLIGHT`].
    Default,
}

impl AirlightFrom {
    /// The name reports use (`airlight_source` in `--json`).
    pub fn name(self) -> &'static str {
        match self {
            AirlightFrom::Given => "given",
            AirlightFrom::Sky => "sky",
            AirlightFrom::Neutral => "neutral",
            AirlightFrom::Default => "default",
        }
    }
}

/// A photo's range ready for fog, with what was found on the way.
#[derive(Clone, Debug)]
pub struct PreparedPhoto {
    /// The range the fog reads: pre-processed and, once [`PreparedPhoto::refine`] ran,
    /// at the image's size.
    pub range: ScalarMap,
    /// What pre-processing found (sky and filled masks, statistics), on the grid of
    /// [`PreparedPhoto::range`]; `None` without pre-processing.
    pub prepared: Option<Prepared>,
    /// The airlight, linear RGB.
    pub airlight: [f32; 3],
    /// Where the airlight came from.
    pub airlight_from: AirlightFrom,
    /// The refinement that ran, once it has.
    pub refined: Option<RefinePlan>,
}

/// Pre-processes `photo`'s range on the depth map's grid, with the image averaged to that
/// grid as the sky detector's guide and the airlight's source (CPU only: a dataset's
/// loader thread runs it). Errors: bad options, masks of another size than the depth map,
/// pre-processing's own.
pub fn preprocess(photo: &Photo, opts: &PrepareOptions) -> Result<PreparedPhoto> {
    opts.refine.validate()?;
    let range = &photo.depth.range;
    let given = opts.airlight.map(|a| (a, AirlightFrom::Given));
    let Some(prep_opts) = &opts.prep else {
        let (airlight, airlight_from) = given.unwrap_or((DEFAULT_AIRLIGHT, AirlightFrom::Default));
        return Ok(PreparedPhoto {
            range: range.clone(),
            prepared: None,
            airlight,
            airlight_from,
            refined: None,
        });
    };
    let (w, h) = (range.width(), range.height());
    let prep_opts = &prep_opts.for_depth(&photo.depth);
    let (small, cell_opts);
    let (image, prep_opts) = if (photo.image.width(), photo.image.height()) == (w, h) {
        (&photo.image, prep_opts)
    } else {
        small = refine::image_at_depth_size(&photo.image, w, h);
        cell_opts = margin_in_cells(prep_opts, photo.image.width() as f64 / w as f64);
        (&small, &cell_opts)
    };
    let guides = Guides {
        image: Some(image),
        sky_mask: opts.sky_mask.as_ref(),
        ego_mask: opts.ego_mask.as_ref(),
    };
    let prepared = prep::prepare_guided(range, guides, prep_opts)?;
    let (airlight, airlight_from) = given.unwrap_or_else(|| {
        let estimate = prep::estimate_airlight(image, &prepared);
        let from = match estimate.source {
            AirlightSource::Sky => AirlightFrom::Sky,
            AirlightSource::Neutral => AirlightFrom::Neutral,
        };
        (estimate.rgb, from)
    });
    Ok(PreparedPhoto {
        range: prepared.range.clone(),
        prepared: Some(prepared),
        airlight,
        airlight_from,
        refined: None,
    })
}

/// `opts` for a depth map `factor` times smaller than the image: the horizon margin
/// ([`PrepOptions::margin_px`]) is a width in the image's pixels, so on the depth map's
/// grid it spans `margin_px / factor` cells, at least one (none stays none). Measured on a
/// phone's depth at 1/8 (`tools/phone_depth_eval.py`): 8 cells, 64 of the image's pixels,
/// tapered the range of every tower far into the sky round it, and fogged a halo of sky
/// that much too thin.
fn margin_in_cells(opts: &PrepOptions, factor: f64) -> PrepOptions {
    let mut cells = opts.clone();
    if opts.margin_px > 0.0 {
        cells.margin_px = (opts.margin_px / factor).max(1.0);
    }
    cells
}

impl PreparedPhoto {
    /// Refines the range with `photo`'s image ([`refine::refine_prepared`]): a depth map
    /// smaller than the image is upsampled to its size and the guided filter runs as
    /// `opts` asks, by `filter` (the GPU's [`crate::Renderer`] or [`refine::CpuFilter`]).
    /// Returns the plan that ran. Without pre-processing, the range must be known
    /// everywhere for anything to run.
    pub fn refine(
        &mut self,
        photo: &Photo,
        opts: &RefineOptions,
        filter: &mut dyn RangeFilter,
    ) -> Result<RefinePlan> {
        let plan = match &mut self.prepared {
            Some(p) => {
                let plan = refine::refine_prepared(&photo.image, p, opts, filter)?;
                self.range = p.range.clone();
                plan
            }
            None => {
                let (w, h) = (photo.image.width(), photo.image.height());
                let plan = opts.plan((w, h), (self.range.width(), self.range.height()));
                if !plan.is_empty() {
                    refine::check_positive(&self.range)
                        .map_err(|_| unprepared_range(plan, opts.mode, &self.range, (w, h)))?;
                    self.range =
                        refine::refine_range(&photo.image, &self.range, None, opts, filter)?;
                }
                plan
            }
        };
        self.refined = Some(plan);
        Ok(plan)
    }
}

/// [`preprocess`] then [`PreparedPhoto::refine`] with `opts.refine`.
pub fn prepare(
    photo: &Photo,
    opts: &PrepareOptions,
    filter: &mut dyn RangeFilter,
) -> Result<PreparedPhoto> {
    let mut prepared = preprocess(photo, opts)?;
    prepared.refine(photo, &opts.refine, filter)?;
    Ok(prepared)
}

/// The error of a refinement `plan` (in `mode`) on a range that was not pre-processed and
/// has unknown pixels: what needs the range filled (the upsampling of a depth map smaller
/// than the image, `w`x`h`; the guided filter) and what would do.
fn unprepared_range(
    plan: RefinePlan,
    mode: RefineMode,
    range: &ScalarMap,
    (w, h): (usize, usize),
) -> Error {
    let mut needs = Vec::new();
    if plan.upsample {
        needs.push(format!(
            "a depth map of {}x{}, smaller than the {w}x{h} image (it is upsampled)",
            range.width(),
            range.height()
        ));
    }
    if plan.guided.is_some() {
        needs.push(format!("the {} refinement", mode.name()));
    }
    let remedy = if plan.upsample {
        ""
    } else {
        " (or `refine` none)"
    };
    Error::invalid(
        "prep",
        "off",
        format!(
            "pre-processing with {}: refinement reads a range known at every pixel, which \
             pre-processing fills{remedy}",
            needs.join(" and ")
        ),
    )
}
