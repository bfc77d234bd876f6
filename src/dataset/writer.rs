//! The writer thread of a batch run: each output captured, encoded and written
//! atomically, then logged (one JSON line) as soon as it is in place or has failed.

use super::batch::Failed;
use super::report::{BatchEvent, BatchReport};
use crate::error::{Error, Result};
use crate::io::output::{self, Outputs};
use crate::photo::{capture, CaptureOptions};
use crate::raster::RgbaImage;
use serde_json::json;
use std::collections::VecDeque;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc::Receiver;
use std::thread::ScopedJoinHandle;
use std::time::Instant;

/// One output for the writer thread.
pub(super) struct Encode {
    pub(super) path: PathBuf,
    pub(super) image: RgbaImage,
    /// The photo's colour profile and EXIF, which the output carries.
    pub(super) metadata: crate::io::metadata::PhotoMetadata,
    pub(super) transmittance: Option<(PathBuf, Vec<[u8; 3]>, usize, usize)>,
    pub(super) record: serde_json::Value,
    /// The capture after the fog, seeded for this output (applied on the writer thread).
    pub(super) capture: CaptureOptions,
}

/// What the GPU loop hands the writer thread.
pub(super) enum Event {
    /// An output to encode and write.
    Output(Encode),
    /// A frame that failed, with the number of its outputs that will not be written.
    FrameFailed { failed: Failed, outputs: usize },
    /// A frame loaded with warnings, before its outputs.
    FrameWarned {
        image: PathBuf,
        warnings: Vec<String>,
    },
}

/// The writer thread: captures, encodes and writes each output atomically, up to
/// `writers` at once on threads of its own, and logs each as soon as it and everything
/// before it are in place or have failed, in the order the events came. An error that
/// stops the run (a full disk, a log that cannot be written) still waits for the outputs
/// at work and logs them.
pub(super) fn write_outputs(rx: Receiver<Event>, mut log: Log, writers: usize) -> Result<Log> {
    let observe = log.observe;
    std::thread::scope(|s| {
        let mut queue = VecDeque::new();
        let run = || -> Result<()> {
            for event in rx {
                let Event::Output(job) = event else {
                    queue.push_back(Queued::Event(Box::new(event)));
                    continue;
                };
                while queue.iter().filter(|q| q.is_output()).count() >= writers {
                    log_first(&mut queue, &mut log)?;
                }
                queue.push_back(Queued::output(s, job, observe));
                while queue.front().is_some_and(Queued::is_done) {
                    log_first(&mut queue, &mut log)?;
                }
            }
            while !queue.is_empty() {
                log_first(&mut queue, &mut log)?;
            }
            Ok(())
        };
        let stopped = run();
        if stopped.is_err() {
            while !queue.is_empty() {
                // The run's first error is the one to report.
                let _ = log_first(&mut queue, &mut log);
            }
        }
        stopped.map(|()| log)
    })
}

/// What waits in the writer's queue to be logged, in the order it came.
enum Queued<'scope> {
    /// An output at work (or done) on a writer thread.
    Output {
        path: PathBuf,
        record: serde_json::Value,
        work: ScopedJoinHandle<'scope, (Result<()>, f64)>,
    },
    /// A frame's failure or warnings.
    Event(Box<Event>),
}

impl<'scope> Queued<'scope> {
    /// Starts `job` on a writer thread of its own.
    fn output<'env>(
        s: &'scope std::thread::Scope<'scope, 'env>,
        mut job: Encode,
        observe: &'env (dyn Fn(BatchEvent) + Sync),
    ) -> Queued<'scope> {
        let (path, record) = (job.path.clone(), std::mem::take(&mut job.record));
        let work = s.spawn(move || {
            let t = Instant::now();
            let result =
                capture(&mut job.image, &job.capture).and_then(|_| write_one(&job, observe));
            (result, t.elapsed().as_secs_f64() * 1e3)
        });
        Queued::Output { path, record, work }
    }

    fn is_output(&self) -> bool {
        matches!(self, Queued::Output { .. })
    }

    /// Whether logging it would not wait.
    fn is_done(&self) -> bool {
        match self {
            Queued::Output { work, .. } => work.is_finished(),
            Queued::Event(_) => true,
        }
    }
}

/// Logs the queue's first entry, waiting for its output if it is still at work.
fn log_first(queue: &mut VecDeque<Queued>, log: &mut Log) -> Result<()> {
    match queue.pop_front() {
        Some(Queued::Output { path, record, work }) => {
            let (result, ms) = work.join().unwrap_or_else(|p| std::panic::resume_unwind(p));
            log.report.encode_ms += ms;
            log.output(&path, record, result)
        }
        Some(Queued::Event(event)) => match *event {
            Event::FrameFailed { failed, outputs } => log.frame_failed(&failed, outputs),
            Event::FrameWarned { image, warnings } => {
                log.frame_warned(&image, &warnings);
                Ok(())
            }
            Event::Output(_) => unreachable!("outputs are queued at work"),
        },
        None => Ok(()),
    }
}

