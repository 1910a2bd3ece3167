//! Unit tests: every formula of method.md §4 and §8 against hand-computed values, and
//! every guard.

use super::*;
use std::f64::consts::PI;

/// N_B = 2, N_F = 2, S = 0.5 m², Φ = 1 W: κ(L) = L and c = (1 − ½)·0.5·2/(1·2) = ¼.
const SIMPLE: Budget = Budget {
    camera_samples: 2.0,
    photons: 2.0,
    merge_area: 0.5,
    flux: 1.0,
};

const OPTIMAL: Heuristic = Heuristic::Optimal {
    clamp_weights: false,
};

fn assert_close(actual: f64, expected: f64) {
    let tolerance = 1e-14 * expected.abs().max(1.0);
    assert!(
        (actual - expected).abs() <= tolerance,
        "{actual} != {expected} (tolerance {tolerance})"
    );
}

fn lit(f_tilde: f64, direct: f64, indirect: f64, b: f64) -> Pair {
    Pair {
        x0: X0Inputs {
            f_tilde,
            ..Default::default()
        },
        x1: X1Inputs {
            direct,
            indirect,
            b,
            ..Default::default()
        },
        ..Pair::default()
    }
}

#[test]
fn kappa_and_c_match_hand_values() {
    assert_close(SIMPLE.kappa(3.0), 3.0);
    assert_close(SIMPLE.c(), 0.25);
    let budget = Budget {
        camera_samples: 30.0,
        photons: 1e6,
        merge_area: 2e-5,
        flux: 4.0,
    };
    // κ = 2e-5 · 7 · 1e6 / 4 = 35; c = (1 − 1e-6) · 2e-5 · 1e6 / (4 · 30).
    assert_close(budget.kappa(7.0), 35.0);
    assert_close(budget.c(), (1.0 - 1e-6) * 2e-5 * 1e6 / 120.0);
    assert_eq!(budget.kappa(0.0), 0.0);
}

#[test]
fn c_vanishes_with_one_photon() {
    let budget = Budget {
        photons: 1.0,
        ..SIMPLE
    };
    assert_eq!(budget.c(), 0.0);
    // Without correlation, eq. 8 is W₁ even with large A, B.
    let pair = lit(0.5, 1.0, 3.0, 8.0);
    let pixel = PixelTerms { a: 5.0, b: 50.0 };
    let w = OPTIMAL.weight(&budget, &pair, Some(&pixel));
    assert_close(w.w1, w1_partial(&budget, 0.5, 4.0, 8.0));
    assert!(!w.clamped_cb);
}

#[test]
fn algebraic_matches_hand_values() {
    // N_B f̃ = 1. Direct only: κ(1) = 1, w₁ = ½. Direct + indirect: κ(4) = 4, w₁ = ⅕.
    let pair = lit(0.5, 1.0, 3.0, 0.0);
    let direct = Heuristic::AlgebraicDirect.weight(&SIMPLE, &pair, None);
    let full = Heuristic::Algebraic.weight(&SIMPLE, &pair, None);
    assert_close(direct.w1, 0.5);
    assert_close(full.w1, 0.2);
    assert_close(full.w0(), 0.8);
    assert!(!full.outside_unit && !full.clamped_cb);
}

#[test]
fn algebraic_lambert_is_preprint_closed_form() {
    let budget = Budget {
        camera_samples: 30.0,
        photons: 1e6,
        merge_area: PI * 1.7e-3 * 1.7e-3,
        flux: 1.0,
    };
    for radiance in [0.0, 1e-3, 0.05, 1.0, 40.0, 3e4] {
        let pair = lit(1.0 / PI, radiance, 0.0, 0.0);
        let w = Heuristic::AlgebraicDirect.weight(&budget, &pair, None);
        let expected = 1.0 / (1.0 + PI * budget.kappa(radiance) / 30.0);
        assert_close(w.w1, expected);
    }
}

#[test]
fn optimal_matches_hand_values() {
    // N_B f̃ = 1, L = 4, b/L = 2, κ = 4: D = 7, W₁ = 1/7.
    // c·B = ½, G̃ = A/(1 − c·B) = 2, w₁ = N_B (f̃ + c·G̃)/D = 2·(½ + ½)/7 = 2/7.
    let pair = lit(0.5, 1.0, 3.0, 8.0);
    assert_close(w1_partial(&SIMPLE, 0.5, 4.0, 8.0), 1.0 / 7.0);
    let pixel = PixelTerms { a: 1.0, b: 2.0 };
    let w = OPTIMAL.weight(&SIMPLE, &pair, Some(&pixel));
    assert_close(w.w1, 2.0 / 7.0);
    assert!(!w.clamped_cb && !w.outside_unit);
    // Without a pixel table, A = B = 0 and eq. 8 is W₁.
    assert_close(OPTIMAL.weight(&SIMPLE, &pair, None).w1, 1.0 / 7.0);
}

