//! A dataset fogged in bulk, as `brume batch` does it, for any host. Each frame is loaded
//! and pre-processed once, then rendered for every β on one GL context; loading the next
//! frame and writing the last outputs run on their own threads while the GPU works.
//! Outputs are written atomically and logged (JSON lines) as soon as each is in place, so
//! a run that stops leaves only complete files, and the next run skips them. A [`Shard`]
//! takes a deterministic share of the frames, for array jobs. A frame refused memory
//! while others were loaded beside it is tried again alone once they are done.
//!
//! ```no_run
//! use brume::dataset::{Batch, BatchEvent, BatchOptions};
//! # fn main() -> brume::Result<()> {
//! let opts = BatchOptions::new("foggy".into());
//! let batch = Batch::plan(&["cityscapes/leftImg8bit/val".into()], None, opts)?;
//! let mut headless = brume::Headless::new(None)?;
//! let report = batch.run(headless.renderer()?, &|event: BatchEvent| {
//!     if let BatchEvent::Written { output } = event {
//!         println!("{}", output.display());
//!     }
//! })?;
//! report.check()?; // an error if a frame or an output failed
//! # Ok(()) }
//! ```

use super::destinations::{check_destinations, check_sky_mask_size};
use super::report::{BatchEvent, BatchReport};
use super::settings::{check_settings, record_settings, settings_of};
use super::writer::{write_outputs, Encode, Event, Log};
use super::{find_cityscapes, read_manifest, Item, Shard};
use crate::blur::Blur;
use crate::error::{Error, Result};
use crate::io::output;
use crate::medium::Medium;
use crate::photo::{
    transmittance_rgb8, BetaDistribution, CaptureOptions, Frame, FrameFog, FrameOptions,
};
use crate::renderer::Renderer;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::sync::Arc;
use std::time::Instant;

/// The thinnest fog a batch renders, m⁻¹: visibility 3,000 km, no fog a camera can see
/// (and β names the output files: 1e-300 would be a 300-digit name).
pub const MIN_BETA: f64 = 1e-6;
/// The densest, m⁻¹: visibility 0.3 m.
pub const MAX_BETA: f64 = 10.0;

/// The extinctions a batch fogs its frames at.
#[derive(Clone, Debug, PartialEq)]
pub enum Betas {
    /// Every frame at each of these β (m⁻¹), each in [`MIN_BETA`, `MAX_BETA`] and given
    /// once.
    Each(Vec<f64>),
    /// One β per frame, drawn from the distribution under the capture's seed: a function
    /// of the frame's name alone ([`Item::drawn_beta`]), whatever the order or shard.
    Drawn(BetaDistribution),
}

/// What a batch writes and how: the output folder, the extinctions, the share of the
/// frames, and how each frame is read, prepared, fogged and captured.
#[derive(Clone, Debug, PartialEq)]
pub struct BatchOptions {
    /// The output folder (made by [`Batch::run`]); the input tree is mirrored under it,
    /// and the log is `brume-batch-{K}-of-{N}.jsonl` in it.
    pub out: PathBuf,
    /// The extinctions of each frame's outputs.
    pub betas: Betas,
    /// The share of the frames this run takes.
    pub shard: Shard,
    /// Also write each output's transmittance τ as an 8-bit grey PNG.
    pub transmittance: bool,
    /// How every frame is read, prepared and fogged.
    pub frame: FrameOptions,
    /// The camera after the fog; each output's noise is seeded by the seed, the frame's
    /// name and its β.
    pub capture: CaptureOptions,
    /// Loader threads, each decoding and pre-processing every `loaders`-th frame ahead of
    /// the GPU (1 to [`MAX_LOADERS`]): on a real GPU one loader cannot keep up. A lone
    /// loader holds up to two frames in memory, several one each.
    pub loaders: usize,
    /// Writer threads, each capturing, encoding and writing one output at a time (1 to
    /// [`MAX_WRITERS`]); the log keeps the outputs' order. Each holds its output's image
    /// (32 MB at 2048 x 1024): on a real GPU, with several loaders, one writer (about 40
    /// ms of PNG encoding an output) sets the rate.
    pub writers: usize,
}

