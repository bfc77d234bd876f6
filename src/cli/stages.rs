//! The stage a command without a progress bar of its own is at, on stderr: `render` and
//! `prep` run for seconds on a large photo (about 4 s at 4000 x 3000 on llvmpipe) and said
//! nothing until the end.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::Write;
use std::sync::Mutex;
use std::time::Duration;

/// The spinner shown now, if any: the log's lines go above it ([`LogWriter`]).
static SHOWN: Mutex<Option<ProgressBar>> = Mutex::new(None);

/// A spinner on stderr naming the stage, with the time so far. Nothing is drawn where
/// stderr is not a terminal (indicatif's rule: logs and pipes stay clean) or where the log
/// says each stage itself (`-v`). Taken off before anything the program prints
/// ([`clear_shown`], from `outln!` and the others) and when dropped (an error's line
/// comes after it).
/// (Whether this one put up the spinner: [`SHOWN`] holds it, the one handle to it.)
pub struct Stages(bool);

impl Stages {
    /// Shows `first` as the stage.
    pub fn start(first: &str) -> Self {
        if log::log_enabled!(log::Level::Info) {
            return Stages(false);
        }
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
        let style = ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
            .unwrap_or_else(|_| ProgressStyle::default_spinner());
        bar.set_style(style);
        bar.set_message(first.to_string());
        bar.enable_steady_tick(Duration::from_millis(100));
        *shown() = Some(bar);
        Stages(true)
    }

    /// Shows `stage` as the stage, while the spinner is up.
    pub fn at(&self, stage: &str) {
        if let Some(bar) = shown().as_ref() {
            bar.set_message(stage.to_string());
        }
    }
}

impl Drop for Stages {
    fn drop(&mut self) {
        if self.0 {
            clear_shown();
        }
    }
}

/// Takes the spinner shown, if any, off the terminal for what is printed next.
pub fn clear_shown() {
    if let Some(bar) = shown().take() {
        bar.finish_and_clear();
    }
}

fn shown() -> std::sync::MutexGuard<'static, Option<ProgressBar>> {
    SHOWN.lock().unwrap_or_else(|e| e.into_inner())
}

/// stderr for the log: a line written while a spinner of [`Stages`] is shown goes above
/// it instead of into it.
pub struct LogWriter;

impl Write for LogWriter {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let spinner = shown().clone();
        match spinner {
            Some(bar) => bar.suspend(|| std::io::stderr().write(buf)),
            None => std::io::stderr().write(buf),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        std::io::stderr().flush()
    }
}
