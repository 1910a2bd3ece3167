//! One pass of the BDPM mix: the photon map (and with light tracing the splats of its
//! arrivals), every pixel's camera samples, and the splats added in photon order.
use bdpm_bdf::luminance;
use bdpm_geometry::Domain;
use bdpm_mis::Weigher;
use bdpm_photon::{PhotonMap, TraceOptions};
use bdpm_scene::Scene;
use bdpm_settings::RenderSettings;
use glam::DVec3;
use rayon::prelude::*;

use crate::bdpm::{BATCH, Job, Slots};
use crate::connect::Splats;
use crate::correction::{CandidateSums, Correction};
use crate::direct::DirectSamples;
use crate::estimates::{PassOutput, Techniques, WeightStats};
use crate::mix::Mix;
use crate::products::Products;
use crate::sampler::PixelSamples;
use crate::setup::Setup;
use crate::stage::{self, Stage, StageProbe};
use crate::table::PixelTable;

/// What a BDPM pass reads besides its mix and settings: the scene and r, the per-pixel
/// preparations, whether to keep the split by technique, and the probe of its stages.
pub(crate) struct PassContext<'p> {
    pub(crate) scene: &'p Scene,
    /// Merge radius r, metres (the photon grid is built for the largest pixel's).
    pub(crate) radius: f32,
    pub(crate) table: Option<&'p PixelTable>,
    pub(crate) correction: Option<&'p Correction>,
    pub(crate) direct: Option<&'p DirectSamples>,
    /// Keep each pixel's estimate split by technique ([`PassOutput::techniques`]).
    pub(crate) record: bool,
    pub(crate) probe: Option<&'p dyn StageProbe>,
}

impl<'p> PassContext<'p> {
    /// The context of `setup` with the per-pixel preparations among `products`.
    pub(crate) fn new(
        setup: &'p Setup<'p>,
        products: &'p Products,
        record: bool,
        probe: Option<&'p dyn StageProbe>,
    ) -> Self {
        PassContext {
            scene: setup.scene,
            radius: setup.radius,
            table: products.get(),
            correction: products.get(),
            direct: products.get(),
            record,
            probe,
        }
    }
}

/// Pass `pass` of the mix `mix` under `s` (the render's settings, or the pilot's with
/// their own seed). With [`Mix::pilot`] it also returns each pixel's pass estimate under
/// every candidate factor of `corrected-balance` (luminance), and reads neither the pixel
/// table nor the factors (the pilot weighs with `balance`); otherwise that list is empty.
/// `None` when `stop()` stopped it (asked before each chunk of photons and each row).
pub(crate) fn bdpm_pass(
    cx: &PassContext<'_>,
    mix: &Mix<'_>,
    s: &RenderSettings,
    pass: u32,
    progress: &(dyn Fn(u64) + Sync),
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<(PassOutput, Vec<CandidateSums>)> {
    stage::enter(cx.probe, Stage::Photons);
    let t_photons = std::time::Instant::now();
    let (table, correction) = if mix.pilot {
        (None, None)
    } else {
        (cx.table, cx.correction)
    };
    let weigher_at = |x: u32, y: u32| {
        let factor = correction.map_or(1.0, |c| c.get(x, y));
        let p = table.map(|t| t.get(x, y));
        let inputs = (p.map(|p| p.camera_samples), p.map(|p| &p.terms));
        mix.weigher(inputs, factor, mix.radius_scale(x, y))
    };
    let (map, splats) = pass_photons(cx, mix, s, pass, &weigher_at, stop)?;
    let prev_inputs = mix.prev_inputs(&map);
    let photon_seconds = t_photons.elapsed().as_secs_f64();
    stage::leave(cx.probe, Stage::Photons);
    stage::enter(cx.probe, Stage::Camera);
    let t_camera = std::time::Instant::now();
    let camera = CameraPass {
        mix,
        s,
        pass,
        map: &map,
        prev_inputs: &prev_inputs,
        weigher_at: &weigher_at,
        direct: cx.direct,
        record: cx.record,
    };
    let rows: Vec<Row> = (0..s.height as usize)
        .into_par_iter()
        .map(|y| {
            if stop() {
                return None;
            }
            let row = camera.row(y);
            progress(1);
            Some(row)
        })
        .collect::<Option<_>>()?;
    stage::leave(cx.probe, Stage::Camera);
    let pixels = s.width as usize * s.height as usize;
    let sums = Gathered::new(rows, &splats, cx.record, mix.pilot, pixels);
    let out = PassOutput {
        estimates: sums.estimates,
        dropped: sums.dropped,
        samples: pixels as u64 * s.spp as u64,
        stage_seconds: vec![
            (Stage::Photons, photon_seconds),
            (Stage::Camera, t_camera.elapsed().as_secs_f64()),
        ],
        techniques: cx.record.then_some(sums.techniques),
        photons_stored: map.photons().len() as u64,
        photon_map_bytes: map.memory_bytes(),
        weights: sums.weights,
    };
    Some((out, sums.candidates))
}

/// The photon map of pass `pass` under `s`, and with light tracing the splats of its
/// arrivals (weighed with `weigher_at`); `None` when `stop()` stopped the tracing.
fn pass_photons<F: Fn(u32, u32) -> Weigher + Sync>(
    cx: &PassContext<'_>,
    mix: &Mix<'_>,
    s: &RenderSettings,
    pass: u32,
    weigher_at: &F,
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
    // Built for the largest pixel radius, which every gather's query may reach.
    let grid_radius = cx.radius * mix.largest_radius_scale();
    if mix.light_tracing {
        PhotonMap::trace_visiting_until(
            cx.scene,
            &options,
            grid_radius,
            |_| Splats::default(),
            |acc, a, vertices| mix.splat(a, vertices, weigher_at, acc),
            stop,
        )
    } else {
        // `PhotonMap::trace` is this with nothing visited.
        let no_visit = |_: &mut (), _: &_, _: &[_]| {};
        let traced = PhotonMap::trace_visiting_until(
            cx.scene,
            &options,
            grid_radius,
            |_| (),
            no_visit,
            stop,
        )?;
        Some((traced.0, Vec::new()))
    }
}

/// The camera samples of one BDPM pass, row by row ([`CameraPass::row`]).
struct CameraPass<'p, F> {
    mix: &'p Mix<'p>,
    s: &'p RenderSettings,
    pass: u32,
    map: &'p PhotonMap,
    prev_inputs: &'p [[f32; 3]],
    /// Each pixel's weigher.
    weigher_at: &'p F,
    direct: Option<&'p DirectSamples>,
    /// Keep each pixel's estimate split by technique.
    record: bool,
}

