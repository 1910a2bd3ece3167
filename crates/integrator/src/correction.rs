//! `corrected-balance` (method-notes.md, "corrected-balance"): the balance heuristic with a
//! factor c per pixel on BDD=1's density, learnt from data in the style of Hua, Grittmann and
//! Slusallek 2025 ("Correct your balance heuristic"), as a data-driven baseline for the
//! model-based weights.
//!
//! A pilot renders [`PILOT_PASSES`] passes of `balance` on its own random streams (seed
//! [`pilot_seed`]) and keeps, per pixel and for every candidate factor of [`CANDIDATES`], the
//! pass estimate that the candidate's weights would have given: every weighted contribution
//! knows `balance`'s w₁, and [`bdpm_mis::corrected_share`] turns it into the candidate's. The
//! squared pass estimates are the candidates' second moments; all candidates estimate the same
//! pixel value, so the smallest second moment is the smallest variance. One pass is a very
//! noisy score, so (as the paper's filtered variant) the second moments are box-filtered over a
//! neighbourhood before the best candidate is taken, and the chosen factors are filtered again.
//!
//! The render then weighs every path of the pixel with the pixel's factor, from both sides of
//! the mix, so the weights of a path still sum to one: unbiased for any factor. The pilot's
//! streams are not the render's, so the factors do not correlate with the render's noise.

use bdpm_mis::corrected_share;

/// The factors on BDD=1's density the pilot scores: 1 (`balance`) and powers of two and four
/// up to 64 either way, since which technique `balance` over-weights differs from pixel to
/// pixel.
pub const CANDIDATES: [f64; 9] = [1.0 / 64.0, 1.0 / 16.0, 0.25, 0.5, 1.0, 2.0, 4.0, 16.0, 64.0];

/// Passes of `balance` the pilot renders (the paper's filtered variant learns from one
/// iteration).
pub const PILOT_PASSES: u32 = 1;

/// The second moments' filter radius is the image's larger side over this (32 pixels at 256²,
/// the paper's); the factors' is half that. Measured at 256² on both Cornell boxes (1 pilot
/// pass, relV after 6–8 passes): /8 gave the lowest relV of /4, /8, /16, /32, /64 on the
/// Lambert box and within noise of the lowest on the glossy one; /64 was 44 % worse there.
const MOMENTS_RADIUS_DIVISOR: usize = 8;

/// Added to the render's seed for the pilot's streams: any non-zero offset keeps them apart
/// from the render's own (every stream is keyed by a hash of the seed).
const PILOT_SEED_OFFSET: u64 = 0x5eed_c0de_0000_0001;

/// The seed of the pilot of a render with seed `seed`.
pub fn pilot_seed(seed: u64) -> u64 {
    seed.wrapping_add(PILOT_SEED_OFFSET)
}

/// One value per candidate of [`CANDIDATES`]: a sample's (or pixel's) estimate under each
/// candidate's weights, luminance in W·m⁻²·sr⁻¹ (or a sum of squares of such).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct CandidateSums(pub(crate) [f64; CANDIDATES.len()]);

impl CandidateSums {
    /// Adds a weighted contribution of luminance `value` whose `balance` weight of BDD=1 is
    /// `w1`: BDD=1's part of the path when `bdd1`, else BDD=0's (weight 1 − w₁).
    #[inline]
    pub(crate) fn add(&mut self, value: f64, w1: f64, bdd1: bool) {
        for (sum, &c) in self.0.iter_mut().zip(&CANDIDATES) {
            let w = corrected_share(w1, c);
            *sum += value * if bdd1 { w } else { 1.0 - w };
        }
    }

    /// Adds `value` (an unweighted part, e.g. direct light at x₀) to every candidate.
    pub(crate) fn add_to_all(&mut self, value: f64) {
        for sum in &mut self.0 {
            *sum += value;
        }
    }

    /// Adds another set of values candidate by candidate.
    pub(crate) fn add_sums(&mut self, other: &CandidateSums) {
        for (a, b) in self.0.iter_mut().zip(&other.0) {
            *a += b;
        }
    }

    /// Adds the squares of another set's values, scaled by `scale`.
    pub(crate) fn add_squares(&mut self, other: &CandidateSums, scale: f64) {
        for (a, b) in self.0.iter_mut().zip(&other.0) {
            *a += b * b * scale;
        }
    }

    /// Multiplies every value by `k`.
    pub(crate) fn scaled(mut self, k: f64) -> CandidateSums {
        for v in &mut self.0 {
            *v *= k;
        }
        self
    }
}

/// The per-pixel factors of `corrected-balance`, row-major, frozen before rendering.
#[derive(Clone, Debug, PartialEq)]
pub struct Correction {
    width: u32,
    factors: Vec<f32>,
}

impl Correction {
    /// The factors chosen from per-pixel second moments `second` (one [`CandidateSums`] per
    /// pixel, row-major, `width` pixels a row): each candidate's second moments box-filtered
    /// over a neighbourhood of radius 1/8 of the image's larger side, the best candidate per pixel
    /// (1 where no candidate has a positive moment, e.g. where the camera sees nothing), and the
    /// factors filtered again over half that size.
    pub(crate) fn from_moments(width: u32, second: &[CandidateSums]) -> Correction {
        let w = width as usize;
        let h = second.len() / w.max(1);
        let moments_radius = (w.max(h) / MOMENTS_RADIUS_DIVISOR).max(1);
        let factor_radius = (moments_radius / 2).max(1);
        let filtered: Vec<Vec<f64>> = (0..CANDIDATES.len())
            .map(|k| {
                let image: Vec<f64> = second.iter().map(|m| m.0[k]).collect();
                box_filter(&image, w, h, moments_radius)
            })
            .collect();
        let chosen: Vec<f64> = (0..w * h)
            .map(|i| {
                let mut best = (f64::INFINITY, 1.0);
                for (k, &c) in CANDIDATES.iter().enumerate() {
                    let m = filtered[k][i];
                    if m > 0.0 && m < best.0 {
                        best = (m, c);
                    }
                }
                best.1
            })
            .collect();
        let factors = box_filter(&chosen, w, h, factor_radius)
            .into_iter()
            .map(|c| c as f32)
            .collect();
        Correction { width, factors }
    }

