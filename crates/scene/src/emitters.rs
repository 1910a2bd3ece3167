//! Area lights: triangles whose material emits a radiance Le (W·m⁻²·sr⁻¹ per channel),
//! cosine emission on the front side of the triangle (the side its winding normal points
//! to) or on both sides. What the scene keeps of them ([`Emitters`]), how a shading point
//! samples one for its direct light ([`Scene::sample_emitter`], [`Scene::direct_area`]),
//! the density of that sample in solid angle ([`Scene::emitter_pdf`]), which a BDF sample
//! that hits an emitter needs for its MIS weight, and photon emission from them
//! ([`Scene::emit_from_emitter`]).
//!
//! A triangle is chosen in proportion to its emitted power, then a point on it: uniform in
//! the solid angle it covers from the shading point (spherical-triangle sampling,
//! [`crate::spherical`]) where that solid angle is at least [`SPHERICAL_MIN`] sr, uniform by
//! area otherwise. Which of the two is a function of the shading point and the triangle
//! alone, so a BDF sample that hits the emitter from the same point gets the same density for
//! its MIS weight ([`Scene::emitter_pdf`]). Why that threshold: docs/method-notes.md, "Area
//! lights: sampling".

use std::f32::consts::PI;

use bdpm_bdf::luminance;
use bdpm_core::sampling::uniform_triangle;
use bdpm_geometry::{Frame, Geometry};
use glam::{Vec2, Vec3};

use crate::spherical;
use crate::{Material, PointLight, Scene, Shading};

/// Solid angle (sr) of an emitting triangle, seen from a shading point, from which on a
/// light sample there takes its point uniform in solid angle rather than by area. Below it
/// the triangle is small or far enough that area sampling's density, p(e)/A · d²/|cos θₑ|,
/// varies little over it, and the trigonometry would cost more than it saves (measured:
/// docs/method-notes.md, "Area lights: sampling").
pub const SPHERICAL_MIN: f64 = 0.2;

/// Solid angle (sr) above which a light sample goes back to area sampling: near 2π (a point
/// almost on the emitter) the spherical triangle's angles approach π and its construction
/// divides by their vanishing sines (pbrt-v4 stops at the same value).
pub const SPHERICAL_MAX: f64 = 6.22;

/// One emitting triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emitter {
    /// Index of the triangle in the geometry.
    pub prim: u32,
    /// Emitted radiance Le, W·m⁻²·sr⁻¹ per channel: constant over the triangle, or, where
    /// the material has an emissive texture, its mean over the triangle estimated at a fixed
    /// stratified set of points (at least [`crate::EMISSION_PICK_FLOOR`] of the factor), the
    /// weight the light distribution gives the triangle; Le at a point is
    /// [`Scene::emission_at`].
    pub radiance: Vec3,
    /// Emits on both sides, not only on the side of the winding normal.
    pub two_sided: bool,
    /// Area of the triangle, m².
    pub area: f32,
}

impl Emitter {
    /// Emitted flux Φ = π·Le·A per emitting side, W per channel.
    pub fn flux(&self) -> Vec3 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        self.radiance * (PI * self.area * sides)
    }
}

/// The emitting triangles of a scene and the distribution that light sampling picks them
/// from (by flux luminance; a binary search, O(log n) per pick). Empty for a scene without
/// emission, which then holds no per-triangle table.
#[derive(Clone, Debug)]
pub(crate) struct Emitters {
    pub(crate) list: Vec<Emitter>,
    /// The solid angle (sr) from which on a light sample takes a triangle in solid angle
    /// ([`SPHERICAL_MIN`] unless a measurement sets another, [`Scene::set_spherical_min`]).
    spherical_min: f64,
    /// Per emitter: its centroid and the largest distance from it to a vertex (m), for a
    /// cheap bound on its solid angle.
    spheres: Vec<(Vec3, f32)>,
    /// Cumulative flux luminance of `list`, normalised to end at 1.
    cdf: Vec<f32>,
    /// Per triangle: its index in `list`, or `u32::MAX`; empty without emitters.
    pub(crate) of_prim: Vec<u32>,
    /// Per emitter: the texture coordinates of its vertices for its material's emissive
    /// texture; empty when no emitting material has one (`emission_texture.rs`).
    pub(crate) texcoords: Vec<[Vec2; 3]>,
}

impl Default for Emitters {
    fn default() -> Emitters {
        Emitters {
            list: Vec::new(),
            spherical_min: SPHERICAL_MIN,
            spheres: Vec::new(),
            cdf: Vec::new(),
            of_prim: Vec::new(),
            texcoords: Vec::new(),
        }
    }
}

impl Emitters {
    /// The emitters among `geometry`'s triangles whose material emits.
    pub(crate) fn new(geometry: &Geometry, materials: &[Material]) -> Emitters {
        if !materials.iter().any(Material::emits) {
            return Emitters::default();
        }
        let n = geometry.triangle_count();
        let mut of_prim = vec![u32::MAX; n];
        let mut list = Vec::new();
        for prim in 0..n as u32 {
            let m = &materials[geometry.material(prim) as usize];
            let area = geometry.area(prim);
            if m.emits() && area > 0.0 {
                of_prim[prim as usize] = list.len() as u32;
                list.push(Emitter {
                    prim,
                    radiance: m.emission,
                    two_sided: m.two_sided_emission,
                    area,
                });
            }
        }
        let spheres = list
            .iter()
            .map(|e| {
                let v = geometry.vertices(e.prim);
                let c = (v[0] + v[1] + v[2]) / 3.0;
                (c, v.iter().map(|x| x.distance(c)).fold(0.0, f32::max))
            })
            .collect();
        let mut emitters = Emitters {
            list,
            spherical_min: SPHERICAL_MIN,
            spheres,
            cdf: Vec::new(),
            of_prim,
            texcoords: Vec::new(),
        };
        emitters.build_cdf();
        emitters
    }

