//! Mirrors and dielectrics at a surface point: one delta scattering ([`Scene::delta_step`]),
//! and a ray's walk through delta vertices to the first non-delta one
//! ([`Scene::walk_to_non_delta`]), the part of a camera path before x₀ (and of a `path` sample).
//!
//! A delta vertex is only ever sampled: it stores no photon, takes no direct light and no
//! connection (docs/method-notes.md, "Mirrors and glass").

use bdpm_bdf::Transport;
use bdpm_geometry::Frame;
use glam::Vec3;

use crate::{Scene, Shading};

/// The most delta vertices in a row that a walk follows: a path with more is dropped (its
/// light lost). A guard against rays trapped between perfect mirrors; Russian roulette on
/// lossy steps ends almost every other chain long before.
pub const MAX_DELTA_CHAIN: u32 = 64;

/// One sampled scattering at a delta vertex (see [`Scene::delta_step`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeltaStep {
    /// Unit world direction the path leaves along.
    pub direction: Vec3,
    /// Throughput weight of the step (dimensionless, per channel; see
    /// [`bdpm_bdf::SpecularSample::weight`]).
    pub weight: Vec3,
    /// True iff the step refracted through the surface.
    pub refracted: bool,
    /// Probability that the branch taken was sampled (a dielectric's F or 1 − F; 1 at a
    /// mirror).
    pub probability: f32,
    /// The factor by which the step scales radiance for crossing into another medium: 1/η²
    /// (η = η_t/η_i) for a refraction in [`Transport::Radiance`], else 1. `weight` divided by
    /// it is the light the step keeps; a roulette keys on that, as pbrt-v4 does with its
    /// `etaScale`, or it would end most paths entering glass and weight the rest by η².
    pub eta_scale: f32,
}

/// The factor by which a light path's (importance) throughput at a vertex with a shading
/// normal differs from the camera path's, |wo·ns|·|wi·ng| / (|wo·ng|·|wi·ns|) for the unit
/// directions `wo` (back along the arriving path) and `wi` (the one it leaves along): Veach's
/// adjoint BSDF for shading normals (his thesis, §5.3), without which light tracing and photons
/// would see a smooth glass or mirror sphere brighter or darker than camera paths do (the
/// amount is in docs/results.md, "Smooth spheres"). `None` where a cosine vanishes.
fn shading_normal_adjoint(sh: &Shading, wo: Vec3, wi: Vec3) -> Option<f32> {
    let num = wo.dot(sh.frame.n).abs() * wi.dot(sh.ng).abs();
    let den = wo.dot(sh.ng).abs() * wi.dot(sh.frame.n).abs();
    let factor = num / den;
    (den > 0.0 && factor.is_finite()).then_some(factor)
}

/// Where a ray's walk through delta vertices ended (see [`Scene::walk_to_non_delta`]).
#[derive(Clone, Copy, Debug)]
pub struct DeltaWalk {
    /// The first non-delta vertex, shaded towards `wo`.
    pub sh: Shading,
    /// Unit direction from it back along the walk's last segment.
    pub wo: Vec3,
    /// Product of the delta steps' weights, each divided by its roulette probability
    /// (dimensionless, per channel; exactly 1 when the ray met no delta vertex).
    pub beta: Vec3,
    /// Delta vertices passed before `sh`.
    pub vertices: u32,
    /// Bit i set iff the walk refracted at its i-th delta vertex (0 = the first): with
    /// `vertices`, the branches [`Scene::follow_branches`] takes again for a nearby ray.
    pub branches: u64,
}

