//! `brume batch`: fog a dataset. Each frame is loaded and pre-processed once, then
//! rendered for every β on one GL context; loading the next frame and writing the last
//! outputs run on their own threads while the GPU works. Outputs are written atomically, so
//! a run that stops leaves only complete files, and the next run skips them. `--shard K/N`
//! takes a deterministic share of the frames, for array jobs.

use super::args::{BatchArgs, Compat, RenderArgs};
use super::render::{self as render_cmd, PrepReport, Scene};
use brume::dataset::{self, Item, Shard};
use brume::io::output::Outputs;
use brume::raster::ScalarMap;
use brume::{Error, Renderer, Result};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::time::Instant;

/// A frame ready for the GPU: loaded and pre-processed, with what that cost.
struct Loaded {
    item: Item,
    args: RenderArgs,
    scene: Scene,
    prep: PrepReport,
    decode_ms: f64,
    prep_ms: f64,
}

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
}

/// Everything a run needs, checked before anything is created: the options, the frames of
/// this shard with the β values still to write, and the outputs proven to lie under
/// `--out`, one file each.
pub struct Plan {
    shard: Shard,
    template: RenderArgs,
    /// Frames of this shard with the β values whose outputs are missing.
    pending: Vec<(Item, Vec<f64>)>,
    /// Frames of this shard that could not be assembled (no disparity, no camera).
    failures: Vec<Failed>,
    /// Frames found in all shards.
    total: usize,
    /// Outputs of this shard already complete, skipped.
    skipped: usize,
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
    let template = args.render_template(betas[0])?;
    if args.out.exists() && !args.out.is_dir() {
        return Err(Error::invalid(
            "--out",
            args.out.display(),
            "a folder for the outputs (this is a file)",
        ));
    }
    let (items, mut failures) = collect_items(args)?;
    super::batch_checks::check_sky_mask_size(args, &items)?;
    super::batch_checks::check_destinations(args, &items, &betas)?;
    let total = items.len() + failures.len();
    let items: Vec<Item> = items.into_iter().filter(|i| shard.contains(i)).collect();
    failures.retain(|f| shard.contains(&f.item));
    let mut skipped = 0;
    let pending: Vec<(Item, Vec<f64>)> = items
        .into_iter()
        .filter_map(|item| {
            let todo: Vec<f64> = betas
                .iter()
                .copied()
                .filter(|&b| !outputs_complete(args, &item, b))
                .collect();
            skipped += betas.len() - todo.len();
            (!todo.is_empty()).then_some((item, todo))
        })
        .collect();
    Ok(Plan {
        shard,
        template,
        pending,
        failures,
        total,
        skipped,
    })
}

