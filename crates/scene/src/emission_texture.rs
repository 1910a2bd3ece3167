//! Emissive textures: Le(p) = the material's emission (glTF: `emissiveFactor` ×
//! `emissiveStrength`) × its emissive texture at p's texture coordinates, sampled as base-colour
//! textures are ([`Texture::sample`]: sRGB-decoded texels, bilinear, the sampler's wraps).
//!
//! Le then varies inside a triangle while the light distribution picks triangles in O(log n)
//! from one weight each. That weight is the triangle's mean Le, estimated once at a fixed
//! stratified set of points ([`mean_radiance`]); every estimator that samples a point of the
//! triangle divides Le at that point by the point's density (p(triangle)/A), so the estimate's
//! error changes only the variance, never the expectation.

use std::sync::Arc;

use bdpm_core::sampling::uniform_triangle;
use glam::{DVec3, Vec2, Vec3};

use crate::{Scene, SceneError, Texture};

/// The least share of a textured triangle's emission factor that its weight in the light
/// distribution keeps, per channel: a triangle whose stratified points all fall on black
/// texels while a lit texel lies between them is still picked, so the light samples and
/// photons that reach that texel exist (unbiased), at a cost of this share of wasted picks.
pub const EMISSION_PICK_FLOOR: f32 = 1e-3;

/// Fewest and most points per side of the stratified grid that estimates a triangle's mean Le
/// (16 to 1024 points): one per texel the triangle covers, within those bounds.
const GRID_SIDES: (u32, u32) = (4, 32);

/// The emissive textures of a scene, given to [`Scene::with_emission_textures`].
#[derive(Clone, Debug, Default)]
pub struct EmissionTextures {
    /// Per material index: its emissive texture, or `None`. Shorter than the material list
    /// means `None` for the rest.
    pub textures: Vec<Option<Arc<Texture>>>,
    /// Per triangle index: the texture coordinates of its vertices 0, 1, 2 for its material's
    /// emissive texture (zero where unused).
    pub texcoords: Vec<[Vec2; 3]>,
}