/// The most loader threads a batch runs.
pub const MAX_LOADERS: usize = 16;

/// The most writer threads a batch runs.
pub const MAX_WRITERS: usize = 16;

/// The loader threads by default: a quarter of the cores (the pre-processing of each
/// frame already runs on all of them in parts), from 1 to 4.
pub fn default_loaders() -> usize {
    quarter_of(cores())
}

/// The writer threads by default for outputs captured with `capture`: a quarter of the
/// cores, from 1 to 4, as the loaders; at least 2 when the camera model draws noise or
/// makes a JPEG round trip (about 0.5 s an output at 2048 x 1024, more than the GPU's
/// passes even on llvmpipe: two writers on two cores took a third less time).
pub fn default_writers(capture: &CaptureOptions) -> usize {
    let costly = capture.noise.is_some() || capture.jpeg_quality.is_some();
    let cores = cores();
    quarter_of(cores).max(if costly { cores.min(2) } else { 1 })
}

/// The cores this process may use (1 if that cannot be told).
fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// A quarter of `cores`, from 1 to 4.
fn quarter_of(cores: usize) -> usize {
    (cores / 4).clamp(1, 4)
}

impl BatchOptions {
    /// Foggy Cityscapes' three extinctions (0.005, 0.01, 0.02 m⁻¹) of every frame, written
    /// under `out`, with brume's default frame options and no capture.
    pub fn new(out: PathBuf) -> BatchOptions {
        BatchOptions {
            out,
            betas: Betas::Each(vec![0.005, 0.01, 0.02]),
            shard: Shard::ALL,
            transmittance: false,
            frame: FrameOptions::default(),
            capture: CaptureOptions::default(),
            loaders: default_loaders(),
            writers: default_writers(&CaptureOptions::default()),
        }
    }
}

/// Refuses a β outside [`MIN_BETA`, `MAX_BETA`], named `beta`.
pub fn check_beta(beta: f64) -> Result<()> {
    if (MIN_BETA..=MAX_BETA).contains(&beta) {
        return Ok(());
    }
    Err(Error::invalid(
        "beta",
        beta,
        format!(
            "an extinction coefficient from {MIN_BETA} to {MAX_BETA} per metre (visibility \
             from 3,000 km to 0.3 m)"
        ),
    ))
}

/// A frame that could not be loaded or rendered.
pub(super) struct Failed {
    pub(super) item: Item,
    pub(super) error: Error,
}

/// A batch checked and ready to run: its options, the frames of its shard with the β
/// values still to write, and the outputs proven to lie under the output folder, one
/// file each.
pub struct Batch {
    opts: BatchOptions,
    /// Frames of this shard with the β values whose outputs are missing.
    pending: Vec<(Item, Vec<f64>)>,
    /// Frames of this shard that could not be assembled (no disparity, no camera).
    failures: Vec<Failed>,
    /// Frames found in all shards.
    total: usize,
    /// Outputs of this shard already complete, skipped.
    skipped: usize,
    /// The settings its outputs are made with ([`settings_of`]).
    settings: serde_json::Value,
}

