//! Scattering models of bdpm: Lambert, the Gaussian lobe of method.md §9, and their mix
//! `f = kd/π + g_r·G`, with evaluation, sampling, pdfs and directional albedos.
//!
//! # Conventions
//!
//! - Directions live in the **local shading frame, normal +z**. They are unit `Vec3`s
//!   pointing **away** from the surface: `wo` towards the viewer (the next vertex of the
//!   eye path), `wi` towards the light. Directions with z ≤ 0 give zero value and pdf.
//! - Units: f is in sr⁻¹ (radiance units, Lambert is kd/π); pdfs are per solid angle
//!   (sr⁻¹); albedos and sample weights are dimensionless; the lobe width Δ is in radians.
//! - Colours are linear RGB `Vec3`; scalar decisions (which component to sample) use
//!   their Rec. 709 [`luminance`].
//! - Both models are reciprocal, so there is no transport mode: light paths and camera
//!   paths use the same `eval`, with the arguments in either order.
//! - Sampling may fail (`None`): a lobe direction below the horizon counts as a sample
//!   of zero weight, and `pdf` is not renormalised for it, so `pdf` integrates to at most 1.
//! - The lobe's constant C and its albedo table are computed once per distinct Δ
//!   (a few milliseconds) and shared process-wide; `Bdf` is cheap to clone and `Send + Sync`.
//! - Precision: the lobe's constant and table are computed in f64; evaluation, pdfs, sampling
//!   and the albedo lookup run in f32, within a few 10⁻⁶ relative of the f64 formulas
//!   wherever the lobe is not negligible (the lobe's unit tests hold them to it).
//!
//! # Architecture invariant
//!
//! This crate knows nothing about geometry, rays, scenes, lights or photons; callers
//! transform to and from the local frame. Its only dependency is `glam`.
//!
//! # Example
//!
//! ```
//! use bdpm_bdf::Bdf;
//! use glam::Vec3;
//!
//! let bdf = Bdf::new(Vec3::splat(0.3), Vec3::splat(0.6), 5f32.to_radians())?;
//! let wo = Vec3::new(0.6, 0.0, 0.8);
//! let s = bdf.sample(wo, [0.9, 0.5, 0.5]).expect("a sample above the horizon");
//! assert_eq!(s.pdf, bdf.pdf(wo, s.wi));
//! assert_eq!(bdf.eval(wo, s.wi), bdf.eval(s.wi, wo));
//! assert!(bdf.albedo(wo).max_element() <= 1.0);
//! # Ok::<(), bdpm_bdf::BdfError>(())
//! ```

mod bdf;
mod error;
mod fresnel;
mod lobe;
mod material;
mod quadrature;
mod specular;
mod survival;

pub use bdf::{Bdf, BdfSample, Outgoing};
pub use error::BdfError;
pub use fresnel::{
    Polarised, fresnel_conductor, fresnel_conductor_polarised, fresnel_dielectric,
    fresnel_dielectric_polarised, reflect, refract,
};
pub use lobe::{LOBE_EPSILON, LOBE_WIDTH_MAX, LOBE_WIDTH_MIN};
pub use material::Material;
pub use specular::{
    Dielectric, ETA_MAX, ETA_MIN, Mirror, SpecularError, SpecularSample, Transport,
};
pub use survival::{MAX_SURVIVAL, survival_at, survival_probability};

// Luminance is shared with the crates below the BDFs (photon tracing, the cache).
pub use bdpm_core::{LUMINANCE_WEIGHTS, luminance};
