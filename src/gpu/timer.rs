//! Per-pass timing: `GL_TIME_ELAPSED` queries where `GL_EXT_disjoint_timer_query` exists,
//! else `glFinish` + a monotonic clock. Every figure says which clock produced it.
//!
//! Driver facts this module works around (measured on Mesa 22.3): llvmpipe's first TIME_ELAPSED query
//! on a fresh context returns nonsense (about the system uptime), so [`warm_up`] spends
//! one; a disjoint event (`GPU_DISJOINT_EXT`) invalidates a batch of queries; and some
//! mobile drivers return values that cannot be right, so a batch whose sum exceeds the
//! wall time that enclosed it is rejected and the caller re-measures by the wall clock.

use crate::error::{Error, Result};
use glow::HasContext;
use std::cell::RefCell;
use std::sync::Arc;
use std::time::Instant;

/// How far the sum of per-pass figures may exceed the wall time that enclosed them.
///
/// Consecutive TIME_ELAPSED intervals can overlap on a pipelined driver: on llvmpipe
/// (2 rasteriser threads) the per-pass sums run 5-20 % above the enclosing wall time.
/// The values this check exists to catch are off by orders of magnitude (llvmpipe's
/// first query reports the system uptime), so a factor of 1.5 separates the two; the
/// extra 1 ms covers clock granularity on tiny renders.
const OVERLAP_ALLOWANCE: f64 = 1.5;

/// `GL_GPU_DISJOINT_EXT`, which glow does not export.
pub const GPU_DISJOINT_EXT: u32 = 0x8FBB;

/// Which clock produced a figure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Clock {
    /// `GL_TIME_ELAPSED` queries (on llvmpipe this is CPU time of the rasteriser threads).
    #[serde(rename = "gpu-timer")]
    GpuTimer,
    /// `glFinish` after each pass and a monotonic wall clock.
    #[serde(rename = "wall")]
    Wall,
}

impl Clock {
    /// The name used in reports and JSON: `gpu-timer` or `wall`.
    pub fn name(self) -> &'static str {
        match self {
            Clock::GpuTimer => "gpu-timer",
            Clock::Wall => "wall",
        }
    }
}

/// Times of each pass of one render, in milliseconds.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PassTimes {
    /// The clock used.
    pub clock: Clock,
    /// One figure per pass, in pass order.
    pub pass_ms: Vec<f64>,
    /// Sum of `pass_ms`.
    pub total_ms: f64,
}

/// Why a GPU-timer batch was thrown away.
#[derive(Debug)]
pub enum Rejected {
    /// The driver flagged a disjoint event during the batch.
    Disjoint,
    /// The figures cannot be right (sum above the enclosing wall time, or not finite).
    Implausible(String),
}

/// Spends the first TIME_ELAPSED query of a fresh context, whose result is meaningless on
/// llvmpipe, around `draw` (real work: an empty query does not absorb the bogus sample),
/// and clears any pending disjoint flag.
pub fn warm_up(gl: &glow::Context, draw: impl FnOnce()) -> Result<()> {
    // SAFETY: one query object created, begun and ended around the draw, read and
    // deleted on the current context.
    unsafe {
        let q = gl.create_query().map_err(Error::Gl)?;
        gl.begin_query(glow::TIME_ELAPSED, q);
        draw();
        gl.end_query(glow::TIME_ELAPSED);
        let _ = query_result_ns(gl, q);
        gl.delete_query(q);
        let _ = gl.get_parameter_i32(GPU_DISJOINT_EXT);
    }
    super::check_gl(gl, "warming up the timer query")
}

/// TIME_ELAPSED query objects kept for the next batch, so that a frame loop creates none
/// after its first frame. Deletes them when dropped.
pub struct QueryPool {
    gl: Arc<glow::Context>,
    free: RefCell<Vec<glow::Query>>,
}

impl QueryPool {
    /// An empty pool on `gl`.
    pub fn new(gl: &Arc<glow::Context>) -> Self {
        QueryPool {
            gl: Arc::clone(gl),
            free: RefCell::new(Vec::new()),
        }
    }

    /// A query from the pool, or a new one.
    fn take(&self) -> Result<glow::Query> {
        if let Some(q) = self.free.borrow_mut().pop() {
            return Ok(q);
        }
        // SAFETY: query creation on the current context; owned by the pool once given back.
        let q = unsafe { self.gl.create_query().map_err(Error::Gl)? };
        super::object_created();
        Ok(q)
    }

    /// Returns queries whose results have been read (or that will not be).
    fn give_back(&self, queries: impl IntoIterator<Item = glow::Query>) {
        self.free.borrow_mut().extend(queries);
    }
}

