//! Command-line interface: argument definitions and the glue from arguments to the library.

mod args;
mod bench;
mod info;
mod prep;
mod render;

pub use args::{Cli, Command};
use brume::egl::Platform;
use brume::{Error, Headless, Result};
use clap::CommandFactory;

/// Runs the chosen subcommand.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(a) => render::run(&a, cli.egl),
        Command::Info(a) => info::run(&a, cli.egl),
        Command::Prep(a) => prep::run(&a),
        Command::Bench(cmd) => {
            let mut headless = open_renderer(cli.egl)?;
            bench::run(
                &cmd,
                headless.renderer()?,
                &brume::io::demo::demo_image,
                &|p| brume::io::image::load_linear_rgb(p),
            )
        }
    }
}

/// Opens the GL context the way every subcommand does.
fn open_renderer(egl: Option<Platform>) -> Result<Headless> {
    let r = Headless::new(egl)?;
    let caps = r.caps();
    let egl = caps.egl.as_ref();
    log::info!(
        "{} on {} via EGL {} ({})",
        caps.version,
        caps.renderer,
        egl.map_or("?", |e| e.platform.as_str()),
        egl.map_or("?", |e| e.vendor.as_str()),
    );
    Ok(r)
}

/// Library fields whose flag is not the field's name with dashes.
const FLAG_ALIASES: [(&str, &str); 3] = [
    ("sky_range_factor", "--sky-factor"),
    ("min_area_fraction", "--sky-min-area"),
    ("margin_px", "--margin"),
];

/// The library names a bad parameter as its field (`rho_max`); on the command line it is
/// a flag (`--rho-max`). Names that are a flag of `brume` become that flag; others (a
/// file's field, `range map`) are kept.
pub fn name_flags(e: Error) -> Error {
    match e {
        Error::InvalidParameter {
            name,
            value,
            expected,
        } => {
            let flag = match FLAG_ALIASES.iter().find(|(field, _)| *field == name) {
                Some((_, flag)) => flag.to_string(),
                None => format!("--{}", name.replace('_', "-")),
            };
            let name = if is_flag(&flag) { flag } else { name };
            Error::InvalidParameter {
                name,
                value,
                expected,
            }
        }
        other => other,
    }
}

/// Whether `flag` (`--name`) is a long option of any `brume` command.
fn is_flag(flag: &str) -> bool {
    fn walk(cmd: &clap::Command, flag: &str) -> bool {
        cmd.get_arguments()
            .filter_map(|a| a.get_long())
            .any(|long| flag.strip_prefix("--") == Some(long))
            || cmd.get_subcommands().any(|sub| walk(sub, flag))
    }
    walk(&Cli::command(), flag)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn library_names_become_flags() {
        let cases = [
            ("ka", "--ka"),
            ("rho_max", "--rho-max"),
            ("uniform_sigma", "--uniform-sigma"),
            ("sigmas", "--sigmas"),
            ("depth_scale", "--depth-scale"),
            ("range map", "range map"),
            ("sigma_max", "sigma_max"),
            ("sky_range_factor", "--sky-factor"),
            ("margin_px", "--margin"),
        ];
        for (name, shown) in cases {
            let e = name_flags(Error::invalid(name, 1, "x"));
            let Error::InvalidParameter { name, .. } = e else {
                panic!("kind changed")
            };
            assert_eq!(name, shown);
        }
    }
}
