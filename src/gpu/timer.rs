//! Per-pass timing, as an option ([`Timing`]): off (no query, no wait: the default of a
//! [`crate::Pipeline`]), deferred (`GL_TIME_ELAPSED` queries read on a later call without
//! waiting, as engines do), or blocking (this call's figures, waiting for them: the GPU
//! timer where `GL_EXT_disjoint_timer_query` exists, else `glFinish` + a monotonic clock).
//! Every figure says which clock produced it, and a call whose figures are missing says so
//! ([`Clock::Unavailable`]); passes are never run again to get a figure.
//!
//! Driver facts this module works around (measured on Mesa 22.3): llvmpipe's first
//! TIME_ELAPSED query on a fresh context returns nonsense (about the system uptime), so
//! [`warm_up`] spends one before the first timed call; a disjoint event
//! (`GPU_DISJOINT_EXT`) invalidates the queries in flight; and some mobile drivers return
//! values that cannot be right, so a batch whose sum exceeds the wall time that enclosed
//! it is rejected (its times are unavailable).
//!
//! A host's own TIME_ELAPSED query is left alone: brume reads `GL_CURRENT_QUERY` first
//! (`glGetQueryiv`, which glow does not wrap: see [`HostQueryProbe`]) and begins none of
//! its own while the host's is open.

use crate::error::{Error, Result};
use glow::HasContext;
use std::cell::{Cell, RefCell};
use std::collections::VecDeque;
use std::sync::{Arc, OnceLock};
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

/// How many calls' queries [`Timing::Deferred`] keeps in flight. A call that finds them
/// all still pending is not timed (its queries would push out figures that are almost
/// in), so a GPU more than this many calls behind gives no figures rather than stale ones.
pub const DEFERRED_IN_FLIGHT: usize = 4;

/// When a pipeline times its passes. Set with [`crate::Pipeline::set_timing`] (or
/// [`crate::Renderer::set_timing`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Timing {
    /// No query, no `glFinish`: a call returns once its commands are issued, and its
    /// times are [unavailable](PassTimes::unavailable). The default of
    /// [`crate::Pipeline::new`]: a host's frame loop never waits for brume.
    #[default]
    Off,
    /// `GL_TIME_ELAPSED` queries around each pass, read on a later call without waiting
    /// (as engines time their passes): a call returns the figures of the newest earlier
    /// call whose results have come in, with [`PassTimes::calls_ago`] saying how many
    /// timed calls back it was, or unavailable times when none has come in (or its
    /// figures were rejected). Each call's figures are returned once. Needs
    /// `GL_EXT_disjoint_timer_query`; without it every call's times are unavailable.
    /// The first timed call waits once for a 1x1 draw ([`warm_up`]).
    Deferred,
    /// This call's own figures, waiting for them: `GL_TIME_ELAPSED` queries where the
    /// driver has them (the call waits for their results), else `glFinish` before and
    /// after every pass and a monotonic clock. Figures the driver flags as disjoint, or
    /// that cannot be right, are unavailable (the passes are not run again). The default
    /// of [`crate::Renderer`], which the `brume` program and its benchmarks use.
    Blocking,
    /// Blocking by the wall clock even where the GPU timer exists: `glFinish` before and
    /// after every pass. Never rejected, never stopped by a host's query: for a benchmark
    /// that must have a figure for every call.
    BlockingWall,
}

impl Timing {
    /// The name used in reports: `off`, `deferred`, `blocking` or `blocking-wall`.
    pub fn name(self) -> &'static str {
        match self {
            Timing::Off => "off",
            Timing::Deferred => "deferred",
            Timing::Blocking => "blocking",
            Timing::BlockingWall => "blocking-wall",
        }
    }
}

/// Which clock produced a figure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Clock {
    /// `GL_TIME_ELAPSED` queries (on llvmpipe this is CPU time of the rasteriser threads).
    #[serde(rename = "gpu-timer")]
    GpuTimer,
    /// `glFinish` after each pass and a monotonic wall clock.
    #[serde(rename = "wall")]
    Wall,
    /// No figure: timing off, the results rejected (disjoint, implausible) or not in yet,
    /// or a host's own `TIME_ELAPSED` query open during the call.
    #[serde(rename = "n/a")]
    Unavailable,
}

