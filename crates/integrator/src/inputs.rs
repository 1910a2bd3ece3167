//! One assembly of a weight's inputs (the [`Pair`] of method.md §2 and §8) for every caller:
//! the camera side of the mix (BDD=1 at x₁), the photon side (BDD=0, a photon's previous
//! vertex as x₁, merged at x₀ or light-traced to the camera), `predict`'s model, the pixel
//! table and the weight map.
//!
//! The mix is unbiased only if both techniques of a full path …→x₁→x₀ see the same inputs
//! (w₀ + w₁ = 1 per path). Each input is therefore computed by one function here from data
//! both sides hold alike: x₀, the vertex x₁, the direction x₀→x₁ and how the light reached
//! x₁ ([`Arrival`]). [`Mix::camera_side_pair`] and [`Mix::light_vertex_pair`] are the two
//! ways in (the photon side's merge, [`Mix::photon_side_pair`], and light tracing's splat,
//! `Mix::splat_pair`, both take the second); a test checks, for stored light paths, that the
//! camera side, the merge and the splat agree bit for bit.
use bdpm_bdf::{luminance, survival_at};
use bdpm_cache::{CacheSlot, RadianceCache};
use bdpm_geometry::Frame;
use bdpm_mis::{Pair, PathKind, X0Inputs, X1Inputs, acceptance_probability};
use bdpm_photon::{AREA_LIGHT, PathVertex, Photon, PhotonMap};
use bdpm_scene::WeightVertex;
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::PI;

use crate::mix::{FirstVertex, Mix};

/// How the light subpath of a full path …→x₁→x₀ reaches x₁: what the path's own inputs (its
/// kind, f₁ at x₁, the densities, `camis`'s β) are read from.
#[derive(Clone, Copy)]
pub(crate) enum Arrival<'m> {
    /// Straight from light `light`: the one-bounce path light→x₁→x₀. Its direction at x₁ is
    /// computed from the light's position (a photon's stored direction at its first vertex is
    /// the emitted ray's, which the camera side does not have).
    Light(usize),
    /// Straight from a point of an area light, arriving at x₁ along the unit direction
    /// (pointing away from x₁): the camera side's light sample, or a photon's recorded
    /// direction at its first vertex. The point on the light, which a photon does not keep,
    /// is found again by tracing back along it ([`bdpm_scene::Scene::area_light_end`]), on both sides
    /// alike, for the emission density of the balance-type weights.
    Area(Vec3),
    /// Scattered at the light-path vertex `vertices[from]` (x₂; the vertices stored path by
    /// path, as [`PhotonMap::vertices`] holds them) and arriving at x₁ along `incoming` (unit,
    /// pointing away from x₁): a merge path …→x₂→x₁→x₀.
    Vertex {
        vertices: &'m [PathVertex],
        from: u32,
        incoming: Vec3,
    },
    /// `predict`'s stand-in for the light paths it does not follow: arriving along x₁'s
    /// normal, with f₁ at x₁ replaced by the cache's average over arrivals, b/L_d.
    Modelled,
    /// `predict`'s sampled arrival of a merge path at x₁ along the unit direction (pointing
    /// away from x₁), for weights that read the photon's own f₁: f₁ and the densities as for a
    /// photon from there, without `camis`'s β (no stored light path to walk).
    Sampled(Vec3),
}

/// `camis` stops walking a light path once its β has fallen below this fraction of the camera
/// prefix's a: every further factor is ≤ 1, so β only shrinks, and r = a/(a + β(1 − a)) is
/// then within 1e-9 of 1. The cut is a deterministic function of the path, so both techniques
/// still evaluate the same weight.
const SUFFIX_CUTOFF: f64 = 1e-9;

impl<'a> Mix<'a> {
    /// f̃ = f/µ at x₀ for direction `v` (luminances), sr⁻¹.
    fn f_tilde(&self, x0: &FirstVertex<'_>, f: Vec3) -> f64 {
        if x0.albedo > 0.0 {
            (luminance(f) / x0.albedo) as f64
        } else {
            0.0
        }
    }

