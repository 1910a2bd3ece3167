//! The BDPM mix of method.md §2: direct light at x₀, photons merged at x₀ weighted per photon
//! by 1 − w₁(x₀, y_p), and the camera's second vertex x₁ weighted by w₁(x₀, x₁), taken in
//! batches of camera samples ([`Mix::sample_batch`]).
use bdpm_bdf::{BdfSample, Transport, luminance};
use bdpm_cache::CacheSlot;
use bdpm_geometry::{Hit, Rng};
use bdpm_mis::{Pair, Weigher};
use bdpm_photon::{PhotonMap, PhotonQuery};
use bdpm_scene::{Scene, Shading, WeightVertex};
use glam::{DVec3, Vec3};

use crate::correction::CandidateSums;
use crate::direct::emitted_and_area;
use crate::estimates::{Techniques, WeightStats};
use crate::inputs::Arrival;
use crate::mix::{DeltaChain, FirstVertex, Mix};
use crate::one_bounce::{area_samples_at_x1, chain_direct};
use crate::plan::PixelPlan;

/// Camera samples that [`Mix::sample_batch`] takes together: enough for each sample's
/// photon-map fetches to be hidden behind the others' work, few enough for the batch's state
/// (~8 KB) to stay in L1. Measured (camera stage, 1 thread): 4 is 7 % slower than 8, 16 is
/// 2 % (Lambert) to 5 % (glossy) faster, 32 is slower again.
pub(crate) const BATCH: usize = 16;

/// Rounds of [`PhotonMap::advance_query`] between a batch's rays and its gathers: one per
/// stage of a query, so that every read of a gather has been fetched.
const QUERY_STAGES: usize = 3;

/// One camera sample to take: which of its pixel's samples, its image point (pixels, x right
/// and y down from the top-left corner) and its random stream.
#[derive(Clone, Debug)]
pub(crate) struct Job {
    /// Sample k of the pixel (its direct-light points' stream, [`PixelPlan::direct_extra`]).
    k: u32,
    x: f32,
    y: f32,
    rng: Rng,
    /// The numbers of the BDF sample at x₀ when the sampler fixes them (`None`: from `rng`).
    bdf: Option<[f32; 3]>,
}

impl Job {
    /// Sample `k` (< N_B) of the pixel of `plan`.
    #[inline]
    pub(crate) fn new(plan: &PixelPlan<'_>, k: u32) -> Job {
        let c = plan.sample(k);
        Job {
            k,
            x: plan.x as f32 + c.offset[0],
            y: plan.y as f32 + c.offset[1],
            rng: c.rng,
            bdf: c.bdf,
        }
    }
}

/// What one camera sample gives: its value split by technique and, in `corrected-balance`'s
/// pilot ([`Mix::pilot`]), its weighted parts under each candidate factor (direct light at x₀
/// is not in those).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SampleOut {
    pub(crate) techniques: Techniques,
    pub(crate) pilot: CandidateSums,
}

/// Room for the state of a batch of samples between their rays and their gathers, reused from
/// batch to batch: it is a few kilobytes, and is filled in place rather than moved.
#[derive(Default)]
pub(crate) struct Slots<'s>([Slot<'s>; BATCH]);

impl Slots<'_> {
    /// What the first `n` samples of the last batch gave, in sample order.
    pub(crate) fn outputs(&self, n: usize) -> impl Iterator<Item = &SampleOut> {
        self.0[..n].iter().map(|s| &s.out)
    }
}

/// A sample between its rays and its gathers.
#[derive(Default)]
struct Slot<'s> {
    /// What the sample gives, filled as it goes.
    out: SampleOut,
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

impl Second {
    /// True when x₁ was reached through delta vertices, which `dist2` = 0 marks (a chain has no
    /// straight distance; a real x₁ is never at x₀): every path through it then takes `w_const`
    /// ([`Mix::chain_w1`]), and `v` is the last segment's direction. A field of its own made
    /// the struct's moves a memcpy call (+0.4 % instructions a pass).
    fn chain(&self) -> bool {
        self.dist2 == 0.0
    }
}

