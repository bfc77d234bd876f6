//! Pre-processing of real scanner range data (paper 000, sec. 4.1): hole filling, sky
//! detection, horizon margin and airlight estimation. Pure CPU, no GL.
//!
//! [`prepare`] (range alone) and [`prepare_guided`] (range with the colour image and/or a
//! sky mask) turn a range map with unknown pixels (any non-finite value, normally NaN)
//! into a map that is finite everywhere. **Every known value that is not sky, not a far or
//! local outlier, not beyond the level road, not matcher noise next to the sky (steps 2
//! and 3) and not under the ego-vehicle mask is kept bit for bit.**
//!
//! 1. **Components.** The 4-connected components of unknown pixels are labelled in linear
//!    time (one raster scan, breadth-first flood fill, no label image).
//! 2. **Sky**, decided in one of three ways ([`PrepStats::sky_method`]):
//!    - *Depth rules* ([`SkyRules`], the range alone). A component of unknown pixels is sky
//!      when: it touches the top row; its area is at least 1 % of the image; it covers at
//!      least 10 % of the top row (sky is wide at the top, an occlusion band or a border
//!      strip is not); it fills at least 30 % of its own bounding box (a thin frame of
//!      unknown pixels round the image, as stereo ground truth often has, fills about
//!      1 %); and it does not reach the bottom row (an occlusion band running the whole
//!      height is not sky). Of the components that pass, the [`SkyRules::max_components`]
//!      (default 4) largest are sky. Indoor data (e.g. Middlebury Aloe, whose unknown
//!      pixels are occlusions, 3.5 % of the image in 1211 components, none touching the
//!      top row) gets no sky.
//!    - *Depth rules and the image* ([`ImageSkyRules`], with [`Guides::image`]). On real
//!      outdoor frames the depth rules fail: the sky's unknown region is joined to the
//!      band along the left border where a stereo pair has no match, which reaches the
//!      bottom row; and a matcher leaves scattered, wrong but valid values in the sky. The
//!      image tells sky from scene, the range only vetoes. Per pixel: luminance `Y` (Rec.
//!      709, linear); *texture*, the 3 x 3 mean of the largest relative colour step to a
//!      4-neighbour; a *range class*: unknown, unsupported (fewer than 2, or fewer than
//!      half, of its known 8-neighbours agree within 5 %, and it does not lie between its
//!      two neighbours on two of the four lines through it, as a surface seen at a
//!      grazing angle does: matcher noise), far (above the
//!      far-outlier cut of step 3, taken over all known values) or confident (the rest).
//!      A pixel *looks like sky* when `Y` is at least the brightness floor, it is blue or
//!      grey (`B >= 0.7 max(R, G)`) and its range is not confident; it is *admissible*
//!      when its texture is also at most 0.05. Seeds: admissible pixels of the top 5 % of
//!      the rows, and the depth rules' sky where it looks like sky. The floor is the
//!      median luminance of the scene (the pixels of confident range; of the whole image
//!      without any: in a frame mostly of sky the image's median is the sky's own),
//!      raised to half the seeds' median luminance. From each
//!      seed a region grows breadth-first over admissible 4-neighbours whose colour
//!      differs by at most 8 % (relative to the brighter one's `Y`) from the pixel grown
//!      from; a blocked direction may jump up to 6 pixels to an admissible pixel that
//!      passes the same test (overhead wires do not cut the sky in two); then two rounds
//!      of edge refinement add neighbours that look like sky and pass the step test,
//!      without the texture test (the texture window of a pixel next to the horizon sees
//!      the horizon). A region is kept when it covers at least
//!      [`SkyRules::min_area_fraction`] of the image and does not reach the bottom row (it
//!      leaked). The sky is the kept regions and, of the depth rules' sky, the admissible
//!      pixels and those the sky reaches over pixels of it that look like sky or glow
//!      (bright and smooth whatever the hue: a sunset's orange under the blue), in the
//!      growth's colour steps, with the growth's edge refinement, all of them open to
//!      the sky above them (in their column, only such pixels up to the sky, each in a
//!      colour step of the one above: sky-coloured water under the far city is not, nor
//!      a light grey face under its top edge); all of the depth rules' sky when the image
//!      finds none (a sunset's orange sky alone is not blue or grey). What is left of the
//!      depth rules' sky, in
//!      pieces larger than a gap (below), is the scene beyond the sensor's reach (a
//!      time-of-flight camera stops at 8 m; the ground, the street and the city behind are
//!      unknown and joined to the sky), filled in step 4. Finally each
//!      4-connected region of non-sky pixels that does not reach the bottom row and holds
//!      no confident range is a gap in the sky (a bird, a lamp head, a cloud's textured
//!      rim, blobs of matcher noise) and becomes sky when it is at most 0.2 % of the image
//!      or at least half as bright as the floor. Then each 4-connected set of pixels of
//!      confident range next to the sky that would look like sky but for its range,
//!      smooth and reached from the sky in colour steps of at most half the growth's (a
//!      matcher's streak: semi-global matching carries an object's disparity along the
//!      rows of a textureless sky as smooth, backed-up values) becomes sky unless it
//!      reaches the bottom row, and the sky grows on from it as from seeds (sky between
//!      far towers that a streak wider than the jump closed off; a region that reaches
//!      the bottom row is dropped). The left band below the sky shows the
//!      scene (textured, darker, not blue): it is not grown into and is filled as a hole.
//!      Once sky is found, known pixels left outside it that look like sky and whose
//!      range is unsupported are matcher noise in slivers of sky the growth could not
//!      enter (between a wire and a roof, between leaves): they become unknown
//!      ([`PrepStats::sky_noise`]), or they would set `Rmax`.
//!    - *A sky mask* ([`Guides::sky_mask`], e.g. semantic segmentation) is the sky, known
//!      range under it included; nothing is detected.
//!
//!    Sky pixels get the constant range `Smax = sky_range_factor x Rmax` (default 1.5),
//!    where `Rmax` is the maximum known range outside the sky once far outliers are
//!    removed. The output stays in the input's units: a renderer that normalises range by
//!    `Rmax` ([`PrepStats::r_max`]) sees the sky at `sky_range_factor`.
//!    [`PrepOptions::detect_sky`] = false treats every component as a hole.
//! 3. **Far outliers.** Among the known values outside the sky, those above `cut =
//!    far_outlier_factor x P99` (default 2 x the 99th percentile, nearest rank: up to 1 %
//!    of bogus values cannot move it) whose 8-connected patch of values above the cut has
//!    fewer than `far_patch_fraction` (default 0.05 %, at least 16 pixels) of the image
//!    become unknown ([`PrepStats::far_outliers`]). A distant hillside is a patch; a
//!    speck of 100 km on the street is an outlier, and would otherwise be `Rmax`, the
//!    scale of the whole frame.
//!
//!    **Local outliers** ([`PrepOptions::local_outlier_factor`], see `local.rs`): small
//!    patches whose disparity `1/R` differs by more than a factor (default 3) from the
//!    medians of every neighbourhood round them, stereo mismatches below the far cut,
//!    become unknown too ([`PrepStats::local_outliers`]); long structures (poles) stay.
//!
//!    **The level road** ([`PrepOptions::ground`], a vehicle camera's mount, see
//!    `ground.rs`), before both: below the horizon, known values beyond the range at which
//!    their ray would meet the road falling 5 % away from the camera's level, in
//!    4-connected patches under 1 % of the image, become unknown
//!    ([`PrepStats::below_ground`]).
//!
//!    **Scan lines** (a LiDAR's map as KITTI stores it, see `scan.rs`): when most unknown
//!    pixels lie in short runs down a column between two known ones, the depth rules read
//!    what lies below the scanner's top line as known (step 2), the scene beyond the reach
//!    is only what lies over it, and a region reached below it counts as reached; here the
//!    known pixels whose range is unlike that of their colour's round them go (the
//!    background seen past an object's edge, [`PrepStats::scan_unlike`]) and each gap is
//!    filled from its ends, in 1/R or split at the image's colour edge
//!    ([`PrepStats::scan_gaps`]).
//! 4. **Border bands** ([`PrepOptions::border_band_fraction`], see `border.rs`) are filled
//!    first, line by line from each border: a run of unknown pixels continues the surface
//!    it meets, linearly in disparity, or is sky when it runs down from the top border
//!    into the sky ([`PrepStats::border_filled`], [`PrepStats::border_sky`]), once the
//!    far specks a matcher left in it are dropped ([`PrepStats::border_islands`]). With
//!    the level road known, no band pixel is left farther than the road along its ray.
//!
//!    **Holes** (the components of unknown pixels outside the sky, far outliers included)
//!    are filled by RANSAC (Fischler and Bolles 1981), as
//!    in the paper, "by sampling from the available values on each hole boundary" and
//!    keeping "the value that minimizes a robust function of the gradient across the
//!    boundary". The boundary is the set of *edges* (hole pixel `h`, known 4-neighbour
//!    `b`). A candidate surface `F` is scored by the truncated L1 jump it leaves across the
//!    boundary, `E(F) = sum_b min(|F(b) - R(b)|, delta)`: `F` continued onto the known side
//!    should meet the data. For a constant `F = c` this is exactly the truncated L1 norm of
//!    the finite-difference gradient `c - R(b)` across every boundary edge; for a plane it
//!    is the gradient left over after the plane's own slope. The truncation makes the
//!    score robust: a boundary that straddles a depth edge (foreground on one side,
//!    background on the other) is won by the majority surface instead of being averaged.
//!    `delta = 1.4826 x MAD` of the boundary values (one robust standard deviation),
//!    floored at a few ulps of their median. Each of the `ransac_samples` (default 32)
//!    trials draws one constant (a boundary value; all boundary values are tried when
//!    there are no more of them than trials) and, through three boundary samples, a plane
//!    in range `R = a + b x + c y` and a plane of the scene `1/R = a + b x + c y` (only
//!    for boundaries of at least 4 edges; three on one column give the plane through the
//!    two farthest apart that is level along the rows, three on one row the one level down
//!    the columns, other collinear triplets are skipped; for a whole hole a sloped plane
//!    must score 2 delta below the best level one). With the level road known
//!    ([`PrepOptions::ground`]), the road itself, range `h / s` along each ray, is a
//!    candidate of every hole, scored as a level plane. A plane of the
//!    scene is affine in inverse depth in a pinhole image, and so nearly in inverse
//!    range: the ground behind an occluder grows as `1/(y - y_horizon)`, which a plane in
//!    range fills as a ramp, its middle too far (60 % in the unit test). Long boundaries
//!    are scored on an evenly strided subset of 1024 edges. A winning plane is refitted
//!    by least squares to its inliers (jump `< delta`), in its own variable, if that
//!    scores no worse; a plane must be strictly better than the best constant. This
//!    generalises the paper's sampled values to sampled planes, so a hole in a tilted
//!    surface is filled with the surface, not a step. The fill is finally clamped to the
//!    range of the boundary values, so extrapolation can never create a spike, except
//!    that a plane of the scene may recede up to `Rmax` (the ground's unknown far part
//!    below the sky, which no known pixel bounds, continues toward the horizon, as the
//!    border bands continue; a hole enclosed by known pixels lies between its boundary's
//!    values in any case). Sky pixels
//!    are not boundary values; a hole with no known pixel round it (sky all round: a wire,
//!    outliers in the sky) has nothing to be filled from and is sky (the ego vehicle, when
//!    only it and no sky is round it).
//!
//!    **With the colour image**, a hole is first split into regions of one colour
//!    (4-neighbours within [`ImageSkyRules::max_step`], the sky growth's step). A region
//!    with at least 8 edges to known pixels of its own colour (within twice that step) is
//!    filled by the same RANSAC from those edges alone, when at least 70 % of them lie
//!    within 25 % of the range of its fit: a stereo occlusion is the background the image
//!    shows there, not a blend of it with the foreground on the hole's other side, and a
//!    face the matcher left blank continues the face ([`PrepStats::colour_regions`]). A
//!    region whose own colour's edges disagree (a column of false matches on a face
//!    without texture, beside the right ones) and the large pieces of what is left (a
//!    textured surface the matcher missed whole) take the whole hole's surface, as
//!    without the image; small pieces left (up to 256 pixels: texture specks) are filled
//!    from what is round them once the regions are, so a speck amid the background is
//!    the background.
//!
//!    **Stereo occlusions** ([`PrepOptions::stereo_focal_baseline`], a matched disparity:
//!    Cityscapes, Middlebury, any read with a focal length and baseline): a run of unknown
//!    pixels in a row whose one side is at least 1.25 times nearer than the other or 8 px
//!    of disparity nearer (close range), at most about twice as wide as their disparities
//!    differ, between measured sides (the far one a surface over 8 pixels), is the
//!    background the other camera could not see: left of the nearer surface in a left view,
//!    right of it in a right view (the map's view, [`PrepOptions::stereo_view`], says which
//!    side is looked at). Its hole is filled without the edges to the near surface beside
//!    such runs, the *occluder* (see `occlusion.rs`), but for a colour region whose colour
//!    only the occluder shows (the pole the matcher missed); [`PrepStats::occluded`] counts
//!    the runs' pixels.
//!
//!    **The scene beyond the sensor's reach** (step 2; [`PrepStats::beyond_reach`]) is
//!    at least as far as the farthest range measured and no farther than the sky: the
//!    ground receding toward the horizon and what stands on it. In each column it goes
//!    from `Rmax` where it meets the scene below (with the image, above something nearer
//!    than the reach, a box's top edge: where it meets the ground at the reach beside, for
//!    the ground behind the box) to `Smax` at the horizon, linearly in log
//!    range, and is `Smax` above the horizon; the horizon is the lowest row the sky comes
//!    down to (between far towers; only the sky that reaches the top row: sky seen in
//!    water is no horizon), along the tilt of the reach's contour on the ground across
//!    the whole width where that tells the camera's roll, else level within half the
//!    width either side, so the ground below a far tower recedes as the ground beside it
//!    (the tower's own skyline would draw its ghost down to the ground). With the image,
//!    what stands on that ground (a pixel run of another material just above the
//!    ground's materials, or the last ground's below it as the colour drifts with
//!    distance, rising over the horizon or with the ground seen again above it, its foot
//!    at least three rows of the grid below the horizon) keeps its foot's range up the
//!    column, as an upright face does,
//!    and along the rows to its material beside it (up to a sixteenth of the width);
//!    and a surface the sensor reached in part (a region of one material under measured
//!    pixels of its own in a quarter of its columns: a face just at the reach's limit,
//!    measured here and there through the noise) is no scene beyond the reach but holes,
//!    filled from what was reached. Physical fog reads the fill's parameter as the
//!    ground's 1/R, linear from `1/Rmax` to the sky's 1/1 km ([`Prepared::beyond_reach`],
//!    `PreparedPhoto::metres`). The known range beside it (a near pole) is not used: it
//!    says nothing of the background behind the pole, and blending it in would draw a
//!    clear halo round the pole. Like the sky, it is not marked `filled`: the
//!    refinement's guided filter (`--refine unreliable`, `repair`) would pull it toward
//!    the near scene round it. Without the image none of this is found: the depth rules'
//!    sky is all sky (a wall of fog at the sensor's reach).
//!
//!    **The ego vehicle** ([`Guides::ego_mask`]): its pixels are unknown and black to the
//!    sky detector, then neither data nor holes, and finally get range 0 (never fogged;
//!    [`PrepStats::ego_pixels`]).
//! 5. **Horizon margin.** The exact Euclidean distance transform of the scene mask
//!    (separable lower-envelope method of Felzenszwalb and Huttenlocher, exact and linear
//!    like Maurer et al. 2003; see [`edt`]) is thresholded at `µ` ([`PrepOptions::margin_px`],
//!    default 8 px): the sky pixels within `µ` of the scene form the margin. There,
//!    `laplace(S) = 0` is solved with `S = R` on the scene side and `S = Smax` on the sky
//!    side, from `S0 = Smax`, by Jacobi iterations restricted to the list of margin pixels
//!    (default `ceil(2 µ)` sweeps, the paper's "about 2µ iterations"). Only margin pixels
//!    change. The range therefore tapers from the data into the sky with no hard step.
//! 6. **Airlight** ([`estimate_airlight`]): the per-channel median of the linear colour of
//!    the sky pixels (the median ignores the sun, birds, wires and saturated leakage);
//!    without sky, a neutral grey (R = G = B) at the 99th percentile of the Rec. 709
//!    luminance of the known pixels, since no pixel then shows the colour of the light.
//!
//! **Randomness.** A built-in SplitMix64 generator; each hole gets its own stream derived
//! from [`PrepOptions::seed`] (default 0) and the index of its first pixel, so the output is
//! bit-identical for the same seed and input on every platform, and the fill of one hole
//! does not depend on the others.
//!
//! **Cost.** Everything is linear in the number of pixels (the RANSAC part is linear in
//! the boundary length with a constant of `2 x ransac_samples x` at most 1024), single
//! threaded. Working memory beyond input and output: 4 bytes per unknown pixel (component
//! lists), 2 bytes per pixel (the `sky` and `filled` masks), 4 bytes per known pixel (the
//! percentile of the far-outlier cut) and 4 bytes per pixel of the sky's bounding box
//! (distance transform). The image-guided detector adds about 20 bytes per pixel
//! (luminance, texture, range class, region and gap lists) while it runs, and the hole
//! fill with the image 5 (luminance, the regions' state) and up to 16 bytes per unknown
//! pixel (its region lists); the scene beyond the sensor's reach 1 byte per pixel and 8
//! per pixel of it (its mask and list); on a 2048 x 1024 street frame the detector takes
//! about 80 % of the whole 0.2-0.4 s.

