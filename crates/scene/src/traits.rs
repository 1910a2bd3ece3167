//! bdpm's [`Scene`] as the photon tracer and the radiance cache see it: the trait impls live
//! here, with the scene, so that `bdpm-photon` and `bdpm-cache` need neither the BVH nor the
//! BDF models.

use bdpm_bdf::{Transport, luminance, survival_at};
use bdpm_cache::CacheSurfaces;
use bdpm_photon::{AreaEmission, PhotonScene, Scatter};
use glam::Vec3;

use crate::{PointLight, Scene, Shading};

/// bdpm's own scene: flux-proportional light choice, its BVH, its BDFs (shading-frame
/// sampling, q = [`survival_at`]) and [`Scene::visible_light_mask`].
impl PhotonScene for Scene {
    #[inline]
    fn pick_light(&self, u: f32) -> (usize, f32) {
        Scene::pick_light(self, u)
    }

    #[inline]
    fn light(&self, index: usize) -> PointLight {
        self.lights()[index]
    }

    #[inline]
    fn is_area_light(&self, index: usize) -> bool {
        index >= self.lights().len()
    }

    fn emit_area(
        &self,
        index: usize,
        probability: f32,
        u_point: [f32; 2],
        u_dir: [f32; 2],
    ) -> Option<AreaEmission> {
        let e = self.emit_from_emitter(index - self.lights().len(), probability, u_point, u_dir)?;
        Some(AreaEmission {
            origin: e.origin,
            direction: e.direction,
            flux: e.flux,
        })
    }

    #[inline]
    fn intersect(&self, origin: Vec3, dir: Vec3) -> Option<Shading> {
        self.geometry()
            .intersect(origin, dir, f32::INFINITY)
            .map(|hit| self.shade(&hit, -dir))
    }

    #[inline]
    fn is_delta(&self, sh: &Shading) -> bool {
        Scene::is_delta(self, sh.material)
    }

    #[inline]
    fn scatter(&self, sh: &Shading, incoming: Vec3, u: [f32; 3]) -> (f32, Option<Scatter>) {
        if Scene::is_delta(self, sh.material) {
            return self.scatter_delta(sh, incoming, u[0]);
        }
        let bdf = self.bdf_at(sh);
        let in_local = bdf.outgoing(sh.frame.to_local(incoming));
        let survival = survival_at(&bdf, &in_local);
        let scatter = bdf.sample_at(&in_local, u).map(|s| Scatter {
            direction: sh.frame.to_world(s.wi),
            f: s.f,
            pdf: s.pdf,
            weight: s.weight,
        });
        (survival, scatter)
    }

    #[inline]
    fn spawn(&self, sh: &Shading, dir: Vec3) -> Vec3 {
        Scene::spawn(self, sh, dir)
    }

    #[inline]
    fn visible_light_mask(&self, sh: &Shading) -> u32 {
        Scene::visible_light_mask(self, sh)
    }

    #[inline]
    fn visible_light_mask_reached(&self, sh: &Shading, light: usize) -> u32 {
        Scene::visible_light_mask_reached(self, sh, light)
    }
}

impl Scene {
    /// [`PhotonScene::scatter`] at a delta vertex: survival q = the largest channel of the
    /// material's albedo for `incoming` (1 for clear glass and white mirrors, so lossless
    /// chains are never rouletted), and the delta step as a [`Scatter`] whose `f` and `pdf`
    /// are 0 (a delta has no value per steradian). Out of line and cold: inlined into the photon
    /// walk it cost scenes without delta materials 0.7 % of a pass's instructions.
    #[cold]
    #[inline(never)]
    fn scatter_delta(&self, sh: &Shading, incoming: Vec3, u: f32) -> (f32, Option<Scatter>) {
        let albedo = self.delta_albedo(sh, incoming).unwrap_or(Vec3::ZERO);
        let survival = albedo.max_element().clamp(0.0, 1.0);
        let step = self.delta_step(sh, incoming, u, Transport::Importance);
        let scatter = step.map(|s| Scatter {
            direction: s.direction,
            f: Vec3::ZERO,
            pdf: 0.0,
            weight: s.weight,
        });
        (survival, scatter)
    }
}

/// bdpm's own scene: its triangle mesh and materials.
impl CacheSurfaces for Scene {
    fn triangle_count(&self) -> usize {
        self.geometry().triangle_count()
    }
    fn triangle(&self, prim: u32) -> [Vec3; 3] {
        self.geometry().vertices(prim)
    }
    fn normal(&self, prim: u32) -> Vec3 {
        self.geometry().normal(prim)
    }
    fn area(&self, prim: u32) -> f32 {
        self.geometry().area(prim)
    }
    fn lambert_only(&self) -> bool {
        self.all_lambert()
    }
    fn lambert_albedo(&self, prim: u32) -> f32 {
        luminance(self.bdf(self.geometry().material(prim)).kd())
    }
}