    /// f(u, v) at x₀ for the unit direction `v`, sr⁻¹ per channel: the BDF value the weights'
    /// f̃ is made of. Evaluated, never taken from the BDF sample that chose v, so that a
    /// camera sample and a photon reaching x₀ from the same x₁ compute the same bits.
    pub(crate) fn f_at_x0(&self, x0: &FirstVertex<'_>, v: Vec3) -> Vec3 {
        self.scene.eval_with(&x0.bdf, &x0.sh, x0.u, v)
    }

    /// The pair data shared by both path kinds for x₀ and a candidate x₁ at `x1`.
    pub(crate) fn pair(&self, x0: &FirstVertex<'_>, x1: &WeightVertex, v: Vec3, f0: Vec3) -> Pair {
        self.pair_at(x0, x1, v, f0, self.cache_slot(x1.prim, x1.p, -v))
    }

    /// Where the weights' radiance-cache lookup for the point `p` of triangle `prim` towards
    /// `wo` reads (None without a cache); see [`Self::pair_at`].
    pub(crate) fn cache_slot(&self, prim: u32, p: Vec3, wo: Vec3) -> Option<CacheSlot> {
        self.cache_needed().and_then(|c| c.slot(prim, p, wo))
    }

    /// [`Self::pair`] with the cache slot of (x₁, −v) found beforehand by [`Self::cache_slot`],
    /// so that its read could be fetched ahead.
    pub(crate) fn pair_at(
        &self,
        x0: &FirstVertex<'_>,
        x1: &WeightVertex,
        v: Vec3,
        f0: Vec3,
        slot: Option<CacheSlot>,
    ) -> Pair {
        let direct = if self.needs.direct_at_x1 {
            luminance(self.scene.direct_masked(x1, -v))
        } else {
            0.0
        };
        let cached = self
            .cache_needed()
            .map(|cache| slot.map_or((0.0, 0.0), |s| self.cache_read(cache, s, x1)));
        self.pair_with(x0, x1, f0, direct, cached)
    }

    /// [`Self::pair_at`] from L₀(x₁→x₀) (luminance, `direct`) and the cache's (L_d, b) at
    /// x₁ towards x₀ (`cached`, None without a cache) found beforehand.
    fn pair_with(
        &self,
        x0: &FirstVertex<'_>,
        x1: &WeightVertex,
        f0: Vec3,
        direct: f32,
        cached: Option<(f32, f32)>,
    ) -> Pair {
        let mut pair = Pair {
            x0: X0Inputs {
                f_tilde: self.f_tilde(x0, f0),
                acceptance_area: x0.acceptance_area,
                primary_density: x0.primary_density,
            },
            x1: X1Inputs {
                direct: direct as f64,
                ..X1Inputs::default()
            },
            ..Pair::default()
        };
        if let (Some(_), Some((ld, b))) = (self.cache, cached) {
            pair.x1.indirect = ld as f64;
            pair.x1.b = b as f64;
        }
        if self.needs.light_distance {
            pair.x1.light_distance = self
                .scene
                .lights()
                .iter()
                .map(|l| (l.position - x1.p).length())
                .fold(f32::INFINITY, f32::min) as f64;
        }
        pair
    }