impl Scene {
    /// Samples the delta material at `sh` (shaded towards `wo`, the unit direction back along
    /// the arriving path) with `u` uniform in [0, 1) choosing a dielectric's branch; `mode`
    /// says whether the path carries radiance (camera) or importance (light). `None` for a
    /// non-delta material, an unusable `wo`, or a sample that the shading normal sends to the
    /// wrong side of the geometric one (a reflection below the surface or a refraction above
    /// it), which carries no light.
    ///
    /// A dielectric's exterior is the side the triangle's own normal faces (outward for the
    /// closed shapes of a scene file): `sh`'s frame faces `wo`, so it is turned back where
    /// `wo` lies inside.
    #[cold]
    #[inline(never)]
    pub fn delta_step(
        &self,
        sh: &Shading,
        wo: Vec3,
        u: f32,
        mode: bdpm_bdf::Transport,
    ) -> Option<DeltaStep> {
        let (model, frame) = self.delta_frame(sh)?;
        let s = model.sample_delta(frame.to_local(wo), u, mode)?;
        let direction = frame.to_world(s.wi);
        let side = sh.ng.dot(direction);
        if (s.refracted && side >= 0.0) || (!s.refracted && side <= 0.0) {
            return None;
        }
        let weight = match mode {
            Transport::Importance if sh.frame.n != sh.ng => {
                s.weight * shading_normal_adjoint(sh, wo, direction)?
            }
            _ => s.weight,
        };
        Some(DeltaStep {
            direction,
            weight,
            refracted: s.refracted,
            probability: s.probability,
            eta_scale: match mode {
                Transport::Radiance if s.refracted => 1.0 / (s.eta * s.eta),
                _ => 1.0,
            },
        })
    }

    /// The fraction of flux the delta material at `sh` scatters for light arriving from the
    /// unit direction `wo` (per channel, in [0, 1]; see [`bdpm_bdf::Material::albedo`]);
    /// `None` for a non-delta material.
    pub fn delta_albedo(&self, sh: &Shading, wo: Vec3) -> Option<Vec3> {
        let (model, frame) = self.delta_frame(sh)?;
        Some(model.albedo(frame.to_local(wo)))
    }

    /// The delta model at `sh` and the frame it scatters in: +z towards the exterior (the side
    /// the triangle's own normal faces), since `sh`'s frame faces the arriving path.
    fn delta_frame(&self, sh: &Shading) -> Option<(&bdpm_bdf::Material, Frame)> {
        let model = self.materials()[sh.material as usize].delta.as_ref()?;
        let outside = sh.ng.dot(self.geometry().normal(sh.prim)) >= 0.0;
        let frame = if outside {
            sh.frame
        } else {
            Frame::from_normal(-sh.frame.n)
        };
        Some((model, frame))
    }

    /// Follows the ray from `origin` along the unit `dir` through delta vertices to the first
    /// non-delta surface it meets: `None` if it leaves the scene, a delta step fails, the
    /// roulette ends it, or it passes [`MAX_DELTA_CHAIN`] delta vertices. `uniform` gives
    /// numbers uniform in [0, 1): one per delta vertex for its branch and one more for the
    /// roulette where a step loses light (survival probability: the step weight's largest
    /// channel). A ray that meets no delta vertex draws none and returns the hit exactly as
    /// [`Scene::shade`] gives it, with `beta` = 1.
    pub fn walk_to_non_delta(
        &self,
        origin: Vec3,
        dir: Vec3,
        mode: Transport,
        mut uniform: impl FnMut() -> f32,
    ) -> Option<DeltaWalk> {
        self.walk_with(origin, dir, |sh, wo| {
            let step = self.delta_step(sh, wo, uniform(), mode)?;
            let kept = roulette(step.weight / step.eta_scale, &mut uniform)?;
            Some((step, kept * step.eta_scale))
        })
    }

    /// The walk of [`Self::walk_to_non_delta`] that takes at every delta vertex its more
    /// probable branch (reflection where the Fresnel reflectance is at least ½) and plays no
    /// roulette: the one x₀ that stands for a pixel whose samples may split between branches
    /// (the weights' per-pixel table). `beta` is the product of the steps' weights times their
    /// probabilities: the share of the light through the pixel that takes this chain (per
    /// channel).
    pub fn walk_principal(&self, origin: Vec3, dir: Vec3, mode: Transport) -> Option<DeltaWalk> {
        self.walk_with(origin, dir, |sh, wo| {
            // u = 0 reflects with probability F wherever F > 0.
            let reflect = self.delta_step(sh, wo, 0.0, mode);
            let step = match reflect {
                Some(r) if r.refracted || r.probability >= 0.5 => r,
                _ => self.delta_step(sh, wo, 1.0 - f32::EPSILON, mode)?,
            };
            Some((step, step.weight * step.probability))
        })
    }

