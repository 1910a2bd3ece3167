//! The delta models' API: construction and its errors, the sampled direction, weight and
//! probability of each branch on both sides of the surface, zero eval and pdf, and the
//! unusable inputs that give `None` rather than a panic or a NaN.

use crate::common::{direction, rng, uf, uniform_hemisphere};
use bdpm_bdf::{
    Dielectric, ETA_MAX, ETA_MIN, Mirror, SpecularError, Transport, fresnel_conductor,
    fresnel_dielectric,
};
use glam::Vec3;

const MODES: [Transport; 2] = [Transport::Radiance, Transport::Importance];

fn below(w: Vec3) -> Vec3 {
    Vec3::new(w.x, w.y, -w.z)
}

#[test]
fn mirror_reflects_on_both_sides_with_its_reflectance() {
    let r = Vec3::new(0.9, 0.8, 0.7);
    let m = Mirror::new(r).unwrap();
    assert!(m.is_delta());
    for theta in [0.0, 30.0, 60.0, 89.9] {
        for wo in [direction(theta), below(direction(theta))] {
            for mode in MODES {
                let s = m.sample(wo, 0.5, mode).unwrap();
                assert_eq!(s.wi, Vec3::new(-wo.x, -wo.y, wo.z));
                assert_eq!(s.weight, r);
                assert_eq!((s.probability, s.refracted, s.eta), (1.0, false, 1.0));
            }
            assert_eq!(m.albedo(wo), r);
        }
    }
}

#[test]
fn conductor_mirror_weighs_the_fresnel_term() {
    // Gold.
    let (eta, k) = (Vec3::new(0.166, 0.434, 1.45), Vec3::new(3.15, 2.45, 1.95));
    let m = Mirror::conductor(Vec3::splat(0.9), eta, k).unwrap();
    assert_eq!(m.conductor_index(), Some((eta, k)));
    for theta in [0.0, 45.0, 80.0] {
        let wo = direction(theta);
        let s = m.sample(wo, 0.0, Transport::Radiance).unwrap();
        assert_eq!(s.weight, 0.9 * fresnel_conductor(wo.z, eta, k));
        assert_eq!(
            m.sample(below(wo), 0.0, Transport::Importance)
                .unwrap()
                .weight,
            s.weight
        );
    }
}

#[test]
fn eval_and_pdf_of_delta_models_are_zero() {
    let m = Mirror::new(Vec3::ONE).unwrap();
    let d = Dielectric::new(1.5).unwrap();
    let mut rng = rng(5);
    for _ in 0..200 {
        let wo = uniform_hemisphere(&mut rng);
        // Including the exact mirror and refraction directions: a delta has no value there.
        let s = d.sample(wo, uf(&mut rng), Transport::Radiance).unwrap();
        for wi in [
            uniform_hemisphere(&mut rng),
            Vec3::new(-wo.x, -wo.y, wo.z),
            s.wi,
        ] {
            assert_eq!(m.eval(wo, wi), Vec3::ZERO);
            assert_eq!(m.pdf(wo, wi), 0.0);
            assert_eq!(d.eval(wo, wi), Vec3::ZERO);
            assert_eq!(d.pdf(wo, wi), 0.0);
        }
    }
}

#[test]
fn dielectric_branches_carry_their_probability_and_tint() {
    let (rt, tt) = (Vec3::new(1.0, 0.5, 0.25), Vec3::new(0.2, 0.4, 0.8));
    let d = Dielectric::tinted(1.5, rt, tt).unwrap();
    assert!(d.is_delta());
    for theta in [0.0, 20.0, 50.0, 80.0] {
        for wo in [direction(theta), below(direction(theta))] {
            let f = fresnel_dielectric(wo.z, 1.5);
            assert_eq!(d.fresnel(wo), f);
            for mode in MODES {
                let r = d.sample(wo, 0.0, mode).unwrap();
                assert!(!r.refracted && r.probability == f && r.weight == rt && r.eta == 1.0);
                assert_eq!(r.wi, Vec3::new(-wo.x, -wo.y, wo.z));
                if f < 1.0 {
                    let t = d.sample(wo, 0.999_999, mode).unwrap();
                    assert!(t.refracted && t.probability == 1.0 - f);
                    assert!(t.wi.z * wo.z < 0.0, "a refraction crosses the surface");
                    let want_eta = if wo.z > 0.0 { 1.5 } else { 1.0 / 1.5 };
                    assert!((t.eta - want_eta).abs() < 1e-7);
                    let scale = match mode {
                        Transport::Radiance => 1.0 / (t.eta * t.eta),
                        Transport::Importance => 1.0,
                    };
                    assert!((t.weight - tt * scale).abs().max_element() < 1e-6 * scale);
                }
            }
            let want = rt * f + tt * (1.0 - f);
            assert!((d.albedo(wo) - want).abs().max_element() < 1e-6);
        }
    }
}

#[test]
fn index_matched_dielectric_passes_straight_through() {
    let d = Dielectric::new(1.0).unwrap();
    let wo = direction(40.0);
    assert_eq!(d.fresnel(wo), 0.0);
    let s = d.sample(wo, 0.0, Transport::Radiance).unwrap();
    assert!(s.refracted);
    assert!((s.wi + wo).length() < 1e-6, "{} vs {}", s.wi, -wo);
    assert_eq!(s.weight, Vec3::ONE);
}

