//! `bdpm predict` with an area light: the noise model (`Renderer::predict_variance`) against
//! the per-pass variance measured on scenes/cornell-box-glossy.toml, whose only light is the
//! ceiling's area light. There direct light at x₁ is BDD=1's one light sample per camera
//! sample and direct light at x₀ one more, both estimates with their own variance; before the
//! model saw area lights it took L₀ = 0 at every vertex (issue 46 item 4's bar: 8×8-block
//! median of predicted/measured V in 0.8–1.25 and correlation of ln V ≥ 0.8).

use bdpm_integrator::Renderer;
use bdpm_suite::{load, with_mode};

use crate::predict::{MODEL_PHOTONS, block_agreement};

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
    // The default mode.
    let s = with_mode(&settings, "optimal-path", PASSES, 4, 100_000);
    let renderer = Renderer::new(&scene, &s)
        .expect("valid settings")
        .with_model_cache(MODEL_PHOTONS);
    let p = renderer
        .predict_variance()
        .expect("a mode with a noise model");
    block_agreement(&renderer, &p.total, side)
        .report_and_assert_bars("cornell-box-glossy optimal-path");
}
