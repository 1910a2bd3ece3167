//! The noise model of method.md §12 evaluated per pixel for a mode's weights: the per-pass
//! variance V that the functional predicts, split into its terms, for comparison with the
//! variance a render measures (`bdpm predict`).
//!
//! For the pixel's centre x₀ (u towards the camera) and directions v drawn from the BDF's
//! sampling pdf p(v) at x₀ (N = `pixel_table_rays`, 64 if not given; their own random stream), with x₁ the
//! point v hits, L = L₀(x₁→x₀) + L_d(x₁→x₀) (shadow rays and the model's own radiance cache,
//! [`Renderer::with_model_cache`]; the weights read the render's), b from the same cache,
//! f = f(v, u; x₀) and cos = cos θ_v at x₀ (luminances), α = Φ/(N_F·S):
//!
//! ```text
//! T0 = α·N_eff/N_B · E_p[(1 − w)²·f²·L·cos/p]           ∫ (1 − w₁)² f² L cos dv
//! T1 = 1/N_B · Var_p[w·f·L·cos/p]                        ∫ w₁² f² L² cos²/p dv − (∫ w₁ f L cos dv)²
//! T2 = α/N_B · E_p[w²·f²·cos²·b/p²]                      ∫ w₁² f² cos²/p · b dv
//! T_jitter = 1/N_B · Var_{x₀ in pixel}[L₀(x₀→u) + L_d(x₀→u)]     (only with pixel jitter)
//! ```
//!
//! Each estimator is the integral on its right written as an expectation over v ~ p
//! (∫ g dv = E_p[g/p]); T1 is the sample variance (divisor N − 1) of the BDD=1 sample value
//! w·E·L with E = f·cos/p, counting directions that find no x₁ as zeros, as the renderer does.
//! T0 is the photon noise of the merges at x₀ (each photon carries Φ/N_F; a gather's variance
//! is α∫f²L cos dv, and the N_B jittered gathers of a pass act like N_B/N_eff independent ones),
//! T1 the jumps of x₁, T2 the photon noise of the merges at x₁ (b = ∫ f² J dv′ at x₁), and
//! T_jitter the spread of the pixel's mean radiance over its footprint, which the functional of
//! §12 leaves out (it is the same for every mode) but a measured V contains.
//!
//! **Stratified samples** (the `stratified` sampler, the default). The N_B samples of a pass take
//! one cell each of an n_x × n_y grid (of the pixel, and of the BDF's two direction numbers at
//! x₀), and the mean of one value per cell has variance (1/N_B)·mean over cells of σ²_cell,
//! the variance within a cell. So Var_p in T1 and Var_{x₀ in pixel} in T_jitter become that
//! mean within-cell variance, estimated from pairs of rays drawn in one random cell:
//! σ²_cell ≈ ½(g_a − g_b)². T0's ρ is that of pairs of samples in distinct cells
//! ([`bdpm_mis::overlap_factor_stratified`]); T0 and T2 are means over v and keep their form.
//!
//! **Which N_eff.** T0's N_eff = 1 + (N_B − 1)·ρ uses ρ from the pixel's footprint whenever the
//! samples are jittered, whatever the noise model of the weights: it describes how the render
//! shares photons, not what the weights assume. The weights themselves use the budget the
//! renderer gives them (the pixel table's N_eff under the footprint model, N_B otherwise).
//!
//! **Weights that depend on the photon's incoming direction at x₁** (`balance`, `power`): for
//! a direction v, the one-bounce paths light→x₁→x₀ have a weight w_ob,l per light l (incoming
//! direction: towards the light) and the longer paths a weight w_m, evaluated with the incoming
//! direction along x₁'s normal. The effective weight of the direction is
//! w = (Σ_l L₀,l·w_ob,l + L_d·w_m)/L, which is exactly what the BDD=1 mean needs (T1). The
//! squared weights of T0 and T2 are taken per part instead of from w:
//! (1 − w)²L → Σ_l L₀,l (1 − w_ob,l)² + L_d (1 − w_m)² (each photon at x₀ carries its own
//! weight) and w²b → w_m²·b (b comes from the merge photons at x₁ only). For every other mode
//! w_ob = w_m = w and both readings coincide.
//!
//! **`optimal-path`** weighs each merge photon by its own f₁ at x₁ (the BDF of x₁ from the
//! photon's arrival towards x₀). At a glossy x₁ the model draws [`ARRIVAL_SAMPLES`] arrivals ω₂
//! from x₁'s BDF, finds the radiance ℓ that reaches x₁ along each after at least one bounce
//! (the light's direct light at the next non-delta vertex plus the cache's L_d there), and
//! takes the merge paths' w, (1 − w)² and w² as averages under f₁·ℓ·cos (for L_d: BDD=1's
//! mean, the merges at x₀) and under f₁²·ℓ·cos (for b: the merges at x₁); the cache's L_d and
//! b keep their magnitudes. Elsewhere the cell's average f₁ = b/L_d stands for every arrival,
//! which is `optimal-split`'s weight.
//!
//! **Area lights.** Direct light from emitting triangles is one light sample per camera sample
//! at x₁ (BDD=1) and at x₀ (M with `direct_boost`), weighed against a BDF ray at x₀ (where the
//! mode traces BDD=1) and at a glossy x₁. The model draws [`AREA_SAMPLES`] such samples per
//! vertex, the BDF rays included: their mean joins L₀ (at x₁ each sample weighted by its own path's w₁,
//! at x₀ with x₀'s own Le), and the variance of one sample is added to T1 (at x₁, times E²)
//! and to T_jitter (at x₀, over M), less the 1/K of it that the K-sample means already carry
//! into the sample variances. A scene without emission draws none.
//!
//! Units: every term is a variance of a radiance, W²·m⁻⁴·sr⁻².
use bdpm_bdf::{Transport, luminance};
use bdpm_cache::RadianceCache;
use bdpm_geometry::{Domain, Rng};
use bdpm_mis::{Heuristic, Weigher, effective_samples};
use bdpm_scene::Shading;
use glam::Vec3;