    /// (Re)builds the CDF from the emitters' fluxes.
    pub(crate) fn build_cdf(&mut self) {
        let mut acc = 0.0f64;
        let mut cdf: Vec<f32> = Vec::with_capacity(self.list.len());
        let fluxes: Vec<f64> = self
            .list
            .iter()
            .map(|e| luminance(e.flux()) as f64)
            .collect();
        let total: f64 = fluxes.iter().sum();
        for f in &fluxes {
            acc += f;
            cdf.push((acc / total) as f32);
        }
        self.cdf = cdf;
    }

    /// Picks an emitter by flux luminance for `u` in [0, 1): (index, probability).
    pub(crate) fn pick(&self, u: f32) -> (usize, f32) {
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.list.len() - 1);
        (i, self.probability(i))
    }

    /// Probability with which [`Self::pick`] returns emitter `i`.
    pub(crate) fn probability(&self, i: usize) -> f32 {
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        self.cdf[i] - lo
    }

    /// Total flux luminance, W.
    pub(crate) fn total_flux(&self) -> Vec3 {
        self.list.iter().map(Emitter::flux).sum()
    }
}

/// A point sampled on an emitter for the direct light at a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterSample {
    /// Position on the emitter, m.
    pub p: Vec3,
    /// Unit winding normal of the emitter's triangle.
    pub n: Vec3,
    /// The emitter's triangle.
    pub prim: u32,
    /// Barycentric coordinates (b1, b2) of `p` in the triangle (vertex 0's weight 1 − b1 − b2).
    pub bary: Vec2,
    /// Density of the direction from the shading point to `p` in solid angle, the emitter's
    /// choice included, sr⁻¹ (the same as [`Scene::emitter_pdf`] gives for it).
    pub pdf: f32,
}

/// A photon leaving an emitter ([`Scene::emit_from_emitter`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterPhoton {
    /// Ray origin, pushed off the emitter to the side of `direction`, m.
    pub origin: Vec3,
    /// Unit direction, cosine-distributed about the emitting side's normal.
    pub direction: Vec3,
    /// Flux the photon stands for before the division by N_F: Le(p)·π·A·sides / p(emitter),
    /// W per channel, with Le at the photon's point p.
    pub flux: Vec3,
}

impl Scene {
    /// The emitting triangles (empty without emission).
    #[inline]
    pub fn emitters(&self) -> &[Emitter] {
        &self.emitters.list
    }

    /// True iff some triangle emits: without, every path runs as in a point-light scene.
    #[inline]
    pub fn has_emission(&self) -> bool {
        !self.emitters.list.is_empty()
    }

    /// Radiance emitted at barycentric point `bary` of triangle `prim` towards the unit world
    /// direction `wo` (pointing away from it), W·m⁻²·sr⁻¹: Le there on an emitting side
    /// (textured where the material has an emissive texture), else 0.
    #[inline]
    pub fn emitted(&self, prim: u32, bary: Vec2, wo: Vec3) -> Vec3 {
        if !self.has_emission() {
            return Vec3::ZERO;
        }
        let Some(e) = self.emitter_of(prim) else {
            return Vec3::ZERO;
        };
        if e.two_sided || self.geometry.normal(prim).dot(wo) > 0.0 {
            self.emitter_radiance(self.emitters.of_prim[prim as usize] as usize, bary)
        } else {
            Vec3::ZERO
        }
    }

    /// The point on an area light that a light path arriving at its first vertex y (position
    /// `p`, unit geometric normal `n`, triangle `prim`) along the unit direction `incoming`
    /// (pointing from y towards the light) left from, found by tracing back along `incoming`,
    /// and its densities. Both techniques of a path can find it: a photon keeps its arrival
    /// direction, a light sample or a BDF ray has its own. `None` where the ray meets no
    /// emitter, or an emitter's back.
    pub fn area_light_end(
        &self,
        p: Vec3,
        n: Vec3,
        prim: u32,
        incoming: Vec3,
    ) -> Option<AreaLightEnd> {
        let side = if n.dot(incoming) >= 0.0 { 1.0 } else { -1.0 };
        let origin = p + n * (side * self.geometry.spawn_offset(prim));
        let hit = self.geometry.intersect(origin, incoming, f32::INFINITY)?;
        let e = self.emitter_of(hit.prim)?;
        let cos_l = self.geometry.normal(hit.prim).dot(-incoming);
        if cos_l == 0.0 || (!e.two_sided && cos_l < 0.0) {
            return None;
        }
        let index = self.emitters.of_prim[hit.prim as usize] as usize;
        let sides = if e.two_sided { 2.0 } else { 1.0 };
        let pick = self.light_probability(self.lights().len() + index) as f64;
        let d2 = (hit.p - p).length_squared() as f64;
        let cos_y = n.dot(incoming).abs() as f64;
        Some(AreaLightEnd {
            position_density: pick / (e.area as f64 * sides),
            vertex_density: cos_l.abs() as f64 / std::f64::consts::PI * cos_y / d2,
            light_sample_density: self.emitter_pdf(p, hit.prim, hit.p) as f64,
        })
    }