#[test]
fn optimal_without_correlation_or_b_is_algebraic() {
    let budget = Budget {
        camera_samples: 10.0,
        photons: 250_000.0,
        merge_area: 3e-6,
        flux: 1.0,
    };
    let zero = PixelTerms { a: 0.0, b: 0.0 };
    for (f_tilde, direct, indirect) in [(1.0 / PI, 0.3, 0.02), (40.0, 12.0, 1.0), (0.01, 1e3, 7.0)]
    {
        let pair = lit(f_tilde, direct, indirect, 0.0);
        let algebraic = Heuristic::Algebraic.weight(&budget, &pair, None).w1;
        assert_close(OPTIMAL.weight(&budget, &pair, Some(&zero)).w1, algebraic);
        assert_close(OPTIMAL.weight(&budget, &pair, None).w1, algebraic);
    }
}

#[test]
fn optimal_equals_preprint_form() {
    // w₁ = W₁·(1 + (1/f̃)·c·A/(1 − c·B)) (preprint eq. 8 with eq. 9).
    let budget = Budget {
        camera_samples: 3.0,
        photons: 1000.0,
        merge_area: 1e-3,
        flux: 2.0,
    };
    let c = budget.c();
    for (f_tilde, direct, indirect, b, a, big_b) in [
        (1.0 / PI, 0.5, 0.1, 0.03, 0.2, 1.0),
        (25.0, 3.0, 0.0, 4.0, 7.0, 5.0),
        (0.02, 0.0, 9.0, 1.0, 0.5, 5.5),
    ] {
        let pair = lit(f_tilde, direct, indirect, b);
        let pixel = PixelTerms { a, b: big_b };
        let w = OPTIMAL.weight(&budget, &pair, Some(&pixel));
        let partial = w1_partial(&budget, f_tilde, direct + indirect, b);
        let preprint = partial * (1.0 + c * a / (1.0 - c * big_b) / f_tilde);
        assert!(c * big_b < 1.0 - CB_EPSILON);
        assert_close(w.w1, preprint);
    }
}

#[test]
fn unlit_x1_gives_full_partial_weight() {
    // L = 0 takes b/L = 0 even for an inconsistent b > 0: W₁ = 1.
    assert_eq!(w1_partial(&SIMPLE, 0.5, 0.0, 0.0), 1.0);
    assert_eq!(w1_partial(&SIMPLE, 0.5, 0.0, 3.0), 1.0);
    assert_eq!(
        Heuristic::Algebraic
            .weight(&SIMPLE, &lit(0.5, 0.0, 0.0, 0.0), None)
            .w1,
        1.0
    );
    // Eq. 8 with D = N_B f̃: w₁ = 1 + c·G̃/f̃ = 1 + ¼·2/½ = 2, outside [0, 1].
    let pixel = PixelTerms { a: 1.0, b: 2.0 };
    let w = OPTIMAL.weight(&SIMPLE, &lit(0.5, 0.0, 0.0, 0.0), Some(&pixel));
    assert_close(w.w1, 2.0);
    assert!(w.outside_unit);
}

#[test]
fn zero_f_tilde_gives_zero_partial_weight() {
    assert_eq!(w1_partial(&SIMPLE, 0.0, 4.0, 8.0), 0.0);
    let pair = lit(0.0, 1.0, 3.0, 8.0);
    assert_eq!(Heuristic::Algebraic.weight(&SIMPLE, &pair, None).w1, 0.0);
    assert_eq!(
        Heuristic::AlgebraicDirect.weight(&SIMPLE, &pair, None).w1,
        0.0
    );
    // Eq. 8 keeps its correlation term: w₁ = N_B·c·G̃/D = 2·¼·2/6 = ⅙.
    let pixel = PixelTerms { a: 1.0, b: 2.0 };
    assert_close(OPTIMAL.weight(&SIMPLE, &pair, Some(&pixel)).w1, 1.0 / 6.0);
}

#[test]
fn zero_f_tilde_and_unlit_x1_gives_zero_weight() {
    // D = 0: no division, w₁ = 0 by the documented choice.
    assert_eq!(w1_partial(&SIMPLE, 0.0, 0.0, 0.0), 0.0);
    let pair = lit(0.0, 0.0, 0.0, 0.0);
    assert_eq!(Heuristic::Algebraic.weight(&SIMPLE, &pair, None).w1, 0.0);
    let pixel = PixelTerms { a: 1.0, b: 2.0 };
    let w = OPTIMAL.weight(&SIMPLE, &pair, Some(&pixel));
    assert_eq!(w.w1, 0.0);
    assert!(!w.outside_unit);
}

#[test]
fn cb_near_one_is_clamped() {
    let pair = lit(0.5, 1.0, 3.0, 8.0);
    // c = ¼: B = 4 gives c·B = 1, B = 40 gives c·B = 10; both clamp to 1 − ε.
    for big_b in [4.0, 40.0, 4.0 * (1.0 - 0.5 * CB_EPSILON)] {
        let pixel = PixelTerms { a: 1.0, b: big_b };
        let w = OPTIMAL.weight(&SIMPLE, &pair, Some(&pixel));
        assert!(w.clamped_cb, "B = {big_b}");
        // G̃ = A/ε; w₁ = 2·(½ + ¼·A/ε)/7.
        assert_close(w.w1, 2.0 * (0.5 + 0.25 / CB_EPSILON) / 7.0);
        assert!(w.w1.is_finite() && w.outside_unit);
    }
    // Just inside the convex range: no clamp.
    let pixel = PixelTerms {
        a: 1.0,
        b: 4.0 * (1.0 - 2.0 * CB_EPSILON),
    };
    assert!(!OPTIMAL.weight(&SIMPLE, &pair, Some(&pixel)).clamped_cb);
}