    /// The inputs of the weight of one full path through (x₀, x₁): `base` (the part every
    /// path through the pair shares, from [`Self::pair`]) completed with the path's own part
    /// as the heuristic needs it. `v` is the unit direction x₀→x₁ and `dist2` = |x₁ − x₀|²
    /// (m²).
    pub(crate) fn path_pair(
        &self,
        x0: &FirstVertex<'_>,
        x1: &WeightVertex,
        (v, dist2): (Vec3, f32),
        arrival: Arrival<'_>,
        base: Pair,
    ) -> Pair {
        let mut pair = base;
        match arrival {
            Arrival::Light(light) => {
                pair.path.kind = PathKind::OneBounce;
                if self.needs.densities {
                    let incoming = self.light_direction(light, x1.p);
                    let (pc, pl) = self.densities(x0, x1, v, dist2, incoming);
                    pair.path.camera_density = pc;
                    pair.path.light_density = pl;
                    pair.path.emission_density = self.emission_density(light, x1);
                }
            }
            Arrival::Area(incoming) => {
                pair.path.kind = PathKind::OneBounce;
                if self.needs.densities {
                    let (pc, pl) = self.densities(x0, x1, v, dist2, incoming);
                    pair.path.camera_density = pc;
                    pair.path.light_density = pl;
                    pair.path.emission_density = self.area_emission_density(x1, incoming);
                }
            }
            Arrival::Vertex { incoming, .. } | Arrival::Sampled(incoming) => {
                pair.path.kind = PathKind::Merge;
                if self.needs.x1_scattering {
                    pair.path.x1_scattering = self.x1_scattering(x1, incoming, v);
                }
                if self.needs.densities {
                    let (pc, pl) = self.densities(x0, x1, v, dist2, incoming);
                    pair.path.camera_density = pc;
                    pair.path.light_density = pl;
                    // A sampled arrival has no stored light path to walk for `camis`'s β.
                    if let Arrival::Vertex { vertices, from, .. } = arrival
                        && self.needs.light_suffix
                    {
                        pair.path.light_suffix = self.light_suffix(vertices, x0, x1, from, pc);
                    }
                }
            }
            Arrival::Modelled => {
                pair.path.kind = PathKind::Merge;
                if self.needs.x1_scattering && pair.x1.indirect > 0.0 {
                    pair.path.x1_scattering = pair.x1.b / pair.x1.indirect;
                }
                if self.needs.densities {
                    let (pc, pl) = self.densities(x0, x1, v, dist2, x1.n);
                    pair.path.camera_density = pc;
                    pair.path.light_density = pl;
                }
            }
        }
        pair
    }

    /// The camera side's part shared by every path through its x₀ and x₁ (`x1`, reached along
    /// the unit direction `v`), with the cache slot of (x₁, −v) found beforehand
    /// ([`Self::cache_slot`]) so that its read could be fetched ahead.
    pub(crate) fn camera_side_base(
        &self,
        x0: &FirstVertex<'_>,
        x1: &WeightVertex,
        v: Vec3,
        slot: Option<CacheSlot>,
    ) -> Pair {
        self.pair_at(x0, x1, v, self.f_at_x0(x0, v), slot)
    }

    /// The camera side's inputs for the merge path through the photon `ph` found around the
    /// camera's x₁ (`x1`, with `base` = [`Self::pair`] there): the photon's light path
    /// arrives at x₁ from its previous vertex, along its stored direction.
    pub(crate) fn camera_side_pair(
        &self,
        map: &PhotonMap,
        x0: &FirstVertex<'_>,
        x1: &WeightVertex,
        v_dist2: (Vec3, f32),
        ph: &Photon,
        base: Pair,
    ) -> Pair {
        let arrival = Arrival::Vertex {
            vertices: map.vertices(),
            from: ph.prev,
            incoming: ph.incoming,
        };
        self.path_pair(x0, x1, v_dist2, arrival, base)
    }

    /// The photon side's inputs for the path that ends with the photon `ph` (index `i` of
    /// `map`'s photons) landing at x₀: [`Self::light_vertex_pair`] of its previous vertex y_p
    /// in the map's stored paths, with y_p's precomputed inputs from `prev_inputs`
    /// ([`Self::prev_inputs`]'s table, or empty). None where y_p is x₀ itself.
    pub(crate) fn photon_side_pair(
        &self,
        (map, prev_inputs): (&PhotonMap, &[[f32; 3]]),
        x0: &FirstVertex<'_>,
        i: usize,
        ph: &Photon,
    ) -> Option<Pair> {
        self.light_vertex_pair(x0, map.vertices(), ph.prev, prev_inputs.get(i))
    }