use crate::direct::x1_weighs_bdf;
use crate::inputs::Arrival;
use rayon::prelude::*;

use crate::error::RenderError;
use crate::mix::{FirstVertex, Mix};
use crate::photon_spread::photon_power_spread;
use crate::render::Renderer;
use crate::sampler::{direction_strata, in_cell, pixel_strata, random_cell};
use crate::table::{footprint_overlap, pixel_walk};
use bdpm_settings::PINHOLE_TABLE_RAYS;

/// Jittered primary rays per pixel for T_jitter (method.md §12 leaves this term out; 16 gives
/// its per-pixel value to about ±35 %, far less over blocks of pixels).
pub const JITTER_RAYS: u32 = 16;

/// Light samples per vertex with which the model estimates the area lights' direct light at
/// x₁ and at x₀ and the variance of the renderer's one sample there (8 keeps the per-pixel
/// estimate's own noise below that of its 64 directions; a scene without emission draws none).
pub const AREA_SAMPLES: u32 = 8;

/// Normals within about 8° count as the same surface for T_jitter's L_d (a tessellated sphere
/// of 20480 facets turns by about 2° from facet to facet).
const SAME_PLANE_COS: f32 = 0.99;

/// The predicted per-pass variance of each pixel's luminance, split into its terms; row-major,
/// W²·m⁻⁴·sr⁻² (NaN where the ray through the pixel centre sees no surface, or its back).
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// T0: photon noise of the merges at x₀ (BDD=0).
    pub t0: Vec<f64>,
    /// T1: the jumps of x₁ (BDD=1's camera sampling at x₀).
    pub t1: Vec<f64>,
    /// T2: photon noise of the merges at x₁ (BDD=1).
    pub t2: Vec<f64>,
    /// T_jitter: variance of the pixel's mean radiance over its footprint, divided by N_B
    /// (0 without pixel jitter).
    pub t_jitter: Vec<f64>,
    /// T0 + T1 + T2 + T_jitter.
    pub total: Vec<f64>,
    /// ρ of T0's N_eff = 1 + (N_B − 1)·ρ (1 without jitter; dimensionless).
    pub overlap: Vec<f64>,
}

/// The four terms of one pixel, W²·m⁻⁴·sr⁻².
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Terms {
    t0: f64,
    t1: f64,
    t2: f64,
    jitter: f64,
    overlap: f64,
}

/// One direction's contributions before the constant factors.
#[derive(Clone, Copy, Debug, Default)]
struct Direction {
    /// w·E·L, the BDD=1 sample value (luminance), W·m⁻²·sr⁻¹.
    value: f64,
    /// The part of `value` by the one-bounce paths light→x₁→x₀, W·m⁻²·sr⁻¹.
    direct: f64,
    /// Σ (1 − w)²·L over the parts, times f²·cos/p.
    photons_x0: f64,
    /// w_m²·E²·b.
    photons_x1: f64,
    /// E²·Var(w·c): the variance of one light sample c of the area lights at x₁ (weighted by
    /// its path's w₁), which BDD=1's value carries beside the jumps of x₁.
    light_var: f64,
}