#[test]
fn optional_clamp_keeps_the_report() {
    let pair = lit(0.5, 0.0, 0.0, 0.0);
    let pixel = PixelTerms { a: 1.0, b: 2.0 };
    let clamped = Heuristic::Optimal {
        clamp_weights: true,
    }
    .weight(&SIMPLE, &pair, Some(&pixel));
    assert_eq!(clamped.w1, 1.0);
    assert_eq!(clamped.w0(), 0.0);
    assert!(clamped.outside_unit);
}

#[test]
fn pure_strategies_and_threshold() {
    let mut pair = lit(0.5, 1.0, 3.0, 8.0);
    assert_eq!(Heuristic::Bdd0.weight(&SIMPLE, &pair, None).w1, 0.0);
    assert_eq!(Heuristic::Bdd1.weight(&SIMPLE, &pair, None).w1, 1.0);
    let threshold = Heuristic::Threshold { radius: 0.2 };
    for (distance, expected) in [(0.0, 0.0), (0.199, 0.0), (0.2, 1.0), (3.0, 1.0)] {
        pair.x1.light_distance = distance;
        assert_eq!(
            threshold.weight(&SIMPLE, &pair, None).w1,
            expected,
            "d = {distance}"
        );
    }
}

fn densities(path: PathKind, camera: f64, light: f64, emission: f64) -> Pair {
    Pair {
        path: PathInputs {
            kind: path,
            camera_density: camera,
            light_density: light,
            emission_density: emission,
            ..Default::default()
        },
        ..Pair::default()
    }
}

#[test]
fn balance_and_power_match_hand_values() {
    // Merge: p_C = 3, p_L = 1.
    let merge = densities(PathKind::Merge, 3.0, 1.0, 123.0);
    assert_close(Heuristic::Balance.weight(&SIMPLE, &merge, None).w1, 0.75);
    assert_close(Heuristic::Power.weight(&SIMPLE, &merge, None).w1, 0.9);
    // One bounce: S·N_F = 1, S·N_F·p_L(light→x₁)·p_L(x₁→x₀) = 2·1.5 = 3, p_C = 1.
    let one_bounce = densities(PathKind::OneBounce, 1.0, 1.5, 2.0);
    assert_close(
        Heuristic::Balance.weight(&SIMPLE, &one_bounce, None).w1,
        0.25,
    );
    assert_close(Heuristic::Power.weight(&SIMPLE, &one_bounce, None).w1, 0.1);
    // η = S·N_F enters only the one-bounce case.
    let budget = Budget {
        merge_area: 0.05,
        ..SIMPLE
    };
    assert_close(Heuristic::Balance.weight(&budget, &merge, None).w1, 0.75);
    assert_close(
        Heuristic::Balance.weight(&budget, &one_bounce, None).w1,
        1.0 / 1.3,
    );
}

/// Light tracing in BDD=0's place: the balance family divides BDD=0's density by the ratio,
/// the model-based modes read the ratio where they read N_B, the fixed modes ignore it, and a
/// ratio of 0 (x₀ the camera cannot sample) leaves the path to light tracing.
#[test]
fn light_traced_weights_match_hand_values() {
    // p_C = 3, p_L = 1: `balance` 3/(3 + 1/2) = 6/7 and `power` 9/(9 + 1/4) = 36/37 at ratio 2.
    let merge = densities(PathKind::Merge, 3.0, 1.0, 123.0);
    let weigher = |h| Weigher::new(h, &SIMPLE, None);
    assert_close(
        weigher(Heuristic::Balance)
            .weight_light_traced(&merge, 2.0)
            .w1,
        6.0 / 7.0,
    );
    assert_close(
        weigher(Heuristic::Power)
            .weight_light_traced(&merge, 2.0)
            .w1,
        36.0 / 37.0,
    );
    // Ratio 1: a merge and a connection are equally likely, so nothing changes.
    assert_close(
        weigher(Heuristic::Balance)
            .weight_light_traced(&merge, 1.0)
            .w1,
        0.75,
    );
    // `optimal` with f̃ = ½, L = 4, b/L = 2, κ = 4, A = 1, B = 0 at ratio 4: N f̃ = 2,
    // D = 2 + 2 + 4 = 8, N·c·G̃ = S·(N_F − 1)/Φ·A = ½, w₁ = (2 + ½)/8 = 5/16, the merge's
    // weight with N_B = 4.
    let pair = lit(0.5, 1.0, 3.0, 8.0);
    let pixel = PixelTerms { a: 1.0, b: 0.0 };
    let traced = Weigher::new(OPTIMAL, &SIMPLE, Some(&pixel)).weight_light_traced(&pair, 4.0);
    assert_close(traced.w1, 5.0 / 16.0);
    let four = Budget {
        camera_samples: 4.0,
        ..SIMPLE
    };
    assert_close(OPTIMAL.weight(&four, &pair, Some(&pixel)).w1, 5.0 / 16.0);
    for h in [Heuristic::Balance, OPTIMAL] {
        assert_eq!(weigher(h).weight_light_traced(&pair, 0.0).w1, 0.0);
        assert_eq!(weigher(h).weight_light_traced(&pair, f64::NAN).w1, 0.0);
    }
    for h in [
        Heuristic::Bdd0,
        Heuristic::Bdd1,
        Heuristic::Threshold { radius: 0.2 },
    ] {
        let w = weigher(h);
        assert_eq!(w.weight_light_traced(&pair, 2.0), w.weight(&pair));
    }
}

