//! One pass of the BDPM mix: the photon map (and with light tracing the splats of its
//! arrivals), every pixel's camera samples in the camera pass (crate::camera), and the splats
//! added in photon order. What a pass keeps per pixel beside its estimate is a
//! [`PixelAccumulator`] that plugs into both: the technique split, `corrected-balance`'s
//! candidate sums, or nothing.
use std::marker::PhantomData;

use bdpm_bdf::luminance;
use bdpm_geometry::Domain;
use bdpm_photon::{PhotonMap, TraceOptions};
use bdpm_settings::RenderSettings;
use glam::{DVec3, Vec3};

use crate::bdpm::{BATCH, Job, SampleOut, Slots};
use crate::camera::{PixelEstimator, camera_pass};
use crate::connect::{Splat, Splats};
use crate::correction::CandidateSums;
use crate::estimates::{PassOutput, Techniques, WeightStats};
use crate::mix::Mix;
use crate::plan::{PixelPlan, PixelPlanner};
use crate::products::Products;
use crate::setup::Setup;
use crate::stage::{self, Stage, StageProbe};

/// What a BDPM pass reads besides its mix and settings: the setup (the scene, r), the
/// products of the preparations (the pixel table, the factors, the direct-light samples) and
/// the probe of its stages.
pub(crate) struct PassContext<'p> {
    pub(crate) setup: &'p Setup<'p>,
    pub(crate) products: &'p Products,
    pub(crate) probe: Option<&'p dyn StageProbe>,
}

/// A per-pixel layer that a BDPM pass keeps beside its estimate. It plugs into the camera
/// pass, which feeds it every finite camera sample of the pixel, and into the splats of light
/// tracing, each added to the layer of the pixel it lands in.
pub(crate) trait PixelAccumulator {
    /// A pixel's running sum over its samples, then (after [`Self::finish`]) its value.
    type Sum: Default + Send;

    /// Adds a finite sample's output.
    fn add_sample(sum: &mut Self::Sum, out: &SampleOut);

    /// The pixel's value from the sum over its `n` samples.
    fn finish(sum: Self::Sum, n: f64) -> Self::Sum;

    /// Adds the finite splat `s`, of weighted value `weighted` (its raw value × (1 − w₁)).
    fn add_splat(pixel: &mut Self::Sum, s: &Splat, weighted: Vec3);
}

/// Nothing beside the estimate.
impl PixelAccumulator for () {
    type Sum = ();

    fn add_sample(_: &mut (), _: &SampleOut) {}

    fn finish(_: (), _: f64) {}

    fn add_splat(_: &mut (), _: &Splat, _: Vec3) {}
}

/// The estimate split by technique ([`PassOutput::techniques`]; the radius map's pilot).
pub(crate) struct TechniqueSplit;

impl PixelAccumulator for TechniqueSplit {
    type Sum = Techniques;

    fn add_sample(sum: &mut Techniques, out: &SampleOut) {
        let t = &out.techniques;
        sum.direct += t.direct;
        sum.x0_raw += t.x0_raw;
        sum.x0_weighted += t.x0_weighted;
        sum.x1_raw += t.x1_raw;
        sum.x1_weighted += t.x1_weighted;
    }

    fn finish(sum: Techniques, n: f64) -> Techniques {
        Techniques {
            direct: sum.direct / n,
            x0_raw: sum.x0_raw / n,
            x0_weighted: sum.x0_weighted / n,
            x1_raw: sum.x1_raw / n,
            x1_weighted: sum.x1_weighted / n,
        }
    }

    fn add_splat(pixel: &mut Techniques, s: &Splat, weighted: Vec3) {
        pixel.x0_raw += s.raw.as_dvec3();
        pixel.x0_weighted += weighted.as_dvec3();
    }
}

/// The pixel's estimate (luminance) under every candidate factor of `corrected-balance`
/// (its pilot, a mix with [`Mix::pilot`]).
pub(crate) struct CandidateLayer;

impl PixelAccumulator for CandidateLayer {
    type Sum = CandidateSums;

