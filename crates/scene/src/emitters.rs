//! Area lights: triangles whose material emits a radiance Le (W·m⁻²·sr⁻¹ per channel),
//! cosine emission on the front side of the triangle (the side its winding normal points
//! to) or on both sides. What the scene keeps of them ([`Emitters`]), how a shading point
//! samples one for its direct light ([`Scene::sample_emitter`], [`Scene::direct_area`]),
//! the density of that sample in solid angle ([`Scene::emitter_pdf`]), which a BDF sample
//! that hits an emitter needs for its MIS weight, and photon emission from them
//! ([`Scene::emit_from_emitter`]).
//!
//! A point is sampled uniformly by area on a triangle chosen in proportion to its emitted
//! power. Spherical-triangle (solid-angle) sampling would have less variance close to a
//! large emitter; it is left for later because it costs trigonometry per sample and its
//! density is needed again for every BDF hit, while area sampling is exact for the small
//! emitters the scenes have and its density is one division.

use std::f32::consts::PI;

use bdpm_bdf::luminance;
use bdpm_core::sampling::uniform_triangle;
use bdpm_geometry::{Frame, Geometry};
use glam::Vec3;

use crate::{Material, Scene, Shading};

/// One emitting triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emitter {
    /// Index of the triangle in the geometry.
    pub prim: u32,
    /// Emitted radiance Le, W·m⁻²·sr⁻¹ per channel (constant over the triangle).
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
#[derive(Clone, Debug, Default)]
pub(crate) struct Emitters {
    pub(crate) list: Vec<Emitter>,
    /// Cumulative flux luminance of `list`, normalised to end at 1.
    cdf: Vec<f32>,
    /// Per triangle: its index in `list`, or `u32::MAX`; empty without emitters.
    of_prim: Vec<u32>,
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
        let mut acc = 0.0f64;
        let mut cdf: Vec<f32> = Vec::with_capacity(list.len());
        let fluxes: Vec<f64> = list.iter().map(|e| luminance(e.flux()) as f64).collect();
        let total: f64 = fluxes.iter().sum();
        for f in &fluxes {
            acc += f;
            cdf.push((acc / total) as f32);
        }
        Emitters { list, cdf, of_prim }
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
    /// Density of the point in area measure, the emitter's choice included, m⁻².
    pub pdf_area: f32,
}

/// A photon leaving an emitter ([`Scene::emit_from_emitter`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterPhoton {
    /// Ray origin, pushed off the emitter to the side of `direction`, m.
    pub origin: Vec3,
    /// Unit direction, cosine-distributed about the emitting side's normal.
    pub direction: Vec3,
    /// Flux the photon stands for before the division by N_F: Le·π·A·sides / p(emitter),
    /// W per channel.
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

    /// Radiance emitted by triangle `prim` towards the unit world direction `wo` (pointing
    /// away from it), W·m⁻²·sr⁻¹: Le on an emitting side, else 0.
    #[inline]
    pub fn emitted(&self, prim: u32, wo: Vec3) -> Vec3 {
        if !self.has_emission() {
            return Vec3::ZERO;
        }
        let Some(e) = self.emitter_of(prim) else {
            return Vec3::ZERO;
        };
        if e.two_sided || self.geometry.normal(prim).dot(wo) > 0.0 {
            e.radiance
        } else {
            Vec3::ZERO
        }
    }

    /// The emitter on triangle `prim`, if it emits.
    fn emitter_of(&self, prim: u32) -> Option<&Emitter> {
        let i = *self.emitters.of_prim.get(prim as usize)?;
        self.emitters.list.get(i as usize)
    }

    /// Solid-angle density (sr⁻¹) with which [`Self::sample_emitter`] from `from` yields the
    /// point `p` of triangle `prim`: p(emitter)/A · d²/|cos θ_e|. 0 where `prim` emits
    /// nothing towards `from`.
    pub fn emitter_pdf(&self, from: Vec3, prim: u32, p: Vec3) -> f32 {
        let Some(e) = self.emitter_of(prim) else {
            return 0.0;
        };
        let i = self.emitters.of_prim[prim as usize] as usize;
        let to = from - p;
        let d2 = to.length_squared();
        let cos = self.geometry.normal(prim).dot(to) / d2.sqrt();
        if d2 <= 0.0 || cos == 0.0 || (!e.two_sided && cos < 0.0) {
            return 0.0;
        }
        self.emitters.probability(i) / e.area * d2 / cos.abs()
    }

    /// A point on an emitter: the emitter picked by flux with `u_pick`, the point uniform on
    /// its triangle by `u_point`. `None` without emitters.
    pub fn sample_emitter(&self, u_pick: f32, u_point: [f32; 2]) -> Option<EmitterSample> {
        if !self.has_emission() {
            return None;
        }
        let (i, p) = self.emitters.pick(u_pick);
        let e = &self.emitters.list[i];
        let [a, b, c] = self.geometry.vertices(e.prim);
        let (b1, b2) = uniform_triangle(u_point);
        Some(EmitterSample {
            p: a * (1.0 - b1 - b2) + b * b1 + c * b2,
            n: self.geometry.normal(e.prim),
            prim: e.prim,
            pdf_area: p / e.area,
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
        let s = self.sample_emitter(u[0], [u[1], u[2]])?;
        let to = s.p - sh.p;
        let d2 = to.length_squared();
        if d2 <= 0.0 {
            return None;
        }
        let wi = to / d2.sqrt();
        let le = self.emitted(s.prim, -wi);
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
        if self.geometry.occluded(self.spawn(sh, wi), end) {
            return None;
        }
        let pdf = s.pdf_area * d2 / cos_e;
        let weight = if mis {
            let bdf = self.bdf_at(sh);
            power_heuristic(pdf, bdf.pdf(sh.frame.to_local(wo), sh.frame.to_local(wi)))
        } else {
            1.0
        };
        let c = f * le * (cos * weight / pdf);
        c.is_finite().then_some((c, wi))
    }

    /// Radiance emitted by the triangle of a BDF sample's hit (`prim`, at `p`) back towards
    /// the vertex `from` it was sampled at with solid-angle density `pdf_bdf` (sr⁻¹), weighted
    /// by the power heuristic against [`Self::direct_area`]'s light sample there.
    pub fn emitted_mis(&self, from: Vec3, pdf_bdf: f32, prim: u32, p: Vec3) -> Vec3 {
        let wo = (from - p).normalize_or_zero();
        let le = self.emitted(prim, wo);
        if le == Vec3::ZERO {
            return Vec3::ZERO;
        }
        le * power_heuristic(pdf_bdf, self.emitter_pdf(from, prim, p))
    }

    /// A photon from the area lights: emitter `index` (chosen with probability
    /// `probability` by the caller's light distribution), a point uniform on it (`u_point`),
    /// a side (`u_dir[0]` for a two-sided one) and a cosine-distributed direction.
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
        Some(EmitterPhoton {
            origin,
            direction,
            flux: e.flux() / probability,
        })
    }
}

/// The power heuristic p_a²/(p_a² + p_b²) of a sample drawn with density `a` against the
/// other strategy's density `b` for the same direction (1 where `b` is 0).
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && (a2 + b2).is_finite() {
        a2 / (a2 + b2)
    } else if b > a {
        0.0
    } else {
        1.0
    }
}

/// A cosine-distributed direction about +z (density cos θ/π sr⁻¹), from the concentric disk.
#[inline]
pub fn cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let d = bdpm_core::sampling::concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}