impl Renderer<'_> {
    /// Evaluates the noise model of method.md §12 per pixel for this renderer's mode and
    /// settings (see the module documentation of `predict.rs` for the estimators).
    ///
    /// Needs the radiance cache for every mode: build the renderer with
    /// [`Renderer::with_model_inputs`]. The `path` and `light` modes have no model and give an
    /// error. Deterministic: the directions come from the `PixelTable` stream keyed by pixel
    /// (distinct from the A/B rays' keys), the jittered rays likewise.
    pub fn predict_variance(&self) -> Result<Prediction, RenderError> {
        let Some(h) = self.heuristic() else {
            return Err(RenderError::NoNoiseModel(self.settings().mode));
        };
        self.predict_variance_for(h)
    }

    /// [`Self::predict_variance`] for the weights `h` in place of the mode's own, with this
    /// renderer's settings, cache and pixel table: e.g. the unclamped `optimal-split`, the
    /// minimiser of the functional over weights per (x₀, x₁) and path kind, as the floor that no
    /// such weight can go below (the headroom of `bdpm predict`). If `h` reads the pixel table's A and B, the renderer's mode must have
    /// built it (an `optimal*` mode); otherwise the error says so.
    pub fn predict_variance_for(&self, h: Heuristic) -> Result<Prediction, RenderError> {
        if self.light_traced() {
            return Err(RenderError::LightTracing(h.name()));
        }
        if h.needs().pixel_table && !self.pixel_table().is_some_and(|t| t.has_terms()) {
            return Err(RenderError::NoPixelTable {
                weights: h.name(),
                mode: self.settings().mode,
            });
        }
        if h.needs().balance_correction && self.correction().is_none() {
            return Err(RenderError::NoCorrection {
                weights: h.name(),
                mode: self.settings().mode,
            });
        }
        let Some(cache) = self.model_cache() else {
            return Err(RenderError::NoCache);
        };
        let mut mix = self.mix(h);
        // The model needs L₀ at x₁ for every mode; this changes only what the pair carries,
        // not the weights (a mode reads only the fields it needs). Its L_d and b come from
        // `cache`, the weights' from theirs, as in the render.
        mix.needs.direct_at_x1 = true;
        let s = self.settings();
        let (w, hgt) = (s.width as usize, s.height as usize);
        let kappa = photon_power_spread(self.scene(), s.seed);
        let mut terms = vec![None; w * hgt];
        terms.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, out) in row.iter_mut().enumerate() {
                *out = self.pixel_terms(&mix, (cache, kappa), (x as u32, y as u32));
            }
        });
        let pick = |f: fn(&Terms) -> f64| -> Vec<f64> {
            terms
                .iter()
                .map(|t| t.as_ref().map_or(f64::NAN, f))
                .collect()
        };
        Ok(Prediction {
            width: s.width,
            height: s.height,
            t0: pick(|t| t.t0),
            t1: pick(|t| t.t1),
            t2: pick(|t| t.t2),
            t_jitter: pick(|t| t.jitter),
            total: pick(|t| t.t0 + t.t1 + t.t2 + t.jitter),
            overlap: pick(|t| t.overlap),
        })
    }

    /// The terms of pixel (x, y), or None if its centre sees no surface facing the camera
    /// (through mirrors and glass, on their more probable branches: [`pixel_walk`]).
    fn pixel_terms(
        &self,
        mix: &Mix<'_>,
        (cache, kappa): (&RadianceCache, f64),
        (x, y): (u32, u32),
    ) -> Option<Terms> {
        let scene = self.scene();
        let s = self.settings();
        let pixel = y as u64 * s.width as u64 + x as u64;
        let centre = (x as f32 + 0.5, y as f32 + 0.5);
        let walk = pixel_walk(scene, centre)?;
        let x0 = mix.first_vertex_shaded(walk.sh, walk.wo)?;
        let n_b = s.spp as f64;
        // The pixel's radius (`adaptive_radius`): its merges, S, N_eff and weights are its own.
        let scale = mix.radius_scale(x, y);
        let radius = self.radius() * scale;
        let overlap_at = |sh: &Shading, chain: (u32, u64)| {
            if s.pixel_jitter {
                footprint_overlap(scene, sh, centre, radius, pixel_strata(s), chain)
            } else {
                1.0
            }
        };
        let overlap = overlap_at(&x0.sh, (walk.vertices, walk.branches));
        let n_eff = effective_samples(n_b, overlap);
        let weigher = self.pixel_weigher(mix, (x, y), scale);
        let caustic = self.caustic_cache();

        // The model's own directions: as many as the preprint's A/B rays unless given, so that
        // a prediction does not get noisier where the table takes fewer.
        let rays = s.pixel_table_rays.unwrap_or(PINHOLE_TABLE_RAYS).max(2);
        let (mut sum, mut sum_sq, mut photons_x0, mut photons_x1) = (0.0, 0.0, 0.0, 0.0);
        let (mut caustic_x0, mut light_var) = (0.0, 0.0);
        let n_alloc = self.one_bounce_samples().map_or(1, |n| n.at(x, y));
        let mut one_bounce = OneBounceShare::new(mix.one_bounce_samples(&x0, n_alloc));
        let grid = direction_strata(s);
        // With stratified directions, rays 2i and 2i + 1 fall in one random cell of the
        // sampler's grid: half their squared difference estimates that cell's variance.
        let (mut cell, mut previous, mut within) = ((0, 0), 0.0, 0.0);
        for j in 0..rays {
            let (mut rng, u) = direction_numbers(s.seed, (pixel, j), grid, &mut cell);
            // Through mirrors and glass each sample takes its own branches to its own x₀
            // (key slot 5), whose light the chain's throughput β scales; its N_eff is that of
            // its own footprint. Without a chain: the centre's x₀, β = 1 (bits unchanged).
            let own = (walk.vertices > 0)
                .then(|| self.sample_x0(mix, centre, [pixel, j as u64, 5], &overlap_at))
                .flatten();
            let (at, beta, share) = match &own {
                Some((x0, beta, n)) => (x0, *beta, n / n_eff),
                None if walk.vertices > 0 => (&x0, 0.0, 0.0),
                None => (&x0, 1.0, 1.0),
            };
            let d = direction(mix, cache, &weigher, at, u, &mut rng).unwrap_or_default();
            let value = one_bounce.value(&d, beta);
            sum += value;
            sum_sq += value * value;
            photons_x0 += share * beta * beta * d.photons_x0;
            photons_x1 += beta * beta * d.photons_x1;
            light_var += beta * beta * d.light_var;
            if let Some(c) = caustic {
                let b = c.lookup(at.sh.prim, at.sh.p, at.u).1 as f64;
                caustic_x0 += share * beta * beta * b;
            }
            if j % 2 == 1 {
                within += 0.5 * (value - previous).powi(2);
            }
            previous = value;
        }
        let n = rays as f64;
        let b = mix.pixel_budget(None, scale);
        // α = Φ/(N_F·S), W·m⁻², S the pixel's, times κ for the photons' unequal powers.
        let alpha = b.flux / (b.photons * b.merge_area) * kappa;
        // The variance of one sample's BDD=1 value: the sample variance (unbiased, divisor
        // N − 1) for independent directions; for stratified ones the mean variance within a
        // cell, since the mean of N_B samples, one per cell, has variance Σ σ²_cell/N_B².
        let jumps = match grid {
            Some(_) => within / (rays / 2) as f64,
            None => ((sum_sq - sum * sum / n) / (n - 1.0)).max(0.0),
        };
        let jumps = jumps + one_bounce.further_variance(n);
        let jitter = if s.pixel_jitter {
            self.jitter_variance(cache, &x0, (x, y), mix.needs.second_vertex) / n_b
        } else {
            0.0
        };
        // The area light's sample at x₁: its variance, less the 1/K of it that the values' own
        // K-sample means already put into `jumps`.
        let light_samples = 1.0 - 1.0 / AREA_SAMPLES as f64;
        // The caustic's photons at x₀ (light → mirrors and glass → x₀) are the merge at x₀'s
        // alone, (1 − w)² = 1: their noise is α·N_eff/N_B·b_caustic(x₀→u).
        Some(Terms {
            t0: alpha * n_eff / n_b * (photons_x0 + caustic_x0) / n,
            t1: (jumps + light_samples * light_var / (n * one_bounce.n)) / n_b,
            t2: alpha / n_b * photons_x1 / n,
            jitter,
            overlap,
        })
    }

    /// Pixel (x, y)'s weigher with its radius `scale`: the weights' inputs exactly as the
    /// renderer passes them (the pixel table's, `corrected-balance`'s factor).
    fn pixel_weigher(&self, mix: &Mix<'_>, (x, y): (u32, u32), scale: f32) -> Weigher {
        let table = self.pixel_table().map(|t| t.get(x, y));
        let factor = self.correction().map_or(1.0, |c| c.get(x, y));
        let inputs = (table.map(|p| p.camera_samples), table.map(|p| &p.terms));
        mix.weigher(inputs, factor, scale)
    }

    /// One camera sample's way through the pixel's mirrors and glass from its centre
    /// (`centre`, pixels) with its own branches and roulette drawn from the stream `key`: x₀,
    /// the luminance of the chain's throughput β, and N_eff of its footprint (`overlap_at`).
    fn sample_x0<'m>(
        &self,
        mix: &'m Mix<'_>,
        centre: (f32, f32),
        key: [u64; 3],
        overlap_at: &dyn Fn(&Shading, (u32, u64)) -> f64,
    ) -> Option<(FirstVertex<'m>, f64, f64)> {
        let scene = self.scene();
        let cam = scene.camera();
        let mut rng = Rng::new(self.settings().seed, Domain::PixelTable, key);
        let dir = cam.ray_direction(centre.0, centre.1);
        let walk =
            scene.walk_to_non_delta(cam.position(), dir, Transport::Radiance, || rng.uniform())?;
        let x0 = mix.first_vertex_shaded(walk.sh, walk.wo)?;
        let overlap = overlap_at(&x0.sh, (walk.vertices, walk.branches));
        let n_eff = effective_samples(self.settings().spp as f64, overlap);
        Some((x0, luminance(walk.beta) as f64, n_eff))
    }

    /// Var over the pixel's footprint of L₀(x₀→u) + L_d(x₀→u), from [`JITTER_RAYS`]
    /// uniformly jittered primary rays; rays that miss, or see a surface's back, count with the
    /// value the renderer gives them (0, or the direct light alone).
    ///
    /// L_d comes from the radiance cache, but on x₀'s own plane it is taken at x₀ (`centre`)
    /// for every ray: the cache is piecewise constant with a few percent to tens of percent
    /// of photon noise per cell, and a footprint that straddles a cell boundary would count
    /// that noise as variation over the pixel (in the sphere furnace, ten times the true
    /// jitter variance). Indirect light varies little within a pixel on one surface; across
    /// an edge to another surface, its change is real and the cache's value there is used.
    /// `mis`: the mode weighs x₀'s area-light sample against BDD=1's BDF ray.
    fn jitter_variance(
        &self,
        cache: &RadianceCache,
        centre: &FirstVertex<'_>,
        (x, y): (u32, u32),
        mis: bool,
    ) -> f64 {
        let scene = self.scene();
        let cam = &scene.camera();
        let seed = self.settings().seed;
        let pixel = y as u64 * self.settings().width as u64 + x as u64;
        let n0 = centre.sh.ng;
        let ld_centre = cache.lookup(centre.sh.prim, centre.sh.p, centre.u).0 as f64;
        let strata = pixel_strata(self.settings());
        // Sums over the rays of (L₀, L_d) and of their products, and the same over the pairs'
        // half squared differences: the pixel's `direct_boost` M divides L₀'s share.
        let (mut sum, mut sum_sq, mut within) = ([0.0; 2], [0.0; 3], [0.0; 3]);
        let (mut previous, mut cell) = ([0.0; 2], (0, 0));
        // Σ over the rays of β²·Var(one light sample of the area lights at x₀).
        let mut light_var = 0.0;
        for m in 0..JITTER_RAYS {
            let mut rng = Rng::new(seed, Domain::PixelTable, [pixel, m as u64, 2]);
            let mut jitter = rng.uniform2();
            // Stratified samples: rays 2i and 2i + 1 in one random cell of the pixel's grid.
            if let Some(grid) = strata {
                if m % 2 == 0 {
                    let key = [pixel, m as u64 / 2, 4];
                    cell = random_cell(grid, &mut Rng::new(seed, Domain::PixelTable, key));
                }
                jitter = in_cell(cell, grid, jitter);
            }
            let [jx, jy] = jitter;
            let dir = cam.ray_direction(x as f32 + jx, y as f32 + jy);
            // Through mirrors and glass with this ray's own branches (none drawn without).
            let value = scene
                .walk_to_non_delta(cam.position(), dir, Transport::Radiance, || rng.uniform())
                .map_or([0.0; 2], |walk| {
                    let (u, sh) = (walk.wo, walk.sh);
                    let beta = luminance(walk.beta) as f64;
                    let mut direct = luminance(scene.direct(&sh, u)) as f64;
                    if scene.has_emission() {
                        // x₀'s own Le and its area-light sample, as the renderer's direct term.
                        let area = area_moments(scene, (&sh, u), &mut rng, mis, |_| 1.0);
                        direct +=
                            luminance(scene.emitted(sh.prim, sh.bary, u)) as f64 + area.weighted;
                        light_var += beta * beta * area.variance;
                    }
                    let faces = sh.frame.to_local(u).z > 0.0;
                    let same_plane = sh.ng.dot(n0) > SAME_PLANE_COS
                        && (n0.dot(sh.p - centre.sh.p)).abs() < self.radius();
                    let ld = match () {
                        _ if !faces => 0.0,
                        _ if same_plane => ld_centre,
                        _ => cache.lookup(sh.prim, sh.p, u).0 as f64,
                    };
                    [beta * direct, beta * ld]
                });
            let [d, l] = value;
            sum[0] += d;
            sum[1] += l;
            sum_sq[0] += d * d;
            sum_sq[1] += l * l;
            sum_sq[2] += d * l;
            if m % 2 == 1 {
                let (dd, dl) = (d - previous[0], l - previous[1]);
                within[0] += 0.5 * dd * dd;
                within[1] += 0.5 * dl * dl;
                within[2] += 0.5 * dd * dl;
            }
            previous = value;
        }
        // A sample's value is the mean of L₀ over M points of its region plus L_d at its own:
        // Var = Var(L₀)/M + Var(L_d) + 2·Cov(L₀, L_d)/M.
        let inv_m = 1.0 / self.direct_samples().map_or(1, |d| d.at(x, y)) as f64;
        let combine = |[dd, ll, dl]: [f64; 3]| dd * inv_m + ll + 2.0 * dl * inv_m;
        let m = JITTER_RAYS as f64;
        // The light sample's own variance at x₀ (M samples' mean), less the 1/K of it that the
        // rays' K-sample means already put into the spread above.
        let light = light_var / m * inv_m * (1.0 - 1.0 / AREA_SAMPLES as f64);
        light
            + match strata {
                // The mean variance within a cell: N_B stratified samples, one per cell, have a
                // mean whose variance is that over N_B (falling faster than 1/N_B at an edge,
                // which crosses few cells).
                Some(_) => combine(within) / (m / 2.0),
                None => {
                    let moments = [
                        sum_sq[0] - sum[0] * sum[0] / m,
                        sum_sq[1] - sum[1] * sum[1] / m,
                        sum_sq[2] - sum[0] * sum[1] / m,
                    ];
                    (combine(moments) / (m - 1.0)).max(0.0)
                }
            }
    }
}

