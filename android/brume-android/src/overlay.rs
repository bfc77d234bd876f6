//! The per-pass GPU times on screen without a UI toolkit: every shape is a rectangle,
//! filled by `glScissor` + `glClear` (no program, no buffer, no GL object at all). Along
//! the bottom, one bar per frame with a segment per pass (the medium pass red, the
//! diffusion passes green, the composite blue), its length the pass's time on a scale
//! where the width is two 60 Hz frames, a white tick at one frame (16.7 ms); above it the
//! total in milliseconds in seven-segment digits.

use glow::HasContext;
use std::fmt::Write;

/// One frame at 60 Hz (ms).
pub const FRAME_BUDGET_MS: f64 = 1000.0 / 60.0;

/// A filled rectangle in framebuffer pixels (origin bottom-left, as GL's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    /// Left edge.
    pub x: i32,
    /// Bottom edge.
    pub y: i32,
    /// Width (> 0).
    pub width: i32,
    /// Height (> 0).
    pub height: i32,
    /// Colour as stored in the framebuffer.
    pub colour: [f32; 3],
}

const BACKGROUND: [f32; 3] = [0.08, 0.08, 0.08];
const MEDIUM: [f32; 3] = [0.9, 0.25, 0.2];
const DIFFUSE: [[f32; 3]; 2] = [[0.2, 0.75, 0.3], [0.1, 0.5, 0.2]];
const COMPOSITE: [f32; 3] = [0.25, 0.45, 0.95];
const TICK: [f32; 3] = [1.0, 1.0, 1.0];
const DIGIT: [f32; 3] = [0.95, 0.95, 0.95];

/// Segments a-g of the digits 0-9 (bit 0 = a … bit 6 = g).
const SEGMENTS: [u8; 10] = [0x3F, 0x06, 0x5B, 0x4F, 0x66, 0x6D, 0x7D, 0x07, 0x7F, 0x6F];

/// The overlay's shapes, laid out again each frame into buffers kept between frames.
#[derive(Debug, Default)]
pub struct Overlay {
    rects: Vec<Rect>,
    text: String,
}

impl Overlay {
    /// Lays out the bar of `pass_ms` and the digits of their sum for a `width x height`
    /// framebuffer.
    pub fn layout(&mut self, pass_ms: &[f64], (width, height): (i32, i32)) {
        self.rects.clear();
        let margin = (width / 60).max(8);
        let bar = (height / 90).max(12);
        let length = width - 2 * margin;
        if length <= 0 || height < 4 * bar {
            return;
        }
        let scale = f64::from(length) / (2.0 * FRAME_BUDGET_MS);
        self.push(margin - 2, margin - 2, length + 4, bar + 4, BACKGROUND);
        let mut x = margin;
        for (i, &ms) in pass_ms.iter().enumerate() {
            let end = margin + length;
            let w = ((ms.max(0.0) * scale).round() as i32).max(1).min(end - x);
            if w <= 0 {
                break;
            }
            self.push(x, margin, w, bar, pass_colour(i, pass_ms.len()));
            x += w;
        }
        let tick = margin + (FRAME_BUDGET_MS * scale).round() as i32;
        self.push(tick - 1, margin - bar / 2, 2, 2 * bar, TICK);
        let total: f64 = pass_ms.iter().sum();
        self.text.clear();
        let _ = write!(self.text, "{total:.1}");
        let text = std::mem::take(&mut self.text);
        self.digits(&text, margin, margin + 2 * bar, 2 * bar);
        self.text = text;
    }

    /// The shapes of the last layout.
    pub fn rects(&self) -> &[Rect] {
        &self.rects
    }

    /// Fills the shapes in the bound draw framebuffer; leaves `SCISSOR_TEST` disabled and
    /// the clear colour changed.
    pub fn draw(&self, gl: &glow::Context) {
        // SAFETY: state setters and clears on the current context.
        unsafe {
            gl.enable(glow::SCISSOR_TEST);
            for r in &self.rects {
                gl.scissor(r.x, r.y, r.width, r.height);
                gl.clear_color(r.colour[0], r.colour[1], r.colour[2], 1.0);
                gl.clear(glow::COLOR_BUFFER_BIT);
            }
            gl.disable(glow::SCISSOR_TEST);
        }
    }

