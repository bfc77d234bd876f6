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
        let data = crate::parallel::run(|| {
            (0..width * height)
                .into_par_iter()
                .map(|i| f(i % width, i / width))
                .collect()
        });
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flip_rows_reverses_rows_of_odd_and_even_heights() {
        for h in [1, 2, 3, 4] {
            let mut g = Grid::from_fn(2, h, |x, y| 10 * y + x);
            g.flip_rows();
            let expected = Grid::from_fn(2, h, |x, y| 10 * (h - 1 - y) + x);
            assert_eq!(g.as_slice(), expected.as_slice(), "height {h}");
        }
    }
}