/// The stream and the three numbers of the model's direction `j` of `pixel`: with the
/// sampler's direction strata `grid`, directions 2i and 2i + 1 share one random cell (`cell`,
/// drawn at the even one).
fn direction_numbers(
    seed: u64,
    (pixel, j): (u64, u32),
    grid: Option<(u32, u32)>,
    cell: &mut (u32, u32),
) -> (Rng, [f32; 3]) {
    // Key slot 1: the A/B rays of table.rs use slot 0 with the same pixel and ray.
    let mut rng = Rng::new(seed, Domain::PixelTable, [pixel, j as u64, 1]);
    let mut u = rng.uniform3();
    if let Some(grid) = grid {
        if j % 2 == 0 {
            // Key slot 3: the cell of pair j/2.
            let key = [pixel, j as u64 / 2, 3];
            *cell = random_cell(grid, &mut Rng::new(seed, Domain::PixelTable, key));
        }
        let [a, b] = in_cell(*cell, grid, [u[1], u[2]]);
        u = [u[0], a, b];
    }
    (rng, u)
}

/// One BDF-sampled direction v at x₀: its BDD=1 value and its photon-noise integrands, or None
/// when the sample finds no x₁ (it then contributes zero, as in the renderer).
///
/// A direction that meets a mirror or glass is followed through it to a non-delta x₁
/// ([`chain_direction`]), with numbers from `rng`; none are drawn otherwise.
fn direction(
    mix: &Mix<'_>,
    cache: &RadianceCache,
    weigher: &Weigher,
    x0: &FirstVertex<'_>,
    u: [f32; 3],
    rng: &mut Rng,
) -> Option<Direction> {
    let scene = mix.scene;
    let s = x0.bdf.sample_at(&x0.out, u)?;
    let v = x0.sh.frame.to_world(s.wi);
    if x0.sh.ng.dot(v) <= 0.0 || s.pdf <= 0.0 {
        return None;
    }
    let hit1 = scene
        .geometry()
        .intersect(scene.spawn(&x0.sh, v), v, f32::INFINITY)?;
    let wo1 = -v;
    let sh1 = scene.shade(&hit1, wo1);
    if scene.is_delta(sh1.material) {
        return chain_direction(mix, cache, x0, (&s, v), rng);
    }
    let x1 = scene.weight_vertex(&sh1);
    let pair = mix.pair(x0, &x1, v, mix.f_at_x0(x0, v));
    let dist2 = (x1.p - x0.sh.p).length_squared();
    let needs = weigher.heuristic().needs();
    let per_light = needs.densities;
    // The longer paths' weight for the model's stand-in light path.
    let merge = mix.path_pair(x0, &x1, (v, dist2), Arrival::Modelled, pair);
    let w_merge = weigher.weight(&merge).w1;
    // Weights that tell one-bounce paths from merge paths (`optimal-split`, `optimal-path`).
    let w_direct = if needs.path_kinds {
        let one = mix.path_pair(x0, &x1, (v, dist2), Arrival::Light(0), pair);
        weigher.weight(&one).w1
    } else {
        w_merge
    };

    // L₀(x₁→x₀) light by light, as BDD=1 evaluates it (shading normal, visibility bits).
    let (mut l0_w, mut l0_w0_sq) = (0.0f64, 0.0f64);
    for l in 0..scene.lights().len() {
        let c = scene.direct_from_masked(&sh1, wo1, l, x1.lights);
        let c = luminance(c) as f64;
        if c == 0.0 {
            continue;
        }
        let w = if per_light {
            let one_bounce = mix.path_pair(x0, &x1, (v, dist2), Arrival::Light(l), pair);
            weigher.weight(&one_bounce).w1
        } else {
            w_direct
        };
        l0_w += c * w;
        l0_w0_sq += c * (1.0 - w) * (1.0 - w);
    }
    // The area lights' one-bounce paths, each light sample weighted as its own path.
    let mut area = AreaMoments::default();
    if scene.has_emission() {
        // BDD=1's glossy x₁ weighs its light sample against a BDF ray, a Lambert one does not.
        let mis = x1_weighs_bdf(scene, &sh1);
        area = area_moments(scene, (&sh1, wo1), rng, mis, |wi| {
            if per_light {
                let one = mix.path_pair(x0, &x1, (v, dist2), Arrival::Area(wi), pair);
                weigher.weight(&one).w1
            } else {
                w_direct
            }
        });
    }
    // The model's L_d and b at x₁ towards x₀ (the weights read theirs, in `pair`).
    let (ld, b) = mix.model_lookup(cache, &x1, wo1);
    // `optimal-path` weighs each photon by its own f₁ at x₁: at a glossy x₁ its merge paths'
    // weights are averaged over sampled arrivals; elsewhere one weight stands for them all.
    let per_arrival = |incoming| {
        let path = mix.path_pair(x0, &x1, (v, dist2), Arrival::Sampled(incoming), pair);
        weigher.weight(&path).w1
    };
    let merge_w = (needs.x1_scattering && x1_weighs_bdf(scene, &sh1))
        .then(|| arrival_moments(mix, cache, &sh1, wo1, rng, per_arrival))
        .flatten()
        .unwrap_or(MergeWeights::one(w_merge));
    let f = luminance(s.f) as f64;
    let cos = s.wi.z as f64;
    let pdf = s.pdf as f64;
    // E = f·cos/p, the camera path's weight after the scattering at x₀.
    let e = f * cos / pdf;
    Some(Direction {
        value: e * (l0_w + area.weighted + ld * merge_w.mean),
        direct: e * (l0_w + area.weighted),
        photons_x0: (l0_w0_sq + area.unweighted_sq + ld * merge_w.complement_sq) * f * f * cos
            / pdf,
        photons_x1: merge_w.square_b * e * e * b,
        light_var: e * e * area.variance,
    })
}

