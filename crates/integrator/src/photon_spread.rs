//! How unequal the photons' powers are, for the noise model's photon terms (`predict`).
//!
//! The model's merge noise α·∫f²ℓ (method.md §12) takes every gathered photon to carry the
//! luminance Φ/N_F it left the light with. Russian roulette keeps that only on grey surfaces:
//! it survives with the largest channel of the albedo and divides by it, so after a bounce on
//! a coloured surface a photon's luminance is lum(kd)/max(kd) of what it was (0.83 on Mitsuba's
//! warm white, 0.27 on its red wall), and a radiance ℓ is carried by more, dimmer photons, whose
//! kernel estimate is less noisy: its variance is ∝ Σ P² = ℓ·E_ℓ\[P\], not ℓ·Φ/N_F.
use bdpm_bdf::luminance;
use bdpm_core::Domain;
use bdpm_photon::{MAX_DEPTH, TraceOptions, trace_photons};
use bdpm_scene::Scene;

/// Photons traced for [`photon_power_spread`]: its mean over the gathered photons is then good
/// to a few per mille, for a few hundredths of a second.
pub const SPREAD_PHOTONS: u64 = 100_000;

/// κ = Σ P² / (Σ P · Φ/N) over the photons a merge gathers (arrivals after at least one
/// scattering, not at mirrors or glass), P each one's luminance power and Φ/N what each left
/// the light with: the factor by which the photon terms' α·∫f²ℓ, which assume P = Φ/N, are to
/// be scaled (dimensionless; 1 where every surface is grey, 1 without photons).
pub fn photon_power_spread(scene: &Scene, seed: u64) -> f64 {
    let options = TraceOptions {
        photons: SPREAD_PHOTONS,
        seed,
        domain: Domain::Other,
        pass: 0,
        light_visibility: false,
        max_depth: MAX_DEPTH,
    };
    let records = trace_photons(scene, &options, |a, out: &mut Vec<f64>| {
        if a.vertex.depth > 0 && !a.delta {
            out.push(f64::from(luminance(a.power)));
        }
    });
    let per_photon = f64::from(luminance(scene.total_flux())) / SPREAD_PHOTONS as f64;
    let (sum, sum_sq) = records
        .iter()
        .fold((0.0, 0.0), |(s, q), &p| (s + p, q + p * p));
    if sum > 0.0 && per_photon > 0.0 {
        sum_sq / (sum * per_photon)
    } else {
        1.0
    }
}