#[test]
fn balance_for_lambert_merge_is_one_over_one_plus_q() {
    // Lambert x₀ and x₁ at distance d with cosines cos₀, cos₁; photon survival q at x₁.
    let (d, cos0, cos1) = (1.3_f64, 0.8, 0.35);
    for q in [1.0, 0.5, 0.25] {
        let p_c = cos0 / PI * cos1 / (d * d);
        let p_l = q * cos1 / PI * cos0 / (d * d);
        let pair = densities(PathKind::Merge, p_c, p_l, 0.0);
        assert_close(
            Heuristic::Balance.weight(&SIMPLE, &pair, None).w1,
            1.0 / (1.0 + q),
        );
        assert_close(
            Heuristic::Power.weight(&SIMPLE, &pair, None).w1,
            1.0 / (1.0 + q * q),
        );
    }
}

#[test]
fn density_guards() {
    for heuristic in [Heuristic::Balance, Heuristic::Power] {
        let w = |camera, light| {
            let pair = densities(PathKind::Merge, camera, light, 0.0);
            heuristic.weight(&SIMPLE, &pair, None).w1
        };
        assert_eq!(w(0.0, 0.0), 0.5);
        assert_eq!(w(f64::INFINITY, f64::INFINITY), 0.5);
        assert_eq!(w(0.0, 2.0), 0.0);
        assert_eq!(w(2.0, 0.0), 1.0);
        assert_eq!(w(f64::INFINITY, 2.0), 1.0);
        assert_eq!(w(2.0, f64::INFINITY), 0.0);
        assert_eq!(w(f64::NAN, 2.0), 0.0);
        assert_eq!(w(1e-300, 1e300), 0.0);
        // One bounce with 0·∞ among the light factors: the light term is 0.
        let pair = densities(PathKind::OneBounce, 1.0, 0.0, f64::INFINITY);
        assert_eq!(heuristic.weight(&SIMPLE, &pair, None).w1, 1.0);
    }
}

/// A merge pair for `camis`: A = 2 m², p_C(x₀) = 1 m⁻² (so the primary factor is 1).
fn camis_merge(camera: f64, light: f64, suffix: f64) -> Pair {
    {
        let mut pair = densities(PathKind::Merge, camera, light, 0.0);
        pair.x0.acceptance_area = 2.0;
        pair.x0.primary_density = 1.0;
        pair.path.light_suffix = suffix;
        pair
    }
}

#[test]
fn acceptance_area_and_probability_match_hand_values() {
    // A = π (d tan 1°)²; d = 1/tan 1° gives a disk of radius 1 m.
    assert_close(acceptance_area(1.0 / ACCEPTANCE_ANGLE_TAN), PI);
    assert_close(
        acceptance_area(10.0),
        PI * (10.0 * 1f64.to_radians().tan()).powi(2),
    );
    assert_close(acceptance_probability(0.25, 2.0), 0.5);
    assert_eq!(acceptance_probability(3.0, 2.0), 1.0);
    assert_eq!(acceptance_probability(0.0, f64::INFINITY), 0.0);
    assert_eq!(acceptance_probability(f64::NAN, 1.0), 0.0);
    assert_eq!(acceptance_probability(-1.0, 1.0), 0.0);
    assert_eq!(acceptance_area(f64::NAN), 0.0);
    assert_eq!(acceptance_area(-3.0), 0.0);
}

#[test]
fn correlation_factor_matches_hand_values() {
    // r = a/(a + β − aβ): a = ½, β = ½ → ½/(¾) = ⅔; a = 0.1, β = 0.3 → 0.1/0.37.
    assert_close(correlation_factor(0.5, 0.5), 2.0 / 3.0);
    assert_close(correlation_factor(0.1, 0.3), 0.1 / 0.37);
    // No correlation information, or a certain camera prefix: factor 1 exactly.
    assert_eq!(correlation_factor(0.0, 0.0), 1.0);
    assert_eq!(correlation_factor(0.3, 0.0), 1.0);
    assert_eq!(correlation_factor(1.0, 0.7), 1.0);
    // A certain light subpath: r = a.
    assert_close(correlation_factor(0.2, 1.0), 0.2);
    assert_eq!(correlation_factor(0.0, 0.5), 0.0);
    // Out-of-range inputs are clamped into [0, 1].
    assert_eq!(correlation_factor(f64::NAN, 0.5), 0.0);
    assert_eq!(correlation_factor(f64::INFINITY, 0.5), 1.0);
    assert_close(correlation_factor(0.5, f64::INFINITY), 0.5);
}

