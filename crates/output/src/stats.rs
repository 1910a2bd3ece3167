//! Statistics over passes: the one luminance and the one per-pixel accumulator of the
//! driver (the noise map and `--target-noise` of `bdpm render`, the error curves of `bdpm
//! study`). The film of the integrator keeps per-channel statistics; these are of the
//! luminance, which the per-channel ones cannot give (they lack the covariances between
//! channels).
use bdpm_integrator::film::PassSums;
use glam::DVec3;

/// Rec. 709 luminance of a linear RGB value (same unit as the value, e.g. W·m⁻²·sr⁻¹).
pub fn luminance(c: DVec3) -> f64 {
    let [r, g, b] = bdpm_bdf::LUMINANCE_WEIGHTS;
    r * c.x + g * c.y + b * c.z
}

/// Mean over pixels of an image (e.g. one pass's estimates), per channel.
pub fn image_mean(pixels: &[DVec3]) -> [f64; 3] {
    let sum: DVec3 = pixels.iter().copied().sum();
    (sum / pixels.len().max(1) as f64).to_array()
}

/// Standard error of the mean of `samples` (per channel, e.g. the image means of the
/// passes), from their spread; 0 with fewer than two.
pub fn standard_error_of_mean(samples: &[[f64; 3]]) -> [f64; 3] {
    let n = samples.len() as f64;
    if samples.len() < 2 {
        return [0.0; 3];
    }
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mean = samples.iter().map(|s| s[c]).sum::<f64>() / n;
        let var = samples.iter().map(|s| (s[c] - mean).powi(2)).sum::<f64>() / (n - 1.0);
        *o = (var / n).sqrt();
    }
    out
}

/// Per-pixel statistics of the pass luminance: the integrator's one accumulator
/// ([`PassSums`]) over luminance instead of RGB.
#[derive(Clone, Debug)]
pub struct PixelStats {
    sums: PassSums<f64>,
}

impl PixelStats {
    /// Empty statistics for an image of `pixels` pixels.
    pub fn new(pixels: usize) -> PixelStats {
        PixelStats {
            sums: PassSums::new(pixels),
        }
    }

    /// Adds one pass's per-pixel estimates (row-major, W·m⁻²·sr⁻¹).
    pub fn add_pass(&mut self, estimates: &[DVec3]) {
        self.sums.add_pass(estimates.iter().map(|e| luminance(*e)));
    }

    /// Running mean luminance per pixel, W·m⁻²·sr⁻¹.
    pub fn mean(&self) -> Vec<f64> {
        self.sums.mean()
    }

    /// Unbiased per-pass variance V per pixel, (W·m⁻²·sr⁻¹)²; `None` before two passes.
    pub fn variance(&self) -> Option<Vec<f64>> {
        self.sums.pass_variance()
    }

    /// √V per pixel, W·m⁻²·sr⁻¹; zero with fewer than two passes (V unknown).
    pub fn noise(&self) -> Vec<f64> {
        match self.variance() {
            Some(v) => v.into_iter().map(f64::sqrt).collect(),
            None => vec![0.0; self.sums.len()],
        }
    }

    /// Mean over pixels with a non-zero mean of (standard error of the mean) / mean
    /// (dimensionless); `None` with fewer than two passes or an all-black image.
    pub fn mean_relative_stderr(&self) -> Option<f64> {
        let k = self.sums.passes() as f64;
        let (mut total, mut count) = (0.0, 0u64);
        for (s, var) in self.sums.sums().iter().zip(self.variance()?) {
            let mean = s / k;
            if mean > 0.0 {
                total += (var / k).sqrt() / mean;
                count += 1;
            }
        }
        (count > 0).then(|| total / count as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn luminance_of_white_is_one() {
        assert!((luminance(DVec3::ONE) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn mean_variance_and_relative_error() {
        let mut f = PixelStats::new(1);
        assert!(f.variance().is_none());
        assert_eq!(f.noise(), [0.0]);
        assert_eq!(f.mean_relative_stderr(), None);
        for v in [1.0, 2.0, 3.0, 6.0, 3.0] {
            f.add_pass(&[DVec3::splat(v)]);
        }
        assert!((f.mean()[0] - 3.0).abs() < 1e-12);
        assert!((f.variance().expect("5 passes")[0] - 3.5).abs() < 1e-12);
        let rse = f.mean_relative_stderr().expect("5 passes");
        assert!((rse - (3.5f64 / 5.0).sqrt() / 3.0).abs() < 1e-12);
    }
}
