//! Where the camera samples of one pixel go within one pass: the one owner of the pixel
//! positions and of the BDF numbers at x₀ that every camera-side estimator reads (the BDPM mix,
//! `path`, `light`'s direct term, the first-hit layers' primary rays; the noise model's ρ and T_jitter
//! read the layout's strata from here too).
//!
//! [`Sampler::Independent`] gives every sample its own uniform numbers from the camera stream
//! keyed (seed, pass, pixel, sample), as before the sampler existed (same bits).
//!
//! [`Sampler::Stratified`] cuts the unit square into an n_x × n_y grid of N_B strata
//! ([`strata`]) and puts one uniformly jittered point in each: sample k gets stratum k of the
//! pixel, and of a second grid for the BDF direction at x₀ the stratum π(k) of a random
//! permutation π; the BDF's third number (the lobe choice of a mix) is stratified in one
//! dimension by another permutation (pbrt-v3's stratified sampler, with its padding by
//! permutation). Each pass and pixel draws its own layout from the stream keyed
//! (seed, [`Domain::PixelPattern`], pass, pixel), so passes stay independent and identically
//! distributed: the per-pass variance that the `noise` layer reports is still the variance of
//! one pass estimate, and partial renders merge exactly. Nothing is stratified across passes.
//!
//! Why a jittered grid rather than an Owen-scrambled Sobol set: N_B is any whole number (30 in
//! the Lambert box), which a grid takes exactly while a (0,2)-net needs a power of two; and the
//! grid's pair distribution is known in closed form, so the noise model's overlap factor ρ and
//! its pixel-integration term follow the layout exactly ([`bdpm_mis::overlap_factor_stratified`],
//! `predict.rs`).

use bdpm_geometry::{Domain, Rng};
use bdpm_settings::{RenderSettings, Sampler};

use crate::direct::DirectExtra;

/// Where in the pixel a camera sample goes: the jittered offset, or the centre.
#[inline]
fn pixel_offset(u: [f32; 2], jitter: bool) -> [f32; 2] {
    if jitter { u } else { [0.5, 0.5] }
}

/// The largest f32 below 1: a jittered coordinate (i + u)/n can round up to 1 in f32.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// The grid of strata (n_x, n_y) for `n` samples: n_x·n_y = n with n_x the largest divisor of
/// n that is at most √n (30 → 5 × 6, 16 → 4 × 4, a prime p → 1 × p). `n` = 0 is taken as 1.
pub(crate) fn strata(n: u32) -> (u32, u32) {
    let n = n.max(1);
    let mut nx = (n as f64).sqrt() as u32;
    while nx > 1 && !n.is_multiple_of(nx) {
        nx -= 1;
    }
    let nx = nx.max(1);
    (nx, n / nx)
}

/// The pixel's strata under `settings` when its samples are stratified over the pixel
/// (stratified sampler with jitter), for the noise model's ρ and T_jitter; `None` when the
/// samples are independent or all at the centre.
pub(crate) fn pixel_strata(settings: &RenderSettings) -> Option<(u32, u32)> {
    (settings.sampler == Sampler::Stratified && settings.pixel_jitter).then(|| strata(settings.spp))
}

/// The grid of the BDF direction's strata at x₀ when the sampler stratifies it (the
/// stratified sampler, with or without pixel jitter), for the noise model's T1.
pub(crate) fn direction_strata(settings: &RenderSettings) -> Option<(u32, u32)> {
    (settings.sampler == Sampler::Stratified).then(|| strata(settings.spp))
}

/// A cell of `grid` drawn uniformly from `rng`, for estimators of a stratified layout's
/// variance (pairs of points in one random cell).
pub(crate) fn random_cell((nx, ny): (u32, u32), rng: &mut Rng) -> (u32, u32) {
    let n = nx as u64 * ny as u64;
    let c = ((rng.next_u64() as u128 * n as u128) >> 64) as u32;
    (c % nx, c / nx)
}