    /// The inputs of the path whose light subpath ends at the stored vertex
    /// `vertices[at]` = y_p and goes on to x₀ (a photon landing there, or light tracing's
    /// connection of an arrival at x₀ to the camera): x₁ is y_p, and the light arrived there
    /// from the light (a one-bounce path) or from the vertex stored before it (`vertices`
    /// are stored path by path). `precomputed` are y_p's [L₀, L_d, b] from
    /// [`Self::prev_inputs`], if any. None where y_p is x₀ itself.
    // Inlined into the merge at x₀'s per-photon closure, as it was before the splat shared
    // it: a call per photon visit cost 0.3 % of a glossy pass.
    #[inline(always)]
    pub(crate) fn light_vertex_pair(
        &self,
        x0: &FirstVertex<'_>,
        vertices: &[PathVertex],
        at: u32,
        precomputed: Option<&[f32; 3]>,
    ) -> Option<Pair> {
        let prev = &vertices[at as usize];
        let y = prev.at;
        let (v, dist2) = direction_to(x0, &y)?;
        let f0 = self.f_at_x0(x0, v);
        let base = match precomputed {
            Some(&[l0, ld, b]) if !l0.is_nan() && self.same_cache_side(&y, -v) => {
                // direct_masked's own test of the side; the rest of L₀ is the same number for
                // any direction on it (method-notes.md, "Precomputed inputs").
                let direct = if y.n.dot(-v) <= 0.0 { 0.0 } else { l0 };
                let cached = self.cache_needed().map(|_| (ld, b));
                self.pair_with(x0, &y, f0, direct, cached)
            }
            _ => self.pair(x0, &y, v, f0),
        };
        let arrival = if prev.depth == 0 && prev.light == AREA_LIGHT {
            Arrival::Area(prev.incoming)
        } else if prev.depth == 0 {
            Arrival::Light(prev.light as usize)
        } else {
            // Light paths are stored vertex after vertex: x₂ is the vertex before y_p.
            Arrival::Vertex {
                vertices,
                from: at - 1,
                incoming: prev.incoming,
            }
        };
        Some(self.path_pair(x0, &y, (v, dist2), arrival, base))
    }

    /// Area-measure densities of §8 for a full path …→x₁→x₀ whose light path arrives at x₁
    /// from direction `incoming` (unit, pointing away from x₁). Returns (p_C(x₀→x₁), p_L(x₁→x₀)).
    pub(crate) fn densities(
        &self,
        x0: &FirstVertex<'_>,
        x1: &WeightVertex,
        v: Vec3,
        dist2: f32,
        incoming: Vec3,
    ) -> (f64, f64) {
        let cos1 = x1.n.dot(v).abs();
        let cos0 = x0.sh.ng.dot(v).abs();
        let p_c = x0.bdf.pdf_at(&x0.out, x0.sh.frame.to_local(v)) * cos1 / dist2;
        let frame1 = Frame::from_normal(x1.n);
        let bdf1 = self.scene.bdf_at_vertex(x1);
        let in_l = bdf1.outgoing(frame1.to_local(incoming));
        let q = survival_at(&bdf1, &in_l);
        let p_l = q * bdf1.pdf_at(&in_l, frame1.to_local(-v)) * cos0 / dist2;
        (p_c as f64, p_l as f64)
    }

    /// f₁(ω₂, x₁→x₀): the BDF at the candidate x₁ (luminance, sr⁻¹) for a light path arriving
    /// from `incoming` (unit, pointing away from x₁) and leaving towards x₀ (along −`v`), in
    /// the geometric-normal frame: the same evaluation for the camera's x₁ and a photon's
    /// previous vertex, so both techniques see the same weight (method.md §2).
    fn x1_scattering(&self, x1: &WeightVertex, incoming: Vec3, v: Vec3) -> f64 {
        let bdf = self.scene.bdf_at_vertex(x1);
        if bdf.is_lambert() {
            // The BDF's own test without the frame: the local z of a direction is its dot
            // with the normal, and finite directions stay finite in any orthonormal frame.
            let inside = x1.n.dot(-v) > 0.0 && x1.n.dot(incoming) > 0.0;
            let finite = v.is_finite() && incoming.is_finite();
            return if inside && finite {
                luminance(bdf.kd() * std::f32::consts::FRAC_1_PI) as f64
            } else {
                0.0
            };
        }
        let frame = Frame::from_normal(x1.n);
        luminance(bdf.eval(frame.to_local(-v), frame.to_local(incoming))) as f64
    }

