//! What the viewer shows and the controls that change it: a photo with depth (or the demo)
//! under paper 000's haze, a uniform blur or paper 002's aerial perspective, as
//! `brume render` renders it; or brume's procedural 3D scene under paper 001's distance
//! fog or paper 003's layered fog, as `brume scene` renders it. Each source derives its
//! medium and blur from the same options, with the same functions, as its command does,
//! so that the window shows what the command writes; the controls then edit the medium.

use crate::cli::aerial::{aerial_job, AerialJob};
use crate::cli::args::{BlurKind, FogKind, MediumKind, RenderArgs, SceneArgs};
use crate::cli::limits;
use crate::cli::photo_args as render_cmd;
use crate::cli::scene::{self as scene_cmd, SceneMedium};
use brume::atmosphere::AttenuationTable;
use brume::camera::{Camera, FrameInputs};
use brume::gpu::texture::{Filter, TexelFormat, Texture};
use brume::medium::haze::Haze;
use brume::medium::{HeightProfile, Medium, UniformBlur};
use brume::raster::{RgbImage, RgbaImage, ScalarMap};
use brume::scene::SceneRenderer;
use brume::{Blur, Encoding, FogBlur, GaussBlur, Input, Output, Pipeline, Precision, Result};
use brume::{Error, Scheme};
use egui::Ui;
use std::sync::Arc;

/// The GPU figures of one frame.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FrameTimes {
    /// Pass names, in order.
    pub pass_names: Vec<String>,
    /// Per-pass times (ms).
    pub pass_ms: Vec<f64>,
    /// Their sum (ms).
    pub total_ms: f64,
    /// `gpu-timer` or `wall`.
    pub clock: &'static str,
}

/// What the window shows.
pub enum Source {
    /// A photo with depth, or the built-in demo.
    Photo(Box<Photo>),
    /// brume's procedural scene.
    Scene(Box<SceneView>),
}

impl Source {
    /// The frame size (px).
    pub fn size(&self) -> (usize, usize) {
        match self {
            Source::Photo(p) => (p.width, p.height),
            Source::Scene(s) => (s.width, s.height),
        }
    }

    /// Whether frames change with time (the scene's water and noise).
    pub fn animated(&self) -> bool {
        match self {
            Source::Photo(_) => false,
            Source::Scene(s) => s.animate,
        }
    }

    /// Renders the frame at `time` (s) into `target` (RGBA8, the source's size) as
    /// sRGB-encoded values, ready to show.
    pub fn render(
        &mut self,
        pipeline: &mut Pipeline,
        target: &Texture,
        time: f64,
    ) -> Result<FrameTimes> {
        let output = Output::Texture {
            texture: target.raw(),
            encoding: Encoding::Srgb,
        };
        match self {
            Source::Photo(p) => p.render(pipeline, &output),
            Source::Scene(s) => s.render(pipeline, &output, time),
        }
    }

    /// The photo's colour profile and EXIF, which a saved frame carries (none for a
    /// scene).
    pub fn metadata(&self) -> brume::io::metadata::PhotoMetadata {
        match self {
            Source::Photo(p) => p.metadata.clone(),
            Source::Scene(_) => Default::default(),
        }
    }

    /// Renders the frame at `time` in float and reads it back, top row first.
    pub fn render_to_image(&mut self, pipeline: &mut Pipeline, time: f64) -> Result<RgbaImage> {
        match self {
            Source::Photo(p) => {
                let (medium, blur) = p.look.medium_and_blur();
                Ok(pipeline.fog_to_image(&p.input(), medium, &blur)?.1)
            }
            Source::Scene(s) => s.render_to_image(pipeline, time),
        }
    }

    /// The controls of this source; true when something changed.
    pub fn controls(&mut self, ui: &mut Ui) -> bool {
        match self {
            Source::Photo(p) => p.controls(ui),
            Source::Scene(s) => s.controls(ui),
        }
    }

    /// Back to the parameters the viewer started with.
    pub fn reset(&mut self) {
        match self {
            Source::Photo(p) => p.look = p.initial.clone(),
            Source::Scene(s) => s.reset(),
        }
    }