#[test]
fn camis_matches_hand_values() {
    // p_C = ¼, p_L = ⅛, A = 2: a = min(1·2, 1)·min(¼·2, 1) = ½; β = ½ → r = ⅔;
    // w₁ = (⅔·¼)/(⅔·¼ + ⅛) = (1/6)/(7/24) = 4/7.
    let w = Heuristic::Camis.weight(&SIMPLE, &camis_merge(0.25, 0.125, 0.5), None);
    assert_close(w.w1, 4.0 / 7.0);
    assert_eq!(w.w0() + w.w1, 1.0);
    assert!(!w.outside_unit && !w.clamped_cb);
    // A pixel footprint larger than A (p_C(x₀)·A = ½) halves a: a = ¼, β = ½ → r = 0.4;
    // w₁ = 0.1/(0.1 + ⅛) = 4/9.
    let pair = {
        let mut pair = camis_merge(0.25, 0.125, 0.5);
        pair.x0.primary_density = 0.25;
        pair
    };
    assert_close(Heuristic::Camis.weight(&SIMPLE, &pair, None).w1, 4.0 / 9.0);
    // The factor only ever moves weight to BDD=0.
    let balance = Heuristic::Balance.weight(&SIMPLE, &pair, None).w1;
    assert_close(balance, 2.0 / 3.0);
}

#[test]
fn camis_with_factor_one_is_balance() {
    for (camera, light) in [
        (0.25, 0.125),
        (3.0, 1e-9),
        (0.0, 2.0),
        (0.0, 0.0),
        (1e300, 1e-300),
    ] {
        let balance = Heuristic::Balance
            .weight(
                &SIMPLE,
                &densities(PathKind::Merge, camera, light, 0.0),
                None,
            )
            .w1;
        // β = 0 (light subpath never concentrated), or A = 0 (no surrogate at all).
        for pair in [camis_merge(camera, light, 0.0), {
            let mut pair = camis_merge(camera, light, 0.7);
            pair.x0.acceptance_area = 0.0;
            pair
        }] {
            assert_eq!(Heuristic::Camis.weight(&SIMPLE, &pair, None).w1, balance);
        }
    }
    // One-bounce paths: BDD=1 is a connection, so camis is balance whatever β says.
    let one_bounce = {
        let mut pair = densities(PathKind::OneBounce, 0.25, 0.5, 0.3);
        pair.x0.acceptance_area = 2.0;
        pair.x0.primary_density = 1.0;
        pair.path.light_suffix = 1.0;
        pair
    };
    assert_eq!(
        Heuristic::Camis.weight(&SIMPLE, &one_bounce, None).w1,
        Heuristic::Balance.weight(&SIMPLE, &one_bounce, None).w1
    );
}

#[test]
fn camis_guards() {
    let camis = |pair: &Pair| Heuristic::Camis.weight(&SIMPLE, pair, None).w1;
    // Infinite densities: the factor is still in [0, 1] and the weight finite.
    assert_eq!(camis(&camis_merge(f64::INFINITY, f64::INFINITY, 0.0)), 0.5);
    assert_eq!(camis(&camis_merge(f64::INFINITY, 1.0, 0.5)), 1.0);
    assert_eq!(camis(&camis_merge(1.0, f64::INFINITY, 0.5)), 0.0);
    // Zero densities: the both-zero convention of balance.
    assert_eq!(camis(&camis_merge(0.0, 0.0, 0.5)), 0.5);
    assert_eq!(camis(&camis_merge(0.0, 1.0, 0.5)), 0.0);
    // A camera prefix that never lands (p_C(x₀) = 0) against a light subpath that does: r = 0.
    let unseen = {
        let mut pair = camis_merge(0.25, 0.125, 0.5);
        pair.x0.primary_density = 0.0;
        pair
    };
    assert_eq!(camis(&unseen), 0.0);
    // NaN and negative inputs count as 0; infinite A and β saturate the probabilities at 1.
    for x in [f64::NAN, -1.0, 0.0, f64::INFINITY] {
        for pair in [
            camis_merge(x, 0.125, 0.5),
            camis_merge(0.25, x, 0.5),
            camis_merge(0.25, 0.125, x),
            {
                let mut pair = camis_merge(0.25, 0.125, 0.5);
                pair.x0.acceptance_area = x;
                pair
            },
            {
                let mut pair = camis_merge(0.25, 0.125, 0.5);
                pair.x0.primary_density = x;
                pair
            },
        ] {
            let w = camis(&pair);
            assert!((0.0..=1.0).contains(&w), "{w} for {pair:?}");
        }
    }
}

