//! The BDPM mix of method.md §2: direct light at x₀, photons merged at x₀ weighted per photon
//! by 1 − w₁(x₀, y_p), and the camera's second vertex x₁ weighted by w₁(x₀, x₁).
use std::borrow::Cow;

use bdpm_bdf::{Bdf, Outgoing, luminance};
use bdpm_cache::RadianceCache;
use bdpm_geometry::Hit;
use bdpm_geometry::Rng;
use bdpm_mis::{Budget, Heuristic, Needs, Pair, Weigher, acceptance_area};
use bdpm_photon::{PhotonMap, PhotonQuery};
use bdpm_scene::{Scene, Shading};

use crate::correction::CandidateSums;
use crate::direct::DirectExtra;
use crate::inputs::Arrival;
use crate::radius::RadiusMap;
use crate::table::PixelWeights;
use bdpm_scene::WeightVertex;
use glam::{DVec3, Vec3};

/// The contributions of one camera sample, split by technique (for the debug layers).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Techniques {
    /// L₀(x₀): direct light at the first vertex (never weighted).
    pub direct: DVec3,
    /// Photons merged at x₀, unweighted (the pure BDD=0 estimate of indirect light).
    pub x0_raw: DVec3,
    /// Photons merged at x₀, each weighted by 1 − w₁(x₀, y_p).
    pub x0_weighted: DVec3,
    /// E·(L₀(x₁→x₀) + Ph(x₁)), unweighted (the pure BDD=1 estimate of indirect light).
    pub x1_raw: DVec3,
    /// The same with weights w₁.
    pub x1_weighted: DVec3,
}

impl Techniques {
    /// The sample value: direct + weighted x₀ merge + weighted x₁ part.
    pub fn total(&self) -> DVec3 {
        self.direct + self.x0_weighted + self.x1_weighted
    }
}

/// Counts of weight evaluations, for the run report (method.md §4 asks that clamped c·B and
/// weights outside [0, 1] be reported).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WeightStats {
    /// Weights evaluated.
    pub evaluations: u64,
    /// Weights whose w₁ fell outside [0, 1] (before any optional clamp).
    pub outside_unit: u64,
    /// Optimal weights whose c·B was clamped to 1 − ε.
    pub clamped_cb: u64,
}

impl WeightStats {
    /// Adds another set of counts.
    pub fn add(&mut self, o: &WeightStats) {
        self.evaluations += o.evaluations;
        self.outside_unit += o.outside_unit;
        self.clamped_cb += o.clamped_cb;
    }
}

/// Camera samples that [`Mix::sample_batch`] takes together: enough for each sample's
/// photon-map fetches to be hidden behind the others' work, few enough for the batch's state
/// (~8 KB) to stay in L1. Measured (camera stage, 1 thread): 4 is 7 % slower than 8, 16 is
/// 2 % (Lambert) to 5 % (glossy) faster, 32 is slower again.
pub(crate) const BATCH: usize = 16;

/// Rounds of [`PhotonMap::advance_query`] between a batch's rays and its gathers: one per
/// stage of a query, so that every read of a gather has been fetched.
const QUERY_STAGES: usize = 3;

/// One camera sample to take: its image point (pixels, x right and y down from the top-left
/// corner), its random stream, and where its value goes.
#[derive(Clone, Debug)]
pub(crate) struct Job {
    pub(crate) x: f32,
    pub(crate) y: f32,
    pub(crate) rng: Rng,
    /// The numbers of the BDF sample at x₀ when the sampler fixes them (`None`: from `rng`).
    pub(crate) bdf: Option<[f32; 3]>,
    pub(crate) out: Techniques,
    /// The weighted parts of the value under each candidate factor of `corrected-balance`'s
    /// pilot (only when [`Mix::pilot`]; direct light at x₀ is not in it).
    pub(crate) pilot: CandidateSums,
    /// Further points where direct light at x₀ is evaluated (`direct_boost`), if any.
    pub(crate) direct_extra: Option<DirectExtra>,
    /// The pixel's scale of the merge radius ([`Mix::radius_scale`]).
    pub(crate) scale: f32,
}

