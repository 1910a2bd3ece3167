//! The `light` reference: exact direct light at the camera's first vertex plus light tracing
//! for everything else (every photon arrival after ≥ 1 scattering is connected to the camera).
//! It is unbiased and independent of the BDPM code paths, and it converges fast where a small
//! bright secondary source (the Cornell ceiling spot) makes `path` slow (method.md §10).
use bdpm_geometry::Domain;
use bdpm_photon::{TraceOptions, trace_photons};
use bdpm_scene::Scene;
use glam::{DVec3, Vec3};

use crate::camera::{EstimateRow, PixelEstimator, camera_pass};
use crate::connect::connect;
use crate::direct::{DirectSamples, direct_through};
use crate::estimates::{PassOutput, accumulate};
use crate::plan::{PixelPlan, PixelPlanner};
use crate::stage::{Stage, never};
use bdpm_settings::RenderSettings;

/// The `light` reference's camera samples: exact direct light at x₀, over the pixel's
/// direct-light samples (crate::direct).
struct DirectPixels<'s> {
    scene: &'s Scene,
    spp: u32,
}

impl PixelEstimator for DirectPixels<'_> {
    type Scratch = ();
    type Row = EstimateRow;

    fn scratch(&self) {}

    fn pixel(&self, plan: &PixelPlan<'_>, _: &mut (), row: &mut EstimateRow) {
        let mut sum = DVec3::ZERO;
        for k in 0..self.spp {
            let mut c = plan.sample(k);
            let [jx, jy] = c.offset;
            let (x, y) = (plan.x as f32 + jx, plan.y as f32 + jy);
            let mut l = direct_through(self.scene, x, y, || c.rng.uniform());
            if let Some(mut extra) = plan.direct_extra(k) {
                l = extra.mean_with(self.scene, l).as_vec3();
            }
            accumulate(&mut sum, l, &mut row.dropped);
        }
        row.push_mean(sum, self.spp);
    }
}

/// Renders one pass of the `light` reference; `direct` gives the pixels whose direct term
/// takes more than one point per camera sample (`direct_boost`, crate::direct).
pub(crate) fn render_light_pass(
    scene: &Scene,
    settings: &RenderSettings,
    direct: Option<&DirectSamples>,
    pass: u32,
    progress: &(dyn Fn(u64) + Sync),
) -> PassOutput {
    let (w, h) = (settings.width as usize, settings.height as usize);
    let t_camera = std::time::Instant::now();
    let pixels = DirectPixels {
        scene,
        spp: settings.spp,
    };
    let planner = PixelPlanner::unweighted(direct);
    let rows = camera_pass(settings, pass, &planner, &pixels, progress, &never)
        .expect("a pass that is never stopped is complete");
    let (mut estimates, camera_dropped) = EstimateRow::concat(rows, w * h);
    let camera_seconds = t_camera.elapsed().as_secs_f64();

    let t_light = std::time::Instant::now();
    let options = TraceOptions {
        photons: settings.photons,
        seed: settings.seed,
        domain: Domain::Photon,
        pass,
        light_visibility: false,
        max_depth: bdpm_photon::MAX_DEPTH,
    };
    // Splats come back in photon order, so the sums below do not depend on the thread count.
    let splats: Vec<(u32, Vec3)> = trace_photons(scene, &options, |arrival, out| {
        // Nothing connects to a delta vertex: its BSDF is zero for every given pair.
        if arrival.vertex.depth == 0 || arrival.delta {
            return;
        }
        let sh = &arrival.shading;
        if let Some(c) = connect(scene, sh, arrival.vertex.incoming, arrival.power) {
            out.push((c.y * w as u32 + c.x, c.value));
        }
    });
    let mut light = vec![DVec3::ZERO; w * h];
    let mut light_dropped = 0;
    for (pixel, value) in splats {
        accumulate(&mut light[pixel as usize], value, &mut light_dropped);
    }
    for (e, l) in estimates.iter_mut().zip(&light) {
        *e += *l;
    }
    PassOutput {
        estimates,
        dropped: camera_dropped + light_dropped,
        samples: (w * h) as u64 * settings.spp as u64,
        stage_seconds: vec![
            (Stage::Camera, camera_seconds),
            (Stage::LightTracing, t_light.elapsed().as_secs_f64()),
        ],
        techniques: None,
        photons_stored: 0,
        photon_map_bytes: 0,
        weights: Default::default(),
    }
}