impl Clock {
    /// The name used in reports and JSON: `gpu-timer`, `wall` or `n/a`.
    pub fn name(self) -> &'static str {
        match self {
            Clock::GpuTimer => "gpu-timer",
            Clock::Wall => "wall",
            Clock::Unavailable => "n/a",
        }
    }
}

/// Times of each pass of one call, in milliseconds, or none
/// ([`Clock::Unavailable`]: no figures, `total_ms` NaN, which JSON writes as `null`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PassTimes {
    /// The clock used; [`Clock::Unavailable`] when there are no figures.
    pub clock: Clock,
    /// One figure per pass, in pass order (empty when unavailable).
    pub pass_ms: Vec<f64>,
    /// Sum of `pass_ms` (NaN when unavailable).
    pub total_ms: f64,
    /// How many timed calls of this pipeline before the one that returned these figures
    /// their passes ran: 0 (the call's own) with [`Timing::Blocking`], 1 or more with
    /// [`Timing::Deferred`]. 0 when unavailable.
    pub calls_ago: u32,
}

impl PassTimes {
    /// No figures.
    pub fn unavailable() -> Self {
        PassTimes {
            clock: Clock::Unavailable,
            pass_ms: Vec::new(),
            total_ms: f64::NAN,
            calls_ago: 0,
        }
    }

    /// Whether there are figures.
    pub fn is_available(&self) -> bool {
        self.clock != Clock::Unavailable
    }

    /// The sum, if there are figures.
    pub fn total(&self) -> Option<f64> {
        self.is_available().then_some(self.total_ms)
    }

    /// The total as a report shows it: `12.345` (`decimals` digits) or `n/a`.
    pub fn total_text(&self, decimals: usize) -> String {
        match self.total() {
            Some(ms) => format!("{ms:.decimals$}"),
            None => "n/a".to_string(),
        }
    }

    /// The total and its clock as a report says them: `12.3 ms by gpu-timer` (`decimals`
    /// digits), or `time n/a`.
    pub fn describe(&self, decimals: usize) -> String {
        match self.total() {
            Some(ms) => format!("{ms:.decimals$} ms by {}", self.clock.name()),
            None => "time n/a".to_string(),
        }
    }

    fn measured(clock: Clock, pass_ms: Vec<f64>, calls_ago: u32) -> Self {
        let total_ms = pass_ms.iter().sum();
        PassTimes {
            clock,
            pass_ms,
            total_ms,
            calls_ago,
        }
    }
}

/// Why a GPU-timer batch was thrown away.
#[derive(Debug)]
pub enum Rejected {
    /// The driver flagged a disjoint event while the queries were in flight.
    Disjoint,
    /// The figures cannot be right (sum above the enclosing wall time, or not finite).
    Implausible(String),
}

/// Spends the first TIME_ELAPSED query of a fresh context, whose result is meaningless on
/// llvmpipe, around `draw` (real work: an empty query does not absorb the bogus sample),
/// and clears any pending disjoint flag. Waits for the draw.
pub fn warm_up(gl: &glow::Context, draw: impl FnOnce()) -> Result<()> {
    // SAFETY: one query object created, begun and ended around the draw, read and
    // deleted on the current context (no other TIME_ELAPSED query is active: the caller
    // checked the host's).
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
/// after its first frames. Deletes them when dropped.
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

    /// Returns queries whose results have been read (or that will not be). A query that
    /// was ended and not read may be begun again: begin discards the old result.
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

/// How one call is timed, decided when it starts ([`Timekeeper::plan`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plan {
    method: Method,
    /// The call number (1 for a pipeline's first timed call).
    call: u64,
    /// The first query of the context must be spent first ([`warm_up`]).
    pub warm_up: bool,
}