/// The mean of `factor` × `texture` over the triangle whose vertices have texture
/// coordinates `uv`, estimated at n × n points stratified by area (cell centres of the unit
/// square through the area-preserving map onto the triangle), n = √(texels covered) within
/// [`GRID_SIDES`]; at least [`EMISSION_PICK_FLOOR`] × `factor` per channel. W·m⁻²·sr⁻¹.
pub(crate) fn mean_radiance(factor: Vec3, texture: &Texture, uv: [Vec2; 3]) -> Vec3 {
    let (w, h) = texture.size();
    let uv_area = 0.5 * (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs();
    let texels = f64::from(uv_area) * f64::from(w) * f64::from(h);
    // NaN (non-finite coordinates) casts to 0 and takes the fewest points.
    let n = (texels.sqrt().ceil() as u32).clamp(GRID_SIDES.0, GRID_SIDES.1);
    let mut sum = DVec3::ZERO;
    for i in 0..n {
        for j in 0..n {
            let u = [(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32];
            let (b1, b2) = uniform_triangle(u);
            sum += texture
                .sample(interpolate(uv, Vec2::new(b1, b2)))
                .as_dvec3();
        }
    }
    let mean = factor * (sum / f64::from(n * n)).as_vec3();
    mean.max(factor * EMISSION_PICK_FLOOR)
}

/// The texture coordinates at barycentric point `bary` of a triangle whose vertices have `uv`.
#[inline]
fn interpolate(uv: [Vec2; 3], bary: Vec2) -> Vec2 {
    uv[0] * (1.0 - bary.x - bary.y) + uv[1] * bary.x + uv[2] * bary.y
}

impl Scene {
    /// Gives emitting materials emissive textures: Le at a point of such a material's triangle
    /// is its emission times the texture there ([`Scene::emission_at`]), and the light
    /// distribution weighs each of its triangles by the triangle's mean Le (estimated at a
    /// fixed stratified set of points). Textures of materials that do not emit are kept but
    /// change nothing. Without any texture the scene is returned as it was.
    pub fn with_emission_textures(mut self, t: EmissionTextures) -> Result<Scene, SceneError> {
        let any = t.textures.iter().any(Option::is_some);
        let fits = t.textures.len() <= self.materials.len()
            && (!any || t.texcoords.len() == self.geometry.triangle_count());
        if !fits {
            return Err(SceneError::BadTextures {
                textures: t.textures.len(),
                texcoords: t.texcoords.len(),
            });
        }
        let textured = |m: u32| t.textures.get(m as usize).and_then(Option::as_deref);
        if !self
            .emitters
            .list
            .iter()
            .any(|e| textured(self.geometry.material(e.prim)).is_some())
        {
            return Ok(self);
        }
        let mut texcoords = Vec::with_capacity(self.emitters.list.len());
        for e in &mut self.emitters.list {
            let m = self.geometry.material(e.prim);
            let uv = t.texcoords[e.prim as usize];
            texcoords.push(uv);
            if let Some(texture) = textured(m) {
                e.radiance = mean_radiance(self.materials[m as usize].emission, texture, uv);
            }
        }
        self.emitters.texcoords = texcoords;
        self.emitters.build_cdf();
        self.light_cdf = crate::light_cdf(&self.lights, &self.emitters)?;
        self.emission_textures = t.textures;
        Ok(self)
    }

    /// The emissive texture of a material index, if it has one.
    #[inline]
    pub fn emission_texture(&self, material: u32) -> Option<&Texture> {
        self.emission_textures
            .get(material as usize)
            .and_then(|t| t.as_deref())
    }

    /// Texture coordinates of the three vertices of emitting triangle `prim` for its
    /// material's emissive texture, if the scene has a textured emitter. For exporters.
    pub fn emission_texcoords(&self, prim: u32) -> Option<[Vec2; 3]> {
        let i = *self.emitters.of_prim.get(prim as usize)?;
        self.emitters.texcoords.get(i as usize).copied()
    }

    /// Emitted radiance Le at barycentric point `bary` of triangle `prim` on an emitting side,
    /// W·m⁻²·sr⁻¹ (0 if the triangle does not emit).
    pub fn emission_at(&self, prim: u32, bary: Vec2) -> Vec3 {
        match self.emitter_of(prim) {
            Some(_) => self.emitter_radiance(self.emitters.of_prim[prim as usize] as usize, bary),
            None => Vec3::ZERO,
        }
    }

    /// Le of emitter `i` (an index into [`Scene::emitters`]) at barycentric point `bary`:
    /// the emitter's constant radiance, or its material's emission × emissive texture.
    #[inline]
    pub(crate) fn emitter_radiance(&self, i: usize, bary: Vec2) -> Vec3 {
        let e = &self.emitters.list[i];
        let Some(&uv) = self.emitters.texcoords.get(i) else {
            return e.radiance;
        };
        let m = self.geometry.material(e.prim);
        match self.emission_texture(m) {
            Some(t) => self.materials[m as usize].emission * t.sample(interpolate(uv, bary)),
            None => e.radiance,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Camera, Material, PointLight, Wrap};
    use bdpm_bdf::{Bdf, luminance};
    use bdpm_core::{Domain, Rng};
    use bdpm_geometry::{Geometry, TriangleMesh};

    /// A 1 m × 1 m emitter in the plane y = 1 facing down (material 1, factor `factor`), over a
    /// Lambert floor (material 0), the emitter's texture coordinates spanning [0, 1]² once;
    /// `texture` is 2 × 1 texels: the left half (u < ½) and the right half.
    fn panel(factor: Vec3, left: Vec3, right: Vec3) -> Scene {
        let mut mesh = TriangleMesh::default();
        mesh.push_rect(Vec3::ZERO, Vec3::Z * 2.0, Vec3::X * 2.0, 0);
        mesh.push_rect(Vec3::Y, Vec3::X * 0.5, Vec3::Z * 0.5, 1);
        let lambert = |k: f32| Bdf::lambert(Vec3::splat(k)).unwrap();
        let materials = vec![
            Material::new("floor", lambert(0.5)),
            Material::new("panel", lambert(0.0)).with_emission(factor, false),
        ];
        let camera = Camera::look_at(Vec3::new(0.0, 1.0, -3.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 8);
        let geometry = Geometry::new(mesh).unwrap();
        // Texture coordinates from the vertex positions: u = x + ½, v = z + ½.
        let texcoords = (0..geometry.triangle_count() as u32)
            .map(|prim| {
                geometry
                    .vertices(prim)
                    .map(|p| Vec2::new(p.x + 0.5, p.z + 0.5))
            })
            .collect();
        let texture = Texture::new(2, 1, vec![left, right], Wrap::ClampToEdge, Wrap::Repeat);
        Scene::new(
            geometry,
            materials,
            Vec::<PointLight>::new(),
            camera.unwrap(),
        )
        .unwrap()
        .with_emission_textures(EmissionTextures {
            textures: vec![None, Some(Arc::new(texture.unwrap()))],
            texcoords,
        })
        .unwrap()
    }

    /// Le at a point is the factor times the texel there; the light distribution weighs each
    /// triangle by its mean over the triangle, which a quadrature of the same texture checks.
    #[test]
    fn le_is_factor_times_texture_and_the_weight_its_mean() {
        let factor = Vec3::new(2.0, 3.0, 4.0);
        let s = panel(factor, Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.5, 1.0));
        for e in s.emitters() {
            let [a, b, c] = s.geometry().vertices(e.prim);
            // A point near each corner lies in one half, away from the bilinear blend.
            for (p, bary) in [(a, Vec2::new(0.0, 0.0)), (b, Vec2::X), (c, Vec2::Y)] {
                let bary = bary * 0.98 + Vec2::splat(0.01);
                let want = if p.x < 0.0 {
                    factor * Vec3::new(1.0, 0.0, 0.0)
                } else {
                    factor * Vec3::new(0.0, 0.5, 1.0)
                };
                let got = s.emission_at(e.prim, bary);
                assert!(
                    (got - want).abs().max_element() < 1e-5,
                    "{got} against {want}"
                );
            }
            // The weight against a fine midpoint quadrature of Le over the triangle.
            let uv = s.emission_texcoords(e.prim).unwrap();
            let k = 400;
            let mut sum = DVec3::ZERO;
            for i in 0..k {
                for j in 0..k {
                    let u = [(i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32];
                    let (b1, b2) = uniform_triangle(u);
                    sum += s.emission_at(e.prim, Vec2::new(b1, b2)).as_dvec3();
                }
            }
            let exact = (sum / (k * k) as f64).as_vec3();
            let rel = (e.radiance - exact).abs() / exact.max(Vec3::splat(1e-6));
            assert!(rel.max_element() < 0.02, "{} against {exact}", e.radiance);
            assert_eq!(
                e.radiance,
                mean_radiance(factor, s.emission_texture(1).unwrap(), uv)
            );
        }
        assert!(s.emission_texture(0).is_none());
        assert_eq!(s.emission_at(0, Vec2::ZERO), Vec3::ZERO);
    }

    /// A black half still gets a weight (the floor), so a triangle's lit texels are never left
    /// unreachable; and a black point emits no photon.
    #[test]
    fn a_black_texture_keeps_a_floor_and_emits_nothing_where_black() {
        let factor = Vec3::splat(5.0);
        let s = panel(factor, Vec3::ZERO, Vec3::ZERO);
        for (i, e) in s.emitters().iter().enumerate() {
            assert_eq!(e.radiance, factor * EMISSION_PICK_FLOOR);
            assert!(s.light_probability(i) > 0.0);
            assert!(
                s.emit_from_emitter(i, 0.5, [0.3, 0.3], [0.5, 0.5])
                    .is_none()
            );
        }
    }

    /// Unbiased whatever the triangles' weights: with the two triangles' weights set 5× and
    /// 0.2× their mean Le, the flux of the photons (and the light samples' f·Le·cos/p at a
    /// floor point off the centre) over the textured panel still average to the exact Φ (and
    /// direct light) of its two halves, whose Le differ by a factor 9, within 4 standard
    /// errors. A photon or light sample that carried the triangle's weight instead of Le at
    /// its point would miss both.
    #[test]
    fn photons_and_light_samples_carry_le_over_their_density() {
        let factor = Vec3::splat(2.0);
        let (dark, bright) = (0.1f32, 0.9f32);
        let mut s = panel(factor, Vec3::splat(dark), Vec3::splat(bright));
        s.emitters.list[0].radiance *= 5.0;
        s.emitters.list[1].radiance *= 0.2;
        s.emitters.build_cdf();
        s.light_cdf = crate::light_cdf(&s.lights, &s.emitters).unwrap();
        // Φ = π·A·mean Le: each half 0.5 m², the bilinear blend symmetric about u = ½.
        let exact_flux = std::f64::consts::PI * 2.0 * f64::from(dark + bright) / 2.0;
        let mut rng = Rng::new(11, Domain::Other, [0; 3]);
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let (light, p) = s.pick_light(rng.uniform());
            let x = s
                .emit_from_emitter(light, p, rng.uniform2(), rng.uniform2())
                .map_or(0.0, |e| f64::from(luminance(e.flux)));
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
        assert!(
            (mean - exact_flux).abs() < 4.0 * se && se < 0.01 * exact_flux,
            "{mean} ± {se} against {exact_flux}"
        );
        // Direct light at a floor point under the bright side against a midpoint quadrature of
        // f·Le·cos·cosₑ/d².
        let (px, pz) = (0.3f64, 0.1f64);
        let from = Vec3::new(px as f32, 0.5, pz as f32);
        let hit = s.geometry().intersect(from, -Vec3::Y, 1.0).unwrap();
        let wo = Vec3::new(0.0, 1.0, -1.0).normalize();
        let sh = s.shade(&hit, wo);
        let k = 600;
        let mut exact = 0.0f64;
        for i in 0..k {
            for j in 0..k {
                let x = (i as f64 + 0.5) / k as f64 - 0.5;
                let z = (j as f64 + 0.5) / k as f64 - 0.5;
                let p = Vec3::new(x as f32, 1.0, z as f32);
                let le = f64::from(s.emission_at(emitter_at(&s, p), bary_at(&s, p)).x);
                let d2 = (x - px).powi(2) + 1.0 + (z - pz).powi(2);
                exact += 0.5 / std::f64::consts::PI * le / (d2 * d2) / (k * k) as f64;
            }
        }
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let x = f64::from(s.direct_area(&sh, wo, rng.uniform3(), false).x);
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
        assert!(
            (mean - exact).abs() < 4.0 * se && se < 0.01 * exact,
            "{mean} ± {se} against {exact}"
        );
    }

    /// The emitting triangle under point `p` of the panel, by a ray from below.
    fn emitter_at(s: &Scene, p: Vec3) -> u32 {
        s.geometry()
            .intersect(p - Vec3::Y * 0.5, Vec3::Y, 1.0)
            .unwrap()
            .prim
    }

    /// The barycentric coordinates of point `p` of the panel in its triangle.
    fn bary_at(s: &Scene, p: Vec3) -> Vec2 {
        s.geometry()
            .intersect(p - Vec3::Y * 0.5, Vec3::Y, 1.0)
            .unwrap()
            .uv
    }
}
