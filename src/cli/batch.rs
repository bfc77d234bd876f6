//! `brume batch`: fog a dataset. Each frame is loaded and pre-processed once, then
//! rendered for every β on one GL context; loading the next frame and writing the last
//! outputs run on their own threads while the GPU works. Outputs are written atomically, so
//! a run that stops leaves only complete files, and the next run skips them. `--shard K/N`
//! takes a deterministic share of the frames, for array jobs.

use super::args::{BatchArgs, Compat};
use brume::blur::Blur;
use brume::dataset::{self, Item, Shard};
use brume::io::depth::DepthFormat;
use brume::io::output::Outputs;
use brume::medium::Medium;
use brume::photo::{
    capture, transmittance_rgb8, BetaDistribution, CaptureOptions, Conventions, Frame, FrameFog,
    FrameOptions,
};
use brume::{Error, Renderer, Result};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::time::Instant;

/// A frame that could not be loaded.
struct Failed {
    item: Item,
    error: Error,
}

/// One output for the writer thread.
struct Encode {
    path: PathBuf,
    image: brume::raster::RgbaImage,
    transmittance: Option<(PathBuf, Vec<[u8; 3]>, usize, usize)>,
    record: serde_json::Value,
    /// The capture after the fog, seeded for this output (applied on the writer thread).
    capture: CaptureOptions,
}

/// Everything a run needs, checked before anything is created: the options, the frames of
/// this shard with the β values still to write, and the outputs proven to lie under
/// `--out`, one file each.
pub struct Plan {
    shard: Shard,
    /// How every frame is read, prepared and fogged (the library's per-frame loop).
    options: FrameOptions,
    /// Frames of this shard with the β values whose outputs are missing.
    pending: Vec<(Item, Vec<f64>)>,
    /// Frames of this shard that could not be assembled (no disparity, no camera).
    failures: Vec<Failed>,
    /// Frames found in all shards.
    total: usize,
    /// Outputs of this shard already complete, skipped.
    skipped: usize,
    /// The capture after the fog (--exposure-stops, noise, --jpeg-quality).
    capture: CaptureOptions,
}

/// Checks every option and every frame's outputs before any file or folder is made: a bad
/// value names its flag, a manifest row whose outputs would leave `--out` or land on
/// another frame's is refused, and nothing has been written when it fails.
pub fn plan(args: &BatchArgs) -> Result<Plan> {
    let shard = match &args.shard {
        Some(s) => Shard::parse(s)?,
        None => Shard::ALL,
    };
    let betas = parse_betas(&args.beta)?;
    let capture = super::capture::capture_options(&args.capture, args.prep.seed)?;
    let seed = capture.seed;
    // With --beta-dist, the options are checked at the β the draws stay within, and the
    // destinations at its median (the frames' own β only change the number in the name).
    let betas = match &args.beta_dist {
        Some(dist) => drawn_beta_bounds(dist)?,
        None => betas,
    };
    let options = args.frame_options(&betas)?;
    if args.out.exists() && !args.out.is_dir() {
        return Err(Error::invalid(
            "--out",
            args.out.display(),
            "a folder for the outputs (this is a file)",
        ));
    }
    let (items, mut failures) = collect_items(args)?;
    super::batch_checks::check_sky_mask_size(args, &items)?;
    let checked = match &args.beta_dist {
        Some(dist) => vec![dist.quantile(0.5)],
        None => betas.clone(),
    };
    super::batch_checks::check_destinations(args, &items, &checked)?;
    let total = items.len() + failures.len();
    let items: Vec<Item> = items.into_iter().filter(|i| shard.contains(i)).collect();
    failures.retain(|f| shard.contains(&f.item));
    let mut skipped = 0;
    let pending: Vec<(Item, Vec<f64>)> = items
        .into_iter()
        .filter_map(|item| {
            let wanted = match &args.beta_dist {
                Some(dist) => vec![item.drawn_beta(dist, seed)],
                None => betas.clone(),
            };
            let todo: Vec<f64> = wanted
                .iter()
                .copied()
                .filter(|&b| !outputs_complete(args, &item, b))
                .collect();
            skipped += wanted.len() - todo.len();
            (!todo.is_empty()).then_some((item, todo))
        })
        .collect();
    Ok(Plan {
        shard,
        options,
        pending,
        failures,
        total,
        skipped,
        capture,
    })
}