impl<F: Fn(u32, u32) -> Weigher + Sync> CameraPass<'_, F> {
    /// Image row `y`: each pixel's N_B camera samples, in batches of [`BATCH`].
    fn row(&self, y: usize) -> Row {
        let (mix, s, pass, record) = (self.mix, self.s, self.pass, self.record);
        let w = s.width as usize;
        let mut row = Row::default();
        let mut slots = Slots::default();
        let mut layout = PixelSamples::new(s);
        for x in 0..w {
            let pixel = (y * w + x) as u64;
            let mut sum = DVec3::ZERO;
            let mut tsum = Techniques::default();
            let mut csum = CandidateSums::default();
            let weigher = (self.weigher_at)(x as u32, y as u32);
            let direct_m = self.direct.map_or(1, |d| d.at(x as u32, y as u32));
            layout.start(pass, pixel);
            for first in (0..s.spp).step_by(BATCH) {
                let count = (s.spp - first).min(BATCH as u32);
                let mut jobs: [Job; BATCH] = std::array::from_fn(|i| {
                    // Past N_B the slot is unused; sample 0's numbers fill it.
                    let k = (first + i as u32).min(s.spp - 1);
                    let c = layout.sample(k);
                    let direct_extra = layout.direct_extra(k, (x as u32, y as u32), direct_m);
                    Job {
                        x: x as f32 + c.offset[0],
                        y: y as f32 + c.offset[1],
                        rng: c.rng,
                        bdf: c.bdf,
                        out: Techniques::default(),
                        pilot: CandidateSums::default(),
                        direct_extra,
                        scale: mix.radius_scale(x as u32, y as u32),
                    }
                });
                let jobs = &mut jobs[..count as usize];
                mix.sample_batch(
                    self.map,
                    self.prev_inputs,
                    jobs,
                    &mut slots,
                    &weigher,
                    &mut row.stats,
                );
                // Summed in sample order, so the pixel does not depend on the batching.
                for job in jobs.iter() {
                    let t = &job.out;
                    let value = t.total();
                    if value.is_finite() {
                        sum += value;
                        if record {
                            tsum.direct += t.direct;
                            tsum.x0_raw += t.x0_raw;
                            tsum.x0_weighted += t.x0_weighted;
                            tsum.x1_raw += t.x1_raw;
                            tsum.x1_weighted += t.x1_weighted;
                        }
                        if mix.pilot {
                            csum.add_sums(&job.pilot);
                            csum.add_to_all(f64::from(luminance(t.direct.as_vec3())));
                        }
                    } else {
                        row.dropped += 1;
                    }
                }
            }
            let n = s.spp as f64;
            row.estimates.push(sum / n);
            if record {
                row.techniques.push(Techniques {
                    direct: tsum.direct / n,
                    x0_raw: tsum.x0_raw / n,
                    x0_weighted: tsum.x0_weighted / n,
                    x1_raw: tsum.x1_raw / n,
                    x1_weighted: tsum.x1_weighted / n,
                });
            }
            if mix.pilot {
                row.candidates.push(csum.scaled(1.0 / n));
            }
        }
        row
    }
}

/// A pass's rows put together, with light tracing's splats added.
struct Gathered {
    estimates: Vec<DVec3>,
    techniques: Vec<Techniques>,
    candidates: Vec<CandidateSums>,
    dropped: u64,
    weights: WeightStats,
}

impl Gathered {
    /// The rows in row order, then the splats in photon order (so the sums do not depend on
    /// the threads); `record` keeps the technique split, `pilot` the candidates.
    fn new(rows: Vec<Row>, splats: &[Splats], record: bool, pilot: bool, pixels: usize) -> Self {
        let mut estimates = Vec::with_capacity(pixels);
        let mut techniques = Vec::with_capacity(if record { pixels } else { 0 });
        let mut candidates = Vec::new();
        let mut dropped = 0;
        let mut weights = WeightStats::default();
        for row in rows {
            estimates.extend(row.estimates);
            techniques.extend(row.techniques);
            candidates.extend(row.candidates);
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
                if record {
                    techniques[p].x0_raw += s.raw.as_dvec3();
                    techniques[p].x0_weighted += weighted.as_dvec3();
                }
                if pilot {
                    candidates[p].add(f64::from(luminance(s.raw)), s.w1, false);
                }
            }
        }
        Gathered {
            estimates,
            techniques,
            candidates,
            dropped,
            weights,
        }
    }
}

/// One image row of a BDPM pass, gathered in row order.
#[derive(Default)]
struct Row {
    estimates: Vec<DVec3>,
    techniques: Vec<Techniques>,
    candidates: Vec<CandidateSums>,
    dropped: u64,
    stats: WeightStats,
}
