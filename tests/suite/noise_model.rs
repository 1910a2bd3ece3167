//! The overlap model of method.md §12, measured: `bdd0` with fixed N_F and N_B ∈ {1, 4, 16, 64}
//! on cornell-lambert at two resolutions. With jittered samples the per-pass variance of the
//! photon estimate at x₀ should fall as V(N_B)/V(1) = 1/N_B + ρ(1 − 1/N_B), ρ the pixel's
//! footprint overlap for pairs of that N_B's samples (computed by the renderer's pixel table:
//! with the default stratified samples it depends on N_B through the strata); with every
//! sample through the pixel centre it should not fall at all (the N_B gathers are one gather).
//!
//! Only the photon part of the sample (the `x0_weighted` technique layer, which for `bdd0` is the
//! whole indirect estimate) is measured: the direct light at x₀ varies over the footprint and
//! averages as 1/N_B whatever ρ is, which is not what this checks. The test prints the table of
//! docs/results.md: `cargo test --release -p bdpm-suite --test suite noise_model:: -- --nocapture`.

use bdpm_integrator::{Mode, NoiseModel, RenderSettings, Renderer};
use bdpm_suite::{load, lum};

/// Passes per configuration: enough that the image-mean variance ratio has a standard error of
/// a few per cent.
const PASSES: u32 = 48;
/// Photons per pass: few enough that photon noise dwarfs the variation of indirect light over a
/// pixel (the model's premise), enough that most gathers find some photons.
const PHOTONS: u64 = 100_000;
/// Merge radius, m: large enough that the disks of two samples in one pixel overlap noticeably
/// at these small resolutions (ρ ≈ 0.05–0.3), as r = 1.75 mm does at 256²–512².
const RADIUS: f32 = 0.02;
const SPPS: [u32; 4] = [1, 4, 16, 64];

/// Per pass, per pixel: the luminance of the photon estimate at x₀ (mean over the pixel's
/// samples).
fn photon_estimates(
    scene: &bdpm_scene::Scene,
    base: &RenderSettings,
    spp: u32,
    jitter: bool,
) -> Vec<Vec<f64>> {
    let settings = RenderSettings {
        mode: Mode::parse("bdd0").unwrap(),
        spp,
        pixel_jitter: jitter,
        ..base.clone()
    };
    let renderer = Renderer::new(scene, &settings)
        .unwrap_or_else(|e| panic!("{e}"))
        .with_technique_layers(true);
    (0..settings.passes)
        .map(|pass| {
            let out = renderer.render_pass(pass, &|_| {});
            out.techniques
                .expect("technique layers")
                .iter()
                .map(|t| lum(t.x0_weighted.as_vec3()) as f64)
                .collect()
        })
        .collect()
}

/// The renderer's ρ per pixel for N_B = `spp` (from the pixel table of a footprint-model mode;
/// stratified samples, the default, have a ρ that depends on N_B through the strata).
fn overlaps(scene: &bdpm_scene::Scene, base: &RenderSettings, spp: u32) -> Vec<f64> {
    let settings = RenderSettings {
        mode: Mode::parse("algebraic-direct").unwrap(),
        noise_model: NoiseModel::Footprint,
        pixel_jitter: true,
        spp,
        ..base.clone()
    };
    let renderer = Renderer::new(scene, &settings).unwrap_or_else(|e| panic!("{e}"));
    let table = renderer.pixel_table().expect("footprint table");
    table.pixels().iter().map(|p| p.overlap).collect()
}

/// Per-pixel sample variance over the passes in `keep` (all but one, for the jackknife).
fn variances(est: &[Vec<f64>], skip: Option<usize>) -> Vec<f64> {
    let pixels = est[0].len();
    let passes: Vec<&Vec<f64>> = est
        .iter()
        .enumerate()
        .filter(|(k, _)| Some(*k) != skip)
        .map(|(_, e)| e)
        .collect();
    let n = passes.len() as f64;
    (0..pixels)
        .map(|p| {
            let mean = passes.iter().map(|e| e[p]).sum::<f64>() / n;
            passes.iter().map(|e| (e[p] - mean).powi(2)).sum::<f64>() / (n - 1.0)
        })
        .collect()
}

/// (measured, predicted) image-level ratio Σ V_N / Σ V_1 and the V_1-weighted prediction
/// Σ V_1·(1/N + ρ(1 − 1/N)) / Σ V_1.
fn ratios(v1: &[f64], vn: &[f64], rho: &[f64], n: f64) -> (f64, f64) {
    let (mut s1, mut sn, mut sp) = (0.0, 0.0, 0.0);
    for p in 0..v1.len() {
        if v1[p] > 0.0 {
            s1 += v1[p];
            sn += vn[p];
            sp += v1[p] * (1.0 / n + rho[p] * (1.0 - 1.0 / n));
        }
    }
    (sn / s1, sp / s1)
}

struct Row {
    spp: u32,
    measured: f64,
    predicted: f64,
    standard_error: f64,
    pixel_median: f64,
    pixel_q10: f64,
    pixel_q90: f64,
}

