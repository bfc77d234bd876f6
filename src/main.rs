//! `brume`: add physically based haze to RGBD images on OpenGL ES 3.2 through EGL.

#[macro_use]
mod cli;
#[cfg(all(feature = "viewer", not(target_os = "android")))]
mod viewer;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    keep_freed_memory();
    let args = cli::Cli::try_parse().unwrap_or_else(|e| {
        let argv: Vec<String> = std::env::args_os()
            .map(|a| a.to_string_lossy().into_owned())
            .collect();
        cli::tips::explain_parse_error(e, &argv).exit()
    });
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

/// Has glibc's malloc keep the memory brume frees for its next allocations instead of
/// handing it back to the kernel. A photo's maps and images are tens to hundreds of MB;
/// by default glibc maps each afresh and unmaps it on free, and the kernel zeroes every
/// page again at its first touch (a fifth of a 12 MP render's CPU samples were the
/// kernel's `clear_page`). Measured in the README, *Freed memory is kept*: about 12 %
/// off a 12 MP render and a batch, for 5 % more peak memory. `MALLOC_MMAP_THRESHOLD_`
/// or `MALLOC_TRIM_THRESHOLD_` in the environment are left to decide.
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    for (variable, parameter) in [
        ("MALLOC_MMAP_THRESHOLD_", libc::M_MMAP_THRESHOLD),
        ("MALLOC_TRIM_THRESHOLD_", libc::M_TRIM_THRESHOLD),
    ] {
        if std::env::var_os(variable).is_none() {
            // SAFETY: before any thread is started; mallopt only sets glibc's thresholds
            // (it returns 0, and changes nothing, for a value it refuses).
            unsafe { libc::mallopt(parameter, libc::c_int::MAX) };
        }
    }
}

fn init_logging(verbose: u8) {
    let level = match verbose {
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    let env = env_logger::Env::default().default_filter_or(level);
    let mut builder = env_logger::Builder::from_env(env);
    // Through the writer that puts a line above a command's spinner; env_logger colours a
    // writer of its own only when told to, as it would stderr by itself.
    builder.target(env_logger::Target::Pipe(Box::new(cli::stages::LogWriter)));
    if std::env::var_os("RUST_LOG_STYLE").is_none() {
        use std::io::IsTerminal;
        let colour = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
        builder.write_style(if colour {
            env_logger::WriteStyle::Always
        } else {
            env_logger::WriteStyle::Never
        });
    }
    builder
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