    /// The emitter on triangle `prim`, if it emits.
    pub(crate) fn emitter_of(&self, prim: u32) -> Option<&Emitter> {
        let i = *self.emitters.of_prim.get(prim as usize)?;
        self.emitters.list.get(i as usize)
    }

    /// Solid-angle density (sr⁻¹) with which [`Self::sample_emitter`] from `from` yields the
    /// point `p` of triangle `prim`: p(emitter)/Ω where it samples that triangle in solid angle
    /// from `from`, else p(emitter)/A · d²/|cos θₑ|. 0 where `prim` emits nothing towards
    /// `from`.
    pub fn emitter_pdf(&self, from: Vec3, prim: u32, p: Vec3) -> f32 {
        let Some(e) = self.emitter_of(prim) else {
            return 0.0;
        };
        let to = from - p;
        let d2 = to.length_squared();
        let cos = self.geometry.normal(prim).dot(to) / d2.sqrt();
        if d2 <= 0.0 || cos == 0.0 || (!e.two_sided && cos < 0.0) {
            return 0.0;
        }
        let i = self.emitters.of_prim[prim as usize] as usize;
        let pick = self.emitters.probability(i);
        match self.spherical_solid_angle(i, from) {
            Some(omega) => (pick as f64 / omega) as f32,
            None => pick / e.area * d2 / cos.abs(),
        }
    }

    /// The solid angle (sr) of emitter `i` seen from `from` where a light sample there takes
    /// it in solid angle ([`SPHERICAL_MIN`] to [`SPHERICAL_MAX`]), else `None`: the one rule
    /// that sampling and [`Self::emitter_pdf`] share.
    fn spherical_solid_angle(&self, i: usize, from: Vec3) -> Option<f64> {
        let e = &self.emitters.list[i];
        let (centre, radius) = self.emitters.spheres[i];
        // Ω = ∫ h/d³ dA ≤ A·h/d_min³, with h the distance to the triangle's plane and d_min ≥
        // max(h, |from − centre| − radius): most emitters are far below the threshold, and
        // this spares them the exact Ω (three normalisations and an atan2 in f64).
        let to = from - centre;
        let h = self.geometry.normal(e.prim).dot(to).abs();
        let d_min = h.max(to.length() - radius);
        if d_min > 0.0
            && (e.area as f64 * h as f64) < self.emitters.spherical_min * (d_min as f64).powi(3)
        {
            return None;
        }
        let omega = spherical::solid_angle(from, self.geometry.vertices(e.prim));
        (self.emitters.spherical_min..=SPHERICAL_MAX)
            .contains(&omega)
            .then_some(omega)
    }

    /// Sets the solid angle (sr) from which on light samples take an emitting triangle in
    /// solid angle (default [`SPHERICAL_MIN`]; `f64::INFINITY`: area sampling everywhere, 0:
    /// solid angle wherever it is below [`SPHERICAL_MAX`]). Sampling and [`Self::emitter_pdf`]
    /// follow it together, so every value gives an unbiased image; it is there to measure the
    /// rule (tests/suite/area_lights.rs, `spherical_sampling_threshold`).
    pub fn set_spherical_min(&mut self, sr: f64) {
        self.emitters.spherical_min = sr;
    }

    /// A point on an emitter for the direct light at `from`: the emitter picked by flux with
    /// `u_pick`, the point uniform in the solid angle it covers from `from` or uniform by area
    /// (the module's rule) with `u_point`. `None` without emitters or where the triangle has
    /// no extent seen from `from`.
    pub fn sample_emitter(
        &self,
        from: Vec3,
        u_pick: f32,
        u_point: [f32; 2],
    ) -> Option<EmitterSample> {
        if !self.has_emission() {
            return None;
        }
        let (i, pick) = self.emitters.pick(u_pick);
        let e = &self.emitters.list[i];
        let v = self.geometry.vertices(e.prim);
        let n = self.geometry.normal(e.prim);
        let at = |b1: f32, b2: f32| v[0] * (1.0 - b1 - b2) + v[1] * b1 + v[2] * b2;
        if let Some(omega) = self.spherical_solid_angle(i, from) {
            let (b1, b2, _) = spherical::sample(from, v, u_point)?;
            return Some(EmitterSample {
                p: at(b1, b2),
                n,
                prim: e.prim,
                bary: Vec2::new(b1, b2),
                pdf: (pick as f64 / omega) as f32,
            });
        }
        let (b1, b2) = uniform_triangle(u_point);
        let p = at(b1, b2);
        let to = from - p;
        let d2 = to.length_squared();
        let cos = n.dot(to) / d2.sqrt();
        if d2 <= 0.0 || cos == 0.0 {
            return None;
        }
        Some(EmitterSample {
            p,
            n,
            prim: e.prim,
            bary: Vec2::new(b1, b2),
            pdf: pick / e.area * d2 / cos.abs(),
        })
    }

