//! The physics of the delta models: energy conservation, Snell's law and reversibility, total
//! internal reflection, the η² asymmetry of the transport modes and the adjoint relations in the
//! delta sense, the sampling frequencies against F, and a random walk through a glass slab
//! against its closed-form transmittance.
//!
//! Notation: `wo` is the direction the model is sampled from, `wi` the sampled one; η_o and
//! η_i are the (absolute) indices on their sides, with the exterior at 1 and the interior at
//! the model's η.

use crate::common::{rng, uf};
use bdpm_bdf::{Dielectric, SpecularSample, Transport, fresnel_dielectric, refract};
use glam::{DVec3, Vec3};

const ETAS: [f32; 5] = [1.0 / 1.33, 1.33, 1.5, 1.6, 2.4];
/// The largest f32 below 1: the refraction branch whenever F < 1.
const U_REFRACT: f32 = 1.0 - f32::EPSILON / 2.0;

/// A unit direction at polar angle `theta` (radians, from +z; > π/2 is inside) and azimuth `phi`.
fn dir(theta: f64, phi: f64) -> Vec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    DVec3::new(st * cp, st * sp, ct).as_vec3()
}

/// Directions on both sides of the surface, from near normal to near grazing.
fn directions() -> Vec<Vec3> {
    let mut out = Vec::new();
    for i in 0..=40 {
        let theta = (0.001 + 0.0385 * f64::from(i)).min(1.55);
        let phi = 0.37 + 0.61 * f64::from(i);
        out.push(dir(theta, phi));
        out.push(dir(std::f64::consts::PI - theta, phi));
    }
    out
}

/// The index on the side of `w`: 1 outside (z > 0), η inside.
fn index_at(w: Vec3, eta: f32) -> f64 {
    if w.z > 0.0 { 1.0 } else { f64::from(eta) }
}

fn refraction(d: &Dielectric, wo: Vec3, mode: Transport) -> Option<SpecularSample> {
    d.sample(wo, U_REFRACT, mode).filter(|s| s.refracted)
}

#[test]
fn white_dielectric_conserves_energy_under_importance_transport() {
    for eta in ETAS {
        let d = Dielectric::new(eta).unwrap();
        for wo in directions() {
            let r = d.sample(wo, 0.0, Transport::Importance).unwrap();
            assert_eq!(r.weight, Vec3::ONE);
            let f = d.fresnel(wo);
            match refraction(&d, wo, Transport::Importance) {
                // R + T = 1: the two branches' probabilities partition the unit interval, and
                // each carries weight 1, so every photon keeps its flux.
                Some(t) => {
                    assert_eq!(t.weight, Vec3::ONE);
                    assert_eq!(r.probability + t.probability, 1.0, "η = {eta}, wo = {wo}");
                }
                None => assert_eq!(f, 1.0),
            }
            assert!((d.albedo(wo) - Vec3::ONE).abs().max_element() < 1e-6);
        }
    }
}

#[test]
fn refraction_obeys_snell_and_is_reversible() {
    for eta in ETAS {
        let d = Dielectric::new(eta).unwrap();
        for wo in directions() {
            let Some(t) = refraction(&d, wo, Transport::Radiance) else {
                continue;
            };
            let (o, i) = (wo.as_dvec3(), t.wi.as_dvec3());
            let (n_o, n_i) = (index_at(wo, eta), index_at(t.wi, eta));
            assert!(o.z * i.z < 0.0 && (i.length() - 1.0).abs() < 1e-6);
            assert!((f64::from(t.eta) - n_i / n_o).abs() < 1e-6 * n_i / n_o);
            // η_o sin θ_o = η_i sin θ_i, and wi lies in the plane of wo and the normal,
            // on the other side of the normal.
            let (sin_o, sin_i) = (o.truncate().length(), i.truncate().length());
            assert!(
                (n_o * sin_o - n_i * sin_i).abs() < 2e-6 * n_o.max(n_i),
                "η = {eta}, wo = {wo}"
            );
            assert!(o.truncate().perp_dot(i.truncate()).abs() < 1e-6);
            assert!(o.truncate().dot(i.truncate()) <= 0.0);
            // The public function is the same refraction.
            assert_eq!(refract(wo, eta), Some((t.wi, t.eta)));
            // Back through the interface: refract(refract(w)) = w. Near grazing exit the
            // reverse Fresnel reflectance reaches 1 in f32 and refraction cannot be drawn.
            if d.fresnel(t.wi) < U_REFRACT {
                let back =
                    refraction(&d, t.wi, Transport::Radiance).expect("the reverse path refracts");
                assert!(
                    (back.wi - wo).length() < 2e-6,
                    "η = {eta}: {wo} → {} → {}",
                    t.wi,
                    back.wi
                );
                assert!((f64::from(back.eta) * f64::from(t.eta) - 1.0).abs() < 1e-6);
            }
        }
    }
}

