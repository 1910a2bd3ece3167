//! The per-render constants of the BDPM mix and what every camera-side estimator builds from
//! them: x₀'s data ([`FirstVertex`]), a pixel's budget and weigher, and w₁ of a pair.
use std::borrow::Cow;

use bdpm_bdf::{Bdf, Outgoing, luminance};
use bdpm_cache::RadianceCache;
use bdpm_geometry::Hit;
use bdpm_mis::{Budget, Heuristic, Needs, Pair, PixelTerms, Weigher, acceptance_area};
use bdpm_photon::{Photon, PhotonMap};
use bdpm_scene::{Scene, Shading};
use glam::Vec3;

use crate::estimates::WeightStats;
use crate::radius::RadiusMap;

/// Per-render constants of the mix.
pub(crate) struct Mix<'a> {
    pub(crate) scene: &'a Scene,
    pub(crate) heuristic: Heuristic,
    pub(crate) needs: Needs,
    /// w₁ of a mode that does not weigh (`bdd0`: 0, `bdd1`: 1; [`Heuristic::fixed_w1`]).
    pub(crate) fixed_w1: Option<f64>,
    pub(crate) budget: Budget,
    /// Merge kernel 1/S, m⁻².
    pub(crate) inv_area: f32,
    /// Merge radius r, m (a pixel's is r times its [`Self::radius_scale`]).
    pub(crate) radius: f32,
    /// Each pixel's scale of r (`adaptive_radius`); `None`: r everywhere.
    pub(crate) radius_map: Option<&'a RadiusMap>,
    /// The frozen radiance cache, when the mode needs L_d (and b).
    pub(crate) cache: Option<&'a RadianceCache>,
    /// `corrected-balance`'s pilot: every weighted contribution also goes into the sample's
    /// candidate sums under each candidate factor (crate::correction).
    pub(crate) pilot: bool,
    /// BDD=0's paths are sampled by light tracing (`Mix::splat`) instead of merged at x₀.
    pub(crate) light_tracing: bool,
    /// The test-only switches (only with the feature `test-hooks`).
    #[cfg(feature = "test-hooks")]
    pub(crate) hooks: Hooks,
}

/// Switches that only tests turn on (with the feature `test-hooks`; without it nothing holds
/// them and the mix's branches on them are constant).
#[cfg(feature = "test-hooks")]
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Hooks {
    /// Weight the x₀ photon sum with w₁(x₀, x₁ᶜ) of the camera's x₁, as the preprint's eq.
    /// 2–3 read literally. It is biased; a test shows it.
    pub(crate) camera_x1_weighting: bool,
    /// Compute a photon's y_p inputs at every visit, not once per photon
    /// (`Mix::prev_inputs`); the image bits must not change.
    pub(crate) per_visit_inputs: bool,
    /// The splats ignore light tracing's density ratio (a biased mix).
    pub(crate) two_way_splat_weights: bool,
}

/// What lies before the chain of delta vertices a photon left last ([`Mix::after_delta`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum DeltaChain {
    /// The chain goes back to the light (L–S…–x₀): no technique but the merge at x₀ samples it.
    FromLight,
    /// A non-delta vertex x₁ lies before the chain (…–x₁–S…–x₀): BDD=1 samples it too, with
    /// [`Mix::chain_w1`].
    FromVertex,
}

/// The camera side of x₀: the shading point, its outgoing direction and its BDF data.
pub(crate) struct FirstVertex<'s> {
    pub(crate) sh: Shading,
    pub(crate) u: Vec3,
    /// The BDF's data for outgoing direction u, shared by every sample and pdf at x₀.
    pub(crate) out: Outgoing,
    /// The BDF at x₀ (kd from its texture where the material has one).
    pub(crate) bdf: Cow<'s, Bdf>,
    /// Luminance of the directional albedo µ(u; x₀).
    pub(crate) albedo: f32,
    /// `camis` only (else 0): its acceptance area A at x₀'s distance from the camera, m².
    pub(crate) acceptance_area: f64,
    /// `camis` only (else 0): p_C(x₀), the camera's density of x₀ within its pixel, m⁻².
    pub(crate) primary_density: f64,
    /// The throughput of the mirrors and glass the camera ray passed before x₀ (per
    /// channel), `None` where it met none.
    pub(crate) beta: Option<Vec3>,
}