    /// `camis`'s β for a merge path …→x₂→x₁→x₀ (method-notes.md, "camis"): the product of
    /// min(p_L·A, 1) over the light path's densities of x₁ (from x₂), of x₂ (from x₃), … and
    /// of its first vertex (from the light). `start` is x₂'s index in the photon map, whose
    /// vertices are stored path by path, so each vertex of depth k > 0 follows its
    /// predecessor. `camera_density` is p_C(x₀→x₁) (m⁻²), which sets the cut-off.
    ///
    /// The camera's x₁ and a photon's previous vertex y_p enter only through their position
    /// and normal, and everything beyond them is read from the same stored vertices, so both
    /// techniques get the same β for the same path.
    fn light_suffix(
        &self,
        vertices: &[PathVertex],
        x0: &FirstVertex<'_>,
        x1: &WeightVertex,
        start: u32,
        camera_density: f64,
    ) -> f64 {
        let area = x0.acceptance_area;
        let camera = acceptance_probability(x0.primary_density, area)
            * acceptance_probability(camera_density, area);
        let cutoff = camera * SUFFIX_CUTOFF;
        let (mut to_p, mut to_n) = (x1.p, x1.n);
        let mut index = start;
        let mut beta = 1.0;
        loop {
            let y = &vertices[index as usize];
            let d = to_p - y.at.p;
            let d2 = d.length_squared();
            if d2 <= 0.0 {
                return beta;
            }
            let dir = d / d2.sqrt();
            let frame = Frame::from_normal(y.at.n);
            let bdf = self.scene.bdf_at_vertex(&y.at);
            let out = bdf.outgoing(frame.to_local(y.incoming));
            let p = y.survival * bdf.pdf_at(&out, frame.to_local(dir)) * to_n.dot(dir).abs() / d2;
            beta *= acceptance_probability(p as f64, area);
            if beta <= cutoff {
                return beta;
            }
            if y.depth == 0 && y.light == AREA_LIGHT {
                // The density of y from its point on the light, and of that point (SeeSharp's
                // second factor of A for a vertex sampled on an emitter).
                let (p, n, prim) = (y.at.p, y.at.n, y.at.prim);
                return self
                    .scene
                    .area_light_end(p, n, prim, y.incoming)
                    .map_or(0.0, |end| {
                        beta * acceptance_probability(end.vertex_density, area)
                            * acceptance_probability(end.position_density, area)
                    });
            }
            if y.depth == 0 {
                let emission = self.emission_density(y.light as usize, &y.at);
                return beta * acceptance_probability(emission, area);
            }
            // A map not stored path by path (hand-made in tests) ends the walk here.
            if index == 0 || vertices[index as usize - 1].depth + 1 != y.depth {
                debug_assert!(false, "light-path vertices are not consecutive");
                return beta;
            }
            (to_p, to_n) = (y.at.p, y.at.n);
            index -= 1;
        }
    }

    /// Unit direction from `at` to light `light`: a one-bounce path's arrival direction at
    /// x₁, computed from the positions on both sides of the mix (a photon's stored direction
    /// at its first vertex is the emitted ray's, which the camera side does not have).
    fn light_direction(&self, light: usize, at: Vec3) -> Vec3 {
        (self.scene.lights()[light].position - at).normalize_or_zero()
    }

    /// [`Self::emission_density`] of a one-bounce path from an area light, arriving at x₁ along
    /// the unit `incoming`, m⁻²·sr: the photon's density of x₁ (the point on the light, and x₁
    /// from it) over BDD=1's light-sample density of that point, both in area measure at the
    /// light, so that the balance-type weights compare p_C(x₀→x₁)·p_ls with the photon's
    /// p(point)·p(x₁)·p_L(x₁→x₀)·S·N_F; their common cos θₗ/d² cancels. 0 where the point is
    /// not found or no light sample reaches it (BDD=1 then takes the path).
    fn area_emission_density(&self, x1: &WeightVertex, incoming: Vec3) -> f64 {
        let Some(end) = self.scene.area_light_end(x1.p, x1.n, x1.prim, incoming) else {
            return 0.0;
        };
        if end.light_sample_density <= 0.0 {
            return 0.0;
        }
        let cos1 = x1.n.dot(incoming).abs() as f64;
        end.position_density * cos1 / (std::f64::consts::PI * end.light_sample_density)
    }

    /// Emission density p_L(light→x₁) in area measure (choice of light included).
    pub(crate) fn emission_density(&self, light: usize, x1: &WeightVertex) -> f64 {
        let l = self.scene.lights()[light];
        let to = l.position - x1.p;
        let d2 = to.length_squared();
        let cos = x1.n.dot(to).abs() / d2.sqrt();
        (self.scene.light_probability(light) / (4.0 * PI) * cos / d2) as f64
    }

