//! brume's CPU thread pool: every parallel loop of the library (rayon's iterators and
//! `join`) runs on it, inside [`run`].
//!
//! Why not rayon's global pool: a process that forks after brume's first parallel call (a
//! PyTorch `DataLoader`'s workers, Python's `multiprocessing` on Linux, a server that
//! forks workers) gives its child a copy of the pool without the pool's threads, so the
//! child's first parallel call waits for them forever, and rayon's global pool cannot be
//! built again. This pool is built once per process: a child that finds the parent's
//! builds its own.

use rayon::{ThreadPool, ThreadPoolBuilder};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// The pool and the process that built it.
static POOL: Mutex<Option<(u32, Arc<ThreadPool>)>> = Mutex::new(None);

/// The pool's size that [`set_num_threads`] asked for; 0: rayon's default.
static NUM_THREADS: AtomicUsize = AtomicUsize::new(0);

/// Sizes brume's pool: `Some(n)` threads, or `None` for `RAYON_NUM_THREADS`, else one a
/// core (the default). Work already running keeps the pool it started on; the next call
/// builds the new one.
pub fn set_num_threads(threads: Option<usize>) {
    NUM_THREADS.store(threads.unwrap_or(0), Ordering::Relaxed);
    let mut slot = POOL.lock().unwrap_or_else(|e| e.into_inner());
    if slot
        .as_ref()
        .is_some_and(|(owner, _)| *owner == std::process::id())
    {
        *slot = None;
    }
}

/// This process's pool, built on first use; `None` if its threads cannot be started (then
/// rayon's own pool is used).
fn pool() -> Option<Arc<ThreadPool>> {
    let pid = std::process::id();
    let mut slot = POOL.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((owner, pool)) = slot.as_ref() {
        if *owner == pid {
            return Some(Arc::clone(pool));
        }
    }
    // A parent's pool (this process was forked): its threads are not in this process, and
    // dropping it would wait on them, so it is leaked.
    if let Some((_, inherited)) = slot.take() {
        std::mem::forget(inherited);
    }
    let pool = ThreadPoolBuilder::new()
        .num_threads(NUM_THREADS.load(Ordering::Relaxed))
        .thread_name(|i| format!("brume-cpu-{i}"))
        .build()
        .map_err(|e| log::warn!("brume's CPU thread pool could not start ({e}): using rayon's"))
        .ok()?;
    let pool = Arc::new(pool);
    *slot = Some((pid, Arc::clone(&pool)));
    Some(pool)
}

/// Runs `f` on this process's pool, so that the parallel iterators inside it use the pool.
pub fn run<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    match pool() {
        Some(pool) => pool.install(f),
        None => f(),
    }
}

/// Items a parallel filter tests per task. rayon's own split of a 2-megapixel
/// `filter().collect()` makes so many small pieces that collecting them cost more than
/// the tests (5-6 ms a frame).
const FILTER_PIECE: usize = 1 << 16;

/// The items of `items` that `keep(index, item)` keeps, in their order, tested in
/// parallel in pieces of [`FILTER_PIECE`].
pub(crate) fn filter_in_order<T: Copy + Send + Sync>(
    items: &[T],
    keep: impl Fn(usize, T) -> bool + Sync,
) -> Vec<T> {
    use rayon::prelude::*;
    let keep = &keep;
    items
        .par_chunks(FILTER_PIECE)
        .enumerate()
        .flat_map_iter(|(c, piece)| {
            let first = c * FILTER_PIECE;
            (first..)
                .zip(piece)
                .filter_map(move |(i, &v)| keep(i, v).then_some(v))
        })
        .collect()
}

/// The indices below `len` that `keep` keeps, in order, tested as [`filter_in_order`]
/// tests.
pub(crate) fn indices_in_order(len: usize, keep: impl Fn(usize) -> bool + Sync) -> Vec<usize> {
    indices_in_order_with(len, || (), |_, i| keep(i))
}

/// [`indices_in_order`] with a scratch value from `init` that `keep` may reuse from one
/// index to the next: one per piece, rather than an allocation per index.
pub(crate) fn indices_in_order_with<S>(
    len: usize,
    init: impl Fn() -> S + Sync,
    keep: impl Fn(&mut S, usize) -> bool + Sync,
) -> Vec<usize> {
    use rayon::prelude::*;
    let (init, keep) = (&init, &keep);
    (0..len.div_ceil(FILTER_PIECE))
        .into_par_iter()
        .flat_map_iter(|c| {
            let piece = c * FILTER_PIECE..len.min((c + 1) * FILTER_PIECE);
            let mut scratch = init();
            piece.filter(move |&i| keep(&mut scratch, i))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    /// Over several pieces: every kept item, in order, with its own index.
    #[test]
    fn filters_keep_the_order_and_the_indices() {
        let len = 3 * FILTER_PIECE + 17;
        let items: Vec<u32> = (0..len as u32)
            .map(|i| i.wrapping_mul(2_654_435_761))
            .collect();
        let keep = |i: usize, v: u32| i % 5 == 1 && !v.is_multiple_of(3);
        let want: Vec<u32> = (0..len)
            .filter(|&i| keep(i, items[i]))
            .map(|i| items[i])
            .collect();
        assert_eq!(filter_in_order(&items, keep), want);
        let want: Vec<usize> = (0..len).filter(|&i| i % 7 == 3).collect();
        assert_eq!(indices_in_order(len, |i| i % 7 == 3), want);
        assert!(indices_in_order(0, |_| true).is_empty());
    }

    #[test]
    fn parallel_work_runs_on_brumes_pool() {
        let names: Vec<String> = run(|| {
            (0..64)
                .into_par_iter()
                .map(|_| std::thread::current().name().unwrap_or("").to_owned())
                .collect()
        });
        assert!(
            names.iter().all(|n| n.starts_with("brume-cpu-")),
            "{names:?}"
        );
        let (a, b) = run(|| rayon::join(|| 2 + 2, || "four"));
        assert_eq!((a, b), (4, "four"));
        set_num_threads(Some(3));
        assert_eq!(run(rayon::current_num_threads), 3);
        set_num_threads(None);
        assert_eq!(
            run(rayon::current_num_threads),
            ThreadPoolBuilder::new()
                .build()
                .unwrap()
                .current_num_threads()
        );
    }
}
