//! The camera pass: the one loop over an image's pixels that every camera-side estimator runs
//! in (the BDPM mix, crate::pass; `path`; `light`'s direct term; the first-hit layers). Rows
//! run in parallel; each pixel's plan is built once (crate::plan) and its samples placed by
//! the sampler; an estimator says only what one pixel's samples give, into its row's results,
//! which come back in row order, so the image does not depend on the threads.
use bdpm_bdf::Transport;
use bdpm_scene::Scene;
use bdpm_settings::RenderSettings;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::estimates::{PassOutput, WeightStats, accumulate};
use crate::plan::{PixelPlan, PixelPlanner};
use crate::sampler::PixelSamples;
use crate::stage::{Stage, never};

/// What one pixel's camera samples give, as the camera pass drives it.
pub(crate) trait PixelEstimator: Sync {
    /// State reused from pixel to pixel of a row (e.g. a batch's slots).
    type Scratch;
    /// A row's results, pixel after pixel.
    type Row: Default + Send;

    /// Fresh scratch for a row.
    fn scratch(&self) -> Self::Scratch;

    /// Takes the samples of the pixel of `plan` and adds what they give to `row`.
    fn pixel(&self, plan: &PixelPlan<'_>, scratch: &mut Self::Scratch, row: &mut Self::Row);
}

/// Runs `estimator` over every pixel of pass `pass` under `s` (N_B, the sampler's layout on
/// the seed of `s`), each pixel's plan from `planner`. `progress` is told of each row done;
/// `stop`, asked before each row, gives up with `None`. The rows come back in order.
pub(crate) fn camera_pass<E: PixelEstimator>(
    s: &RenderSettings,
    pass: u32,
    planner: &PixelPlanner<'_>,
    estimator: &E,
    progress: &(dyn Fn(u64) + Sync),
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<Vec<E::Row>> {
    let w = s.width as usize;
    (0..s.height as usize)
        .into_par_iter()
        .map(|y| {
            if stop() {
                return None;
            }
            let mut layout = PixelSamples::new(s);
            let mut scratch = estimator.scratch();
            let mut row = E::Row::default();
            for x in 0..w {
                layout.start(pass, (y * w + x) as u64);
                let plan = planner.plan(x as u32, y as u32, &layout);
                estimator.pixel(&plan, &mut scratch, &mut row);
            }
            progress(1);
            Some(row)
        })
        .collect()
}

/// A row's pixel estimates and its dropped (non-finite) samples.
#[derive(Default)]
pub(crate) struct EstimateRow {
    pub(crate) estimates: Vec<DVec3>,
    pub(crate) dropped: u64,
}

impl EstimateRow {
    /// The rows' estimates in row order, and their dropped samples.
    pub(crate) fn concat(rows: Vec<EstimateRow>, pixels: usize) -> (Vec<DVec3>, u64) {
        let mut estimates = Vec::with_capacity(pixels);
        let mut dropped = 0;
        for row in rows {
            estimates.extend(row.estimates);
            dropped += row.dropped;
        }
        (estimates, dropped)
    }

    /// Ends a pixel: the mean of `sum` over `n` samples.
    #[inline]
    pub(crate) fn push_mean(&mut self, sum: DVec3, n: u32) {
        self.estimates.push(sum / n as f64);
    }
}

/// `path`'s camera samples: a path-traced radiance sample through each.
struct PathPixels<'s> {
    scene: &'s Scene,
    spp: u32,
    roulette_depth: u32,
}

impl PixelEstimator for PathPixels<'_> {
    type Scratch = ();
    type Row = EstimateRow;

    fn scratch(&self) {}

    fn pixel(&self, plan: &PixelPlan<'_>, _: &mut (), row: &mut EstimateRow) {
        let cam = self.scene.camera();
        let mut sum = DVec3::ZERO;
        for k in 0..self.spp {
            let mut c = plan.sample(k);
            let (x, y) = (plan.x as f32 + c.offset[0], plan.y as f32 + c.offset[1]);
            let l = crate::path::trace_path_with_first(
                self.scene,
                (cam.position(), cam.ray_direction(x, y)),
                &mut c.rng,
                self.roulette_depth,
                c.bdf,
            );
            accumulate(&mut sum, l, &mut row.dropped);
        }
        row.push_mean(sum, self.spp);
    }
}