impl<'a> Mix<'a> {
    /// Prepares x₀ for a camera ray that hit `hit` (u = towards the camera), or None if the
    /// shading normal faces away from the camera.
    pub(crate) fn first_vertex<'s>(&'s self, hit: &Hit, u: Vec3) -> Option<FirstVertex<'s>> {
        self.first_vertex_shaded(self.scene.shade(hit, u), u)
    }

    /// [`Self::first_vertex`] for a hit already shaded for `u`.
    pub(crate) fn first_vertex_shaded<'s>(
        &'s self,
        sh: Shading,
        u: Vec3,
    ) -> Option<FirstVertex<'s>> {
        let u_local = sh.frame.to_local(u);
        if u_local.z <= 0.0 {
            return None;
        }
        let bdf = self.scene.bdf_at(&sh);
        let out = bdf.outgoing(u_local);
        let (acceptance_area, primary_density) = if self.needs.primary_terms || self.light_tracing {
            self.primary_terms(&sh, u)
        } else {
            (0.0, 0.0)
        };
        Some(FirstVertex {
            sh,
            u,
            out,
            albedo: luminance(bdf.albedo_at(&out)),
            bdf,
            acceptance_area,
            primary_density,
            beta: None,
        })
    }

    /// Whether the photon `ph` of `map` left a delta vertex (a mirror or glass) last, and if so
    /// what lies before that chain of delta vertices: `None` for a photon whose y_p is a
    /// non-delta vertex (always, in a scene without delta materials). The stored vertices of a
    /// path lie in path order, so the vertex before a depth-d one (d ≥ 1) is the one before it.
    #[inline]
    pub(crate) fn after_delta(&self, map: &PhotonMap, ph: &Photon) -> Option<DeltaChain> {
        let vertices = map.vertices();
        let mut i = ph.prev as usize;
        if !self.scene.is_delta(vertices[i].at.material) {
            return None;
        }
        loop {
            if vertices[i].depth == 0 {
                return Some(DeltaChain::FromLight);
            }
            i -= 1;
            if !self.scene.is_delta(vertices[i].at.material) {
                return Some(DeltaChain::FromVertex);
            }
        }
    }

    /// w₁ of a path with a chain of delta vertices between x₀ and a non-delta x₁, the same for
    /// both techniques: the fixed w₁ of `bdd0`/`bdd1`, else the lobe's share of x₀'s
    /// directional albedo towards the camera, 1 − kd/µ(u) (luminance; 0 at a Lambert x₀, so
    /// BDD=1 does not trace these chains there). A function of x₀ alone, so the camera side
    /// (BDD=1 through the chain) and the photon side (the merge at x₀) agree on it whatever
    /// the chain; a stand-in until the noise model sees through delta vertices
    /// (docs/method-notes.md, "Mirrors and glass").
    pub(crate) fn chain_w1(&self, x0: &FirstVertex<'_>) -> f64 {
        if let Some(w1) = self.fixed_w1 {
            return w1;
        }
        if x0.albedo <= 0.0 {
            return 0.0;
        }
        f64::from(1.0 - luminance(x0.bdf.kd()) / x0.albedo).clamp(0.0, 1.0)
    }
    /// `camis`'s acceptance area A (m²) and p_C(x₀) (m⁻²) for x₀ at `sh` seen along −u.
    ///
    /// Both are functions of x₀ alone. A pixel is sampled uniformly over its area a_pix on
    /// the image plane at unit distance; dω = cos³θ_c·dA_image and dA(x₀) = d₀²·dω/cos θ₀,
    /// hence p_C(x₀) = cos θ₀/(d₀²·a_pix·cos³θ_c).
    fn primary_terms(&self, sh: &Shading, u: Vec3) -> (f64, f64) {
        let cam = &self.scene.camera();
        let d2 = (sh.p - cam.position()).length_squared() as f64;
        let cos0 = sh.ng.dot(u).abs() as f64;
        let cos_c = cam.forward().dot(-u).max(0.0) as f64;
        let image = d2 * cam.pixel_area() as f64 * cos_c * cos_c * cos_c;
        let density = if image > 0.0 { cos0 / image } else { 0.0 };
        (acceptance_area(d2.sqrt()), density)
    }

    /// The mix's budget for one pixel: its N_B (N_eff where given, else the mix's) and its
    /// merge area, scale²·S for a radius of `scale` × r (exactly S at a scale of 1).
    pub(crate) fn pixel_budget(&self, camera_samples: Option<f64>, scale: f32) -> Budget {
        let mut budget = Budget {
            camera_samples: camera_samples.unwrap_or(self.budget.camera_samples),
            ..self.budget
        };
        if scale != 1.0 {
            budget.merge_area *= f64::from(scale) * f64::from(scale);
        }
        budget
    }

    /// Pixel (x, y)'s scale of the merge radius: 1 without a map. Exactly 1 keeps every
    /// kernel, gather and weight input bit for bit what it is without one.
    #[inline]
    pub(crate) fn radius_scale(&self, x: u32, y: u32) -> f32 {
        self.radius_map.map_or(1.0, |m| m.scale(x, y))
    }

    /// The largest pixel radius over r: the photon grid is built for r times it.
    pub(crate) fn largest_radius_scale(&self) -> f32 {
        self.radius_map.map_or(1.0, |m| m.largest().max(1.0))
    }

    /// The weigher of one pixel: the mode with the pixel's A, B (`terms`) and, where the pixel
    /// table gives one, its N_eff (`camera_samples`) in place of N_B (method.md §12; N_B itself
    /// under the pinhole model and without jitter, so those weights keep their bits),
    /// `corrected-balance`'s factor `correction` for the pixel (1 for `balance`'s weights; the
    /// other modes ignore it), and the pixel's merge area scale²·S for its radius of `scale`
    /// × r ([`Self::radius_scale`]). The per-pixel plan (crate::plan) is its one caller.
    pub(crate) fn weigher(
        &self,
        (camera_samples, terms): (Option<f64>, Option<&PixelTerms>),
        correction: f64,
        scale: f32,
    ) -> Weigher {
        let budget = self.pixel_budget(camera_samples, scale);
        Weigher::new(self.heuristic, &budget, terms).with_correction(correction)
    }

    /// Whether the camera side merges photons at x₀ (BDD=0 by merging, not light tracing).
    pub(crate) fn merges_at_x0(&self) -> bool {
        self.needs.photons_at_x0 && !self.light_tracing
    }

    /// w₁ for `pair` under `weigher`, counted in `stats`; with light tracing in BDD=0's place,
    /// [`Weigher::weight_light_traced`] with N_B·S·p_C(x₀), S the weigher's (its pixel's, with
    /// `adaptive_radius`): both sides of a path compute it from x₀ and its pixel alone.
    pub(crate) fn w1(&self, pair: &Pair, weigher: &Weigher, stats: &mut WeightStats) -> f64 {
        let w = if self.light_tracing {
            let b = &self.budget;
            let ratio = b.camera_samples * weigher.merge_area() * pair.x0.primary_density;
            weigher.weight_light_traced(pair, ratio)
        } else {
            weigher.weight(pair)
        };
        stats.evaluations += 1;
        stats.outside_unit += w.outside_unit as u64;
        stats.clamped_cb += w.clamped_cb as u64;
        w.w1
    }
}

