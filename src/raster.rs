//! Plain CPU image buffers shared by loaders, pre-processing, the CPU reference and the GPU
//! pipeline. Rows are stored top to bottom, pixels left to right.

/// A 2D grid of `T`, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid<T> {
    width: usize,
    height: usize,
    data: Vec<T>,
}

/// Linear-light RGB, one `[r, g, b]` per pixel.
pub type RgbImage = Grid<[f32; 3]>;
/// Linear-light RGBA, one `[r, g, b, a]` per pixel.
pub type RgbaImage = Grid<[f32; 4]>;

impl RgbImage {
    /// The image with alpha 1 at every pixel, as brume's RGBA writers and uploads take it.
    pub fn opaque(&self) -> RgbaImage {
        self.map(|&[r, g, b]| [r, g, b, 1.0])
    }
}
/// A scalar map (range, depth, disparity, rate). Unknown values are NaN unless a loader
/// says otherwise.
pub type ScalarMap = Grid<f32>;

impl<T: Clone> Grid<T> {
    /// A grid filled with `value`.
    pub fn filled(width: usize, height: usize, value: T) -> Self {
        Grid {
            width,
            height,
            data: vec![value; width * height],
        }
    }
}

impl<T> Grid<T> {
    /// Wraps `data` (row-major, `width * height` items). Panics if the length is wrong,
    /// which is a programming error, not bad input.
    pub fn from_vec(width: usize, height: usize, data: Vec<T>) -> Self {
        assert_eq!(data.len(), width * height, "grid data length");
        Grid {
            width,
            height,
            data,
        }
    }