    /// A one-line description for the window title and the panel.
    pub fn describe(&self) -> String {
        match self {
            Source::Photo(p) => format!("{} ({}x{})", p.name, p.width, p.height),
            Source::Scene(s) => format!("brume scene ({}x{})", s.width, s.height),
        }
    }
}

/// A photo with depth and the medium on it.
pub struct Photo {
    name: String,
    metadata: brume::io::metadata::PhotoMetadata,
    width: usize,
    height: usize,
    colour: Texture,
    depth: Texture,
    look: PhotoLook,
    initial: PhotoLook,
}

/// The medium of a photo and its blur.
#[derive(Clone)]
enum PhotoLook {
    /// Paper 000's haze, or a uniform blur when `uniform` is on.
    Haze {
        haze: Haze,
        uniform: Option<UniformBlur>,
        blur: Blur,
    },
    /// Paper 002's aerial perspective; the table is rebuilt when `turbidity` or
    /// `altitude` move.
    Aerial {
        medium: brume::medium::AerialPerspective,
        sensitivity: Arc<brume::atmosphere::Sensitivity>,
        turbidity: f64,
        altitude: f64,
        max_distance_m: f64,
        blur: Blur,
    },
}

impl PhotoLook {
    fn medium_and_blur(&self) -> (&dyn Medium, FogBlur) {
        match self {
            PhotoLook::Haze {
                haze,
                uniform,
                blur,
            } => {
                let medium: &dyn Medium = match uniform {
                    Some(u) => u,
                    None => haze,
                };
                (medium, FogBlur::Diffusion(*blur))
            }
            PhotoLook::Aerial { medium, blur, .. } => {
                let fog_blur = if medium.lambda == 0.0 {
                    FogBlur::None
                } else {
                    FogBlur::Diffusion(*blur)
                };
                (medium, fog_blur)
            }
        }
    }
}

impl Photo {
    /// The photo `brume render ARGS` would render, uploaded to `gl`.
    pub fn load(args: &RenderArgs, gl: &Arc<glow::Context>) -> Result<Self> {
        let fog = render_cmd::fog_options(args)?;
        let mut scene = render_cmd::load_scene(args)?;
        let mut prep = render_cmd::preprocess(args, &scene)?;
        // Once, at load, on the window's context: the GPU passes `brume render` runs, so
        // the window shows its range (their f64 CPU references, which the viewer ran
        // before, took 570 against 321 ms on llvmpipe for a 2048x1024 photo with a depth
        // map 4x smaller). The renderer is the load's alone: its programs and textures
        // are freed with it.
        let mut refiner = brume::Renderer::new(Arc::clone(gl))?;
        refiner.set_timing(brume::Timing::Off);
        crate::cli::refine::refine_scene(args, &mut scene, &mut prep, &mut refiner)?;
        drop(refiner);
        let (image, depth, look) = if args.medium == MediumKind::Aerial {
            let job = aerial_job(args, &scene, &prep)?;
            let look = aerial_look(&job);
            (job.photo.image, job.photo.range, look)
        } else {
            let (medium_range, _) = brume::photo::medium_range(&fog.extinction, &prep)?;
            let look = PhotoLook::Haze {
                haze: fog.haze(prep.airlight)?,
                uniform: args.uniform_sigma.map(UniformBlur::new),
                blur: fog.blur,
            };
            (scene.image, medium_range, look)
        };
        let (colour, depth) = upload(gl, &image, &depth)?;
        Ok(Photo {
            name: scene.image_name,
            metadata: scene.metadata,
            width: image.width(),
            height: image.height(),
            colour,
            depth,
            initial: look.clone(),
            look,
        })
    }

    fn input(&self) -> Input {
        Input {
            colour: self.colour.raw(),
            colour_encoding: Encoding::Linear,
            depth: self.depth.raw(),
            width: self.width,
            height: self.height,
            frame: FrameInputs::default(),
        }
    }

    fn render(&mut self, pipeline: &mut Pipeline, output: &Output) -> Result<FrameTimes> {
        let input = self.input();
        let (medium, fog_blur) = self.look.medium_and_blur();
        let frame = pipeline.fog(&input, medium, &fog_blur, output)?;
        Ok(times(&frame))
    }