/// Runs the batch `plan` made from `args` on `renderer`.
pub fn run(args: &BatchArgs, plan: Plan, renderer: &mut Renderer) -> Result<()> {
    let Plan {
        shard,
        options,
        pending,
        failures,
        total,
        skipped,
        capture,
    } = plan;
    let outputs: usize = pending.iter().map(|(_, b)| b.len()).sum();
    log::info!(
        "{total} frames found, {} in shard {}/{}; {outputs} outputs to write, {skipped} \
         already written",
        pending.len() + failures.len(),
        shard.index,
        shard.count
    );
    std::fs::create_dir_all(&args.out).map_err(|e| Error::io(&args.out, e))?;
    let stale = brume::io::output::remove_stale_temporaries(&args.out)?;
    if stale > 0 {
        errln!(
            "brume: removed {stale} temporary files left under {} by an interrupted run",
            args.out.display()
        );
    }
    let log_path = args.out.join(format!(
        "brume-batch-{}-of-{}.jsonl",
        shard.index, shard.count
    ));
    let log_file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&log_path)
        .map_err(|e| Error::io(&log_path, e))?;
    let mut log = Log {
        file: log_file,
        path: log_path,
        progress: progress_bar(outputs as u64),
        summary: Summary {
            skipped,
            ..Summary::default()
        },
    };
    for f in &failures {
        log.frame_failed(f, 0)?;
    }
    let started = Instant::now();
    let (load_tx, load_rx) = sync_channel::<std::result::Result<Frame, Failed>>(1);
    let (event_tx, event_rx) = sync_channel::<Event>(2);
    let frames: Vec<Item> = pending.iter().map(|(i, _)| i.clone()).collect();
    let mut stats = Stats::default();
    let log = std::thread::scope(|s| -> Result<Log> {
        s.spawn(|| load_frames(&options, frames, load_tx));
        let writer = s.spawn(move || write_outputs(event_rx, log));
        let gpu = Gpu {
            args,
            options: &options,
            events: &event_tx,
            capture: &capture,
        };
        gpu.render_frames(renderer, &pending, load_rx, &mut stats);
        drop(event_tx);
        writer.join().expect("the writer thread does not panic")
    })?;
    log.progress.finish_and_clear();
    let summary = &log.summary;
    stats.print(summary, started.elapsed().as_secs_f64(), &log.path);
    if summary.failed_frames > 0 || summary.failed_outputs > 0 {
        return Err(Error::BatchFailures {
            frames: summary.failed_frames,
            outputs: summary.failed_outputs,
            log: log.path.clone(),
        });
    }
    Ok(())
}

/// The frames of the roots and the manifest, sorted by key; frames that cannot be
/// assembled (missing disparity or camera) as failures.
fn collect_items(args: &BatchArgs) -> Result<(Vec<Item>, Vec<Failed>)> {
    let mut items = Vec::new();
    let mut failures = Vec::new();
    for root in &args.inputs {
        if !root.is_dir() {
            return Err(Error::invalid(
                "input folder",
                root.display(),
                "a folder to search for Cityscapes frames ({name}_leftImg8bit.png)",
            ));
        }
        for found in dataset::find_cityscapes(root)? {
            match found {
                Ok(item) => items.push(item),
                Err(error) => failures.push(Failed {
                    item: unassembled(&error),
                    error,
                }),
            }
        }
    }
    if let Some(m) = &args.manifest {
        items.extend(dataset::read_manifest(m)?);
    }
    if items.is_empty() && failures.is_empty() {
        return Err(Error::invalid(
            "inputs",
            "(no frames)",
            "folders with Cityscapes frames or a --manifest CSV with at least one row",
        ));
    }
    items.sort_by_key(Item::key);
    Ok((items, failures))
}

/// A stand-in item for a frame that could not be assembled, so that its failure can be
/// logged and sharded like the others.
fn unassembled(error: &Error) -> Item {
    let image = match error {
        Error::Format { path, .. } => path.clone(),
        _ => PathBuf::new(),
    };
    Item {
        stem: image
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        depth: PathBuf::new(),
        camera: None,
        calib: None,
        sky_mask: None,
        out_dir: image.parent().map(Path::to_path_buf).unwrap_or_default(),
        image,
    }
}

fn outputs_complete(args: &BatchArgs, item: &Item, beta: f64) -> bool {
    item.foggy_output(&args.out, beta).is_file()
        && (!args.transmittance || item.transmittance_output(&args.out, beta).is_file())
}

/// The loader thread: decodes and pre-processes each frame in turn, one ahead of the GPU.
fn load_frames(
    options: &FrameOptions,
    frames: Vec<Item>,
    tx: SyncSender<std::result::Result<Frame, Failed>>,
) {
    for item in frames {
        let loaded = Frame::load(&item, options).map_err(|error| Failed {
            item: item.clone(),
            error: super::name_flags(error),
        });
        if tx.send(loaded).is_err() {
            return;
        }
    }
}