    /// The walk through delta vertices that `step` scatters at (returning the step and its
    /// factor of `beta`): the loop of [`Self::walk_to_non_delta`] and [`Self::walk_principal`].
    fn walk_with(
        &self,
        mut origin: Vec3,
        mut dir: Vec3,
        mut step: impl FnMut(&Shading, Vec3) -> Option<(DeltaStep, Vec3)>,
    ) -> Option<DeltaWalk> {
        let mut beta = Vec3::ONE;
        let mut branches = 0u64;
        for vertices in 0..=MAX_DELTA_CHAIN {
            let hit = self.geometry().intersect(origin, dir, f32::INFINITY)?;
            let wo = -dir;
            let sh = self.shade(&hit, wo);
            if !self.is_delta(sh.material) {
                return Some(DeltaWalk {
                    sh,
                    wo,
                    beta,
                    vertices,
                    branches,
                });
            }
            if vertices == MAX_DELTA_CHAIN {
                return None;
            }
            let (s, factor) = step(&sh, wo)?;
            beta *= factor;
            branches |= u64::from(s.refracted) << vertices;
            origin = self.spawn(&sh, s.direction);
            dir = s.direction;
        }
        None
    }

    /// Ray differentials through a delta chain: the ray from `origin` along the unit `dir`
    /// is taken through its first `vertices` delta vertices on the branches of `branches`
    /// (bit i: refract at the i-th; see [`DeltaWalk::branches`]), and each nearby ray of
    /// `near` (from the same origin, unit directions) with it: at each of the ray's delta
    /// vertices a nearby ray's line crosses that vertex's tangent plane (ahead or behind) and
    /// scatters there as the ray does (same normal, same branch), whatever the surface does
    /// beside the vertex. The nearby rays' last segments (origin, unit direction), or `None`
    /// where the ray leaves the chain or a nearby ray is parallel to a plane or cannot take
    /// the branch (total internal reflection).
    pub fn follow_branches<const N: usize>(
        &self,
        (mut origin, mut dir): (Vec3, Vec3),
        (vertices, branches): (u32, u64),
        near: [Vec3; N],
    ) -> Option<[(Vec3, Vec3); N]> {
        let mut rays = near.map(|d| (origin, d));
        for i in 0..vertices.min(MAX_DELTA_CHAIN) {
            let hit = self.geometry().intersect(origin, dir, f32::INFINITY)?;
            let sh = self.shade(&hit, -dir);
            if !self.is_delta(sh.material) {
                return None;
            }
            let refract = (branches >> i) & 1 == 1;
            // u = 0 reflects wherever F > 0; u just below 1 refracts wherever F < 1.
            let u = if refract { 1.0 - f32::EPSILON } else { 0.0 };
            let forced = |sh: &Shading, d: Vec3| {
                let step = self.delta_step(sh, -d, u, Transport::Radiance)?;
                (step.refracted == refract)
                    .then(|| (self.spawn(sh, step.direction), step.direction))
            };
            for (o, d) in rays.iter_mut() {
                // A line of the differential: its crossing may lie behind its origin.
                let t = sh.ng.dot(sh.p - *o) / sh.ng.dot(*d);
                if !t.is_finite() {
                    return None;
                }
                let at = Shading {
                    p: *o + *d * t,
                    ..sh
                };
                (*o, *d) = forced(&at, *d)?;
            }
            (origin, dir) = forced(&sh, dir)?;
        }
        Some(rays)
    }
}

/// A delta step's weight divided by its survival probability q = min(1, largest channel), or
/// `None` when the roulette (one number from `uniform`, drawn only if q < 1) ends the path.
/// Lossless steps (clear glass, a white mirror) are never rouletted.
pub(crate) fn roulette(weight: Vec3, uniform: &mut impl FnMut() -> f32) -> Option<Vec3> {
    let q = weight.max_element().min(1.0);
    if q >= 1.0 {
        return Some(weight);
    }
    if q <= 0.0 || uniform() >= q {
        return None;
    }
    Some(weight / q)
}