mod airlight;
mod border;
mod colour_guide;
mod colour_step;
mod components;
pub mod edt;
mod fill;
mod ground;
mod holes;
mod horizon;
mod local;
mod margin;
mod occlusion;
mod options;
mod outliers;
mod range_class;
mod rank;
mod reach;
mod scan;
mod sky;
mod sky_image;
pub mod stereo;
#[cfg(test)]
mod street_tests;
pub mod synthetic;
mod vis;

use std::time::Instant;

use crate::raster::{Grid, RgbImage, ScalarMap};
use crate::{Error, Result};

pub use airlight::{estimate_airlight, AirlightEstimate, AirlightSource};
pub use ground::Ground;
pub use options::{ImageSkyRules, PrepOptions, SkyRules, MONOCULAR_SKY_FACTOR};
use options::{MIN_FAR_PATCH, MIN_LOCAL_SPAN};
pub use vis::visualize;

/// How the sky was decided (`sky_method` in the JSON reports).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SkyMethod {
    /// Sky detection off ([`PrepOptions::detect_sky`] false, no mask).
    #[default]
    Off,
    /// The depth rules on the range alone (no colour image).
    Depth,
    /// The depth rules and the image-guided detector together.
    DepthAndImage,
    /// A sky mask given by the user.
    Mask,
}