    /// The cache's (L_d, b) at `slot` for the vertex `x1`. A Lambert-only cache derives b
    /// from the triangle's kd (its material's); where the material is textured, b is
    /// kd/π·L_d with the kd at the actual point instead.
    fn cache_read(&self, cache: &RadianceCache, slot: CacheSlot, x1: &WeightVertex) -> (f32, f32) {
        let (ld, b) = cache.at(slot);
        if self.scene.texture(x1.material).is_some() && !cache.stats().stores_b {
            let kd = self.scene.kd_at(x1.material, x1.prim, x1.bary);
            return (ld, luminance(kd) * std::f32::consts::FRAC_1_PI * ld);
        }
        (ld, b)
    }

    /// (L_d, b) of `cache` (the noise model's) at the vertex `x1` towards `wo`, luminances,
    /// read as [`Self::pair`] reads the weights' cache.
    pub(crate) fn model_lookup(
        &self,
        cache: &RadianceCache,
        x1: &WeightVertex,
        wo: Vec3,
    ) -> (f64, f64) {
        cache.slot(x1.prim, x1.p, wo).map_or((0.0, 0.0), |s| {
            let (ld, b) = self.cache_read(cache, s, x1);
            (ld as f64, b as f64)
        })
    }

    /// The radiance cache, when the mode's weights read it.
    fn cache_needed(&self) -> Option<&'a RadianceCache> {
        self.cache.filter(|_| self.needs.radiance_cache)
    }

    /// Whether a cache lookup at `y` towards `wo` reads the side that [`Self::prev_inputs`]
    /// read (towards y's normal); true without a cache.
    fn same_cache_side(&self, y: &WeightVertex, wo: Vec3) -> bool {
        self.cache_needed()
            .is_none_or(|c| c.same_side(y.prim, wo, y.n))
    }

    /// The weight inputs of every photon's previous vertex y_p that do not depend on where
    /// the photon landed, one [L₀, L_d, b] (luminances: W·m⁻²·sr⁻¹, b in W·m⁻²·sr⁻²) per photon of `map`, in its
    /// order: for a Lambert y_p, L₀(y_p) and the cache's L_d and b on the side of y_p's normal
    /// (isotropic there; `merge_at_x0` checks the side), NaN for the others. Empty when the
    /// mode's weights at x₀ read neither, or the cache has directional bins. A one-bin cache
    /// reads the same (L_d, b) for any direction on a side, whether it stores b (a scene with
    /// glossy surfaces and `cache_bins = 1`) or derives it from kd.
    ///
    /// A merge at x₀ visits a photon once per camera sample whose disk holds it, several
    /// times per pass at high resolution; computing these once per photon gives the same
    /// numbers, bit for bit, as [`Self::pair`] would for each visit.
    pub(crate) fn prev_inputs(&self, map: &PhotonMap) -> Vec<[f32; 3]> {
        let reads_inputs = self.needs.direct_at_x1 || self.needs.radiance_cache;
        let per_visit = !self.needs.weighs || self.camera_x1_weighting() || self.per_visit_inputs();
        let isotropic = self.cache_needed().is_none_or(|c| c.is_isotropic());
        if !(self.merges_at_x0() && reads_inputs && isotropic) || per_visit {
            return Vec::new();
        }
        // Computed in path order and then gathered into grid order: the vertices read in the
        // photons' (grid) order are random reads of a large array, which took 2.6 times as long
        // as this (cornell-lambert 256², 1.3 M photons: 0.37 s → 0.14 s a pass, one thread).
        let per_vertex: Vec<[f32; 3]> = map
            .vertices()
            .par_iter()
            .map(|prev| {
                if !self.scene.bdf(prev.at.material).is_lambert() {
                    return [f32::NAN; 3];
                }
                let y = prev.at;
                let l0 = if self.needs.direct_at_x1 {
                    luminance(self.scene.direct_masked(&y, y.n))
                } else {
                    0.0
                };
                let (ld, b) = self.cache_needed().map_or((0.0, 0.0), |c| {
                    self.cache_slot(y.prim, y.p, y.n)
                        .map_or((0.0, 0.0), |s| self.cache_read(c, s, &y))
                });
                [l0, ld, b]
            })
            .collect();
        map.photons()
            .par_iter()
            .map(|ph| per_vertex[ph.prev as usize])
            .collect()
    }
}

