//! How many x₁ the camera samples of each pixel take for BDD=1's one-bounce paths
//! light → x₁ → x₀ at a glossy x₀, in a scene with area lights ([`OneBounceSamples`]), and
//! x₁'s direct term that each such x₁ estimates.
//!
//! At a glossy x₀ the one-bounce term is the reflection of directly lit surfaces in a narrow
//! lobe: its noise lies in which x₁ the lobe reaches and in x₁'s light sample and BDF ray,
//! and where x₁ is itself glossy and sees the light's reflection (on
//! scenes/cornell-box-glossy.toml the side walls' upper corners, which reflect the light's
//! reflection in the back wall: camera → side wall → back wall → light) it is most of the
//! pixel's error at equal time. A further x₁ costs a BDF ray at x₀, x₁'s light sample and
//! BDF ray and its weight w₁, but no gather. Taken at every glossy x₀, a second x₁ lowered
//! the glossy box's per-pass variance by a quarter but cost a fifth of a pass
//! (docs/results.md, "Area lights: the light's reflections"); here only the pixels whose
//! one-bounce estimate is noisy take them.
//!
//! N per pixel is fixed before the passes from the scene alone, as `direct_boost`'s M is
//! (crate::direct): at 16 points of the pixel (a 4 × 4 jittered grid from a stream fixed by
//! the pixel), one one-bounce estimate each as a camera sample takes it (x₀'s BDF ray, x₁'s
//! direct term, unweighted); the spread s is their standard deviation over the probes at a
//! glossy x₀, times the square root of the share of such probes (a Lambert x₀ takes one x₁
//! whatever N says); N = ⌊s / (`THRESHOLD`·s_rms)⌋ clamped to [1, min(`MOST`, M_max)], M_max
//! being `direct_boost`. N ∝ s is the allocation that minimises Σ Jₚ/Nₚ for a given Σ Nₚ with
//! Jₚ ∝ sₚ², and the same bounds hold as for M: at most P/(4·THRESHOLD²) pixels with N > 1
//! and Σ (N − 1) ≤ P/THRESHOLD. Since N depends on nothing random, every pass stays an
//! unbiased, independent, identically distributed estimate. Point-light scenes and scenes
//! without glossy surfaces take one x₁ everywhere and keep their image bits.
use bdpm_bdf::{Transport, luminance};
use bdpm_geometry::{Domain, Rng};
use bdpm_scene::{Scene, Shading};
use bdpm_settings::RenderSettings;
use glam::Vec3;

use crate::direct::{SampleCounts, x1_weighs_bdf};

/// x₁ samples per camera sample for the one-bounce paths, per pixel: the [`SampleCounts`] N of
/// the module's rule.
#[derive(Clone, Debug, PartialEq)]
pub struct OneBounceSamples(SampleCounts);

/// N = ⌊s / (THRESHOLD·s_rms)⌋.
pub(crate) const THRESHOLD: f64 = 1.0;

/// The largest N.
pub(crate) const MOST: u32 = 8;

/// Probes per side of a pixel (a jittered grid of PROBES_SIDE² points).
const PROBES_SIDE: u32 = 4;

impl OneBounceSamples {
    /// The allocation for `scene` under `settings`, or `None` where every pixel takes one x₁:
    /// a scene without area lights or without a glossy surface, `direct_boost` ≤ 1, or no
    /// pixel above the threshold.
    pub(crate) fn allocate(scene: &Scene, settings: &RenderSettings) -> Option<OneBounceSamples> {
        let most = settings.direct_boost.min(MOST);
        if most <= 1 || !scene.has_emission() || !has_glossy(scene) {
            return None;
        }
        let counts =
            SampleCounts::from_spreads(settings, THRESHOLD, most, |x, y| spread(scene, x, y))?;
        Some(OneBounceSamples(counts))
    }
}

impl std::ops::Deref for OneBounceSamples {
    type Target = SampleCounts;

    fn deref(&self) -> &SampleCounts {
        &self.0
    }
}

/// Whether some material of `scene` is glossy (neither Lambert nor delta).
fn has_glossy(scene: &Scene) -> bool {
    scene
        .materials()
        .iter()
        .any(|m| !m.is_delta() && !m.bdf.is_lambert())
}