#[test]
fn total_internal_reflection_always_reflects_with_weight_one() {
    let mut rng = rng(11);
    for eta in [1.33f32, 1.5, 2.4] {
        let tinted = Dielectric::tinted(eta, Vec3::new(0.9, 0.6, 0.3), Vec3::splat(0.5)).unwrap();
        let d = Dielectric::new(eta).unwrap();
        let theta_c = (1.0 / f64::from(eta)).asin();
        for k in 1..=20 {
            let theta = theta_c + (std::f64::consts::FRAC_PI_2 - theta_c) * f64::from(k) / 21.0;
            // Inside: the polar angle from −z is θ.
            let wo = dir(std::f64::consts::PI - theta, 0.3 * f64::from(k));
            assert_eq!(refract(wo, eta), None);
            for u in [0.0, uf(&mut rng), 0.5, U_REFRACT] {
                for mode in [Transport::Radiance, Transport::Importance] {
                    let s = d.sample(wo, u, mode).unwrap();
                    assert!(!s.refracted && s.probability == 1.0 && s.weight == Vec3::ONE);
                    assert_eq!(s.wi, Vec3::new(-wo.x, -wo.y, wo.z));
                    assert_eq!(
                        tinted.sample(wo, u, mode).unwrap().weight,
                        tinted.reflect_tint()
                    );
                }
            }
        }
        // Just below the critical angle, refraction is possible again.
        let wo = dir(std::f64::consts::PI - (theta_c - 1e-3), 0.0);
        assert!(refraction(&d, wo, Transport::Importance).is_some());
    }
}

/// The radiance weight of a refraction times η² (η = η_t/η_i, the index ratio of the
/// crossing) is the importance weight, and reflections are the same in both modes.
#[test]
fn radiance_and_importance_differ_by_eta_squared_on_refraction() {
    let d = Dielectric::tinted(1.5, Vec3::new(0.9, 0.8, 0.7), Vec3::new(0.3, 0.6, 0.9)).unwrap();
    for wo in directions() {
        let r = (
            d.sample(wo, 0.0, Transport::Radiance).unwrap(),
            d.sample(wo, 0.0, Transport::Importance).unwrap(),
        );
        assert_eq!(r.0, r.1);
        let (Some(rad), Some(imp)) = (
            refraction(&d, wo, Transport::Radiance),
            refraction(&d, wo, Transport::Importance),
        ) else {
            continue;
        };
        assert_eq!(
            (rad.wi, rad.probability, rad.eta),
            (imp.wi, imp.probability, imp.eta)
        );
        let eta2 = rad.eta * rad.eta;
        assert!(
            (rad.weight * eta2 - imp.weight).abs().max_element() < 1e-6,
            "wo = {wo}"
        );
        // Into the denser medium radiance is brighter per solid angle: the camera path,
        // looking from outside, sees the inside radiance dimmed by 1/η².
        if wo.z > 0.0 {
            assert!(rad.weight.max_element() < imp.weight.max_element());
        }
    }
}

