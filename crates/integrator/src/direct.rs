//! How many direct-light samples the camera samples of each pixel take
//! ([`RenderSettings::direct_boost`]).
//!
//! Direct light L₀(x₀) is exact for a given x₀ (one shadow ray per point light), so its only
//! noise is pixel integration: where x₀ is one of the pixel's points, L₀ varies with it. That
//! is small almost everywhere, since stratification takes most of it, but not where a surface
//! lies close to a point light: on the Lambert box the ceiling above the light falls off as
//! 1/d² across each pixel's footprint (d = 6.8 cm, footprints of 1–2 cm), and its ~100
//! pixels, hundreds of times brighter than the image's mean, hold a quarter of the image's
//! per-pass variance (docs/results.md, "Direct light near a light"). There each camera sample of the BDPM mix,
//! and of the `light` reference's direct term (`path` is left as it is), also evaluates L₀
//! at M − 1 further uniform points of its own stratum and takes the mean of its M values:
//! that stratum's L₀ variance falls M-fold for M − 1 primary and shadow rays, no gathers.
//!
//! M per pixel is fixed before the passes from the scene alone: L₀'s luminance at four fixed
//! points of the pixel (the centres of its quarters; no random numbers) gives its spread s
//! over the pixel (their standard deviation, W·m⁻²·sr⁻¹), and M = ⌊s / (2·s_rms)⌋ clamped to
//! [1, M_max], with s_rms the root mean square of s over the image. In a scene with area
//! lights a 5 × 5 lattice with the pixel's corners replaces the four points, which miss half
//! the emitters' outlines, and the scale is 1·s_rms (`THRESHOLD_AREA`). There L₀ at a point
//! is itself an estimate (one light sample, at a glossy surface weighed against a BDF ray of
//! its own), so each probe draws its sample from a stream fixed by the pixel and the spread
//! takes in the estimate's own variance: the light's reflection in a glossy wall, where the
//! estimate is noisy though L₀ varies little over the pixel, is boosted too. M ∝ s is the
//! allocation that minimises Σ Jₚ/Mₚ for a given number of samples Σ Mₚ when a pixel's L₀ noise is
//! Jₚ ∝ sₚ²; the scale 2·s_rms keeps the cost bounded whatever the scene: M > 1 needs
//! s ≥ 4·s_rms, which at most P/16 of the P pixels have, and Σ (M − 1) ≤ Σ s/(2·s_rms) ≤ P/2
//! (Cauchy–Schwarz), so at most half as many more direct-light samples as camera samples,
//! each a primary and a shadow ray. On the Lambert box 102 pixels take more than one, and
//! the image 0.9 % more direct-light samples. Since M depends on nothing random, every pass
//! stays an unbiased, independent, identically distributed estimate, and the per-pass
//! variance layer stays exact.

use bdpm_bdf::{Transport, luminance};
use bdpm_geometry::{Domain, Rng};
use bdpm_scene::{Scene, Shading};
use bdpm_settings::RenderSettings;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// The further direct-light points of one camera sample (crate::direct): `count` uniform
/// points of the region `corner + [0, size)` of the image (pixels), which is the part of the
/// pixel that the sample itself is uniform over, from their own stream.
#[derive(Clone, Debug)]
pub(crate) struct DirectExtra {
    pub(crate) count: u32,
    pub(crate) corner: [f32; 2],
    pub(crate) size: [f32; 2],
    pub(crate) rng: Rng,
}

impl DirectExtra {
    /// The mean of L₀ at x₀ over a camera sample's own point (`own`, W·m⁻²·sr⁻¹) and these
    /// further points, each a primary ray and shadow rays (none if it meets nothing).
    pub(crate) fn mean_with(&mut self, scene: &Scene, own: Vec3) -> DVec3 {
        let mut sum = own.as_dvec3();
        for _ in 0..self.count {
            let [a, b] = self.rng.uniform2();
            let (x, y) = (
                self.corner[0] + a * self.size[0],
                self.corner[1] + b * self.size[1],
            );
            let rng = &mut self.rng;
            sum += direct_through(scene, x, y, || rng.uniform()).as_dvec3();
        }
        sum / (self.count + 1) as f64
    }
}