/// The GPU's side of a run: the options, and the channel to the writer thread.
struct Gpu<'a> {
    args: &'a BatchArgs,
    options: &'a FrameOptions,
    events: &'a SyncSender<Event>,
    capture: &'a CaptureOptions,
}

impl Gpu<'_> {
    /// The GPU loop: every β of every frame, in the order the loader delivers them;
    /// outputs and failures go to the writer thread as they come.
    fn render_frames(
        &self,
        renderer: &mut Renderer,
        pending: &[(Item, Vec<f64>)],
        rx: Receiver<std::result::Result<Frame, Failed>>,
        stats: &mut Stats,
    ) {
        for ((_, betas), loaded) in pending.iter().zip(rx) {
            let writer_alive = match loaded {
                Ok(frame) => {
                    stats.frames += 1;
                    stats.decode_ms += frame.decode_ms;
                    stats.prep_ms += frame.prep_ms;
                    self.render_frame(renderer, frame, betas, stats)
                }
                Err(failed) => self.frame_failed(failed, betas.len()),
            };
            if !writer_alive {
                return;
            }
        }
    }

    /// Hands a frame's failure (`outputs` of it not written) to the writer; false when the
    /// writer is gone.
    fn frame_failed(&self, failed: Failed, outputs: usize) -> bool {
        let event = Event::FrameFailed { failed, outputs };
        self.events.send(event).is_ok()
    }

    /// Refines a frame once on the GPU, then renders its β values from one upload, each
    /// output handed to the writer thread as soon as it is read back. A failure after some
    /// outputs counts only those not sent. False when the writer is gone.
    fn render_frame(
        &self,
        renderer: &mut Renderer,
        mut frame: Frame,
        betas: &[f64],
        stats: &mut Stats,
    ) -> bool {
        let fail = |item: &Item, error| Failed {
            item: item.clone(),
            error: super::name_flags(error),
        };
        if let Err(e) = frame.refine(self.options, renderer) {
            return self.frame_failed(fail(&frame.item, e), betas.len());
        }
        stats.refine_ms += frame.refine_ms;
        let (mut sent, mut writer_gone) = (0, false);
        let mut started = Instant::now();
        let result = frame.fog_each(renderer, self.options, betas, |beta, fogged| {
            let render_ms = started.elapsed().as_secs_f64() * 1e3;
            // NaN (JSON null) where the GPU timer's figures were rejected.
            if fogged.gpu_ms.is_finite() {
                stats.gpu_ms += fogged.gpu_ms;
            }
            stats.render_ms += render_ms;
            let job = self.encode(&frame, beta, fogged, render_ms);
            if self.events.send(Event::Output(job)).is_err() {
                writer_gone = true;
                return Err(Error::invalid(
                    "writer",
                    "stopped",
                    "a running writer thread",
                ));
            }
            sent += 1;
            started = Instant::now();
            Ok(())
        });
        match result {
            Ok(()) => true,
            // The writer is gone: the run is ending, nothing more to report.
            Err(_) if writer_gone => false,
            Err(error) => self.frame_failed(fail(&frame.item, error), betas.len() - sent),
        }
    }

    /// One output of a frame: the image, its transmittance map if asked for, and its log
    /// record.
    fn encode(&self, frame: &Frame, beta: f64, fogged: FrameFog, render_ms: f64) -> Encode {
        let (args, item) = (self.args, &frame.item);
        let path = item.foggy_output(&args.out, beta);
        let metres = frame.metres().expect("refined before fog");
        let transmittance = args.transmittance.then(|| {
            (
                item.transmittance_output(&args.out, beta),
                transmittance_rgb8(&fogged.haze, metres),
                metres.width(),
                metres.height(),
            )
        });
        let record = json!({
            "status": "ok",
            "image": item.image.display().to_string(),
            "depth": item.depth.display().to_string(),
            "camera": item.camera.as_ref().map(|p| p.display().to_string()),
            "sky_mask": item.sky_mask.as_ref().map(|p| p.display().to_string()),
            "output": path.display().to_string(),
            "beta": beta,
            "beta_dist": args.beta_dist.map(|d| d.to_string()),
            "visibility_m": -(0.05f64.ln()) / beta,
            "width": fogged.image.width(),
            "height": fogged.image.height(),
            "sigma_max": fogged.sigma_max,
            "diffusion_passes": fogged.passes,
            "airlight": fogged.airlight,
            "airlight_source": fogged.airlight_source,
            "decode_ms": frame.decode_ms,
            "prep_ms": frame.prep_ms,
            "gpu_ms": fogged.gpu_ms,
            "render_ms": render_ms,
            "capture": super::capture::capture_json(self.capture),
        });
        let capture = CaptureOptions {
            seed: self.capture.seed ^ item.name_hash() ^ beta.to_bits(),
            ..*self.capture
        };
        Encode {
            path,
            image: fogged.image,
            transmittance,
            record,
            capture,
        }
    }
}