    /// Direct light from the area lights leaving `sh` towards `wo` by one light sample
    /// (numbers `u`), W·m⁻²·sr⁻¹: f·Le·cos/p_ω with its shadow ray. With `mis`, weighted
    /// by the power heuristic against sampling the BDF at `sh` (whose hits on emitters then
    /// take [`Self::emitted_mis`]); without, the whole of it. 0 without emitters.
    #[inline]
    pub fn direct_area(&self, sh: &Shading, wo: Vec3, u: [f32; 3], mis: bool) -> Vec3 {
        self.direct_area_sample(sh, wo, u, mis)
            .map_or(Vec3::ZERO, |(c, _)| c)
    }

    /// [`Self::direct_area`] with the unit direction from `sh` to the sampled point: `None`
    /// where the sample contributes nothing.
    pub fn direct_area_sample(
        &self,
        sh: &Shading,
        wo: Vec3,
        u: [f32; 3],
        mis: bool,
    ) -> Option<(Vec3, Vec3)> {
        let s = self.sample_emitter(sh.p, u[0], [u[1], u[2]])?;
        let to = s.p - sh.p;
        let d2 = to.length_squared();
        if d2 <= 0.0 {
            return None;
        }
        let wi = to / d2.sqrt();
        let le = self.emitted(s.prim, s.bary, -wi);
        let cos_e = s.n.dot(wi).abs();
        if le == Vec3::ZERO || cos_e <= 0.0 || sh.ng.dot(wi) <= 0.0 {
            return None;
        }
        let f = self.eval(sh, wo, wi);
        let cos = sh.frame.n.dot(wi);
        if f == Vec3::ZERO || cos <= 0.0 {
            return None;
        }
        // The light's end pushed off its triangle towards sh, so the emitter itself does not
        // block the segment.
        let side = if s.n.dot(wi) < 0.0 { 1.0 } else { -1.0 };
        let end = s.p + s.n * (side * self.geometry.spawn_offset(s.prim));
        // Through the point lights' shadow test, so that the ray kernel keeps one call site in
        // this crate and stays inlined there (a second site cost point-light scenes about 1 % of
        // a pass's instructions).
        let at = PointLight {
            position: end,
            flux: Vec3::ZERO,
        };
        if !self.light_visible(sh, &at) {
            return None;
        }
        let pdf = s.pdf;
        let weight = if mis {
            let bdf = self.bdf_at(sh);
            power_heuristic(pdf, bdf.pdf(sh.frame.to_local(wo), sh.frame.to_local(wi)))
        } else {
            1.0
        };
        let c = f * le * (cos * weight / pdf);
        c.is_finite().then_some((c, wi))
    }

    /// The BDF-sampled strategy of the area lights' direct light at `sh` towards `wo` (numbers
    /// `u`): one direction from the BDF, its ray traced, and where the ray's first hit is an
    /// emitter seen from its emitting side, f·cos/p·Le weighted by the power heuristic against
    /// [`Self::direct_area`]'s light sample (W·m⁻²·sr⁻¹), with the unit direction. The two
    /// together (`direct_area` with `mis`) estimate the direct light unbiasedly. `None` where the
    /// sample brings nothing: no direction, a ray below the geometric surface, a hit that is
    /// not an emitter, or a mirror or glass (an emitter behind one is not direct light).
    pub fn emitter_hit_by_bdf(&self, sh: &Shading, wo: Vec3, u: [f32; 3]) -> Option<(Vec3, Vec3)> {
        let bdf = self.bdf_at(sh);
        let s = bdf.sample_at(&bdf.outgoing(sh.frame.to_local(wo)), u)?;
        let wi = sh.frame.to_world(s.wi);
        if sh.ng.dot(wi) <= 0.0 {
            return None;
        }
        let hit = self
            .geometry
            .intersect(self.spawn(sh, wi), wi, f32::INFINITY)?;
        if self.is_delta(hit.material) {
            return None;
        }
        let le = self.emitted_mis(sh.p, s.pdf, hit.prim, hit.p, hit.uv);
        if le == Vec3::ZERO {
            return None;
        }
        let c = s.weight * le;
        c.is_finite().then_some((c, wi))
    }

    /// Radiance emitted by the triangle of a BDF sample's hit (`prim`, at `p`, barycentric
    /// point `bary`) back towards the vertex `from` it was sampled at with solid-angle density
    /// `pdf_bdf` (sr⁻¹), weighted by the power heuristic against [`Self::direct_area`]'s light
    /// sample there.
    pub fn emitted_mis(&self, from: Vec3, pdf_bdf: f32, prim: u32, p: Vec3, bary: Vec2) -> Vec3 {
        let wo = (from - p).normalize_or_zero();
        let le = self.emitted(prim, bary, wo);
        if le == Vec3::ZERO {
            return Vec3::ZERO;
        }
        le * power_heuristic(pdf_bdf, self.emitter_pdf(from, prim, p))
    }

