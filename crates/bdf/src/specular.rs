//! The delta (specular) scattering models: a perfect mirror, optionally with a conductor's
//! Fresnel reflectance, and a smooth dielectric that reflects or refracts.
//!
//! A delta model scatters an incident direction into one direction (or one of two), so its
//! BSDF is a Dirac delta: `eval` and `pdf` are zero for every pair of directions (no pair
//! given in advance hits the delta), and the only way to use it is `sample`, which returns the
//! direction and the throughput weight `f·|cos θᵢ|/p` in the delta sense, the ratio of the
//! two deltas.

use std::fmt;

use glam::Vec3;

use crate::fresnel::{fresnel_conductor, fresnel_dielectric, reflect, refract};

/// Which quantity a path carries through a refraction, which decides the η² scaling of
/// radiance (Veach's thesis §5.2; pbrt-v4's `TransportMode`).
///
/// Radiance crossing an interface into a medium of index η_t from one of index η_i scales by
/// (η_t/η_i)², because L/η² is what is conserved along a ray; flux and importance do not. So
/// the adjoint BSDF, the one light paths use, differs from the one camera paths use by that
/// factor for a refraction. Reflections and the non-delta models are unaffected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Transport {
    /// A camera (eye) path: `wo` points towards the camera, the sampled `wi` towards the
    /// light, and the path's throughput multiplies radiance arriving along `wi`. A refraction
    /// into the side of `wi` weighs 1/η² with η = η_t/η_i (η_t on the side of `wi`, η_i on the
    /// side of `wo`): radiance leaving a dense medium into a thin one is dimmer.
    Radiance,
    /// A light path (a photon, or importance traced from the light): `wo` points back to
    /// where the path came from, the sampled `wi` is where it continues, and the weight
    /// multiplies flux. A refraction weighs its transmittance 1 − F only.
    Importance,
}

/// One sampled scattering of a delta model (see [`Mirror::sample`], [`Dielectric::sample`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularSample {
    /// The scattered direction (local frame, unit, pointing away from the surface): on the
    /// side of `wo` for a reflection, on the other side for a refraction.
    pub wi: Vec3,
    /// The throughput weight f·|cos θᵢ|/p in the delta sense (dimensionless, per channel):
    /// the tint for a dielectric's reflection; the tint, times 1/η² under
    /// [`Transport::Radiance`], for its refraction; the reflectance (times the conductor's
    /// Fresnel term) for a mirror.
    pub weight: Vec3,
    /// The discrete probability with which this branch was chosen (dimensionless, in (0, 1]):
    /// F for a dielectric's reflection, 1 − F for its refraction, 1 for a mirror. The
    /// weight already includes it; it is returned for the MIS densities of later vertices.
    pub probability: f32,
    /// True iff `wi` is a refraction (it lies on the other side of the surface from `wo`).
    pub refracted: bool,
    /// η_t/η_i of the crossing, seen from `wo`'s side (η_t on `wi`'s side): η or 1/η for a
    /// refraction, 1 for a reflection (dimensionless).
    pub eta: f32,
}

/// Why a [`Mirror`] or a [`Dielectric`] could not be built. Each variant names the offending
/// parameter and carries its value, so that a scene loader can report it as is.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum SpecularError {
    /// A reflectance or tint (`which` names it) has a channel that is not finite or not in [0, 1].
    Albedo {
        /// The parameter's name.
        which: &'static str,
        /// The value as given.
        value: Vec3,
    },
    /// A conductor's complex index has a channel with η not finite and > 0, or k not finite
    /// and ≥ 0.
    ConductorIndex {
        /// The real part η, per channel.
        eta: Vec3,
        /// The extinction coefficient k, per channel.
        k: Vec3,
    },
    /// A dielectric's relative index η is not finite or not in [[`ETA_MIN`], [`ETA_MAX`]].
    DielectricIndex {
        /// η as given.
        eta: f32,
    },
}

impl fmt::Display for SpecularError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Albedo { which, value } => {
                write!(
                    f,
                    "{which} = {value} has a channel outside [0, 1] or not finite"
                )
            }
            Self::ConductorIndex { eta, k } => write!(
                f,
                "conductor index eta = {eta}, k = {k}: every eta must be finite and > 0, \
                 every k finite and >= 0"
            ),
            Self::DielectricIndex { eta } => write!(
                f,
                "dielectric index ratio eta = {eta} is not in [{ETA_MIN}, {ETA_MAX}]"
            ),
        }
    }
}

impl std::error::Error for SpecularError {}

/// Smallest interior/exterior index ratio a [`Dielectric`] accepts (dimensionless).
pub const ETA_MIN: f32 = 0.01;
/// Largest interior/exterior index ratio a [`Dielectric`] accepts (dimensionless). Real
/// materials lie within 1/4 to 4; the bounds keep 1/η² and η² finite in f32 with room to spare.
pub const ETA_MAX: f32 = 100.0;

