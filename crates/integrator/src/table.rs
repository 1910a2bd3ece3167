//! The per-pixel inputs of the model-based weights, computed once before the passes from their
//! own random stream and frozen: the overlap factor ρ and N_eff of method.md §12 (from the
//! pixel's footprint), and the integrals A and B of method.md §6 (preprint §6.2) over the
//! second vertex of the partial weight W₁ (computed with the pixel's N_eff).
use bdpm_bdf::Transport;
use bdpm_geometry::{Domain, Rng};
use bdpm_mis::{
    Budget, PixelTerms, effective_samples, overlap_factor, overlap_factor_stratified,
    split_weighted_radiance, w1_partial,
};
use bdpm_scene::{DeltaWalk, Scene, Shading};
use rayon::prelude::*;

use crate::mix::{FirstVertex, Mix};

/// What the weights of one pixel's camera samples need beyond the pair (x₀, x₁).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelWeights {
    /// A, B of method.md §6 (zero unless the mode is `optimal`).
    pub terms: PixelTerms,
    /// The N_B that the weights use for this pixel: N_eff = 1 + (N_B − 1)·ρ under the
    /// footprint noise model, N_B under the pinhole one (method.md §12).
    pub camera_samples: f64,
    /// ρ, the mean overlap of two samples' merge disks over the pixel's footprint (1 when
    /// every sample goes through the pixel's centre or the model is `pinhole`).
    pub overlap: f64,
}

/// Per-pixel weight inputs, row-major; frozen before rendering.
#[derive(Clone, Debug)]
pub struct PixelTable {
    width: u32,
    pixels: Vec<PixelWeights>,
    /// Whether A and B were computed (the `optimal` mode).
    has_terms: bool,
}

impl PixelTable {
    /// The weight inputs of pixel (x, y).
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> &PixelWeights {
        &self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Memory of the table, bytes.
    pub fn bytes(&self) -> u64 {
        (self.pixels.len() * std::mem::size_of::<PixelWeights>()) as u64
    }

    /// Every pixel's inputs, row-major.
    pub fn pixels(&self) -> &[PixelWeights] {
        &self.pixels
    }

    /// Whether A and B were computed (otherwise they are zero).
    pub fn has_terms(&self) -> bool {
        self.has_terms
    }
}

/// A and B for one first vertex with `budget` (whose N_B is the pixel's N_eff): `rays`
/// BDF-sampled directions from the stream keyed by (seed, `key`, ray).
pub(crate) fn pixel_terms(
    mix: &Mix<'_>,
    budget: &Budget,
    x0: &FirstVertex<'_>,
    rays: u32,
    seed: u64,
    key: u64,
) -> PixelTerms {
    let scene = mix.scene;
    // Weights by path kind accumulate their own weighted radiance (method-notes.md).
    let split = mix.needs.path_kinds;
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
            .geometry()
            .intersect(scene.spawn(&x0.sh, v), v, f32::INFINITY)
        else {
            continue;
        };
        let sh1 = scene.shade(&hit1, -v);
        let x1 = scene.weight_vertex(&sh1);
        let pair = mix.pair(x0, &x1, v, mix.f_at_x0(x0, v));
        let cos_over_pdf = (s.wi.z / s.pdf) as f64;
        if split {
            let wl = split_weighted_radiance(
                budget,
                pair.x0.f_tilde,
                pair.x1.direct,
                pair.x1.indirect,
                pair.x1.b,
            );
            a += wl * pair.x0.f_tilde * cos_over_pdf;
            b += wl * cos_over_pdf;
        } else {
            let l = pair.x1.direct + pair.x1.indirect;
            let w1 = w1_partial(budget, pair.x0.f_tilde, l, pair.x1.b);
            a += w1 * pair.x0.f_tilde * l * cos_over_pdf;
            b += w1 * l * cos_over_pdf;
        }
    }
    let n = rays.max(1) as f64;
    PixelTerms { a: a / n, b: b / n }
}