    /// A photon from the area lights: emitter `index` (chosen with probability
    /// `probability` by the caller's light distribution), a point uniform on it (`u_point`),
    /// a side (`u_dir[0]` for a two-sided one) and a cosine-distributed direction. Its flux
    /// carries Le at its point over the density of that point, so that a textured emitter,
    /// picked by its mean Le, stays unbiased; `None` where Le is 0 there.
    pub fn emit_from_emitter(
        &self,
        index: usize,
        probability: f32,
        u_point: [f32; 2],
        u_dir: [f32; 2],
    ) -> Option<EmitterPhoton> {
        let e = self.emitters.list.get(index)?;
        if probability <= 0.0 || probability.is_nan() {
            return None;
        }
        let [a, b, c] = self.geometry.vertices(e.prim);
        let (b1, b2) = uniform_triangle(u_point);
        let p = a * (1.0 - b1 - b2) + b * b1 + c * b2;
        let mut n = self.geometry.normal(e.prim);
        let mut u = u_dir;
        if e.two_sided {
            // The first number chooses the side and is reused, rescaled, for the direction.
            if u[0] < 0.5 {
                u[0] *= 2.0;
            } else {
                n = -n;
                u[0] = u[0] * 2.0 - 1.0;
            }
        }
        let local = cosine_hemisphere(u);
        let direction = Frame::from_normal(n).to_world(local);
        let origin = p + n * self.geometry.spawn_offset(e.prim);
        let flux = if self.emitters.texcoords.is_empty() {
            e.flux() / probability
        } else {
            let le = self.emitter_radiance(index, Vec2::new(b1, b2));
            if le == Vec3::ZERO {
                return None;
            }
            Emitter { radiance: le, ..*e }.flux() / probability
        };
        Some(EmitterPhoton {
            origin,
            direction,
            flux,
        })
    }
}

/// The power heuristic p_a²/(p_a² + p_b²) of a sample drawn with density `a` against the
/// other strategy's density `b` for the same direction (1 where `b` is 0), written with the
/// ratio of the smaller to the larger so that it neither overflows nor underflows.
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    if a == b {
        return if a > 0.0 { 0.5 } else { 1.0 };
    }
    if a > b {
        let r = b / a;
        1.0 / (1.0 + r * r)
    } else {
        let r = a / b;
        r * r / (1.0 + r * r)
    }
}

/// A cosine-distributed direction about +z (density cos θ/π sr⁻¹), from the concentric disk.
#[inline]
pub fn cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let d = bdpm_core::sampling::concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// The most emitters that get a visibility bit in a [`crate::WeightVertex`]'s `lights` (after
/// the point lights' bits, within [`crate::MASKED_LIGHTS`]): each costs a shadow ray per weight
/// vertex (every camera x₁ and every stored photon vertex), so a mesh light of many triangles
/// is seen by the weights through its first few alone.
pub const MASKED_EMITTERS: usize = 8;

/// Where a light path from the area lights began, seen from its first vertex y
/// ([`Scene::area_light_end`]): the densities that the balance-type weights and `camis` read
/// for the path's light end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLightEnd {
    /// Density of the emitted point on the lights, m⁻²: its emitter's probability among all
    /// lights over the emitter's area, halved for a two-sided emitter (the photon tracer's).
    pub position_density: f64,
    /// Density of y given that point, m⁻²: cos θₗ/π · |cos θ_y|/d² (cosine emission).
    pub vertex_density: f64,
    /// Solid-angle density at y with which a light sample yields that point, sr⁻¹
    /// ([`Scene::emitter_pdf`]).
    pub light_sample_density: f64,
}

impl Scene {
    /// The emitters with a visibility bit in a weight vertex's `lights` and the bit of the first:
    /// (first bit, count). The bits follow the point lights' (the first
    /// min(point lights, [`crate::MASKED_LIGHTS`]) bits), so a scene without emission has none.
    #[inline]
    pub fn masked_emitters(&self) -> (usize, usize) {
        let first = self.lights().len().min(crate::MASKED_LIGHTS);
        let count = self
            .emitters
            .list
            .len()
            .min(MASKED_EMITTERS)
            .min(crate::MASKED_LIGHTS - first);
        (first, count)
    }

    /// The emitters' visibility bits at `sh` (see [`Self::masked_emitters`]): bit set iff the
    /// centroid of the emitter's triangle lies above `sh`, emits towards it and is not
    /// blocked. 0 without emission. One shadow ray per masked emitter, the weights' stand-in for
    /// the area light's visible fraction (method-notes.md, "Area lights: the ingredients").
    pub fn visible_emitter_mask(&self, sh: &Shading) -> u32 {
        let (first, count) = self.masked_emitters();
        let mut mask = 0;
        for (k, e) in self.emitters.list.iter().take(count).enumerate() {
            let centre = self.emitter_centroid(e);
            let n = self.geometry.normal(e.prim);
            let to_sh = sh.p - centre;
            let facing = n.dot(to_sh);
            if facing == 0.0 || (!e.two_sided && facing < 0.0) {
                continue;
            }
            // Pushed off the triangle towards sh, as the light sample's shadow ray does.
            let side = if facing > 0.0 { 1.0 } else { -1.0 };
            let at = PointLight {
                position: centre + n * (side * self.geometry.spawn_offset(e.prim)),
                flux: Vec3::ZERO,
            };
            if self.light_visible(sh, &at) {
                mask |= 1 << (first + k);
            }
        }
        mask
    }

