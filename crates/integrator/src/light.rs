//! The `light` reference: exact direct light at the camera's first vertex plus light tracing
//! for everything else (every photon arrival after ≥ 1 scattering is connected to the camera).
//! It is unbiased and independent of the BDPM code paths, and it converges fast where a small
//! bright secondary source (the Cornell ceiling spot) makes `path` slow (method.md §10).
use std::sync::atomic::{AtomicU64, Ordering};

use bdpm_geometry::Domain;
use bdpm_photon::{TraceOptions, trace_photons};
use bdpm_scene::Scene;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::connect::connect;
use crate::direct::{DirectSamples, direct_through};
use crate::estimates::{PassOutput, accumulate};
use crate::sampler::PixelSamples;
use crate::stage::Stage;
use bdpm_settings::RenderSettings;

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
    let dropped = AtomicU64::new(0);
    let mut estimates = vec![DVec3::ZERO; w * h];
    estimates
        .par_chunks_mut(w)
        .enumerate()
        .for_each(|(y, row)| {
            let mut row_dropped = 0;
            let mut layout = PixelSamples::new(settings);
            for (x, px) in row.iter_mut().enumerate() {
                let pixel = (y * w + x) as u64;
                let mut sum = DVec3::ZERO;
                let xy = (x as u32, y as u32);
                let m = direct.map_or(1, |d| d.at(xy.0, xy.1));
                layout.start(pass, pixel);
                for k in 0..settings.spp {
                    let [jx, jy] = layout.sample(k).offset;
                    let mut l = direct_through(scene, x as f32 + jx, y as f32 + jy);
                    if let Some(mut extra) = layout.direct_extra(k, xy, m) {
                        l = extra.mean_with(scene, l).as_vec3();
                    }
                    accumulate(&mut sum, l, &mut row_dropped);
                }
                *px = sum / settings.spp as f64;
            }
            dropped.fetch_add(row_dropped, Ordering::Relaxed);
            progress(1);
        });
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
        if arrival.vertex.depth == 0 {
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
        dropped: dropped.into_inner() + light_dropped,
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