/// Measures one resolution: rows for N_B = 4, 16, 64 (jittered) and the centred ratios.
fn measure(size: u32) -> (Vec<f64>, Vec<Row>, Vec<f64>) {
    let (scene, base) = load("preprint/cornell-lambert.toml", size, size);
    let base = RenderSettings {
        passes: PASSES,
        photons: PHOTONS,
        radius: Some(RADIUS),
        seed: 7,
        ..base
    };
    let jittered: Vec<Vec<Vec<f64>>> = SPPS
        .iter()
        .map(|&n| photon_estimates(&scene, &base, n, true))
        .collect();
    let mut rows = Vec::new();
    let v1 = variances(&jittered[0], None);
    let mut mean_rho = Vec::new();
    for (i, &n) in SPPS.iter().enumerate().skip(1) {
        let nf = n as f64;
        let rho = overlaps(&scene, &base, n);
        let surface: Vec<f64> = rho.iter().copied().filter(|&r| r > 0.0).collect();
        mean_rho.push(surface.iter().sum::<f64>() / surface.len().max(1) as f64);
        let vn = variances(&jittered[i], None);
        let (measured, predicted) = ratios(&v1, &vn, &rho, nf);
        // Jackknife over passes (the N_B = 1 and N_B = n renders share each pass's photon map,
        // so a pass is left out of both).
        let k = PASSES as usize;
        let leave_out: Vec<f64> = (0..k)
            .map(|j| {
                let (m, p) = ratios(
                    &variances(&jittered[0], Some(j)),
                    &variances(&jittered[i], Some(j)),
                    &rho,
                    nf,
                );
                m - p
            })
            .collect();
        let mean = leave_out.iter().sum::<f64>() / k as f64;
        let var =
            leave_out.iter().map(|d| (d - mean).powi(2)).sum::<f64>() * (k as f64 - 1.0) / k as f64;
        let mut per_pixel: Vec<f64> = (0..v1.len())
            .filter(|&p| v1[p] > 0.0)
            .map(|p| (vn[p] / v1[p]) / (1.0 / nf + rho[p] * (1.0 - 1.0 / nf)))
            .collect();
        per_pixel.sort_by(f64::total_cmp);
        let q = |f: f64| per_pixel[((per_pixel.len() - 1) as f64 * f).round() as usize];
        rows.push(Row {
            spp: n,
            measured,
            predicted,
            standard_error: var.sqrt(),
            pixel_median: q(0.5),
            pixel_q10: q(0.1),
            pixel_q90: q(0.9),
        });
    }
    let centred: Vec<f64> = SPPS
        .iter()
        .skip(1)
        .map(|&n| {
            let c1 = variances(&photon_estimates(&scene, &base, 1, false), None);
            let cn = variances(&photon_estimates(&scene, &base, n, false), None);
            let (s1, sn) = c1
                .iter()
                .zip(&cn)
                .filter(|(a, _)| **a > 0.0)
                .fold((0.0, 0.0), |(s1, sn), (a, b)| (s1 + a, sn + b));
            sn / s1
        })
        .collect();
    (mean_rho, rows, centred)
}

#[test]
fn photon_noise_at_x0_falls_as_the_overlap_model_predicts() {
    let mut failures = Vec::new();
    println!(
        "| resolution | mean ρ | N_B | measured V(N_B)/V(1) | predicted | (m − p)/SE | per-pixel measured/predicted: median [10 %, 90 %] | centred V(N_B)/V(1) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for size in [32, 64] {
        let (mean_rho, rows, centred) = measure(size);
        for ((row, c), mean_rho) in rows.iter().zip(&centred).zip(&mean_rho) {
            let z = (row.measured - row.predicted) / row.standard_error;
            println!(
                "| {size}² | {mean_rho:.3} | {} | {:.4} ± {:.4} | {:.4} | {z:+.2} | {:.3} [{:.3}, {:.3}] | {c:.6} |",
                row.spp,
                row.measured,
                row.standard_error,
                row.predicted,
                row.pixel_median,
                row.pixel_q10,
                row.pixel_q90
            );
            // The image-level ratio within 3 standard errors of the prediction, plus 5 % of it
            // for the model's planar footprint: a footprint that crosses an edge is taken to
            // continue on x₀'s plane. With stratified samples that overstates the sharing by
            // 3–4 % at 32² (footprints of several disk radii, a quarter of them on an edge);
            // at 64² the ratios are within 1.2 standard errors. ρ of independent samples in
            // place of the stratified one is 12 % off at 64², N_B = 4, and fails.
            if (row.measured - row.predicted).abs()
                > 3.0 * row.standard_error + 0.05 * row.predicted
            {
                failures.push(format!("{size}², N_B = {}: z = {z:.2}", row.spp));
            }
            // Per pixel, the typical pixel follows the model too (a wide band: one pixel's
            // variance from 48 passes is uncertain by ~20 %).
            if !(0.85..=1.15).contains(&row.pixel_median) {
                failures.push(format!(
                    "{size}², N_B = {}: per-pixel median ratio {:.3}",
                    row.spp, row.pixel_median
                ));
            }
            // Through the centre the N_B gathers are one gather: no reduction at all.
            if (c - 1.0).abs() > 1e-9 {
                failures.push(format!("{size}², N_B = {}: centred ratio {c}", row.spp));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