impl Plan {
    /// Whether the call begins TIME_ELAPSED queries.
    pub fn uses_queries(&self) -> bool {
        self.method == Method::Queries
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Method {
    /// Not timed.
    None,
    /// TIME_ELAPSED queries.
    Queries,
    /// `glFinish` and the wall clock.
    Wall,
}

/// Times the passes of one call, as its [`Plan`] says.
pub struct PassTimer<'a> {
    keeper: &'a Timekeeper,
    plan: Plan,
    queries: Vec<glow::Query>,
    wall_ms: Vec<f64>,
    batch_start: Instant,
}

impl PassTimer<'_> {
    /// Runs `draw` as one timed pass.
    pub fn pass(&mut self, draw: impl FnOnce()) -> Result<()> {
        let gl = &self.keeper.gl;
        match self.plan.method {
            Method::None => draw(),
            Method::Queries => {
                let q = self.keeper.pool.take()?;
                self.queries.push(q);
                self.keeper.begun.set(self.keeper.begun.get() + 1);
                // SAFETY: a query object held by this timer (back to the pool in Drop)
                // brackets the draw; no other TIME_ELAPSED query is active (the plan
                // checked the host's).
                unsafe {
                    gl.begin_query(glow::TIME_ELAPSED, q);
                    draw();
                    gl.end_query(glow::TIME_ELAPSED);
                }
            }
            Method::Wall => {
                let start = Instant::now();
                draw();
                // SAFETY: glFinish has no preconditions.
                unsafe { gl.finish() };
                self.wall_ms.push(start.elapsed().as_secs_f64() * 1e3);
            }
        }
        Ok(())
    }
}

impl Drop for PassTimer<'_> {
    fn drop(&mut self) {
        // Queries not handed on (a failed call) go back: ended, reusable.
        self.keeper.pool.give_back(self.queries.drain(..));
    }
}

/// One deferred call's queries, in flight.
struct InFlight {
    call: u64,
    queries: Vec<glow::Query>,
    /// When its passes were issued: the figures cannot sum to more than the time since.
    issued: Instant,
}

/// A pipeline's timing: the [`Timing`] option, the query pool and the deferred calls in
/// flight. Methods take `&self` (the passes borrow the pipeline).
pub struct Timekeeper {
    timing: Timing,
    /// `GL_EXT_disjoint_timer_query`.
    gpu_timer: bool,
    probe: HostQueryProbe,
    warmed: Cell<bool>,
    /// Timed calls so far (every call that runs passes, whatever the timing).
    calls: Cell<u64>,
    /// TIME_ELAPSED queries begun so far.
    begun: Cell<u64>,
    in_flight: RefCell<VecDeque<InFlight>>,
    /// The newest deferred figures not yet returned: the call and its pass times.
    ready: RefCell<Option<(u64, Vec<f64>)>>,
    /// The next read of the disjoint flag sees it set ([`Timekeeper::simulate_disjoint`]).
    simulated_disjoint: Cell<bool>,
    // After `in_flight` (whose queries go back to it in Drop); `gl` last.
    pool: QueryPool,
    gl: Arc<glow::Context>,
}

impl Timekeeper {
    /// Timing off, on `gl` (current on this thread); `gpu_timer`: the driver has
    /// `GL_EXT_disjoint_timer_query`.
    pub fn new(gl: &Arc<glow::Context>, gpu_timer: bool) -> Self {
        Timekeeper {
            timing: Timing::Off,
            gpu_timer,
            probe: HostQueryProbe::load(),
            warmed: Cell::new(false),
            calls: Cell::new(0),
            begun: Cell::new(0),
            in_flight: RefCell::new(VecDeque::new()),
            ready: RefCell::new(None),
            simulated_disjoint: Cell::new(false),
            pool: QueryPool::new(gl),
            gl: Arc::clone(gl),
        }
    }

    /// The timing option.
    pub fn timing(&self) -> Timing {
        self.timing
    }

    /// Sets the timing option. Deferred figures not yet returned are dropped when it
    /// changes. Makes no GL call.
    pub fn set_timing(&mut self, timing: Timing) {
        if timing != self.timing {
            self.drop_in_flight();
            self.timing = timing;
        }
    }

    /// For tests: the next time figures are read, the disjoint flag is taken as set (as a
    /// phone's driver sets it), so they are rejected.
    pub fn simulate_disjoint(&self) {
        self.simulated_disjoint.set(true);
    }

    /// `GL_GPU_DISJOINT_EXT`, read (which clears it).
    fn disjoint(&self) -> bool {
        // SAFETY: a state query on the current context.
        let flagged = unsafe { self.gl.get_parameter_i32(GPU_DISJOINT_EXT) } != 0;
        flagged | self.simulated_disjoint.replace(false)
    }

    /// TIME_ELAPSED queries begun so far (none with [`Timing::Off`]).
    pub fn queries_begun(&self) -> u64 {
        self.begun.get()
    }