/// Runs the batch `plan` made from `args` on `renderer`.
pub fn run(args: &BatchArgs, plan: Plan, renderer: &mut Renderer) -> Result<()> {
    let Plan {
        shard,
        template,
        pending,
        failures,
        total,
        skipped,
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
    let (load_tx, load_rx) = sync_channel::<std::result::Result<Loaded, Failed>>(1);
    let (event_tx, event_rx) = sync_channel::<Event>(2);
    let frames: Vec<Item> = pending.iter().map(|(i, _)| i.clone()).collect();
    let mut stats = Stats::default();
    let log = std::thread::scope(|s| -> Result<Log> {
        s.spawn(|| load_frames(&template, frames, load_tx));
        let writer = s.spawn(move || write_outputs(event_rx, log));
        render_frames(args, renderer, &pending, load_rx, &event_tx, &mut stats);
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
    template: &RenderArgs,
    frames: Vec<Item>,
    tx: SyncSender<std::result::Result<Loaded, Failed>>,
) {
    for item in frames {
        let loaded = load_frame(template, &item).map_err(|error| Failed {
            item: item.clone(),
            error,
        });
        if tx.send(loaded).is_err() {
            return;
        }
    }
}

fn load_frame(template: &RenderArgs, item: &Item) -> Result<Loaded> {
    let args = frame_args(template, item);
    let t = Instant::now();
    let scene = render_cmd::load_scene(&args)?;
    let decode_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let prep = render_cmd::preprocess(&args, &scene)?;
    let prep_ms = t.elapsed().as_secs_f64() * 1e3;
    Ok(Loaded {
        item: item.clone(),
        args,
        scene,
        prep,
        decode_ms,
        prep_ms,
    })
}

/// `brume render`'s options for one frame: the batch's, with the frame's files.
fn frame_args(template: &RenderArgs, item: &Item) -> RenderArgs {
    let mut args = template.clone();
    args.image = Some(item.image.clone());
    args.depth.depth = Some(item.depth.clone());
    if item.calib.is_some() {
        args.depth.calib = item.calib.clone();
    }
    apply_companions(&mut args, item);
    args
}

/// The GPU loop: every β of every frame, in the order the loader delivers them; outputs
/// and failures go to the writer thread as they come.
fn render_frames(
    args: &BatchArgs,
    renderer: &mut Renderer,
    pending: &[(Item, Vec<f64>)],
    rx: Receiver<std::result::Result<Loaded, Failed>>,
    events: &SyncSender<Event>,
    stats: &mut Stats,
) {
    for ((_, betas), loaded) in pending.iter().zip(rx) {
        let loaded = match loaded {
            Ok(l) => l,
            Err(failed) => {
                let event = Event::FrameFailed {
                    failed,
                    outputs: betas.len(),
                };
                if events.send(event).is_err() {
                    return;
                }
                continue;
            }
        };
        stats.frames += 1;
        stats.decode_ms += loaded.decode_ms;
        stats.prep_ms += loaded.prep_ms;
        // Refined once, and the range in metres made once, for every β of the frame.
        let frame = match refine_frame(renderer, loaded, stats) {
            Ok(f) => f,
            Err(failed) => {
                let event = Event::FrameFailed {
                    failed: *failed,
                    outputs: betas.len(),
                };
                if events.send(event).is_err() {
                    return;
                }
                continue;
            }
        };
        for (k, &beta) in betas.iter().enumerate() {
            let event = match render_beta(args, renderer, &frame, beta) {
                Ok((job, gpu_ms, render_ms)) => {
                    // NaN (JSON null) where the GPU timer's figures were rejected.
                    if gpu_ms.is_finite() {
                        stats.gpu_ms += gpu_ms;
                    }
                    stats.render_ms += render_ms;
                    Event::Output(job)
                }
                Err(error) => Event::FrameFailed {
                    failed: Failed {
                        item: frame.loaded.item.clone(),
                        error,
                    },
                    outputs: betas.len() - k,
                },
            };
            let failed = matches!(event, Event::FrameFailed { .. });
            if events.send(event).is_err() {
                return;
            }
            if failed {
                break;
            }
        }
    }
}

/// A loaded frame with its range refined (on the GPU) and in the medium's metres.
struct Refined {
    loaded: Loaded,
    /// The range texture's values (metres), shared by every β.
    range: ScalarMap,
}

/// Refines a loaded frame's range with its image ([`super::refine::refine_scene`]) and makes
/// the range every β renders from.
fn refine_frame(
    renderer: &mut Renderer,
    mut loaded: Loaded,
    stats: &mut Stats,
) -> std::result::Result<Refined, Box<Failed>> {
    let t = Instant::now();
    let Loaded {
        args, scene, prep, ..
    } = &mut loaded;
    let result = super::refine::refine_scene(args, scene, prep, renderer)
        .and_then(|_| render_cmd::haze_inputs(args, prep));
    stats.refine_ms += t.elapsed().as_secs_f64() * 1e3;
    match result {
        Ok((range, _, _)) => Ok(Refined { loaded, range }),
        Err(error) => Err(Box::new(Failed {
            item: loaded.item,
            error,
        })),
    }
}

/// Renders one β of a loaded frame; returns the output to write, the GPU time and the
/// render's wall time (uploads, passes, read-back).
fn render_beta(
    args: &BatchArgs,
    renderer: &mut Renderer,
    refined: &Refined,
    beta: f64,
) -> Result<(Encode, f64, f64)> {
    let (frame, range) = (&refined.loaded, &refined.range);
    let t = Instant::now();
    let mut fog_args = frame.args.clone();
    apply_beta(&mut fog_args, beta);
    let haze = render_cmd::haze_from_args(&fog_args)?;
    let look = render_cmd::look_from_args(&fog_args, &haze, frame.prep.airlight);
    // Foggy Cityscapes' conventions: the blend on the CPU, no passes.
    let (image, passes, gpu_ms) = if fog_args.compat == Some(Compat::FoggyCityscapes) {
        let (image, _, _) =
            super::compat::foggy_cityscapes_image(&fog_args, &frame.scene.image, range, beta)?;
        (image, 0, 0.0)
    } else {
        let r = renderer.render(&frame.scene.image, range, look.medium(), &look.blur)?;
        (r.image, r.schedule.steps, r.times.total_ms)
    };
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    let item = &frame.item;
    let path = item.foggy_output(&args.out, beta);
    let transmittance = args.transmittance.then(|| {
        // The range texture is in metres; the medium's unit is haze.range_unit.
        let unit = look.haze.range_unit;
        let t = transmittance_rgb8(range, |r| look.haze.transmission(r / unit)[1]);
        (
            item.transmittance_output(&args.out, beta),
            t,
            range.width(),
            range.height(),
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
        "visibility_m": -(0.05f64.ln()) / beta,
        "width": image.width(),
        "height": image.height(),
        "sigma_max": look.sigma_max(),
        "diffusion_passes": passes,
        "airlight": look.airlight(),
        "airlight_source": frame.prep.airlight_from.name(),
        "decode_ms": frame.decode_ms,
        "prep_ms": frame.prep_ms,
        "gpu_ms": gpu_ms,
        "render_ms": render_ms,
    });
    Ok((
        Encode {
            path,
            image,
            transmittance,
            record,
        },
        gpu_ms,
        render_ms,
    ))
}

/// τ as an 8-bit grey image (top row first); unknown range as τ of the sky (0).
fn transmittance_rgb8(range: &ScalarMap, tau: impl Fn(f64) -> f64) -> Vec<[u8; 3]> {
    range
        .as_slice()
        .iter()
        .map(|&r| {
            let t = if r.is_finite() {
                tau(f64::from(r))
            } else {
                0.0
            };
            let v = (t.clamp(0.0, 1.0) * 255.0).round() as u8;
            [v, v, v]
        })
        .collect()
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
            Event::Output(job) => {
                let t = Instant::now();
                let result = write_one(&job);
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
    /// `brume render`'s options for every frame: the defaults, with the batch's blur,
    /// airlight and pre-processing, and physical fog (`beta`, the first β: loading a frame
    /// then checks that its range is in metres).
    fn render_template(&self, beta: f64) -> Result<RenderArgs> {
        let mut args = render_cmd::default_args();
        apply_beta(&mut args, beta);
        if let Some(l) = self.lambda {
            args.lambda = l;
        }
        if let Some(s) = self.scheme {
            args.scheme = s;
        }
        if let Some(p) = self.precision {
            args.precision = p;
        }
        args.airlight = self.airlight;
        args.albedo = self.albedo;
        args.no_prep = self.no_prep;
        args.prep = self.prep.clone();
        args.compat = self.compat;
        args.refine = self.refine.clone();
        super::options::check_options(&args)?;
        let haze = render_cmd::haze_from_args(&args)?;
        super::inputs::prep_options(&args.prep)?;
        if let Some(mask) = &args.prep.sky_mask {
            if !mask.is_file() {
                return Err(Error::invalid(
                    "--sky-mask",
                    mask.display(),
                    "an existing PNG sky mask",
                ));
            }
        }
        // The blur's steps do not depend on β (σmax is reached at the visibility).
        let look = render_cmd::look_from_args(&args, &haze, [1.0; 3]);
        look.blur.schedule_for(look.medium()).map_err(|e| match e {
            Error::InvalidParameter { name, expected, .. } if name != "rho_max" => {
                Error::invalid("--lambda", args.lambda, expected)
            }
            e => e,
        })?;
        Ok(args)
    }
}

/// The frame's camera file and sky mask, as `--camera` and `--sky-mask` (and a labelIds
/// sky mask as `--ego-mask` too).
fn apply_companions(args: &mut RenderArgs, item: &Item) {
    if item.camera.is_some() {
        args.depth.camera = item.camera.clone();
    }
    if item.sky_mask.is_some() && !args.no_prep && !args.prep.no_sky {
        args.prep.sky_mask = item.sky_mask.clone();
    }
    // A Cityscapes labelIds file names the ego vehicle too (label 1).
    let labels = item.sky_mask.as_ref().filter(|p| {
        brume::io::mask::SkyMaskFormat::from_file_name(p)
            == brume::io::mask::SkyMaskFormat::CityscapesLabelIds
    });
    if labels.is_some() && !args.no_prep && args.prep.ego_mask.is_none() {
        args.prep.ego_mask = labels.cloned();
    }
}

/// The fog at extinction `beta` (1/m), as `--beta`.
fn apply_beta(args: &mut RenderArgs, beta: f64) {
    args.beta = Some(beta);
    args.visibility = None;
}
