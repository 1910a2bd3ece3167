//! The scattering models on their own: a Lambert surface and a Gaussian lobe (method.md §9),
//! evaluated, sampled and integrated. Checks that the sampler's Monte Carlo albedo matches
//! `Bdf::albedo`, and that the lobe is reciprocal.
//!
//! `cargo run --release -p bdpm-bdf --example lobe`

use bdpm_bdf::Bdf;
use glam::Vec3;

/// A tiny deterministic generator (the example needs no random crate).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

fn main() {
    let lambert = Bdf::lambert(Vec3::splat(0.5)).expect("albedo below 1");
    // Diffuse 0.2, lobe albedo 0.6, lobe width Δ = 10° (radians).
    let glossy = Bdf::new(Vec3::splat(0.2), Vec3::splat(0.6), 10f32.to_radians()).expect("valid");
    let wo = Vec3::new(0.5, 0.0, 0.866).normalize();
    let mut rng = Lcg(7);
    for (name, bdf) in [("lambert", &lambert), ("glossy", &glossy)] {
        // E[f·cos/pdf] over the sampler = directional albedo µ(wo).
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            if let Some(s) = bdf.sample(wo, [rng.next(), rng.next(), rng.next()]) {
                sum += f64::from(s.weight.x);
            }
        }
        let estimate = sum / n as f64;
        let exact = f64::from(bdf.albedo(wo).x);
        println!(
            "{name}: albedo by sampling {estimate:.4}, by the model {exact:.4} (dimensionless)"
        );
        assert!(
            (estimate - exact).abs() < 0.01,
            "{name}: {estimate} vs {exact}"
        );
    }
    // Reciprocity: f(wo, wi) = f(wi, wo).
    let wi = Vec3::new(-0.3, 0.2, 0.93).normalize();
    let (a, b) = (glossy.eval(wo, wi), glossy.eval(wi, wo));
    assert!((a - b).abs().max_element() <= 1e-6 * a.max_element());
    println!("glossy f(wo, wi) = {:.5} sr⁻¹ = f(wi, wo)", a.x);
}