/// A uniform point of cell `(i, j)` of `grid`, from two uniforms.
#[inline]
pub(crate) fn in_cell((i, j): (u32, u32), (nx, ny): (u32, u32), u: [f32; 2]) -> [f32; 2] {
    jittered(i, nx, j, ny, u)
}

/// One camera sample: its random stream (for every number the layout does not fix), its
/// position in the pixel, and the BDF numbers at x₀ if the layout fixes them.
pub(crate) struct CameraSample {
    /// The sample's own stream, keyed (seed, camera, pass, pixel, sample).
    pub(crate) rng: Rng,
    /// Offset in the pixel, each coordinate in [0, 1) (the centre without jitter).
    pub(crate) offset: [f32; 2],
    /// The three numbers of the BDF sample at x₀ (`None`: drawn from `rng`).
    pub(crate) bdf: Option<[f32; 3]>,
}

/// The layout of one pixel's samples in one pass, refilled pixel after pixel (the buffers are
/// reused, so a row allocates once).
pub(crate) struct PixelSamples {
    sampler: Sampler,
    jitter: bool,
    seed: u64,
    spp: u32,
    grid: (u32, u32),
    pass: u32,
    pixel: u64,
    positions: Vec<[f32; 2]>,
    directions: Vec<[f32; 2]>,
    lobe: Vec<f32>,
}

impl PixelSamples {
    /// The layout of `settings` (sampler, N_B, jitter, seed), not yet placed on a pixel.
    pub(crate) fn new(settings: &RenderSettings) -> PixelSamples {
        PixelSamples {
            sampler: settings.sampler,
            jitter: settings.pixel_jitter,
            seed: settings.seed,
            spp: settings.spp,
            grid: strata(settings.spp),
            pass: 0,
            pixel: 0,
            positions: Vec::new(),
            directions: Vec::new(),
            lobe: Vec::new(),
        }
    }

    /// Places the layout on `pixel` (row-major index) of pass `pass`.
    pub(crate) fn start(&mut self, pass: u32, pixel: u64) {
        self.pass = pass;
        self.pixel = pixel;
        if self.sampler == Sampler::Independent {
            return;
        }
        let n = self.spp as usize;
        let mut rng = Rng::new(self.seed, Domain::PixelPattern, [pass as u64, pixel, 0]);
        // Cells in raster order (sample k takes pixel cell k), then the direction's points
        // and the lobe numbers shuffled: a random pairing of the three stratifications.
        fill_grid(&mut self.positions, self.grid, &mut rng);
        fill_grid(&mut self.directions, self.grid, &mut rng);
        shuffle(&mut self.directions, &mut rng);
        let inv_n = 1.0 / n as f32;
        self.lobe.clear();
        for k in (0..n).step_by(2) {
            let u = two_uniforms(&mut rng);
            for (c, u) in (k..n.min(k + 2)).zip(u) {
                self.lobe
                    .push(((c as f32 + u) * inv_n).min(ONE_MINUS_EPSILON));
            }
        }
        shuffle(&mut self.lobe, &mut rng);
    }

    /// Sample `k` (< N_B) of the pixel and pass given to [`Self::start`].
    #[inline]
    pub(crate) fn sample(&self, k: u32) -> CameraSample {
        let mut rng = Rng::new(
            self.seed,
            Domain::Camera,
            [self.pass as u64, self.pixel, k as u64],
        );
        // Drawn whatever the layout, so the rest of the stream (roulette, later bounces) is the
        // same numbers under either sampler and without jitter.
        let uniform = rng.uniform2();
        match self.sampler {
            Sampler::Independent => CameraSample {
                offset: pixel_offset(uniform, self.jitter),
                rng,
                bdf: None,
            },
            _ => {
                let k = k as usize;
                let [u, v] = self.directions[k];
                CameraSample {
                    offset: pixel_offset(self.positions[k], self.jitter),
                    rng,
                    bdf: Some([self.lobe[k], u, v]),
                }
            }
        }
    }
}

