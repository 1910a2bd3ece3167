use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::Rng as _;

/// Which part of the renderer a random stream belongs to. Streams of different domains never
/// coincide, so e.g. the radiance cache's photons are independent of the rendered photons.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u64)]
pub enum Domain {
    /// Camera samples of a render pass.
    Camera = 1,
    /// Photons of a render pass.
    Photon = 2,
    /// Photons of the radiance-cache pre-pass.
    CachePhoton = 3,
    /// Backward rays of the per-pixel A/B pre-pass.
    PixelTable = 4,
    /// Anything else (tests, tools).
    Other = 5,
    /// The per-pass layout of a pixel's camera samples (the stratified sampler's strata and
    /// permutations), apart from each sample's own camera stream.
    PixelPattern = 6,
    /// The further direct-light points of a camera sample (`direct_boost`), apart from its
    /// own camera stream so that the rest of the sample is the same numbers with or without.
    DirectSamples = 7,
}

/// A deterministic random stream: a PCG (128-bit MCG, XSL-RR output) whose state is a hash of
/// (seed, domain, keys). Same keys, same numbers, on any thread.
#[derive(Clone, Debug)]
pub struct Rng(Pcg64Mcg);

/// SplitMix64's finaliser: a bijective 64-bit mix with full avalanche.
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Rng {
    /// The stream for `seed`, `domain` and up to three integer keys (e.g. pass, pixel, sample).
    #[inline]
    pub fn new(seed: u64, domain: Domain, keys: [u64; 3]) -> Rng {
        let mut h = mix64(seed ^ 0x9e37_79b9_7f4a_7c15);
        h = mix64(h ^ (domain as u64).wrapping_mul(0xd6e8_feb8_6659_fd93));
        let mut lo = h;
        for (i, k) in keys.iter().enumerate() {
            lo = mix64(lo ^ k.wrapping_add(0x9e37_79b9_7f4a_7c15u64.wrapping_mul(i as u64 + 1)));
        }
        let hi = mix64(lo ^ 0x2545_f491_4f6c_dd1d);
        Rng(Pcg64Mcg::new(((hi as u128) << 64) | lo as u128))
    }

    /// A uniform `f32` in [0, 1) with 24 random bits.
    #[inline]
    pub fn uniform(&mut self) -> f32 {
        (self.0.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// A uniform `f64` in [0, 1) with 53 random bits.
    #[inline]
    pub fn uniform_f64(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }

    /// Two uniforms in [0, 1).
    #[inline]
    pub fn uniform2(&mut self) -> [f32; 2] {
        [self.uniform(), self.uniform()]
    }

    /// Three uniforms in [0, 1).
    #[inline]
    pub fn uniform3(&mut self) -> [f32; 3] {
        [self.uniform(), self.uniform(), self.uniform()]
    }

    /// A raw 64-bit output.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0.next_u64()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_pure_functions_of_their_keys() {
        let mut a = Rng::new(7, Domain::Camera, [1, 2, 3]);
        let mut b = Rng::new(7, Domain::Camera, [1, 2, 3]);
        for _ in 0..100 {
            assert_eq!(a.next_u64(), b.next_u64());
        }
        let first = |seed, d, k| Rng::new(seed, d, k).next_u64();
        let base = first(7, Domain::Camera, [1, 2, 3]);
        assert_ne!(base, first(8, Domain::Camera, [1, 2, 3]));
        assert_ne!(base, first(7, Domain::Photon, [1, 2, 3]));
        assert_ne!(base, first(7, Domain::Camera, [2, 1, 3]));
        assert_ne!(base, first(7, Domain::Camera, [1, 2, 4]));
    }

    #[test]
    fn uniforms_are_in_range_and_unbiased() {
        let mut r = Rng::new(1, Domain::Other, [0; 3]);
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let u = r.uniform();
            assert!((0.0..1.0).contains(&u));
            sum += u as f64;
        }
        // Mean of U(0,1) is 1/2 with standard error sqrt(1/12/n) ≈ 6.5e-4; allow 5 SE.
        assert!((sum / n as f64 - 0.5).abs() < 5.0 * (1.0f64 / 12.0 / n as f64).sqrt());
    }
}