fn write_one(job: &Encode, observe: &(dyn Fn(BatchEvent) + Sync)) -> Result<()> {
    if let Some(dir) = job.path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    let mut outputs = Outputs::new();
    outputs.stage_photo(&job.path, &job.image, &job.metadata)?;
    if let Some((path, rgb, w, h)) = &job.transmittance {
        outputs.stage_png_rgb8(path, *w, *h, rgb)?;
    }
    observe(BatchEvent::Staged { outputs: &outputs });
    outputs.commit()
}

/// The run's JSON-lines log and its counts: one line per output, written (in one
/// `write`, on a file opened for appending, so that shards sharing nothing but the folder
/// never interleave) as soon as the output is in place or has failed.
pub(super) struct Log<'a> {
    pub(super) file: std::fs::File,
    pub(super) path: PathBuf,
    pub(super) observe: &'a (dyn Fn(BatchEvent) + Sync),
    pub(super) report: BatchReport,
}

impl Log<'_> {
    /// Logs an output written or failed. An error stops the run: the log cannot be
    /// written, or the output's device is full, when every later output would fail too.
    fn output(
        &mut self,
        output: &Path,
        mut record: serde_json::Value,
        result: Result<()>,
    ) -> Result<()> {
        if let Err(error) = &result {
            record["status"] = json!("failed");
            record["error"] = json!(error.to_string());
        }
        let appended = self.append(&record);
        match &result {
            Ok(()) => self.report.written += 1,
            Err(_) => self.report.failed_outputs += 1,
        }
        (self.observe)(match &result {
            Ok(()) => BatchEvent::Written { output },
            Err(error) => BatchEvent::OutputFailed { output, error },
        });
        let full = |r: &Result<()>| r.as_ref().is_err_and(output::is_out_of_space);
        if full(&result) || full(&appended) {
            return Err(self.out_of_space(output));
        }
        appended
    }

    /// The error that stops a run whose output device is full at `output`.
    fn out_of_space(&self, output: &Path) -> Error {
        let folder = self.path.parent().unwrap_or(Path::new("."));
        let written = self.report.written;
        Error::io(
            folder,
            std::io::Error::new(
                std::io::ErrorKind::StorageFull,
                format!(
                    "no space left on its device (or in the disk quota): the run stopped at \
                     {} after writing {written} outputs, as every later output would fail \
                     too; free some space and run the same command again, which skips the \
                     outputs already written",
                    output.display()
                ),
            ),
        )
    }

    /// A frame that could not be loaded or rendered; `outputs` of it are not written.
    pub(super) fn frame_failed(&mut self, failed: &Failed, outputs: usize) -> Result<()> {
        let (item, error) = (&failed.item, &failed.error);
        self.append(&json!({
            "status": "failed",
            "image": item.image.display().to_string(),
            "error": error.to_string(),
        }))?;
        self.report.failed_frames += 1;
        (self.observe)(BatchEvent::FrameFailed {
            image: &item.image,
            error,
            outputs,
        });
        Ok(())
    }

    /// A frame loaded with warnings (its outputs' records carry them).
    fn frame_warned(&mut self, image: &Path, warnings: &[String]) {
        self.report.warned_frames += 1;
        (self.observe)(BatchEvent::FrameWarned { image, warnings });
    }

    fn append(&mut self, record: &serde_json::Value) -> Result<()> {
        let line = format!("{record}\n");
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| Error::io(&self.path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn log_in(dir: &Path, observe: &'static (dyn Fn(BatchEvent) + Sync)) -> Log<'static> {
        let path = dir.join("brume-batch-1-of-1.jsonl");
        Log {
            file: std::fs::File::create(&path).unwrap(),
            path,
            observe,
            report: BatchReport::default(),
        }
    }

    // A run whose disk filled went on rendering every remaining frame (hours of a large
    // dataset), failing each output in turn. It now stops at the first full-disk failure,
    // logged like any other.
    #[test]
    fn a_full_disk_stops_the_run_and_other_failures_do_not() {
        let dir = tempfile::tempdir().unwrap();
        let mut log = log_in(dir.path(), &|_| {});
        let out = dir.path().join("a_foggy_beta_0.01.png");
        log.output(&out, json!({"status": "ok"}), Ok(())).unwrap();
        let denied = std::io::Error::from(std::io::ErrorKind::PermissionDenied);
        let failed = Err(Error::io(&out, denied));
        log.output(&out, json!({"status": "ok"}), failed).unwrap();

        const ENOSPC: i32 = 28;
        let full = Err(Error::io(&out, std::io::Error::from_raw_os_error(ENOSPC)));
        let e = log.output(&out, json!({"status": "ok"}), full).unwrap_err();
        let msg = e.to_string();
        assert!(output::is_out_of_space(&e), "{msg}");
        assert!(
            msg.contains("no space left")
                && msg.contains("a_foggy_beta_0.01.png after writing 1 outputs")
                && msg.contains("run the same command again"),
            "{msg}"
        );
        assert_eq!((log.report.written, log.report.failed_outputs), (1, 2));
        let lines = std::fs::read_to_string(&log.path).unwrap();
        let failed = lines.lines().filter(|l| l.contains(r#""status":"failed""#));
        assert_eq!(failed.count(), 2, "the full disk's failure is logged too");
    }

    #[test]
    fn out_of_space_is_told_through_wrapping_and_from_other_errors() {
        const ENOSPC: i32 = 28;
        const EDQUOT: i32 = 122;
        let p = Path::new("x.png");
        let os = std::io::Error::from_raw_os_error;
        assert!(output::is_out_of_space(&Error::io(p, os(ENOSPC))));
        assert!(output::is_out_of_space(&Error::io(p, os(EDQUOT))));
        let wrapped = std::io::Error::other(os(ENOSPC));
        assert!(output::is_out_of_space(&Error::io(p, wrapped)));
        let text = std::io::Error::other("No space left on device (os error 28)");
        assert!(
            !output::is_out_of_space(&Error::io(p, text)),
            "text alone is not trusted"
        );
        assert!(!output::is_out_of_space(&Error::io(p, os(13))));
        assert!(!output::is_out_of_space(&Error::format(p, "truncated")));
    }

    /// A writer whose device is full.
    struct Full;
    impl Write for Full {
        fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
            Err(std::io::ErrorKind::StorageFull.into())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    /// Outputs written by three writers at once, the first the slowest to encode (so the
    /// later ones finish first), and one that cannot be written: the log has them in the
    /// order they came, with the frames' events between them, and the bytes are one
    /// writer's.
    #[test]
    fn several_writers_log_in_the_order_the_outputs_came() {
        let dir = tempfile::tempdir().unwrap();
        let blocked = dir.path().join("a-file");
        std::fs::write(&blocked, b"").unwrap();
        let sizes = [(1500, 1000), (8, 8), (16, 4), (8, 8), (4, 4)];
        let path = |k: usize, root: &Path| match k {
            3 => blocked.join("under-a-file.png"),
            _ => root.join(format!("o{k}.png")),
        };
        let events = |root: &Path| -> Vec<Event> {
            let mut events: Vec<Event> = (0..sizes.len())
                .map(|k| {
                    let (w, h) = sizes[k];
                    Event::Output(Encode {
                        path: path(k, root),
                        image: RgbaImage::from_fn(w, h, |x, y| {
                            [(x % 7) as f32 / 7.0, (y % 5) as f32 / 5.0, 0.5, 1.0]
                        }),
                        metadata: Default::default(),
                        transmittance: None,
                        record: json!({ "k": k }),
                        capture: CaptureOptions::default(),
                    })
                })
                .collect();
            let warned = Event::FrameWarned {
                image: root.join("frame.png"),
                warnings: vec!["a warning".into()],
            };
            events.insert(2, warned);
            events
        };
        let run = |writers: usize, name: &str| -> (Vec<serde_json::Value>, Vec<Vec<u8>>) {
            let root = dir.path().join(name);
            std::fs::create_dir(&root).unwrap();
            let (tx, rx) = std::sync::mpsc::sync_channel(2);
            let log = log_in(&root, &|_| {});
            let sent = events(&root);
            let writer = std::thread::spawn(move || write_outputs(rx, log, writers).unwrap());
            sent.into_iter().for_each(|e| tx.send(e).unwrap());
            drop(tx);
            let log = writer.join().unwrap();
            assert_eq!((log.report.written, log.report.failed_outputs), (4, 1));
            assert_eq!(log.report.warned_frames, 1);
            let records = std::fs::read_to_string(&log.path).unwrap();
            let records = records.lines().map(|l| serde_json::from_str(l).unwrap());
            let bytes = [0, 1, 2, 4].map(|k| std::fs::read(path(k, &root)).unwrap());
            (records.collect(), bytes.to_vec())
        };
        let (one, one_bytes) = run(1, "one");
        let (three, three_bytes) = run(3, "three");
        assert_eq!(one, three);
        assert!(one_bytes == three_bytes, "the outputs differ");
        let order: Vec<_> = three.iter().map(|r| r["k"].as_u64()).collect();
        assert_eq!(order, [0, 1, 2, 3, 4].map(Some));
        assert_eq!(three[3]["status"], "failed", "{:?}", three[3]);
    }

    // The png crate turned the OS error into text of kind `Other`, so a full disk did not
    // look like one.
    #[test]
    fn the_png_writer_keeps_the_os_error() {
        let e = crate::io::codec::png::write_rgb8(Full, &[0; 12], 2, 2, None, None).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::StorageFull, "{e}");
    }
}