/// The spread s of pixel (x, y)'s one-bounce estimates at a glossy x₀ (luminance,
/// W·m⁻²·sr⁻¹), as the module's text defines it.
fn spread(scene: &Scene, x: u32, y: u32) -> f64 {
    let mut rng = Rng::new(0, Domain::DirectSamples, [u64::MAX - 1, x as u64, y as u64]);
    let cam = scene.camera();
    let (mut n, mut sum, mut sum_sq) = (0u32, 0.0, 0.0);
    let step = 1.0 / PROBES_SIDE as f32;
    for k in 0..PROBES_SIDE * PROBES_SIDE {
        let [a, b] = rng.uniform2();
        let (i, j) = ((k % PROBES_SIDE) as f32, (k / PROBES_SIDE) as f32);
        let dir = cam.ray_direction(x as f32 + (i + a) * step, y as f32 + (j + b) * step);
        let walk =
            scene.walk_to_non_delta(cam.position(), dir, Transport::Radiance, || rng.uniform());
        let Some(walk) = walk else { continue };
        if let Some(v) = probe(scene, &walk.sh, walk.wo, &mut rng) {
            let v = v * luminance(walk.beta) as f64;
            n += 1;
            sum += v;
            sum_sq += v * v;
        }
    }
    let total = (PROBES_SIDE * PROBES_SIDE) as f64;
    // Σ (v − mean)² over the glossy probes, over all probes: their variance times their share.
    ((sum_sq - sum * sum / n.max(1) as f64) / total)
        .max(0.0)
        .sqrt()
}

/// One one-bounce estimate at x₀ = `sh0` seen along `wo0` (luminance, W·m⁻²·sr⁻¹, before
/// the camera side's throughput) as a camera sample takes it, unweighted: x₀'s BDF ray to
/// the first non-delta x₁ and x₁'s direct term ([`chain_direct`]). `None` at a Lambert x₀,
/// which takes one x₁ whatever the allocation says.
fn probe(scene: &Scene, sh0: &Shading, wo0: Vec3, rng: &mut Rng) -> Option<f64> {
    let bdf = scene.bdf_at(sh0);
    if bdf.is_lambert() {
        return None;
    }
    let out = bdf.outgoing(sh0.frame.to_local(wo0));
    let Some(s) = bdf.sample_at(&out, rng.uniform3()) else {
        return Some(0.0);
    };
    let v = sh0.frame.to_world(s.wi);
    if sh0.ng.dot(v) <= 0.0 {
        return Some(0.0);
    }
    let origin = scene.spawn(sh0, v);
    let walk = scene.walk_to_non_delta(origin, v, Transport::Radiance, || rng.uniform());
    Some(walk.map_or(0.0, |w| {
        let c = s.weight * w.beta * chain_direct(scene, &w.sh, w.wo, rng);
        luminance(c) as f64
    }))
}

/// The direct light at x₁ = `sh1` towards `wo` (W·m⁻²·sr⁻¹): the point lights' exact term and
/// the area lights' samples ([`area_samples_at_x1`]).
pub(crate) fn chain_direct(scene: &Scene, sh1: &Shading, wo: Vec3, rng: &mut Rng) -> Vec3 {
    let mut direct = scene.direct(sh1, wo);
    if scene.has_emission() {
        let area = area_samples_at_x1(scene, sh1, wo, rng);
        direct += area.into_iter().flatten().map(|(c, _)| c).sum::<Vec3>();
    }
    direct
}

/// x₁'s area-light direct term towards `wo` by its strategies, each (value W·m⁻²·sr⁻¹, unit
/// direction to the light) or None: at a glossy x₁ one light sample and one BDF ray weighted
/// against each other by the power heuristic (`Scene::direct_area_sample` with MIS,
/// `Scene::emitter_hit_by_bdf`), at a Lambert x₁ the light sample alone, whose BDF ray seldom
/// meets a light (on Mitsuba's box it cost about 15 % of a pass, in one run, for no variance;
/// docs/results.md, "Area lights: MIS at x₁").
pub(crate) fn area_samples_at_x1(
    scene: &Scene,
    sh1: &Shading,
    wo: Vec3,
    rng: &mut Rng,
) -> [Option<(Vec3, Vec3)>; 2] {
    let mis = x1_weighs_bdf(scene, sh1);
    let light = scene.direct_area_sample(sh1, wo, rng.uniform3(), mis);
    let bdf = mis
        .then(|| scene.emitter_hit_by_bdf(sh1, wo, rng.uniform3()))
        .flatten();
    [light, bdf]
}
