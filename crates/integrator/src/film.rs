//! The film: per-pixel sums of the passes' estimates and of their squares (f64), from which the
//! mean and the per-pass variance of every pixel come ([`Film`], [`PassSums`] of any value).
use std::ops::{Add, Div, Mul, Sub};

use glam::DVec3;

/// A per-pixel value [`PassSums`] can accumulate: radiance per channel ([`DVec3`]) or a scalar
/// such as luminance (`f64`).
pub trait PassValue:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<f64, Output = Self>
{
    /// The zero value.
    const ZERO: Self;
    /// The value with negative parts raised to zero (rounding can make `Σx² − (Σx)²/K` negative).
    fn clamp_negative(self) -> Self;
}

impl PassValue for DVec3 {
    const ZERO: Self = DVec3::ZERO;
    fn clamp_negative(self) -> Self {
        self.max(DVec3::ZERO)
    }
}

impl PassValue for f64 {
    const ZERO: Self = 0.0;
    fn clamp_negative(self) -> Self {
        self.max(0.0)
    }
}

/// The one accumulator of per-pixel statistics: the sums of the pass estimates and of their
/// squares, in f64, so that the mean and the per-pass variance V (the preprint's noise
/// measure, method.md §3) are known after any number of passes. [`Film`] holds one over RGB
/// radiance; tools hold one over luminance.
#[derive(Clone, Debug, PartialEq)]
pub struct PassSums<T> {
    sum: Vec<T>,
    sum_sq: Vec<T>,
    passes: u32,
}

impl<T: PassValue> PassSums<T> {
    /// Empty sums for `pixels` pixels.
    pub fn new(pixels: usize) -> PassSums<T> {
        PassSums {
            sum: vec![T::ZERO; pixels],
            sum_sq: vec![T::ZERO; pixels],
            passes: 0,
        }
    }

    /// Adds one pass's per-pixel estimates (row-major; panics if the length differs).
    pub fn add_pass(&mut self, estimates: impl ExactSizeIterator<Item = T>) {
        assert_eq!(
            estimates.len(),
            self.sum.len(),
            "pass size differs from the accumulator"
        );
        for ((s, q), e) in self.sum.iter_mut().zip(&mut self.sum_sq).zip(estimates) {
            *s = *s + e;
            *q = *q + e * e;
        }
        self.passes += 1;
    }

    /// Number of passes added.
    pub fn passes(&self) -> u32 {
        self.passes
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.sum.len()
    }

    /// True for an accumulator of no pixels.
    pub fn is_empty(&self) -> bool {
        self.sum.is_empty()
    }

    /// Per-pixel sums of the estimates (the mean times the number of passes).
    pub fn sums(&self) -> &[T] {
        &self.sum
    }

    /// Mean per pixel over the passes (zero before the first).
    pub fn mean(&self) -> Vec<T> {
        let k = self.passes.max(1) as f64;
        self.sum.iter().map(|s| *s / k).collect()
    }

    /// Unbiased sample variance of one pass estimate per pixel (the square of the unit of the
    /// estimates); `None` with fewer than two passes (it is then unknown).
    pub fn pass_variance(&self) -> Option<Vec<T>> {
        if self.passes < 2 {
            return None;
        }
        let k = self.passes as f64;
        Some(
            self.sum
                .iter()
                .zip(&self.sum_sq)
                .map(|(s, q)| ((*q - *s * *s / k) / (k - 1.0)).clamp_negative())
                .collect(),
        )
    }
}

/// Accumulates per-pixel pass estimates of RGB radiance (a [`PassSums`] over [`DVec3`]) with
/// the image size and the count of dropped samples.
///
/// The size is private: the buffers are laid out for it (row-major).
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    sums: PassSums<DVec3>,
    dropped: u64,
}

impl Film {
    /// An empty film of `width` × `height` pixels.
    pub fn new(width: u32, height: u32) -> Film {
        Film {
            width,
            height,
            sums: PassSums::new(width as usize * height as usize),
            dropped: 0,
        }
    }

    /// Adds one pass: the per-pixel pass estimates (row-major, row 0 at the top, W·m⁻²·sr⁻¹)
    /// and the number of non-finite samples that the pass dropped.
    pub fn add_pass(&mut self, estimates: &[DVec3], dropped: u64) {
        self.sums.add_pass(estimates.iter().copied());
        self.dropped += dropped;
    }

    /// Image width, pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height, pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Number of passes accumulated.
    pub fn passes(&self) -> u32 {
        self.sums.passes()
    }

    /// Number of non-finite samples dropped over all passes.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Mean radiance per pixel over the passes, W·m⁻²·sr⁻¹.
    pub fn mean(&self) -> Vec<DVec3> {
        self.sums.mean()
    }

    /// Unbiased sample variance of one pass estimate per pixel, (W·m⁻²·sr⁻¹)²; zero with fewer
    /// than two passes (it is then unknown).
    pub fn pass_variance(&self) -> Vec<DVec3> {
        self.sums
            .pass_variance()
            .unwrap_or_else(|| vec![DVec3::ZERO; self.sums.len()])
    }

    /// Standard error of the mean per pixel: √(V/K), W·m⁻²·sr⁻¹.
    pub fn standard_error(&self) -> Vec<DVec3> {
        let k = self.passes().max(1) as f64;
        self.pass_variance()
            .into_iter()
            .map(|v| (v / k).map(f64::sqrt))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_variance_and_standard_error() {
        let mut f = Film::new(2, 1);
        for v in [1.0, 2.0, 3.0, 6.0] {
            f.add_pass(&[DVec3::splat(v), DVec3::new(v, 0.0, -v)], 0);
        }
        f.add_pass(&[DVec3::splat(3.0), DVec3::new(3.0, 0.0, -3.0)], 2);
        // Samples 1,2,3,6,3: mean 3, sample variance (4+1+0+9+0)/4 = 3.5.
        let m = f.mean();
        let v = f.pass_variance();
        assert_eq!(m[0], DVec3::splat(3.0));
        assert!((v[0] - DVec3::splat(3.5)).abs().max_element() < 1e-12);
        assert!((v[1] - DVec3::new(3.5, 0.0, 3.5)).abs().max_element() < 1e-12);
        assert!((f.standard_error()[0].x - (3.5f64 / 5.0).sqrt()).abs() < 1e-12);
        assert_eq!((f.passes(), f.dropped()), (5, 2));
    }
}
