//! Where a phone's portrait map stops, when its depth image is a lossy JPEG. A portrait
//! mode writes its map up to a limit (GDepth's `Far`; an iPhone's farthest code) and
//! clamps all that lies beyond, the sky included, to that code: a spike of samples at it,
//! which brume reads as unknown (the scene beyond the reach). A JPEG's ringing beside an
//! edge lifts that flat background off the code by one or a few, and each sample so lifted,
//! read as a depth just short of the limit, is a clear blotch in the fog. So in a lossy
//! image clamped at its limit, codes within [`LOSSY_STOP_CODES`] of it are read as it too.
//!
//! A map whose farthest samples merely reach the code has no spike there: a background
//! that recedes smoothly to the farthest code (an iPhone's maps are spread over their own
//! least and greatest disparity, so some sample is always at the farthest code) keeps its
//! codes beside it as depths. On a real iPhone X portrait (`tests/data/apple/iphone-x.jpg`)
//! the 7 443 samples within 3 codes of its farthest (663 at it) were the wall behind a vase,
//! and read as unknown, a bright strip of them at the top of the frame became sky.

/// How near the code where a map stops a sample of a lossy image clamped there is read as
/// stopped too, in codes of 255. 3 was the best of those tried (0 to 8) on the street scene
/// of `tools/phone_depth_eval.py` (`--format apple-depth` at JPEG qualities 85, 95 and 100,
/// `--format gdepth --gdepth-mime jpeg`): the README's tables.
pub(super) const LOSSY_STOP_CODES: f64 = 3.0;

/// The margin that keeps a code at a tolerance within it whichever way a division rounds.
const ROUNDING: f64 = 1e-9;

/// Whether a sample `from_stop` of the code range (0 to 1) away from the code where the
/// map stops is where it stops: within `tolerance` (a fraction of the range) of that code.
pub(super) fn stopped(from_stop: f64, tolerance: f64) -> bool {
    from_stop <= tolerance + ROUNDING
}

/// The tolerance of a lossy image ([`LOSSY_STOP_CODES`] of 255, as a fraction of the code
/// range) if its map is clamped at the code where it stops: more of its samples at that
/// code than within the tolerance beside it. `from_stop` is each sample's distance from
/// that code, as a fraction of the range. `None` for a map that only reaches the code.
pub(super) fn lossy_stop(from_stop: impl Iterator<Item = f64>) -> Option<f64> {
    let tolerance = LOSSY_STOP_CODES / 255.0;
    let (mut at, mut beside) = (0usize, 0usize);
    for f in from_stop {
        if stopped(f, 0.0) {
            at += 1;
        } else if stopped(f, tolerance) {
            beside += 1;
        }
    }
    (at > beside).then_some(tolerance)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn from_stop(codes: &[u8]) -> impl Iterator<Item = f64> + '_ {
        codes.iter().map(|&c| f64::from(255 - c) / 255.0)
    }

    /// A lossless image stops at its last code only; a lossy one clamped there, within 3
    /// codes of 255 of it.
    #[test]
    fn a_clamped_lossy_image_stops_near_its_last_code() {
        let at = |code: u8| f64::from(255 - code) / 255.0;
        assert!(stopped(at(255), 0.0) && !stopped(at(254), 0.0));
        assert!(
            !stopped(1.0 / 65535.0, 0.0),
            "a 16-bit PNG's last code but one"
        );
        let tolerance = LOSSY_STOP_CODES / 255.0;
        for code in [255, 254, 252] {
            assert!(stopped(at(code), tolerance), "{code}");
        }
        assert!(!stopped(at(251), tolerance));
    }

    /// A spike at the last code (the sky clamped there, a little ringing beside it) is a
    /// clamp; a tail of codes reaching it (a wall receding to the farthest sample) is not.
    #[test]
    fn a_clamp_is_a_spike_at_the_last_code() {
        let clamped = [vec![255; 500], vec![254; 40], vec![253; 20], vec![100; 900]].concat();
        assert_eq!(lossy_stop(from_stop(&clamped)), Some(3.0 / 255.0));
        let reaching = [
            vec![255; 60],
            vec![254; 300],
            vec![252; 200],
            vec![100; 900],
        ]
        .concat();
        assert_eq!(lossy_stop(from_stop(&reaching)), None);
        assert_eq!(
            lossy_stop(from_stop(&[100, 200])),
            None,
            "nothing at the stop"
        );
    }
}