// The test hooks are read through these, so that without the feature `test-hooks` the mix
// has no fields for them and its branches on them are constant.
impl Mix<'_> {
    /// Test hook: weight the photon sum at x₀ with the camera's w₁.
    #[cfg(feature = "test-hooks")]
    #[inline]
    pub(crate) fn camera_x1_weighting(&self) -> bool {
        self.hooks.camera_x1_weighting
    }

    /// Test hook: compute a photon's y_p inputs at every visit.
    #[cfg(feature = "test-hooks")]
    #[inline]
    pub(crate) fn per_visit_inputs(&self) -> bool {
        self.hooks.per_visit_inputs
    }

    /// Test hook: the splats' weights without light tracing's density ratio.
    #[cfg(feature = "test-hooks")]
    #[inline]
    pub(crate) fn two_way_splat_weights(&self) -> bool {
        self.hooks.two_way_splat_weights
    }

    /// Without the feature `test-hooks`: never.
    #[cfg(not(feature = "test-hooks"))]
    #[inline]
    pub(crate) fn camera_x1_weighting(&self) -> bool {
        false
    }

    /// Without the feature `test-hooks`: never.
    #[cfg(not(feature = "test-hooks"))]
    #[inline]
    pub(crate) fn per_visit_inputs(&self) -> bool {
        false
    }

    /// Without the feature `test-hooks`: never.
    #[cfg(not(feature = "test-hooks"))]
    #[inline]
    pub(crate) fn two_way_splat_weights(&self) -> bool {
        false
    }
}
