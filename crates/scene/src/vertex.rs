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
    /// [`Scene::light_visible`]): one shadow ray per light on the lit side; then, in a scene
    /// with emission, the emitters' bits ([`Scene::visible_emitter_mask`]).
    pub fn visible_light_mask(&self, sh: &Shading) -> u32 {
        let mut mask = 0;
        for (l, light) in self.lights.iter().enumerate().take(MASKED_LIGHTS) {
            if self.light_visible(sh, light) {
                mask |= 1 << l;
            }
        }
        if self.has_emission() {
            mask |= self.visible_emitter_mask(sh);
        }
        mask
    }

    /// [`Self::visible_light_mask`] at the first vertex `sh` of a photon path emitted by light
    /// `light`: that light's bit needs no shadow ray, since the emitted ray reached `sh`
    /// before anything else (only the side test remains). The others cast theirs.
    pub fn visible_light_mask_reached(&self, sh: &Shading, light: usize) -> u32 {
        let mut mask = 0;
        for (l, point) in self.lights.iter().enumerate().take(MASKED_LIGHTS) {
            let visible = if l == light {
                sh.ng.dot(point.position - sh.p) > 0.0
            } else {
                self.light_visible(sh, point)
            };
            if visible {
                mask |= 1 << l;
            }
        }
        if self.has_emission() {
            mask |= self.visible_emitter_mask(sh);
        }
        mask
    }

    /// The weights' vertex at a camera hit: [`WeightVertex::at`] with its visibility bits.
    pub fn weight_vertex(&self, sh: &Shading) -> WeightVertex {
        WeightVertex::at(sh, self.visible_light_mask(sh))
    }

    /// L₀ leaving `v` towards the unit direction `wo` (W·m⁻²·sr⁻¹ per channel), from the
    /// vertex's stored visibility bits and its geometric-normal frame: the same evaluation for
    /// camera and photon vertices. Lights beyond [`MASKED_LIGHTS`] do not contribute. Area
    /// lights contribute through their own bits ([`Scene::emitters_masked_sum`]).
    pub fn direct_masked(&self, v: &WeightVertex, wo: Vec3) -> Vec3 {
        if v.lights == 0 || v.n.dot(wo) <= 0.0 {
            return Vec3::ZERO;
        }
        let bdf = self.bdf_at_vertex(v);
        if bdf.is_lambert() {
            // The same bits without the frame: f = kd/π wherever both directions lie above the
            // surface, a direction's local z is its dot with the normal (the BDF's own test),
            // and a finite unit vector stays finite in any orthonormal frame.
            if !wo.is_finite() {
                return Vec3::ZERO;
            }
            let f = bdf.kd() * std::f32::consts::FRAC_1_PI;
            let f = |wi: Vec3| if wi.is_finite() { f } else { Vec3::ZERO };
            let points = self.masked_lights_sum(v, f);
            if !self.has_emission() {
                return points;
            }
            return points + self.emitters_masked_sum((v.p, v.n, v.lights), f);
        }
        let frame = Frame::from_normal(v.n);
        let wo_l = frame.to_local(wo);
        let f = |wi: Vec3| bdf.eval(wo_l, frame.to_local(wi));
        let points = self.masked_lights_sum(v, f);
        if !self.has_emission() {
            return points;
        }
        points + self.emitters_masked_sum((v.p, v.n, v.lights), f)
    }

    /// Σ f(ωᵢ)·I·cos/d² over the lights whose bit `v` holds and that lie above its normal, with
    /// f (sr⁻¹ per channel) given the unit direction ωᵢ from `v` to the light.
    fn masked_lights_sum(&self, v: &WeightVertex, f: impl Fn(Vec3) -> Vec3) -> Vec3 {
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
                sum += f(wi) * light.intensity() * (cos / d2);
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

#[cfg(test)]
mod tests {
    use bdpm_bdf::Bdf;
    use bdpm_geometry::{Frame, Geometry, TriangleMesh};
    use glam::{Vec2, Vec3};

    use crate::{Camera, PointLight, Scene, WeightVertex};

    /// L₀ as the general path computes it: the BDF evaluated in the normal's frame.
    fn direct_by_eval(scene: &Scene, v: &WeightVertex, wo: Vec3) -> Vec3 {
        if v.lights == 0 || v.n.dot(wo) <= 0.0 {
            return Vec3::ZERO;
        }
        let frame = Frame::from_normal(v.n);
        let bdf = scene.bdf_at_vertex(v);
        let mut sum = Vec3::ZERO;
        for (l, light) in scene.lights().iter().enumerate() {
            if v.lights & (1 << l) == 0 {
                continue;
            }
            let to = light.position - v.p;
            let d2 = to.length_squared();
            let wi = to / d2.sqrt();
            let cos = v.n.dot(wi);
            if cos > 0.0 {
                let f = bdf.eval(frame.to_local(wo), frame.to_local(wi));
                sum += f * light.intensity() * (cos / d2);
            }
        }
        sum
    }

    #[test]
    fn lambert_direct_light_without_the_frame_has_the_bits_of_the_bdf_evaluation() {
        let mut mesh = TriangleMesh::default();
        mesh.push_rect(Vec3::ZERO, Vec3::X * 4.0, Vec3::Y * 4.0, 0);
        let lights = vec![
            PointLight {
                position: Vec3::new(0.3, -0.2, 1.1),
                flux: Vec3::new(3.0, 2.0, 1.0),
            },
            PointLight {
                position: Vec3::new(-1.0, 0.5, -0.7),
                flux: Vec3::ONE,
            },
            PointLight {
                position: Vec3::new(0.9, 0.9, 0.01),
                flux: Vec3::splat(0.5),
            },
        ];
        let scene = Scene::one_material(
            Geometry::new(mesh).unwrap(),
            Bdf::lambert(Vec3::new(0.7, 0.4, 0.2)).unwrap(),
            lights,
            Camera::look_at(Vec3::Z * 3.0, Vec3::ZERO, Vec3::Y, 40.0, 8, 8).unwrap(),
        )
        .unwrap();
        let mut checked = 0;
        for i in 0..2000u32 {
            // A deterministic spread of points, tilted normals, directions and masks.
            let t = i as f32 * 0.618_034;
            let p = Vec3::new(t.sin() * 1.5, (t * 1.3).cos() * 1.5, 0.0);
            let n = Vec3::new((t * 2.1).sin() * 0.4, (t * 0.7).cos() * 0.4, 1.0).normalize();
            let wo = Vec3::new((t * 3.7).cos(), (t * 1.9).sin(), (t * 0.3).sin()).normalize();
            let v = WeightVertex {
                p,
                n,
                material: 0,
                prim: 0,
                bary: Vec2::ZERO,
                lights: i % 8,
            };
            let fast = scene.direct_masked(&v, wo);
            assert_eq!(fast, direct_by_eval(&scene, &v, wo), "vertex {i}");
            checked += (fast != Vec3::ZERO) as u32;
        }
        assert!(checked > 500, "only {checked} lit cases");
    }
}