/// Arrival directions per glossy x₁ with which the model resolves `optimal-path`'s per-photon
/// weights (8 keeps their averages' noise below that of the pixel's 64 directions).
pub const ARRIVAL_SAMPLES: u32 = 8;

/// The merge paths' weight w₁ at x₁ averaged over their arrivals: under L_d's density
/// (f₁·ℓ·cos) for BDD=1's mean and the merges at x₀, under b's (f₁²·ℓ·cos) for the merges at
/// x₁ (dimensionless).
#[derive(Clone, Copy, Debug)]
struct MergeWeights {
    /// The mean of w under f₁·ℓ·cos.
    mean: f64,
    /// The mean of (1 − w)² under f₁·ℓ·cos.
    complement_sq: f64,
    /// The mean of w² under f₁²·ℓ·cos.
    square_b: f64,
}

impl MergeWeights {
    /// One weight for every arrival.
    fn one(w: f64) -> Self {
        Self {
            mean: w,
            complement_sq: (1.0 - w) * (1.0 - w),
            square_b: w * w,
        }
    }
}

/// [`MergeWeights`] at x₁ (`sh1`, towards x₀ along the unit `wo1`) from [`ARRIVAL_SAMPLES`]
/// BDF-sampled arrivals ω₂, each weighted by `weight`(ω₂) and by the radiance ℓ that arrives
/// along it after at least one bounce (the light's direct light at the next non-delta vertex y
/// plus the cache's L_d there, through mirrors and glass; y's own Le is a one-bounce path at x₁,
/// which the light sample takes). None where no arrival finds light.
fn arrival_moments(
    mix: &Mix<'_>,
    cache: &RadianceCache,
    sh1: &Shading,
    wo1: Vec3,
    rng: &mut Rng,
    weight: impl Fn(Vec3) -> f64,
) -> Option<MergeWeights> {
    let scene = mix.scene;
    let bdf = scene.bdf_at(sh1);
    let out = bdf.outgoing(sh1.frame.to_local(wo1));
    // Σ f₁ℓcos/p, Σ f₁²ℓcos/p, and their sums weighted by w, (1 − w)², w².
    let (mut ld, mut b, mut mean, mut complement, mut square) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for _ in 0..ARRIVAL_SAMPLES {
        let Some(s) = bdf.sample_at(&out, rng.uniform3()) else {
            continue;
        };
        let wi = sh1.frame.to_world(s.wi);
        if s.pdf <= 0.0 || sh1.ng.dot(wi) <= 0.0 {
            continue;
        }
        let Some(walk) =
            scene.walk_to_non_delta(scene.spawn(sh1, wi), wi, Transport::Radiance, || {
                rng.uniform()
            })
        else {
            continue;
        };
        let (sh, u) = (walk.sh, walk.wo);
        let mut l = scene.direct(&sh, u);
        if scene.has_emission() {
            l += scene
                .direct_area_sample(&sh, u, rng.uniform3(), false)
                .map_or(Vec3::ZERO, |(c, _)| c);
        }
        let l = luminance(walk.beta * l) as f64
            + cache.lookup(sh.prim, sh.p, u).0 as f64 * luminance(walk.beta) as f64;
        let f1 = luminance(s.f) as f64;
        let g = f1 * s.wi.z as f64 / s.pdf as f64 * l;
        let w = weight(wi);
        ld += g;
        b += f1 * g;
        mean += w * g;
        complement += (1.0 - w) * (1.0 - w) * g;
        square += w * w * f1 * g;
    }
    (ld > 0.0 && b > 0.0).then(|| MergeWeights {
        mean: mean / ld,
        complement_sq: complement / ld,
        square_b: square / b,
    })
}

