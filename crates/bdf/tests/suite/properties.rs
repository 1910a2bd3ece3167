//! Physical and API properties of `Bdf`: reciprocity, energy conservation, the lobe's
//! normalisation constant, constructor validation, and finite output at the edges.

use std::f32::consts::{FRAC_1_PI, FRAC_PI_2};

use crate::common::{MirrorFrame, close, direction, gauss_legendre, rng, u3, uniform_hemisphere};
use bdpm_bdf::{Bdf, BdfError, luminance};
use glam::Vec3;

fn lobe_widths_deg() -> [f32; 11] {
    [0.05, 0.1, 0.5, 1.5, 5.0, 10.0, 20.0, 30.0, 45.0, 60.0, 90.0]
}

#[test]
fn reciprocity() {
    let mut rng = rng(1);
    for deg in [0.05f32, 0.5, 1.5, 5.0, 30.0, 90.0] {
        for (kd, gr) in [
            (Vec3::ZERO, Vec3::ONE),
            (Vec3::new(0.5, 0.2, 0.1), Vec3::new(0.3, 0.6, 0.5)),
        ] {
            let bdf = Bdf::new(kd, gr, deg.to_radians()).unwrap();
            let mut lobe_pairs = 0;
            for k in 0..4000 {
                let wo = uniform_hemisphere(&mut rng);
                // Half the pairs are independent directions, half are near the lobe's
                // peak (where the lobe term is large and asymmetries would show).
                let wi = if k % 2 == 0 {
                    uniform_hemisphere(&mut rng)
                } else {
                    match bdf.sample(
                        wo,
                        [
                            0.0,
                            crate::common::uf(&mut rng),
                            crate::common::uf(&mut rng),
                        ],
                    ) {
                        Some(s) => s.wi,
                        None => continue,
                    }
                };
                let (a, b) = (bdf.eval(wo, wi), bdf.eval(wi, wo));
                assert!(
                    close(a, b, 1e-5),
                    "Δ={deg}°: f({wo}, {wi}) = {a} but f(wi, wo) = {b}"
                );
                if (a - kd * FRAC_1_PI).max_element() > 1e-3 * a.max_element() {
                    lobe_pairs += 1;
                }
            }
            assert!(lobe_pairs > 1000, "Δ={deg}°: the lobe was rarely exercised");
        }
    }
}

/// ∫ f(wo, wi) cos θᵢ dωᵢ by a quadrature independent of the crate's: polar coordinates
/// around the mirror direction with ϑ = Δ·sinh(A·w), midpoint rule in w, and a
/// Gauss–Legendre rule over the azimuths above the horizon.
fn reflected_fraction(bdf: &Bdf, wo: Vec3) -> Vec3 {
    let delta = f64::from(bdf.delta().unwrap_or(1.0));
    let frame = MirrorFrame::new(wo);
    let span = (std::f64::consts::PI / delta).asinh();
    let gl = gauss_legendre(16);
    let n = 600;
    let mut sum = glam::DVec3::ZERO;
    for k in 0..n {
        let w = (k as f64 + 0.5) / n as f64;
        let theta = delta * (span * w).sinh();
        let dtheta = delta * span * (span * w).cosh() / n as f64;
        let t = 1.0 - theta.cos();
        let phi_max = frame.phi_max(t);
        for &(x, wx) in &gl {
            let wi = frame.direction(t, phi_max * x);
            let f = bdf.eval(wo, wi).as_dvec3();
            sum += f * f64::from(wi.z) * (wx * phi_max) * theta.sin() * dtheta;
        }
    }
    sum.as_vec3()
}

#[test]
fn energy_is_conserved_and_albedo_is_right() {
    let thetas = [
        0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 75.0, 80.0, 85.0, 87.0, 88.0, 89.0, 89.5,
        89.9, 89.99,
    ];
    for deg in lobe_widths_deg() {
        for (kd, gr) in [
            (Vec3::ZERO, Vec3::ONE),
            (Vec3::splat(0.4), Vec3::splat(0.6)),
        ] {
            let bdf = Bdf::new(kd, gr, deg.to_radians()).unwrap();
            let mut peak: f32 = 0.0;
            for theta in thetas {
                let wo = direction(theta);
                let reflected = reflected_fraction(&bdf, wo);
                let albedo = bdf.albedo(wo);
                assert!(
                    reflected.max_element() <= 1.0 + 1e-3,
                    "Δ={deg}° θo={theta}°: reflects {reflected}"
                );
                assert!(
                    albedo.max_element() <= 1.0 + 1e-5,
                    "Δ={deg}° θo={theta}°: {albedo}"
                );
                assert!(
                    (reflected - albedo).abs().max_element() < 1e-3,
                    "Δ={deg}° θo={theta}°: quadrature {reflected} vs albedo() {albedo}"
                );
                peak = peak.max(albedo.max_element());
            }
            // C is the *largest* constant: some direction reflects (almost) everything.
            // The grid above contains normal incidence, where narrow lobes peak, but not
            // the exact maximum for wider lobes, hence the looser bound.
            let sup = (0..=2000)
                .map(|k| {
                    bdf.albedo(direction(90.0 * k as f64 / 2000.0))
                        .max_element()
                })
                .fold(peak, f32::max);
            assert!(sup > 0.999, "Δ={deg}°: sup albedo {sup}");
        }
    }
}