/// What [`prepare`] found and did, and how long it took (serialised as is in the CLI's
/// JSON reports).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct PrepStats {
    /// Number of holes (non-sky components of unknown pixels) filled.
    pub holes: usize,
    /// Number of pixels in those holes.
    pub hole_pixels: usize,
    /// Number of regions of one colour in those holes filled from the known pixels of
    /// their own colour alone (with the colour image only).
    pub colour_regions: usize,
    /// Number of sky components (4-connected regions of the final sky).
    pub sky_components: usize,
    /// Number of sky pixels (margin included).
    pub sky_pixels: usize,
    /// Number of sky pixels whose input range was known (matcher noise in the sky, or
    /// pixels a sky mask covers): their value is replaced.
    pub sky_known_pixels: usize,
    /// Number of sky pixels in the horizon margin (the ones the Jacobi iterations change).
    pub margin_pixels: usize,
    /// How the sky was decided.
    pub sky_method: SkyMethod,
    /// Number of known values removed as far outliers (then filled, or sky).
    pub far_outliers: usize,
    /// Number of known values removed as beyond the level ground's bound, in small
    /// patches ([`PrepOptions::ground`]; then filled, or sky).
    pub below_ground: usize,
    /// Number of known values removed as local outliers (patches whose range disagrees
    /// with their neighbourhood; then filled, or sky).
    pub local_outliers: usize,
    /// Number of unknown pixels of border bands filled by continuing the surface they
    /// meet (the islands dropped in them included).
    pub border_filled: usize,
    /// Number of unknown pixels of border bands made sky (they meet the sky).
    pub border_sky: usize,
    /// Number of known values dropped inside border bands (short runs far beyond the surface
    /// the band continues, a matcher's specks or a hood's reflection; see `border.rs`), then
    /// filled with the band (counted in `border_filled`).
    pub border_islands: usize,
    /// Border band pixels brought no farther than the level road along their ray
    /// ([`PrepOptions::ground`]; 0 without it; counted in `border_filled` too).
    pub border_on_road: usize,
    /// Pixels between a scanner's lines (a LiDAR's map, see `scan.rs`) filled from the
    /// lines above and below them.
    pub scan_gaps: usize,
    /// Known pixels of a scanner's map whose range is unlike that of the pixels of their
    /// colour round them (a background seen past an object's edge), made unknown first.
    pub scan_unlike: usize,
    /// Unknown pixels taken as stereo occlusions and filled from their background alone
    /// ([`PrepOptions::stereo_focal_baseline`]; 0 without it).
    pub occluded: usize,
    /// Number of unknown pixels of the scene beyond the sensor's reach (image-guided
    /// detection only: the depth rules took them for sky, the image does not join them to
    /// its sky), filled receding from `Rmax` into the sky.
    pub beyond_reach: usize,
    /// Number of pixels under the ego-vehicle mask (range 0: never fogged).
    pub ego_pixels: usize,
    /// Number of known values removed as matcher noise in slivers of sky (image-guided
    /// detection only: outside the sky found, looking like sky, below the far cut and not
    /// backed up by their neighbours; then filled, or sky).
    pub sky_noise: usize,
    /// The far-outlier cut, `far_outlier_factor x P99` of the known range outside the sky
    /// (`None` when the rule is off or there is nothing to cut).
    pub far_cut: Option<f32>,
    /// Maximum known range `Rmax` outside the sky, far outliers removed.
    pub r_max: f32,
    /// Sky range `Smax`, if there is sky.
    pub s_max: Option<f32>,
    /// Milliseconds spent removing far outliers, labelling components and filling holes.
    pub fill_ms: f64,
    /// Milliseconds spent detecting, selecting and assigning the sky.
    pub sky_ms: f64,
    /// Milliseconds spent on the distance transform and the Jacobi iterations.
    pub margin_ms: f64,
    /// Milliseconds for the whole of [`prepare`].
    pub total_ms: f64,
}

