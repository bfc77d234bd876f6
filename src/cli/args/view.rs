//! `brume view`'s arguments.

use super::*;

/// `brume view`.
#[derive(Args, Clone, Debug)]
#[command(
    after_help = "Keys: S saves the frame as PNG, E as EXR (next to --save, numbered, \
never overwriting), R resets the parameters, Q or Escape quits.\n\n\
Examples:\n  brume view\n  brume view render --image photo.png --depth depth.png --ka 0.5\n  \
brume view scene --fog layered\n  brume view --frames 10 --screenshot shot.png --stats stats.json"
)]
pub struct ViewArgs {
    /// Render N frames, save --screenshot and --stats, and exit (N >= 1). Without it the
    /// window stays until closed.
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: Option<u32>,

    /// With --frames: the window's contents after the last frame, as PNG.
    #[arg(long, value_name = "PATH", requires = "frames")]
    pub screenshot: Option<PathBuf>,

    /// With --frames: per-frame GPU and wall-clock times, the image's place in the
    /// screenshot and the GL objects created after the first frame, as JSON.
    #[arg(long, value_name = "PATH", requires = "frames")]
    pub stats: Option<PathBuf>,

    /// Image scale: fit (to the window) or a factor of physical pixels per image pixel.
    #[arg(long, value_name = "fit|F", default_value = "fit", allow_hyphen_values = true, value_parser = parse_zoom)]
    pub zoom: Zoom,

    /// First window size in logical pixels [default: the panel and the image].
    #[arg(long, value_name = "WxH", allow_hyphen_values = true)]
    pub window: Option<String>,

    /// Where S and E save the frame (the extension is theirs).
    #[arg(long, value_name = "PATH", default_value = "brume-view.png")]
    pub save: PathBuf,

    /// What to show [default: the demo, as `brume render` renders it].
    #[command(subcommand)]
    pub source: Option<ViewSource>,
}

/// What `brume view` shows.
#[derive(clap::Subcommand, Clone, Debug)]
pub enum ViewSource {
    /// A photo with depth, or the demo, with `brume render`'s options (--out is ignored).
    Render(Box<RenderArgs>),
    /// brume's 3D scene, with `brume scene`'s options (--out, --frames are ignored).
    Scene(Box<SceneArgs>),
}

/// How big the viewer shows the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Zoom {
    /// As large as the window allows.
    Fit,
    /// Physical pixels per image pixel.
    Factor(f32),
}

fn parse_zoom(s: &str) -> Result<Zoom, String> {
    if s == "fit" {
        return Ok(Zoom::Fit);
    }
    match s.parse::<f32>() {
        Ok(f) if f.is_finite() && (0.05..=16.0).contains(&f) => Ok(Zoom::Factor(f)),
        _ => Err(format!(
            "expected `fit` or a factor in [0.05, 16], got `{s}`"
        )),
    }
}