#[test]
fn lobe_constant_matches_independent_values() {
    // C(1.5°) has its maximum at normal incidence, C(5°) near grazing (method.md §9).
    for (deg, want) in [(1.5f32, 281.08), (5.0, 23.869)] {
        let bdf = Bdf::new(Vec3::ZERO, Vec3::ONE, deg.to_radians()).unwrap();
        let c = bdf.lobe_constant().unwrap();
        assert!(
            (c / want - 1.0).abs() < 1e-3,
            "C({deg}°) = {c}, want {want}"
        );
    }
    assert_eq!(Bdf::lambert(Vec3::ONE).unwrap().lobe_constant(), None);
}

#[test]
fn constructors_validate() {
    let d = 5f32.to_radians();
    let half = Vec3::splat(0.5);
    type Case = (Vec3, Vec3, f32, fn(&BdfError) -> bool);
    let cases: [Case; 10] = [
        (Vec3::new(-0.1, 0.2, 0.2), Vec3::ZERO, d, |e| {
            matches!(e, BdfError::AlbedoOutOfRange { which: "kd", .. })
        }),
        (Vec3::new(0.1, 1.2, 0.2), Vec3::ZERO, d, |e| {
            matches!(e, BdfError::AlbedoOutOfRange { which: "kd", .. })
        }),
        (Vec3::ZERO, Vec3::new(0.1, 0.2, -1e-3), d, |e| {
            matches!(e, BdfError::AlbedoOutOfRange { which: "gr", .. })
        }),
        (Vec3::new(f32::NAN, 0.2, 0.2), Vec3::ZERO, d, |e| {
            matches!(e, BdfError::NotFinite { which: "kd", .. })
        }),
        (Vec3::ZERO, Vec3::new(0.1, f32::INFINITY, 0.2), d, |e| {
            matches!(e, BdfError::NotFinite { which: "gr", .. })
        }),
        (half, Vec3::new(0.5, 0.51, 0.5), d, |e| {
            matches!(e, BdfError::EnergyGain { .. })
        }),
        (half, half, f32::NAN, |e| {
            matches!(e, BdfError::LobeWidth { .. })
        }),
        (half, half, 0.04f32.to_radians(), |e| {
            matches!(e, BdfError::LobeWidth { .. })
        }),
        (half, half, 90.1f32.to_radians(), |e| {
            matches!(e, BdfError::LobeWidth { .. })
        }),
        (half, half, -d, |e| matches!(e, BdfError::LobeWidth { .. })),
    ];
    for (kd, gr, delta, is_expected) in cases {
        let err = Bdf::new(kd, gr, delta).expect_err("invalid input accepted");
        assert!(
            is_expected(&err),
            "kd={kd} gr={gr} Δ={delta}: wrong error {err:?}"
        );
        assert!(!err.to_string().is_empty());
    }
    assert!(matches!(
        Bdf::lambert(Vec3::splat(1.5)),
        Err(BdfError::AlbedoOutOfRange { which: "kd", .. })
    ));

    // The limits themselves, and decimal sums that round above 1, are accepted.
    for delta in [
        0.05f32.to_radians(),
        90f32.to_radians(),
        FRAC_PI_2,
        bdpm_bdf::LOBE_WIDTH_MIN,
        bdpm_bdf::LOBE_WIDTH_MAX,
    ] {
        assert!(Bdf::new(half, half, delta).is_ok(), "Δ={delta}");
    }
    assert!(Bdf::new(Vec3::splat(0.3), Vec3::splat(0.7), 0.1).is_ok());
    // Without a lobe, Δ is irrelevant and not checked.
    let lambert = Bdf::new(half, Vec3::ZERO, f32::NAN).unwrap();
    assert!(lambert.is_lambert());
    assert_eq!(lambert.delta(), None);
}