    fn add_sample(sum: &mut CandidateSums, out: &SampleOut) {
        sum.add_sums(&out.pilot);
        sum.add_to_all(f64::from(luminance(out.techniques.direct.as_vec3())));
    }

    fn finish(sum: CandidateSums, n: f64) -> CandidateSums {
        sum.scaled(1.0 / n)
    }

    fn add_splat(pixel: &mut CandidateSums, s: &Splat, _: Vec3) {
        pixel.add(f64::from(luminance(s.raw)), s.w1, false);
    }
}

/// Pass `pass` of the mix `mix` under `s` (the render's settings, or a pilot's with its own
/// seed), keeping each pixel's layer `A` beside its estimate. A pilot of `corrected-balance`
/// ([`Mix::pilot`]) reads neither the pixel table nor the factors (it weighs with `balance`).
/// `None` when `stop()` stopped it (asked before each chunk of photons and each row).
pub(crate) fn bdpm_pass<A: PixelAccumulator>(
    cx: &PassContext<'_>,
    mix: &Mix<'_>,
    s: &RenderSettings,
    pass: u32,
    progress: &(dyn Fn(u64) + Sync),
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<(PassOutput, Vec<A::Sum>)> {
    stage::enter(cx.probe, Stage::Photons);
    let t_photons = std::time::Instant::now();
    let planner = PixelPlanner::weighted(mix, cx.products);
    let (map, splats) = pass_photons(cx, mix, s, pass, &planner, stop)?;
    let prev_inputs = mix.prev_inputs(&map);
    let photon_seconds = t_photons.elapsed().as_secs_f64();
    stage::leave(cx.probe, Stage::Photons);
    stage::enter(cx.probe, Stage::Camera);
    let t_camera = std::time::Instant::now();
    let estimator = BdpmPixels::<A> {
        mix,
        photons: (&map, &prev_inputs),
        spp: s.spp,
        layer: PhantomData,
    };
    let rows = camera_pass(s, pass, &planner, &estimator, progress, stop)?;
    stage::leave(cx.probe, Stage::Camera);
    let pixels = s.width as usize * s.height as usize;
    let sums = Gathered::<A::Sum>::new::<A>(rows, &splats, pixels);
    let out = PassOutput {
        estimates: sums.estimates,
        dropped: sums.dropped,
        samples: pixels as u64 * s.spp as u64,
        stage_seconds: vec![
            (Stage::Photons, photon_seconds),
            (Stage::Camera, t_camera.elapsed().as_secs_f64()),
        ],
        techniques: None,
        photons_stored: map.photons().len() as u64,
        photon_map_bytes: map.memory_bytes(),
        weights: sums.weights,
    };
    Some((out, sums.layer))
}

/// The camera samples of a BDPM pass, in batches of [`BATCH`], with the layer `A`.
struct BdpmPixels<'p, A> {
    mix: &'p Mix<'p>,
    /// The pass's photon map and [`Mix::prev_inputs`]' table.
    photons: (&'p PhotonMap, &'p [[f32; 3]]),
    /// N_B.
    spp: u32,
    layer: PhantomData<fn() -> A>,
}

/// One image row of a BDPM pass.
struct BdpmRow<S> {
    estimates: Vec<DVec3>,
    layer: Vec<S>,
    dropped: u64,
    stats: WeightStats,
}

impl<S> Default for BdpmRow<S> {
    fn default() -> Self {
        BdpmRow {
            estimates: Vec::new(),
            layer: Vec::new(),
            dropped: 0,
            stats: WeightStats::default(),
        }
    }
}

impl<'p, A: PixelAccumulator> PixelEstimator for BdpmPixels<'p, A> {
    type Scratch = Slots<'p>;
    type Row = BdpmRow<A::Sum>;

