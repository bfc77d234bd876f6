//! `brume`: add physically based haze to RGBD images on OpenGL ES 3.2 through EGL.

#[macro_use]
mod cli;
#[cfg(all(feature = "viewer", not(target_os = "android")))]
mod viewer;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    init_logging(args.verbose);
    cli::remove_temporaries_on_signals();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            errln!("brume: error: {}", cli::name_flags(e));
            ExitCode::FAILURE
        }
    }
}

fn init_logging(verbose: u8) {
    let level = match verbose {
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or(level))
        .format(|buf, record| {
            use std::io::Write;
            let level = record.level();
            let style = buf.default_level_style(level);
            // The library's warnings name options as fields; here they are flags.
            let text = cli::flags_in(&record.args().to_string());
            writeln!(buf, "[{style}{level:<5}{style:#}] {text}")
        })
        .init();
}