    /// The clock [`Timing::Blocking`] uses: the GPU timer where the driver has one.
    pub fn preferred_clock(&self) -> Clock {
        if self.gpu_timer {
            Clock::GpuTimer
        } else {
            Clock::Wall
        }
    }

    /// Decides how the next call is timed (and counts it). Reads `GL_CURRENT_QUERY` when
    /// it would begin queries, and with [`Timing::Deferred`] collects the figures that
    /// have come in.
    pub fn plan(&self) -> Plan {
        let call = self.calls.get() + 1;
        self.calls.set(call);
        let method = match self.timing {
            Timing::Off => Method::None,
            Timing::BlockingWall => Method::Wall,
            Timing::Blocking if !self.gpu_timer => Method::Wall,
            Timing::Deferred if !self.gpu_timer => Method::None,
            Timing::Blocking | Timing::Deferred => {
                if self.timing == Timing::Deferred {
                    self.collect();
                }
                match self.host_query_open() {
                    Some(true) => Method::None,
                    // Unable to see a host's query: none of brume's, but blocking can
                    // still time by the wall clock.
                    None if self.timing == Timing::Blocking => Method::Wall,
                    None => Method::None,
                    Some(false)
                        if self.timing == Timing::Deferred
                            && self.in_flight.borrow().len() >= DEFERRED_IN_FLIGHT =>
                    {
                        log::debug!(
                            "{DEFERRED_IN_FLIGHT} timed calls still in flight: call {call} not timed"
                        );
                        Method::None
                    }
                    Some(false) => Method::Queries,
                }
            }
        };
        Plan {
            method,
            call,
            warm_up: method == Method::Queries && !self.warmed.get(),
        }
    }

    /// The first query has been spent ([`warm_up`]).
    pub fn warmed_up(&self) {
        self.warmed.set(true);
    }

