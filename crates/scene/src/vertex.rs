//! The one description of a candidate second vertex x₁ that the MIS weights read, shared by
//! the camera's x₁ and a photon's previous vertex y_p (docs/method.md §2: both techniques must
//! evaluate the same function w₁(x₀, x₁), so both must see the same inputs).

use std::borrow::Cow;

use bdpm_bdf::Bdf;
use bdpm_geometry::Frame;
use glam::Vec3;

use crate::{MASKED_LIGHTS, Scene, Shading, WeightVertex};

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