fn check_albedo(which: &'static str, value: Vec3) -> Result<Vec3, SpecularError> {
    let ok = value.is_finite() && value.min_element() >= 0.0 && value.max_element() <= 1.0;
    if ok {
        Ok(value)
    } else {
        Err(SpecularError::Albedo { which, value })
    }
}

/// A usable incident direction for a delta model: finite and off the tangent plane.
fn valid(wo: Vec3) -> bool {
    wo.z != 0.0 && wo.is_finite()
}

/// A perfect mirror: every direction reflects about the normal, weighted by a reflectance
/// and, optionally, by a conductor's Fresnel term at the angle of incidence.
///
/// A delta model: [`Self::eval`] and [`Self::pdf`] are zero for every pair of directions,
/// [`Self::sample`] is the only way to scatter. The mirror is two-sided (a `wo` below the
/// surface reflects below it) and reciprocal, so both [`Transport`] modes give the same
/// weight. Cheap to copy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror {
    reflectance: Vec3,
    /// The complex index (η, k) of a conductor, per channel, if the Fresnel term applies.
    conductor: Option<(Vec3, Vec3)>,
}

impl Mirror {
    /// A mirror that reflects the fraction `reflectance` (per channel, finite, in [0, 1]) at
    /// every angle.
    pub fn new(reflectance: Vec3) -> Result<Self, SpecularError> {
        Ok(Self {
            reflectance: check_albedo("reflectance", reflectance)?,
            conductor: None,
        })
    }

    /// A polished metal: `reflectance` (per channel, in [0, 1], usually 1) times the Fresnel
    /// reflectance of the complex index `eta + i·k` relative to the exterior medium (per
    /// channel, η > 0, k ≥ 0; see [`crate::fresnel_conductor`]).
    pub fn conductor(reflectance: Vec3, eta: Vec3, k: Vec3) -> Result<Self, SpecularError> {
        let ok =
            eta.is_finite() && k.is_finite() && eta.min_element() > 0.0 && k.min_element() >= 0.0;
        if !ok {
            return Err(SpecularError::ConductorIndex { eta, k });
        }
        Ok(Self {
            reflectance: check_albedo("reflectance", reflectance)?,
            conductor: Some((eta, k)),
        })
    }

    /// The reflectance factor (per channel, in [0, 1]), before any Fresnel term.
    pub fn reflectance(&self) -> Vec3 {
        self.reflectance
    }

    /// The conductor's complex index (η, k) per channel, or `None` without a Fresnel term.
    pub fn conductor_index(&self) -> Option<(Vec3, Vec3)> {
        self.conductor
    }

    /// Always true: a mirror is a delta model.
    pub fn is_delta(&self) -> bool {
        true
    }

    /// The fraction of light reflected at `wo` (per channel, in [0, 1]): the reflectance,
    /// times the conductor's Fresnel term at |cos θ_o|. Zero for an unusable `wo`
    /// (in the tangent plane or not finite).
    pub fn albedo(&self, wo: Vec3) -> Vec3 {
        if !valid(wo) {
            return Vec3::ZERO;
        }
        match self.conductor {
            Some((eta, k)) => self.reflectance * fresnel_conductor(wo.z, eta, k),
            None => self.reflectance,
        }
    }

    /// The reflection of `wo` (either side of the surface, unit): `wi` = (−x, −y, z) with
    /// weight [`Self::albedo`]`(wo)`, probability 1. The mirror needs no random number and is
    /// the same in both transport modes; `u` and `mode` exist so that every delta model
    /// samples with one signature. `None` for `wo` in the tangent plane or not finite.
    pub fn sample(&self, wo: Vec3, u: f32, mode: Transport) -> Option<SpecularSample> {
        let _ = (u, mode);
        if !valid(wo) {
            return None;
        }
        Some(SpecularSample {
            wi: reflect(wo),
            weight: self.albedo(wo),
            probability: 1.0,
            refracted: false,
            eta: 1.0,
        })
    }

    /// Zero (sr⁻¹): no pair of directions given in advance lies on the delta.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let _ = (wo, wi);
        Vec3::ZERO
    }

    /// Zero (sr⁻¹): the sampled direction is a point mass, it has no density per solid angle.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let _ = (wo, wi);
        0.0
    }
}

impl fmt::Display for Mirror {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Mirror[reflectance = {}", self.reflectance)?;
        if let Some((eta, k)) = self.conductor {
            write!(f, ", eta = {eta}, k = {k}")?;
        }
        write!(f, "]")
    }
}

/// A smooth dielectric interface (glass, water): Fresnel reflection and refraction, with total
/// internal reflection.
///
/// The local normal +z points into the **exterior** medium; η = η_interior/η_exterior (1.5 for
/// glass in air, 1/1.33 for an air bubble in water). `wo` may lie on either side: z < 0 means
/// the path is inside the medium. Optional tints (per channel, in [0, 1]) multiply the
/// reflected and the transmitted light (white for clear glass).
///
/// A delta model: [`Self::eval`] and [`Self::pdf`] are zero for every pair of directions,
/// [`Self::sample`] is the only way to scatter. Cheap to copy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    eta: f32,
    reflect_tint: Vec3,
    transmit_tint: Vec3,
}