/// L₀ at the first non-delta surface the camera ray through image point (`x`, `y`) (pixels)
/// meets, seen along that ray and through the mirrors and glass before it (their throughput
/// included; `uniform` chooses their branches, [`Scene::walk_to_non_delta`]), W·m⁻²·sr⁻¹: a
/// primary ray and shadow rays (0 if it meets nothing).
pub(crate) fn direct_through(
    scene: &Scene,
    x: f32,
    y: f32,
    mut uniform: impl FnMut() -> f32,
) -> Vec3 {
    let cam = scene.camera();
    let dir = cam.ray_direction(x, y);
    scene
        .walk_to_non_delta(cam.position(), dir, Transport::Radiance, &mut uniform)
        .map_or(Vec3::ZERO, |w| {
            let mut l0 = scene.direct(&w.sh, w.wo);
            if scene.has_emission() {
                l0 += area_estimate(scene, &w.sh, w.wo, &mut uniform);
            }
            if w.vertices == 0 { l0 } else { w.beta * l0 }
        })
}

/// One estimate of what area lights add to L₀ at `sh` seen along `wo` (W·m⁻²·sr⁻¹): the
/// radiance it emits and one light sample, which at a glossy surface is weighed by the power
/// heuristic against a BDF ray of its own whose hit on an emitter takes the complementary
/// weight, as at x₁ (`x1_weighs_bdf`). A glossy lobe narrower than the light's image makes
/// the light sample alone a rare event there: on scenes/cornell-box-glossy.toml the light's
/// reflection in the back wall held a fifth of the default mode's squared error at equal time
/// (docs/results.md, "Area lights: the light's reflections").
fn area_estimate(scene: &Scene, sh: &Shading, wo: Vec3, uniform: &mut impl FnMut() -> f32) -> Vec3 {
    let mis = x1_weighs_bdf(scene, sh);
    let u = [uniform(), uniform(), uniform()];
    let mut l = emitted_and_area(scene, sh, wo, u, mis);
    if mis {
        let u = [uniform(), uniform(), uniform()];
        if let Some((c, _)) = scene.emitter_hit_by_bdf(sh, wo, u) {
            l += c;
        }
    }
    l
}

/// What area lights add to L₀ at a camera path's x₀ (`sh`, seen along `wo`), W·m⁻²·sr⁻¹: the
/// radiance x₀ emits itself and one light sample of the emitters, weighted by the power
/// heuristic against a BDF ray from x₀ with `mis` (the caller then adds that ray's hits on
/// emitters), else light sampling alone (docs/method-notes.md, "Area lights: MIS at x₀").
pub(crate) fn emitted_and_area(
    scene: &Scene,
    sh: &Shading,
    wo: Vec3,
    u: [f32; 3],
    mis: bool,
) -> Vec3 {
    scene.emitted(sh.prim, sh.bary, wo) + scene.direct_area(sh, wo, u, mis)
}

/// Whether an area-light sample at `sh1` is weighed against a BDF ray (a glossy surface) or
/// taken alone (a Lambert one): at x₁ (`area_samples_at_x1` in crate::bdpm, and `predict`'s
/// model of it) and at the further direct-light points of a glossy x₀ ([`area_estimate`]).
pub(crate) fn x1_weighs_bdf(scene: &Scene, sh1: &Shading) -> bool {
    !scene.bdf_at(sh1).is_lambert()
}

/// The four fixed points of a pixel where L₀ is probed (offsets in the pixel, [0, 1)²).
const PROBES: [[f32; 2]; 4] = [[0.25, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]];

/// M = ⌊s / (THRESHOLD·s_rms)⌋: a pixel takes more than one direct-light sample per camera
/// sample when its spread of L₀ is at least twice this many times the image's RMS spread.
pub(crate) const THRESHOLD: f64 = 2.0;

/// [`THRESHOLD`] in a scene with area lights. Their pixels of large spread are the emitters'
/// outlines seen directly, where L₀ jumps by Le and the camera sample's other estimates
/// (merges, the cache) are cheap beside it; halving the threshold doubles M there. Measured on
/// scenes/cornell-box.toml (docs/results.md, "Area lights: the light's outline"): per-pass
/// ΣV 0.89× that of [`THRESHOLD`] for 0.006 more direct-light samples per camera sample. The
/// bounds of the module's text become at most P/4 pixels with M > 1 and Σ (M − 1) ≤ P.
/// Point-light scenes keep [`THRESHOLD`] and so their image bits.
pub(crate) const THRESHOLD_AREA: f64 = 1.0;

/// Direct-light samples per camera sample, per pixel: the [`SampleCounts`] M of the module's
/// rule.
#[derive(Clone, Debug, PartialEq)]
pub struct DirectSamples(SampleCounts);

