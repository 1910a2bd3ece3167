//! The Russian roulette of photon paths (method.md §1), a function of the BDF alone so that
//! the photon tracer and the weights that recompute a photon's density (method.md §8) share it.

use glam::Vec3;

use crate::{Bdf, Outgoing};

/// Upper bound on the Russian-roulette survival probability: even a white (non-absorbing)
/// surface ends a path with probability ≥ 5 % per scattering, so every walk terminates.
pub const MAX_SURVIVAL: f32 = 0.95;

/// Russian-roulette survival probability q = min(0.95, max channel of the albedo µ(ω_in)),
/// with `incoming_local` the arrival direction in the BDF's local frame (pointing away from the
/// surface). It depends only on the vertex and the incoming direction, never on the photon's
/// power, so the photon density p_L(x₁→x₀) that the balance heuristic needs (method.md §8) is
/// `q · pdf` and can be recomputed from a stored vertex. Zero below the surface.
pub fn survival_probability(bdf: &Bdf, incoming_local: Vec3) -> f32 {
    survival_at(bdf, &bdf.outgoing(incoming_local))
}

/// [`survival_probability`] for an arrival direction prepared by [`Bdf::outgoing`].
pub fn survival_at(bdf: &Bdf, incoming: &Outgoing) -> f32 {
    bdf.albedo_at(incoming)
        .max_element()
        .clamp(0.0, MAX_SURVIVAL)
}