impl Dielectric {
    /// Clear glass of relative index `eta` = η_interior/η_exterior, finite and in
    /// [[`ETA_MIN`], [`ETA_MAX`]].
    pub fn new(eta: f32) -> Result<Self, SpecularError> {
        Self::tinted(eta, Vec3::ONE, Vec3::ONE)
    }

    /// A dielectric of relative index `eta` whose reflected light is multiplied by
    /// `reflect_tint` and transmitted light by `transmit_tint` (per channel, in [0, 1]).
    /// The tints scale the weights; the branch is still chosen with probability F.
    pub fn tinted(
        eta: f32,
        reflect_tint: Vec3,
        transmit_tint: Vec3,
    ) -> Result<Self, SpecularError> {
        // NaN fails the range test.
        if !(ETA_MIN..=ETA_MAX).contains(&eta) {
            return Err(SpecularError::DielectricIndex { eta });
        }
        Ok(Self {
            eta,
            reflect_tint: check_albedo("reflect_tint", reflect_tint)?,
            transmit_tint: check_albedo("transmit_tint", transmit_tint)?,
        })
    }

    /// The relative index η = η_interior/η_exterior (dimensionless).
    pub fn eta(&self) -> f32 {
        self.eta
    }

    /// The tint of reflected light (per channel, in [0, 1]).
    pub fn reflect_tint(&self) -> Vec3 {
        self.reflect_tint
    }

    /// The tint of transmitted light (per channel, in [0, 1]).
    pub fn transmit_tint(&self) -> Vec3 {
        self.transmit_tint
    }

    /// Always true: a smooth dielectric is a delta model.
    pub fn is_delta(&self) -> bool {
        true
    }

    /// The Fresnel reflectance F at `wo` (dimensionless, in [0, 1]; 1 under total internal
    /// reflection): the probability that [`Self::sample`] reflects.
    pub fn fresnel(&self, wo: Vec3) -> f32 {
        fresnel_dielectric(wo.z, self.eta)
    }

    /// The fraction of flux scattered at `wo` (per channel, in [0, 1]), the expected
    /// [`Transport::Importance`] weight: F·reflect_tint + (1 − F)·transmit_tint, 1 for clear
    /// glass. Zero for an unusable `wo` (in the tangent plane or not finite).
    pub fn albedo(&self, wo: Vec3) -> Vec3 {
        if !valid(wo) {
            return Vec3::ZERO;
        }
        let f = self.fresnel(wo);
        self.reflect_tint * f + self.transmit_tint * (1.0 - f)
    }

    /// Reflects (probability F) or refracts (probability 1 − F) `wo`, a unit direction on
    /// either side of the surface, choosing with `u` uniform in [0, 1): reflection iff u < F.
    ///
    /// The weight is the reflect tint for a reflection; for a refraction it is the transmit
    /// tint under [`Transport::Importance`] and the transmit tint / η² under
    /// [`Transport::Radiance`], η = [`SpecularSample::eta`] = η_t/η_i. Under total internal
    /// reflection F = 1 and the sample always reflects. `None` for `wo` in the tangent plane
    /// or not finite.
    pub fn sample(&self, wo: Vec3, u: f32, mode: Transport) -> Option<SpecularSample> {
        if !valid(wo) {
            return None;
        }
        let f = self.fresnel(wo);
        if u < f {
            return Some(SpecularSample {
                wi: reflect(wo),
                weight: self.reflect_tint,
                probability: f,
                refracted: false,
                eta: 1.0,
            });
        }
        // F < 1, so the wave is not totally reflected and refraction succeeds: both use the
        // same f64 test of total internal reflection.
        let (wi, eta) = refract(wo, self.eta)?;
        let weight = match mode {
            Transport::Radiance => self.transmit_tint / (eta * eta),
            Transport::Importance => self.transmit_tint,
        };
        Some(SpecularSample {
            wi,
            weight,
            probability: 1.0 - f,
            refracted: true,
            eta,
        })
    }

    /// Zero (sr⁻¹): no pair of directions given in advance lies on the delta.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let _ = (wo, wi);
        Vec3::ZERO
    }

    /// Zero (sr⁻¹): the sampled direction is a point mass, it has no density per solid angle.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let _ = (wo, wi);
        0.0
    }
}

impl fmt::Display for Dielectric {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Dielectric[eta = {}", self.eta)?;
        if self.reflect_tint != Vec3::ONE || self.transmit_tint != Vec3::ONE {
            write!(
                f,
                ", reflect_tint = {}, transmit_tint = {}",
                self.reflect_tint, self.transmit_tint
            )?;
        }
        write!(f, "]")
    }
}