impl DirectSamples {
    /// The allocation for `scene` under `settings`: M per pixel as in the module's rule, or
    /// `None` when nothing would take more than one (M_max = 1, no pixel jitter, or no pixel
    /// above the threshold).
    pub(crate) fn allocate(scene: &Scene, settings: &RenderSettings) -> Option<DirectSamples> {
        if settings.direct_boost <= 1 || !settings.pixel_jitter {
            return None;
        }
        let threshold = if scene.has_emission() {
            THRESHOLD_AREA
        } else {
            THRESHOLD
        };
        let counts =
            SampleCounts::from_spreads(settings, threshold, settings.direct_boost, |x, y| {
                spread(scene, x, y)
            })?;
        Some(DirectSamples(counts))
    }
}

impl std::ops::Deref for DirectSamples {
    type Target = SampleCounts;

    fn deref(&self) -> &SampleCounts {
        &self.0
    }
}

/// A count of samples per camera sample for each pixel of the image, every one in [1, 255]:
/// what a boost of some term of a camera sample (`direct_boost`'s direct light, x₁'s one-bounce
/// paths) allocates, fixed before the passes.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleCounts {
    width: u32,
    /// The count per pixel, row-major.
    m: Vec<u8>,
}

impl SampleCounts {
    /// The counts of [`allocation`] from the spread of each pixel (x, y) of the image of
    /// `settings` (`spread`, computed in parallel), or `None` when every count is 1.
    pub(crate) fn from_spreads(
        settings: &RenderSettings,
        threshold: f64,
        most: u32,
        spread: impl Fn(u32, u32) -> f64 + Sync,
    ) -> Option<SampleCounts> {
        let (w, h) = (settings.width, settings.height);
        let spreads: Vec<f64> = (0..h)
            .into_par_iter()
            .flat_map_iter(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| spread(x, y))
            .collect();
        let m = allocation(&spreads, most, threshold);
        m.iter()
            .any(|&m| m > 1)
            .then_some(SampleCounts { width: w, m })
    }

    /// The count of pixel (x, y).
    #[inline]
    pub fn at(&self, x: u32, y: u32) -> u32 {
        self.m[(y as usize) * (self.width as usize) + x as usize] as u32
    }

    /// Pixels whose count is more than 1.
    pub fn boosted(&self) -> usize {
        self.m.iter().filter(|&&m| m > 1).count()
    }

    /// Samples beyond one per camera sample, per camera sample of the image (mean of the
    /// count − 1 over the pixels).
    pub fn extra_per_sample(&self) -> f64 {
        self.m.iter().map(|&m| (m - 1) as f64).sum::<f64>() / self.m.len().max(1) as f64
    }

    /// The largest count of any pixel.
    pub fn largest(&self) -> u32 {
        self.m.iter().copied().max().unwrap_or(1) as u32
    }

    /// Bytes held.
    pub fn bytes(&self) -> u64 {
        self.m.len() as u64
    }
}

/// The standard deviation of L₀'s luminance over the probes of pixel (x, y), W·m⁻²·sr⁻¹ (a
/// probe that meets nothing counts as 0): the four [`PROBES`], or in a scene with area
/// lights the [`LATTICE`]² lattice of [`lattice_probes`].
fn spread(scene: &Scene, x: u32, y: u32) -> f64 {
    if scene.has_emission() {
        // An area light's sample is an estimate with a variance of its own, which the spread
        // takes in: every probe draws its light sample (and its branch through glass) from a
        // stream fixed by the pixel alone, so M still depends on the scene alone.
        let mut rng = Rng::new(0, Domain::DirectSamples, [u64::MAX, x as u64, y as u64]);
        return std_dev(lattice_probes().map(|[dx, dy]| {
            let l0 = direct_through(scene, x as f32 + dx, y as f32 + dy, || rng.uniform());
            luminance(l0) as f64
        }));
    }
    // A fixed branch through glass: the probes use no random numbers.
    std_dev(PROBES.map(|[dx, dy]: [f32; 2]| {
        luminance(direct_through(scene, x as f32 + dx, y as f32 + dy, || 0.5)) as f64
    }))
}

/// Probes per side of a pixel in a scene with area lights.
const LATTICE: usize = 5;