/// The unit direction x₀ → `y` and the squared distance (m²), or None where `y` is x₀ itself.
#[inline]
pub(crate) fn direction_to(x0: &FirstVertex<'_>, y: &WeightVertex) -> Option<(Vec3, f32)> {
    let to = y.p - x0.sh.p;
    let dist2 = to.length_squared();
    (dist2 > 0.0).then(|| (to / dist2.sqrt(), dist2))
}

#[cfg(test)]
pub(crate) mod tests {
    //! The agreement of the ways in: for stored light paths, the inputs the camera side
    //! assembles for the path …→x₂→x₁→x₀ (x₁ its own vertex, the photon stored at x₁ found
    //! around it) are the inputs the photon side assembles when that path's next photon lands
    //! at x₀ (x₁ its previous vertex), and those light tracing's splat assembles when it
    //! connects that arrival at x₀ to the camera, bit for bit, for every mixing mode.
    use std::collections::HashMap;

    use bdpm_bdf::Bdf;
    use bdpm_geometry::{Domain, Geometry, TriangleMesh};
    use bdpm_mis::Heuristic;
    use bdpm_photon::{PhotonMap, TraceOptions};
    use bdpm_scene::{Camera, Material, PointLight, Scene};
    use bdpm_settings::{Mode, RenderSettings};
    use glam::Vec3;

    use super::Arrival;
    use crate::Renderer;

    /// An open box: Lambert floor and left wall, a back wall that is Lambert or glossy, two
    /// point lights.
    pub(crate) fn open_box(glossy_back: bool) -> Scene {
        let mut mesh = TriangleMesh::default();
        let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        mesh.push_quad(
            [
                p(-1., 0., -1.),
                p(-1., 0., 1.),
                p(1., 0., 1.),
                p(1., 0., -1.),
            ],
            0,
        );
        mesh.push_quad(
            [
                p(-1., 0., -1.),
                p(1., 0., -1.),
                p(1., 2., -1.),
                p(-1., 2., -1.),
            ],
            1,
        );
        mesh.push_quad(
            [
                p(-1., 0., -1.),
                p(-1., 2., -1.),
                p(-1., 2., 1.),
                p(-1., 0., 1.),
            ],
            0,
        );
        let back = if glossy_back {
            Bdf::new(Vec3::splat(0.2), Vec3::splat(0.6), 0.15)
        } else {
            Bdf::lambert(Vec3::new(0.7, 0.5, 0.3))
        };
        let materials = vec![
            Material::new(
                "lambert",
                Bdf::lambert(Vec3::splat(0.6)).expect("valid albedo"),
            ),
            Material::new("back", back.expect("valid BDF")),
        ];
        let lights = vec![
            PointLight {
                position: p(0.3, 1.5, 0.2),
                flux: Vec3::splat(20.0),
            },
            PointLight {
                position: p(-0.5, 0.6, 0.5),
                flux: Vec3::new(5.0, 8.0, 10.0),
            },
        ];
        let camera = Camera::look_at(p(0.5, 1.2, 3.0), p(-0.2, 0.6, -0.5), Vec3::Y, 50.0, 8, 8)
            .expect("a valid camera");
        Scene::new(
            Geometry::new(mesh).expect("a valid mesh"),
            materials,
            lights,
            camera,
        )
        .expect("a valid scene")
    }