    fn push(&mut self, x: i32, y: i32, width: i32, height: i32, colour: [f32; 3]) {
        if width > 0 && height > 0 {
            self.rects.push(Rect {
                x,
                y,
                width,
                height,
                colour,
            });
        }
    }

    /// Seven-segment digits and points of `text`, `height` tall, from (x, y) (bottom-left).
    fn digits(&mut self, text: &str, mut x: i32, y: i32, height: i32) {
        let width = height / 2;
        let t = (height / 8).max(2);
        let half = height / 2;
        for c in text.chars() {
            match c.to_digit(10) {
                Some(d) => {
                    let segments = [
                        (x, y + height - t, width, t),      // a
                        (x + width - t, y + half, t, half), // b
                        (x + width - t, y, t, half),        // c
                        (x, y, width, t),                   // d
                        (x, y, t, half),                    // e
                        (x, y + half, t, half),             // f
                        (x, y + half - t / 2, width, t),    // g
                    ];
                    for (bit, &(sx, sy, sw, sh)) in segments.iter().enumerate() {
                        if SEGMENTS[d as usize] & (1 << bit) != 0 {
                            self.push(sx, sy, sw, sh, DIGIT);
                        }
                    }
                    x += width + 2 * t;
                }
                None if c == '.' => {
                    self.push(x, y, t, t, DIGIT);
                    x += 3 * t;
                }
                None => x += width + 2 * t,
            }
        }
    }
}

/// The colour of pass `i` of `n`: the medium pass first, the composite last, diffusion
/// passes between (one pass alone, as the engine fog's, is the medium's colour).
fn pass_colour(i: usize, n: usize) -> [f32; 3] {
    if i == 0 {
        MEDIUM
    } else if i + 1 == n {
        COMPOSITE
    } else {
        DIFFUSE[i % 2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn segments_of(overlay: &Overlay) -> usize {
        overlay.rects().iter().filter(|r| r.colour == DIGIT).count()
    }

    #[test]
    fn each_pass_is_a_segment_proportional_to_its_time() {
        let mut o = Overlay::default();
        let viewport = (1080, 2400);
        o.layout(&[2.0, 1.0, 1.0, 0.5], viewport);
        let bars: Vec<&Rect> = o
            .rects()
            .iter()
            .filter(|r| [MEDIUM, DIFFUSE[0], DIFFUSE[1], COMPOSITE].contains(&r.colour))
            .collect();
        assert_eq!(bars.len(), 4);
        assert_eq!(bars[0].colour, MEDIUM);
        assert_eq!(bars[3].colour, COMPOSITE);
        // Side by side, lengths ∝ times: 2 ms is twice 1 ms (±1 px of rounding).
        assert_eq!(bars[1].x, bars[0].x + bars[0].width);
        assert!((bars[0].width - 2 * bars[1].width).abs() <= 1);
        // The tick sits at one frame, half of the bar's length.
        let tick = o.rects().iter().find(|r| r.colour == TICK).unwrap();
        let margin = 1080 / 60;
        assert_eq!(tick.x + 1, margin + (1080 - 2 * margin) / 2);
    }

    #[test]
    fn the_total_is_written_in_seven_segment_digits() {
        let mut o = Overlay::default();
        // 4.5 ms: "4" has 4 segments, "." one square, "5" five segments.
        o.layout(&[2.0, 2.5], (720, 1280));
        assert_eq!(segments_of(&o), 4 + 1 + 5);
        o.layout(&[8.0, 0.8], (720, 1280));
        // "8.8": 7 + 1 + 7.
        assert_eq!(segments_of(&o), 15);
        assert!(o.rects().iter().all(|r| r.width > 0 && r.height > 0));
    }

    #[test]
    fn long_frames_are_clipped_to_the_bar_and_tiny_screens_get_nothing() {
        let mut o = Overlay::default();
        o.layout(&[40.0, 40.0, 40.0], (600, 1000));
        let margin = 600 / 60;
        let end = 600 - margin;
        for r in o.rects().iter().filter(|r| r.colour != DIGIT) {
            assert!(r.x + r.width <= end + 2, "{r:?} beyond the bar");
        }
        o.layout(&[1.0], (10, 10));
        assert!(o.rects().is_empty());
    }
}