#[test]
fn names_round_trip() {
    let all = [
        Heuristic::Bdd0,
        Heuristic::Bdd1,
        Heuristic::Threshold {
            radius: DEFAULT_THRESHOLD_RADIUS,
        },
        Heuristic::AlgebraicDirect,
        Heuristic::Algebraic,
        Heuristic::Optimal {
            clamp_weights: false,
        },
        SPLIT,
        PATH,
        Heuristic::Balance,
        Heuristic::Power,
        Heuristic::Camis,
        Heuristic::CorrectedBalance,
    ];
    let names: Vec<_> = all.iter().map(Heuristic::name).collect();
    assert_eq!(names, Heuristic::ALL_NAMES);
    for (name, heuristic) in Heuristic::ALL_NAMES.iter().zip(all) {
        assert_eq!(Heuristic::parse(name), Some(heuristic));
        assert_eq!(name.parse::<Heuristic>(), Ok(heuristic));
        assert_eq!(heuristic.to_string(), *name);
        let kind = heuristic.kind();
        assert_eq!((kind.name(), kind.heuristic()), (*name, heuristic));
        assert_eq!(HeuristicKind::parse(name), Some(kind));
    }
    // The kind leaves the parameters out.
    assert_eq!(
        Heuristic::Threshold { radius: 0.5 }.kind(),
        HeuristicKind::Threshold
    );
    assert_eq!(HeuristicKind::parse("Optimal"), None);
    assert_eq!(Heuristic::parse("Optimal"), None);
    let err = "Optimal".parse::<Heuristic>().unwrap_err();
    assert_eq!(
        err.to_string(),
        format!(
            "unknown mode 'Optimal'; expected one of {}",
            Heuristic::ALL_NAMES.join(", ")
        )
    );
    assert!(err.to_string().contains("optimal-split"), "{err}");
    assert_eq!(Heuristic::parse(""), None);
    assert_eq!(
        Heuristic::Threshold { radius: 0.5 }.to_string(),
        "threshold (R = 0.5 m)"
    );
}

#[test]
fn needs_follow_method_table() {
    let needs = |name| Heuristic::parse(name).unwrap().needs();
    let mix = Needs {
        photons_at_x0: true,
        second_vertex: true,
        weighs: true,
        ..Needs::default()
    };
    assert_eq!(
        needs("bdd0"),
        Needs {
            photons_at_x0: true,
            ..Needs::default()
        }
    );
    assert_eq!(
        needs("bdd1"),
        Needs {
            second_vertex: true,
            ..Needs::default()
        }
    );
    assert_eq!(
        needs("threshold"),
        Needs {
            light_distance: true,
            ..mix
        }
    );
    let direct = Needs {
        direct_at_x1: true,
        effective_samples: true,
        ..mix
    };
    assert_eq!(needs("algebraic-direct"), direct);
    let cached = Needs {
        radiance_cache: true,
        ..direct
    };
    assert_eq!(needs("algebraic"), cached);
    assert_eq!(
        needs("optimal"),
        Needs {
            cache_b: true,
            pixel_table: true,
            ..cached
        }
    );
    let density = Needs {
        densities: true,
        ..mix
    };
    assert_eq!(needs("balance"), density);
    assert_eq!(needs("power"), density);
    assert_eq!(
        needs("camis"),
        Needs {
            primary_terms: true,
            light_suffix: true,
            ..density
        }
    );
    // Only the pure strategies do not weigh, and their w₁ is fixed.
    for name in Heuristic::ALL_NAMES {
        let h = Heuristic::parse(name).unwrap();
        assert_eq!(h.needs().weighs, h.fixed_w1().is_none(), "{name}");
    }
    assert_eq!(Heuristic::Bdd0.fixed_w1(), Some(0.0));
    assert_eq!(Heuristic::Bdd1.fixed_w1(), Some(1.0));
    assert_eq!(
        needs("corrected-balance"),
        Needs {
            balance_correction: true,
            ..density
        }
    );
}

#[test]
fn extreme_inputs_stay_finite() {
    let budgets = [
        Budget {
            camera_samples: 1.0,
            photons: 1.0,
            merge_area: 1e-14,
            flux: 1e-10,
        },
        Budget {
            camera_samples: 1e9,
            photons: 1e9,
            merge_area: 1e2,
            flux: 1e-10,
        },
        Budget {
            camera_samples: 1.0,
            photons: 1e300,
            merge_area: 1e300,
            flux: 1e-300,
        },
    ];
    let pixel = PixelTerms {
        a: 1e300,
        b: 1e-300,
    };
    for budget in &budgets {
        for f_tilde in [0.0, 1e-300, 1.0, 1e300] {
            for radiance in [0.0, 1e-300, 1.0, 1e300] {
                for b in [0.0, 1e300] {
                    let pair = lit(f_tilde, radiance, radiance, b);
                    for name in Heuristic::ALL_NAMES {
                        let w = Heuristic::parse(name)
                            .unwrap()
                            .weight(budget, &pair, Some(&pixel));
                        assert!(
                            w.w1.is_finite() && w.w0().is_finite(),
                            "{name} {budget:?} {pair:?}"
                        );
                    }
                    assert!(w1_partial(budget, f_tilde, radiance, b).is_finite());
                }
            }
        }
    }
}

const SPLIT: Heuristic = Heuristic::OptimalSplit {
    clamp_weights: false,
};
const PATH: Heuristic = Heuristic::OptimalPath {
    clamp_weights: false,
};

fn kind(pair: Pair, path: PathKind) -> Pair {
    {
        let mut pair = pair;
        pair.path.kind = path;
        pair
    }
}

