//! The one description of a candidate second vertex x₁ that the MIS weights read, shared by
//! the camera's x₁ and a photon's previous vertex y_p (docs/method.md §2: both techniques must
//! evaluate the same function w₁(x₀, x₁), so both must see the same inputs).

use std::borrow::Cow;

use bdpm_bdf::Bdf;
use bdpm_geometry::Frame;
use glam::{Vec2, Vec3};

use crate::{Scene, Shading};

/// Lights whose visibility a [`WeightVertex`] records (bit `l` of [`WeightVertex::lights`]);
/// lights beyond these are tested with a shadow ray where they are needed.
pub const MASKED_LIGHTS: usize = 32;

/// What the weights know about a candidate x₁: where it is, which way it faces, what it is made
/// of and which lights it sees. Built only by [`WeightVertex::at`] and
/// [`Scene::visible_light_mask`], for camera vertices and photon vertices alike.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightVertex {
    /// Position, m.
    pub p: Vec3,
    /// Unit geometric normal on the side the vertex was reached from (the side x₀ sees for a
    /// camera vertex, the side the light arrived from for a photon vertex).
    pub n: Vec3,
    /// Material index.
    pub material: u32,
    /// Triangle index.
    pub prim: u32,
    /// Barycentric coordinates of `p` in the triangle (for a textured material's kd).
    pub bary: Vec2,
    /// Bit `l` set iff light `l < MASKED_LIGHTS` lies on the side of `n` and nothing blocks the
    /// segment to it; 0 where visibility was not computed.
    pub lights: u32,
}

impl WeightVertex {
    /// The vertex at a shading point, with the given light-visibility bits (from
    /// [`Scene::visible_light_mask`] of the same point, or 0 where the weights never read them).
    #[inline]
    pub fn at(sh: &Shading, lights: u32) -> WeightVertex {
        WeightVertex {
            p: sh.p,
            n: sh.ng,
            material: sh.material,
            prim: sh.prim,
            bary: sh.bary,
            lights,
        }
    }
}

impl Scene {
    /// [`Scene::bdf_on`] at a weight vertex.
    #[inline]
    pub fn bdf_at_vertex(&self, v: &WeightVertex) -> Cow<'_, Bdf> {
        self.bdf_on(v.material, v.prim, v.bary)
    }

    /// Visibility bits of the first [`MASKED_LIGHTS`] lights from `sh` (bit `l` iff
    /// [`Scene::light_visible`]): one shadow ray per light on the lit side.
    pub fn visible_light_mask(&self, sh: &Shading) -> u32 {
        let mut mask = 0;
        for (l, light) in self.lights.iter().enumerate().take(MASKED_LIGHTS) {
            if self.light_visible(sh, light) {
                mask |= 1 << l;
            }
        }
        mask
    }

    /// The weights' vertex at a camera hit: [`WeightVertex::at`] with its visibility bits.
    pub fn weight_vertex(&self, sh: &Shading) -> WeightVertex {
        WeightVertex::at(sh, self.visible_light_mask(sh))
    }

    /// L₀ leaving `v` towards the unit direction `wo` (W·m⁻²·sr⁻¹ per channel), from the
    /// vertex's stored visibility bits and its geometric-normal frame: the same evaluation for
    /// camera and photon vertices. Lights beyond [`MASKED_LIGHTS`] do not contribute.
    pub fn direct_masked(&self, v: &WeightVertex, wo: Vec3) -> Vec3 {
        if v.lights == 0 || v.n.dot(wo) <= 0.0 {
            return Vec3::ZERO;
        }
        let frame = Frame::from_normal(v.n);
        let bdf = self.bdf_at_vertex(v);
        let wo_l = frame.to_local(wo);
        let mut sum = Vec3::ZERO;
        for (l, light) in self.lights.iter().enumerate().take(MASKED_LIGHTS) {
            if v.lights & (1 << l) == 0 {
                continue;
            }
            let to = light.position - v.p;
            let d2 = to.length_squared();
            let wi = to / d2.sqrt();
            let cos = v.n.dot(wi);
            if cos > 0.0 {
                sum += bdf.eval(wo_l, frame.to_local(wi)) * light.intensity() * (cos / d2);
            }
        }
        sum
    }

    /// The part of [`Scene::direct`] at `sh` due to light `l`, with the shadow ray of a light
    /// `l < MASKED_LIGHTS` replaced by bit `l` of `lights` (the [`Scene::visible_light_mask`]
    /// of the same point, computed once for all its uses), W·m⁻²·sr⁻¹ per channel.
    #[inline]
    pub fn direct_from_masked(&self, sh: &Shading, wo: Vec3, l: usize, lights: u32) -> Vec3 {
        let light = &self.lights[l];
        if l < MASKED_LIGHTS {
            if lights & (1 << l) == 0 {
                return Vec3::ZERO;
            }
            self.direct_unshadowed(sh, wo, light)
        } else {
            self.direct_from(sh, wo, light)
        }
    }
}