impl Batch {
    /// The frames of the Cityscapes trees under `inputs` ([`find_cityscapes`]) and of
    /// `manifest` ([`read_manifest`]), checked before any file or folder is made: the
    /// options (each β, the masks exist, the blur's schedule at each β), a shared sky mask
    /// of every frame's size, every frame's outputs under [`BatchOptions::out`], its own
    /// and none a file a frame reads, and that the outputs already in the folder were made with these settings
    /// ([`SETTINGS_FILE`](super::SETTINGS_FILE)). Outputs already complete are skipped.
    /// Frames that cannot be assembled (missing disparity or camera) are not an error
    /// here: the run logs them as failed.
    pub fn plan(inputs: &[PathBuf], manifest: Option<&Path>, opts: BatchOptions) -> Result<Batch> {
        for (name, threads, max) in [
            ("loaders", opts.loaders, MAX_LOADERS),
            ("writers", opts.writers, MAX_WRITERS),
        ] {
            if !(1..=max).contains(&threads) {
                let kind = name.trim_end_matches('s');
                return Err(Error::invalid(
                    name,
                    threads,
                    format!("1 to {max} {kind} threads"),
                ));
            }
        }
        let bounds = checked_betas(&opts.betas)?;
        check_frame_options(&opts.frame, &bounds)?;
        if opts.out.exists() && !opts.out.is_dir() {
            return Err(Error::invalid(
                "out",
                opts.out.display(),
                "a folder for the outputs (this is a file)",
            ));
        }
        let (items, mut failures) = collect_items(inputs, manifest)?;
        if let Some(mask) = &opts.frame.sky_mask {
            check_sky_mask_size(mask, &items)?;
        }
        // A drawn β only changes the number in an output's name: its median stands for
        // all of them.
        let named = match &opts.betas {
            Betas::Drawn(dist) => vec![dist.quantile(0.5)],
            Betas::Each(betas) => betas.clone(),
        };
        check_destinations(&opts.out, opts.transmittance, &items, &named)?;
        let settings = settings_of(&opts);
        check_settings(&opts.out, &settings)?;
        let total = items.len() + failures.len();
        failures.retain(|f| opts.shard.contains(&f.item));
        let mut skipped = 0;
        let pending = items
            .into_iter()
            .filter(|item| opts.shard.contains(item))
            .filter_map(|item| {
                let wanted = match &opts.betas {
                    Betas::Drawn(dist) => vec![item.drawn_beta(dist, opts.capture.seed)],
                    Betas::Each(betas) => betas.clone(),
                };
                let todo: Vec<f64> = wanted
                    .iter()
                    .copied()
                    .filter(|&b| !outputs_complete(&opts, &item, b))
                    .collect();
                skipped += wanted.len() - todo.len();
                (!todo.is_empty()).then_some((item, todo))
            })
            .collect();
        Ok(Batch {
            opts,
            pending,
            failures,
            total,
            skipped,
            settings,
        })
    }

    /// Frames found, in all shards.
    pub fn frames_found(&self) -> usize {
        self.total
    }

    /// Outputs this run will write (or fail).
    pub fn outputs(&self) -> usize {
        self.pending.iter().map(|(_, b)| b.len()).sum()
    }

    /// Outputs of this shard already complete, which the run skips.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    /// The share of the frames this run takes.
    pub fn shard(&self) -> Shard {
        self.opts.shard
    }

