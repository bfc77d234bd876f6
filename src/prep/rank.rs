//! The value of a given rank among a map's values (a percentile, a median) without
//! sorting or copying the map: a radix select.
//!
//! `select_nth_unstable` on a copy of a 2-megapixel map's values costs a 7 MB copy and
//! ~10 ms a call; pre-processing asks for such ranks several times a frame. Here one
//! parallel pass counts the values by the top 16 bits of their order key, which names the
//! bucket holding the rank; only that bucket's values (a few thousand at 2 megapixels)
//! are copied and selected from. The result is the same value, bit for bit, as selecting from a copy.

use rayon::prelude::*;

/// Buckets of the first pass: the key's top 16 bits.
const BUCKETS: usize = 1 << 16;

/// Values a parallel task counts at least: fewer histograms to add up.
const MIN_TASK: usize = 1 << 16;

/// A key whose unsigned order is [`f32::total_cmp`]'s order.
#[inline]
fn order_key(v: f32) -> u32 {
    let bits = v.to_bits();
    if bits >> 31 == 1 {
        !bits
    } else {
        bits | 1 << 31
    }
}

/// The value of 0-based rank `rank(n)` in [`f32::total_cmp`] order among the `n` values
/// `values[i]` for which `keep(i, values[i])`; `None` when no value is kept. `rank(n)`
/// must be below `n`.
pub(crate) fn nth_kept(
    values: &[f32],
    keep: impl Fn(usize, f32) -> bool + Sync,
    rank: impl FnOnce(usize) -> usize,
) -> Option<f32> {
    let counts = bucket_counts(values, &keep);
    let n: usize = counts.iter().sum();
    if n == 0 {
        return None;
    }
    let rank = rank(n);
    assert!(rank < n, "rank {rank} of {n} values");
    let (bucket, below) = bucket_of(&counts, rank);
    let mut in_bucket = crate::parallel::filter_in_order(values, |i, v| {
        (order_key(v) >> 16) as usize == bucket && keep(i, v)
    });
    Some(
        *in_bucket
            .select_nth_unstable_by(rank - below, f32::total_cmp)
            .1,
    )
}

/// How many values one parallel task takes.
fn task_len(len: usize) -> usize {
    MIN_TASK.max(len / (4 * rayon::current_num_threads()))
}

/// How many kept values fall in each bucket.
fn bucket_counts(values: &[f32], keep: &(impl Fn(usize, f32) -> bool + Sync)) -> Vec<usize> {
    let task = task_len(values.len());
    values
        .par_chunks(task)
        .enumerate()
        .map(|(c, chunk)| {
            let mut counts = vec![0usize; BUCKETS];
            for (j, &v) in chunk.iter().enumerate() {
                if keep(c * task + j, v) {
                    counts[(order_key(v) >> 16) as usize] += 1;
                }
            }
            counts
        })
        .reduce_with(|mut a, b| {
            a.iter_mut().zip(&b).for_each(|(a, b)| *a += b);
            a
        })
        .unwrap_or_else(|| vec![0; BUCKETS])
}

/// The bucket that holds `rank`, and how many values are in the buckets before it.
fn bucket_of(counts: &[usize], rank: usize) -> (usize, usize) {
    let mut below = 0;
    for (bucket, &count) in counts.iter().enumerate() {
        if rank < below + count {
            return (bucket, below);
        }
        below += count;
    }
    unreachable!("rank {rank} is below the number of values {below}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// The rank's value from a sorted copy: the definition, independent of the buckets.
    fn by_sorting(values: &[f32], keep: impl Fn(usize, f32) -> bool, rank: usize) -> f32 {
        let mut kept: Vec<f32> = (0..values.len())
            .filter(|&i| keep(i, values[i]))
            .map(|i| values[i])
            .collect();
        kept.sort_by(f32::total_cmp);
        kept[rank]
    }

    #[test]
    fn every_rank_matches_a_sorted_copy() {
        let mut rng = SplitMix64::new(7);
        // Negative, zero of both signs, infinities, NaN, ties, values sharing a bucket.
        let mut values: Vec<f32> = (0..5000)
            .map(|_| (rng.unit() as f32 - 0.3) * 100.0)
            .collect();
        values.extend([
            0.0,
            -0.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            1.0,
            1.0,
        ]);
        values.extend((0..300).map(|i| 50.0 + i as f32 * 1e-5));
        let keep = |i: usize, v: f32| v.is_finite() && i % 3 != 1;
        let n = (0..values.len()).filter(|&i| keep(i, values[i])).count();
        for rank in (0..n).step_by(37).chain([0, n / 2, n - 1]) {
            let got = nth_kept(&values, keep, |m| {
                assert_eq!(m, n);
                rank
            });
            let want = by_sorting(&values, keep, rank);
            assert_eq!(got.map(f32::to_bits), Some(want.to_bits()), "rank {rank}");
        }
        // Every value kept, NaN and infinities included, ordered as total_cmp orders them.
        let all = values.len();
        for rank in [0, 1, all / 2, all - 2, all - 1] {
            let got = nth_kept(&values, |_, _| true, |_| rank).map(f32::to_bits);
            assert_eq!(got, Some(by_sorting(&values, |_, _| true, rank).to_bits()));
        }
    }

    /// More values than one parallel task takes: each task's indices are the map's.
    #[test]
    fn the_tasks_keep_the_pixels_indices() {
        let mut rng = SplitMix64::new(3);
        let values: Vec<f32> = (0..5 * MIN_TASK + 123)
            .map(|_| rng.unit() as f32 * 10.0)
            .collect();
        // Kept by index alone: a task that read its indices wrong keeps other values.
        let keep = |i: usize, _: f32| i % 7 == 2;
        let n = (0..values.len()).filter(|&i| keep(i, 0.0)).count();
        for rank in [0, n / 3, n / 2, n - 1] {
            let got = nth_kept(&values, keep, |_| rank).map(f32::to_bits);
            assert_eq!(got, Some(by_sorting(&values, keep, rank).to_bits()));
        }
    }

    #[test]
    fn nothing_kept_has_no_rank() {
        assert_eq!(nth_kept(&[1.0, 2.0], |_, _| false, |_| 0), None);
        assert_eq!(nth_kept(&[], |_, _| true, |_| 0), None);
    }
}