    /// Builds a grid by calling `f(x, y)` for every pixel.
    pub fn from_fn(width: usize, height: usize, mut f: impl FnMut(usize, usize) -> T) -> Self {
        let mut data = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                data.push(f(x, y));
            }
        }
        Grid {
            width,
            height,
            data,
        }
    }

    /// [`Grid::from_fn`] on every core (rayon): `f` must not depend on the order of the
    /// calls, and the result is the same as `from_fn`'s.
    pub fn par_from_fn(width: usize, height: usize, f: impl Fn(usize, usize) -> T + Sync) -> Self
    where
        T: Send,
    {
        use rayon::prelude::*;
        let len = width * height;
        let mut data = Vec::with_capacity(len);
        if len > 0 {
            // Row by row, in place: a pixel's column and row come from the loops, not from
            // dividing a flat index (two divisions a pixel cost more than most `f`s).
            let slots = &mut data.spare_capacity_mut()[..len];
            crate::parallel::run(|| {
                slots
                    .par_chunks_mut(width)
                    .enumerate()
                    .for_each(|(y, row)| {
                        for (x, slot) in row.iter_mut().enumerate() {
                            slot.write(f(x, y));
                        }
                    });
            });
            // SAFETY: the loops wrote every one of the first `len` slots (one chunk a row,
            // each slot of it); a panic in `f` is propagated by rayon before this line.
            unsafe { data.set_len(len) };
        }
        Grid {
            width,
            height,
            data,
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// True for a 0-pixel grid.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The pixel at column `x`, row `y` (row 0 at the top).
    pub fn get(&self, x: usize, y: usize) -> &T {
        &self.data[y * self.width + x]
    }

    /// Mutable pixel at column `x`, row `y`.
    pub fn get_mut(&mut self, x: usize, y: usize) -> &mut T {
        &mut self.data[y * self.width + x]
    }

    /// Reverses the order of the rows, in place.
    pub fn flip_rows(&mut self) {
        let (w, h) = (self.width, self.height);
        for y in 0..h / 2 {
            let (top, bottom) = self.data.split_at_mut((h - 1 - y) * w);
            top[y * w..(y + 1) * w].swap_with_slice(&mut bottom[..w]);
        }
    }

    /// All pixels, row-major.
    pub fn as_slice(&self) -> &[T] {
        &self.data
    }

    /// All pixels, row-major, mutable.
    pub fn as_mut_slice(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// Consumes the grid and returns its pixels.
    pub fn into_vec(self) -> Vec<T> {
        self.data
    }

    /// Applies `f` to every pixel.
    pub fn map<U>(&self, f: impl FnMut(&T) -> U) -> Grid<U> {
        Grid {
            width: self.width,
            height: self.height,
            data: self.data.iter().map(f).collect(),
        }
    }

    /// A copy of the `w x h` window whose top-left corner is `(x0, y0)`.
    pub fn crop(&self, x0: usize, y0: usize, w: usize, h: usize) -> Self
    where
        T: Clone,
    {
        assert!(
            x0 + w <= self.width && y0 + h <= self.height,
            "crop outside grid"
        );
        Grid::from_fn(w, h, |x, y| self.get(x0 + x, y0 + y).clone())
    }
}

/// How a photo's stored pixels are turned to show upright: its EXIF orientation (TIFF tag
/// 274), as viewers apply it. A phone held upright stores its sensor's landscape frame
/// with [`Orientation::Rotate90`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Orientation {
    /// Stored upright (EXIF 1, or no tag).
    #[default]
    Upright,
    /// Mirrored left to right (EXIF 2).
    MirrorLeftRight,
    /// Turned 180° (EXIF 3).
    Rotate180,
    /// Mirrored top to bottom (EXIF 4).
    MirrorTopBottom,
    /// Turned 90° clockwise, then mirrored left to right: a transpose (EXIF 5).
    Rotate90Mirror,
    /// Turned 90° clockwise (EXIF 6).
    Rotate90,
    /// Turned 90° anticlockwise, then mirrored left to right (EXIF 7).
    Rotate270Mirror,
    /// Turned 90° anticlockwise (EXIF 8).
    Rotate270,
}

impl Orientation {
    /// The eight, in the order of their EXIF values 1 to 8.
    const BY_EXIF: [Orientation; 8] = [
        Orientation::Upright,
        Orientation::MirrorLeftRight,
        Orientation::Rotate180,
        Orientation::MirrorTopBottom,
        Orientation::Rotate90Mirror,
        Orientation::Rotate90,
        Orientation::Rotate270Mirror,
        Orientation::Rotate270,
    ];

    /// The orientation of an EXIF value, 1 to 8; `None` for any other.
    pub fn from_exif(value: u16) -> Option<Orientation> {
        Self::BY_EXIF
            .get(usize::from(value).checked_sub(1)?)
            .copied()
    }

    /// Its EXIF value, 1 to 8.
    pub fn exif(self) -> u16 {
        let index = Self::BY_EXIF.iter().position(|&o| o == self);
        1 + index.expect("all eight are listed") as u16
    }

    /// Whether turning upright swaps width and height.
    pub fn swaps_axes(self) -> bool {
        use Orientation as O;
        matches!(
            self,
            O::Rotate90Mirror | O::Rotate90 | O::Rotate270Mirror | O::Rotate270
        )
    }

    /// The orientation that turns an upright grid back to how it was stored.
    pub fn inverse(self) -> Orientation {
        match self {
            Orientation::Rotate90 => Orientation::Rotate270,
            Orientation::Rotate270 => Orientation::Rotate90,
            other => other,
        }
    }

    /// In words, for messages: what a viewer does to the stored pixels.
    pub fn describe(self) -> &'static str {
        use Orientation as O;
        match self {
            O::Upright => "upright",
            O::MirrorLeftRight => "mirrored left to right",
            O::Rotate180 => "turned 180°",
            O::MirrorTopBottom => "mirrored top to bottom",
            O::Rotate90Mirror => "turned 90° clockwise and mirrored",
            O::Rotate90 => "turned 90° clockwise",
            O::Rotate270Mirror => "turned 90° anticlockwise and mirrored",
            O::Rotate270 => "turned 90° anticlockwise",
        }
    }

    /// The stored pixel `(x, y)` that shows at `(u, v)` of the upright grid, for a stored
    /// grid of `w x h`.
    fn stored_pixel(self, u: usize, v: usize, w: usize, h: usize) -> (usize, usize) {
        use Orientation as O;
        match self {
            O::Upright => (u, v),
            O::MirrorLeftRight => (w - 1 - u, v),
            O::Rotate180 => (w - 1 - u, h - 1 - v),
            O::MirrorTopBottom => (u, h - 1 - v),
            O::Rotate90Mirror => (v, u),
            O::Rotate90 => (v, h - 1 - u),
            O::Rotate270Mirror => (w - 1 - v, h - 1 - u),
            O::Rotate270 => (w - 1 - v, u),
        }
    }
}

