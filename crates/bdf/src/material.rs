//! The one type a surface's scattering is: a non-delta [`Bdf`] or a delta model, for the
//! integrator to dispatch on.

use std::fmt;

use glam::Vec3;

use crate::Bdf;
use crate::specular::{Dielectric, Mirror, SpecularSample, Transport};

/// How a surface scatters: the smooth Lambert + lobe model, or one of the delta models.
///
/// A plain enum, cheap to clone (the lobe's tables are shared), `Send + Sync`. Integrators
/// branch on [`Self::is_delta`]: a delta vertex is only ever sampled
/// ([`Self::sample_delta`]), never connected to (its `eval` and `pdf` are zero), and stores no
/// photon; a non-delta vertex uses the [`Bdf`] (through [`Self::bdf`]).
#[derive(Clone, Debug)]
pub enum Material {
    /// The non-delta model `f = kd/π + g_r·G` (Lambert, Gaussian lobe, their mix).
    Smooth(Bdf),
    /// A perfect mirror, optionally a conductor.
    Mirror(Mirror),
    /// A smooth dielectric: Fresnel reflection and refraction.
    Dielectric(Dielectric),
}

impl Material {
    /// True iff the model scatters into isolated directions (a mirror or a dielectric).
    pub fn is_delta(&self) -> bool {
        match self {
            Self::Smooth(_) => false,
            Self::Mirror(m) => m.is_delta(),
            Self::Dielectric(d) => d.is_delta(),
        }
    }

    /// The non-delta model, or `None` for a delta one.
    pub fn bdf(&self) -> Option<&Bdf> {
        match self {
            Self::Smooth(b) => Some(b),
            _ => None,
        }
    }

    /// Samples a delta model (see [`Mirror::sample`] and [`Dielectric::sample`]): `u` uniform
    /// in [0, 1) chooses a dielectric's branch, `mode` says whether the path carries radiance
    /// or importance. `None` for a non-delta model (sample its [`Bdf`] instead) and for an
    /// unusable `wo`.
    pub fn sample_delta(&self, wo: Vec3, u: f32, mode: Transport) -> Option<SpecularSample> {
        match self {
            Self::Smooth(_) => None,
            Self::Mirror(m) => m.sample(wo, u, mode),
            Self::Dielectric(d) => d.sample(wo, u, mode),
        }
    }

    /// f(wo, wi) in sr⁻¹: the [`Bdf`]'s value, zero for a delta model (for every pair).
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match self {
            Self::Smooth(b) => b.eval(wo, wi),
            Self::Mirror(m) => m.eval(wo, wi),
            Self::Dielectric(d) => d.eval(wo, wi),
        }
    }

    /// The solid-angle pdf in sr⁻¹: the [`Bdf`]'s, zero for a delta model (for every pair).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Self::Smooth(b) => b.pdf(wo, wi),
            Self::Mirror(m) => m.pdf(wo, wi),
            Self::Dielectric(d) => d.pdf(wo, wi),
        }
    }

    /// The fraction of flux scattered at `wo` (per channel, in [0, 1]): the [`Bdf`]'s
    /// directional albedo, [`Mirror::albedo`] or [`Dielectric::albedo`]. What a Russian
    /// roulette through delta chains can key on.
    pub fn albedo(&self, wo: Vec3) -> Vec3 {
        match self {
            Self::Smooth(b) => b.albedo(wo),
            Self::Mirror(m) => m.albedo(wo),
            Self::Dielectric(d) => d.albedo(wo),
        }
    }
}

impl From<Bdf> for Material {
    fn from(b: Bdf) -> Self {
        Self::Smooth(b)
    }
}

impl From<Mirror> for Material {
    fn from(m: Mirror) -> Self {
        Self::Mirror(m)
    }
}

impl From<Dielectric> for Material {
    fn from(d: Dielectric) -> Self {
        Self::Dielectric(d)
    }
}

impl fmt::Display for Material {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Smooth(b) => b.fmt(f),
            Self::Mirror(m) => m.fmt(f),
            Self::Dielectric(d) => d.fmt(f),
        }
    }
}