    /// Starts timing a call. With the wall clock, waits for earlier GL work first so that
    /// it is not charged to the first pass; with blocking queries, clears the disjoint
    /// flag so that the end sees only this call's.
    pub fn start(&self, plan: Plan) -> PassTimer<'_> {
        // SAFETY: glFinish and a state query on the current context.
        unsafe {
            match plan.method {
                Method::Wall => self.gl.finish(),
                Method::Queries if self.timing == Timing::Blocking => {
                    let _ = self.gl.get_parameter_i32(GPU_DISJOINT_EXT);
                }
                Method::Queries | Method::None => {}
            }
        }
        PassTimer {
            keeper: self,
            plan,
            queries: Vec::new(),
            wall_ms: Vec::new(),
            batch_start: Instant::now(),
        }
    }

    /// The figures a call returns: its own (blocking), an earlier call's (deferred), or
    /// none.
    pub fn finish(&self, mut timer: PassTimer) -> Result<PassTimes> {
        let times = match (self.timing, timer.plan.method) {
            (_, Method::Wall) => {
                PassTimes::measured(Clock::Wall, std::mem::take(&mut timer.wall_ms), 0)
            }
            (Timing::Deferred, method) => {
                if method == Method::Queries {
                    self.in_flight.borrow_mut().push_back(InFlight {
                        call: timer.plan.call,
                        queries: std::mem::take(&mut timer.queries),
                        issued: timer.batch_start,
                    });
                }
                // Collected when the call was planned, before its own queries began: the
                // figures are an earlier call's.
                match self.ready.borrow_mut().take() {
                    Some((call, ms)) => {
                        let ago = (timer.plan.call - call).try_into().unwrap_or(u32::MAX);
                        PassTimes::measured(Clock::GpuTimer, ms, ago)
                    }
                    None => PassTimes::unavailable(),
                }
            }
            (_, Method::Queries) => {
                // SAFETY: results of queries this timer began and ended (waits for them).
                let ns: Vec<u64> = timer
                    .queries
                    .iter()
                    .map(|&q| unsafe { query_result_ns(&self.gl, q) })
                    .collect();
                let enclosing_ms = timer.batch_start.elapsed().as_secs_f64() * 1e3;
                // After all results are in.
                match judge(&ns, enclosing_ms, self.disjoint()) {
                    Ok(ms) => PassTimes::measured(Clock::GpuTimer, ms, 0),
                    Err(rejected) => {
                        log::warn!("GPU timer figures rejected ({rejected:?}): times unavailable");
                        PassTimes::unavailable()
                    }
                }
            }
            (_, Method::None) => PassTimes::unavailable(),
        };
        super::check_gl(&self.gl, "reading timer queries")?;
        Ok(times)
    }

    /// Whether the host has a TIME_ELAPSED query open (`None`: this cannot be told).
    fn host_query_open(&self) -> Option<bool> {
        // SAFETY: glGetQueryiv(TIME_ELAPSED, CURRENT_QUERY) on the current context, which
        // has GL_EXT_disjoint_timer_query (the target is valid).
        let open = unsafe { self.probe.time_elapsed_open() };
        match open {
            Some(true) => log::debug!("the host has a TIME_ELAPSED query open: no query begun"),
            None => log::debug!("glGetQueryiv not found: a host's query cannot be seen"),
            Some(false) => {}
        }
        open
    }

    /// Moves the deferred calls whose results are in (oldest first, in order) out of
    /// flight, keeping the newest one's figures in `ready` unless the driver flags a
    /// disjoint event (then every call in flight is dropped) or they cannot be right.
    /// Never waits.
    fn collect(&self) {
        let mut newest = None;
        {
            let mut flight = self.in_flight.borrow_mut();
            while let Some(front) = flight.front() {
                // SAFETY: availability of queries this keeper began and ended.
                let done = front.queries.iter().all(|&q| unsafe {
                    self.gl
                        .get_query_parameter_u32(q, glow::QUERY_RESULT_AVAILABLE)
                        != 0
                });
                if !done {
                    break;
                }
                let set = flight.pop_front().expect("front() was Some");
                // SAFETY: results that are available (no wait).
                let ns: Vec<u64> = set
                    .queries
                    .iter()
                    .map(|&q| unsafe { query_result_ns(&self.gl, q) })
                    .collect();
                let bound_ms = set.issued.elapsed().as_secs_f64() * 1e3;
                self.pool.give_back(set.queries);
                newest = Some((set.call, ns, bound_ms));
            }
        }
        let Some((call, ns, bound_ms)) = newest else {
            return;
        };
        // After the results were read. The flag covers every query in flight since it was
        // last read.
        let disjoint = self.disjoint();
        if disjoint {
            self.drop_in_flight();
        }
        match judge(&ns, bound_ms, disjoint) {
            Ok(ms) => *self.ready.borrow_mut() = Some((call, ms)),
            Err(rejected) => {
                log::warn!("GPU timer figures of call {call} rejected ({rejected:?})");
            }
        }
    }

    /// Forgets the deferred calls in flight and the figures not yet returned.
    fn drop_in_flight(&self) {
        let mut flight = self.in_flight.borrow_mut();
        self.pool
            .give_back(flight.drain(..).flat_map(|f| f.queries));
        *self.ready.borrow_mut() = None;
    }
}

impl Drop for Timekeeper {
    fn drop(&mut self) {
        // Back to the pool, which deletes them.
        self.drop_in_flight();
    }
}

/// The figures in milliseconds, or why they are rejected: a disjoint event, or a sum
/// that is not finite or exceeds the wall time that enclosed the passes.
fn judge(ns: &[u64], enclosing_ms: f64, disjoint: bool) -> std::result::Result<Vec<f64>, Rejected> {
    if disjoint {
        return Err(Rejected::Disjoint);
    }
    let ms: Vec<f64> = ns.iter().map(|&n| n as f64 / 1e6).collect();
    let sum: f64 = ms.iter().sum();
    if !sum.is_finite() || sum > enclosing_ms * OVERLAP_ALLOWANCE + 1.0 {
        return Err(Rejected::Implausible(format!(
            "timer queries sum to {sum:.3} ms inside {enclosing_ms:.3} ms of wall time"
        )));
    }
    Ok(ms)
}

/// Waits for a query's result and returns it (nanoseconds for TIME_ELAPSED). The driver's
/// blocking read waits: polling QUERY_RESULT_AVAILABLE with `yield_now` kept a core busy
/// that llvmpipe's threads shade on (a 12 MP render 2.91 → 2.75 s on 2 cores).
unsafe fn query_result_ns(gl: &glow::Context, q: glow::Query) -> u64 {
    let mut value: u64 = 0;
    // glow's "offset" is the destination pointer when no query buffer is bound.
    gl.get_query_parameter_u64_with_offset(
        q,
        glow::QUERY_RESULT,
        std::ptr::addr_of_mut!(value) as usize,
    );
    value
}

