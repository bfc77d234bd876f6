//! What one command-line value may ask for: every count has a cap and every image size a
//! cap and a memory estimate, checked before the work or the allocation starts, so that a
//! typo (`--runs 1000000`, `--size 100000`) is an error naming the option instead of a
//! run that never ends or a process the allocator kills. The README's limits table lists
//! these constants.

use brume::io::limits::{MAX_PIXELS, MAX_SIDE};
use brume::{Error, Result};

/// Frames of one `brume scene` or scripted `brume view` run.
pub const MAX_FRAMES: u32 = 10_000;
/// Timed runs per configuration of `bench speed` and `bench fog`.
pub const MAX_RUNS: usize = 1_000;
/// Estimations per image of `turbidity --repeats` and `bench turbidity --estimations`.
pub const MAX_ESTIMATIONS: usize = brume::sky::turbidity::MAX_REPEATS;
/// Random sample points of one turbidity estimation (`--samples`).
pub const MAX_SAMPLES: usize = 100_000;
/// Sample points of a whole turbidity run (estimations × samples × skies): 7-10 µs each
/// (measured on a 500 px sky, with and without `--fit-level`), so about a minute and a
/// half at most.
pub const MAX_SAMPLE_POINTS: u64 = 10_000_000;
/// Side of a `bench turbidity` sky image: the paper's are 500 px; the estimator samples a
/// few hundred points, so larger skies only cost memory and time (a 2000 px sky with
/// clouds takes about 13 s to make, and the benchmark makes 16 by default).
pub const MAX_TURBIDITY_BENCH_SIDE: usize = 2048;
/// Side of `view --window`, logical px: X11 sizes are 16-bit and a window larger than any
/// screen has no use; the screenshot read back from it stays under 256 MB.
#[cfg(all(feature = "viewer", not(target_os = "android")))]
pub const MAX_WINDOW_SIDE: usize = 8192;

/// A count given on the command line, in `min..=max`, naming `option` and the unit.
pub fn count(option: &str, value: i64, min: usize, max: usize, unit: &str) -> Result<usize> {
    usize::try_from(value)
        .ok()
        .filter(|n| (min..=max).contains(n))
        .ok_or_else(|| {
            Error::invalid(
                option,
                value,
                format!("a number of {unit} from {min} to {max}"),
            )
        })
}

/// `--frames`: from 1 to [`MAX_FRAMES`].
pub fn check_frames(frames: u32) -> Result<()> {
    if !(1..=MAX_FRAMES).contains(&frames) {
        return Err(Error::invalid(
            "--frames",
            frames,
            format!("a number of frames from 1 to {MAX_FRAMES}"),
        ));
    }
    Ok(())
}

/// `WIDTHxHEIGHT` for `option`: both ≥ 1, at most `max_side` and, together, at most
/// [`MAX_PIXELS`] (the largest image brume reads).
pub fn parse_size(option: &str, text: &str, max_side: usize) -> Result<(usize, usize)> {
    let bad = || {
        Error::invalid(
            option,
            text,
            format!(
                "WIDTHxHEIGHT in px, both from 1 to {max_side} and at most {MAX_PIXELS} \
                 pixels in all, e.g. 1600x1120"
            ),
        )
    };
    let (w, h) = text.trim().split_once(['x', 'X']).ok_or_else(bad)?;
    let w: usize = w.trim().parse().map_err(|_| bad())?;
    let h: usize = h.trim().parse().map_err(|_| bad())?;
    let fits = |s: usize| (1..=max_side).contains(&s);
    if !(fits(w) && fits(h)) || w * h > MAX_PIXELS {
        return Err(bad());
    }
    Ok((w, h))
}

/// An image size option of a command that renders: [`parse_size`] with brume's largest
/// image side.
pub fn parse_image_size(option: &str, text: &str) -> Result<(usize, usize)> {
    parse_size(option, text, MAX_SIDE)
}

/// Refuses `option`'s image of `width` x `height` when `bytes_per_pixel` of it (measured
/// for the command, see the README) cannot fit in the memory left.
pub fn check_memory(option: &str, width: usize, height: usize, bytes_per_pixel: u64) -> Result<()> {
    let pixels = width as u64 * height as u64;
    brume::memory::check_available(
        &format!("{option} {width}x{height}"),
        pixels.saturating_mul(bytes_per_pixel),
        &format!(
            "this command holds about {bytes_per_pixel} bytes per pixel: give a smaller \
             {option}"
        ),
    )
}

/// Refuses a turbidity run whose `estimations` × `samples` × `skies` sample points exceed
/// [`MAX_SAMPLE_POINTS`], naming the options that set them.
pub fn check_sample_points(
    options: &str,
    estimations: usize,
    samples: usize,
    skies: usize,
) -> Result<()> {
    let points = (estimations as u64)
        .saturating_mul(samples as u64)
        .saturating_mul(skies as u64);
    if points > MAX_SAMPLE_POINTS {
        return Err(Error::invalid(
            options,
            format!("{estimations} x {samples} x {skies} = {points} sample points"),
            format!("at most {MAX_SAMPLE_POINTS} sample points in one run"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_capped_and_named() {
        assert_eq!(count("--runs", 5, 1, MAX_RUNS, "runs").unwrap(), 5);
        for bad in [0, -1, 1_000_001] {
            let e = count("--runs", bad, 1, MAX_RUNS, "runs").unwrap_err();
            let text = e.to_string();
            assert!(text.contains("--runs") && text.contains("1000"), "{text}");
        }
    }

    #[test]
    fn sizes_are_capped_per_side_and_in_all() {
        assert_eq!(parse_size("--size", "2x3", 10).unwrap(), (2, 3));
        for bad in ["0x3", "11x2", "2x", "ax2", "100000x100000"] {
            let text = parse_size("--window", bad, 10).unwrap_err().to_string();
            assert!(text.contains("--window") && text.contains("10"), "{text}");
        }
        assert!(parse_image_size("--size", "16384x4096").is_ok());
        assert!(parse_image_size("--size", "16384x16384").is_err());
    }

    #[test]
    fn sample_points_are_capped() {
        assert!(check_sample_points("--repeats", 10, 100, 1).is_ok());
        let e = check_sample_points("--repeats/--samples", 10_000, 100_000, 1).unwrap_err();
        assert!(e.to_string().contains("--repeats/--samples"), "{e}");
    }
}