    /// The area lights' direct light leaving the weight vertex at `p` (unit normal `n`) as the
    /// weights read it from the visibility bits `lights`, W·m⁻²·sr⁻¹ per channel, with the BDF
    /// value `f` (sr⁻¹ per channel) given the unit direction ωᵢ to an emitter's centroid: per
    /// visible masked emitter Le·f·cos θᵢ·A·|cos θₑ|/(d² + A/π), the centroid's point-light
    /// term with d² kept above A/π (the on-axis irradiance of a disk of area A is
    /// π·Le·A/(π·d² + A), so the term stays finite on the emitter and is exact there for a disk).
    /// A deterministic function of the vertex, so both techniques read the same number.
    pub fn emitters_masked_sum(
        &self,
        (p, n, lights): (Vec3, Vec3, u32),
        f: impl Fn(Vec3) -> Vec3,
    ) -> Vec3 {
        let (first, count) = self.masked_emitters();
        let mut sum = Vec3::ZERO;
        for (k, e) in self.emitters.list.iter().take(count).enumerate() {
            if lights & (1 << (first + k)) == 0 {
                continue;
            }
            let to = self.emitter_centroid(e) - p;
            let d2 = to.length_squared();
            if d2 <= 0.0 {
                continue;
            }
            let wi = to / d2.sqrt();
            let cos = n.dot(wi);
            let cos_e = self.geometry.normal(e.prim).dot(wi).abs();
            if cos > 0.0 {
                let g = cos * e.area * cos_e / (d2 + e.area * std::f32::consts::FRAC_1_PI);
                sum += f(wi) * e.radiance * g;
            }
        }
        sum
    }