impl PixelSamples {
    /// The part of the pixel that sample `k` (< N_B) is uniform over: (its corner, its size),
    /// offsets in the pixel. Its stratum under the stratified sampler, else the whole pixel.
    fn region(&self, k: u32) -> ([f32; 2], [f32; 2]) {
        match self.sampler {
            Sampler::Independent => ([0.0, 0.0], [1.0, 1.0]),
            _ => {
                let (nx, ny) = self.grid;
                let (sx, sy) = (1.0 / nx as f32, 1.0 / ny as f32);
                ([(k % nx) as f32 * sx, (k / nx) as f32 * sy], [sx, sy])
            }
        }
    }

    /// The further direct-light points of sample `k` (< N_B) of pixel (`x`, `y`) when the
    /// pixel takes `m` > 1 direct-light samples per camera sample (`direct_boost`): m − 1
    /// points uniform over the sample's own region, from the stream keyed (seed,
    /// `DirectSamples`, pass, pixel, k). `None` for m ≤ 1.
    pub(crate) fn direct_extra(&self, k: u32, (x, y): (u32, u32), m: u32) -> Option<DirectExtra> {
        (m > 1).then(|| {
            let (corner, size) = self.region(k);
            DirectExtra {
                count: m - 1,
                corner: [x as f32 + corner[0], y as f32 + corner[1]],
                size,
                rng: Rng::new(
                    self.seed,
                    Domain::DirectSamples,
                    [self.pass as u64, self.pixel, k as u64],
                ),
            }
        })
    }
}

/// A uniform point of cell (i, j) of an nx × ny grid of the unit square.
#[inline]
fn jittered(i: u32, nx: u32, j: u32, ny: u32, [u, v]: [f32; 2]) -> [f32; 2] {
    [
        ((i as f32 + u) / nx as f32).min(ONE_MINUS_EPSILON),
        ((j as f32 + v) / ny as f32).min(ONE_MINUS_EPSILON),
    ]
}

/// Two uniforms in [0, 1) with 24 bits each from one 64-bit output (the layout draws a few
/// numbers per sample; one generator step for two of them halves its cost).
#[inline]
fn two_uniforms(rng: &mut Rng) -> [f32; 2] {
    const SCALE: f32 = 1.0 / 16_777_216.0;
    let x = rng.next_u64();
    [
        (x >> 40) as f32 * SCALE,
        ((x >> 8) & 0xff_ffff) as f32 * SCALE,
    ]
}

/// One uniform point in each cell of `grid`, cells in raster order, into `out`.
fn fill_grid(out: &mut Vec<[f32; 2]>, (nx, ny): (u32, u32), rng: &mut Rng) {
    let (sx, sy) = (1.0 / nx as f32, 1.0 / ny as f32);
    out.clear();
    for j in 0..ny {
        for i in 0..nx {
            let [u, v] = two_uniforms(rng);
            out.push([
                ((i as f32 + u) * sx).min(ONE_MINUS_EPSILON),
                ((j as f32 + v) * sy).min(ONE_MINUS_EPSILON),
            ]);
        }
    }
}