#[test]
fn split_weights_reduce_to_eq8_for_a_single_kind_of_light() {
    let pixel = PixelTerms { a: 0.3, b: 0.7 };
    // Only secondary light at x₁: the merge weight is eq. 8.
    let indirect_only = lit(0.4, 0.0, 1.5, 0.6);
    let eq8 = OPTIMAL.weight(&SIMPLE, &indirect_only, Some(&pixel)).w1;
    let split = SPLIT
        .weight(&SIMPLE, &kind(indirect_only, PathKind::Merge), Some(&pixel))
        .w1;
    assert!((split - eq8).abs() < 1e-14, "{split} vs {eq8}");
    // Only direct light at x₁ (b = 0): the one-bounce weight is eq. 8.
    let direct_only = lit(0.4, 2.0, 0.0, 0.0);
    let eq8 = OPTIMAL.weight(&SIMPLE, &direct_only, Some(&pixel)).w1;
    let split = SPLIT
        .weight(
            &SIMPLE,
            &kind(direct_only, PathKind::OneBounce),
            Some(&pixel),
        )
        .w1;
    assert!((split - eq8).abs() < 1e-14, "{split} vs {eq8}");
}

#[test]
fn split_weights_match_hand_values() {
    // N_B = 2, κ(L) = L, c = ¼ (SIMPLE); f̃ = 0.5, L₀ = 1, L_d = 2, b = 1 (β = ½), no pixel terms.
    // N_B f̃ = 1, D″ = (1 + ½)(1 + 1) + 2·1 = 5: w^d = 1·1/5, w⁰ = 1·1.5/5.
    let pair = lit(0.5, 1.0, 2.0, 1.0);
    assert_close(
        SPLIT.weight(&SIMPLE, &kind(pair, PathKind::Merge), None).w1,
        0.2,
    );
    assert_close(
        SPLIT
            .weight(&SIMPLE, &kind(pair, PathKind::OneBounce), None)
            .w1,
        0.3,
    );
    // optimal-path with the photon's own f₁ = 2 instead of β: 1·1.5·(1/(1 + 2))/5 = 0.1.
    let photon = {
        let mut pair = kind(pair, PathKind::Merge);
        pair.path.x1_scattering = 2.0;
        pair
    };
    assert_close(PATH.weight(&SIMPLE, &photon, None).w1, 0.1);
    // With f₁ = β it is the split weight, and one-bounce paths ignore f₁.
    let at_beta = {
        let mut pair = photon;
        pair.path.x1_scattering = 0.5;
        pair
    };
    assert_close(PATH.weight(&SIMPLE, &at_beta, None).w1, 0.2);
    let one = {
        let mut pair = photon;
        pair.path.kind = PathKind::OneBounce;
        pair
    };
    assert_close(PATH.weight(&SIMPLE, &one, None).w1, 0.3);
}

/// The split weights make the §12 noise functional stationary: for a discretised pixel (a few
/// directions v with probabilities π, exact BDF sampling so that cos/p = 1/f̃) whose x₁ scatter
/// with a fixed β (Lambert), the gradient of
/// F = α N E[f̃((1−w⁰)²L₀ + (1−w^d)²L_d)] + E[m²] − (1 − 1/N_F)E[m]² + α E[(w^d)² β L_d],
/// m = w⁰L₀ + w^d L_d, vanishes at the weights the crate returns (with A, B from
/// [`split_weighted_radiance`] as the renderer accumulates them).
#[test]
fn split_weights_are_stationary_points_of_the_noise_functional() {
    let budget = Budget {
        camera_samples: 3.0,
        photons: 50.0,
        merge_area: 0.02,
        flux: 1.0,
    };
    let alpha = budget.flux / (budget.photons * budget.merge_area);
    let n = budget.camera_samples;
    // (π, f̃, L₀, L_d, β)
    let dirs = [
        (0.2, 0.3, 0.0, 0.8, 0.15),
        (0.3, 0.3, 2.5, 0.4, 0.15),
        (0.1, 1.2, 0.7, 1.9, 0.4),
        (0.4, 0.05, 6.0, 0.0, 0.1),
    ];
    let (mut a, mut b) = (0.0, 0.0);
    for &(p, f, l0, ld, beta) in &dirs {
        let wl = split_weighted_radiance(&budget, f, l0, ld, beta * ld);
        a += p * wl;
        b += p * wl / f;
    }
    let pixel = PixelTerms { a, b };
    let weights: Vec<(f64, f64)> = dirs
        .iter()
        .map(|&(_, f, l0, ld, beta)| {
            let pair = lit(f, l0, ld, beta * ld);
            let w0 = SPLIT.weight(&budget, &kind(pair, PathKind::OneBounce), Some(&pixel));
            let wd = SPLIT.weight(&budget, &kind(pair, PathKind::Merge), Some(&pixel));
            (w0.w1, wd.w1)
        })
        .collect();
    let mean_m: f64 = dirs
        .iter()
        .zip(&weights)
        .map(|(&(p, _, l0, ld, _), &(w0, wd))| p * (w0 * l0 + wd * ld))
        .sum();
    let corr = 1.0 - 1.0 / budget.photons;
    for (&(p, f, l0, ld, beta), &(w0, wd)) in dirs.iter().zip(&weights) {
        let m = w0 * l0 + wd * ld;
        let d_w0 =
            p * (-2.0 * alpha * n * f * (1.0 - w0) * l0 + 2.0 * m * l0 - 2.0 * corr * mean_m * l0);
        let d_wd = p
            * (-2.0 * alpha * n * f * (1.0 - wd) * ld + 2.0 * m * ld - 2.0 * corr * mean_m * ld
                + 2.0 * alpha * beta * wd * ld);
        // The terms are O(1); a wrong formula leaves O(0.1) or more.
        assert!(
            d_w0.abs() < 1e-12 && d_wd.abs() < 1e-12,
            "{d_w0} {d_wd} at f̃ = {f}"
        );
    }
}

