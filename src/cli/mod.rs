//! Command-line interface: argument definitions and the glue from arguments to the library.

/// `outln!` for the program's reports: a closed stdout (`brume … | head -c 0`) ends
/// nothing and panics nowhere; the rest of the work, and its outputs, go on as if the
/// reader had kept reading, as `cat` into a closed pipe would not, but the outputs matter
/// more than the report.
macro_rules! outln {
    ($($t:tt)*) => { $crate::cli::write_stream($crate::cli::Stream::Out, format_args!("{}\n", format_args!($($t)*))) };
}
/// `print!` with [`outln!`]'s tolerance of a closed stdout.
macro_rules! out {
    ($($t:tt)*) => { $crate::cli::write_stream($crate::cli::Stream::Out, format_args!($($t)*)) };
}
/// `errln!` that does not panic when stderr is a closed pipe.
macro_rules! errln {
    ($($t:tt)*) => { $crate::cli::write_stream($crate::cli::Stream::Err, format_args!("{}\n", format_args!($($t)*))) };
}
/// `err!` with [`errln!`]'s tolerance.
macro_rules! err {
    ($($t:tt)*) => { $crate::cli::write_stream($crate::cli::Stream::Err, format_args!($($t)*)) };
}

pub(crate) mod aerial;
pub(crate) mod args;
mod batch;
mod bench;
mod capture;
mod compare;
mod compat;
mod info;
mod inputs;
pub(crate) mod limits;
pub(crate) mod options;
pub(crate) mod photo_args;
mod prep;
pub(crate) mod refine;
pub(crate) mod render;
pub(crate) mod scene;
mod sky;
pub(crate) mod stages;
mod sun;
pub(crate) mod tips;
#[cfg(all(feature = "viewer", not(target_os = "android")))]
pub(crate) mod view;

pub use args::{Cli, Command};
use brume::egl::Platform;
use brume::io::output::{self, Outputs};
use brume::{Error, Headless, Result};
use clap::CommandFactory;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Runs the chosen subcommand.
pub fn run(cli: Cli) -> Result<()> {
    if let Some(platform) = cli.egl.filter(|_| !opens_headless_context(&cli.command)) {
        return Err(Error::invalid(
            "--egl",
            platform,
            "a command that opens brume's headless GL context with it (render, scene, batch, \
             info, bench): this one runs on the CPU or in a window of its own",
        ));
    }
    match cli.command {
        Command::Render(a) => render::run(&a, cli.egl),
        Command::Scene(a) => scene::run(&a, cli.egl),
        Command::Compare(a) => compare::run(&a),
        Command::Info(a) => info::run(&a, cli.egl),
        Command::Batch(a) => {
            let plan = batch::plan(&a)?;
            if a.dry_run {
                return batch::dry_run(&plan, &a);
            }
            let mut headless = open_renderer(cli.egl)?;
            batch::run(plan, headless.renderer()?)
        }
        #[cfg(all(feature = "viewer", not(target_os = "android")))]
        Command::View(a) => {
            view::check_args(&a)?;
            crate::viewer::run(a)
        }
        Command::Prep(a) => prep::run(&a),
        Command::Sky(a) => sky::run_sky(&a),
        Command::Turbidity(a) => sky::run_turbidity(&a),
        Command::Sun(a) => sun::run_sun(&a),
        Command::Completions(a) => print_completions(a.shell),
        // CPU only: no GL context to open.
        Command::Bench(bench::BenchCommand::Turbidity(a)) => bench::run_turbidity(&a),
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

/// Whether `command` opens brume's headless EGL context, which `--egl` chooses.
fn opens_headless_context(command: &Command) -> bool {
    match command {
        Command::Render(_) | Command::Scene(_) | Command::Batch(_) | Command::Info(_) => true,
        Command::Bench(bench::BenchCommand::Turbidity(_)) => false,
        Command::Bench(_) => true,
        #[cfg(all(feature = "viewer", not(target_os = "android")))]
        Command::View(_) => false,
        Command::Compare(_)
        | Command::Prep(_)
        | Command::Sky(_)
        | Command::Turbidity(_)
        | Command::Sun(_)
        | Command::Completions(_) => false,
    }
}

/// Prints `shell`'s completion script for the `brume` program on stdout. Unlike a
/// report's, a failed write is an error: the script is redirected into a file the shell
/// reads, and half of one must not pass for done (a reader that left, `| head`, is not).
fn print_completions(shell: clap_complete::Shell) -> Result<()> {
    use std::io::Write;
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut Cli::command(), "brume", &mut script);
    let mut stdout = std::io::stdout().lock();
    match stdout.write_all(&script).and_then(|()| stdout.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(Error::io("standard output", e))
        }
        _ => Ok(()),
    }
}

/// `report`, a JSON object, with the build of brume that made it (`brume`: the version,
/// `sources`: the fingerprint of its sources, [`brume::SOURCES`]): figures and outputs of
/// two builds of one version can differ.
pub fn stamped(mut report: serde_json::Value) -> serde_json::Value {
    if let Some(fields) = report.as_object_mut() {
        fields.insert("brume".into(), brume::VERSION.into());
        fields.insert("sources".into(), brume::SOURCES.into());
    }
    report
}

