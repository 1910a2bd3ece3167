//! Property tests over random directions and parameters: every model value is finite and
//! non-negative, reciprocal, and sampling agrees with evaluation wherever it succeeds.

use bdpm_bdf::{Bdf, luminance};
use glam::Vec3;
use proptest::prelude::*;

/// A unit direction from two uniforms, on the upper hemisphere or anywhere.
fn dir(u: f32, v: f32, upper: bool) -> Vec3 {
    let z = if upper { u } else { 2.0 * u - 1.0 };
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn model() -> impl Strategy<Value = Bdf> {
    // Δ comes from a fixed set spanning the allowed range: each new Δ costs a quadrature, and
    // the values in between add nothing the set does not cover.
    let deltas = prop::sample::select(vec![0.05f32, 0.1, 0.5, 1.5, 5.0, 12.0, 30.0, 60.0, 90.0]);
    (0.0f32..=1.0, 0.0f32..=1.0, deltas).prop_map(|(kd, share, delta_deg)| {
        let gr = (1.0 - kd) * share;
        Bdf::new(Vec3::splat(kd), Vec3::splat(gr), delta_deg.to_radians()).unwrap()
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn values_are_finite_non_negative_and_reciprocal(
        b in model(), a in (0.0f32..1.0, 0.0f32..1.0), c in (0.0f32..1.0, 0.0f32..1.0), any_side in any::<bool>(),
    ) {
        let wo = dir(a.0, a.1, !any_side);
        let wi = dir(c.0, c.1, !any_side);
        let f = b.eval(wo, wi);
        prop_assert!(f.is_finite() && f.min_element() >= 0.0, "f = {f}");
        let g = b.eval(wi, wo);
        prop_assert!((f - g).abs().max_element() <= 1e-5 * f.max_element().max(1e-12) + 1e-12, "{f} vs {g}");
        let p = b.pdf(wo, wi);
        prop_assert!(p.is_finite() && p >= 0.0);
        let mu = b.albedo(wo);
        prop_assert!(mu.is_finite() && mu.min_element() >= 0.0 && mu.max_element() <= 1.0 + 1e-3, "albedo {mu}");
    }

    #[test]
    fn samples_agree_with_evaluation(b in model(), a in (0.0f32..1.0, 0.0f32..1.0), u in (0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0)) {
        let wo = dir(a.0, a.1, true);
        if let Some(s) = b.sample(wo, [u.0, u.1, u.2]) {
            prop_assert!(s.wi.z > 0.0 && s.pdf > 0.0 && s.pdf.is_finite());
            prop_assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0);
            prop_assert_eq!(s.f, b.eval(wo, s.wi));
            prop_assert_eq!(s.pdf, b.pdf(wo, s.wi));
            let w = s.f * s.wi.z / s.pdf;
            prop_assert!((w - s.weight).abs().max_element() <= 1e-4 * luminance(w).max(1e-6));
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4000, failure_persistence: None, ..ProptestConfig::default() })]

    /// Any direction on either side, any index in range, any tint: a delta sample is a unit
    /// direction on the right side, with a finite non-negative weight and a probability in
    /// (0, 1]; never a NaN.
    #[test]
    fn delta_samples_are_well_formed(
        eta in bdpm_bdf::ETA_MIN..=bdpm_bdf::ETA_MAX, tint in 0.0f32..=1.0,
        a in (0.0f32..1.0, 0.0f32..1.0), u in 0.0f32..1.0, radiance in any::<bool>(),
    ) {
        use bdpm_bdf::{Dielectric, Mirror, Transport};
        let mode = if radiance { Transport::Radiance } else { Transport::Importance };
        let wo = dir(a.0, a.1, false);
        let glass = Dielectric::tinted(eta, Vec3::splat(tint), Vec3::ONE).unwrap();
        let metal = Mirror::conductor(Vec3::ONE, Vec3::splat(eta), Vec3::splat(tint * 5.0)).unwrap();
        for s in [glass.sample(wo, u, mode), metal.sample(wo, u, mode)].into_iter().flatten() {
            prop_assert!((s.wi.length() - 1.0).abs() < 1e-5, "wi = {}", s.wi);
            prop_assert_eq!(s.refracted, s.wi.z * wo.z < 0.0);
            prop_assert!(s.weight.is_finite() && s.weight.min_element() >= 0.0, "weight {}", s.weight);
            prop_assert!(s.probability > 0.0 && s.probability <= 1.0);
            prop_assert!(s.eta.is_finite() && s.eta > 0.0);
        }
        let f = glass.fresnel(wo);
        prop_assert!((0.0..=1.0).contains(&f));
    }
}