/// What the GPU loop hands the writer thread.
enum Event {
    /// An output to encode and write.
    Output(Encode),
    /// A frame that failed, with the number of its outputs that will not be written.
    FrameFailed { failed: Failed, outputs: usize },
}

/// The writer thread: encodes and writes each output atomically, and logs it as soon as
/// it is in place.
fn write_outputs(rx: Receiver<Event>, mut log: Log) -> Result<Log> {
    for event in rx {
        match event {
            Event::Output(mut job) => {
                let t = Instant::now();
                let result = capture(&mut job.image, &job.capture).and_then(|_| write_one(&job));
                log.summary.encode_ms += t.elapsed().as_secs_f64() * 1e3;
                log.output(job.record, result)?;
            }
            Event::FrameFailed { failed, outputs } => log.frame_failed(&failed, outputs)?,
        }
    }
    Ok(log)
}

fn write_one(job: &Encode) -> Result<()> {
    if let Some(dir) = job.path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    let mut outputs = Outputs::new();
    outputs.stage_rgba(&job.path, &job.image)?;
    if let Some((path, rgb, w, h)) = &job.transmittance {
        outputs.stage_png_rgb8(path, *w, *h, rgb)?;
    }
    super::commit(outputs)
}

/// The run's JSON-lines log, its progress bar and its counts: one line per output, written
/// (in one `write`, on a file opened for appending, so that shards sharing nothing but the
/// folder never interleave) as soon as the output is in place or has failed.
struct Log {
    file: std::fs::File,
    path: PathBuf,
    progress: ProgressBar,
    summary: Summary,
}

/// What became of this shard's outputs.
#[derive(Default)]
struct Summary {
    written: usize,
    skipped: usize,
    failed_outputs: usize,
    failed_frames: usize,
    encode_ms: f64,
}

impl Log {
    fn output(&mut self, mut record: serde_json::Value, result: Result<()>) -> Result<()> {
        match result {
            Ok(()) => self.summary.written += 1,
            Err(e) => {
                record["status"] = json!("failed");
                record["error"] = json!(e.to_string());
                self.progress.suspend(|| errln!("brume: error: {e}"));
                self.summary.failed_outputs += 1;
            }
        }
        self.progress.inc(1);
        self.append(&record)
    }

    /// A frame that could not be loaded or rendered; `outputs` of it are not written.
    fn frame_failed(&mut self, failed: &Failed, outputs: usize) -> Result<()> {
        let (item, error) = (&failed.item, &failed.error);
        self.progress.suspend(|| {
            errln!("brume: error: skipped {}: {error}", item.image.display());
        });
        self.summary.failed_frames += 1;
        self.progress.inc(outputs as u64);
        self.append(&json!({
            "status": "failed",
            "image": item.image.display().to_string(),
            "error": error.to_string(),
        }))
    }

    fn append(&mut self, record: &serde_json::Value) -> Result<()> {
        let line = format!("{record}\n");
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| Error::io(&self.path, e))
    }
}

/// The thinnest fog a batch renders, m⁻¹: visibility 3,000 km, no fog a camera can see
/// (and β names the output files: 1e-300 would be a 300-digit name).
const MIN_BETA: f64 = 1e-6;
/// The densest, m⁻¹: visibility 0.3 m.
const MAX_BETA: f64 = 10.0;

/// The least and largest β that `dist` draws (its 1e-6 and 1 − 1e-6 quantiles), which
/// must lie in [`MIN_BETA`, `MAX_BETA`] as --beta's values do.
fn drawn_beta_bounds(dist: &BetaDistribution) -> Result<Vec<f64>> {
    let bounds = vec![dist.quantile(1e-6), dist.quantile(1.0 - 1e-6)];
    if bounds.iter().any(|b| !(MIN_BETA..=MAX_BETA).contains(b)) {
        return Err(Error::invalid(
            "--beta-dist",
            dist,
            format!(
                "a distribution whose draws stay from {MIN_BETA} to {MAX_BETA} per metre \
                 (its 1e-6 and 1 − 1e-6 quantiles are {:.3e} and {:.3e})",
                bounds[0], bounds[1]
            ),
        ));
    }
    Ok(bounds)
}