impl<T: Clone + Send + Sync> Grid<T> {
    /// [`Grid::oriented`], taking the grid: no copy for [`Orientation::Upright`].
    pub fn into_oriented(self, orientation: Orientation) -> Self {
        match orientation {
            Orientation::Upright => self,
            o => self.oriented(o),
        }
    }

    /// The grid turned upright by `orientation` (a copy; the same pixels for
    /// [`Orientation::Upright`]).
    pub fn oriented(&self, orientation: Orientation) -> Self {
        let (w, h) = (self.width, self.height);
        let (uw, uh) = if orientation.swaps_axes() {
            (h, w)
        } else {
            (w, h)
        };
        Grid::par_from_fn(uw, uh, |u, v| {
            let (x, y) = orientation.stored_pixel(u, v, w, h);
            self.get(x, y).clone()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Row by row on the pool, the same grid as the serial loop: empty, one row, one
    /// column, sizes that split unevenly, and values that own memory.
    #[test]
    fn par_from_fn_is_from_fn() {
        for (w, h) in [
            (0, 0),
            (0, 3),
            (3, 0),
            (1, 1),
            (1, 7),
            (7, 1),
            (37, 5),
            (5, 37),
        ] {
            let f = |x: usize, y: usize| format!("{x},{y}");
            let serial = Grid::from_fn(w, h, f);
            let parallel = Grid::par_from_fn(w, h, f);
            assert_eq!(parallel, serial, "{w}x{h}");
        }
    }

    #[test]
    fn flip_rows_reverses_rows_of_odd_and_even_heights() {
        for h in [1, 2, 3, 4] {
            let mut g = Grid::from_fn(2, h, |x, y| 10 * y + x);
            g.flip_rows();
            let expected = Grid::from_fn(2, h, |x, y| 10 * (h - 1 - y) + x);
            assert_eq!(g.as_slice(), expected.as_slice(), "height {h}");
        }
    }

    /// Against the image crate's own `apply_orientation`, an independent implementation of
    /// the eight EXIF orientations, on a non-square grid of distinct values.
    #[test]
    fn oriented_matches_the_image_crates_exif_orientations() {
        let (w, h) = (4u32, 3u32);
        let value = |x: u32, y: u32| (10 * y + x + 1) as u16;
        let grid = Grid::from_fn(w as usize, h as usize, |x, y| value(x as u32, y as u32));
        for exif in 1..=8u8 {
            let mut reference =
                image::DynamicImage::ImageLuma16(image::ImageBuffer::from_fn(w, h, |x, y| {
                    image::Luma([value(x, y)])
                }));
            let theirs = image::metadata::Orientation::from_exif(exif).unwrap();
            reference.apply_orientation(theirs);
            let reference = reference.into_luma16();
            let ours = grid.oriented(Orientation::from_exif(u16::from(exif)).unwrap());
            assert_eq!(
                (ours.width() as u32, ours.height() as u32),
                reference.dimensions(),
                "EXIF {exif}"
            );
            assert_eq!(
                ours.as_slice(),
                reference.as_raw().as_slice(),
                "EXIF {exif}"
            );
            assert_eq!(
                Orientation::from_exif(u16::from(exif)).unwrap().exif(),
                u16::from(exif)
            );
            let back = ours.oriented(Orientation::from_exif(u16::from(exif)).unwrap().inverse());
            assert_eq!(back, grid, "EXIF {exif} turned back");
        }
        assert_eq!(Orientation::from_exif(0), None);
        assert_eq!(Orientation::from_exif(9), None);
    }
}
