//! Property tests over wide input ranges: every weight is finite, w₀ + w₁ = 1, the
//! bounded modes stay in [0, 1], and eq. 10 is monotone in the radiance at x₁.

use bdpm_mis::{
    Budget, Heuristic, Pair, PathInputs, PathKind, PixelTerms, X0Inputs, X1Inputs, w1_partial,
};
use proptest::prelude::*;

/// 10ˣ for x uniform in [lo, hi]: log-uniform over many decades.
fn decades(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo..=hi).prop_map(|x| 10f64.powf(x))
}

/// Zero or log-uniform in [10^lo, 10^hi].
fn zero_or(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    prop_oneof![1 => Just(0.0), 4 => decades(lo, hi)]
}

fn budget() -> impl Strategy<Value = Budget> {
    (
        decades(0.0, 9.0),
        decades(0.0, 9.0),
        decades(-14.0, 2.0),
        decades(-10.0, 10.0),
    )
        .prop_map(|(camera_samples, photons, merge_area, flux)| Budget {
            camera_samples,
            photons,
            merge_area,
            flux,
        })
}

fn density() -> impl Strategy<Value = f64> {
    prop_oneof![8 => zero_or(-30.0, 30.0), 1 => Just(f64::INFINITY)]
}

fn pair() -> impl Strategy<Value = Pair> {
    (
        (
            zero_or(-12.0, 4.0),
            zero_or(-30.0, 30.0),
            zero_or(-30.0, 30.0),
            zero_or(-30.0, 30.0),
            0.0..10.0f64,
        ),
        (
            prop_oneof![Just(PathKind::Merge), Just(PathKind::OneBounce)],
            density(),
            density(),
            density(),
            zero_or(-30.0, 30.0),
        ),
        (
            density(),
            density(),
            prop_oneof![zero_or(-30.0, 0.0), Just(1.0)],
        ),
    )
        .prop_map(
            |(
                (f_tilde, direct, indirect, b, light_distance),
                (path, camera, light, emission, x1_scattering),
                (acceptance_area, primary_density, light_suffix),
            )| {
                Pair {
                    x0: X0Inputs {
                        f_tilde,
                        acceptance_area,
                        primary_density,
                    },
                    x1: X1Inputs {
                        direct,
                        indirect,
                        b,
                        light_distance,
                    },
                    path: PathInputs {
                        kind: path,
                        camera_density: camera,
                        light_density: light,
                        emission_density: emission,
                        x1_scattering,
                        light_suffix,
                    },
                }
            },
        )
}

fn pixel() -> impl Strategy<Value = Option<PixelTerms>> {
    prop_oneof![
        1 => Just(None),
        4 => (zero_or(-30.0, 30.0), zero_or(-30.0, 30.0)).prop_map(|(a, b)| Some(PixelTerms { a, b })),
    ]
}

const BOUNDED: [Heuristic; 8] = [
    Heuristic::Bdd0,
    Heuristic::Bdd1,
    Heuristic::Threshold { radius: 0.2 },
    Heuristic::AlgebraicDirect,
    Heuristic::Algebraic,
    Heuristic::Balance,
    Heuristic::Power,
    Heuristic::Camis,
];

proptest! {
    #[test]
    fn bounded_modes_stay_in_unit_interval(budget in budget(), pair in pair(), pixel in pixel()) {
        for heuristic in BOUNDED {
            let w = heuristic.weight(&budget, &pair, pixel.as_ref());
            prop_assert!((0.0..=1.0).contains(&w.w1), "{heuristic}: {w:?}");
            prop_assert_eq!(w.w0() + w.w1, 1.0);
            prop_assert!(!w.outside_unit && !w.clamped_cb);
        }
    }

    /// The correlation factor is in [0, 1] and scales BDD=1 only: camis never gives BDD=1
    /// more weight than balance, and is balance on one-bounce paths.
    #[test]
    fn camis_never_exceeds_balance(budget in budget(), pair in pair()) {
        let camis = Heuristic::Camis.weight(&budget, &pair, None).w1;
        let balance = Heuristic::Balance.weight(&budget, &pair, None).w1;
        if pair.path.kind == PathKind::OneBounce {
            prop_assert_eq!(camis, balance);
        } else if pair.path.camera_density > 0.0 || pair.path.light_density > 0.0 {
            prop_assert!(camis <= balance, "{camis} > {balance}");
        }
    }

    #[test]
    fn optimal_is_finite_and_reports_honestly(budget in budget(), pair in pair(), pixel in pixel()) {
        let free = Heuristic::Optimal { clamp_weights: false }.weight(&budget, &pair, pixel.as_ref());
        let clamped = Heuristic::Optimal { clamp_weights: true }.weight(&budget, &pair, pixel.as_ref());
        prop_assert!(free.w1.is_finite() && free.w0().is_finite(), "{free:?}");
        // The correlation term is non-negative: w₁ ≥ W₁ ≥ 0.
        let partial = w1_partial(&budget, pair.x0.f_tilde, pair.x1.direct + pair.x1.indirect, pair.x1.b);
        prop_assert!((0.0..=1.0).contains(&partial));
        prop_assert!(free.w1 >= partial);
        prop_assert_eq!(free.outside_unit, !(0.0..=1.0).contains(&free.w1));
        // w₀ = 1 − w₁ by definition; the float sum is exact up to w₁'s own rounding.
        prop_assert!((free.w0() + free.w1 - 1.0).abs() <= f64::EPSILON * free.w1.max(1.0));
        prop_assert_eq!(clamped.w1, free.w1.clamp(0.0, 1.0));
        prop_assert_eq!(clamped.w0() + clamped.w1, 1.0);
        prop_assert_eq!((clamped.outside_unit, clamped.clamped_cb), (free.outside_unit, free.clamped_cb));
    }

    #[test]
    fn algebraic_is_monotone_in_radiance(
        budget in budget(),
        pair in pair(),
        extra_direct in zero_or(-30.0, 30.0),
        extra_indirect in zero_or(-30.0, 30.0),
    ) {
        let brighter = {
            let mut pair = pair;
            pair.x1.direct += extra_direct;
            pair.x1.indirect += extra_indirect;
            pair
        };
        for heuristic in [Heuristic::AlgebraicDirect, Heuristic::Algebraic] {
            let dim = heuristic.weight(&budget, &pair, None).w1;
            let bright = heuristic.weight(&budget, &brighter, None).w1;
            prop_assert!(bright <= dim, "{heuristic}: {bright} > {dim}");
        }
    }
}
