//! Far outliers: isolated values in the far tail of the range, which a scanner or a stereo
//! matcher produces where it has nothing to match (the sky, glass, a dark sky-line) and
//! which, left in, would set the frame's scale `Rmax` on their own.
//!
//! The tail is cut robustly: `cut = factor x P99`, the 99th percentile (nearest rank) of
//! the values considered, so up to 1 % of bogus values cannot move it. A value above the
//! cut is kept only when it is *supported*: its 8-connected patch of values above the cut
//! has at least `min_patch` pixels. A real far surface (a distant hillside, a tower) is a
//! patch; a bogus value is a speck or a small blob.

/// Nearest-rank percentile of the values that set the cut.
const PERCENTILE: f64 = 0.99;

/// `factor x` the 99th percentile of the finite values of `work` at the pixels where
/// `include` is true; `None` when `factor` is 0 (the rule is off), when no such value is
/// finite, or when the percentile is not positive (no meaningful "far" then).
pub(crate) fn far_cut(
    work: &[f32],
    include: impl Fn(usize) -> bool + Sync,
    factor: f64,
) -> Option<f32> {
    if factor == 0.0 {
        return None;
    }
    let p99 = super::rank::nth_kept(
        work,
        |i, v| v.is_finite() && include(i),
        |n| ((n as f64 * PERCENTILE).ceil() as usize).clamp(1, n) - 1,
    )?;
    (p99 > 0.0).then(|| (factor * f64::from(p99)).min(f64::from(f32::MAX)) as f32)
}

/// The range above which a known pixel may be sky for the image-guided detector (its
/// [`super::range_class::RangeClass::Far`]): the far-outlier cut over the whole map, or,
/// for a monocular model's map ([`super::PrepOptions::sky_in_far_tail`]), `k` times the
/// lower quartile of the range where that is lower (a quartile, not the median: the sky
/// may be half the frame, and its depth would be the median).
pub(crate) fn sky_candidate_cut(work: &[f32], opts: &super::PrepOptions) -> Option<f32> {
    let far = far_cut(work, |_| true, opts.far_outlier_factor);
    let tail = opts.sky_in_far_tail.and_then(|k| {
        let quartile = super::rank::nth_kept(work, |_, v| v.is_finite(), |n| n / 4)?;
        Some((k * f64::from(quartile)).min(f64::from(f32::MAX)) as f32)
    });
    match (far, tail) {
        (Some(f), Some(t)) => Some(f.min(t)),
        (f, t) => f.or(t),
    }
}

/// Makes unknown (NaN) every known pixel of `work` outside `sky` whose value exceeds `cut`
/// and whose 8-connected patch of such pixels has fewer than `min_patch` pixels. Returns
/// how many were removed.
pub(crate) fn remove_far(
    work: &mut [f32],
    sky: &[bool],
    width: usize,
    height: usize,
    cut: f32,
    min_patch: usize,
) -> usize {
    let beyond = |work: &[f32], i: usize| !sky[i] && work[i].is_finite() && work[i] > cut;
    let mut seen = vec![false; work.len()];
    let mut patch = Vec::new();
    let mut removed = 0;
    for seed in 0..work.len() {
        if seen[seed] || !beyond(work, seed) {
            continue;
        }
        patch.clear();
        patch.push(seed);
        seen[seed] = true;
        let mut head = 0;
        while head < patch.len() {
            let p = patch[head];
            head += 1;
            for q in neighbours8(p, width, height).into_iter().flatten() {
                if !seen[q] && beyond(work, q) {
                    seen[q] = true;
                    patch.push(q);
                }
            }
        }
        if patch.len() < min_patch {
            patch.iter().for_each(|&p| work[p] = f32::NAN);
            removed += patch.len();
        }
    }
    removed
}

/// The in-image 8-neighbours of pixel `p`.
#[inline]
pub(crate) fn neighbours8(p: usize, width: usize, height: usize) -> [Option<usize>; 8] {
    let (x, y) = (p % width, p / width);
    let (l, r, u, d) = (x > 0, x + 1 < width, y > 0, y + 1 < height);
    [
        (u && l).then(|| p - width - 1),
        u.then(|| p - width),
        (u && r).then(|| p - width + 1),
        l.then(|| p - 1),
        r.then(|| p + 1),
        (d && l).then(|| p + width - 1),
        d.then(|| p + width),
        (d && r).then(|| p + width + 1),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sky candidates' cut: the far-outlier cut, or for a monocular map ten times the
    /// lower quartile where that is lower; an invalid factor is refused.
    #[test]
    fn a_monocular_maps_far_tail_may_be_sky() {
        // A quarter of the map at 1, a quarter at 4, half (the sky) at 300.
        let m: Vec<f32> = (0..100)
            .map(|i| match i {
                0..25 => 1.0,
                25..50 => 4.0,
                _ => 300.0,
            })
            .collect();
        let mut opts = crate::prep::PrepOptions::default();
        assert_eq!(sky_candidate_cut(&m, &opts), Some(600.0));
        opts.sky_in_far_tail = Some(10.0);
        assert_eq!(sky_candidate_cut(&m, &opts), Some(40.0));
        opts.far_outlier_factor = 0.0;
        assert_eq!(sky_candidate_cut(&m, &opts), Some(40.0));
        for bad in [1.0, 0.5, f64::NAN, f64::INFINITY] {
            opts.sky_in_far_tail = Some(bad);
            let e = opts.validate().unwrap_err().to_string();
            assert!(e.contains("sky_in_far_tail"), "{e}");
        }
    }

    #[test]
    fn specks_go_patches_stay() {
        let (w, h) = (20, 10);
        let mut m = vec![10.0f32; w * h];
        m[3 * w + 3] = 1e5; // a speck
        m[7 * w + 10] = 500.0; // a diagonal pair: one 8-connected patch of 2
        m[8 * w + 11] = 600.0;
        for y in 0..5 {
            for x in 14..20 {
                m[y * w + x] = 300.0; // a 30-px far surface
            }
        }
        let cut = far_cut(&m, |_| true, 2.0).unwrap();
        // 33 of 200 values are far: the 99th percentile is among them.
        assert!(cut >= 600.0, "{cut}");
        let cut = 20.0;
        let sky = vec![false; w * h];
        let removed = remove_far(&mut m, &sky, w, h, cut, 16);
        assert_eq!(removed, 3);
        assert!(m[3 * w + 3].is_nan() && m[7 * w + 10].is_nan() && m[8 * w + 11].is_nan());
        assert_eq!(m.iter().filter(|v| **v == 300.0).count(), 30);
    }

    #[test]
    fn off_empty_or_non_positive_gives_no_cut() {
        assert_eq!(far_cut(&[1.0, 2.0], |_| true, 0.0), None);
        assert_eq!(far_cut(&[f32::NAN], |_| true, 2.0), None);
        assert_eq!(far_cut(&[-1.0, 0.0], |_| true, 2.0), None);
        assert_eq!(far_cut(&[1.0, 2.0], |i| i == 0, 2.0), Some(2.0));
        assert_eq!(far_cut(&[f32::MAX], |_| true, 3.0), Some(f32::MAX));
    }
}