/// ρ for the camera samples of the pixel whose image point (x, y) (pixels) sees x₀ at `sh`
/// through the delta chain `chain` ((vertices, branches) of its [`DeltaWalk`]; (0, 0) where
/// it sees x₀ directly): the footprint is the parallelogram where the rays through
/// (x ± ½, y ± ½) cross x₀'s tangent plane (ray differentials, as pbrt does for texture
/// filtering), each taken with the centre's ray through the same mirrors and glass on the same
/// branches as a ray differential ([`Scene::follow_branches`]; one that cannot follow makes
/// the footprint unbounded).
///
/// A footprint that crosses an edge or a silhouette is treated as if it continued on x₀'s
/// plane. Pairs of samples on the two sides of the edge share no photons, but the pairs on each
/// side share more; for footprints much larger than the merge disk the two effects cancel
/// (ρ ≈ S/|F| either way), and for small ones ρ ≈ 1 either way. A footprint that reaches the
/// horizon of the plane gives ρ = 0.
///
/// `strata`: the sampler's grid of the pixel when its samples are stratified
/// ([`overlap_factor_stratified`]), `None` for independent samples.
pub(crate) fn footprint_overlap(
    scene: &Scene,
    sh: &Shading,
    (x, y): (f32, f32),
    radius: f32,
    strata: Option<(u32, u32)>,
    (vertices, branches): (u32, u64),
) -> f64 {
    let cam = &scene.camera();
    let n = sh.ng.as_dvec3();
    let unbounded = glam::DVec3::splat(f64::INFINITY);
    // A nearby ray's last segment after a chain is a line of the differential: it may cross
    // x₀'s plane before the last delta vertex's plane (t < 0) where the centre's crosses it
    // after. From the camera, a crossing behind it is none.
    let behind_ok = vertices > 0;
    let cross_from = |origin: glam::DVec3, d: glam::DVec3| {
        let t = n.dot(sh.p.as_dvec3() - origin) / n.dot(d);
        // Behind the camera or parallel to the plane: an unbounded footprint.
        if (t > 0.0 || behind_ok) && t.is_finite() {
            origin + d * t
        } else {
            unbounded
        }
    };
    let offsets = [(0.5, 0.0), (-0.5, 0.0), (0.0, 0.5), (0.0, -0.5)];
    let near = offsets.map(|(dx, dy)| cam.ray_direction(x + dx, y + dy));
    let c = if vertices == 0 {
        near.map(|d| cross_from(cam.position().as_dvec3(), d.as_dvec3()))
    } else {
        let centre = (cam.position(), cam.ray_direction(x, y));
        scene
            .follow_branches(centre, (vertices, branches), near)
            .map_or([unbounded; 4], |rays| {
                rays.map(|(o, d)| cross_from(o.as_dvec3(), d.as_dvec3()))
            })
    };
    let (edge_x, edge_y) = (c[0] - c[1], c[2] - c[3]);
    let (edge_x, edge_y, radius) = (edge_x.to_array(), edge_y.to_array(), radius as f64);
    match strata {
        Some(strata) => overlap_factor_stratified(edge_x, edge_y, radius, strata),
        None => overlap_factor(edge_x, edge_y, radius),
    }
}

/// How the table is built.
pub(crate) struct TableSpec {
    /// Backward rays per pixel for A and B; `None` skips A and B (modes other than `optimal`).
    pub(crate) rays: Option<u32>,
    /// Compute ρ from the footprint (footprint noise model with jittered samples); otherwise
    /// ρ = 1 and N_eff = N_B.
    pub(crate) footprint: bool,
    /// The sampler's strata of the pixel when its samples are stratified (for ρ).
    pub(crate) strata: Option<(u32, u32)>,
    /// Merge radius r, metres.
    pub(crate) radius: f32,
    /// Master seed.
    pub(crate) seed: u64,
}