    fn scratch(&self) -> Slots<'p> {
        Slots::default()
    }

    fn pixel(&self, plan: &PixelPlan<'_>, slots: &mut Slots<'p>, row: &mut Self::Row) {
        let spp = self.spp;
        let mut sum = DVec3::ZERO;
        let mut layer = A::Sum::default();
        for first in (0..spp).step_by(BATCH) {
            let count = (spp - first).min(BATCH as u32) as usize;
            // Past N_B the job is unused; the last sample's numbers fill it.
            let mut jobs: [Job; BATCH] =
                std::array::from_fn(|i| Job::new(plan, (first + i as u32).min(spp - 1)));
            let jobs = &mut jobs[..count];
            self.mix
                .sample_batch(self.photons, plan, jobs, slots, &mut row.stats);
            // Summed in sample order, so the pixel does not depend on the batching.
            for out in slots.outputs(count) {
                let value = out.techniques.total();
                if value.is_finite() {
                    sum += value;
                    A::add_sample(&mut layer, out);
                } else {
                    row.dropped += 1;
                }
            }
        }
        let n = spp as f64;
        row.estimates.push(sum / n);
        row.layer.push(A::finish(layer, n));
    }
}

/// A pass's rows put together, with light tracing's splats added.
struct Gathered<S> {
    estimates: Vec<DVec3>,
    layer: Vec<S>,
    dropped: u64,
    weights: WeightStats,
}

impl<S> Gathered<S> {
    /// The rows in row order, then the splats in photon order (so the sums do not depend on
    /// the threads), each added to its pixel's estimate and layer `A`.
    fn new<A: PixelAccumulator<Sum = S>>(
        rows: Vec<BdpmRow<S>>,
        splats: &[Splats],
        pixels: usize,
    ) -> Self {
        let mut estimates = Vec::with_capacity(pixels);
        let mut layer = Vec::with_capacity(pixels);
        let mut dropped = 0;
        let mut weights = WeightStats::default();
        for row in rows {
            estimates.extend(row.estimates);
            layer.extend(row.layer);
            dropped += row.dropped;
            // Integer sums: the total does not depend on the order rows finish in.
            weights.add(&row.stats);
        }
        for chunk in splats {
            weights.add(&chunk.stats);
            for s in &chunk.list {
                let p = s.pixel as usize;
                let weighted = s.raw * (1.0 - s.w1) as f32;
                if !(s.raw.is_finite() && weighted.is_finite()) {
                    dropped += 1;
                    continue;
                }
                estimates[p] += weighted.as_dvec3();
                A::add_splat(&mut layer[p], s, weighted);
            }
        }
        Gathered {
            estimates,
            layer,
            dropped,
            weights,
        }
    }
}

/// The photon map of pass `pass` under `s`, and with light tracing the splats of its
/// arrivals (each weighed with the weigher of the pixel it lands in, from `planner`); `None`
/// when `stop()` stopped the tracing.
fn pass_photons(
    cx: &PassContext<'_>,
    mix: &Mix<'_>,
    s: &RenderSettings,
    pass: u32,
    planner: &PixelPlanner<'_>,
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<(PhotonMap, Vec<Splats>)> {
    let options = TraceOptions {
        photons: s.photons,
        seed: s.seed,
        domain: Domain::Photon,
        pass,
        light_visibility: mix.needs.direct_at_x1,
        max_depth: bdpm_photon::MAX_DEPTH,
    };
    let scene = cx.setup.scene;
    // Built for the largest pixel radius, which every gather's query may reach.
    let grid_radius = cx.setup.radius * mix.largest_radius_scale();
    if mix.light_tracing {
        let weigher_at = |x, y| planner.weigher(x, y);
        PhotonMap::trace_visiting_until(
            scene,
            &options,
            grid_radius,
            |_| Splats::default(),
            |acc, a, vertices| mix.splat(a, vertices, weigher_at, acc),
            stop,
        )
    } else {
        // `PhotonMap::trace` is this with nothing visited.
        let no_visit = |_: &mut (), _: &_, _: &[_]| {};
        let traced =
            PhotonMap::trace_visiting_until(scene, &options, grid_radius, |_| (), no_visit, stop)?;
        Some((traced.0, Vec::new()))
    }
}
