//! The image side of the estimation: the sun's blob, the usable pixels, the reference
//! patch and the draw of samples.

use super::*;

/// `n` distinct indices in `0..len`, uniformly (`n ≤ len`).
pub(super) fn draw_distinct(rng: &mut SplitMix64, len: usize, n: usize) -> Vec<usize> {
    if 2 * n > len {
        // Dense: a partial Fisher-Yates shuffle of all indices.
        let mut all: Vec<usize> = (0..len).collect();
        for i in 0..n {
            let j = i + rng.below(len - i);
            all.swap(i, j);
        }
        all.truncate(n);
        return all;
    }
    let mut seen = HashSet::with_capacity(2 * n);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let i = rng.below(len);
        if seen.insert(i) {
            out.push(i);
        }
    }
    out
}

pub(super) fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let m = values.len() / 2;
    if values.len() % 2 == 1 {
        values[m]
    } else {
        0.5 * (values[m - 1] + values[m])
    }
}

/// Usable as a sample or reference: finite, not black, not clipped.
pub(super) fn is_usable(rgb: [f32; 3], lum: f64, clip: f64) -> bool {
    let top = rgb[0].max(rgb[1]).max(rgb[2]) as f64;
    lum > 0.0 && lum.is_finite() && top < clip
}

/// The side of a square, non-empty image, or an error naming it.
pub(super) fn check_square(image: &RgbImage, name: &str) -> Result<usize> {
    if image.is_empty() || image.width() != image.height() {
        return Err(Error::format(
            name,
            format!(
                "is {}x{}: a fisheye sky image must be square, with the horizon circle \
                 inscribed (crop it to the circle's bounding square)",
                image.width(),
                image.height()
            ),
        ));
    }
    Ok(image.width())
}

/// The largest channel value inside the horizon circle.
pub(super) fn image_max(image: &RgbImage, fisheye: &Fisheye) -> Result<f64> {
    let size = image.width();
    let mut max = 0.0f64;
    for y in 0..size {
        for x in 0..size {
            if fisheye.pixel_direction(size, x, y).is_some() {
                let p = image.get(x, y);
                max = max.max(p[0].max(p[1]).max(p[2]) as f64);
            }
        }
    }
    Ok(max)
}

/// The usable pixels within [`REFERENCE_RADIUS_PX`] of the reference direction and
/// their mean luminance, or `None` if there is none.
pub(super) fn reference_patch(
    image: &RgbImage,
    fisheye: &Fisheye,
    reference: [f64; 2],
    sun: [f64; 2],
    clip: f64,
    luminance: [f64; 3],
) -> Option<(Vec<Geom>, f64)> {
    let size = image.width();
    let (px, py) = fisheye.pixel(size, reference[0], reference[1])?;
    let r = REFERENCE_RADIUS_PX;
    let (x0, x1) = (
        (px - r).floor().max(0.0) as usize,
        ((px + r).ceil() as usize).min(size),
    );
    let (y0, y1) = (
        (py - r).floor().max(0.0) as usize,
        ((py + r).ceil() as usize).min(size),
    );
    let mut patch = Vec::new();
    for y in y0..y1 {
        for x in x0..x1 {
            let (cx, cy) = (x as f64 + 0.5 - px, y as f64 + 0.5 - py);
            if cx * cx + cy * cy > r * r {
                continue;
            }
            let Some((theta, phi)) = fisheye.pixel_direction(size, x, y) else {
                continue;
            };
            let rgb = *image.get(x, y);
            let lum = super::super::weighted_luminance(luminance, rgb);
            if !is_usable(rgb, lum, clip) {
                continue;
            }
            patch.push((Geom::new(theta, phi, sun), lum));
        }
    }
    if patch.is_empty() {
        return None;
    }
    // Leave out the pixels that disagree with the rest of the patch (the edge of a cloud
    // across it): over a few pixels the model's F hardly changes shape with T, so Y/F at
    // a middling T is the same for every clear pixel; keep those within 3 robust
    // standard deviations (at least 1 %, PATCH_MIN_THRESHOLD) of the median.
    let mid = Perez::luminance(5.0);
    let u: Vec<f64> = patch.iter().map(|(g, lum)| lum / g.f(&mid)).collect();
    let m = median(&mut u.clone());
    let mut dev: Vec<f64> = u.iter().map(|v| (v / m - 1.0).abs()).collect();
    let limit = (3.0 * 1.4826 * median(&mut dev.clone())).max(PATCH_MIN_THRESHOLD);
    dev.iter_mut()
        .for_each(|d| *d = if *d <= limit { 1.0 } else { 0.0 });
    let kept: Vec<(Geom, f64)> = patch
        .into_iter()
        .zip(dev)
        .filter(|(_, keep)| *keep > 0.0)
        .map(|(p, _)| p)
        .collect();
    let n = kept.len() as f64;
    let mean = kept.iter().map(|(_, lum)| lum).sum::<f64>() / n;
    Some((kept.into_iter().map(|(g, _)| g).collect(), mean))
}