/// `glGetQueryiv`, which glow wraps only for query objects.
type GetQueryIv = unsafe extern "system" fn(u32, u32, *mut i32);

/// Tells whether a TIME_ELAPSED query is open on the current context
/// (`glGetQueryiv(GL_TIME_ELAPSED, GL_CURRENT_QUERY)`). glow does not wrap that call, and
/// a host's `glow::Context` does not lend its loader, so the entry point is looked up in
/// the GL libraries the process has already loaded: `eglGetProcAddress` of its libEGL
/// (`BRUME_EGL_LIBRARY`, `libEGL.so.1`, `libEGL.so`), then the symbol in `libGLESv2`
/// or `libGL`. Where none is found, brume cannot see a host's query and begins none.
#[derive(Clone, Copy, Debug)]
pub struct HostQueryProbe {
    get_query_iv: Option<GetQueryIv>,
}

impl HostQueryProbe {
    /// Looks the entry point up (once found, kept for the process).
    pub fn load() -> Self {
        static FOUND: OnceLock<GetQueryIv> = OnceLock::new();
        let get_query_iv = FOUND.get().copied().or_else(|| {
            let f = find_get_query_iv()?;
            Some(*FOUND.get_or_init(|| f))
        });
        HostQueryProbe { get_query_iv }
    }

    /// `Some(true)` when a TIME_ELAPSED query is open, `None` when this cannot be told.
    ///
    /// # Safety
    /// A context with `GL_EXT_disjoint_timer_query` is current on this thread.
    pub unsafe fn time_elapsed_open(&self) -> Option<bool> {
        let f = self.get_query_iv?;
        let mut name: i32 = 0;
        f(glow::TIME_ELAPSED, glow::CURRENT_QUERY, &mut name);
        Some(name != 0)
    }
}

/// `RTLD_NOLOAD` (glibc and bionic): open a library only if it is already loaded.
#[cfg(any(target_os = "linux", target_os = "android"))]
const RTLD_NOLOAD: std::os::raw::c_int = 4;

#[cfg(any(target_os = "linux", target_os = "android"))]
fn find_get_query_iv() -> Option<GetQueryIv> {
    use libloading::os::unix::{Library, RTLD_NOW};
    use std::ffi::c_void;
    type GetProcAddress = unsafe extern "system" fn(*const std::os::raw::c_char) -> *const c_void;
    // SAFETY: only libraries already loaded are opened (no initialiser runs); each is
    // kept open for the process (forgotten), so the pointers stay valid.
    let open =
        |name: &std::ffi::OsStr| unsafe { Library::open(Some(name), RTLD_NOW | RTLD_NOLOAD).ok() };
    let mut egl_names: Vec<std::ffi::OsString> = Vec::new();
    if let Some(name) = std::env::var_os(crate::egl::EGL_LIBRARY_ENV) {
        egl_names.push(name);
    }
    egl_names.extend(["libEGL.so.1".into(), "libEGL.so".into()]);
    for name in &egl_names {
        let Some(lib) = open(name) else { continue };
        // SAFETY: eglGetProcAddress has this signature; EGL 1.5 (and
        // EGL_KHR_get_all_proc_addresses, which Mesa, libglvnd and Android offer)
        // returns core GL entry points too.
        let found = unsafe {
            lib.get::<GetProcAddress>(b"eglGetProcAddress\0")
                .ok()
                .map(|get| get(c"glGetQueryiv".as_ptr()))
                .filter(|p| !p.is_null())
                .map(|p| std::mem::transmute::<*const c_void, GetQueryIv>(p))
        };
        std::mem::forget(lib);
        if found.is_some() {
            return found;
        }
    }
    for name in [
        "libGLESv2.so.2",
        "libGLESv2.so",
        "libGLESv3.so",
        "libGL.so.1",
    ] {
        let Some(lib) = open(name.as_ref()) else {
            continue;
        };
        // SAFETY: the GL entry point has this signature.
        let found = unsafe { lib.get::<GetQueryIv>(b"glGetQueryiv\0").ok().map(|s| *s) };
        std::mem::forget(lib);
        if found.is_some() {
            return found;
        }
    }
    None
}

#[cfg(not(any(target_os = "linux", target_os = "android")))]
fn find_get_query_iv() -> Option<GetQueryIv> {
    None
}