/// One of the program's standard streams.
#[derive(Clone, Copy)]
pub enum Stream {
    /// stdout: reports, JSON.
    Out,
    /// stderr: errors, warnings, tables beside a JSON report.
    Err,
}

/// Writes to stdout or stderr, ignoring a reader that went away (EPIPE): what was to be
/// printed is lost, nothing else is. Other write errors (a full disk behind a
/// redirection) are said once on stderr.
pub fn write_stream(stream: Stream, text: std::fmt::Arguments) {
    use std::io::Write;
    stages::clear_shown();
    let result = match stream {
        Stream::Out => std::io::stdout().lock().write_fmt(text),
        Stream::Err => std::io::stderr().lock().write_fmt(text),
    };
    if let Err(e) = result {
        static SAID: std::sync::Once = std::sync::Once::new();
        if e.kind() != std::io::ErrorKind::BrokenPipe {
            SAID.call_once(|| {
                let _ = writeln!(
                    std::io::stderr(),
                    "brume: warning: cannot write the report: {e}"
                );
            });
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
const FLAG_ALIASES: [(&str, &str); 16] = [
    ("local_outlier_factor", "--local-outliers"),
    ("latitude_deg", "--latitude"),
    ("longitude_deg", "--longitude"),
    ("pressure_hpa", "--pressure"),
    ("temperature_c", "--temperature"),
    ("delta_t_s", "--delta-t"),
    ("heading_deg", "--heading"),
    ("sky_range_factor", "--sky-factor"),
    ("min_area_fraction", "--sky-min-area"),
    ("margin_px", "--margin"),
    ("fov_y_deg", "--fov"),
    ("focal_px", "--focal"),
    ("pitch_deg", "--pitch"),
    ("yaw_deg", "--yaw"),
    ("altitude_m", "--altitude"),
    ("horizon_zenith_deg", "--horizon-zenith"),
];
/// Refuses, before any work, an output that is one of the inputs (nothing a user gave us
/// is overwritten) and two outputs that are one file (neither would survive). `outputs`
/// pairs each option with its path. Links count: an output through a symbolic or hard
/// link to an input is that input.
pub fn refuse_overlaps(outputs: &[(&str, &Path)], inputs: &[PathBuf]) -> Result<()> {
    for (i, &(option, out)) in outputs.iter().enumerate() {
        if let Some(input) = inputs.iter().find(|i| output::same_destination(out, i)) {
            return Err(Error::invalid(
                option,
                out.display(),
                format!("a path other than the input {}", input.display()),
            ));
        }
        let earlier = &outputs[..i];
        if let Some((other, _)) = earlier
            .iter()
            .find(|(_, o)| output::same_destination(o, out))
        {
            return Err(Error::invalid(
                option,
                out.display(),
                format!("a file other than the one {other} names"),
            ));
        }
    }
    Ok(())
}

/// Renames a command's staged outputs into place, all together.
///
/// `BRUME_TEST_HOLD_OUTPUTS=SECONDS` is a hook for the interrupt tests: it announces the
/// staged files on stderr and waits before renaming, so that a test can signal a process
/// that is known to hold temporaries.
pub(crate) fn commit(outputs: Outputs) -> Result<()> {
    hold_staged_outputs(&outputs);
    outputs.commit()
}

/// The hook of [`commit`], for outputs the library commits itself (`brume batch`).
fn hold_staged_outputs(outputs: &Outputs) {
    let hold = std::env::var("BRUME_TEST_HOLD_OUTPUTS").ok();
    if let Some(seconds) = hold.and_then(|s| s.parse::<f64>().ok()) {
        errln!(
            "brume: holding {} staged outputs",
            outputs.destinations().count()
        );
        std::thread::sleep(Duration::from_secs_f64(seconds.clamp(0.0, 600.0)));
    }
}

/// On SIGINT, SIGTERM or SIGHUP, removes the temporary outputs of this process and exits
/// with 128 + the signal's number (130 for Ctrl-C), instead of dying with hidden
/// `.brume-*.tmp` files left in the output folders.
pub fn remove_temporaries_on_signals() {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        match signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) {
            Ok(mut signals) => {
                std::thread::spawn(move || {
                    if let Some(signal) = signals.forever().next() {
                        errln!("brume: interrupted");
                        output::exit_removing_temporaries(128 + signal);
                    }
                });
            }
            Err(e) => log::warn!("no clean-up on Ctrl-C: cannot install the handler: {e}"),
        }
    }
}

/// The library names a bad parameter as its field (`rho_max`), and an option its message
/// asks for in backticks (`` `depth_scale` ``); on the command line they are flags
/// (`--rho-max`, `--depth-scale`). Names that are a flag of `brume` become that flag;
/// others (a file's field, `range map`) are kept.
pub fn name_flags(e: Error) -> Error {
    name_flags_of(e, None)
}

/// [`name_flags`] with the flags of `command` only (`None`: of any command).
fn name_flags_of(e: Error, command: Option<&str>) -> Error {
    match e.rename_options(|field| flag_of(field, command)) {
        // The library's pre-processing turned off is the flag `--no-prep` given.
        Error::InvalidParameter {
            name,
            value,
            expected,
        } if name == "prep" && value == "off" => Error::InvalidParameter {
            name: "--no-prep".into(),
            value: "given".into(),
            expected,
        },
        e => e,
    }
}

/// A frame's error in `brume batch` (one the library keeps, for its log), as the text to
/// show: the options it names become flags only where `batch` has them; the others keep
/// their names, as `depth`, `camera` and `calib` (a frame's own files) do, which are its
/// manifest's columns.
pub fn batch_flags_shown(e: &Error) -> String {
    let command = Some("batch");
    match e {
        Error::InvalidParameter {
            name,
            value,
            expected,
        } => name_flags_of(
            Error::InvalidParameter {
                name: name.clone(),
                value: value.clone(),
                expected: expected.clone(),
            },
            command,
        )
        .to_string(),
        other => batch_flags_in(&other.to_string()),
    }
}

/// `text` (a frame's warning in `brume batch`) with the options it names as flags where
/// `batch` has them, as [`batch_flags_shown`] names them in errors.
pub fn batch_flags_in(text: &str) -> String {
    brume::error::rename_options(text, |f| flag_of(f, Some("batch")))
}

/// `text` (a loader's note, a warning) with the options it names in backticks as flags.
pub fn flags_in(text: &str) -> String {
    brume::error::rename_options(text, |field| flag_of(field, None))
}

/// The flag that sets the library's field `field`, if `command` (`None`: any `brume`
/// command) has one.
fn flag_of(field: &str, command: Option<&str>) -> Option<String> {
    let flag = match FLAG_ALIASES.iter().find(|(f, _)| *f == field) {
        Some((_, flag)) => flag.to_string(),
        None => format!("--{}", field.replace('_', "-")),
    };
    is_flag(&flag, command).then_some(flag)
}

/// Whether `flag` (`--name`) is a long option of `command` (`None`: of any command).
fn is_flag(flag: &str, command: Option<&str>) -> bool {
    fn has(cmd: &clap::Command, flag: &str, nested: bool) -> bool {
        flag.strip_prefix("--")
            .is_some_and(|long| tips::takes(cmd, long))
            || (nested && cmd.get_subcommands().any(|sub| has(sub, flag, true)))
    }
    let cli = Cli::command();
    match command {
        None => has(&cli, flag, true),
        Some(name) => cli
            .find_subcommand(name)
            .is_some_and(|cmd| has(cmd, flag, false)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

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

    /// A batch frame's error names `batch`'s flags, and a frame's own files as its
    /// manifest's columns, not as `render`'s flags.
    #[test]
    fn batch_errors_name_only_batch_flags() {
        let e = Error::invalid("depth", "d.npy", "give `camera`, `calib` or `depth_scale`");
        assert_eq!(
            batch_flags_shown(&e),
            "invalid depth = d.npy: expected give `camera`, `calib` or --depth-scale"
        );
        assert_eq!(
            name_flags(e).to_string(),
            "invalid --depth = d.npy: expected give --camera, --calib or --depth-scale"
        );
    }

    /// Every option whose value is not a path takes a leading hyphen, so that
    /// `--flag -1` is answered by the check that names the flag.
    #[test]
    fn negative_values_reach_their_option() {
        fn walk(cmd: &clap::Command, path: &mut Vec<String>, checked: &mut usize) {
            for arg in cmd.get_arguments() {
                let Some(long) = arg.get_long() else { continue };
                let takes_value = arg.get_num_args().is_some_and(|n| n.takes_values());
                let is_path = arg
                    .get_value_names()
                    .is_some_and(|names| names.iter().any(|n| n.as_str().contains("PATH")));
                if !takes_value || is_path || long == "help" || long == "version" {
                    continue;
                }
                *checked += 1;
                let flag = format!("--{long}");
                let argv = ["brume"]
                    .into_iter()
                    .chain(path.iter().map(String::as_str))
                    .chain([flag.as_str(), "-1"]);
                if let Err(e) = Cli::try_parse_from(argv) {
                    assert!(
                        e.kind() != clap::error::ErrorKind::UnknownArgument
                            && e.to_string().contains(&flag),
                        "{path:?} {flag} -1: {e}"
                    );
                }
            }
            for sub in cmd.get_subcommands() {
                path.push(sub.get_name().to_string());
                walk(sub, path, checked);
                path.pop();
            }
        }
        let (mut cmd, mut checked) = (Cli::command(), 0);
        cmd.build(); // sets every argument's number of values
        walk(&cmd, &mut Vec::new(), &mut checked);
        assert!(checked >= 25, "only {checked} options checked");
    }
}