/// Room for the state of a batch of samples between their rays and their gathers, reused from
/// batch to batch: it is a few kilobytes, and is filled in place rather than moved.
#[derive(Default)]
pub(crate) struct Slots<'s>([Slot<'s>; BATCH]);

/// A sample between its rays and its gathers.
#[derive(Default)]
struct Slot<'s> {
    /// None if the sample ended before any gather.
    x0: Option<FirstVertex<'s>>,
    /// The x₁ part, if the mode has one and x₁ was found.
    second: Option<Second>,
    /// The photon query at x₀ (used when the mode gathers there).
    query0: PhotonQuery,
    /// The photon query at x₁ (used when `second` is Some).
    query1: PhotonQuery,
}

/// The x₁ part of a sample before its gather.
struct Second {
    sh1: Shading,
    x1: WeightVertex,
    /// Unit direction x₀ → x₁.
    v: Vec3,
    dist2: f32,
    pair: Pair,
    /// The weight w₁ when it is the same for every path through (x₀, x₁).
    w_const: f64,
    /// E = f·cos/pdf at x₀.
    weight: Vec3,
    direct_raw: Vec3,
    direct_weighted: Vec3,
}

/// Per-render constants of the mix.
pub(crate) struct Mix<'a> {
    pub(crate) scene: &'a Scene,
    pub(crate) heuristic: Heuristic,
    pub(crate) needs: Needs,
    /// w₁ of a mode that does not weigh (`bdd0`: 0, `bdd1`: 1; [`Heuristic::fixed_w1`]).
    pub(crate) fixed_w1: Option<f64>,
    pub(crate) budget: Budget,
    /// Merge kernel 1/S, m⁻².
    pub(crate) inv_area: f32,
    /// Merge radius r, m (a pixel's is r times its [`Self::radius_scale`]).
    pub(crate) radius: f32,
    /// Each pixel's scale of r (`adaptive_radius`); `None`: r everywhere.
    pub(crate) radius_map: Option<&'a RadiusMap>,
    /// The frozen radiance cache, when the mode needs L_d (and b).
    pub(crate) cache: Option<&'a RadianceCache>,
    /// `corrected-balance`'s pilot: every weighted contribution also goes into the sample's
    /// [`Job::pilot`] under each candidate factor (crate::correction).
    pub(crate) pilot: bool,
    /// BDD=0's paths are sampled by light tracing ([`Mix::splat`]) instead of merged at x₀.
    pub(crate) light_tracing: bool,
    /// Test-only variant: weight the x₀ photon sum with w₁(x₀, x₁ᶜ) of the camera's x₁, as
    /// the preprint's eq. 2–3 read literally. It is biased; a test shows it.
    #[cfg(feature = "test-hooks")]
    pub(crate) camera_x1_weighting: bool,
    /// Test-only: compute a photon's y_p inputs at every visit, not once per photon
    /// ([`Mix::prev_inputs`]); the image bits must not change.
    #[cfg(feature = "test-hooks")]
    pub(crate) per_visit_inputs: bool,
    /// Test-only: the splats ignore light tracing's density ratio (a biased mix).
    #[cfg(feature = "test-hooks")]
    pub(crate) two_way_splat_weights: bool,
}

/// The camera side of x₀: the shading point, its outgoing direction and its BDF data.
pub(crate) struct FirstVertex<'s> {
    pub(crate) sh: Shading,
    pub(crate) u: Vec3,
    /// The BDF's data for outgoing direction u, shared by every sample and pdf at x₀.
    pub(crate) out: Outgoing,
    /// The BDF at x₀ (kd from its texture where the material has one).
    pub(crate) bdf: Cow<'s, Bdf>,
    /// Luminance of the directional albedo µ(u; x₀).
    pub(crate) albedo: f32,
    /// `camis` only (else 0): its acceptance area A at x₀'s distance from the camera, m².
    pub(crate) acceptance_area: f64,
    /// `camis` only (else 0): p_C(x₀), the camera's density of x₀ within its pixel, m⁻².
    pub(crate) primary_density: f64,
}