/// The result of [`prepare`].
#[derive(Clone, Debug, PartialEq)]
pub struct Prepared {
    /// The range map, finite everywhere; known input values bit-identical except those of
    /// sky pixels, outliers (far, local, beyond the level road) and matcher noise next to
    /// the sky.
    pub range: ScalarMap,
    /// Pixels that are sky (set to `Smax`, or relaxed in the margin).
    pub sky: Grid<bool>,
    /// Pixels that were holes (unknown, far outliers or matcher noise) and have been
    /// filled; not the scene beyond the sensor's reach ([`PrepStats::beyond_reach`]).
    pub filled: Grid<bool>,
    /// Pixels of the scene beyond the sensor's reach ([`PrepStats::beyond_reach`]): their
    /// range recedes from `Rmax` to `Smax` linearly in log range, which physical fog reads
    /// as the ground's recession toward the horizon (`PreparedPhoto::metres`).
    pub beyond_reach: Grid<bool>,
    /// The pixels of [`Prepared::beyond_reach`] whose range is the ground's recession
    /// toward the horizon (and the sky's range above it), not that of something standing
    /// on the ground, held at its foot's: the refinement interpolates them when it
    /// upsamples the range ([`crate::refine::refine_prepared`]).
    pub receding: Grid<bool>,
    /// What was found and timings.
    pub stats: PrepStats,
}

