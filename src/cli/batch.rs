//! `brume batch`: fog a dataset ([`brume::dataset::Batch`]) with a progress bar and a
//! summary. `--shard K/N` takes a deterministic share of the frames, for array jobs.

use super::args::{BatchArgs, Compat};
use brume::dataset::{
    self, Batch, BatchEvent, BatchOptions, BatchReport, Betas, Shard, MAX_LOADERS, MAX_WRITERS,
};
use brume::photo::{Conventions, FrameOptions};
use brume::{Error, Renderer, Result};
use indicatif::{ProgressBar, ProgressStyle};

/// Checks every option and every frame's outputs before any file or folder is made: a bad
/// value names its flag, a manifest row whose outputs would leave `--out` or land on
/// another frame's is refused, and nothing has been written when it fails.
pub fn plan(args: &BatchArgs) -> Result<Batch> {
    let shard = match &args.shard {
        Some(s) => Shard::parse(s)?,
        None => Shard::ALL,
    };
    let betas = match args.beta_dist {
        Some(dist) => Betas::Drawn(dist),
        None => Betas::Each(parse_betas(&args.beta)?),
    };
    let capture = super::capture::capture_options(&args.capture, args.prep.seed)?;
    let opts = BatchOptions {
        out: args.out.clone(),
        betas,
        shard,
        transmittance: args.transmittance,
        capture,
        frame: args.frame_options()?,
        loaders: match args.loaders {
            Some(n) => super::limits::count("--loaders", n, 1, MAX_LOADERS, "loader threads")?,
            None => dataset::default_loaders(),
        },
        writers: match args.writers {
            Some(n) => super::limits::count("--writers", n, 1, MAX_WRITERS, "writer threads")?,
            None => dataset::default_writers(&capture),
        },
    };
    Batch::plan(&args.inputs, args.manifest.as_deref(), opts)
}

/// Runs `batch` on `renderer`, with a progress bar, each failure on stderr as it happens
/// and the summary at the end.
pub fn run(batch: Batch, renderer: &mut Renderer) -> Result<()> {
    let progress = progress_bar(batch.outputs() as u64);
    let shown = std::sync::Mutex::new(std::collections::HashSet::new());
    let observe = |event: BatchEvent| match event {
        BatchEvent::RemovedTemporaries { count, folder } => errln!(
            "brume: removed {count} temporary files left under {} by an interrupted run",
            folder.display()
        ),
        BatchEvent::Staged { outputs } => super::hold_staged_outputs(outputs),
        BatchEvent::Written { .. } => progress.inc(1),
        BatchEvent::OutputFailed { error, .. } => {
            progress.suspend(|| errln!("brume: error: {}", super::batch_flags_shown(error)));
            progress.inc(1);
        }
        BatchEvent::FrameWarned { image, warnings } => {
            show_new_warnings(image, warnings, &shown, &progress)
        }
        BatchEvent::FrameFailed {
            image,
            error,
            outputs,
        } => {
            progress.suspend(|| errln!("brume: error: skipped {}", frame_error(image, error)));
            progress.inc(outputs as u64);
        }
    };
    let report = batch.run(renderer, &observe);
    progress.finish_and_clear();
    let report = report?;
    print_summary(&report);
    report.check()
}

/// `--dry-run`: the fogged images `batch` would write, one per line, and a summary; the
/// frames that cannot be read on stderr, as a run shows them. Nothing is written.
pub fn dry_run(batch: &Batch, args: &BatchArgs) -> Result<()> {
    let mut unreadable = 0;
    for (image, error) in batch.unassembled_frames() {
        errln!("brume: error: cannot read {}", frame_error(image, error));
        unreadable += 1;
    }
    for output in batch.planned_outputs() {
        outln!("{}", output.display());
    }
    let record = args.out.join(dataset::SETTINGS_FILE);
    let settings = match record.exists() {
        true => format!("the settings {} records", record.display()),
        false => format!("settings to be recorded in {}", record.display()),
    };
    let skipped = match unreadable {
        0 => String::new(),
        n => format!("; {n} frames that cannot be read (above), which a run logs as failed"),
    };
    let Shard { index, count } = batch.shard();
    let shard = match &args.shard {
        Some(_) => format!(" (this is shard {index}/{count})"),
        None => String::new(),
    };
    outln!(
        "dry run, nothing written: {} frames found{shard}, {} outputs to write, {} already \
         written{skipped}; {settings}",
        batch.frames_found(),
        batch.outputs(),
        batch.skipped()
    );
    Ok(())
}

/// A frame's error with the frame's image named once: `image: why`, or `why` alone where
/// it begins with the image's path (a file's error names its file).
fn frame_error(image: &std::path::Path, error: &Error) -> String {
    let why = super::batch_flags_shown(error);
    let image = image.display().to_string();
    match why.starts_with(&image) {
        true => why,
        false => format!("{image}: {why}"),
    }
}

