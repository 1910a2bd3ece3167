//! The Fresnel terms against closed forms and known values: normal and grazing incidence,
//! Brewster's angle, total internal reflection, energy (R + T = 1 from the transmission
//! amplitudes), the conductor against an independent real-arithmetic formula, and the
//! conductor with k = 0 against the dielectric.

use bdpm_bdf::{
    fresnel_conductor, fresnel_conductor_polarised, fresnel_dielectric,
    fresnel_dielectric_polarised,
};
use glam::Vec3;

const ETAS: [f64; 8] = [1.0 / 2.4, 0.5, 1.0 / 1.5, 1.0 / 1.33, 1.33, 1.5, 2.4, 4.0];

/// Incidence cosines from normal to grazing, decreasing, including the ends.
fn cosines() -> impl Iterator<Item = f64> {
    (0..200)
        .map(|i| 1.0 - f64::from(i) / 200.0)
        .chain([1e-3, 1e-5, 0.0])
}

#[test]
fn dielectric_normal_incidence_is_the_closed_form() {
    for eta in ETAS {
        let want = ((eta - 1.0) / (eta + 1.0)).powi(2);
        for cos in [1.0f32, -1.0] {
            let got = f64::from(fresnel_dielectric(cos, eta as f32));
            assert!(
                (got - want).abs() < 1e-6,
                "η = {eta}, cos {cos}: {got} vs {want}"
            );
        }
    }
    // Glass in air: 4 %.
    assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
}

#[test]
fn dielectric_tends_to_one_at_grazing_incidence() {
    for eta in ETAS {
        let f = fresnel_dielectric(1e-6, eta as f32);
        assert!(f > 0.9999 && f <= 1.0, "η = {eta}: F at grazing = {f}");
        // Monotone towards grazing from outside for the usual indices; for η = 4 the
        // unpolarised reflectance dips near Brewster's angle (R_p's zero outweighs R_s).
        if eta > 2.5 {
            continue;
        }
        let mut last = fresnel_dielectric(1.0, eta as f32);
        for c in cosines().skip(1) {
            let f = fresnel_dielectric(c as f32, eta as f32);
            assert!(
                f >= last - 1e-6,
                "η = {eta}: F not monotone at cos {c}: {f} < {last}"
            );
            last = f;
        }
    }
}

#[test]
fn brewster_angle_zeroes_the_p_polarisation() {
    for eta in ETAS.into_iter().filter(|&e| e != 1.0) {
        // From outside tan θ_B = η; from inside (cos < 0) the wave sees 1/η, tan θ_B = 1/η.
        for (sign, ratio) in [(1.0, eta), (-1.0, 1.0 / eta)] {
            let theta_b = ratio.atan();
            let parts = fresnel_dielectric_polarised((sign * theta_b.cos()) as f32, eta as f32);
            assert!(
                parts.p < 1e-10,
                "η = {eta}, side {sign}: R_p(θ_B) = {}",
                parts.p
            );
            assert!(parts.s > 1e-3, "R_s(θ_B) = {} should not vanish", parts.s);
            // And R_p is not zero away from θ_B.
            let off =
                fresnel_dielectric_polarised((sign * (theta_b + 0.1).cos()) as f32, eta as f32);
            assert!(
                off.p > 1e-6,
                "η = {eta}: R_p 0.1 rad off Brewster = {}",
                off.p
            );
        }
    }
}

#[test]
fn total_internal_reflection_beyond_the_critical_angle() {
    for eta in [1.33f64, 1.5, 2.4] {
        // Inside (cos < 0), the wave sees 1/η: critical angle sin θ_c = 1/η.
        let theta_c = (1.0 / eta).asin();
        for dtheta in [1e-4, 0.01, 0.2] {
            let theta = theta_c + dtheta;
            if theta < std::f64::consts::FRAC_PI_2 {
                let f = fresnel_dielectric(-theta.cos() as f32, eta as f32);
                assert_eq!(f, 1.0, "η = {eta}: θ = θ_c + {dtheta}");
            }
            let below = fresnel_dielectric(-(theta_c - dtheta).cos() as f32, eta as f32);
            assert!(below < 1.0, "η = {eta}: θ = θ_c − {dtheta} gives {below}");
        }
        // η < 1 seen from outside is the same situation.
        let f = fresnel_dielectric((theta_c + 0.01).cos() as f32, (1.0 / eta) as f32);
        assert_eq!(f, 1.0);
    }
}

/// R + T = 1 with T from the transmission amplitudes t_s = 2c/(c + ηc_t), t_p = 2c/(ηc + c_t),
/// T = (η c_t / c)·(t_s² + t_p²)/2 per polarisation mean: an independent energy balance.
#[test]
fn reflectance_and_transmittance_sum_to_one() {
    for eta in ETAS {
        for c in cosines().filter(|&c| c > 0.0) {
            let sin2_t = (1.0 - c * c) / (eta * eta);
            let f = f64::from(fresnel_dielectric(c as f32, eta as f32));
            assert!((0.0..=1.0).contains(&f));
            if sin2_t >= 1.0 {
                assert_eq!(f, 1.0);
                continue;
            }
            let ct = (1.0 - sin2_t).sqrt();
            let ts = 2.0 * c / (c + eta * ct);
            let tp = 2.0 * c / (eta * c + ct);
            let t = eta * ct / c * 0.5 * (ts * ts + tp * tp);
            assert!(
                (f + t - 1.0).abs() < 1e-5,
                "η = {eta}, cos {c}: R {f} + T {t}"
            );
        }
    }
}