    /// The factor of pixel (x, y), dimensionless.
    pub fn get(&self, x: u32, y: u32) -> f64 {
        f64::from(self.factors[y as usize * self.width as usize + x as usize])
    }

    /// Every pixel's factor, row-major.
    pub fn factors(&self) -> &[f32] {
        &self.factors
    }

    /// Memory held, bytes.
    pub fn bytes(&self) -> u64 {
        (self.factors.len() * size_of::<f32>()) as u64
    }

    /// One line for the run report: the factors' spread.
    pub fn summary(&self) -> String {
        let mut sorted: Vec<f32> = self.factors.clone();
        sorted.sort_by(f32::total_cmp);
        let at = |q: f64| sorted[((sorted.len() - 1) as f64 * q).round() as usize];
        let below = self.factors.iter().filter(|&&c| c < 0.99).count();
        let above = self.factors.iter().filter(|&&c| c > 1.01).count();
        let share = |n: usize| 100.0 * n as f64 / self.factors.len().max(1) as f64;
        format!(
            "factor on BDD=1 per pixel from {PILOT_PASSES} pilot pass(es) of balance over {} candidates: \
             min {:.3}, median {:.3}, max {:.3}; {:.0}% of pixels below 1, {:.0}% above",
            CANDIDATES.len(),
            at(0.0),
            at(0.5),
            at(1.0),
            share(below),
            share(above)
        )
    }
}

/// A box filter of radius `r` pixels applied three times (close to a Gaussian of σ ≈ r), each
/// pass the mean over the part of the (2r + 1)² window inside the image.
fn box_filter(image: &[f64], w: usize, h: usize, r: usize) -> Vec<f64> {
    let mut out = image.to_vec();
    let mut tmp = vec![0.0; image.len()];
    for _ in 0..3 {
        for y in 0..h {
            blur_line(&out[y * w..(y + 1) * w], &mut tmp[y * w..(y + 1) * w], r);
        }
        let mut column = vec![0.0; h];
        let mut blurred = vec![0.0; h];
        for x in 0..w {
            for (y, c) in column.iter_mut().enumerate() {
                *c = tmp[y * w + x];
            }
            blur_line(&column, &mut blurred, r);
            for (y, b) in blurred.iter().enumerate() {
                out[y * w + x] = *b;
            }
        }
    }
    out
}

/// The running mean of radius `r` along one line, the window cut at the line's ends.
fn blur_line(line: &[f64], out: &mut [f64], r: usize) {
    let n = line.len();
    let mut prefix = vec![0.0; n + 1];
    for (i, v) in line.iter().enumerate() {
        prefix[i + 1] = prefix[i] + v;
    }
    for (i, o) in out.iter_mut().enumerate() {
        let lo = i.saturating_sub(r);
        let hi = (i + r + 1).min(n);
        *o = (prefix[hi] - prefix[lo]) / (hi - lo) as f64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_candidate_with_the_smallest_second_moment_is_chosen() {
        // A 40 × 20 image: candidate 2 (¼) best on the left half, candidate 7 (16) on the
        // right; far from the border the (filtered) factor is the candidate's.
        let (w, h) = (40usize, 20usize);
        let second: Vec<CandidateSums> = (0..w * h)
            .map(|i| {
                let best = if i % w < w / 2 { 2 } else { 7 };
                let mut m = CandidateSums([5.0; CANDIDATES.len()]);
                m.0[best] = 1.0;
                m
            })
            .collect();
        let c = Correction::from_moments(w as u32, &second);
        assert_eq!(c.get(2, 10), 0.25);
        assert_eq!(c.get(37, 3), 16.0);
        // Near the boundary the factor is between the two.
        let mid = c.get(20, 10);
        assert!(mid > 0.25 && mid < 16.0, "{mid}");
    }

    #[test]
    fn pixels_without_any_moment_keep_balance() {
        let second = vec![CandidateSums::default(); 8 * 8];
        let c = Correction::from_moments(8, &second);
        assert!(c.factors().iter().all(|&f| f == 1.0));
    }

    #[test]
    fn sums_follow_the_corrected_weights() {
        let mut s = CandidateSums::default();
        s.add(2.0, 0.5, true);
        s.add(4.0, 0.5, false);
        s.add_to_all(1.0);
        for (k, &c) in CANDIDATES.iter().enumerate() {
            let w = c / (c + 1.0);
            assert!((s.0[k] - (1.0 + 2.0 * w + 4.0 * (1.0 - w))).abs() < 1e-12);
        }
    }

    #[test]
    fn the_box_filter_keeps_constants_and_the_mean_of_a_spike() {
        let (w, h) = (9, 7);
        let flat = box_filter(&vec![3.0; w * h], w, h, 2);
        assert!(flat.iter().all(|v| (v - 3.0).abs() < 1e-12));
        let mut spike = vec![0.0; w * h];
        spike[3 * w + 4] = 1.0;
        let blurred = box_filter(&spike, w, h, 1);
        assert!(blurred.iter().all(|&v| v >= 0.0));
        assert!(blurred[3 * w + 4] < 1.0 && blurred[3 * w + 4] > 0.0);
    }
}