    fn controls(&mut self, ui: &mut Ui) -> bool {
        let mut changed = false;
        match &mut self.look {
            PhotoLook::Haze {
                haze,
                uniform,
                blur,
            } => {
                ui.heading("Haze (paper 000)");
                let mut on = uniform.is_some();
                changed |= ui.checkbox(&mut on, "uniform blur instead").changed();
                if on != uniform.is_some() {
                    *uniform = on.then(|| UniformBlur::new(4.0_f64.max(blur.sigma0)));
                }
                if let Some(u) = uniform {
                    changed |= slider(ui, &mut u.sigma, blur.sigma0..=32.0, "σ (px)");
                } else {
                    changed |= slider(ui, &mut haze.ka, 0.0..=4.0, "κa absorption");
                    changed |= slider(ui, &mut haze.ks, 0.0..=4.0, "κs scattering");
                    changed |= slider(ui, &mut haze.lambda, 0.0..=32.0, "λ blur (px)");
                    changed |= rgb_sliders(ui, "airlight (linear)", &mut haze.airlight, 0.0..=1.0);
                    let mut tint = haze.tint.map(|t| t as f32);
                    if rgb_sliders(ui, "tint (× κ per channel)", &mut tint, 0.0..=3.0) {
                        haze.tint = tint.map(f64::from);
                        changed = true;
                    }
                }
                changed |= diffusion_controls(ui, blur);
            }
            PhotoLook::Aerial {
                medium,
                sensitivity,
                turbidity,
                altitude,
                max_distance_m,
                blur,
            } => {
                ui.heading("Aerial perspective (paper 002)");
                let table_moved = slider(ui, turbidity, 1.7..=20.0, "turbidity T")
                    | slider(ui, altitude, 0.0..=4000.0, "altitude (m)");
                if table_moved {
                    match AttenuationTable::new(sensitivity, *turbidity, *altitude, *max_distance_m)
                    {
                        Ok(t) => medium.table = Arc::new(t),
                        Err(e) => log::warn!("{e}"),
                    }
                    changed = true;
                }
                changed |= slider(
                    ui,
                    &mut medium.metres_per_unit,
                    0.1..=100.0,
                    "metres per unit",
                );
                changed |= slider(ui, &mut medium.camera.pitch_deg, -30.0..=30.0, "pitch (°)");
                changed |= slider(ui, &mut medium.lambda, 0.0..=32.0, "λ blur (px, 0: none)");
                changed |= rgb_sliders(
                    ui,
                    "horizon light (linear)",
                    &mut medium.horizon_light,
                    0.0..=1.0,
                );
                changed |= diffusion_controls(ui, blur);
            }
        }
        changed
    }
}

fn aerial_look(job: &AerialJob) -> PhotoLook {
    let m = &job.look.medium;
    PhotoLook::Aerial {
        medium: m.clone(),
        sensitivity: Arc::new(job.look.sensitivity.clone()),
        turbidity: m.table.turbidity(),
        altitude: m.table.altitude_m(),
        max_distance_m: m.table.max_distance_m(),
        blur: job.photo.blur,
    }
}

/// The photo's colour (RGB32F) and depth (R32F) textures, bottom row first as GL has them.
fn upload(
    gl: &Arc<glow::Context>,
    image: &RgbImage,
    depth: &ScalarMap,
) -> Result<(Texture, Texture)> {
    let (w, h) = (image.width(), image.height());
    let colour = Texture::new(gl, w, h, TexelFormat::Rgb32F, Filter::Nearest, None)?;
    colour.upload_flipped(image.as_slice().as_flattened());
    let range = Texture::new(gl, w, h, TexelFormat::R32F, Filter::Nearest, None)?;
    range.upload_flipped(depth.as_slice());
    Ok((colour, range))
}

fn times(frame: &brume::Frame) -> FrameTimes {
    FrameTimes {
        pass_names: frame.pass_names(),
        pass_ms: frame.times.pass_ms.clone(),
        total_ms: frame.times.total_ms,
        clock: frame.times.clock.name(),
    }
}