impl Drop for QueryPool {
    fn drop(&mut self) {
        for q in self.free.get_mut().drain(..) {
            // SAFETY: queries this pool created, on the context it holds.
            unsafe { self.gl.delete_query(q) };
            super::object_deleted();
        }
    }
}

/// Times a sequence of passes with one clock.
pub struct PassTimer<'a> {
    gl: Arc<glow::Context>,
    pool: &'a QueryPool,
    clock: Clock,
    queries: Vec<glow::Query>,
    wall_ms: Vec<f64>,
    pass_start: Instant,
    batch_start: Instant,
}

impl<'a> PassTimer<'a> {
    /// Starts timing, with queries from `pool`. With the wall clock, waits for earlier GL
    /// work first so that it is not charged to the first pass.
    pub fn start(gl: &Arc<glow::Context>, clock: Clock, pool: &'a QueryPool) -> Self {
        // SAFETY: glFinish and a state query on the current context.
        unsafe {
            match clock {
                Clock::Wall => gl.finish(),
                // Reading the flag resets it, so a later read sees only this batch.
                Clock::GpuTimer => {
                    let _ = gl.get_parameter_i32(GPU_DISJOINT_EXT);
                }
            }
        }
        let now = Instant::now();
        PassTimer {
            gl: Arc::clone(gl),
            pool,
            clock,
            queries: Vec::new(),
            wall_ms: Vec::new(),
            pass_start: now,
            batch_start: now,
        }
    }

    /// Runs `draw` as one timed pass.
    pub fn pass(&mut self, draw: impl FnOnce()) -> Result<()> {
        match self.clock {
            Clock::GpuTimer => {
                let q = self.pool.take()?;
                self.queries.push(q);
                // SAFETY: a query object held by this timer (back to the pool in Drop)
                // brackets the draw; no other TIME_ELAPSED query is active.
                unsafe {
                    self.gl.begin_query(glow::TIME_ELAPSED, q);
                    draw();
                    self.gl.end_query(glow::TIME_ELAPSED);
                }
            }
            Clock::Wall => {
                self.pass_start = Instant::now();
                draw();
                // SAFETY: glFinish has no preconditions.
                unsafe { self.gl.finish() };
                self.wall_ms
                    .push(self.pass_start.elapsed().as_secs_f64() * 1e3);
            }
        }
        Ok(())
    }

    /// Collects the figures. A GPU-timer batch can be rejected (see [`Rejected`]); the
    /// caller then measures again with [`Clock::Wall`].
    pub fn finish(mut self) -> Result<std::result::Result<PassTimes, Rejected>> {
        let pass_ms = match self.clock {
            Clock::Wall => std::mem::take(&mut self.wall_ms),
            Clock::GpuTimer => {
                // SAFETY: results of queries this timer created and ended.
                let ns: Vec<u64> = self
                    .queries
                    .iter()
                    .map(|&q| unsafe { query_result_ns(&self.gl, q) })
                    .collect();
                let enclosing_ms = self.batch_start.elapsed().as_secs_f64() * 1e3;
                // SAFETY: a state query on the current context, after all results are in.
                if unsafe { self.gl.get_parameter_i32(GPU_DISJOINT_EXT) } != 0 {
                    return Ok(Err(Rejected::Disjoint));
                }
                let ms: Vec<f64> = ns.iter().map(|&n| n as f64 / 1e6).collect();
                let sum: f64 = ms.iter().sum();
                if !sum.is_finite() || sum > enclosing_ms * OVERLAP_ALLOWANCE + 1.0 {
                    return Ok(Err(Rejected::Implausible(format!(
                        "timer queries sum to {sum:.3} ms inside {enclosing_ms:.3} ms of wall time"
                    ))));
                }
                ms
            }
        };
        super::check_gl(&self.gl, "reading timer queries")?;
        let total_ms = pass_ms.iter().sum();
        Ok(Ok(PassTimes {
            clock: self.clock,
            pass_ms,
            total_ms,
        }))
    }
}

impl Drop for PassTimer<'_> {
    fn drop(&mut self) {
        // A query whose result was not read is ended: reusing it is allowed, and begin
        // discards the old result.
        self.pool.give_back(self.queries.drain(..));
    }
}

/// Waits for a query's result and returns it (nanoseconds for TIME_ELAPSED).
unsafe fn query_result_ns(gl: &glow::Context, q: glow::Query) -> u64 {
    while gl.get_query_parameter_u32(q, glow::QUERY_RESULT_AVAILABLE) == 0 {
        std::thread::yield_now();
    }
    let mut value: u64 = 0;
    // glow's "offset" is the destination pointer when no query buffer is bound.
    gl.get_query_parameter_u64_with_offset(
        q,
        glow::QUERY_RESULT,
        std::ptr::addr_of_mut!(value) as usize,
    );
    value
}