/// `--beta 0.005,0.01,0.02`: each in [`MIN_BETA`, `MAX_BETA`], no repeats.
fn parse_betas(text: &str) -> Result<Vec<f64>> {
    let mut betas = Vec::new();
    for part in text.split(',') {
        let beta: f64 = part.trim().parse().map_err(|_| {
            Error::invalid(
                "--beta",
                part,
                "extinction coefficients in 1/m, e.g. 0.005,0.01,0.02",
            )
        })?;
        if !(MIN_BETA..=MAX_BETA).contains(&beta) {
            return Err(Error::invalid(
                "--beta",
                part,
                format!(
                    "an extinction coefficient from {MIN_BETA} to {MAX_BETA} per metre \
                     (visibility from 300 m to 0.3 m)"
                ),
            ));
        }
        if betas.contains(&beta) {
            return Err(Error::invalid("--beta", part, "each β once"));
        }
        betas.push(beta);
    }
    Ok(betas)
}

fn progress_bar(outputs: u64) -> ProgressBar {
    let bar = ProgressBar::new(outputs);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} outputs, {per_sec}, ETA {eta}")
            .expect("a valid template"),
    );
    bar
}

/// Totals over the run, for the summary.
#[derive(Default)]
struct Stats {
    frames: usize,
    decode_ms: f64,
    prep_ms: f64,
    /// Refinement and the range in metres, once per frame on the GPU's thread.
    refine_ms: f64,
    gpu_ms: f64,
    render_ms: f64,
}

impl Stats {
    fn print(&self, summary: &Summary, wall_s: f64, log: &Path) {
        let Summary {
            written,
            skipped,
            failed_outputs,
            failed_frames,
            encode_ms,
        } = *summary;
        let n = written.max(1) as f64;
        let mut line = format!(
            "wrote {written} outputs of {} frames in {wall_s:.1} s, skipped {skipped} already \
             written, failed {failed_outputs} outputs and {failed_frames} frames",
            self.frames
        );
        if written > 0 {
            line += &format!(
                "; {:.2} s per output (wall); per output: decode {:.0} ms, pre-processing \
                 {:.0} ms, refinement {:.0} ms, render {:.0} ms (GPU {:.0} ms), encode {:.0} ms",
                wall_s / n,
                self.decode_ms / n,
                self.prep_ms / n,
                self.refine_ms / n,
                self.render_ms / n,
                self.gpu_ms / n,
                encode_ms / n,
            );
        }
        outln!("{line}; log {}", log.display());
    }
}

impl BatchArgs {
    /// The library's options for every frame: the batch's blur, airlight,
    /// pre-processing, refinement and conventions, checked (and the blur's schedule, which
    /// does not depend on β, made once) before any frame is read.
    fn frame_options(&self, betas: &[f64]) -> Result<FrameOptions> {
        if self.no_prep {
            let seed_read = self.capture.reads_seed() || self.beta_dist.is_some();
            super::options::refuse_prep_options(&self.prep, seed_read)?;
        }
        let mut opts = FrameOptions::default();
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
        opts.prepare.refine = self.refine.options(DepthFormat::Auto)?;
        opts.refine_mode = self.refine.mode;
        opts.sky_mask = self.prep.sky_mask.clone();
        opts.sky_mask_format = self.prep.sky_mask_format;
        opts.ego_mask = self.prep.ego_mask.clone();
        if self.compat == Some(Compat::FoggyCityscapes) {
            opts.conventions = Conventions::FoggyCityscapes;
        }
        for mask in opts.sky_mask.iter().chain(&opts.ego_mask) {
            if !mask.is_file() {
                let flag = match opts.sky_mask.as_ref() == Some(mask) {
                    true => "--sky-mask",
                    false => "--ego-mask",
                };
                return Err(Error::invalid(flag, mask.display(), "an existing PNG mask"));
            }
        }
        for &beta in betas {
            let haze = opts.fog_at(beta)?.haze([1.0; 3])?;
            check_schedule(&haze, &opts.fog.blur, opts.fog.lambda)?;
        }
        Ok(opts)
    }
}

/// The blur's schedule can be made: a λ too large for the pass limit names `--lambda`.
fn check_schedule(medium: &dyn Medium, blur: &Blur, lambda: f64) -> Result<()> {
    blur.schedule_for(medium).map(|_| ()).map_err(|e| match e {
        Error::InvalidParameter { name, expected, .. } if name != "rho_max" => {
            Error::invalid("--lambda", lambda, expected)
        }
        e => e,
    })
}