    /// The centroid of emitter `e`'s triangle, m.
    fn emitter_centroid(&self, e: &Emitter) -> Vec3 {
        let [a, b, c] = self.geometry.vertices(e.prim);
        (a + b + c) / 3.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Camera;
    use crate::test_stats::mean_se;
    use bdpm_bdf::Bdf;
    use bdpm_core::{Domain, Rng};
    use bdpm_geometry::TriangleMesh;

    /// A floor (material 0, Lambert 0.5, 4 m × 4 m at y = 0 facing +y) under two emitters
    /// facing down: material 1 (a × b = 0.4 m × 0.2 m at height 1, Le = (1, 2, 3)) and
    /// material 2 (two-sided, 0.2 m × 0.2 m at x = 1, height 0.5, Le = 5), plus a point light
    /// of flux `point` unless it is zero.
    fn scene(point: f32) -> Scene {
        scene_with_lamp_at(point, 1.0)
    }

    #[test]
    fn a_light_path_s_area_light_end_is_found_and_weighed() {
        // From the floor point y straight up into the lamp (Le = (1, 2, 3), 0.08 m² facing
        // down, one-sided) and slanted to another of its points; the panel (Le = 5, 0.04 m²,
        // two-sided) makes the choice of light. The photon tracer picks a triangle by flux
        // luminance, so the density of a lamp point is lum(Le_lamp)/Σ lum(Le)·A·sides.
        let s = scene(0.0);
        let lum = |v: Vec3| 0.2126 * v.x as f64 + 0.7152 * v.y as f64 + 0.0722 * v.z as f64;
        let total = lum(Vec3::new(1.0, 2.0, 3.0)) * 0.08 + lum(Vec3::splat(5.0)) * 0.04 * 2.0;
        let position = lum(Vec3::new(1.0, 2.0, 3.0)) / total;
        let y = Vec3::new(0.05, 0.0, 0.02);
        let floor = s.geometry().intersect(y + Vec3::Y, -Vec3::Y, 2.0).unwrap();
        for target in [Vec3::new(0.05, 1.0, 0.02), Vec3::new(0.15, 1.0, 0.08)] {
            let to = target - floor.p;
            let incoming = to.normalize();
            let end = s
                .area_light_end(floor.p, floor.ng, floor.prim, incoming)
                .expect("the lamp is straight above");
            let cos = incoming.y as f64;
            let d2 = to.length_squared() as f64;
            assert!(
                (end.position_density / position - 1.0).abs() < 1e-5,
                "{end:?}"
            );
            let vertex = cos * cos / (std::f64::consts::PI * d2);
            assert!((end.vertex_density / vertex - 1.0).abs() < 1e-4, "{end:?}");
            let hit = floor.p + incoming * (1.0 / incoming.y);
            let prim = s
                .geometry()
                .intersect(floor.p + Vec3::Y * 1e-3, incoming, 2.0)
                .unwrap()
                .prim;
            let pdf = s.emitter_pdf(floor.p, prim, hit) as f64;
            assert!(
                (end.light_sample_density / pdf - 1.0).abs() < 1e-4,
                "{end:?} vs {pdf}"
            );
        }
        // Past the lamp: nothing; from above the lamp: its back.
        let away = Vec3::new(1.0, 1.0, 1.0).normalize();
        assert!(
            s.area_light_end(floor.p, floor.ng, floor.prim, away)
                .is_none()
        );
        assert!(
            s.area_light_end(Vec3::new(0.0, 2.0, 0.0), Vec3::Y, floor.prim, -Vec3::Y)
                .is_none()
        );
    }

    /// [`scene`] with the lamp at height `h` (m).
    fn scene_with_lamp_at(point: f32, h: f32) -> Scene {
        let mut mesh = TriangleMesh::default();
        mesh.push_rect(Vec3::ZERO, Vec3::Z * 2.0, Vec3::X * 2.0, 0);
        mesh.push_rect(Vec3::Y * h, Vec3::X * 0.2, Vec3::Z * 0.1, 1);
        mesh.push_rect(Vec3::new(1.0, 0.5, 0.0), Vec3::X * 0.1, Vec3::Z * 0.1, 2);
        let lambert = |k: f32| Bdf::lambert(Vec3::splat(k)).unwrap();
        let materials = vec![
            Material::new("floor", lambert(0.5)),
            Material::new("lamp", lambert(0.0)).with_emission(Vec3::new(1.0, 2.0, 3.0), false),
            Material::new("panel", lambert(0.0)).with_emission(Vec3::splat(5.0), true),
        ];
        let lights = if point > 0.0 {
            vec![PointLight {
                position: Vec3::new(-1.0, 1.0, 0.0),
                flux: Vec3::splat(point),
            }]
        } else {
            Vec::new()
        };
        let camera = Camera::look_at(Vec3::new(0.0, 1.0, -3.0), Vec3::ZERO, Vec3::Y, 40.0, 8, 8);
        Scene::new(
            Geometry::new(mesh).unwrap(),
            materials,
            lights,
            camera.unwrap(),
        )
        .unwrap()
    }

    #[test]
    fn the_light_distribution_is_proportional_to_flux() {
        let s = scene(2.0);
        assert_eq!(s.emitters().len(), 4);
        // Lamp: π·Le·A, one side, per triangle of half the 0.08 m²; panel: both sides.
        let lamp = luminance(Vec3::new(1.0, 2.0, 3.0)) * PI * 0.04;
        let panel = 5.0 * PI * 0.02 * 2.0;
        let point = 2.0;
        let total = point + 2.0 * lamp + 2.0 * panel;
        let want = [point, lamp, lamp, panel, panel].map(|f| f / total);
        for (i, w) in want.iter().enumerate() {
            let p = s.light_probability(i);
            assert!((p - w).abs() < 1e-6, "light {i}: {p} against {w}");
        }
        // pick_light returns each index with its probability (the CDF's steps).
        let mut counts = [0u32; 5];
        let n = 100_000;
        for k in 0..n {
            let (i, p) = s.pick_light((k as f32 + 0.5) / n as f32);
            assert_eq!(p, s.light_probability(i));
            counts[i] += 1;
        }
        for (i, w) in want.iter().enumerate() {
            let got = counts[i] as f32 / n as f32;
            assert!((got - w).abs() < 2e-5, "light {i}: {got} against {w}");
        }
        // The emitters alone, for direct light: the same shares without the point light.
        for (i, w) in [lamp, lamp, panel, panel].iter().enumerate() {
            let want = w / (total - point);
            assert!((s.emitters.probability(i) - want).abs() < 1e-6);
        }
        let flux = s.total_flux();
        assert!((luminance(flux) - total).abs() < 1e-4 * total, "{flux}");
    }

    /// E[1/p_ω] over light samples is the solid angle the emitters cover from the shading
    /// point (counting each point an emitter lights once), here the lamp alone seen from
    /// under its centre: Ω = 4·asin(ab/√((a² + 4h²)(b² + 4h²))), at a height h below it where
    /// its triangles are sampled by area (far) and where they are sampled in solid angle
    /// (near). Also each sample's density is the one `emitter_pdf` gives for its point.
    #[test]
    fn light_sampling_density_integrates_to_the_solid_angle() {
        let s = scene(0.0);
        let (a, b) = (0.4f64, 0.2);
        for (h, spherical) in [(1.0f64, false), (0.1, true)] {
            let from = Vec3::new(0.0, (1.0 - h) as f32, 0.0);
            let lamp_prim = s.emitters()[0].prim;
            let omega = spherical::solid_angle(from, s.geometry.vertices(lamp_prim));
            assert_eq!(s.spherical_solid_angle(0, from).is_some(), spherical);
            let exact =
                4.0 * (a * b / ((a * a + 4.0 * h * h) * (b * b + 4.0 * h * h)).sqrt()).asin();
            let mut rng = Rng::new(3, Domain::Other, [0; 3]);
            let (mean, se) = mean_se(200_000, || {
                let e = s
                    .sample_emitter(from, rng.uniform(), rng.uniform2())
                    .unwrap();
                let own = s.emitter_pdf(from, e.prim, e.p);
                assert!(
                    (own - e.pdf).abs() <= 1e-5 * e.pdf,
                    "{own} against {}",
                    e.pdf
                );
                let lamp = s.geometry.material(e.prim) == 1;
                if lamp { 1.0 / e.pdf as f64 } else { 0.0 }
            });
            assert!(
                (mean - exact).abs() < 4.0 * se + 1e-5 * exact,
                "h = {h} (triangle's Ω {omega}): {mean} ± {se} against {exact}"
            );
            assert!(
                se < 0.02 * exact,
                "the test could not fail: {se} against {exact}"
            );
        }
    }

    /// The direct light of the area lights at a floor point, by light sampling, against a
    /// midpoint quadrature of ∫ f·Le·cos θ·cos θₑ/d² dA over both emitters (400 × 400 cells
    /// each; the panel's both sides, the floor sees its lower one): with the lamp 1 m up,
    /// whose triangles are sampled by area, and 0.1 m up, in solid angle.
    #[test]
    fn direct_area_light_matches_quadrature() {
        for (h, p, spherical) in [
            (1.0f32, Vec3::new(0.3, 0.0, 0.2), false),
            (0.1, Vec3::new(0.15, 0.0, 0.05), true),
        ] {
            let s = scene_with_lamp_at(0.0, h);
            let hit = s
                .geometry
                .intersect(p + Vec3::Y * 0.01, -Vec3::Y, 2.0)
                .unwrap();
            let wo = Vec3::new(0.0, 1.0, -1.0).normalize();
            let sh = s.shade(&hit, wo);
            for i in 0..2 {
                assert_eq!(s.spherical_solid_angle(i, sh.p).is_some(), spherical);
            }
            let quad = |c: Vec3, u: Vec3, v: Vec3, le: f64| {
                let k = 400;
                let area = (4.0 * u.length() * v.length()) as f64;
                let mut sum = 0.0f64;
                for i in 0..k {
                    for j in 0..k {
                        let x = c
                            + u * (2.0 * (i as f32 + 0.5) / k as f32 - 1.0)
                            + v * (2.0 * (j as f32 + 0.5) / k as f32 - 1.0);
                        let to = (x - sh.p).as_dvec3();
                        let d2 = to.length_squared();
                        let cos = to.y / d2.sqrt();
                        sum += cos * cos / d2;
                    }
                }
                0.5 / std::f64::consts::PI * le * sum * area / (k * k) as f64
            };
            let lamp = quad(Vec3::Y * h, Vec3::X * 0.2, Vec3::Z * 0.1, 1.0);
            let panel = quad(Vec3::new(1.0, 0.5, 0.0), Vec3::X * 0.1, Vec3::Z * 0.1, 5.0);
            let exact = lamp + panel;
            let mut rng = Rng::new(5, Domain::Other, [0; 3]);
            let (mean, se) = mean_se(200_000, || {
                s.direct_area(&sh, wo, rng.uniform3(), false).x as f64
            });
            assert!(
                (mean - exact).abs() < 4.0 * se,
                "h = {h}: {mean} ± {se} against {exact}"
            );
            assert!(
                se < 0.01 * exact,
                "the test could not fail: {se} against {exact}"
            );
        }
    }

    /// The weights' stand-in for the area lights' direct light (each visible emitter's
    /// centroid as a point light, [`Scene::emitters_masked_sum`] through `direct_masked`)
    /// against its expectation by light sampling, at floor points where the emitters subtend
    /// a few degrees (within 5 %); every emitter's bit is set there, and a vertex whose bits
    /// are cleared sees no area light.
    #[test]
    fn the_weights_area_light_stand_in_is_close_to_the_sampled_direct_light() {
        let s = scene(0.0);
        assert_eq!(s.masked_emitters(), (0, 4));
        let wo = Vec3::new(0.0, 1.0, -1.0).normalize();
        for p in [Vec3::new(0.3, 0.0, 0.2), Vec3::new(-0.8, 0.0, -0.5)] {
            let hit = s
                .geometry
                .intersect(p + Vec3::Y * 0.1, -Vec3::Y, 1.0)
                .unwrap();
            let sh = s.shade(&hit, wo);
            let v = s.weight_vertex(&sh);
            assert_eq!(v.lights, 0b1111, "at {p}");
            let stand_in = luminance(s.direct_masked(&v, wo)) as f64;
            let mut rng = Rng::new(7, Domain::Other, [0; 3]);
            let n = 200_000;
            let sampled = (0..n)
                .map(|_| luminance(s.direct_area(&sh, wo, rng.uniform3(), false)) as f64)
                .sum::<f64>()
                / n as f64;
            assert!(
                (stand_in / sampled - 1.0).abs() < 0.05,
                "at {p}: {stand_in} against {sampled}"
            );
            let dark = crate::WeightVertex { lights: 0, ..v };
            assert_eq!(s.direct_masked(&dark, wo), Vec3::ZERO);
        }
    }

    /// Photons leave the panel from both sides with cosine-distributed directions: E[cos θ]
    /// = 2/3 about the side's normal, half of them on each side, flux Φ/p.
    #[test]
    fn emitted_photons_are_cosine_distributed_on_the_emitting_sides() {
        let s = scene(0.0);
        let panel = 2;
        let p = 0.25;
        let mut rng = Rng::new(9, Domain::Other, [0; 3]);
        let n = 100_000;
        let (mut up, mut cos_sum, mut cos2) = (0u32, 0.0f64, 0.0f64);
        let normal = s.geometry.normal(s.emitters()[panel].prim);
        for _ in 0..n {
            let e = s
                .emit_from_emitter(panel, p, rng.uniform2(), rng.uniform2())
                .unwrap();
            let c = e.direction.dot(normal) as f64;
            up += (c > 0.0) as u32;
            cos_sum += c.abs();
            cos2 += c * c;
            let want = s.emitters()[panel].flux() / p;
            assert!((e.flux - want).abs().max_element() < 1e-5 * want.max_element());
        }
        let mean = cos_sum / n as f64;
        let se = ((cos2 / n as f64 - mean * mean) / n as f64).sqrt();
        assert!((mean - 2.0 / 3.0).abs() < 4.0 * se, "{mean} ± {se}");
        let share = up as f64 / n as f64;
        assert!(
            (share - 0.5).abs() < 4.0 * (0.25 / n as f64).sqrt(),
            "{share}"
        );
        // The one-sided lamp emits downwards only.
        let lamp = s.emit_from_emitter(0, p, [0.3, 0.6], [0.9, 0.2]).unwrap();
        assert!(lamp.direction.y < 0.0);
    }

    #[test]
    fn power_heuristic_splits_one() {
        for (a, b) in [(1.0f32, 2.0), (0.0, 3.0), (5.0, 0.0), (1e30, 1e30)] {
            let sum = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((sum - 1.0).abs() < 1e-6, "{a} {b}: {sum}");
        }
    }
}
