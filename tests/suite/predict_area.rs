//! `bdpm predict` with an area light: the noise model (`Renderer::predict_variance`) against
//! the per-pass variance measured on scenes/cornell-box-glossy.toml, whose only light is the
//! ceiling's area light. There direct light at x₁ is BDD=1's one light sample per camera
//! sample and direct light at x₀ one more, both estimates with their own variance; before the
//! model saw area lights it took L₀ = 0 at every vertex (issue 46 item 4's bar: 8×8-block
//! median of predicted/measured V in 0.8–1.25 and correlation of ln V ≥ 0.8).

use bdpm_integrator::Renderer;
use bdpm_suite::{load, with_mode};

use crate::predict::{MODEL_PHOTONS, measured_group_variances};

/// Pearson correlation of two equally long samples.
fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

/// Passes of the measured V. The glossy surfaces make BDD=1's light sample at x₁ a rare-event
/// estimate (the sample lands in a 1.5° lobe that reflects the light); with few passes a
/// pixel's measured V usually misses those events and lies below its expectation, the
/// model's (docs/results.md, "Area lights: the noise model and the weights"). The block median
/// of predicted/measured V falls with the passes while the prediction stays the same: 1.68 at
/// 128, 1.22 at 256, 1.18 at 384, 1.11 at 512, 1.14 at 1024 (correlation of ln V 0.81, 0.78,
/// 0.81, 0.84, 0.87): 512 is the fewest that meets the bar with some margin.
const PASSES: u32 = 512;

/// Per 8×8 block: the predicted image-mean V against the measured one from [`PASSES`] passes
/// of 4 samples and 10⁵ photons at 64², for `optimal-path`, the default mode: issue 46's bar,
/// block median within 0.8–1.25 and correlation of ln V ≥ 0.8 (measured 1.11 and 0.84).
#[test]
fn predict_sees_the_area_light_on_the_glossy_box() {
    let side = 64u32;
    let (scene, settings) = load("cornell-box-glossy.toml", side, side);
    for mode in ["optimal-path"] {
        let s = with_mode(&settings, mode, PASSES, 4, 100_000);
        let renderer = Renderer::new(&scene, &s)
            .expect("valid settings")
            .with_model_cache(MODEL_PHOTONS);
        let p = renderer
            .predict_variance()
            .expect("a mode with a noise model");
        let blocks_per_row = side.div_ceil(8) as usize;
        let group: Vec<usize> = (0..(side * side) as usize)
            .map(|i| (i / side as usize / 8) * blocks_per_row + (i % side as usize) / 8)
            .collect();
        let groups = blocks_per_row * blocks_per_row;
        let measured = measured_group_variances(&renderer, &group, groups);
        let mut predicted = vec![(0.0, 0usize); groups];
        for (i, v) in p.total.iter().enumerate() {
            if v.is_finite() {
                predicted[group[i]].0 += v;
                predicted[group[i]].1 += 1;
            }
        }
        let (mut ratios, mut lp, mut lm) = (Vec::new(), Vec::new(), Vec::new());
        for (g, (sum, count)) in predicted.iter().enumerate() {
            let pred = sum / *count as f64;
            let meas = measured[g].0;
            ratios.push(pred / meas);
            lp.push(pred.ln());
            lm.push(meas.ln());
        }
        ratios.sort_by(f64::total_cmp);
        let median = ratios[ratios.len() / 2];
        let correlation = pearson(&lp, &lm);
        eprintln!(
            "cornell-box-glossy {mode}: 8x8 blocks predicted/measured median {median:.3} \
             [min {:.3}, max {:.3}], correlation of ln V {correlation:.3}",
            ratios[0],
            ratios[ratios.len() - 1]
        );
        assert!(
            (0.8..=1.25).contains(&median),
            "{mode}: block median {median}"
        );
        assert!(correlation >= 0.8, "{mode}: correlation {correlation}");
    }
}