/// The [`LATTICE`]² points (i/(LATTICE − 1), j/(LATTICE − 1)) of a pixel, its corners and
/// edges included. An emitter seen directly makes L₀ jump by its Le across the emitter's
/// outline, and such a jump, where the outline crosses a pixel, is most of that pixel's L₀
/// spread; the four [`PROBES`] see it only when the outline passes between them (half the
/// pixels it crosses, measured on scenes/cornell-box.toml: 12 pixels boosted of the ~100 on
/// the light's outline). A straight outline that crosses a pixel separates its corners, so
/// the lattice sees every one, and its inner points weigh how much of the pixel lies on
/// either side (a sliver at the pixel's edge reads as a fifth of the points on one side, where
/// the jitter variance it causes is smaller still: the rule leans to boosting).
fn lattice_probes() -> [[f32; 2]; LATTICE * LATTICE] {
    let step = 1.0 / (LATTICE - 1) as f32;
    std::array::from_fn(|k| [(k % LATTICE) as f32 * step, (k / LATTICE) as f32 * step])
}

/// The standard deviation of `values` (population, not sample).
fn std_dev<const N: usize>(values: [f64; N]) -> f64 {
    let mean = values.iter().sum::<f64>() / N as f64;
    (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / N as f64).sqrt()
}

/// M per pixel from the pixels' spreads: ⌊s / (`threshold`·s_rms)⌋ clamped to [1, `most`]
/// (all 1 when every spread is 0 or a spread is not finite).
pub(crate) fn allocation(spreads: &[f64], most: u32, threshold: f64) -> Vec<u8> {
    let most = most.clamp(1, u8::MAX as u32) as f64;
    let mean_sq = spreads.iter().map(|s| s * s).sum::<f64>() / spreads.len().max(1) as f64;
    let scale = threshold * mean_sq.sqrt();
    if !(scale.is_finite() && scale > 0.0) {
        return vec![1; spreads.len()];
    }
    spreads
        .iter()
        .map(|s| (s / scale).floor().clamp(1.0, most) as u8)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_outliers_take_more_and_in_proportion() {
        // 1000 pixels of spread 1 and two of spread 100 and 300: s_rms = √((1000 + 10⁴ +
        // 9·10⁴)/1002) = 10.04, scale 20.08, so M = ⌊100/20.08⌋ = 4 and ⌊300/20.08⌋ = 14.
        let mut s = vec![1.0; 1000];
        s.push(100.0);
        s.push(300.0);
        let m = allocation(&s, 16, THRESHOLD);
        assert!(m[..1000].iter().all(|&m| m == 1));
        assert_eq!(&m[1000..], &[4, 14]);
        // Clamped to M_max.
        assert_eq!(&allocation(&s, 8, THRESHOLD)[1000..], &[4, 8]);
        assert!(allocation(&s, 1, THRESHOLD).iter().all(|&m| m == 1));
    }

    #[test]
    fn flat_or_broken_input_takes_one_everywhere() {
        assert!(
            allocation(&[0.0; 50], 16, THRESHOLD)
                .iter()
                .all(|&m| m == 1)
        );
        assert!(
            allocation(&[1.0; 50], 16, THRESHOLD)
                .iter()
                .all(|&m| m == 1)
        );
        assert!(
            allocation(&[1.0, f64::NAN], 16, THRESHOLD)
                .iter()
                .all(|&m| m == 1)
        );
        assert!(allocation(&[], 16, THRESHOLD).is_empty());
    }

    #[test]
    fn extra_samples_stay_bounded() {
        // The bounds of the module's text, Σ (M − 1) ≤ P/2 and at most P/16 pixels with M > 1,
        // on 1000 pixels of which n have spread x and the rest 1, for any M_max.
        let mut boosted_somewhere = false;
        for n in [1, 3, 10, 30, 62, 100, 300, 1000] {
            for x in [1.0, 3.0, 10.0, 30.0, 100.0, 1e4, 1e8] {
                let s: Vec<f64> = (0..1000).map(|i| if i < n { x } else { 1.0 }).collect();
                let m = allocation(&s, 255, THRESHOLD);
                let extra: u64 = m.iter().map(|&m| (m - 1) as u64).sum();
                let boosted = m.iter().filter(|&&m| m > 1).count();
                assert!(extra * 2 <= 1000, "n = {n}, x = {x}: {extra} extra");
                assert!(boosted * 16 <= 1000, "n = {n}, x = {x}: {boosted} boosted");
                boosted_somewhere |= boosted > 0;
            }
        }
        assert!(boosted_somewhere);
    }
}