/// The area lights' direct light at a vertex from [`AREA_SAMPLES`] draws as the renderer
/// takes its one ([`area_moments`]: a light sample, with or without MIS against a BDF ray),
/// each strategy's value c (luminance, W·m⁻²·sr⁻¹) weighted by w = `weight`(its unit
/// direction to the light).
#[derive(Clone, Copy, Debug, Default)]
struct AreaMoments {
    /// Mean of w·c, W·m⁻²·sr⁻¹.
    weighted: f64,
    /// Mean of (1 − w)²·c, W·m⁻²·sr⁻¹.
    unweighted_sq: f64,
    /// Unbiased variance of one sample's w·c, W²·m⁻⁴·sr⁻².
    variance: f64,
}

/// [`AreaMoments`] at `sh` towards the unit direction `wo`, numbers from `rng`: with `mis`,
/// per draw one light sample weighted by the power heuristic plus one BDF ray whose hit on an
/// emitter takes the complementary weight (`Scene::emitter_hit_by_bdf`), as the renderer's x₀
/// in every mode that traces BDD=1 and its glossy x₁ take them; without, the light sample alone.
/// Each strategy's value is weighted by `weight`(its unit direction to the light).
fn area_moments(
    scene: &bdpm_scene::Scene,
    (sh, wo): (&Shading, Vec3),
    rng: &mut Rng,
    mis: bool,
    weight: impl Fn(Vec3) -> f64,
) -> AreaMoments {
    let k = AREA_SAMPLES as f64;
    let (mut sum, mut sum_sq, mut rest) = (0.0, 0.0, 0.0);
    for _ in 0..AREA_SAMPLES {
        let light = scene.direct_area_sample(sh, wo, rng.uniform3(), mis);
        let bdf = mis
            .then(|| scene.emitter_hit_by_bdf(sh, wo, rng.uniform3()))
            .flatten();
        let mut draw = 0.0;
        for (c, wi) in [light, bdf].into_iter().flatten() {
            let c = luminance(c) as f64;
            let w = weight(wi);
            draw += w * c;
            rest += (1.0 - w) * (1.0 - w) * c;
        }
        sum += draw;
        sum_sq += draw * draw;
    }
    AreaMoments {
        weighted: sum / k,
        unweighted_sq: rest / k,
        variance: ((sum_sq - sum * sum / k) / (k - 1.0)).max(0.0),
    }
}