/// Shows each warning the first time its text comes (most datasets' frames share one
/// reading and one size, so they would repeat it frame after frame); the summary counts
/// the frames and the log's records list every one.
fn show_new_warnings(
    image: &std::path::Path,
    warnings: &[String],
    shown: &std::sync::Mutex<std::collections::HashSet<String>>,
    progress: &ProgressBar,
) {
    let mut shown = shown.lock().unwrap_or_else(|p| p.into_inner());
    for warning in warnings {
        if shown.insert(warning.clone()) {
            let text = super::batch_flags_in(warning);
            progress.suspend(|| log::warn!("{}: {text}", image.display()));
        }
    }
}

/// `--beta 0.005,0.01,0.02`: each a number the library accepts ([`dataset::check_beta`]),
/// named as typed.
fn parse_betas(text: &str) -> Result<Vec<f64>> {
    text.split(',')
        .map(|part| {
            let beta: f64 = part.trim().parse().map_err(|_| {
                Error::invalid(
                    "--beta",
                    part,
                    "extinction coefficients in 1/m, e.g. 0.005,0.01,0.02",
                )
            })?;
            dataset::check_beta(beta).map_err(|e| match e {
                Error::InvalidParameter { expected, .. } => {
                    Error::invalid("--beta", part, expected)
                }
                e => e,
            })?;
            Ok(beta)
        })
        .collect()
}

fn progress_bar(outputs: u64) -> ProgressBar {
    let bar = ProgressBar::new(outputs);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} outputs, {per_sec}, ETA {eta}")
            .expect("a valid template"),
    );
    bar
}

fn print_summary(r: &BatchReport) {
    let n = r.written.max(1) as f64;
    let mut line = format!(
        "wrote {} outputs of {} frames in {:.1} s, skipped {} already written, failed {} \
         outputs and {} frames",
        r.written, r.frames, r.wall_s, r.skipped, r.failed_outputs, r.failed_frames
    );
    if r.written > 0 {
        line += &format!(
            "; {:.2} s per output (wall); per output: decode {:.0} ms, pre-processing {:.0} \
             ms, refinement {:.0} ms, render {:.0} ms (GPU {:.0} ms), encode {:.0} ms",
            r.wall_s / n,
            r.decode_ms / n,
            r.prep_ms / n,
            r.refine_ms / n,
            r.render_ms / n,
            r.gpu_ms / n,
            r.encode_ms / n,
        );
    }
    if r.warned_frames > 0 {
        line += &format!(
            "; {} frames with warnings (each output's log record lists them)",
            r.warned_frames
        );
    }
    outln!("{line}; log {}", r.log.display());
}

impl BatchArgs {
    /// The library's options for every frame: the batch's blur, airlight,
    /// pre-processing, refinement and conventions (the library checks the masks and the
    /// blur's schedule at each β when it plans the batch).
    fn frame_options(&self) -> Result<FrameOptions> {
        if self.no_prep {
            let seed_read = self.capture.reads_seed() || self.beta_dist.is_some();
            super::options::refuse_prep_options(&self.prep, seed_read)?;
        }
        super::options::check_depth_options(&self.depth)?;
        let mut opts = FrameOptions {
            depth: super::inputs::reading_options(&self.depth),
            ..FrameOptions::default()
        };
        let blur = &mut opts.fog.blur;
        if let Some(s) = self.scheme {
            blur.scheme = s;
        }
        if let Some(p) = self.precision {
            blur.precision = p;
        }
        blur.coarse_from = self.coarse_from.0;
        if let Some(l) = self.lambda {
            opts.fog.lambda = l;
        }
        if let Some(a) = self.albedo {
            opts.albedo = a;
        }
        opts.prepare.airlight = self.airlight;
        opts.prepare.prep = match self.no_prep {
            true => None,
            false => Some(super::inputs::prep_options(&self.prep)?),
        };
        opts.prepare.refine = self.refine.options(self.depth.depth_format)?;
        opts.refine_mode = self.refine.mode;
        opts.sky_mask = self.prep.sky_mask.clone();
        opts.sky_mask_format = self.prep.sky_mask_format;
        opts.ego_mask = self.prep.ego_mask.clone();
        if self.compat == Some(Compat::FoggyCityscapes) {
            use super::options::shown;
            super::options::refuse_with_foggy_cityscapes(&[
                ("--lambda", shown(self.lambda)),
                ("--scheme", shown(self.scheme)),
                ("--precision", shown(self.precision)),
                ("--coarse-from", self.coarse_from.changed()),
                ("--albedo", shown(self.albedo)),
            ])?;
            opts.conventions = Conventions::FoggyCityscapes;
        }
        Ok(opts)
    }
}