/// Shuffles `items` uniformly (Fisher–Yates; each bounded integer by Lemire's multiply-shift
/// from 32 random bits, whose bias of at most n/2³² is far below anything a render sees).
fn shuffle<T>(items: &mut [T], rng: &mut Rng) {
    let mut bits = 0u64;
    for (step, i) in (1..items.len()).rev().enumerate() {
        if step % 2 == 0 {
            bits = rng.next_u64();
        } else {
            bits <<= 32;
        }
        let j = (((bits >> 32) * (i as u64 + 1)) >> 32) as usize;
        items.swap(i, j);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(sampler: Sampler, spp: u32) -> RenderSettings {
        RenderSettings {
            sampler,
            spp,
            ..RenderSettings::default()
        }
    }

    #[test]
    fn strata_factor_the_sample_count() {
        assert_eq!(strata(30), (5, 6));
        assert_eq!(strata(16), (4, 4));
        assert_eq!(strata(10), (2, 5));
        assert_eq!(strata(7), (1, 7));
        assert_eq!(strata(1), (1, 1));
        assert_eq!(strata(0), (1, 1));
        for n in 1..200 {
            let (nx, ny) = strata(n);
            assert_eq!(nx * ny, n);
            assert!(nx <= ny);
        }
    }

    /// Every stratum of the pixel and of the direction's grid holds exactly one sample, and the
    /// lobe numbers one per 1/N_B interval: the property the noise model's formulas assume.
    #[test]
    fn each_stratum_holds_one_sample() {
        for spp in [1, 2, 7, 10, 30, 64] {
            let s = settings(Sampler::Stratified, spp);
            let (nx, ny) = strata(spp);
            let mut p = PixelSamples::new(&s);
            for (pass, pixel) in [(0, 0), (3, 12345)] {
                p.start(pass, pixel);
                let mut pix = vec![0; spp as usize];
                let mut dir = vec![0; spp as usize];
                let mut lobe = vec![0; spp as usize];
                for k in 0..spp {
                    let c = p.sample(k);
                    let [x, y] = c.offset;
                    let cell = |x: f32, y: f32| {
                        (y * ny as f32) as usize * nx as usize + (x * nx as f32) as usize
                    };
                    assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
                    assert_eq!(cell(x, y), k as usize, "sample k sits in pixel stratum k");
                    pix[cell(x, y)] += 1;
                    let [l, u, v] = c.bdf.unwrap();
                    assert!([l, u, v].iter().all(|c| (0.0..1.0).contains(c)));
                    dir[cell(u, v)] += 1;
                    lobe[(l * spp as f32) as usize] += 1;
                }
                assert!(pix.iter().chain(&dir).chain(&lobe).all(|&c| c == 1));
            }
        }
    }

    /// The independent layout is the camera stream's first two numbers, as before the sampler.
    #[test]
    fn the_independent_layout_is_the_camera_stream() {
        let s = settings(Sampler::Independent, 5);
        let mut p = PixelSamples::new(&s);
        p.start(2, 99);
        for k in 0..5 {
            let c = p.sample(k);
            let mut rng = Rng::new(s.seed, Domain::Camera, [2, 99, k as u64]);
            assert_eq!(c.offset, rng.uniform2());
            assert!(c.bdf.is_none());
            assert_eq!(c.rng.clone().next_u64(), rng.next_u64());
        }
    }

    /// Each coordinate of a stratified layout is uniform over [0, 1) across layouts (a χ²-free
    /// check: the mean over many pixels and passes, within 5 standard errors of ½), and two
    /// passes of one pixel differ.
    #[test]
    fn layouts_are_uniform_and_differ_between_passes() {
        let s = settings(Sampler::Stratified, 6);
        let mut p = PixelSamples::new(&s);
        let (mut sum, mut count) = ([0.0f64; 5], 0.0);
        for pixel in 0..4000 {
            p.start(1, pixel);
            // Sample 0 alone: its pixel stratum is fixed, its direction stratum random.
            let c = p.sample(0);
            let [l, u, v] = c.bdf.unwrap();
            for (acc, x) in sum.iter_mut().zip([c.offset[0], c.offset[1], l, u, v]) {
                *acc += x as f64;
            }
            count += 1.0;
        }
        let (nx, ny) = strata(6);
        // Sample 0 lies in the first column and row of the pixel grid.
        let expected = [0.5 / nx as f64, 0.5 / ny as f64, 0.5, 0.5, 0.5];
        let se = (1.0f64 / 12.0 / count).sqrt();
        for (m, e) in sum.iter().map(|s| s / count).zip(expected) {
            assert!((m - e).abs() < 5.0 * se, "mean {m} against {e}");
        }
        p.start(0, 7);
        let a = p.sample(3).offset;
        p.start(1, 7);
        assert_ne!(a, p.sample(3).offset);
    }
}
