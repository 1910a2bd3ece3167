//! Scattering models of bdpm: Lambert, the Gaussian lobe of method.md §9, and their mix
//! `f = kd/π + g_r·G` ([`Bdf`]), with evaluation, sampling, pdfs and directional albedos; the
//! delta models, a perfect [`Mirror`] (optionally a conductor) and a smooth [`Dielectric`]
//! (glass), with their exact Fresnel terms; and [`Material`], the enum over all three.
//!
//! # Conventions
//!
//! - Directions live in the **local shading frame, normal +z**. They are unit `Vec3`s
//!   pointing **away** from the surface: `wo` towards the viewer (the next vertex of the
//!   eye path), `wi` towards the light. For [`Bdf`], directions with z ≤ 0 give zero value
//!   and pdf.
//! - Units: f is in sr⁻¹ (radiance units, Lambert is kd/π); pdfs are per solid angle
//!   (sr⁻¹); albedos, Fresnel reflectances, indices of refraction and sample weights are
//!   dimensionless; the lobe width Δ is in radians.
//! - Colours are linear RGB `Vec3`; scalar decisions (which component to sample) use
//!   their Rec. 709 [`luminance`].
//! - [`Bdf`] is reciprocal, so it has no transport mode: light paths and camera
//!   paths use the same `eval`, with the arguments in either order.
//! - **Delta models.** [`Mirror`] and [`Dielectric`] scatter into one direction (a
//!   dielectric into one of two, reflection with probability F): their BSDF is a Dirac delta,
//!   so `eval` and `pdf` are zero for every pair of directions and `is_delta()` is true. They
//!   are only sampled: [`SpecularSample`] holds the direction, the throughput weight
//!   f·|cos θᵢ|/p in the delta sense, the discrete probability of the branch, whether it
//!   refracted and the index ratio η_t/η_i it crossed. [`Material::is_delta`] is what an
//!   integrator branches on: connections and photon storage happen only at non-delta vertices.
//! - **Sides of a dielectric.** For [`Dielectric`], +z points into the exterior and
//!   η = η_interior/η_exterior; `wo` may have z < 0 (the path is inside), and a refraction
//!   lands on the other side. A [`Mirror`] is two-sided.
//! - **Transport modes.** Refraction is not symmetric: radiance scales by (η_t/η_i)² across
//!   an interface, flux and importance do not (Veach's thesis §5.2). [`Transport::Radiance`]
//!   (camera paths) weighs a refraction by 1/η², η = η_t/η_i with η_t on the side of the
//!   sampled `wi`; [`Transport::Importance`] (light paths, photons) does not. The two are
//!   adjoint: f_imp(wo, wi) = f_rad(wi, wo) in the delta sense.
//! - Sampling may fail (`None`): a lobe direction below the horizon counts as a sample
//!   of zero weight, and `pdf` is not renormalised for it, so `pdf` integrates to at most 1.
//!   A delta model fails only for a `wo` in the tangent plane or not finite.
//! - The lobe's constant C and its albedo table are computed once per distinct Δ
//!   (a few milliseconds) and shared process-wide; `Bdf` and [`Material`] are cheap to clone
//!   and `Send + Sync`.
//! - Precision: the lobe's constant and table are computed in f64; evaluation, pdfs, sampling
//!   and the albedo lookup run in f32, within a few 10⁻⁶ relative of the f64 formulas
//!   wherever the lobe is not negligible (the lobe's unit tests hold them to it). The Fresnel
//!   terms and the refracted direction are computed in f64 and returned in f32.
//!
//! # Architecture invariant
//!
//! This crate knows nothing about geometry, rays, scenes, lights or photons; callers
//! transform to and from the local frame. Its dependencies are `glam` and `bdpm-core`.
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
//!
//! A camera ray entering glass, and a photon on the same path:
//!
//! ```
//! use bdpm_bdf::{Dielectric, Material, Transport, fresnel_dielectric};
//! use glam::Vec3;
//!
//! let glass = Material::from(Dielectric::new(1.5)?);
//! assert!(glass.is_delta());
//! let wo = Vec3::new(0.6, 0.0, 0.8); // towards the camera, outside the glass
//! assert_eq!(glass.eval(wo, -wo), Vec3::ZERO); // a delta: no value for a given pair
//!
//! // u = 0.99 ≥ F ≈ 0.05: the ray refracts into the glass (z < 0).
//! let cam = glass.sample_delta(wo, 0.99, Transport::Radiance).expect("a usable wo");
//! assert!(cam.refracted && cam.wi.z < 0.0);
//! assert!((cam.probability - (1.0 - fresnel_dielectric(wo.z, 1.5))).abs() < 1e-6);
//! // Radiance seen from outside is the inside radiance / η², η = η_t/η_i = 1.5 ...
//! assert!((cam.weight.x - 1.0 / (1.5 * 1.5)).abs() < 1e-6);
//! // ... while a photon keeps its flux through clear glass.
//! let photon = glass.sample_delta(wo, 0.99, Transport::Importance).expect("a usable wo");
//! assert_eq!(photon.weight, Vec3::ONE);
//!
//! // Inside, beyond the critical angle asin(1/1.5) ≈ 41.8°: total internal reflection.
//! let inside = Vec3::new(0.8, 0.0, -0.6);
//! let tir = glass.sample_delta(inside, 0.99, Transport::Radiance).expect("a usable wo");
//! assert!(!tir.refracted && tir.probability == 1.0 && tir.wi == Vec3::new(-0.8, 0.0, -0.6));
//! # Ok::<(), bdpm_bdf::SpecularError>(())
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

// The README (the crate's page on crates.io) as a hidden item, so that `cargo test --doc`
// compiles and runs its example; the crate documentation above stays as it is.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
