//! Command-line interface: argument definitions and the glue from arguments to the library.

mod args;
mod info;
mod prep;
mod render;

pub use args::Cli;
use args::Command;
use brume::egl::Platform;
use brume::{Renderer, Result};

/// Runs the chosen subcommand.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(a) => render::run(&a, cli.egl),
        Command::Info(a) => info::run(&a, cli.egl),
        Command::Prep(a) => prep::run(&a),
        Command::Bench(cmd) => {
            let mut renderer = open_renderer(cli.egl)?;
            brume::bench::run(&cmd, &mut renderer, &brume::io::demo::demo_image, &|p| {
                brume::io::image::load_linear_rgb(p)
            })
        }
    }
}

/// Opens the GL context the way every subcommand does.
fn open_renderer(egl: Option<Platform>) -> Result<Renderer> {
    let r = Renderer::new(egl)?;
    log::info!(
        "{} on {} via EGL {} ({})",
        r.caps().version,
        r.caps().renderer,
        r.caps().egl_platform,
        r.caps().egl_vendor
    );
    Ok(r)
}