/// [`direction`] for a v that meets mirrors or glass before a non-delta x₁: the render weighs
/// these paths with [`Mix::chain_w1`] on both sides, and the chain's throughput β (luminance)
/// scales the radiance x₀ receives through it (the photons at x₀ keep their power, so their
/// noise scales with β; a merge at x₁ seen through the chain, with β²).
#[cold]
fn chain_direction(
    mix: &Mix<'_>,
    cache: &RadianceCache,
    x0: &FirstVertex<'_>,
    (s, v): (&bdpm_bdf::BdfSample, Vec3),
    rng: &mut Rng,
) -> Option<Direction> {
    let scene = mix.scene;
    let walk = scene.walk_to_non_delta(scene.spawn(&x0.sh, v), v, Transport::Radiance, || {
        rng.uniform()
    })?;
    let (sh1, wo1) = (walk.sh, walk.wo);
    let x1 = scene.weight_vertex(&sh1);
    let beta = luminance(walk.beta) as f64;
    let l0: f64 = (0..scene.lights().len())
        .map(|l| luminance(scene.direct_from_masked(&sh1, wo1, l, x1.lights)) as f64)
        .sum();
    let area = if scene.has_emission() {
        let mis = x1_weighs_bdf(scene, &sh1);
        area_moments(scene, (&sh1, wo1), rng, mis, |_| 1.0)
    } else {
        AreaMoments::default()
    };
    let (ld, b) = mix.model_lookup(cache, &x1, wo1);
    let w = mix.chain_w1(x0);
    let (f, cos, pdf) = (luminance(s.f) as f64, s.wi.z as f64, s.pdf as f64);
    let e = f * cos / pdf;
    let l = beta * (l0 + area.weighted + ld);
    Some(Direction {
        value: e * w * l,
        direct: e * w * beta * (l0 + area.weighted),
        photons_x0: (1.0 - w).powi(2) * l * f * f * cos / pdf,
        photons_x1: w * w * e * e * beta * beta * b,
        light_var: (e * w * beta).powi(2) * area.variance,
    })
}

