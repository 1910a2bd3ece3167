//! What photon tracing needs from a scene, as a trait: a renderer with its own scene type
//! implements [`PhotonScene`] and gets bdpm's photon walk, photon map and radiance-cache pass.

use bdpm_core::{PointLight, Shading};
use glam::Vec3;

/// The scene queries of the photon random walk (method.md §1). Every method must be a pure
/// function of its arguments (the walk's determinism rests on it) and callable from many
/// threads at once.
///
/// Units: positions in m, flux in W per RGB channel, directions unit vectors, pdfs per
/// steradian. Surfaces are two-sided and there is no transmission.
///
/// Use [`Shading`] for a surface point (position, geometric normal and shading frame facing
/// the arrival side, material and triangle indices): the photon records
/// (`PathVertex`) store those fields for the MIS weights.
pub trait PhotonScene: Sync {
    /// Chooses the light that emits a photon, for `u` uniform in [0, 1): its index and the
    /// probability p_l with which it was chosen (bdpm picks in proportion to flux
    /// luminance). A probability ≤ 0 (or NaN) means no photon is emitted.
    fn pick_light(&self, u: f32) -> (usize, f32);

    /// Light `index` (a point light: position, m; flux, W per channel). Asked only for the
    /// indices [`Self::is_area_light`] says are not area lights.
    fn light(&self, index: usize) -> PointLight;

    /// True iff light `index` (as [`Self::pick_light`] returns it) is an area light, whose
    /// photons leave from [`Self::emit_area`]. The default: none is (point lights only).
    fn is_area_light(&self, index: usize) -> bool {
        let _ = index;
        false
    }

    /// A photon from area light `index`, chosen with probability `probability`: a point on it
    /// from the uniform numbers `u_point` and a direction from `u_dir` (bdpm's scene: uniform
    /// by area, cosine-distributed on the emitting side). `None` if nothing is emitted. The
    /// default emits nothing.
    fn emit_area(
        &self,
        index: usize,
        probability: f32,
        u_point: [f32; 2],
        u_dir: [f32; 2],
    ) -> Option<AreaEmission> {
        let _ = (index, probability, u_point, u_dir);
        None
    }

    /// The first surface hit by the ray from `origin` along the unit direction `dir` (no
    /// distance limit), shaded to face back along the ray (towards −`dir`).
    fn intersect(&self, origin: Vec3, dir: Vec3) -> Option<Shading>;

    /// At the surface point `sh`, for light arriving from the unit world direction
    /// `incoming` (pointing away from the surface): the Russian-roulette survival
    /// probability q (dimensionless; it must depend only on the point and `incoming`, as the
    /// weights of method.md §8 recompute it; bdpm's scene uses `bdpm_bdf::survival_probability`) and a BDF
    /// sample drawn with the uniform numbers `u`, the direction in world space. `None` if
    /// sampling failed. The tracer drops samples below the geometric normal itself.
    fn scatter(&self, sh: &Shading, incoming: Vec3, u: [f32; 3]) -> (f32, Option<Scatter>);

    /// True iff the surface at `sh` is a delta one (a mirror or a dielectric): the walk then
    /// stores no photon there, takes [`Self::scatter`]'s direction on either side of the
    /// surface (a refraction crosses it), and asks no light visibility. The default: never.
    fn is_delta(&self, sh: &Shading) -> bool {
        let _ = sh;
        false
    }

    /// The origin of a ray leaving `sh` along `dir`, pushed off the surface so that it does
    /// not hit it again, m.
    fn spawn(&self, sh: &Shading, dir: Vec3) -> Vec3;

    /// Bit l set iff light l (l < 32) is visible from `sh` on the side of its normal; asked
    /// only when the trace options' `light_visibility` is
    /// on (the MIS weights read it at photons' previous vertices).
    fn visible_light_mask(&self, sh: &Shading) -> u32;

    /// [`Self::visible_light_mask`] at the first vertex of a path that light `light` emitted:
    /// the emitted ray found nothing before `sh`, so a scene may take that light's
    /// visibility from the path instead of a shadow ray (its side test still applies). The
    /// default casts every ray.
    fn visible_light_mask_reached(&self, sh: &Shading, light: usize) -> u32 {
        let _ = light;
        self.visible_light_mask(sh)
    }
}

/// A photon leaving an area light ([`PhotonScene::emit_area`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaEmission {
    /// Ray origin, off the emitting surface on the side of `direction`, m.
    pub origin: Vec3,
    /// Unit direction of the emitted ray.
    pub direction: Vec3,
    /// Flux over the probability of this sample's light, point and direction as the
    /// estimator of the emitted flux needs it: Φ/p(light) when point and direction follow
    /// the emitted radiance, W per channel (the tracer divides by N_F).
    pub flux: Vec3,
}

/// The light index a [`PathVertex`](crate::PathVertex) records for a path that an area light
/// emitted (its own index may exceed `u16`; the weights need only know it is an area light).
pub const AREA_LIGHT: u16 = u16::MAX;

/// The BDF sample drawn at an arrival (before the roulette decision). At a delta vertex
/// ([`PhotonScene::is_delta`]) `f` and `pdf` are 0 and `weight` is the delta step's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scatter {
    /// Unit world direction leaving the surface, on the side of the vertex's
    /// geometric normal.
    pub direction: Vec3,
    /// BDF value f(ω_in, ω_out), sr⁻¹.
    pub f: Vec3,
    /// Solid-angle pdf of `direction`, sr⁻¹ (without the roulette factor).
    pub pdf: f32,
    /// f·cos/pdf (dimensionless); the scattered energy is `power · weight`.
    pub weight: Vec3,
}