/// Finds the sun in a fisheye sky image: the centroid of the largest 8-connected blob of
/// near-maximal pixels (largest channel ≥ [`NEAR_MAX`] × the image's largest value) inside
/// the horizon circle, as the mean of the blob's unit direction vectors. `name` stands
/// for the image in errors.
pub fn find_sun(image: &RgbImage, name: &str, fisheye: &Fisheye) -> Result<SunDetection> {
    let size = check_square(image, name)?;
    let max = image_max(image, fisheye)?;
    if max <= 0.0 {
        return Err(Error::format(
            name,
            "no sky pixels: every pixel inside the fisheye circle is black",
        ));
    }
    let clip = NEAR_MAX * max;
    let bright = |x: usize, y: usize| {
        let p = image.get(x, y);
        p[0].max(p[1]).max(p[2]) as f64 >= clip && fisheye.pixel_direction(size, x, y).is_some()
    };
    let mut label = vec![false; size * size];
    let mut best: Vec<(usize, usize)> = Vec::new();
    let mut queue = VecDeque::new();
    for y in 0..size {
        for x in 0..size {
            if label[y * size + x] || !bright(x, y) {
                continue;
            }
            label[y * size + x] = true;
            queue.push_back((x, y));
            let mut blob = Vec::new();
            while let Some((cx, cy)) = queue.pop_front() {
                blob.push((cx, cy));
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let (nx, ny) = (cx as i64 + dx, cy as i64 + dy);
                        if nx < 0 || ny < 0 || nx >= size as i64 || ny >= size as i64 {
                            continue;
                        }
                        let (nx, ny) = (nx as usize, ny as usize);
                        if !label[ny * size + nx] && bright(nx, ny) {
                            label[ny * size + nx] = true;
                            queue.push_back((nx, ny));
                        }
                    }
                }
            }
            if blob.len() > best.len() {
                best = blob;
            }
        }
    }
    let mut v = [0.0; 3];
    for &(x, y) in &best {
        if let Some((theta, phi)) = fisheye.pixel_direction(size, x, y) {
            let u = preetham::unit_vector(theta, phi);
            v = [v[0] + u[0], v[1] + u[1], v[2] + u[2]];
        }
    }
    let norm = super::super::dot(v, v).sqrt();
    let zenith = if norm > 0.0 {
        (v[2] / norm).clamp(-1.0, 1.0).acos()
    } else {
        FRAC_PI_2
    };
    if zenith >= FRAC_PI_2 - 1e-6 {
        return Err(Error::format(
            name,
            "cannot find the sun: the brightest pixels are at the horizon; give `sun_zenith` \
             and `sun_azimuth`",
        ));
    }
    Ok(SunDetection {
        zenith,
        azimuth: v[1].atan2(v[0]),
        pixels: best.len(),
    })
}