/// Evidence beyond the range map for [`prepare_guided`]; each must have the range's size.
#[derive(Clone, Copy, Debug, Default)]
pub struct Guides<'a> {
    /// The colour image (linear RGB): turns on the image-guided sky detector.
    pub image: Option<&'a RgbImage>,
    /// A sky mask (true = sky), e.g. from semantic segmentation: replaces sky detection.
    pub sky_mask: Option<&'a Grid<bool>>,
    /// An ego-vehicle mask (true = the car's own hood, e.g. Cityscapes label 1): its
    /// pixels get range 0, so no fog covers them, and their range (a stereo matcher's
    /// guess on a reflecting hood) is never used, not as sky, not to fill a hole.
    pub ego_mask: Option<&'a Grid<bool>>,
}

/// Fills holes, detects sky and builds the horizon margin from the range alone (see the
/// module docs); [`prepare_guided`] with no guide.
///
/// Unknown pixels are the non-finite ones. Errors: [`Error::InvalidParameter`] for bad
/// options, [`Error::Prep`] when the map has no known value at all (or, with sky, a
/// maximum known range that is not positive).
pub fn prepare(range: &ScalarMap, opts: &PrepOptions) -> Result<Prepared> {
    prepare_guided(range, Guides::default(), opts)
}

/// [`prepare`] with the colour image (image-guided sky detection) and/or a sky mask (no
/// detection: the mask is the sky). Errors as [`prepare`], and [`Error::SizeMismatch`]
/// when a guide's size differs from the range's.
pub fn prepare_guided(range: &ScalarMap, guides: Guides, opts: &PrepOptions) -> Result<Prepared> {
    crate::parallel::run(|| prepare_on_pool(range, guides, opts))
}