/// Renders pass `pass` of the `path` reference: N_B jittered samples per pixel, each a pure
/// function of (seed, pass, pixel, sample). `progress` is called with the number of rows done.
pub fn render_path_pass(
    scene: &Scene,
    settings: &RenderSettings,
    pass: u32,
    progress: &(dyn Fn(u64) + Sync),
) -> PassOutput {
    let start = std::time::Instant::now();
    let pixels = settings.width as usize * settings.height as usize;
    let path = PathPixels {
        scene,
        spp: settings.spp,
        roulette_depth: settings.roulette_depth,
    };
    let planner = PixelPlanner::unweighted(None);
    let rows = camera_pass(settings, pass, &planner, &path, progress, &never)
        .expect("a pass that is never stopped is complete");
    let (estimates, dropped) = EstimateRow::concat(rows, pixels);
    PassOutput {
        estimates,
        dropped,
        samples: pixels as u64 * settings.spp as u64,
        stage_seconds: vec![(Stage::Camera, start.elapsed().as_secs_f64())],
        techniques: None,
        photons_stored: 0,
        photon_map_bytes: 0,
        weights: WeightStats::default(),
    }
}

/// Per-pixel first-hit layers for denoisers (Open Image Denoise and the like), see
/// [`first_hit_layers`].
#[derive(Clone, Debug)]
pub struct FirstHitLayers {
    /// Directional albedo µ(wo) of the surface first seen, averaged over the pixel's samples,
    /// each channel in [0, 1]; 0 where nothing is seen. Row-major.
    pub albedo: Vec<DVec3>,
    /// World-space unit shading normal at the first hit (facing the camera), averaged over the
    /// pixel's samples and renormalised; 0 where nothing is seen. Row-major.
    pub normal: Vec<DVec3>,
}

/// The first-hit layers' camera samples: one primary ray each.
struct FirstHits<'s> {
    scene: &'s Scene,
    spp: u32,
}

impl PixelEstimator for FirstHits<'_> {
    type Scratch = ();
    /// Each pixel's (albedo, normal).
    type Row = Vec<(DVec3, DVec3)>;

    fn scratch(&self) {}

    fn pixel(&self, plan: &PixelPlan<'_>, _: &mut (), row: &mut Self::Row) {
        let (scene, cam) = (self.scene, self.scene.camera());
        let (mut albedo, mut normal) = (DVec3::ZERO, DVec3::ZERO);
        for k in 0..self.spp {
            let mut c = plan.sample(k);
            let [jx, jy] = c.offset;
            let dir = cam.ray_direction(plan.x as f32 + jx, plan.y as f32 + jy);
            // The first non-delta surface, as denoisers expect: a mirror shows what it reflects.
            let walk = scene
                .walk_to_non_delta(cam.position(), dir, Transport::Radiance, || c.rng.uniform());
            let Some(walk) = walk else {
                continue;
            };
            let (sh, wo) = (walk.sh, walk.wo);
            let a = walk.beta * scene.bdf_at(&sh).albedo(sh.frame.to_local(wo));
            albedo += a.clamp(Vec3::ZERO, Vec3::ONE).as_dvec3();
            normal += sh.frame.n.as_dvec3();
        }
        row.push((albedo / self.spp as f64, normal.normalize_or_zero()));
    }
}

/// Traces one primary ray per camera sample of pass 0 (the same jittered positions: the
/// camera stream of (seed, 0, pixel, sample)) and records the first hit's directional albedo
/// and shading normal. Costs `spp` ray casts per pixel, independent of the radiance passes,
/// whose bits it does not touch.
pub fn first_hit_layers(scene: &Scene, settings: &RenderSettings) -> FirstHitLayers {
    let hits = FirstHits {
        scene,
        spp: settings.spp.max(1),
    };
    let planner = PixelPlanner::unweighted(None);
    let rows = camera_pass(settings, 0, &planner, &hits, &|_| {}, &never)
        .expect("a pass that is never stopped is complete");
    let (albedo, normal) = rows.into_iter().flatten().unzip();
    FirstHitLayers { albedo, normal }
}
