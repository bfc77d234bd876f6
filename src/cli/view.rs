//! `brume view`'s arguments checked before a window opens, and the viewer's default
//! source; the viewer itself (a window host) is `src/viewer`.

use super::args::{RenderArgs, ViewArgs, ViewSource};
use super::limits::{self, MAX_WINDOW_SIDE};
use brume::io::output;
use brume::Result;
use std::path::Path;

/// Checks every option before a window is asked for, so that a bad value is named even
/// with no display, and nothing is rendered for outputs that cannot be written: the
/// outputs' formats (PNG screenshot, JSON figures), that they are not inputs nor one file,
/// the window's size and the source's options.
pub fn check_args(args: &ViewArgs) -> Result<()> {
    if let Some(frames) = args.frames {
        limits::check_frames(frames)?;
    }
    if let Some(window) = &args.window {
        limits::parse_size("--window", window, MAX_WINDOW_SIDE)?;
    }
    let mut outputs: Vec<(&str, &Path)> = Vec::new();
    if let Some(path) = &args.screenshot {
        output::check_png_output(path, "--screenshot")?;
        outputs.push(("--screenshot", path));
    }
    if let Some(path) = &args.stats {
        output::check_output(path, "--stats", &["json"])?;
        outputs.push(("--stats", path));
    }
    let inputs = match &args.source {
        Some(ViewSource::Render(a)) => {
            super::options::check_options(a)?;
            super::photo_args::input_paths(a)
        }
        Some(ViewSource::Scene(a)) => {
            let (w, h) = limits::parse_image_size("--size", &a.size)?;
            limits::check_memory("--size", w, h, super::scene::SCENE_BYTES_PER_PIXEL)?;
            super::scene::camera_from_args(a).validate()?;
            // Both blurs' values are checked: the panel switches between them, so the
            // options of the one not chosen are taken, not refused as `brume scene` does.
            let (gauss, diffusion) = super::scene::blurs_from_args(a);
            gauss.validate()?;
            diffusion.validate()?;
            super::scene::input_paths(a)
        }
        None => Vec::new(),
    };
    super::refuse_overlaps(&outputs, &inputs)
}

/// `brume render`'s options with nothing given (the built-in demo and the default haze):
/// what the viewer shows when it is given no photo.
pub fn default_render_args() -> RenderArgs {
    use clap::{Args, FromArgMatches};
    let command = RenderArgs::augment_args(clap::Command::new("render"));
    let matches = command.get_matches_from(["render"]);
    RenderArgs::from_arg_matches(&matches).expect("the defaults parse")
}