/// The weight inputs of the pixel whose image point (x, y) sees x₀ (`key` keys A and B's
/// random stream).
pub(crate) fn pixel_weights(
    mix: &Mix<'_>,
    x0: &FirstVertex<'_>,
    (x, y): (f32, f32),
    spec: &TableSpec,
    (key, chain): (u64, (u32, u64)),
) -> PixelWeights {
    let n_b = mix.budget.camera_samples;
    let scale = mix.radius_scale(x as u32, y as u32);
    let overlap = if spec.footprint {
        let radius = spec.radius * scale;
        footprint_overlap(mix.scene, &x0.sh, (x, y), radius, spec.strata, chain)
    } else {
        1.0
    };
    let camera_samples = effective_samples(n_b, overlap);
    let budget = mix.pixel_budget(Some(camera_samples), scale);
    let terms = spec.rays.map_or(PixelTerms::default(), |rays| {
        pixel_terms(mix, &budget, x0, rays, spec.seed, key)
    });
    PixelWeights {
        terms,
        camera_samples,
        overlap,
    }
}

/// The way of the ray through image point `centre` (pixels) to the x₀ that stands for its
/// pixel: the first surface it hits, or through mirrors and glass the first non-delta one on
/// their more probable branches ([`Scene::walk_principal`]). `None` where it finds none.
pub(crate) fn pixel_walk(scene: &Scene, centre: (f32, f32)) -> Option<DeltaWalk> {
    let cam = scene.camera();
    let dir = cam.ray_direction(centre.0, centre.1);
    scene.walk_principal(cam.position(), dir, Transport::Radiance)
}

/// Builds the table: for each pixel, the primary ray through its centre finds x₀ (through
/// mirrors and glass, [`pixel_walk`]); ρ comes from
/// the pixel's footprint there, and (with `spec.rays`) `rays` directions v are sampled from the
/// BDF at x₀ (no absorption) and A += W₁ f̃ L cos/p, B += W₁ L cos/p with
/// L = L₀(x₁→x₀) + L_d(x₁→x₀), divided by `rays`. A pixel whose centre sees nothing gets ρ = 0
/// under the footprint model (its samples that hit land on whatever lies behind the
/// silhouette, spread out) and A = B = 0.
/// `None` when `stop()`, asked before each pixel, stopped it.
pub(crate) fn build(
    mix: &Mix<'_>,
    width: u32,
    height: u32,
    spec: &TableSpec,
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<PixelTable> {
    let scene = mix.scene;
    let n_b = mix.budget.camera_samples;
    let missed = PixelWeights {
        terms: PixelTerms::default(),
        overlap: if spec.footprint { 0.0 } else { 1.0 },
        camera_samples: effective_samples(n_b, if spec.footprint { 0.0 } else { 1.0 }),
    };
    let mut pixels = vec![missed; width as usize * height as usize];
    let stopped = std::sync::atomic::AtomicBool::new(false);
    pixels
        .par_chunks_mut(width as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, out) in row.iter_mut().enumerate() {
                // Asked per pixel: a row of 256 pixels at 16384 rays each takes seconds.
                if stop() {
                    stopped.store(true, std::sync::atomic::Ordering::Relaxed);
                    return;
                }
                let pixel = (y * width as usize + x) as u64;
                let centre = (x as f32 + 0.5, y as f32 + 0.5);
                let Some(walk) = pixel_walk(scene, centre) else {
                    continue;
                };
                let Some(x0) = mix.first_vertex_shaded(walk.sh, walk.wo) else {
                    continue;
                };
                let chain = (walk.vertices, walk.branches);
                *out = pixel_weights(mix, &x0, centre, spec, (pixel, chain));
            }
        });
    if stopped.into_inner() {
        return None;
    }
    Some(PixelTable {
        width,
        pixels,
        has_terms: spec.rays.is_some(),
    })
}

/// Mean of ρ and of N_eff over all pixels, for the run report.
pub(crate) fn mean_overlap(table: &PixelTable) -> (f64, f64) {
    let (mut rho, mut n, mut count) = (0.0, 0.0, 0usize);
    for p in table.pixels() {
        rho += p.overlap;
        n += p.camera_samples;
        count += 1;
    }
    let c = count.max(1) as f64;
    (rho / c, n / c)
}