/// A refraction's BSDF is c·δ(wi − r(wo)) per solid angle of wi, with c = weight/|cos θ_wi|
/// (the delta coefficient). Sampling from `wi` gives the reverse coefficient per solid angle of
/// wo; as distributions on pairs, δ(wo − r(wi)) = J·δ(wi − r(wo)) with the Jacobian of
/// refraction J = dω_wi/dω_wo = η_o²|cos θ_o| / (η_i²|cos θ_i|). Three relations follow
/// (Veach's thesis §5.2; pbrt-v4 §9.5.2):
/// - the adjoint: f_imp(wo, wi) = f_rad(wi, wo), i.e. c_imp(wo) = c_rad(wi)·J;
/// - generalised reciprocity: f_rad(wo, wi)/η_o² = f_rad(wi, wo)/η_i²;
/// - the η² scaling in one argument order: f_rad(wo, wi)/η_o² = f_imp(wo, wi)/η_i².
#[test]
fn transport_modes_are_adjoint_in_the_delta_sense() {
    for eta in ETAS {
        let d = Dielectric::new(eta).unwrap();
        for wo in directions() {
            let (Some(rad), Some(imp)) = (
                refraction(&d, wo, Transport::Radiance),
                refraction(&d, wo, Transport::Importance),
            ) else {
                continue;
            };
            let wi = rad.wi;
            let Some(back) = refraction(&d, wi, Transport::Radiance) else {
                continue;
            };
            let (cos_o, cos_i) = (f64::from(wo.z.abs()), f64::from(wi.z.abs()));
            if cos_o < 1e-3 || cos_i < 1e-3 {
                continue; // the f32 cosines lose relative precision at grazing
            }
            let (n_o, n_i) = (index_at(wo, eta), index_at(wi, eta));
            let jacobian = n_o * n_o * cos_o / (n_i * n_i * cos_i);
            // T = 1 − F in both directions (Stokes), so the Fresnel factors of the two
            // samples cancel: compare their delta coefficients times (1 − F).
            let t_fwd = 1.0 - f64::from(d.fresnel(wo));
            let t_back = 1.0 - f64::from(d.fresnel(wi));
            let c_rad_fwd = f64::from(rad.weight.x) * t_fwd / cos_i;
            let c_imp_fwd = f64::from(imp.weight.x) * t_fwd / cos_i;
            let c_rad_back = f64::from(back.weight.x) * t_back / cos_o;
            // The f32 rounding of wi moves 1 − F by up to ~3·10⁻⁵ relative near grazing; a
            // misplaced η² would be off by a factor of 1.7 or more.
            let tol = 1e-4 * c_imp_fwd.max(c_rad_fwd);
            let msg = format!("η = {eta}, wo = {wo}");
            assert!(
                (c_imp_fwd - c_rad_back * jacobian).abs() < tol,
                "adjoint, {msg}: {c_imp_fwd} vs {} (T {t_fwd}, {t_back}; cos {cos_o}, {cos_i})",
                c_rad_back * jacobian
            );
            assert!(
                (c_rad_fwd / (n_o * n_o) - c_rad_back * jacobian / (n_i * n_i)).abs() < tol,
                "reciprocity, {msg}"
            );
            assert!(
                (c_rad_fwd / (n_o * n_o) - c_imp_fwd / (n_i * n_i)).abs() < tol,
                "η² scaling, {msg}"
            );
        }
    }
}

#[test]
fn reflection_frequency_matches_fresnel_within_four_sigma() {
    let mut rng = rng(45);
    let n = 100_000u32;
    for eta in [1.33f32, 1.5, 2.4, 1.0 / 1.5] {
        let d = Dielectric::new(eta).unwrap();
        for theta in [0.0f64, 0.5, 1.0, 1.3, 1.5] {
            for wo in [dir(theta, 0.2), dir(std::f64::consts::PI - theta, 1.1)] {
                let f = f64::from(d.fresnel(wo));
                let reflected = (0..n)
                    .filter(|_| {
                        !d.sample(wo, uf(&mut rng), Transport::Radiance)
                            .unwrap()
                            .refracted
                    })
                    .count() as f64;
                let mean = f64::from(n) * f;
                let sigma = (f64::from(n) * f * (1.0 - f)).sqrt();
                assert!(
                    (reflected - mean).abs() <= 4.0 * sigma.max(0.5),
                    "η = {eta}, wo = {wo}: {reflected} reflections, expected {mean} ± {sigma}"
                );
            }
        }
    }
}

/// What leaves a slab: the mean weight over walks that leave through the far face and
/// through the near face, and the largest deviation of a transmitted walk's direction from
/// the incident one.
struct SlabResult {
    transmitted: f64,
    reflected: f64,
    direction_error: f32,
    max_transmitted_weight_error: f32,
}