/// brume's procedural scene and its fog.
pub struct SceneView {
    renderer: SceneRenderer,
    args: SceneArgs,
    width: usize,
    height: usize,
    camera: Camera,
    fog: FogKind,
    distance: SceneMedium,
    layered: SceneMedium,
    blur: BlurKind,
    gauss: GaussBlur,
    diffusion: Blur,
    /// The medium of `--fog none`: τ = 1, no blur.
    clear: UniformBlur,
    animate: bool,
}

impl SceneView {
    /// The scene `brume scene ARGS` would render, on `gl`.
    pub fn new(args: &SceneArgs, gl: &Arc<glow::Context>) -> Result<Self> {
        let (width, height) = limits::parse_image_size("--size", &args.size)?;
        let camera = scene_cmd::camera_from_args(args);
        camera.validate()?;
        let renderer = SceneRenderer::new(Arc::clone(gl))?;
        let sun = renderer.scene().sun_direction;
        let (distance, layered) = scene_media(args, camera, sun)?;
        let (gauss, diffusion) = scene_cmd::blurs_from_args(args);
        Ok(SceneView {
            renderer,
            args: args.clone(),
            width,
            height,
            camera,
            fog: args.fog,
            distance,
            layered,
            blur: args.blur,
            gauss,
            diffusion,
            clear: UniformBlur::new(1.0),
            animate: true,
        })
    }

    /// Back to the options' camera, fogs and blur.
    fn reset(&mut self) {
        let camera = scene_cmd::camera_from_args(&self.args);
        let sun = self.renderer.scene().sun_direction;
        // The options were accepted at start-up: building from them again cannot fail.
        if let Ok(media) = scene_media(&self.args, camera, sun) {
            (self.distance, self.layered) = media;
        }
        (self.gauss, self.diffusion) = scene_cmd::blurs_from_args(&self.args);
        self.camera = camera;
        self.fog = self.args.fog;
        self.blur = self.args.blur;
    }

    fn fog_blur(&self) -> FogBlur {
        match self.blur {
            BlurKind::None => FogBlur::None,
            BlurKind::GaussSingle => FogBlur::GaussSingle(self.gauss),
            BlurKind::GaussSeparate => FogBlur::GaussSeparate(self.gauss),
            BlurKind::Diffusion => FogBlur::Diffusion(self.diffusion),
        }
    }

    /// The fog in use and its blur. Without fog: a medium that leaves the frame as it is
    /// (τ = 1) through the fog pass, which also encodes it for the display target. The
    /// same media serve every frame: the camera and the time come with the frame's input.
    fn medium(&self) -> (&dyn Medium, FogBlur) {
        let blur = self.fog_blur();
        let m = match self.fog {
            FogKind::None => return (&self.clear, FogBlur::None),
            FogKind::Distance => &self.distance,
            FogKind::Layered => &self.layered,
        };
        (m.medium(), blur)
    }

    /// Draws the scene at `time` with the viewer's camera: the input of the fog, with
    /// that camera and time.
    fn draw(&mut self, time: f64) -> Result<Input> {
        let frame = self
            .renderer
            .render(&self.camera, self.width, self.height, time)?;
        Ok(Input {
            colour: frame.colour,
            colour_encoding: Encoding::Linear,
            depth: frame.depth,
            width: self.width,
            height: self.height,
            frame: FrameInputs::new(self.camera, time),
        })
    }

    fn render(
        &mut self,
        pipeline: &mut Pipeline,
        output: &Output,
        time: f64,
    ) -> Result<FrameTimes> {
        let input = self.draw(time)?;
        let (medium, blur) = self.medium();
        let frame = pipeline.fog(&input, medium, &blur, output)?;
        Ok(times(&frame))
    }

    fn render_to_image(&mut self, pipeline: &mut Pipeline, time: f64) -> Result<RgbaImage> {
        let input = self.draw(time)?;
        let (medium, blur) = self.medium();
        Ok(pipeline.fog_to_image(&input, medium, &blur)?.1)
    }