/// The error of a range with no known value outside the sky: how many pixels are sky,
/// the ego vehicle (so that a wrong ego mask shows) and unknown.
fn no_range_outside_the_sky(sky: &[bool], ego: &[bool], (w, h): (usize, usize)) -> Error {
    let sky_px = sky.iter().filter(|&&s| s).count();
    let ego_px = ego.iter().filter(|&&e| e).count();
    let ego_part = if ego.is_empty() {
        String::new()
    } else {
        format!(", {ego_px} the ego vehicle (its mask)")
    };
    Error::Prep(format!(
        "no valid range value outside the sky: of the {} pixels ({w}x{h}), {sky_px} are \
         sky{ego_part} and {} unknown",
        w * h,
        w * h - sky_px - ego_px
    ))
}

/// [`prepare_guided`] on brume's thread pool (`crate::parallel`), where its parallel loops
/// (the sky, the local outliers, the margin) run.
fn prepare_on_pool(range: &ScalarMap, guides: Guides, opts: &PrepOptions) -> Result<Prepared> {
    opts.validate()?;
    check_guide_sizes(range, &guides)?;
    let t0 = Instant::now();
    let (w, h) = (range.width(), range.height());
    let _reserved = options::check_memory(w, h, guides.image.is_some())?;
    let mut work: Vec<f32> = range
        .as_slice()
        .iter()
        .map(|&v| if v.is_finite() { v } else { f32::NAN })
        .collect();
    if !work.iter().any(|v| v.is_finite()) {
        return Err(Error::Prep(format!(
            "no valid range value: all {} pixels ({w}x{h}) are unknown (NaN or infinite; the \
             loaders and `Photo::from_range` mark a range ≤ 0 unknown)",
            range.len()
        )));
    }
    let mut stats = PrepStats::default();
    // The ego vehicle's range is never data: unknown while the sky is looked for (and
    // black in the image, so that a hood reflecting the sky is not grown into), then
    // neither known nor unknown (+inf, like the sky while holes are filled), 0 at the end.
    let mut ego: Vec<bool> = guides
        .ego_mask
        .map(|m| m.as_slice().to_vec())
        .unwrap_or_default();
    let masked_image;
    let mut guides = guides;
    if !ego.is_empty() {
        ego.iter()
            .zip(work.iter_mut())
            .filter(|(&e, _)| e)
            .for_each(|(_, v)| *v = f32::NAN);
        if let Some(image) = guides.image {
            masked_image = Grid::from_fn(w, h, |x, y| {
                if ego[y * w + x] {
                    [0.0; 3]
                } else {
                    *image.get(x, y)
                }
            });
            guides.image = Some(&masked_image);
        }
    }
    let scan_lines = scan::find_lines(&work, (w, h));
    let mut found = sky::find_sky(&work, scan_lines.as_ref(), (w, h), guides, opts);
    if let Some(lines) = &scan_lines {
        // The image or a mask found the sky: what is left over the line is the scene.
        let sky_seen = matches!(found.method, SkyMethod::DepthAndImage | SkyMethod::Mask);
        lines.keep_beyond_reach_over_line(&mut found.beyond_reach, sky_seen);
    }
    let mut sky = found.sky;
    stats.sky_method = found.method;
    stats.sky_noise = found.noise.len();
    found.noise.iter().for_each(|&p| work[p] = f32::NAN);
    let guide = guides
        .image
        .map(|i| colour_guide::ColourGuide::new(i, opts.image_sky.max_step));
    if let Some(guide) = &guide {
        // Taken out of the scene beyond the reach, they stay NaN: holes.
        let scanned = scan_lines.is_some();
        let beyond = &mut found.beyond_reach;
        reach::take_out_reached_in_part(&work, &sky, beyond, guide, (w, h), scanned);
    }
    // Neither known nor a hole (as the sky) until the scene round it is filled.
    found
        .beyond_reach
        .iter()
        .for_each(|&p| work[p] = f32::INFINITY);
    for (p, _) in ego.iter().enumerate().filter(|(_, &e)| e) {
        sky[p] = false;
        work[p] = f32::INFINITY;
    }
    let t1 = Instant::now();

    if let Some(ground) = &opts.ground {
        stats.below_ground = ground::drop_below_ground(&mut work, &sky, (w, h), ground);
    }
    remove_far_outliers(&mut work, &sky, w, h, opts, &mut stats);
    remove_local_outliers(&mut work, &sky, w, h, opts, &mut stats);
    if let Some(lines) = &scan_lines {
        if let Some(guide) = &guide {
            stats.scan_unlike =
                scan::drop_points_unlike_their_colour(&mut work, &sky, guide, (w, h));
        }
        stats.scan_gaps = scan::fill_gaps(&mut work, &lines.gaps, &sky, guide.as_ref(), (w, h));
    }
    stats.r_max = max_known_outside(&work, &sky)
        .ok_or_else(|| no_range_outside_the_sky(&sky, &ego, (w, h)))?;
    let mut filled = vec![false; w * h];
    if opts.border_band_fraction > 0.0 {
        let r_min = min_known_outside(&work, &sky).unwrap_or(stats.r_max);
        let b = border::fill_borders(
            &mut work,
            &mut sky,
            &mut filled,
            (w, h),
            opts.border_band_fraction,
            (r_min, stats.r_max),
            guide.as_ref(),
        );
        (stats.border_filled, stats.border_sky, stats.border_islands) =
            (b.filled, b.sky, b.islands);
        if let Some(ground) = &opts.ground {
            stats.border_on_road = ground::bands_on_the_road(&mut work, &filled, (w, h), ground);
        }
    }
    let mut holes = holes::Holes {
        filled: &mut filled,
        sky: &mut sky,
        ego: &mut ego,
    };
    holes::fill_holes(
        &mut work,
        &mut holes,
        (w, h),
        guide.as_ref(),
        opts,
        &mut stats,
    )?;
    let mut beyond_reach = Grid::filled(w, h, false);
    let mut receding = Grid::filled(w, h, false);
    if !found.beyond_reach.is_empty() {
        let mask = beyond_reach.as_mut_slice();
        found.beyond_reach.iter().for_each(|&p| mask[p] = true);
        let s_max = (opts.sky_range_factor * f64::from(stats.r_max)) as f32;
        let held = reach::recede(
            &mut work,
            (&sky, mask),
            (w, h),
            (stats.r_max, s_max),
            guide.as_ref(),
        );
        let receding = receding.as_mut_slice();
        receding.copy_from_slice(mask);
        held.iter().for_each(|&p| receding[p] = false);
        stats.beyond_reach = found.beyond_reach.len();
    }
    for (v, _) in work.iter_mut().zip(&ego).filter(|(_, &e)| e) {
        *v = 0.0;
    }
    stats.ego_pixels = ego.iter().filter(|&&e| e).count();
    let t2 = Instant::now();

    let sky_bbox = assign_sky(&mut work, &sky, w, h, opts, &mut stats)?;
    stats.sky_known_pixels = (range.as_slice().iter().zip(&sky))
        .filter(|(v, &s)| s && v.is_finite())
        .count();
    let t3 = Instant::now();

    if let Some(bbox) = sky_bbox {
        let margin = margin::margin_pixels(&sky, w, h, bbox, opts.margin_px as f32);
        margin::jacobi(&mut work, w, h, &margin, opts.jacobi_sweeps());
        stats.margin_pixels = margin.len();
    }
    let t4 = Instant::now();

    stats.fill_ms = ms(t2 - t1);
    stats.sky_ms = ms(t1 - t0) + ms(t3 - t2);
    stats.margin_ms = ms(t4 - t3);
    stats.total_ms = ms(t4 - t0);
    Ok(Prepared {
        range: Grid::from_vec(w, h, work),
        sky: Grid::from_vec(w, h, sky),
        filled: Grid::from_vec(w, h, filled),
        beyond_reach,
        receding,
        stats,
    })
}