impl<'a> Mix<'a> {
    /// Prepares x₀ for a camera ray that hit `hit` (u = towards the camera), or None if the
    /// shading normal faces away from the camera.
    pub(crate) fn first_vertex<'s>(&'s self, hit: &Hit, u: Vec3) -> Option<FirstVertex<'s>> {
        self.first_vertex_shaded(self.scene.shade(hit, u), u)
    }

    /// [`Self::first_vertex`] for a hit already shaded for `u`.
    pub(crate) fn first_vertex_shaded<'s>(
        &'s self,
        sh: Shading,
        u: Vec3,
    ) -> Option<FirstVertex<'s>> {
        let u_local = sh.frame.to_local(u);
        if u_local.z <= 0.0 {
            return None;
        }
        let bdf = self.scene.bdf_at(&sh);
        let out = bdf.outgoing(u_local);
        let (acceptance_area, primary_density) = if self.needs.primary_terms || self.light_tracing {
            self.primary_terms(&sh, u)
        } else {
            (0.0, 0.0)
        };
        Some(FirstVertex {
            sh,
            u,
            out,
            albedo: luminance(bdf.albedo_at(&out)),
            bdf,
            acceptance_area,
            primary_density,
        })
    }

    /// `camis`'s acceptance area A (m²) and p_C(x₀) (m⁻²) for x₀ at `sh` seen along −u.
    ///
    /// Both are functions of x₀ alone. A pixel is sampled uniformly over its area a_pix on
    /// the image plane at unit distance; dω = cos³θ_c·dA_image and dA(x₀) = d₀²·dω/cos θ₀,
    /// hence p_C(x₀) = cos θ₀/(d₀²·a_pix·cos³θ_c).
    fn primary_terms(&self, sh: &Shading, u: Vec3) -> (f64, f64) {
        let cam = &self.scene.camera();
        let d2 = (sh.p - cam.position()).length_squared() as f64;
        let cos0 = sh.ng.dot(u).abs() as f64;
        let cos_c = cam.forward().dot(-u).max(0.0) as f64;
        let image = d2 * cam.pixel_area() as f64 * cos_c * cos_c * cos_c;
        let density = if image > 0.0 { cos0 / image } else { 0.0 };
        (acceptance_area(d2.sqrt()), density)
    }

    /// The mix's budget for one pixel: its N_B (N_eff where given, else the mix's) and its
    /// merge area, scale²·S for a radius of `scale` × r (exactly S at a scale of 1).
    pub(crate) fn pixel_budget(&self, camera_samples: Option<f64>, scale: f32) -> Budget {
        let mut budget = Budget {
            camera_samples: camera_samples.unwrap_or(self.budget.camera_samples),
            ..self.budget
        };
        if scale != 1.0 {
            budget.merge_area *= f64::from(scale) * f64::from(scale);
        }
        budget
    }

    /// Pixel (x, y)'s scale of the merge radius: 1 without a map. Exactly 1 keeps every
    /// kernel, gather and weight input bit for bit what it is without one.
    #[inline]
    pub(crate) fn radius_scale(&self, x: u32, y: u32) -> f32 {
        self.radius_map.map_or(1.0, |m| m.scale(x, y))
    }

    /// The largest pixel radius over r: the photon grid is built for r times it.
    pub(crate) fn largest_radius_scale(&self) -> f32 {
        self.radius_map.map_or(1.0, |m| m.largest().max(1.0))
    }

    /// The weigher of one pixel: the mode with the pixel's A, B and, where the table gives
    /// one, its N_eff in place of N_B (method.md §12; N_B itself under the pinhole model and
    /// without jitter, so those weights keep their bits), `corrected-balance`'s factor
    /// `correction` for the pixel (1 for `balance`'s weights; the other modes ignore it), and
    /// the pixel's merge area scale²·S for its radius of `scale` × r ([`Self::radius_scale`]).
    pub(crate) fn weigher(
        &self,
        pixel: Option<&PixelWeights>,
        correction: f64,
        scale: f32,
    ) -> Weigher {
        let budget = self.pixel_budget(pixel.map(|p| p.camera_samples), scale);
        Weigher::new(self.heuristic, &budget, pixel.map(|p| &p.terms)).with_correction(correction)
    }

    /// Whether the camera side merges photons at x₀ (BDD=0 by merging, not light tracing).
    pub(crate) fn merges_at_x0(&self) -> bool {
        self.needs.photons_at_x0 && !self.light_tracing
    }

    /// w₁ for `pair` under `weigher`, counted in `stats`; with light tracing in BDD=0's place,
    /// [`Weigher::weight_light_traced`] with N_B·S·p_C(x₀), S the weigher's (its pixel's, with
    /// `adaptive_radius`): both sides of a path compute it from x₀ and its pixel alone.
    pub(crate) fn w1(&self, pair: &Pair, weigher: &Weigher, stats: &mut WeightStats) -> f64 {
        let w = if self.light_tracing {
            let b = &self.budget;
            let ratio = b.camera_samples * weigher.merge_area() * pair.x0.primary_density;
            weigher.weight_light_traced(pair, ratio)
        } else {
            weigher.weight(pair)
        };
        stats.evaluations += 1;
        stats.outside_unit += w.outside_unit as u64;
        stats.clamped_cb += w.clamped_cb as u64;
        w.w1
    }

    /// Camera samples through the image points of `jobs`, each with its own random stream:
    /// every job's `out` receives the value split by technique. At most [`BATCH`] jobs.
    ///
    /// The samples are taken together in stages so that the photon-map reads of one sample
    /// are fetched while the others compute: first every sample's rays, shading and weights
    /// up to its gathers (starting the gathers' queries), then rounds that move every
    /// query on, then the gathers. Each sample's arithmetic is exactly that of a sample taken
    /// alone, so the results do not depend on the batch.
    pub(crate) fn sample_batch<'s>(
        &'s self,
        map: &PhotonMap,
        prev_inputs: &[[f32; 3]],
        jobs: &mut [Job],
        slots: &mut Slots<'s>,
        weigher: &Weigher,
        stats: &mut WeightStats,
    ) {
        assert!(jobs.len() <= BATCH, "at most {BATCH} samples per batch");
        let slots = &mut slots.0;
        for (job, slot) in jobs.iter_mut().zip(slots.iter_mut()) {
            job.out = Techniques::default();
            job.pilot = CandidateSums::default();
            slot.x0 = None;
            slot.second = None;
            self.start_sample(map, job, weigher, stats, slot);
        }
        for _ in 0..QUERY_STAGES {
            // Only this batch's slots: the others still hold an earlier batch's samples.
            for slot in slots[..jobs.len()].iter_mut().filter(|s| s.x0.is_some()) {
                if slot.second.is_some() {
                    map.advance_query(&mut slot.query1);
                }
                if self.merges_at_x0() {
                    map.advance_query(&mut slot.query0);
                }
            }
        }
        for (job, slot) in jobs.iter_mut().zip(slots.iter()) {
            let Some(x0) = &slot.x0 else { continue };
            let camera_w1 = slot.second.as_ref().map(|s| s.w_const);
            // The kernel 1/S of the sample's pixel, for both of its merges.
            let k = self.inv_area / (job.scale * job.scale);
            if let Some(second) = &slot.second {
                let out = (&mut job.out, &mut job.pilot);
                self.merge_at_x1(x0, (map, k), second, &slot.query1, weigher, stats, out);
            }
            if self.merges_at_x0() {
                let photons = (map, prev_inputs);
                self.merge_at_x0(
                    x0,
                    (photons, k),
                    &slot.query0,
                    weigher,
                    camera_w1,
                    stats,
                    (&mut job.out, &mut job.pilot),
                );
            }
        }
    }

    /// Everything of one sample up to its gathers: the direct light at x₀ goes into
    /// `job.out`, the rest into `slot` (whose `x0` stays None if the sample ends before any
    /// gather).
    fn start_sample<'s>(
        &'s self,
        map: &PhotonMap,
        job: &mut Job,
        weigher: &Weigher,
        stats: &mut WeightStats,
        slot: &mut Slot<'s>,
    ) {
        let scene = self.scene;
        let cam = &scene.camera();
        let dir = cam.ray_direction(job.x, job.y);
        let hit0 = scene
            .geometry()
            .intersect(cam.position(), dir, f32::INFINITY);
        let u = -dir;
        let sh0 = hit0.map(|hit| scene.shade(&hit, u));
        let direct = sh0.as_ref().map_or(Vec3::ZERO, |sh| scene.direct(sh, u));
        job.out.direct = match &mut job.direct_extra {
            // The mean of L₀ over the sample's point and the further ones, whether or not
            // the sample's own ray meets anything.
            Some(extra) => extra.mean_with(scene, direct),
            None => direct.as_dvec3(),
        };
        let Some(sh0) = sh0 else {
            return;
        };
        let Some(x0) = self.first_vertex_shaded(sh0, u) else {
            return;
        };
        let r = self.radius * job.scale;
        if self.merges_at_x0() {
            map.restart_query_within(&mut slot.query0, x0.sh.p, r);
        }
        if self.needs.second_vertex {
            let drawn = job.rng.uniform3();
            let bdf_u = job.bdf.unwrap_or(drawn);
            slot.second = self.start_second(
                &x0,
                map,
                (bdf_u, r),
                (weigher, stats),
                &mut slot.query1,
                &mut job.pilot,
            );
        }
        slot.x0 = Some(x0);
    }

    /// BDD=1 up to its gather: sample v at x₀ (never absorbed), find x₁, weigh the one-bounce
    /// paths light→x₁→x₀, and start the photon query at x₁.
    fn start_second(
        &self,
        x0: &FirstVertex<'_>,
        map: &PhotonMap,
        (u, r): ([f32; 3], f32),
        (weigher, stats): (&Weigher, &mut WeightStats),
        query: &mut PhotonQuery,
        pilot: &mut CandidateSums,
    ) -> Option<Second> {
        let scene = self.scene;
        let s = x0.bdf.sample_at(&x0.out, u)?;
        let v = x0.sh.frame.to_world(s.wi);
        if x0.sh.ng.dot(v) <= 0.0 {
            return None;
        }
        let hit1 = scene
            .geometry()
            .intersect(scene.spawn(&x0.sh, v), v, f32::INFINITY)?;
        // Started before the shadow ray and the weight's inputs, which hide its first fetch.
        map.restart_query_within(query, hit1.p, r);
        let wo1 = -v;
        // Likewise the weight's cache read, fetched during the shadow ray.
        let slot = self.cache_slot(hit1.prim, hit1.p, wo1);
        if let (Some(cache), Some(slot)) = (self.cache, slot) {
            cache.prefetch(slot);
        }
        let sh1 = scene.shade(&hit1, wo1);
        let x1 = scene.weight_vertex(&sh1);
        let lights = x1.lights;
        let pair = self.camera_side_base(x0, &x1, v, slot);
        let dist2 = (x1.p - x0.sh.p).length_squared();

        // One-bounce paths light→x₁→x₀, light by light (their balance weights differ).
        let mut direct_raw = Vec3::ZERO;
        let mut direct_weighted = Vec3::ZERO;
        let per_light = self.needs.densities;
        let w_const = if per_light {
            0.0
        } else if let Some(w1) = self.fixed_w1 {
            w1
        } else {
            self.w1(&pair, weigher, stats)
        };
        // Weights by path kind give the one-bounce paths (through L₀(x₁)) their own weight; the
        // merge paths (through the photons at x₁) keep `w_const`.
        // Without densities a one-bounce path's inputs do not depend on its light: one
        // evaluation serves them all.
        let w_direct = if self.needs.path_kinds && lights != 0 && !per_light {
            let one = self.path_pair(x0, &x1, (v, dist2), Arrival::Light(0), pair);
            self.w1(&one, weigher, stats)
        } else {
            w_const
        };
        for l in 0..scene.lights().len() {
            let c = scene.direct_from_masked(&sh1, wo1, l, lights);
            if c == Vec3::ZERO {
                continue;
            }
            direct_raw += c;
            let w = if per_light {
                let one = self.path_pair(x0, &x1, (v, dist2), Arrival::Light(l), pair);
                self.w1(&one, weigher, stats)
            } else {
                w_direct
            };
            direct_weighted += c * w as f32;
            if self.pilot {
                pilot.add(f64::from(luminance(s.weight * c)), w, true);
            }
        }
        Some(Second {
            sh1,
            x1,
            v,
            dist2,
            pair,
            w_const,
            weight: s.weight,
            direct_raw,
            direct_weighted,
        })
    }

    /// BDD=1's merge paths …→x₂→x₁→x₀: photons around x₁, weighted by w₁; finishes the x₁
    /// part of the sample.
    #[allow(clippy::too_many_arguments)]
    fn merge_at_x1(
        &self,
        x0: &FirstVertex<'_>,
        (map, k): (&PhotonMap, f32),
        second: &Second,
        query: &PhotonQuery,
        weigher: &Weigher,
        stats: &mut WeightStats,
        (t, pilot): (&mut Techniques, &mut CandidateSums),
    ) {
        let scene = self.scene;
        let &Second {
            sh1,
            x1,
            v,
            dist2,
            pair,
            w_const,
            weight: e,
            direct_raw,
            direct_weighted,
        } = second;
        let wo1 = -v;
        // Weights that read the light path's own inputs differ from photon to photon.
        let per_path = self.needs.densities || self.needs.x1_scattering;
        let mut ph_raw = Vec3::ZERO;
        let mut ph_weighted = Vec3::ZERO;
        let bdf1 = scene.bdf_at(&sh1);
        map.finish_query(query, |ph| {
            let wp = ph.incoming;
            let f = scene.eval_with(&bdf1, &sh1, wo1, wp);
            if f == Vec3::ZERO {
                return;
            }
            let c = f * ph.power;
            ph_raw += c;
            let w = if per_path {
                let path = self.camera_side_pair(map, x0, &x1, (v, dist2), ph, pair);
                self.w1(&path, weigher, stats)
            } else {
                w_const
            };
            ph_weighted += c * w as f32;
            if self.pilot {
                pilot.add(f64::from(luminance(e * c) * k), w, true);
            }
        });
        t.x1_raw = (e * (direct_raw + ph_raw * k)).as_dvec3();
        t.x1_weighted = (e * (direct_weighted + ph_weighted * k)).as_dvec3();
    }

    /// BDD=0: photons around x₀, each weighted by 1 − w₁(x₀, y_p) (method.md §2).
    #[allow(clippy::too_many_arguments)]
    fn merge_at_x0(
        &self,
        x0: &FirstVertex<'_>,
        (photons, k): ((&PhotonMap, &[[f32; 3]]), f32),
        query: &PhotonQuery,
        weigher: &Weigher,
        camera_w1: Option<f64>,
        stats: &mut WeightStats,
        (t, pilot): (&mut Techniques, &mut CandidateSums),
    ) {
        let scene = self.scene;
        let mut raw = Vec3::ZERO;
        let mut weighted = Vec3::ZERO;
        photons.0.finish_query_indexed(query, |i, ph| {
            let wp = ph.incoming;
            let f = scene.eval_with(&x0.bdf, &x0.sh, x0.u, wp);
            if f == Vec3::ZERO {
                return;
            }
            let c = f * ph.power;
            raw += c;
            let w0 = if let Some(w1) = self.fixed_w1 {
                1.0 - w1
            } else if self.camera_x1_weighting() {
                1.0 - camera_w1.unwrap_or(0.0)
            } else {
                let Some(pair) = self.photon_side_pair(photons, x0, i, ph) else {
                    return;
                };
                let w1 = self.w1(&pair, weigher, stats);
                if self.pilot {
                    pilot.add(f64::from(luminance(c) * k), w1, false);
                }
                1.0 - w1
            };
            weighted += c * w0 as f32;
        });
        t.x0_raw = (raw * k).as_dvec3();
        t.x0_weighted = (weighted * k).as_dvec3();
    }
}

/// The default merge radius for `scene`: its largest bounding-box extent / 1600, metres.
pub fn scene_default_radius(scene: &Scene) -> f32 {
    let (lo, hi) = scene.geometry().bounds();
    bdpm_settings::default_radius((hi - lo).max_element())
}