#[test]
fn accessors_and_lambert() {
    let kd = Vec3::new(0.5, 0.4, 0.3);
    let bdf = Bdf::lambert(kd).unwrap();
    assert!(bdf.is_lambert());
    assert_eq!((bdf.kd(), bdf.gr(), bdf.delta()), (kd, Vec3::ZERO, None));
    let wo = direction(30.0);
    let wi = direction(60.0);
    assert_eq!(bdf.eval(wo, wi), kd * FRAC_1_PI);
    assert!((bdf.pdf(wo, wi) - wi.z * FRAC_1_PI).abs() < 1e-7);
    assert_eq!(bdf.albedo(wo), kd);

    let delta = 3f32.to_radians();
    let mix = Bdf::new(kd, Vec3::splat(0.2), delta).unwrap();
    assert!(!mix.is_lambert());
    assert_eq!(mix.delta(), Some(delta));
    assert_eq!(mix.gr(), Vec3::splat(0.2));
    assert!(mix.to_string().contains("kd"));

    assert!((luminance(Vec3::ONE) - 1.0).abs() < 1e-6);
    assert!((luminance(Vec3::new(0.0, 1.0, 0.0)) - 0.7152).abs() < 1e-6);
}

#[test]
fn shareable_between_threads() {
    fn assert_send_sync<T: Send + Sync + Clone>() {}
    assert_send_sync::<Bdf>();
    assert_send_sync::<bdpm_bdf::BdfSample>();
    assert_send_sync::<BdfError>();
}

#[test]
fn black_surface_has_no_samples() {
    let bdf = Bdf::new(Vec3::ZERO, Vec3::ZERO, 0.1).unwrap();
    let wo = direction(20.0);
    assert_eq!(bdf.sample(wo, [0.5, 0.5, 0.5]), None);
    assert_eq!(bdf.pdf(wo, direction(10.0)), 0.0);
    assert_eq!(bdf.eval(wo, direction(10.0)), Vec3::ZERO);
    assert_eq!(bdf.albedo(wo), Vec3::ZERO);
}

#[test]
fn finite_everywhere_and_zero_below() {
    let zs = [
        1.0f32,
        0.5,
        1e-3,
        1e-6,
        1e-9,
        1e-20,
        1e-38,
        0.0,
        -0.0,
        -1e-9,
        -0.5,
        f32::NAN,
    ];
    let dirs: Vec<Vec3> = zs
        .iter()
        .map(|&z| {
            let r = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new(0.6 * r, -0.8 * r, z)
        })
        .chain([Vec3::NAN, Vec3::new(f32::INFINITY, 0.0, 1.0)])
        .collect();
    let mut rng = rng(3);
    for deg in [0.05f32, 0.1, 60.0, 90.0] {
        for (kd, gr) in [
            (Vec3::ZERO, Vec3::ONE),
            (Vec3::splat(0.5), Vec3::splat(0.5)),
        ] {
            let bdf = Bdf::new(kd, gr, deg.to_radians()).unwrap();
            for &wo in &dirs {
                let valid_o = wo.z > 0.0 && wo.is_finite();
                let albedo = bdf.albedo(wo);
                assert!(
                    albedo.is_finite() && albedo.min_element() >= 0.0,
                    "{wo}: {albedo}"
                );
                for &wi in &dirs {
                    let valid = valid_o && wi.z > 0.0 && wi.is_finite();
                    let (f, p) = (bdf.eval(wo, wi), bdf.pdf(wo, wi));
                    assert!(
                        f.is_finite() && f.min_element() >= 0.0,
                        "{wo} {wi}: f = {f}"
                    );
                    assert!(p.is_finite() && p >= 0.0, "{wo} {wi}: pdf = {p}");
                    if !valid {
                        assert_eq!((f, p), (Vec3::ZERO, 0.0), "{wo} {wi}");
                    }
                }
                for _ in 0..200 {
                    let s = bdf.sample(wo, u3(&mut rng));
                    assert!(valid_o || s.is_none(), "{wo}: sampled below the surface");
                    if let Some(s) = s {
                        assert!(s.wi.z > 0.0 && s.wi.is_finite(), "{s:?}");
                        assert!(s.pdf > 0.0 && s.pdf.is_finite(), "{s:?}");
                        assert!(s.f.is_finite() && s.weight.is_finite(), "{s:?}");
                    }
                }
                // The extreme corners of the sample space.
                for u in [[0.0, 0.0, 0.0], [0.999_999_9, 0.999_999_9, 0.999_999_9]] {
                    if let Some(s) = bdf.sample(wo, u) {
                        assert!(s.weight.is_finite() && s.pdf > 0.0, "{s:?}");
                    }
                }
            }
        }
    }
}