impl<'a> Mix<'a> {
    /// The camera samples `jobs` of the pixel of `plan`, each with its own random stream:
    /// what each gives goes to its slot ([`Slots::outputs`]). At most [`BATCH`] jobs.
    /// `photons` are the pass's map and [`Self::prev_inputs`]' table.
    ///
    /// The samples are taken together in stages so that the photon-map reads of one sample
    /// are fetched while the others compute: first every sample's rays, shading and weights
    /// up to its gathers (starting the gathers' queries), then rounds that move every
    /// query on, then the gathers. Each sample's arithmetic is exactly that of a sample taken
    /// alone, so the results do not depend on the batch.
    pub(crate) fn sample_batch<'s>(
        &'s self,
        photons: (&PhotonMap, &[[f32; 3]]),
        plan: &PixelPlan<'_>,
        jobs: &mut [Job],
        slots: &mut Slots<'s>,
        stats: &mut WeightStats,
    ) {
        assert!(jobs.len() <= BATCH, "at most {BATCH} samples per batch");
        let weigher = plan
            .weigher
            .as_ref()
            .expect("a pixel of the mix has a weigher");
        let map = photons.0;
        // Only this batch's slots: the others still hold an earlier batch's samples.
        let slots = &mut slots.0[..jobs.len()];
        for (job, slot) in jobs.iter_mut().zip(slots.iter_mut()) {
            slot.out = SampleOut::default();
            slot.x0 = None;
            slot.second = None;
            self.start_sample(map, job, plan, (weigher, &mut *stats), slot);
        }
        for _ in 0..QUERY_STAGES {
            for slot in slots.iter_mut().filter(|s| s.x0.is_some()) {
                if slot.second.is_some() {
                    map.advance_query(&mut slot.query1);
                }
                if self.merges_at_x0() {
                    map.advance_query(&mut slot.query0);
                }
            }
        }
        // The kernel 1/S of the pixel, for both merges of every sample.
        let k = self.inv_area / (plan.radius_scale * plan.radius_scale);
        for slot in slots.iter_mut() {
            let Slot {
                out,
                x0,
                second,
                query0,
                query1,
            } = slot;
            let Some(x0) = x0 else { continue };
            let camera_w1 = second.as_ref().map(|s| s.w_const);
            if let Some(second) = second {
                self.merge_at_x1(x0, (map, k), second, query1, (weigher, &mut *stats), out);
            }
            if self.merges_at_x0() {
                let at_x0 = (&*query0, camera_w1);
                let weights = (weigher, &mut *stats);
                // Compiled twice: without delta materials the merge has no delta branch at all.
                if self.scene.has_delta() {
                    self.merge_at_x0::<true>(x0, (photons, k), at_x0, weights, out);
                } else {
                    self.merge_at_x0::<false>(x0, (photons, k), at_x0, weights, out);
                }
            }
            if let Some(beta) = x0.beta {
                out.techniques.scale_merges(beta.as_dvec3());
            }
        }
    }

    /// Everything of one sample up to its gathers: the direct light at x₀ goes into its
    /// output, the rest into `slot` (whose `x0` stays None if the sample ends before any
    /// gather).
    fn start_sample<'s>(
        &'s self,
        map: &PhotonMap,
        job: &mut Job,
        plan: &PixelPlan<'_>,
        weights: (&Weigher, &mut WeightStats),
        slot: &mut Slot<'s>,
    ) {
        let scene = self.scene;
        let cam = &scene.camera();
        let dir = cam.ray_direction(job.x, job.y);
        let (sh0, u, beta) = self.camera_x0(dir, &mut job.rng);
        // x₀'s area-light sample is weighed against BDD=1's BDF ray where the mode traces it
        // (docs/method-notes.md, "Area lights: MIS at x₀").
        let mis = self.needs.second_vertex;
        let direct = sh0.as_ref().map_or(Vec3::ZERO, |sh| {
            let mut l0 = scene.direct(sh, u);
            if scene.has_emission() {
                l0 += emitted_and_area(scene, sh, u, job.rng.uniform3(), mis);
            }
            beta.map_or(l0, |b| b * l0)
        });
        let extra = plan.direct_extra(job.k);
        // The number of points whose L₀ the direct term averages (`direct_boost`).
        let m = extra.as_ref().map_or(1, |e| e.count + 1);
        slot.out.techniques.direct = match extra {
            // The mean of L₀ over the sample's point and the further ones, whether or not
            // the sample's own ray meets anything.
            Some(mut extra) => extra.mean_with(scene, direct),
            None => direct.as_dvec3(),
        };
        let Some(sh0) = sh0 else {
            return;
        };
        let Some(mut x0) = self.first_vertex_shaded(sh0, u) else {
            return;
        };
        x0.beta = beta;
        let r = self.radius * plan.radius_scale;
        if self.merges_at_x0() {
            map.restart_query_within(&mut slot.query0, x0.sh.p, r);
        }
        if self.needs.second_vertex {
            let drawn = job.rng.uniform3();
            let bdf_u = job.bdf.unwrap_or(drawn);
            let n = self.one_bounce_samples(&x0, plan.one_bounce);
            let share = 1.0 / n as f32;
            let (weigher, stats) = weights;
            slot.second = self.start_second(
                &x0,
                map,
                (bdf_u, r, m, share, &mut job.rng),
                (weigher, &mut *stats),
                &mut slot.query1,
                &mut slot.out,
            );
            for _ in 1..n {
                let u = job.rng.uniform3();
                let (weights, out) = ((weigher, &mut *stats), &mut slot.out);
                self.one_bounce_again(&x0, (u, share), &mut job.rng, weights, out);
            }
        }
        slot.x0 = Some(x0);
    }

    /// The camera ray along `dir` to x₀: its shading, the direction back along the ray that
    /// reached it, and the throughput of the mirrors and glass before it (`None` where there
    /// were none). Through delta vertices only in a scene that has them (`rng` chooses their
    /// branches); otherwise the primary hit alone, as cheaply as before there were any.
    #[inline]
    fn camera_x0(&self, dir: Vec3, rng: &mut Rng) -> (Option<Shading>, Vec3, Option<Vec3>) {
        let scene = self.scene;
        let origin = scene.camera().position();
        if !scene.has_delta() {
            let hit = scene.geometry().intersect(origin, dir, f32::INFINITY);
            return (hit.map(|hit| scene.shade(&hit, -dir)), -dir, None);
        }
        match scene.walk_to_non_delta(origin, dir, Transport::Radiance, || rng.uniform()) {
            Some(w) => (Some(w.sh), w.wo, (w.vertices > 0).then_some(w.beta)),
            None => (None, -dir, None),
        }
    }

    /// BDD=1 up to its gather: sample v at x₀ (never absorbed), find x₁, weigh the one-bounce
    /// paths light→x₁→x₀, and start the photon query at x₁.
    fn start_second(
        &self,
        x0: &FirstVertex<'_>,
        map: &PhotonMap,
        (u, r, m, share, rng): ([f32; 3], f32, u32, f32, &mut Rng),
        (weigher, stats): (&Weigher, &mut WeightStats),
        query: &mut PhotonQuery,
        out: &mut SampleOut,
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
        // A mirror or glass between x₀ and x₁: through it, with the weight of such paths.
        if scene.is_delta(hit1.material) {
            let through = (s.weight, v, r, share);
            return self.second_through_delta(x0, map, through, rng, query, &mut out.pilot);
        }
        if scene.has_emission() {
            out.techniques.direct += emitter_hit_at_x1(scene, x0, &s, &hit1, m);
        }
        // Started before the shadow ray and the weight's inputs, which hide its first fetch.
        map.restart_query_within(query, hit1.p, r);
        let wo1 = -v;
        // Likewise the weight's cache read, fetched during the shadow ray.
        let slot = self.cache_slot(hit1.prim, hit1.p, wo1);
        if let (Some(cache), Some(slot)) = (self.cache, slot) {
            cache.prefetch(slot);
        }
        let (sh1, x1, pair, dist2) = self.x1_from(x0, (&hit1, v), slot);
        let at = (&sh1, &x1, v, dist2, pair);
        let e = (s.weight, share);
        let (direct, w_const) = self.one_bounce(x0, at, e, rng, (weigher, stats), &mut out.pilot);
        Some(Second {
            sh1,
            x1,
            v,
            dist2,
            pair,
            w_const,
            weight: s.weight,
            direct_raw: direct.0 * share,
            direct_weighted: direct.1 * share,
        })
    }

    /// How many x₁ a camera sample takes for BDD=1's one-bounce paths light→x₁→x₀ at `x0`:
    /// its pixel's allocation `n` (crate::one_bounce) at a glossy x₀, else 1. Only scenes with
    /// area lights and glossy surfaces allocate more than one.
    pub(crate) fn one_bounce_samples(&self, x0: &FirstVertex<'_>, n: u32) -> u32 {
        if n > 1 && !x0.bdf.is_lambert() { n } else { 1 }
    }

    /// A further x₁ for BDD=1's one-bounce paths at `x0` (numbers `u` at x₀, the estimate's
    /// share 1/n of the camera sample's n): its one-bounce paths, through the mirrors and glass
    /// before it where there are any, added to the sample's BDD=1 output `out` with their
    /// weights w₁. No gather and no emitter hit: those the sample's own x₁ estimates.
    fn one_bounce_again(
        &self,
        x0: &FirstVertex<'_>,
        (u, share): ([f32; 3], f32),
        rng: &mut Rng,
        (weigher, stats): (&Weigher, &mut WeightStats),
        out: &mut SampleOut,
    ) {
        let scene = self.scene;
        let Some(s) = x0.bdf.sample_at(&x0.out, u) else {
            return;
        };
        let v = x0.sh.frame.to_world(s.wi);
        if x0.sh.ng.dot(v) <= 0.0 {
            return;
        }
        let origin = scene.spawn(&x0.sh, v);
        let Some(hit1) = scene.geometry().intersect(origin, v, f32::INFINITY) else {
            return;
        };
        let (raw, weighted) = if scene.is_delta(hit1.material) {
            let w = self.chain_w1(x0);
            let walk = (w > 0.0)
                .then(|| scene.walk_to_non_delta(origin, v, Transport::Radiance, || rng.uniform()))
                .flatten();
            let Some(walk) = walk else {
                return;
            };
            let raw = walk.beta * chain_direct(scene, &walk.sh, walk.wo, rng);
            if self.pilot && raw != Vec3::ZERO {
                out.pilot
                    .add(f64::from(luminance(s.weight * raw * share)), w, true);
            }
            (raw, raw * w as f32)
        } else {
            let wo1 = -v;
            let slot = self.cache_slot(hit1.prim, hit1.p, wo1);
            let (sh1, x1, pair, dist2) = self.x1_from(x0, (&hit1, v), slot);
            let at = (&sh1, &x1, v, dist2, pair);
            let e = (s.weight, share);
            self.one_bounce(x0, at, e, rng, (weigher, stats), &mut out.pilot)
                .0
        };
        let t = &mut out.techniques;
        t.x1_raw += (s.weight * raw * share).as_dvec3();
        t.x1_weighted += (s.weight * weighted * share).as_dvec3();
    }

    /// x₁ at `hit1`, reached from `x0` along the unit direction `v`, with its cache `slot`: its
    /// shading, its weight vertex, the pair's camera side and the squared distance from x₀ (m²).
    fn x1_from(
        &self,
        x0: &FirstVertex<'_>,
        (hit1, v): (&Hit, Vec3),
        slot: Option<CacheSlot>,
    ) -> (Shading, WeightVertex, Pair, f32) {
        let sh1 = self.scene.shade(hit1, -v);
        let x1 = self.scene.weight_vertex(&sh1);
        let pair = self.camera_side_base(x0, &x1, v, slot);
        let dist2 = (x1.p - x0.sh.p).length_squared();
        (sh1, x1, pair, dist2)
    }

    /// The one-bounce paths light→x₁→x₀ of one x₁ (`at`: its shading and weight vertex, the
    /// unit direction and squared distance from x₀, the pair's camera side), light by light:
    /// the (raw, weighted by w₁) sums of their values (W·m⁻²·sr⁻¹, before x₀'s f·cos/p `e.0`),
    /// and w₁ of the merge paths through x₁. `e.1`, the estimate's share of the camera
    /// sample's, scales what `corrected-balance`'s pilot is told.
    fn one_bounce(
        &self,
        x0: &FirstVertex<'_>,
        (sh1, x1, v, dist2, pair): (&Shading, &WeightVertex, Vec3, f32, Pair),
        (e, share): (Vec3, f32),
        rng: &mut Rng,
        (weigher, stats): (&Weigher, &mut WeightStats),
        pilot: &mut CandidateSums,
    ) -> ((Vec3, Vec3), f64) {
        let scene = self.scene;
        let wo1 = -v;
        let lights = x1.lights;
        let e = e * share;
        // One-bounce paths light→x₁→x₀, light by light (their balance weights differ).
        // (raw, weighted by w₁) sums of their values.
        let mut direct = (Vec3::ZERO, Vec3::ZERO);
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
            let one = self.path_pair(x0, x1, (v, dist2), Arrival::Light(0), pair);
            self.w1(&one, weigher, stats)
        } else {
            w_const
        };
        for l in 0..scene.lights().len() {
            let c = scene.direct_from_masked(sh1, wo1, l, lights);
            if c == Vec3::ZERO {
                continue;
            }
            let w = if per_light {
                let one = self.path_pair(x0, x1, (v, dist2), Arrival::Light(l), pair);
                self.w1(&one, weigher, stats)
            } else {
                w_direct
            };
            self.add_one_bounce(&mut direct, (c, w), e, pilot);
        }
        if scene.has_emission() {
            let at = (sh1, x1, v, dist2);
            let area = self.area_at_x1(x0, at, pair, rng, (weigher, stats));
            for cw in area.into_iter().flatten() {
                self.add_one_bounce(&mut direct, cw, e, pilot);
            }
        }
        (direct, w_const)
    }

    /// Adds a one-bounce path's value `c` (W·m⁻²·sr⁻¹) at x₁ with its weight `w` to the
    /// (raw, weighted) sums `direct`, and to `corrected-balance`'s pilot with x₀'s f·cos/p `e`.
    fn add_one_bounce(
        &self,
        direct: &mut (Vec3, Vec3),
        (c, w): (Vec3, f64),
        e: Vec3,
        pilot: &mut CandidateSums,
    ) {
        direct.0 += c;
        direct.1 += c * w as f32;
        if self.pilot {
            pilot.add(f64::from(luminance(e * c)), w, true);
        }
    }

    /// The one-bounce paths light→x₁→x₀ from the area lights (x₁ seen from x₀ along `v`,
    /// |x₁ − x₀|² = `dist2`): at a glossy x₁ by two strategies, one light sample and one BDF
    /// ray weighted against each other by the power heuristic as in `path`, at a Lambert x₁
    /// by the light sample alone (docs/method-notes.md, "Area lights: MIS at x₁"), each with
    /// its raw value and w₁ of its own path (`Arrival::Area`, as the photon side gives the
    /// same path); None where a strategy brings nothing.
    fn area_at_x1(
        &self,
        x0: &FirstVertex<'_>,
        (sh1, x1, v, dist2): (&Shading, &WeightVertex, Vec3, f32),
        pair: Pair,
        rng: &mut Rng,
        (weigher, stats): (&Weigher, &mut WeightStats),
    ) -> [Option<(Vec3, f64)>; 2] {
        area_samples_at_x1(self.scene, sh1, -v, rng).map(|sample| {
            let (c, wi) = sample?;
            let w = self.fixed_w1.unwrap_or_else(|| {
                let one = self.path_pair(x0, x1, (v, dist2), Arrival::Area(wi), pair);
                self.w1(&one, weigher, stats)
            });
            Some((c, w))
        })
    }

    /// BDD=1 through the delta vertices the direction `v` sampled at x₀ (with weight `e`,
    /// f·cos/p) meets first, to the first non-delta x₁ (`rng` chooses the branches): x₁'s
    /// direct light and the start of its gather, every path weighted by [`Mix::chain_w1`].
    /// `None` where that weight is 0 (nothing traced) or the walk ends. Out of line: only
    /// scenes with delta materials come here.
    #[cold]
    #[inline(never)]
    fn second_through_delta(
        &self,
        x0: &FirstVertex<'_>,
        map: &PhotonMap,
        (e, v, r, share): (Vec3, Vec3, f32, f32),
        rng: &mut Rng,
        query: &mut PhotonQuery,
        pilot: &mut CandidateSums,
    ) -> Option<Second> {
        let w = self.chain_w1(x0);
        if w <= 0.0 {
            return None;
        }
        let scene = self.scene;
        let origin = scene.spawn(&x0.sh, v);
        let walk = scene.walk_to_non_delta(origin, v, Transport::Radiance, || rng.uniform())?;
        let sh1 = walk.sh;
        map.restart_query_within(query, sh1.p, r);
        let direct_raw = chain_direct(scene, &sh1, walk.wo, rng) * share;
        let weight = e * walk.beta;
        if self.pilot && direct_raw != Vec3::ZERO {
            pilot.add(f64::from(luminance(weight * direct_raw)), w, true);
        }
        Some(Second {
            sh1,
            x1: WeightVertex::at(&sh1, 0),
            v: -walk.wo,
            dist2: 0.0,
            pair: Pair::default(),
            w_const: w,
            weight,
            direct_raw,
            direct_weighted: direct_raw * w as f32,
        })
    }

    /// BDD=1's merge paths …→x₂→x₁→x₀: photons around x₁, weighted by w₁; finishes the x₁
    /// part of the sample's output `out`.
    fn merge_at_x1(
        &self,
        x0: &FirstVertex<'_>,
        (map, k): (&PhotonMap, f32),
        second: &Second,
        query: &PhotonQuery,
        (weigher, stats): (&Weigher, &mut WeightStats),
        out: &mut SampleOut,
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
        let chain = second.chain();
        let wo1 = -v;
        // Weights that read the light path's own inputs differ from photon to photon.
        let per_path = (self.needs.densities || self.needs.x1_scattering) && !chain;
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
                out.pilot.add(f64::from(luminance(e * c) * k), w, true);
            }
        });
        let t = &mut out.techniques;
        // Added to what further x₁ of the sample's one-bounce paths brought (`one_bounce_again`).
        t.x1_raw += (e * (direct_raw + ph_raw * k)).as_dvec3();
        t.x1_weighted += (e * (direct_weighted + ph_weighted * k)).as_dvec3();
    }

    /// BDD=0: photons around x₀ (`query`), each weighted by 1 − w₁(x₀, y_p) (method.md §2),
    /// into the sample's output `out`; `camera_w1` is the camera's w₁ at its own x₁ (for the
    /// biased test variant only). `DELTA`: the scene has delta materials
    /// ([`bdpm_scene::Scene::has_delta`]), whose paths [`Mix::after_delta`] tells apart.
    fn merge_at_x0<const DELTA: bool>(
        &self,
        x0: &FirstVertex<'_>,
        (photons, k): ((&PhotonMap, &[[f32; 3]]), f32),
        (query, camera_w1): (&PhotonQuery, Option<f64>),
        (weigher, stats): (&Weigher, &mut WeightStats),
        out: &mut SampleOut,
    ) {
        let scene = self.scene;
        let chain_w1 = if DELTA { self.chain_w1(x0) } else { 0.0 };
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
            let chain = if DELTA {
                self.after_delta(photons.0, ph)
            } else {
                None
            };
            let w0 = if let Some(chain) = chain {
                // BDD=1 cannot sample L–S…–x₀; …–x₁–S…–x₀ it takes with `chain_w1`.
                let w1 = match chain {
                    DeltaChain::FromLight => 0.0,
                    DeltaChain::FromVertex => chain_w1,
                };
                if self.pilot {
                    out.pilot.add(f64::from(luminance(c) * k), w1, false);
                }
                1.0 - w1
            } else if let Some(w1) = self.fixed_w1 {
                1.0 - w1
            } else if self.camera_x1_weighting() {
                1.0 - camera_w1.unwrap_or(0.0)
            } else {
                let Some(pair) = self.photon_side_pair(photons, x0, i, ph) else {
                    return;
                };
                let w1 = self.w1(&pair, weigher, stats);
                if self.pilot {
                    out.pilot.add(f64::from(luminance(c) * k), w1, false);
                }
                1.0 - w1
            };
            weighted += c * w0 as f32;
        });
        out.techniques.x0_raw = (raw * k).as_dvec3();
        out.techniques.x0_weighted = (weighted * k).as_dvec3();
    }
}

/// The BDF ray from x₀ to x₁ as the second strategy of x₀'s area-light direct term: Le at x₁
/// (an emitter seen from x₀) times x₀'s f·cos/p, weighted by the power heuristic against
/// x₀'s light sample (which took the complementary weight, `Scene::direct_area` with MIS),
/// through the mirrors and glass before x₀, and divided by the `m` points whose L₀ the
/// direct term averages (only the sample's own light sample is weighed against this ray),
/// W·m⁻²·sr⁻¹. 0 where x₁ emits nothing towards x₀.
fn emitter_hit_at_x1(
    scene: &Scene,
    x0: &FirstVertex<'_>,
    s: &BdfSample,
    hit1: &Hit,
    m: u32,
) -> DVec3 {
    let le = scene.emitted_mis(x0.sh.p, s.pdf, hit1.prim, hit1.p, hit1.uv);
    if le == Vec3::ZERO {
        return DVec3::ZERO;
    }
    let c = s.weight * le;
    let c = x0.beta.map_or(c, |b| b * c);
    c.as_dvec3() / f64::from(m)
}