/// The one-bounce paths' share of a camera sample at a glossy x₀ that takes `n` x₁ for them
/// (crate::one_bounce): the sample's own x₁ carries 1/n of them and n − 1 further x₁, each in
/// its own independent direction, the rest.
struct OneBounceShare {
    /// x₁ per camera sample for the one-bounce paths.
    n: f64,
    /// Σ and Σ² over the model's directions of the one-bounce part of a direction's value.
    sum: f64,
    sum_sq: f64,
}

impl OneBounceShare {
    fn new(n: u32) -> Self {
        OneBounceShare {
            n: f64::from(n),
            sum: 0.0,
            sum_sq: 0.0,
        }
    }

    /// The BDD=1 value of direction `d` (scaled by `beta`) as the sample's own x₁ gives it,
    /// its one-bounce part at 1/n; the part's moments are kept for [`Self::further_variance`].
    fn value(&mut self, d: &Direction, beta: f64) -> f64 {
        let direct = beta * d.direct;
        self.sum += direct;
        self.sum_sq += direct * direct;
        beta * d.value - direct * (1.0 - 1.0 / self.n)
    }

    /// The further x₁'s variance over `rays` directions: (n − 1)/n² of the one-bounce part's
    /// full variance.
    fn further_variance(&self, rays: f64) -> f64 {
        let var = ((self.sum_sq - self.sum * self.sum / rays) / (rays - 1.0)).max(0.0);
        (self.n - 1.0) / (self.n * self.n) * var
    }
}
