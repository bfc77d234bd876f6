//! The GL thread of a `brume.Renderer`: brume's headless EGL context, opened on a thread of
//! its own and kept there for the renderer's life. Python calls hand it a job and wait for
//! the answer with the GIL released; calls from several Python threads queue on it (the
//! job queue is the lock), so the context is only ever current on its own thread.
//!
//! **Forks.** A process forked from one with a renderer (a PyTorch `DataLoader`'s workers,
//! `multiprocessing` on Linux) has a copy of the renderer but not its thread: the first
//! call there starts a thread and a context of the child's own, instead of queueing a job
//! that nothing would ever run.

use super::py_err;
use brume::Headless;
use pyo3::exceptions::PyRuntimeError;
use pyo3::PyResult;
use std::sync::{mpsc, Mutex};
use std::thread;

type Job = Box<dyn FnOnce(&mut Headless) + Send>;

/// One EGL context on a thread of its own, fed jobs through a channel.
pub(crate) struct GlThread {
    queue: Mutex<Queue>,
    pub(crate) renderer_name: String,
}

/// The way to a GL thread, and the process it runs in; no thread once closed.
struct Queue {
    pid: u32,
    thread: Option<Running>,
}

/// A GL thread: its job queue, and its handle to wait for its end.
struct Running {
    jobs: mpsc::Sender<Job>,
    handle: thread::JoinHandle<()>,
}

impl GlThread {
    /// Starts the thread and opens the context on it; the context's error if it cannot.
    pub(crate) fn start() -> PyResult<GlThread> {
        let (running, renderer_name) = spawn()?;
        Ok(GlThread {
            queue: Mutex::new(Queue {
                pid: std::process::id(),
                thread: Some(running),
            }),
            renderer_name,
        })
    }

    /// Ends the thread after the jobs already queued, and waits until it has destroyed
    /// its context (call with the GIL released). Later calls of [`GlThread::run`] fail.
    pub(crate) fn close(&self) -> PyResult<()> {
        let mut queue = self.lock()?;
        let Some(Running { jobs, handle }) = queue.thread.take() else {
            return Ok(());
        };
        if queue.pid != std::process::id() {
            // A parent's thread: nothing here to end or wait for (see `run`).
            std::mem::forget((jobs, handle));
            return Ok(());
        }
        drop(queue);
        drop(jobs);
        handle
            .join()
            .map_err(|_| PyRuntimeError::new_err("the GL thread panicked while closing"))
    }

    /// Whether [`GlThread::close`] has ended the thread.
    pub(crate) fn is_closed(&self) -> bool {
        self.lock().map_or(true, |q| q.thread.is_none())
    }

    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, Queue>> {
        self.queue
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the GL thread's queue is poisoned"))
    }

    /// Runs `f` on the GL thread and waits for its result (call with the GIL released).
    pub(crate) fn run<T: Send + 'static>(
        &self,
        f: impl FnOnce(&mut Headless) -> T + Send + 'static,
    ) -> PyResult<T> {
        let (answer, result) = mpsc::channel();
        let job: Job = Box::new(move |h| {
            let _ = answer.send(f(h));
        });
        let mut queue = self.lock()?;
        let forked = queue.pid != std::process::id();
        let Some(running) = queue.thread.as_mut() else {
            return Err(PyRuntimeError::new_err(
                "this brume.Renderer is closed: open a new one",
            ));
        };
        if forked {
            // The thread behind `jobs` is the parent's. Its sender and handle are leaked,
            // not dropped: dropping would signal a receiver that is not in this process,
            // and its thread cannot be waited for here.
            let (fresh, _) = spawn()?;
            std::mem::forget(std::mem::replace(running, fresh));
        }
        running
            .jobs
            .send(job)
            .map_err(|_| PyRuntimeError::new_err("the GL thread has stopped"))?;
        queue.pid = std::process::id();
        drop(queue);
        result.recv().map_err(|_| {
            PyRuntimeError::new_err("the render failed inside brume (a panic on the GL thread)")
        })
    }
}

/// Starts a GL thread and opens brume's headless context on it: the thread and the GL
/// renderer's name, or the context's error.
fn spawn() -> PyResult<(Running, String)> {
    let (jobs, queue) = mpsc::channel::<Job>();
    let (ready, opened) = mpsc::channel::<brume::Result<String>>();
    let handle = thread::Builder::new()
        .name("brume-gl".into())
        .spawn(move || {
            let mut headless = match Headless::new(None) {
                Ok(h) => h,
                Err(e) => {
                    let _ = ready.send(Err(e));
                    return;
                }
            };
            let _ = ready.send(Ok(headless.caps().renderer.clone()));
            // Ends when the renderer (the last sender) is dropped; the context is
            // then destroyed on this thread, where it is current.
            while let Ok(job) = queue.recv() {
                // A panic in one job (a bug) fails that call, not the renderer.
                let _ =
                    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| job(&mut headless)));
            }
        })
        .map_err(|e| PyRuntimeError::new_err(format!("could not start the GL thread: {e}")))?;
    let renderer_name = opened
        .recv()
        .map_err(|_| PyRuntimeError::new_err("the GL thread stopped while opening EGL"))?
        .map_err(py_err)?;
    Ok((Running { jobs, handle }, renderer_name))
}
