//! The weight map of the preprint's Fig. 5: for a fixed first vertex x₀ (seen by the camera),
//! w₀ = 1 − w₁(x₀, x₁) of a mode as a function of x₁ over every surface point the camera sees.
use bdpm_geometry::Hit;
use glam::Vec3;
use rayon::prelude::*;

use bdpm_mis::{Heuristic, Pair};
use bdpm_settings::RenderSettings;

use crate::error::{RenderError, TargetError};
use crate::mix::{FirstVertex, Mix};
use crate::render::Renderer;
use crate::table::{TableSpec, pixel_weights};

/// Where x₀ is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WeightTarget {
    /// The surface point the camera sees in the direction of this world point (metres); it
    /// must lie within 1 mm + 0.1% of its distance of that point.
    Point(Vec3),
    /// The surface point seen through the centre of this pixel (x, y; row 0 at the top).
    Pixel(u32, u32),
}

/// A map of w₀ per pixel: the value for x₁ = the point seen through the pixel's centre.
#[derive(Clone, Debug, PartialEq)]
pub struct WeightMap {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// w₀ = 1 − w₁ per pixel, row-major; NaN where the pixel sees no surface.
    pub w0: Vec<f64>,
    /// The position of x₀, metres.
    pub x0: Vec3,
    /// The pixel in which the camera sees x₀.
    pub x0_pixel: (u32, u32),
}

/// The heuristic whose weight map `settings` ask for, or why they have none, from the
/// settings alone: a caller can refuse before a renderer prepares anything (the pilot of
/// `corrected-balance`, the radiance cache). `path` and `light` have no weights; a mode that
/// weighs each light path by its incoming direction at x₁ has no map over x₁ alone; the map
/// is of the merge at x₀, not of light tracing in its place. With a radius per block
/// (`adaptive_radius`) the map is of x₀'s pixel, with its radius.
pub fn weight_map_heuristic(settings: &RenderSettings) -> Result<Heuristic, RenderError> {
    let Some(h) = settings.heuristic() else {
        return Err(RenderError::NoWeights(settings.mode));
    };
    if h.needs().densities || h.needs().x1_scattering {
        return Err(RenderError::PerLightPathWeights(h.name()));
    }
    if settings.light_traced() {
        return Err(RenderError::LightTracing(h.name()));
    }
    Ok(h)
}

impl Renderer<'_> {
    /// Computes the weight map of this renderer's mode for x₀ at `target`; the modes
    /// [`weight_map_heuristic`] refuses give its error.
    pub fn weight_map(&self, target: WeightTarget) -> Result<WeightMap, RenderError> {
        let h = weight_map_heuristic(self.settings())?;
        let scene = self.scene();
        let cam = &scene.camera();
        let (hit, dir) = self.target_hit(target)?;
        let mix = self.mix(h);
        let x0 = mix
            .first_vertex(&hit, -dir)
            .ok_or(RenderError::Target(TargetError::FacesAway))?;
        let s = self.settings();
        let needs = h.needs();
        let footprint = self.footprint_model() && needs.effective_samples;
        // The image point that sees x₀: its footprint, and its radius with `adaptive_radius`.
        let projected = cam.project(x0.sh.p);
        let image_point =
            projected.unwrap_or((cam.width() as f32 * 0.5, cam.height() as f32 * 0.5));
        let x0_pixel = projected.map_or((0, 0), |(x, y)| {
            (
                (x as u32).min(cam.width() - 1),
                (y as u32).min(cam.height() - 1),
            )
        });
        let scale = mix.radius_scale(x0_pixel.0, x0_pixel.1);
        let pixel = (needs.pixel_table || footprint).then(|| {
            let spec = TableSpec {
                rays: needs.pixel_table.then_some(s.table_rays()),
                footprint,
                strata: crate::sampler::pixel_strata(s),
                radius: self.radius(),
                seed: s.seed,
            };
            pixel_weights(&mix, &x0, image_point, &spec, (u64::MAX, (0, 0)))
        });
        let budget = mix.pixel_budget(pixel.map(|p| p.camera_samples), scale);
        let (w, hgt) = (cam.width() as usize, cam.height() as usize);
        let mut w0 = vec![f64::NAN; w * hgt];
        w0.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, out) in row.iter_mut().enumerate() {
                let d = cam.ray_direction(x as f32 + 0.5, y as f32 + 0.5);
                let Some(pair) = pair_towards(&mix, &x0, d) else {
                    continue;
                };
                *out = h
                    .weight(&budget, &pair, pixel.as_ref().map(|p| &p.terms))
                    .w0();
            }
        });
        Ok(WeightMap {
            width: cam.width(),
            height: cam.height(),
            w0,
            x0: x0.sh.p,
            x0_pixel,
        })
    }

    /// The camera's first hit towards `target` and the ray's unit direction, or why `target`
    /// cannot be x₀ (outside the image, nothing seen, hidden behind another surface).
    fn target_hit(&self, target: WeightTarget) -> Result<(Hit, Vec3), RenderError> {
        let scene = self.scene();
        let cam = &scene.camera();
        let dir = match target {
            WeightTarget::Point(p) => (p - cam.position()).normalize_or_zero(),
            WeightTarget::Pixel(x, y) => {
                if x >= cam.width() || y >= cam.height() {
                    return Err(RenderError::Target(TargetError::OutsideImage {
                        x,
                        y,
                        width: cam.width(),
                        height: cam.height(),
                    }));
                }
                cam.ray_direction(x as f32 + 0.5, y as f32 + 0.5)
            }
        };
        let hit = scene
            .geometry()
            .intersect(cam.position(), dir, f32::INFINITY)
            .ok_or(RenderError::Target(TargetError::NoSurface))?;
        if let WeightTarget::Point(p) = target {
            let d = (p - cam.position()).length();
            if (hit.p - p).length() > 1e-3 + 1e-3 * d {
                return Err(RenderError::Target(TargetError::Hidden {
                    point: p,
                    seen: hit.p,
                }));
            }
        }
        Ok((hit, dir))
    }
}

/// The inputs of the pair (x₀, x₁) for x₁ the surface point the camera sees along `d`, or
/// None where it sees nothing or x₁ is x₀.
fn pair_towards(mix: &Mix<'_>, x0: &FirstVertex<'_>, d: Vec3) -> Option<Pair> {
    let scene = mix.scene;
    let cam = scene.camera();
    let hit1 = scene
        .geometry()
        .intersect(cam.position(), d, f32::INFINITY)?;
    let to = hit1.p - x0.sh.p;
    let dist = to.length();
    if dist <= 0.0 {
        return None;
    }
    let v = to / dist;
    let sh1 = scene.shade(&hit1, -v);
    let x1 = scene.weight_vertex(&sh1);
    // Behind x₀'s tangent plane no path x₁→x₀ exists; the map shows the weight the formula
    // gives with v mirrored into x₀'s hemisphere (for Lambert f̃ = 1/π for every x₁, as in the
    // preprint's Fig. 5) rather than a meaningless w₀ = 1.
    let n0 = x0.sh.ng;
    let v_eval = if n0.dot(v) < 0.0 {
        v - 2.0 * n0.dot(v) * n0
    } else {
        v
    };
    let f0 = scene.eval(&x0.sh, x0.u, v_eval);
    Some(mix.pair(x0, &x1, v, f0))
}