/// Random walks through a slab of index η between the faces z = 0 (normal +z) and z = −1
/// (normal −z), arriving from above along `incident` (pointing down). Each face is the model
/// in its own local frame (z flipped for the far face); the walk's throughput multiplies the
/// sampled weights.
fn walk_slab(d: &Dielectric, incident: Vec3, mode: Transport, n: u32, seed: u64) -> SlabResult {
    let mut rng = rng(seed);
    let flip = |w: Vec3| Vec3::new(w.x, w.y, -w.z);
    let mut out = SlabResult {
        transmitted: 0.0,
        reflected: 0.0,
        direction_error: 0.0,
        max_transmitted_weight_error: 0.0,
    };
    for _ in 0..n {
        let (mut travel, mut top, mut weight) = (incident, true, Vec3::ONE);
        for _ in 0..10_000 {
            let to_local = |w: Vec3| if top { w } else { flip(w) };
            let s = d
                .sample(to_local(-travel), uf(&mut rng), mode)
                .expect("a usable direction");
            weight *= s.weight;
            travel = to_local(s.wi);
            let leaves = if top { travel.z > 0.0 } else { travel.z < 0.0 };
            if !leaves {
                top = !top;
                continue;
            }
            if top {
                out.reflected += f64::from(weight.x);
            } else {
                out.transmitted += f64::from(weight.x);
                out.direction_error = out.direction_error.max((travel - incident).length());
                let e = (weight - Vec3::ONE).abs().max_element();
                out.max_transmitted_weight_error = out.max_transmitted_weight_error.max(e);
            }
            break;
        }
    }
    out.transmitted /= f64::from(n);
    out.reflected /= f64::from(n);
    out
}

/// Transmittance of a slab in the unpolarised model: each face transmits 1 − R and the light
/// bounces between them, T = (1 − R)² Σ R²ᵏ = (1 − R)/(1 + R), with R the Fresnel reflectance
/// at the angle of incidence (the same at both faces, by the Stokes relations). At normal
/// incidence this is the exact physics; at oblique incidence a polarisation-resolved
/// calculation would average (1 − R_s)/(1 + R_s) and (1 − R_p)/(1 + R_p) instead.
#[test]
fn glass_slab_transmits_its_closed_form() {
    let n = 60_000u32;
    for (eta, theta) in [
        (1.5f32, 0.0f64),
        (1.5, 0.6),
        (1.5, 1.3),
        (2.4, 0.0),
        (2.4, 1.0),
        (1.0 / 1.33, 0.5),
    ] {
        let d = Dielectric::new(eta).unwrap();
        let incident = -dir(theta, 0.4);
        let r = f64::from(fresnel_dielectric(-incident.z, eta));
        let want = (1.0 - r) / (1.0 + r);
        let sigma = (want * (1.0 - want) / f64::from(n)).sqrt();
        for (mode, seed) in [(Transport::Importance, 1), (Transport::Radiance, 2)] {
            let got = walk_slab(&d, incident, mode, n, seed);
            let msg = format!("η = {eta}, θ = {theta}, {mode:?}");
            assert!(
                (got.transmitted - want).abs() <= 4.0 * sigma,
                "{msg}: T = {} vs {want} ± {sigma}",
                got.transmitted
            );
            // White glass loses nothing: what is not transmitted is reflected.
            assert!(
                (got.transmitted + got.reflected - 1.0).abs() < 1e-5,
                "{msg}"
            );
            // Parallel faces: the light leaves in its incident direction, and in radiance
            // transport the 1/η² of entering and the η² of leaving cancel.
            assert!(
                got.direction_error < 1e-5,
                "{msg}: direction off by {}",
                got.direction_error
            );
            assert!(
                got.max_transmitted_weight_error < 1e-5,
                "{msg}: weight off by {}",
                got.max_transmitted_weight_error
            );
        }
    }
    // Normal incidence on glass: R = 0.04, T = 0.96/1.04.
    let got = walk_slab(
        &Dielectric::new(1.5).unwrap(),
        -Vec3::Z,
        Transport::Importance,
        n,
        3,
    );
    let sigma = (0.923 * 0.077 / f64::from(n)).sqrt();
    assert!(
        (got.transmitted - 0.96 / 1.04).abs() <= 4.0 * sigma,
        "T = {}",
        got.transmitted
    );
}
