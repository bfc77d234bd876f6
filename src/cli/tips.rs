//! Tips in clap's errors for what people type from other tools: a file without its flag,
//! a subcommand's option given to its parent, another tool's name for a flag.

use super::Cli;
use clap::CommandFactory;

/// What `--image` takes.
const IMAGE: &str = "the colour image";
/// What `--depth` takes.
const DEPTH: &str = "the depth, range or disparity map";

/// The files brume's commands take by flag, and what each is.
const FILE_FLAGS: [(&str, &str); 2] = [("image", IMAGE), ("depth", DEPTH)];

/// Flags people type from other tools, and brume's flag for what they mean, with what it
/// takes.
const FLAG_SYNONYMS: [(&[&str], &str, &str); 3] = [
    (
        &[
            "input", "in", "img", "photo", "picture", "rgb", "color", "colour",
        ],
        "image",
        IMAGE,
    ),
    (
        &[
            "depth-map",
            "depthmap",
            "disparity",
            "disp",
            "range",
            "range-map",
        ],
        "depth",
        DEPTH,
    ),
    (
        &["fog", "haze", "density", "extinction"],
        "beta",
        "the fog's extinction in 1/m; or --visibility in metres",
    ),
];

/// Flags other tools take to replace their outputs (`convert`'s habit, ffmpeg's `-y`).
const OVERWRITE_FLAGS: [&str; 7] = [
    "--force",
    "--overwrite",
    "--yes",
    "--clobber",
    "--replace",
    "-f",
    "-y",
];

/// clap's error with a tip where a file was given without its flag (`brume render
/// photo.jpg`, or `brume view photo.jpg`, which clap reads as a subcommand), a
/// subcommand's option to its parent (`brume view --image photo.jpg`), or another tool's
/// name for a flag (`--input`, for which clap's nearest name is `--tint`); any other
/// error, or one clap already suggests a name for, as it is.
pub fn explain_parse_error(mut error: clap::Error, argv: &[String]) -> clap::Error {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    let suggested = [ContextKind::SuggestedArg, ContextKind::SuggestedSubcommand]
        .into_iter()
        .any(|kind| error.get(kind).is_some());
    let unexpected = [ContextKind::InvalidArg, ContextKind::InvalidSubcommand]
        .into_iter()
        .find_map(|kind| match error.get(kind) {
            Some(ContextValue::String(arg)) => Some(arg.clone()),
            _ => None,
        });
    let kind_fits = matches!(
        error.kind(),
        ErrorKind::UnknownArgument | ErrorKind::InvalidSubcommand
    );
    let tip = match unexpected {
        Some(arg) if kind_fits => {
            let (command, words) = command_of(argv);
            match synonym_tip(&arg, &command, &words)
                .or_else(|| overwrite_tip(&arg, &command, &words))
            {
                Some(tip) => {
                    // clap's usage line shows the flag it suggested in place.
                    error.remove(ContextKind::SuggestedArg);
                    let usage = command.clone().render_usage();
                    error.insert(ContextKind::Usage, ContextValue::StyledStr(usage));
                    Some(tip)
                }
                None if !suggested => flag_tip(&arg, command, words, argv),
                None => None,
            }
        }
        _ => None,
    };
    if let Some(tip) = tip {
        error.insert(
            ContextKind::Suggested,
            ContextValue::StyledStrs(vec![tip.into()]),
        );
    }
    error
}

/// The command `argv` runs, and its words (`brume view render`).
fn command_of(argv: &[String]) -> (clap::Command, Vec<String>) {
    let mut command = Cli::command();
    // Built, so that each subcommand's usage names the program and its parents.
    command.build();
    let mut words = vec!["brume".to_string()];
    for word in argv.iter().skip(1) {
        if let Some(sub) = command.find_subcommand(word).cloned() {
            words.push(sub.get_name().to_string());
            command = sub;
        }
    }
    (command, words)
}

/// The name of the option `arg` (`--input=x` → `input`); `None` for a value.
fn long_name(arg: &str) -> Option<&str> {
    let option = arg.strip_prefix("--")?;
    option.split('=').next()
}

/// Whether `command` has the option `--long`.
pub(super) fn takes(command: &clap::Command, long: &str) -> bool {
    command.get_arguments().any(|a| a.get_long() == Some(long))
}

/// The tip for another tool's name of a flag `command` has ([`FLAG_SYNONYMS`]).
fn synonym_tip(arg: &str, command: &clap::Command, words: &[String]) -> Option<String> {
    let name = long_name(arg)?;
    let (_, flag, what) = FLAG_SYNONYMS
        .iter()
        .find(|(names, flag, _)| names.contains(&name) && takes(command, flag))?;
    Some(format!(
        "{} takes --{flag} for that ({what}): '{} --{flag} …'",
        words.join(" "),
        words.join(" ")
    ))
}

/// The tip for a flag that asks to replace outputs ([`OVERWRITE_FLAGS`]), to a command
/// with an `--out`: none is needed (clap's nearest name for `--force` is `--focal`).
fn overwrite_tip(arg: &str, command: &clap::Command, words: &[String]) -> Option<String> {
    let flag = arg.split('=').next()?;
    if !(OVERWRITE_FLAGS.contains(&flag) && takes(command, "out")) {
        return None;
    }
    let words = words.join(" ");
    Some(if command.get_name() == "batch" {
        format!(
            "{words} writes the outputs missing under --out and keeps those there (each is \
             complete): remove one to have it written again, or give another --out"
        )
    } else {
        format!(
            "{words} replaces the file --out names without asking (never one of its inputs, \
             nor a read-only file): no flag is needed"
        )
    })
}

/// The tip of [`explain_parse_error`] for `arg`, which `command` (run as `words`) did not
/// expect: a file without its flag, or an option of a subcommand.
fn flag_tip(
    arg: &str,
    mut command: clap::Command,
    mut words: Vec<String>,
    argv: &[String],
) -> Option<String> {
    if let Some(long) = long_name(arg) {
        let sub = command.get_subcommands().find(|c| takes(c, long))?;
        let owner = format!("{} {}", words.join(" "), sub.get_name());
        return Some(format!(
            "--{long} is an option of {owner}: '{owner} --{long} …'"
        ));
    }
    let takes_files = |command: &clap::Command| FILE_FLAGS.iter().any(|(l, _)| takes(command, l));
    if !takes_files(&command) {
        let sub = command
            .get_subcommands()
            .find(|c| takes_files(c))
            .cloned()?;
        words.push(sub.get_name().to_string());
        command = sub;
    }
    let given = |long: &str| argv.iter().any(|a| long_name(a) == Some(long));
    let choices: Vec<String> = FILE_FLAGS
        .iter()
        .filter(|(long, _)| takes(&command, long) && !given(long))
        .map(|(long, what)| format!("'--{long} {arg}' ({what})"))
        .collect();
    (!choices.is_empty()).then(|| {
        format!(
            "{} takes its files by flag: {}",
            words.join(" "),
            choices.join(" or ")
        )
    })
}