    fn controls(&mut self, ui: &mut Ui) -> bool {
        let mut changed = false;
        ui.heading("Camera");
        changed |= slider(ui, &mut self.camera.yaw_deg, -180.0..=180.0, "yaw (°)");
        changed |= slider(ui, &mut self.camera.pitch_deg, -60.0..=60.0, "pitch (°)");
        changed |= ui
            .checkbox(&mut self.animate, "animate (water, noise)")
            .changed();
        ui.separator();
        let fog = self.fog;
        egui::ComboBox::from_label("fog")
            .selected_text(fog_name(self.fog))
            .show_ui(ui, |ui| {
                for f in [FogKind::Distance, FogKind::Layered, FogKind::None] {
                    ui.selectable_value(&mut self.fog, f, fog_name(f));
                }
            });
        changed |= fog != self.fog;
        match self.fog {
            FogKind::Distance => changed |= distance_controls(ui, &mut self.distance),
            FogKind::Layered => changed |= layered_controls(ui, &mut self.layered),
            FogKind::None => {}
        }
        ui.separator();
        let blur = self.blur;
        egui::ComboBox::from_label("blur")
            .selected_text(blur_name(self.blur))
            .show_ui(ui, |ui| {
                for b in [
                    BlurKind::Diffusion,
                    BlurKind::GaussSingle,
                    BlurKind::GaussSeparate,
                    BlurKind::None,
                ] {
                    ui.selectable_value(&mut self.blur, b, blur_name(b));
                }
            });
        changed |= blur != self.blur;
        match self.blur {
            BlurKind::Diffusion => changed |= diffusion_controls(ui, &mut self.diffusion),
            BlurKind::GaussSingle | BlurKind::GaussSeparate => {
                let g = &mut self.gauss;
                changed |= slider(ui, &mut g.distance, 1.0..=1000.0, "blur distance (m)");
                changed |= slider(ui, &mut g.falloff, 0.1..=4.0, "blur falloff");
                changed |= slider(ui, &mut g.maximum, 0.0..=1.0, "blur maximum");
                changed |= precision_control(ui, &mut g.precision);
            }
            BlurKind::None => {}
        }
        changed
    }
}

/// The distance and the layered fog the options describe (whichever `--fog` says), so
/// that the viewer can switch between them.
fn scene_media(
    args: &SceneArgs,
    camera: Camera,
    sun: [f64; 3],
) -> Result<(SceneMedium, SceneMedium)> {
    let medium = |fog| -> Result<SceneMedium> {
        let mut a = args.clone();
        a.fog = fog;
        scene_cmd::medium_from_args(&a, camera, sun)?
            .ok_or_else(|| Error::invalid("--fog", "none", "a fog"))
    };
    Ok((medium(FogKind::Distance)?, medium(FogKind::Layered)?))
}

fn distance_controls(ui: &mut Ui, m: &mut SceneMedium) -> bool {
    let SceneMedium::Distance(f) = m else {
        return false;
    };
    ui.label("Distance fog (paper 001)");
    let mut c = false;
    c |= slider(ui, &mut f.start_distance, 0.0..=500.0, "start (m)");
    c |= slider(ui, &mut f.distance, 10.0..=3000.0, "distance (m)");
    c |= slider(ui, &mut f.exponent, 0.1..=8.0, "exponent");
    c |= slider(ui, &mut f.max_density, 0.0..=1.0, "max density");
    c |= slider(ui, &mut f.scatter_start, 0.0..=500.0, "scatter start (m)");
    c |= slider(ui, &mut f.scatter_exponent, 1.0..=64.0, "scatter exponent");
    if let Some(noise) = &mut f.noise {
        c |= slider(ui, &mut noise.colour_strength, 0.0..=1.0, "noise on colour");
    }
    c |= slider(ui, &mut f.lambda, 0.0..=32.0, "λ blur (px)");
    c |= rgb_sliders(ui, "fog colour (linear)", &mut f.colour, 0.0..=1.0);
    c
}

