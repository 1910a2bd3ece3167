use glam::DVec3;

/// Accumulates per-pixel pass estimates in f64: their sum and sum of squares, so that both
/// the mean and the per-pass variance V (the preprint's noise measure, method.md §3) are known.
#[derive(Clone, Debug, PartialEq)]
///
/// The size is private: the buffers and [`Film::index`] are laid out for it.
pub struct Film {
    width: u32,
    height: u32,
    sum: Vec<DVec3>,
    sum_sq: Vec<DVec3>,
    passes: u32,
    dropped: u64,
}

impl Film {
    /// An empty film of `width` × `height` pixels.
    pub fn new(width: u32, height: u32) -> Film {
        let n = width as usize * height as usize;
        Film {
            width,
            height,
            sum: vec![DVec3::ZERO; n],
            sum_sq: vec![DVec3::ZERO; n],
            passes: 0,
            dropped: 0,
        }
    }

    /// Adds one pass: the per-pixel pass estimates (row-major, row 0 at the top, W·m⁻²·sr⁻¹)
    /// and the number of non-finite samples that the pass dropped.
    pub fn add_pass(&mut self, estimates: &[DVec3], dropped: u64) {
        assert_eq!(
            estimates.len(),
            self.sum.len(),
            "pass size differs from the film"
        );
        for ((s, q), e) in self.sum.iter_mut().zip(&mut self.sum_sq).zip(estimates) {
            *s += *e;
            *q += *e * *e;
        }
        self.passes += 1;
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
        self.passes
    }

    /// Number of non-finite samples dropped over all passes.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Mean radiance per pixel over the passes, W·m⁻²·sr⁻¹.
    pub fn mean(&self) -> Vec<DVec3> {
        let k = self.passes.max(1) as f64;
        self.sum.iter().map(|s| *s / k).collect()
    }

    /// Unbiased sample variance of one pass estimate per pixel, (W·m⁻²·sr⁻¹)²; zero with fewer
    /// than two passes (it is then unknown).
    pub fn pass_variance(&self) -> Vec<DVec3> {
        if self.passes < 2 {
            return vec![DVec3::ZERO; self.sum.len()];
        }
        let k = self.passes as f64;
        self.sum
            .iter()
            .zip(&self.sum_sq)
            .map(|(s, q)| ((*q - *s * *s / k) / (k - 1.0)).max(DVec3::ZERO))
            .collect()
    }

    /// Standard error of the mean per pixel: √(V/K), W·m⁻²·sr⁻¹.
    pub fn standard_error(&self) -> Vec<DVec3> {
        let k = self.passes.max(1) as f64;
        self.pass_variance()
            .into_iter()
            .map(|v| (v / k).map(f64::sqrt))
            .collect()
    }

    /// Index of pixel (x, y) in the row-major buffers.
    pub fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
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