    /// The fogged images this run will write, frame by frame and β by β (each frame's
    /// τ maps beside them with [`BatchOptions::transmittance`]).
    pub fn planned_outputs(&self) -> impl Iterator<Item = PathBuf> + '_ {
        self.pending.iter().flat_map(move |(item, betas)| {
            betas
                .iter()
                .map(move |&beta| item.foggy_output(&self.opts.out, beta))
        })
    }

    /// The frames of this shard that cannot be assembled (a missing disparity or camera
    /// file), each colour image with why: the run logs them as failed.
    pub fn unassembled_frames(&self) -> impl Iterator<Item = (&Path, &Error)> {
        self.failures
            .iter()
            .map(|f| (f.item.image.as_path(), &f.error))
    }

    /// The run's log: one JSON object per output or failed frame, appended.
    pub fn log_path(&self) -> PathBuf {
        let Shard { index, count } = self.opts.shard;
        self.opts
            .out
            .join(format!("brume-batch-{index}-of-{count}.jsonl"))
    }

    /// Makes the output folder, removes the temporaries an interrupted run left in it,
    /// and writes every pending output, each atomically and logged as soon as it is in
    /// place. `observe` hears of each output and failure as it happens (on the writer
    /// thread, hence `Sync`). A frame or an output that fails is logged and skipped: the
    /// report counts them ([`BatchReport::check`]). Errors: the output folder or the log
    /// cannot be made or written, or an output was refused for want of space on its device
    /// or in the disk quota ([`output::is_out_of_space`]), which stops the run there, the
    /// failure logged, as every later output would fail too.
    pub fn run(
        self,
        renderer: &mut Renderer,
        observe: &(dyn Fn(BatchEvent) + Sync),
    ) -> Result<BatchReport> {
        let outputs = self.outputs();
        let log_path = self.log_path();
        let Batch {
            opts,
            pending,
            failures,
            total,
            skipped,
            settings,
        } = self;
        log::info!(
            "{total} frames found, {} in shard {}/{}; {outputs} outputs to write, {skipped} \
             already written",
            pending.len() + failures.len(),
            opts.shard.index,
            opts.shard.count
        );
        std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
        let stale = output::remove_stale_temporaries(&opts.out)?;
        record_settings(&opts.out, &settings)?;
        if stale > 0 {
            observe(BatchEvent::RemovedTemporaries {
                count: stale,
                folder: &opts.out,
            });
        }
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&log_path)
            .map_err(|e| Error::io(&log_path, e))?;
        let mut log = Log {
            file,
            path: log_path,
            observe,
            report: BatchReport {
                skipped,
                ..BatchReport::default()
            },
        };
        for f in &failures {
            log.frame_failed(f, 0)?;
        }
        let started = Instant::now();
        let (event_tx, event_rx) = sync_channel::<Event>(2);
        let frames: Vec<Item> = pending.iter().map(|(i, _)| i.clone()).collect();
        let mut gpu = Gpu {
            opts: &opts,
            events: event_tx,
            times: BatchReport::default(),
        };
        let (log, t) = std::thread::scope(|s| -> Result<(Log, BatchReport)> {
            let loaded = spawn_loaders(s, &opts.frame, frames, opts.loaders);
            let writers = opts.writers;
            let writer = s.spawn(move || write_outputs(event_rx, log, writers));
            gpu.render_frames(renderer, &pending, loaded);
            let Gpu { times, events, .. } = gpu;
            drop(events); // ends the writer's loop
            let log = writer.join().expect("the writer thread does not panic")?;
            Ok((log, times))
        })?;
        Ok(BatchReport {
            frames: t.frames,
            decode_ms: t.decode_ms,
            prep_ms: t.prep_ms,
            refine_ms: t.refine_ms,
            gpu_ms: t.gpu_ms,
            render_ms: t.render_ms,
            wall_s: started.elapsed().as_secs_f64(),
            log: log.path,
            ..log.report
        })
    }
}

/// The β values the options are checked at: each of a list (in range, no repeats), or
/// the least and largest a distribution draws (its 1e-6 and 1 − 1e-6 quantiles).
fn checked_betas(betas: &Betas) -> Result<Vec<f64>> {
    match betas {
        Betas::Each(list) => {
            if list.is_empty() {
                return Err(Error::invalid("beta", "(none)", "at least one β"));
            }
            for (i, &beta) in list.iter().enumerate() {
                check_beta(beta)?;
                if list[..i].contains(&beta) {
                    return Err(Error::invalid("beta", beta, "each β once"));
                }
            }
            Ok(list.clone())
        }
        Betas::Drawn(dist) => {
            let bounds = vec![dist.quantile(1e-6), dist.quantile(1.0 - 1e-6)];
            if bounds.iter().any(|&b| check_beta(b).is_err()) {
                return Err(Error::invalid(
                    "beta_dist",
                    dist,
                    format!(
                        "a distribution whose draws stay from {MIN_BETA} to {MAX_BETA} per \
                         metre (its 1e-6 and 1 − 1e-6 quantiles are {:.3e} and {:.3e})",
                        bounds[0], bounds[1]
                    ),
                ));
            }
            Ok(bounds)
        }
    }
}