#[test]
fn constructors_reject_bad_parameters() {
    for bad in [
        Vec3::splat(-0.1),
        Vec3::new(1.1, 0.0, 0.0),
        Vec3::splat(f32::NAN),
    ] {
        assert!(matches!(
            Mirror::new(bad),
            Err(SpecularError::Albedo {
                which: "reflectance",
                ..
            })
        ));
        assert!(matches!(
            Dielectric::tinted(1.5, bad, Vec3::ONE),
            Err(SpecularError::Albedo {
                which: "reflect_tint",
                ..
            })
        ));
        assert!(matches!(
            Dielectric::tinted(1.5, Vec3::ONE, bad),
            Err(SpecularError::Albedo {
                which: "transmit_tint",
                ..
            })
        ));
    }
    for eta in [
        0.0,
        -1.5,
        f32::NAN,
        f32::INFINITY,
        ETA_MIN * 0.99,
        ETA_MAX * 1.01,
    ] {
        match Dielectric::new(eta) {
            Err(SpecularError::DielectricIndex { eta: e }) => {
                assert_eq!(e.to_bits(), eta.to_bits())
            }
            other => panic!("η = {eta}: {other:?}"),
        }
    }
    assert!(Dielectric::new(ETA_MIN).is_ok() && Dielectric::new(ETA_MAX).is_ok());
    for (eta, k) in [
        (Vec3::ZERO, Vec3::ONE),
        (Vec3::ONE, Vec3::splat(-1.0)),
        (Vec3::splat(f32::NAN), Vec3::ONE),
        (Vec3::ONE, Vec3::splat(f32::INFINITY)),
    ] {
        assert!(matches!(
            Mirror::conductor(Vec3::ONE, eta, k),
            Err(SpecularError::ConductorIndex { .. })
        ));
    }
    // Every error says what is wrong.
    let e = Dielectric::new(-1.0).unwrap_err();
    assert!(e.to_string().contains("eta = -1"), "{e}");
}

#[test]
fn unusable_directions_give_none_not_nan() {
    let m = Mirror::conductor(Vec3::ONE, Vec3::splat(0.2), Vec3::splat(3.0)).unwrap();
    let d = Dielectric::new(1.5).unwrap();
    for wo in [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.6, 0.8, -0.0),
        Vec3::splat(f32::NAN),
        Vec3::new(0.0, 0.0, f32::INFINITY),
    ] {
        for mode in MODES {
            assert_eq!(m.sample(wo, 0.5, mode), None, "{wo}");
            assert_eq!(d.sample(wo, 0.5, mode), None, "{wo}");
        }
        assert_eq!(m.albedo(wo), Vec3::ZERO);
        assert_eq!(d.albedo(wo), Vec3::ZERO);
    }
    // Almost grazing still works, with finite weights.
    let wo = Vec3::new(1.0, 0.0, 1e-30).normalize();
    for u in [0.0, 0.5, 0.999_999] {
        let s = d.sample(wo, u, Transport::Radiance).unwrap();
        assert!(s.weight.is_finite() && s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-6);
    }
}

#[test]
fn display_names_the_parameters() {
    let d = Dielectric::new(1.5).unwrap();
    assert_eq!(d.to_string(), "Dielectric[eta = 1.5]");
    let m = Mirror::new(Vec3::splat(0.5)).unwrap();
    assert!(m.to_string().starts_with("Mirror[reflectance = "));
}

#[test]
fn material_dispatches_and_says_which_models_are_delta() {
    use bdpm_bdf::{Bdf, Material};
    fn send_sync<T: Send + Sync + Clone>() {}
    send_sync::<Material>();

    let bdf = Bdf::new(Vec3::splat(0.3), Vec3::splat(0.5), 10f32.to_radians()).unwrap();
    let smooth = Material::from(bdf.clone());
    let mirror = Material::from(Mirror::new(Vec3::splat(0.9)).unwrap());
    let glass = Material::from(Dielectric::new(1.5).unwrap());
    assert!(!smooth.is_delta() && mirror.is_delta() && glass.is_delta());
    assert!(smooth.bdf().is_some() && mirror.bdf().is_none() && glass.bdf().is_none());

    let (wo, wi) = (direction(30.0), direction(50.0));
    // The smooth model is the Bdf, bit for bit.
    assert_eq!(smooth.eval(wo, wi), bdf.eval(wo, wi));
    assert_eq!(smooth.pdf(wo, wi), bdf.pdf(wo, wi));
    assert_eq!(smooth.albedo(wo), bdf.albedo(wo));
    assert_eq!(smooth.sample_delta(wo, 0.5, Transport::Radiance), None);
    // The delta models: zero eval and pdf, sampling through the enum is the model's.
    for m in [&mirror, &glass] {
        let r = Vec3::new(-wo.x, -wo.y, wo.z);
        assert_eq!((m.eval(wo, r), m.pdf(wo, r)), (Vec3::ZERO, 0.0));
    }
    let s = glass.sample_delta(wo, 0.9, Transport::Radiance).unwrap();
    let d = Dielectric::new(1.5).unwrap();
    assert_eq!(Some(s), d.sample(wo, 0.9, Transport::Radiance));
    assert_eq!(glass.albedo(wo), d.albedo(wo));
    assert_eq!(
        mirror
            .sample_delta(wo, 0.1, Transport::Importance)
            .unwrap()
            .weight,
        Vec3::splat(0.9)
    );
    assert_eq!(glass.to_string(), "Dielectric[eta = 1.5]");
    assert_eq!(smooth.to_string(), bdf.to_string());
}
