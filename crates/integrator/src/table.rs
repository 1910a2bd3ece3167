//! The per-pixel A and B of method.md §6 (preprint §6.2): integrals over the second vertex of
//! the partial weight W₁, computed once before the passes from their own random stream.
use bdpm_geometry::{Domain, Rng};
use bdpm_mis::{PixelTerms, w1_partial};
use rayon::prelude::*;

use crate::bdpm::{FirstVertex, Mix, WeightVertex};

/// A, B per pixel (luminances), row-major; frozen before rendering.
#[derive(Clone, Debug)]
pub struct PixelTable {
    width: u32,
    terms: Vec<PixelTerms>,
}

impl PixelTable {
    /// The terms of pixel (x, y).
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> &PixelTerms {
        &self.terms[y as usize * self.width as usize + x as usize]
    }

    /// Memory of the table, bytes.
    pub fn bytes(&self) -> u64 {
        (self.terms.len() * std::mem::size_of::<PixelTerms>()) as u64
    }

    /// Mean of c·B over pixels with a surface (a stiffness indicator for the report).
    pub fn terms(&self) -> &[PixelTerms] {
        &self.terms
    }
}

/// A and B for one first vertex: `rays` BDF-sampled directions from the stream keyed by
/// (seed, `key`, ray).
pub(crate) fn pixel_terms(
    mix: &Mix<'_>,
    x0: &FirstVertex<'_>,
    rays: u32,
    seed: u64,
    key: u64,
) -> PixelTerms {
    let scene = mix.scene;
    let (mut a, mut b) = (0.0f64, 0.0f64);
    for j in 0..rays {
        let mut rng = Rng::new(seed, Domain::PixelTable, [key, j as u64, 0]);
        let Some(s) = x0.bdf.sample_at(&x0.out, rng.uniform3()) else {
            continue;
        };
        let v = x0.sh.frame.to_world(s.wi);
        if x0.sh.ng.dot(v) <= 0.0 || s.pdf <= 0.0 {
            continue;
        }
        let Some(hit1) = scene
            .geometry
            .intersect(scene.spawn(&x0.sh, v), v, f32::INFINITY)
        else {
            continue;
        };
        let sh1 = scene.shade(&hit1, -v);
        let x1 = WeightVertex::from_shading(scene, &sh1);
        let pair = mix.pair(x0, &x1, v, s.f);
        let l = pair.direct + pair.indirect;
        let w1 = w1_partial(&mix.budget, pair.f_tilde, l, pair.b);
        let cos_over_pdf = (s.wi.z / s.pdf) as f64;
        a += w1 * pair.f_tilde * l * cos_over_pdf;
        b += w1 * l * cos_over_pdf;
    }
    let n = rays.max(1) as f64;
    PixelTerms { a: a / n, b: b / n }
}

/// Builds the table: for each pixel, the primary ray through its centre finds x₀, then `rays`
/// directions v are sampled from the BDF at x₀ (no absorption) and
/// A += W₁ f̃ L cos/p, B += W₁ L cos/p with L = L₀(x₁→x₀) + L_d(x₁→x₀), divided by `rays`.
pub(crate) fn build(mix: &Mix<'_>, width: u32, height: u32, rays: u32, seed: u64) -> PixelTable {
    let scene = mix.scene;
    let cam = &scene.camera;
    let mut terms = vec![PixelTerms::default(); width as usize * height as usize];
    terms
        .par_chunks_mut(width as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, out) in row.iter_mut().enumerate() {
                let pixel = (y * width as usize + x) as u64;
                let dir = cam.ray_direction(x as f32 + 0.5, y as f32 + 0.5);
                let Some(hit0) = scene.geometry.intersect(cam.position, dir, f32::INFINITY) else {
                    continue;
                };
                let Some(x0) = mix.first_vertex(&hit0, -dir) else {
                    continue;
                };
                *out = pixel_terms(mix, &x0, rays, seed, pixel);
            }
        });
    PixelTable { width, terms }
}