fn layered_controls(ui: &mut Ui, m: &mut SceneMedium) -> bool {
    let SceneMedium::Layered(f) = m else {
        return false;
    };
    ui.label("Layered fog (paper 003)");
    let mut c = false;
    match &mut f.profile {
        HeightProfile::Exponential {
            density,
            base,
            scale_height,
        } => {
            c |= slider(ui, density, 0.0..=0.2, "density (1/m)");
            c |= slider(ui, base, -20.0..=100.0, "base (m)");
            c |= slider(ui, scale_height, 0.5..=200.0, "scale height (m)");
        }
        HeightProfile::SineBand {
            density,
            base,
            thickness,
        } => {
            c |= slider(ui, density, 0.0..=0.2, "density (1/m)");
            c |= slider(ui, base, -20.0..=100.0, "base (m)");
            c |= slider(ui, thickness, 0.5..=200.0, "thickness (m)");
        }
        HeightProfile::LinearRamp {
            density,
            floor,
            top,
        } => {
            c |= slider(ui, density, 0.0..=0.2, "density (1/m)");
            c |= slider(ui, floor, -20.0..=100.0, "floor (m)");
            c |= slider(ui, top, -10.0..=200.0, "top (m)");
        }
        HeightProfile::Table(table) => {
            // The table comes from --density-csv; its rows are not edited here.
            let h = table.heights();
            ui.label(format!(
                "table: {} rows, {} to {} m, κ ≤ {:.3e} /m",
                h.len(),
                h[0],
                h[h.len() - 1],
                table.max_density()
            ));
        }
    }
    c |= slider(ui, &mut f.albedo, 0.0..=1.0, "albedo");
    c |= slider(ui, &mut f.lambda, 0.0..=32.0, "λ blur (px)");
    c |= rgb_sliders(ui, "fog colour (linear)", &mut f.colour, 0.0..=1.0);
    c
}

/// Scheme, precision and the diffusion's σ0 and ρmax.
fn diffusion_controls(ui: &mut Ui, blur: &mut Blur) -> bool {
    ui.separator();
    ui.label("Diffusion");
    let scheme = blur.scheme;
    egui::ComboBox::from_label("scheme")
        .selected_text(blur.scheme.to_string())
        .show_ui(ui, |ui| {
            for s in [Scheme::Matched, Scheme::Invariant, Scheme::Euler] {
                ui.selectable_value(&mut blur.scheme, s, s.to_string());
            }
        });
    let mut c = scheme != blur.scheme;
    c |= precision_control(ui, &mut blur.precision);
    c |= slider(ui, &mut blur.sigma0, 0.25..=4.0, "σ0 (px)");
    c |= slider(ui, &mut blur.rho_max, 0.01..=0.25, "ρmax");
    c
}

fn precision_control(ui: &mut Ui, precision: &mut Precision) -> bool {
    let before = *precision;
    ui.horizontal(|ui| {
        ui.label("precision");
        for p in Precision::ALL {
            ui.radio_value(precision, p, p.name());
        }
    });
    before != *precision
}

fn slider(ui: &mut Ui, value: &mut f64, range: std::ops::RangeInclusive<f64>, text: &str) -> bool {
    ui.add(
        egui::Slider::new(value, range)
            .text(text)
            .clamping(egui::SliderClamping::Never),
    )
    .changed()
}

fn rgb_sliders(
    ui: &mut Ui,
    label: &str,
    rgb: &mut [f32; 3],
    range: std::ops::RangeInclusive<f32>,
) -> bool {
    let mut changed = false;
    egui::CollapsingHeader::new(label).show(ui, |ui| {
        for (v, name) in rgb.iter_mut().zip(["R", "G", "B"]) {
            changed |= ui
                .add(egui::Slider::new(v, range.clone()).text(name))
                .changed();
        }
    });
    changed
}

fn fog_name(f: FogKind) -> &'static str {
    match f {
        FogKind::Distance => "distance (paper 001)",
        FogKind::Layered => "layered (paper 003)",
        FogKind::None => "none",
    }
}

fn blur_name(b: BlurKind) -> &'static str {
    match b {
        BlurKind::Diffusion => "diffusion (paper 000)",
        BlurKind::GaussSingle => "5x5 Gaussian, one pass",
        BlurKind::GaussSeparate => "5x5 Gaussian, two passes",
        BlurKind::None => "none",
    }
}
