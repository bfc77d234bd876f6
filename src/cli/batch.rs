//! `brume batch`: fog a dataset. Each frame is loaded and pre-processed once, then
//! rendered for every β on one GL context; loading the next frame and writing the last
//! outputs run on their own threads while the GPU works. Outputs are written atomically, so
//! a run that stops leaves only complete files, and the next run skips them. `--shard K/N`
//! takes a deterministic share of the frames, for array jobs.

use super::args::{BatchArgs, RenderArgs};
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
    /// The range texture's values (metres), shared by every β.
    range: ScalarMap,
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

/// What the writer did with an output.
struct Written {
    record: serde_json::Value,
    encode_ms: f64,
    error: Option<Error>,
}

/// Runs the batch on `renderer`.
pub fn run(args: &BatchArgs, renderer: &mut Renderer) -> Result<()> {
    let shard = match &args.shard {
        Some(s) => Shard::parse(s)?,
        None => Shard::ALL,
    };
    let betas = parse_betas(&args.beta)?;
    let template = args.render_template(betas[0])?;
    let (items, mut failures) = collect_items(args)?;
    let total = items.len() + failures.len();
    let items: Vec<Item> = items.into_iter().filter(|i| shard.contains(i)).collect();
    failures.retain(|f| shard.contains(&f.item));
    let pending: Vec<(Item, Vec<f64>)> = items
        .into_iter()
        .filter_map(|item| {
            let todo: Vec<f64> = betas
                .iter()
                .copied()
                .filter(|&b| !outputs_complete(args, &item, b))
                .collect();
            (!todo.is_empty()).then_some((item, todo))
        })
        .collect();
    let outputs: usize = pending.iter().map(|(_, b)| b.len()).sum();
    log::info!(
        "{total} frames found, {} in shard {}/{}; {outputs} outputs to write",
        pending.len() + failures.len(),
        shard.index,
        shard.count
    );
    std::fs::create_dir_all(&args.out).map_err(|e| Error::io(&args.out, e))?;
    let log_path = args.out.join(format!(
        "brume-batch-{}-of-{}.jsonl",
        shard.index, shard.count
    ));
    let mut log_file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&log_path)
        .map_err(|e| Error::io(&log_path, e))?;
    let progress = progress_bar(outputs as u64);
    let started = Instant::now();
    let (load_tx, load_rx) = sync_channel::<std::result::Result<Loaded, Failed>>(1);
    let (encode_tx, encode_rx) = sync_channel::<Encode>(2);
    let (written_tx, written_rx) = std::sync::mpsc::channel::<Written>();
    let frames: Vec<Item> = pending.iter().map(|(i, _)| i.clone()).collect();
    let mut stats = Stats::default();
    std::thread::scope(|s| -> Result<()> {
        s.spawn(|| load_frames(&template, frames, load_tx));
        s.spawn(|| write_outputs(encode_rx, written_tx));
        let result = render_frames(
            args,
            renderer,
            &pending,
            load_rx,
            &encode_tx,
            &mut failures,
            &mut stats,
        );
        drop(encode_tx);
        for w in written_rx {
            stats.encode_ms += w.encode_ms;
            progress.inc(1);
            match w.error {
                None => {
                    stats.written += 1;
                    writeln!(log_file, "{}", w.record).map_err(|e| Error::io(&log_path, e))?;
                }
                Some(e) => {
                    let mut record = w.record;
                    record["status"] = json!("failed");
                    record["error"] = json!(e.to_string());
                    eprintln!("brume: error: {e}");
                    writeln!(log_file, "{record}").map_err(|e| Error::io(&log_path, e))?;
                    stats.failed_outputs += 1;
                }
            }
        }
        result
    })?;
    progress.finish_and_clear();
    for f in &failures {
        eprintln!(
            "brume: error: skipped {}: {}",
            f.item.image.display(),
            f.error
        );
        report_failure(&mut log_file, &f.item, &f.error)?;
    }
    stats.print(started.elapsed().as_secs_f64(), &log_path);
    if !failures.is_empty() || stats.failed_outputs > 0 {
        return Err(Error::BatchFailures {
            frames: failures.len(),
            outputs: stats.failed_outputs,
            log: log_path,
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
    // Range in metres, the same for every β: made once, here, off the GPU's thread.
    let (range, _, _) = render_cmd::haze_inputs(&args, &scene, &prep)?;
    let prep_ms = t.elapsed().as_secs_f64() * 1e3;
    Ok(Loaded {
        item: item.clone(),
        args,
        scene,
        prep,
        range,
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

/// The GPU loop: every β of every frame, in the order the loader delivers them.
fn render_frames(
    args: &BatchArgs,
    renderer: &mut Renderer,
    pending: &[(Item, Vec<f64>)],
    rx: Receiver<std::result::Result<Loaded, Failed>>,
    encode: &SyncSender<Encode>,
    failures: &mut Vec<Failed>,
    stats: &mut Stats,
) -> Result<()> {
    for ((_, betas), loaded) in pending.iter().zip(rx) {
        let loaded = match loaded {
            Ok(l) => l,
            Err(f) => {
                failures.push(f);
                continue;
            }
        };
        stats.frames += 1;
        stats.decode_ms += loaded.decode_ms;
        stats.prep_ms += loaded.prep_ms;
        for &beta in betas {
            match render_beta(args, renderer, &loaded, beta) {
                Ok((job, gpu_ms, render_ms)) => {
                    stats.gpu_ms += gpu_ms;
                    stats.render_ms += render_ms;
                    if encode.send(job).is_err() {
                        return Ok(());
                    }
                }
                Err(error) => {
                    failures.push(Failed {
                        item: loaded.item.clone(),
                        error,
                    });
                    break;
                }
            }
        }
    }
    Ok(())
}

/// Renders one β of a loaded frame; returns the output to write, the GPU time and the
/// render's wall time (uploads, passes, read-back).
fn render_beta(
    args: &BatchArgs,
    renderer: &mut Renderer,
    frame: &Loaded,
    beta: f64,
) -> Result<(Encode, f64, f64)> {
    let t = Instant::now();
    let mut fog_args = frame.args.clone();
    apply_beta(&mut fog_args, beta);
    let haze = render_cmd::haze_from_args(&fog_args)?;
    let look = render_cmd::look_from_args(&fog_args, &haze, frame.prep.airlight);
    let range = &frame.range;
    let rendered = renderer.render(&frame.scene.image, range, look.medium(), &look.blur)?;
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    let item = &frame.item;
    let path = item.foggy_output(&args.out, beta);
    let transmittance = args.transmittance.then(|| {
        let t = transmittance_rgb8(range, |r| look.haze.transmission(r)[1]);
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
        "width": rendered.image.width(),
        "height": rendered.image.height(),
        "sigma_max": look.sigma_max(),
        "diffusion_passes": rendered.schedule.steps,
        "airlight": look.airlight(),
        "airlight_source": frame.prep.airlight_source,
        "decode_ms": frame.decode_ms,
        "prep_ms": frame.prep_ms,
        "gpu_ms": rendered.times.total_ms,
        "render_ms": render_ms,
    });
    Ok((
        Encode {
            path,
            image: rendered.image,
            transmittance,
            record,
        },
        rendered.times.total_ms,
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

/// The writer thread: encodes and writes each output atomically.
fn write_outputs(rx: Receiver<Encode>, tx: std::sync::mpsc::Sender<Written>) {
    for job in rx {
        let t = Instant::now();
        let result = write_one(&job);
        let _ = tx.send(Written {
            record: job.record,
            encode_ms: t.elapsed().as_secs_f64() * 1e3,
            error: result.err(),
        });
    }
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

fn report_failure(log: &mut std::fs::File, item: &Item, error: &Error) -> Result<()> {
    let record = json!({
        "status": "failed",
        "image": item.image.display().to_string(),
        "error": error.to_string(),
    });
    writeln!(log, "{record}").map_err(|e| Error::io(item.image.clone(), e))
}

/// `--beta 0.005,0.01,0.02`: finite, > 0, no repeats.
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
        if !(beta.is_finite() && beta > 0.0) {
            return Err(Error::invalid(
                "--beta",
                part,
                "an extinction coefficient > 0 (1/m)",
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
    written: usize,
    failed_outputs: usize,
    decode_ms: f64,
    prep_ms: f64,
    gpu_ms: f64,
    render_ms: f64,
    encode_ms: f64,
}

impl Stats {
    fn print(&self, wall_s: f64, log: &Path) {
        let n = self.written.max(1) as f64;
        println!(
            "wrote {} outputs of {} frames in {:.1} s: {:.2} s per output (wall); per output: \
             decode {:.0} ms, pre-processing {:.0} ms, render {:.0} ms (GPU {:.0} ms), encode {:.0} ms; \
             log {}",
            self.written,
            self.frames,
            wall_s,
            wall_s / n,
            self.decode_ms / n,
            self.prep_ms / n,
            self.render_ms / n,
            self.gpu_ms / n,
            self.encode_ms / n,
            log.display()
        );
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
        render_cmd::haze_from_args(&args)?;
        Ok(args)
    }
}

/// The frame's camera file and sky mask, as `--camera` and `--sky-mask`.
fn apply_companions(args: &mut RenderArgs, item: &Item) {
    if item.camera.is_some() {
        args.depth.camera = item.camera.clone();
    }
    if item.sky_mask.is_some() && !args.no_prep && !args.prep.no_sky {
        args.prep.sky_mask = item.sky_mask.clone();
    }
}

/// The fog at extinction `beta` (1/m), as `--beta`.
fn apply_beta(args: &mut RenderArgs, beta: f64) {
    args.beta = Some(beta);
    args.visibility = None;
}
