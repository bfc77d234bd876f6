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

/// The way to a GL thread, and the process it runs in.
struct Queue {
    pid: u32,
    jobs: mpsc::Sender<Job>,
}

impl GlThread {
    /// Starts the thread and opens the context on it; the context's error if it cannot.
    pub(crate) fn start() -> PyResult<GlThread> {
        let (jobs, renderer_name) = spawn()?;
        Ok(GlThread {
            queue: Mutex::new(Queue {
                pid: std::process::id(),
                jobs,
            }),
            renderer_name,
        })
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
        let mut queue = self
            .queue
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the GL thread's queue is poisoned"))?;
        if queue.pid != std::process::id() {
            // Forked: the thread behind `jobs` is the parent's. Its sender is leaked, not
            // dropped: dropping would signal a receiver that is not in this process.
            let (jobs, _) = spawn()?;
            std::mem::forget(std::mem::replace(&mut queue.jobs, jobs));
            queue.pid = std::process::id();
        }
        queue
            .jobs
            .send(job)
            .map_err(|_| PyRuntimeError::new_err("the GL thread has stopped"))?;
        drop(queue);
        result.recv().map_err(|_| {
            PyRuntimeError::new_err("the render failed inside brume (a panic on the GL thread)")
        })
    }
}

/// Starts a GL thread and opens brume's headless context on it: the thread's queue and the
/// GL renderer's name, or the context's error.
fn spawn() -> PyResult<(mpsc::Sender<Job>, String)> {
    let (jobs, queue) = mpsc::channel::<Job>();
    let (ready, opened) = mpsc::channel::<brume::Result<String>>();
    thread::Builder::new()
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
    Ok((jobs, renderer_name))
}