fn ms(d: std::time::Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// Each guide must have the range's size.
fn check_guide_sizes(range: &ScalarMap, guides: &Guides) -> Result<()> {
    let (w, h) = (range.width(), range.height());
    let sizes = [
        guides
            .image
            .map(|i| ("the colour image", i.width(), i.height())),
        guides
            .sky_mask
            .map(|m| ("the sky mask", m.width(), m.height())),
        guides
            .ego_mask
            .map(|m| ("the ego-vehicle mask", m.width(), m.height())),
    ];
    for (name, gw, gh) in sizes.into_iter().flatten() {
        if (gw, gh) != (w, h) {
            return Err(Error::size_mismatch(
                name,
                (gw, gh),
                "the range map",
                (w, h),
            ));
        }
    }
    Ok(())
}

/// Removes the far outliers among the known pixels outside the sky (see [`outliers`]).
fn remove_far_outliers(
    work: &mut [f32],
    sky: &[bool],
    w: usize,
    h: usize,
    opts: &PrepOptions,
    stats: &mut PrepStats,
) {
    stats.far_cut = outliers::far_cut(work, |i| !sky[i], opts.far_outlier_factor);
    if let Some(cut) = stats.far_cut {
        let min_patch =
            ((opts.far_patch_fraction * (w * h) as f64).ceil() as usize).max(MIN_FAR_PATCH);
        stats.far_outliers = outliers::remove_far(work, sky, w, h, cut, min_patch);
    }
}

/// Removes the local outliers among the known pixels outside the sky (see [`local`]).
fn remove_local_outliers(
    work: &mut [f32],
    sky: &[bool],
    w: usize,
    h: usize,
    opts: &PrepOptions,
    stats: &mut PrepStats,
) {
    if opts.local_outlier_factor == 0.0 {
        return;
    }
    let span = ((opts.local_outlier_span * w.max(h) as f64).round() as usize).max(MIN_LOCAL_SPAN);
    stats.local_outliers = local::remove_local(work, sky, w, h, opts.local_outlier_factor, span);
}

/// The smallest finite value outside the sky.
fn min_known_outside(work: &[f32], sky: &[bool]) -> Option<f32> {
    work.iter()
        .zip(sky)
        .filter(|(v, &s)| !s && v.is_finite())
        .map(|(&v, _)| v)
        .reduce(f32::min)
}

/// The largest finite value outside the sky.
fn max_known_outside(work: &[f32], sky: &[bool]) -> Option<f32> {
    work.iter()
        .zip(sky)
        .filter(|(v, &s)| !s && v.is_finite())
        .map(|(&v, _)| v)
        .reduce(f32::max)
}

/// Sets the sky pixels to `Smax` and counts them and their components; returns their
/// bounding box `[x_min, y_min, x_max, y_max]`, or `None` without sky.
fn assign_sky(
    work: &mut [f32],
    sky: &[bool],
    w: usize,
    h: usize,
    opts: &PrepOptions,
    stats: &mut PrepStats,
) -> Result<Option<[usize; 4]>> {
    stats.sky_pixels = sky.iter().filter(|&&s| s).count();
    if stats.sky_pixels == 0 {
        return Ok(None);
    }
    if stats.r_max <= 0.0 {
        return Err(Error::Prep(format!(
            "the maximum known range is {} but the sky range Smax = factor x Rmax needs Rmax > 0",
            stats.r_max
        )));
    }
    let s_max = (opts.sky_range_factor * f64::from(stats.r_max)) as f32;
    let mut bbox = [usize::MAX, usize::MAX, 0, 0];
    for (p, _) in sky.iter().enumerate().filter(|(_, &s)| s) {
        work[p] = s_max;
        let (x, y) = (p % w, p / w);
        bbox = [
            bbox[0].min(x),
            bbox[1].min(y),
            bbox[2].max(x),
            bbox[3].max(y),
        ];
    }
    stats.sky_components = components::label_mask(sky, w, h).list.len();
    stats.s_max = Some(s_max);
    Ok(Some(bbox))
}
