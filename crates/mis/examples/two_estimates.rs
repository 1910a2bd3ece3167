//! MIS weights for an existing renderer's two estimates of one pixel's indirect light:
//! BDD=0 (gather photons at the first camera vertex x₀) and BDD=1 (continue the camera path
//! to x₁ and gather there). bdpm-mis needs no geometry: the renderer passes scalars it
//! already has (luminances, the merge area, photon counts), and mixes its estimates as
//! w₀·E₀ + w₁·E₁ with w₀ = 1 − w₁, which is unbiased for any weight.
//!
//! `cargo run --release -p bdpm-mis --example two_estimates`

use std::f64::consts::PI;

use bdpm_mis::{Budget, Heuristic, Pair, X0Inputs, X1Inputs};

fn main() {
    // The renderer's settings for one pass: 16 camera samples per pixel, a million photons,
    // merge radius 5 mm, 1 W of light (luminance).
    let radius = 0.005; // m
    let budget = Budget {
        camera_samples: 16.0,
        photons: 1e6,
        merge_area: PI * radius * radius,
        flux: 1.0,
    };
    // One pair (x₀, x₁) on Lambert surfaces of albedo 0.5: f̃ = 1/π at x₀; the light leaving
    // x₁ towards x₀ is 0.8 W·m⁻²·sr⁻¹ direct and 0.3 indirect (from the renderer's own
    // radiance cache; b = (k_d/π)·L_d for Lambert).
    let pair = Pair {
        x0: X0Inputs {
            f_tilde: 1.0 / PI,
            ..Default::default()
        },
        x1: X1Inputs {
            direct: 0.8,
            indirect: 0.3,
            b: 0.5 / PI * 0.3,
            light_distance: 0.4,
        },
        ..Pair::default()
    };
    // The renderer's two estimates of this pair's contribution (any numbers: the check below
    // is that the mix never changes what both estimate).
    let (e0, e1) = (0.42, 0.42);

    println!("{:<18} {:>8} {:>8}", "heuristic", "w0", "w1");
    for name in [
        "bdd0",
        "bdd1",
        "threshold",
        "algebraic-direct",
        "algebraic",
        "optimal",
    ] {
        let h = Heuristic::parse(name).expect("a known heuristic name");
        let w = h.weight(&budget, &pair, None);
        println!("{name:<18} {:>8.4} {:>8.4}", w.w0(), w.w1);
        assert!(w.w1.is_finite());
        // w₀ + w₁ = 1 exactly, so equal estimates mix to the same value.
        assert_eq!(w.w0() + w.w1, 1.0);
        assert!((w.w0() * e0 + w.w1 * e1 - e0).abs() < 1e-12);
    }

    // Eq. 10 by hand: the algebraic weight at a Lambert x₀ is 1/(1 + π κ(L)/N_B), with
    // κ(L) = S·L·N_F/Φ the expected photons in the merge disk per steradian.
    let w = Heuristic::Algebraic.weight(&budget, &pair, None);
    let kappa = budget.kappa(pair.x1.direct + pair.x1.indirect);
    let by_hand = 1.0 / (1.0 + PI * kappa / budget.camera_samples);
    println!(
        "algebraic w1 = {:.6}, by hand (eq. 10) = {by_hand:.6}",
        w.w1
    );
    assert!((w.w1 - by_hand).abs() < 1e-12);
}