#[test]
fn split_and_path_weights_guard_degenerate_inputs() {
    for h in [SPLIT, PATH] {
        for path in [PathKind::Merge, PathKind::OneBounce] {
            // Nothing at all: 0, not NaN.
            let w = h.weight(&SIMPLE, &kind(Pair::default(), path), None);
            assert_eq!(w.w1, 0.0);
            // f̃ = 0 with light at x₁.
            let w = h.weight(&SIMPLE, &kind(lit(0.0, 1.0, 1.0, 0.5), path), None);
            assert!(w.w1.is_finite() && w.w1 >= 0.0, "{h}: {w:?}");
            // Huge and NaN inputs.
            let w = h.weight(
                &SIMPLE,
                &{
                    let mut pair = kind(lit(1e300, 1e300, 1e300, f64::NAN), path);
                    pair.path.x1_scattering = f64::NAN;
                    pair
                },
                Some(&PixelTerms { a: 1e300, b: 1e300 }),
            );
            assert!(w.w1.is_finite(), "{h}: {w:?}");
        }
    }
    assert_eq!(split_weighted_radiance(&SIMPLE, 0.0, 0.0, 0.0, 0.0), 0.0);
}

/// `corrected-balance` is c·p_C/(c·p_C + p_L) for both path kinds, `balance` bit for bit at
/// c = 1 and without a factor, and its pilot's formula in w₁ alone agrees with it.
#[test]
fn corrected_balance_scales_the_camera_density() {
    let corrected = |pair: &Pair, c: f64| {
        Weigher::new(Heuristic::CorrectedBalance, &SIMPLE, None)
            .with_correction(c)
            .weight(pair)
            .w1
    };
    // Merge: p_C = 3, p_L = 1 (balance ¾); one bounce: p_C = 1 against S·N_F·2·1.5 = 3 (¼).
    let merge = densities(PathKind::Merge, 3.0, 1.0, 123.0);
    let one_bounce = densities(PathKind::OneBounce, 1.0, 1.5, 2.0);
    assert_close(corrected(&merge, 0.25), 0.75 / 1.75);
    assert_close(corrected(&merge, 4.0), 12.0 / 13.0);
    assert_close(corrected(&one_bounce, 0.5), 0.5 / 3.5);
    assert_close(corrected(&one_bounce, 9.0), 0.75);
    for pair in [merge, one_bounce, densities(PathKind::Merge, 0.0, 0.0, 0.0)] {
        let balance = Heuristic::Balance.weight(&SIMPLE, &pair, None).w1;
        assert_eq!(corrected(&pair, 1.0), balance);
        assert_eq!(
            Heuristic::CorrectedBalance.weight(&SIMPLE, &pair, None).w1,
            balance
        );
        for c in [1e-3, 0.3, 2.0, 50.0] {
            assert_eq!(corrected(&pair, c), corrected_share(balance, c));
        }
    }
}

#[test]
fn corrected_share_guards() {
    assert_eq!(corrected_share(0.4, 1.0), 0.4);
    // c = 0 switches BDD=1 off, c = ∞ switches it on wherever balance gives it anything.
    for w in [0.0, 0.3, 1.0] {
        assert_eq!(corrected_share(w, 0.0), 0.0);
        assert_eq!(corrected_share(w, -2.0), 0.0);
        assert_eq!(corrected_share(w, f64::NAN), 0.0);
    }
    assert_eq!(corrected_share(0.3, f64::INFINITY), 1.0);
    assert_eq!(corrected_share(0.0, f64::INFINITY), 0.0);
    assert_eq!(corrected_share(1.0, 0.5), 1.0);
    assert_eq!(corrected_share(f64::NAN, 2.0), 0.0);
    assert_eq!(corrected_share(1.5, 2.0), 1.0);
    // Monotone in c and in w₁ after rounding.
    let cs = [0.0, 1e-12, 1e-3, 0.25, 1.0, 4.0, 1e3, 1e12, f64::INFINITY];
    let ws = [0.0, 1e-300, 1e-9, 0.2, 0.5, 0.8, 1.0 - 1e-12, 1.0];
    for &w in &ws {
        for pair in cs.windows(2) {
            assert!(corrected_share(w, pair[0]) <= corrected_share(w, pair[1]));
        }
    }
    for &c in &cs {
        for pair in ws.windows(2) {
            assert!(corrected_share(pair[0], c) <= corrected_share(pair[1], c));
        }
    }
}