#[test]
fn dielectric_is_the_same_from_both_sides_of_a_refraction() {
    // Stokes relations: R(θ_i, η) = R(θ_t, 1/η), the conjugate angle from the other side.
    for eta in [1.33f64, 1.5, 2.4] {
        // Not too close to grazing: there the f32 rounding of the conjugate cosine is
        // amplified by dθ/dθ_t → ∞ on the way back.
        for c in cosines().filter(|&c| c > 0.05) {
            let ct = (1.0 - (1.0 - c * c) / (eta * eta)).sqrt();
            let out = fresnel_dielectric(c as f32, eta as f32);
            let inside = fresnel_dielectric(-ct as f32, eta as f32);
            assert!(
                (out - inside).abs() < 5e-5,
                "η = {eta}, cos {c}: {out} vs {inside}"
            );
        }
    }
}

/// pbrt-v3's `FrConductor`: the conductor's reflectance in real arithmetic (a² + b² form),
/// independent of the crate's complex-number evaluation.
fn conductor_reference(c: f64, eta: f64, k: f64) -> f64 {
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let (e2, k2) = (eta * eta, k * k);
    let t0 = e2 - k2 - s2;
    let a2b2 = (t0 * t0 + 4.0 * e2 * k2).sqrt();
    let t1 = a2b2 + c2;
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let t2 = 2.0 * c * a;
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4);
    0.5 * (rs + rp)
}

/// Complex indices at about 650, 550, 450 nm of gold, silver, copper and aluminium, plus
/// made-up extremes.
fn metals() -> Vec<(Vec3, Vec3)> {
    vec![
        (Vec3::new(0.166, 0.434, 1.45), Vec3::new(3.15, 2.45, 1.95)),
        (Vec3::new(0.14, 0.12, 0.13), Vec3::new(4.15, 3.43, 2.52)),
        (Vec3::new(0.21, 0.92, 1.17), Vec3::new(3.67, 2.58, 2.40)),
        (Vec3::new(1.49, 0.96, 0.62), Vec3::new(7.66, 6.69, 5.43)),
        (Vec3::new(0.01, 10.0, 3.0), Vec3::new(0.0, 30.0, 0.01)),
    ]
}

#[test]
fn conductor_matches_the_real_arithmetic_formula() {
    for (eta, k) in metals() {
        for c in cosines() {
            let got = fresnel_conductor(c as f32, eta, k);
            for ch in 0..3 {
                let want = conductor_reference(c, f64::from(eta[ch]), f64::from(k[ch]));
                let g = f64::from(got[ch]);
                assert!(
                    (g - want).abs() < 2e-6,
                    "η = {}, k = {}, cos {c}: {g} vs {want}",
                    eta[ch],
                    k[ch]
                );
                assert!((0.0..=1.0).contains(&g), "F = {g} outside [0, 1]");
            }
        }
    }
}

#[test]
fn conductor_normal_incidence_and_grazing() {
    for (eta, k) in metals() {
        let got = fresnel_conductor(1.0, eta, k);
        let want = ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k);
        assert!((got - want).abs().max_element() < 1e-6, "{got} vs {want}");
        // Opaque: the side does not matter.
        assert_eq!(
            fresnel_conductor(-0.3, eta, k),
            fresnel_conductor(0.3, eta, k)
        );
        let grazing = fresnel_conductor(1e-6, eta, k);
        assert!(grazing.min_element() > 0.999, "grazing {grazing}");
    }
    // Aluminium at 550 nm reflects about 92 % at normal incidence.
    let al = fresnel_conductor(1.0, Vec3::splat(0.96), Vec3::splat(6.69));
    assert!((al.x - 0.9209).abs() < 1e-3, "aluminium {al}");
}

#[test]
fn conductor_with_zero_k_is_the_dielectric() {
    for eta in ETAS {
        for c in cosines() {
            let d = fresnel_dielectric_polarised(c as f32, eta as f32);
            let m = fresnel_conductor_polarised(c as f32, eta as f32, 0.0);
            // Total internal reflection (η < 1) comes out of the complex square root.
            assert!(
                (d.s - m.s).abs() < 1e-6 && (d.p - m.p).abs() < 1e-6,
                "η = {eta}, cos {c}: {d:?} vs {m:?}"
            );
            let f = fresnel_conductor(c as f32, Vec3::splat(eta as f32), Vec3::ZERO);
            assert!((f.x - fresnel_dielectric(c as f32, eta as f32)).abs() < 1e-6);
        }
    }
}

#[test]
fn fresnel_never_leaves_the_unit_interval() {
    // Including out-of-range and non-unit cosines, which are clamped.
    for c in [-2.0f32, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0] {
        for eta in [0.01f32, 0.5, 1.0, 1.5, 100.0] {
            let f = fresnel_dielectric(c, eta);
            assert!((0.0..=1.0).contains(&f), "cos {c}, η {eta}: {f}");
        }
        for (eta, k) in metals() {
            let f = fresnel_conductor(c, eta, k);
            assert!(f.min_element() >= 0.0 && f.max_element() <= 1.0, "{f}");
        }
    }
}
