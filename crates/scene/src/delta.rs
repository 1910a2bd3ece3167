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
        Some(DeltaStep {
            direction,
            weight: s.weight,
            refracted: s.refracted,
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
        mut origin: Vec3,
        mut dir: Vec3,
        mode: Transport,
        mut uniform: impl FnMut() -> f32,
    ) -> Option<DeltaWalk> {
        let mut beta = Vec3::ONE;
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
                });
            }
            if vertices == MAX_DELTA_CHAIN {
                return None;
            }
            let step = self.delta_step(&sh, wo, uniform(), mode)?;
            beta *= roulette(step.weight, &mut uniform)?;
            origin = self.spawn(&sh, step.direction);
            dir = step.direction;
        }
        None
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