/// The frame options hold at every β of `betas`: the shared masks exist, and the blur's
/// schedule can be made (a λ too large for the pass limit is named `lambda`).
fn check_frame_options(opts: &FrameOptions, betas: &[f64]) -> Result<()> {
    for (name, mask) in [("sky_mask", &opts.sky_mask), ("ego_mask", &opts.ego_mask)] {
        if let Some(mask) = mask.as_ref().filter(|m| !m.is_file()) {
            return Err(Error::invalid(name, mask.display(), "an existing PNG mask"));
        }
    }
    for &beta in betas {
        let haze = opts.fog_at(beta)?.haze([1.0; 3])?;
        check_schedule(&haze, &opts.fog.blur, opts.fog.lambda)?;
    }
    Ok(())
}

fn check_schedule(medium: &dyn Medium, blur: &Blur, lambda: f64) -> Result<()> {
    blur.schedule_for(medium).map(|_| ()).map_err(|e| match e {
        Error::InvalidParameter { name, expected, .. } if name != "rho_max" => {
            Error::invalid("lambda", lambda, expected)
        }
        e => e,
    })
}

/// The frames of the roots and the manifest, sorted by key; frames that cannot be
/// assembled (missing disparity or camera) as failures.
fn collect_items(inputs: &[PathBuf], manifest: Option<&Path>) -> Result<(Vec<Item>, Vec<Failed>)> {
    let mut items = Vec::new();
    let mut failures = Vec::new();
    for root in inputs {
        if !root.is_dir() {
            return Err(Error::invalid(
                "input folder",
                root.display(),
                "a folder to search for Cityscapes frames ({name}_leftImg8bit.png)",
            ));
        }
        for found in find_cityscapes(root)? {
            match found {
                Ok(item) => items.push(item),
                Err(error) => failures.push(Failed {
                    item: unassembled(&error),
                    error,
                }),
            }
        }
    }
    if let Some(m) = manifest {
        items.extend(read_manifest(m)?);
    }
    if items.is_empty() && failures.is_empty() {
        return Err(Error::invalid(
            "inputs",
            "(no frames)",
            "folders with Cityscapes frames or a manifest (CSV) with at least one row",
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

fn outputs_complete(opts: &BatchOptions, item: &Item, beta: f64) -> bool {
    item.foggy_output(&opts.out, beta).is_file()
        && (!opts.transmittance || item.transmittance_output(&opts.out, beta).is_file())
}

/// A frame loaded, or why it could not be.
type Loaded = std::result::Result<Frame, Failed>;

/// `item`'s failure for `error`.
fn failed(item: &Item, error: Error) -> Failed {
    Failed {
        item: item.clone(),
        error,
    }
}

/// Starts `count` loader threads in `scope`: loader k decodes and pre-processes frames k,
/// k + count, k + 2·count … in turn, one ahead of the GPU. Returns the frames in their
/// order, each taken from the loader that has it: every loader has a channel of its own,
/// so none runs far ahead (a lone loader two frames, several one each), and the GPU's
/// order (and so the log's) is the frames' whatever their loading times.
fn spawn_loaders<'scope>(
    scope: &'scope std::thread::Scope<'scope, '_>,
    options: &'scope FrameOptions,
    frames: Vec<Item>,
    count: usize,
) -> impl Iterator<Item = Loaded> {
    let count = count.min(frames.len()).max(1);
    let frames = Arc::new(frames);
    let receivers: Vec<Receiver<Loaded>> = (0..count)
        .map(|k| {
            // One loader keeps a frame in hand while the GPU renders another and one more
            // in the channel; several keep one each, their number slack enough.
            let (tx, rx) = sync_channel::<Loaded>(usize::from(count == 1));
            let frames = Arc::clone(&frames);
            scope.spawn(move || load_frames(options, frames.iter().skip(k).step_by(count), tx));
            rx
        })
        .collect();
    (0..frames.len()).map_while(move |i| receivers[i % count].recv().ok())
}

/// A loader thread: decodes and pre-processes each of `frames` in turn, until the GPU's
/// side hangs up.
fn load_frames<'a>(
    options: &FrameOptions,
    frames: impl Iterator<Item = &'a Item>,
    tx: SyncSender<Loaded>,
) {
    for item in frames {
        let loaded = Frame::load(item, options).map_err(|error| failed(item, error));
        if tx.send(loaded).is_err() {
            return;
        }
    }
}

/// The GPU's side of a run: the options, the channel to the writer thread, and the
/// times it adds up (the loader's and its own).
struct Gpu<'a> {
    opts: &'a BatchOptions,
    events: SyncSender<Event>,
    times: BatchReport,
}

impl Gpu<'_> {
    /// The GPU loop: every β of every frame, in the order the loader delivers them;
    /// outputs and failures go to the writer thread as they come. A frame refused memory
    /// before any of its outputs was made, while the loaders held others, is tried again
    /// alone once they are done ([`Gpu::render_alone`]).
    fn render_frames(
        &mut self,
        renderer: &mut Renderer,
        pending: &[(Item, Vec<f64>)],
        loaded: impl Iterator<Item = Loaded>,
    ) {
        let mut short = Vec::new();
        for ((item, betas), loaded) in pending.iter().zip(loaded) {
            let was_loaded = loaded.is_ok();
            let outcome = match loaded {
                Ok(frame) => self.loaded_frame(renderer, frame, betas, true),
                Err(failed) => Err(failed.error),
            };
            match outcome {
                Ok(true) => {}
                Ok(false) => return,
                Err(Error::OutOfMemory { .. }) => short.push((item, betas, was_loaded)),
                Err(error) => {
                    if !self.frame_failed(failed(item, error), betas.len()) {
                        return;
                    }
                }
            }
        }
        self.render_alone(renderer, &short);
    }

    /// Loads and renders each of `frames` (refused memory beside the frames loaded with
    /// them: with `true` where it was loaded then) on this thread, one at a time, as a run
    /// of one frame would; a second refusal is the frame's failure.
    fn render_alone(&mut self, renderer: &mut Renderer, frames: &[(&Item, &Vec<f64>, bool)]) {
        if let Some((first, ..)) = frames.first() {
            let more = match frames.len() {
                1 => String::new(),
                n => format!(" (and {} more frames)", n - 1),
            };
            log::warn!(
                "{}{more} ran out of memory beside the frames loaded and written with it: \
                 tried again alone (fewer `loaders` hold less)",
                first.image.display(),
            );
        }
        let opts = self.opts;
        for &(item, betas, was_loaded) in frames {
            // The last frame's textures would be made again for this one anyway.
            renderer.free_kept_textures();
            // Counted, and its warnings sent, when it was first loaded.
            let outcome = Frame::load(item, &opts.frame)
                .and_then(|frame| self.loaded_frame(renderer, frame, betas, !was_loaded));
            let writer_alive = match outcome {
                Ok(alive) => alive,
                Err(error) => self.frame_failed(failed(item, error), betas.len()),
            };
            if !writer_alive {
                return;
            }
        }
    }

    /// Adds a loaded frame's times (and, when `first`, counts it and hands its warnings to
    /// the writer), then renders it. False when the writer is gone; the error when the
    /// frame failed before any of its outputs was sent (one after is handed on).
    fn loaded_frame(
        &mut self,
        renderer: &mut Renderer,
        frame: Frame,
        betas: &[f64],
        first: bool,
    ) -> Result<bool> {
        self.times.decode_ms += frame.decode_ms;
        self.times.prep_ms += frame.prep_ms;
        if first {
            self.times.frames += 1;
            if !self.frame_warned(&frame) {
                return Ok(false);
            }
        }
        self.render_frame(renderer, frame, betas)
    }

    /// Hands a frame's warnings, if it has any, to the writer; false when the writer is
    /// gone.
    fn frame_warned(&self, frame: &Frame) -> bool {
        let warnings = frame.warnings().to_vec();
        if warnings.is_empty() {
            return true;
        }
        let image = frame.item.image.clone();
        let event = Event::FrameWarned { image, warnings };
        self.events.send(event).is_ok()
    }

    /// Hands a frame's failure (`outputs` of it not written) to the writer; false when the
    /// writer is gone.
    fn frame_failed(&self, failed: Failed, outputs: usize) -> bool {
        let event = Event::FrameFailed { failed, outputs };
        self.events.send(event).is_ok()
    }

    /// Refines a frame once on the GPU, then renders its β values from one upload, each
    /// output handed to the writer thread as soon as it is read back. False when the writer
    /// is gone; the error when none of the outputs was sent (a failure after some counts
    /// only those not sent, and is handed on here).
    fn render_frame(
        &mut self,
        renderer: &mut Renderer,
        mut frame: Frame,
        betas: &[f64],
    ) -> Result<bool> {
        frame.refine(&self.opts.frame, renderer)?;
        self.times.refine_ms += frame.refine_ms;
        let (mut sent, mut writer_gone) = (0, false);
        let mut started = Instant::now();
        let (opts, events) = (self.opts, &self.events);
        let times = &mut self.times;
        let result = frame.fog_each(renderer, &opts.frame, betas, |beta, fogged| {
            let render_ms = started.elapsed().as_secs_f64() * 1e3;
            // NaN (JSON null) where the GPU timer's figures were rejected.
            if fogged.gpu_ms.is_finite() {
                times.gpu_ms += fogged.gpu_ms;
            }
            times.render_ms += render_ms;
            let job = encode(opts, &frame, beta, fogged, render_ms);
            if events.send(Event::Output(job)).is_err() {
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
            Ok(()) => Ok(true),
            // The writer is gone: the run is ending, nothing more to report.
            Err(_) if writer_gone => Ok(false),
            Err(error) if sent == 0 => Err(error),
            Err(error) => Ok(self.frame_failed(failed(&frame.item, error), betas.len() - sent)),
        }
    }
}

/// One output of a frame: the image, its transmittance map if asked for, and its log
/// record.
fn encode(
    opts: &BatchOptions,
    frame: &Frame,
    beta: f64,
    fogged: FrameFog,
    render_ms: f64,
) -> Encode {
    let item = &frame.item;
    let path = item.foggy_output(&opts.out, beta);
    let metres = frame.metres().expect("refined before fog");
    let transmittance = opts.transmittance.then(|| {
        (
            item.transmittance_output(&opts.out, beta),
            transmittance_rgb8(&fogged.haze, metres),
            metres.width(),
            metres.height(),
        )
    });
    let beta_dist = match &opts.betas {
        Betas::Drawn(dist) => Some(dist.to_string()),
        Betas::Each(_) => None,
    };
    let record = json!({
        "status": "ok",
        "image": item.image.display().to_string(),
        "depth": item.depth.display().to_string(),
        "camera": item.camera.as_ref().map(|p| p.display().to_string()),
        "sky_mask": item.sky_mask.as_ref().map(|p| p.display().to_string()),
        "output": path.display().to_string(),
        "brume": crate::VERSION,
        "sources": crate::SOURCES,
        "beta": beta,
        "beta_dist": beta_dist,
        "visibility_m": -(0.05f64.ln()) / beta,
        "width": fogged.image.width(),
        "height": fogged.image.height(),
        "sigma_max": fogged.sigma_max,
        "diffusion_passes": fogged.passes,
        "airlight": fogged.airlight,
        "airlight_source": fogged.airlight_source,
        "decode_ms": frame.decode_ms,
        "prep_ms": frame.prep_ms,
        "refine_ms": frame.refine_ms,
        "gpu_ms": fogged.gpu_ms,
        "render_ms": render_ms,
        "capture": opts.capture.to_json(),
        "warnings": frame.warnings(),
        "depth_notes": frame.photo.depth.notes,
        "colour_profile": frame.photo.metadata.profile().map(|p| p.description()),
    });
    let capture = CaptureOptions {
        seed: opts.capture.seed ^ item.name_hash() ^ beta.to_bits(),
        ..opts.capture
    };
    Encode {
        path,
        image: fogged.image,
        metadata: frame.photo.metadata.clone(),
        transmittance,
        record,
        capture,
    }
}