    /// Paths compared, (one-bounce, merge), over every mixing mode of `scene` with a cache of
    /// `cache_bins` bins per cell side; panics at the first disagreement.
    fn check_agreement(scene: &Scene, cache_bins: u32) -> (usize, usize) {
        let (mut one_bounce, mut merge) = (0, 0);
        // Every mode that mixes the two techniques (the pure ones weigh nothing).
        let mixing = Heuristic::ALL_NAMES.iter().filter(|name| {
            let needs = Heuristic::parse(name).expect("a listed name").needs();
            needs.photons_at_x0 && needs.second_vertex
        });
        for &name in mixing {
            let settings = RenderSettings {
                width: 8,
                height: 8,
                photons: 3000,
                cache_photons: Some(20_000),
                pixel_table_rays: Some(16),
                radius: Some(0.05),
                mode: Mode::parse(name).expect("a mode"),
                cache_bins,
                ..RenderSettings::default()
            };
            let renderer = Renderer::new(scene, &settings).expect("valid settings");
            let h = renderer.heuristic().expect("a mixing mode");
            let mix = renderer.mix(h);
            let options = TraceOptions {
                photons: settings.photons,
                seed: 7,
                domain: Domain::Photon,
                pass: 0,
                light_visibility: mix.needs.direct_at_x1,
                max_depth: bdpm_photon::MAX_DEPTH,
            };
            let map = PhotonMap::trace(scene, &options, 0.05);
            let prev_inputs = mix.prev_inputs(&map);
            // The photon stored at each vertex a path went on from, by its previous vertex.
            let by_prev: HashMap<u32, usize> = map
                .photons()
                .iter()
                .enumerate()
                .map(|(i, ph)| (ph.prev, i))
                .collect();
            let cam = scene.camera();
            for (px, py) in [(1.5, 2.5), (4.5, 4.5), (6.5, 1.5), (2.5, 6.5), (7.5, 7.5)] {
                let dir = cam.ray_direction(px, py);
                let hit = scene
                    .geometry()
                    .intersect(cam.position(), dir, f32::INFINITY)
                    .expect("the camera sees the box");
                let x0 = mix.first_vertex(&hit, -dir).expect("x0 faces the camera");
                for (i, ph) in map.photons().iter().enumerate() {
                    let prev = map.vertex(ph.prev);
                    let Some(photon_side) = mix.photon_side_pair((&map, &prev_inputs), &x0, i, ph)
                    else {
                        continue;
                    };
                    let x1 = prev.at;
                    let to = x1.p - x0.sh.p;
                    let dist2 = to.length_squared();
                    let v = to / dist2.sqrt();
                    let slot = mix.cache_slot(x1.prim, x1.p, -v);
                    let base = mix.camera_side_base(&x0, &x1, v, slot);
                    let camera_side = if prev.depth == 0 {
                        one_bounce += 1;
                        let arrival = Arrival::Light(prev.light as usize);
                        mix.path_pair(&x0, &x1, (v, dist2), arrival, base)
                    } else {
                        merge += 1;
                        // The photon that light path stored at x₁ itself.
                        let at_x1 = by_prev[&(ph.prev - 1)];
                        assert_eq!(map.positions()[at_x1], x1.p);
                        let at_x1 = &map.photons()[at_x1];
                        mix.camera_side_pair(&map, &x0, &x1, (v, dist2), at_x1, base)
                    };
                    // Light tracing's splat of the same arrival at x₀: its chunk's vertices
                    // end with y_p (here the map's, up to y_p).
                    let vertices = &map.vertices()[..=ph.prev as usize];
                    let splat_side = mix.splat_pair(&x0, vertices).expect("as the photon side");
                    // Debug prints the shortest text that reads back to the same f64: equal
                    // text is equal bits, NaN included.
                    for (side, inputs) in [("photon", photon_side), ("splat", splat_side)] {
                        assert_eq!(
                            format!("{camera_side:?}"),
                            format!("{inputs:?}"),
                            "{name}, {side} side: photon {i} (depth {}) at x0 {:?}",
                            prev.depth + 1,
                            x0.sh.p
                        );
                    }
                }
            }
        }
        (one_bounce, merge)
    }

    #[test]
    fn camera_and_photon_side_inputs_agree_lambert() {
        let (one_bounce, merge) = check_agreement(&open_box(false), 1);
        assert!(one_bounce > 1000 && merge > 1000, "{one_bounce} {merge}");
    }

    #[test]
    fn camera_and_photon_side_inputs_agree_glossy() {
        // Directional bins (the method's M ≈ 100) and the default's one bin, which stores b
        // and lets the photon side precompute a Lambert y_p's inputs.
        for bins in [100, 1] {
            let (one_bounce, merge) = check_agreement(&open_box(true), bins);
            assert!(
                one_bounce > 1000 && merge > 1000,
                "{bins}: {one_bounce} {merge}"
            );
        }
    }
}
