//! The Lambert + Gaussian-lobe mixture `f = kd/π + g_r·G` (method.md §9).

use std::f32::consts::{FRAC_1_PI, TAU};
use std::fmt;
use std::sync::Arc;

use glam::Vec3;

use crate::error::BdfError;
use crate::lobe::{DELTA_MAX, DELTA_MIN, LobeTable, lobe_table};
use crate::luminance;

/// Slack allowed on kd + gr ≤ 1, so that values written as decimals (0.3 + 0.7) pass.
const ENERGY_SLACK: f32 = 1e-6;

/// One sampled scattering direction, as returned by [`Bdf::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BdfSample {
    /// Sampled incident direction (local frame, unit, z > 0).
    pub wi: Vec3,
    /// BDF value f(wo, wi), sr⁻¹.
    pub f: Vec3,
    /// Solid-angle pdf of `wi`, sr⁻¹: the full mixture pdf, equal to [`Bdf::pdf`]`(wo, wi)`.
    pub pdf: f32,
    /// `f · cos θᵢ / pdf` (dimensionless).
    pub weight: Vec3,
}

/// The per-outgoing-direction data of a [`Bdf`] (see [`Bdf::outgoing`]): the direction and the
/// lobe's directional albedo µ_G(wo) (dimensionless; 0 without a lobe or below the surface).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outgoing {
    /// The outgoing direction, local frame (normal = +z), unit.
    pub wo: Vec3,
    lobe_albedo: f32,
}

/// A surface's scattering model: `f = kd/π + g_r·G` with G the Gaussian lobe of
/// method.md §9 (width Δ, normalised so that `∫ G cos ≤ 1` for every direction).
///
/// Directions are in the local shading frame (normal +z), unit, pointing away from the
/// surface: `wo` towards the viewer (the next vertex of the eye path), `wi` towards the
/// light. Both components are reciprocal, `f(wo, wi) = f(wi, wo)`, so the same value
/// serves camera and light paths and there is no transport mode. Only reflection exists:
/// any direction with z ≤ 0 (or not finite) gives zero.
///
/// Cloning is cheap: the lobe's tables are shared between all models with the same Δ.
#[derive(Clone, Debug)]
pub struct Bdf {
    kd: Vec3,
    gr: Vec3,
    luminance_kd: f32,
    luminance_gr: f32,
    /// Present iff gr ≠ 0.
    lobe: Option<Arc<LobeTable>>,
}

impl Bdf {
    /// A Lambert surface, `f = kd/π`.
    pub fn lambert(kd: Vec3) -> Result<Self, BdfError> {
        Self::new(kd, Vec3::ZERO, DELTA_MAX as f32)
    }

    /// The mixture `kd/π + gr·G` with lobe width `delta` (radians).
    ///
    /// Every channel of kd and gr must be finite and in [0, 1], with kd + gr ≤ 1; Δ must
    /// be in [0.05°, 90°] when gr ≠ 0 (it is ignored otherwise). The first use of a Δ
    /// computes its normalisation and albedo table (a few milliseconds); later uses are
    /// a cache lookup.
    pub fn new(kd: Vec3, gr: Vec3, delta: f32) -> Result<Self, BdfError> {
        check_albedo("kd", kd)?;
        check_albedo("gr", gr)?;
        if (kd + gr).cmpgt(Vec3::splat(1.0 + ENERGY_SLACK)).any() {
            return Err(BdfError::EnergyGain { kd, gr });
        }
        let lobe = if gr == Vec3::ZERO {
            None
        } else {
            // Compare in f64 with a relative slack so that `0.05f32.to_radians()` passes.
            // NaN is in no range, so it is rejected too.
            let accepted = DELTA_MIN * (1.0 - 1e-6)..=DELTA_MAX * (1.0 + 1e-6);
            if !accepted.contains(&f64::from(delta)) {
                return Err(BdfError::LobeWidth { delta });
            }
            Some(lobe_table(delta))
        };
        Ok(Self {
            kd,
            gr,
            luminance_kd: luminance(kd),
            luminance_gr: luminance(gr),
            lobe,
        })
    }

    /// This model with its Lambert albedo replaced by `kd` (a texture's value at a hit): the
    /// lobe (g_r, Δ and its shared tables) stays. `kd` must be finite and in [0, 1] with
    /// kd + g_r ≤ 1 per channel, which holds for kd = (the material's kd) × (a texel in
    /// [0, 1]); it is not checked again on this per-hit path.
    pub fn with_kd(&self, kd: Vec3) -> Self {
        debug_assert!(check_albedo("kd", kd).is_ok());
        Self {
            kd,
            luminance_kd: luminance(kd),
            ..self.clone()
        }
    }

    /// The Lambert albedo kd.
    pub fn kd(&self) -> Vec3 {
        self.kd
    }

    /// The lobe albedo g_r.
    pub fn gr(&self) -> Vec3 {
        self.gr
    }

    /// The lobe width Δ in radians, or `None` without a lobe (gr = 0).
    pub fn delta(&self) -> Option<f32> {
        self.lobe.as_ref().map(|l| l.delta())
    }

    /// True iff there is no lobe (gr = 0), i.e. `f = kd/π`.
    pub fn is_lambert(&self) -> bool {
        self.lobe.is_none()
    }

    /// The lobe's normalisation constant C (method.md §9), or `None` without a lobe.
    pub fn lobe_constant(&self) -> Option<f64> {
        self.lobe.as_ref().map(|l| l.c())
    }

    /// f(wo, wi) in sr⁻¹; zero if either direction is not above the surface.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if !(above(wo) && above(wi)) {
            return Vec3::ZERO;
        }
        self.mix_value(self.lobe.as_ref().map(|lobe| lobe.value(wo, wi)))
    }

    /// kd/π + gr·G from G (`None` without a lobe): the one expression of f, shared by
    /// [`Self::eval`] and [`Self::sample_at`] so that their results agree bit for bit.
    fn mix_value(&self, lobe_value: Option<f32>) -> Vec3 {
        let diffuse = self.kd * FRAC_1_PI;
        match lobe_value {
            Some(g) => diffuse + self.gr * g,
            None => diffuse,
        }
    }

    /// What [`Self::eval`], [`Self::pdf`], [`Self::sample`] and [`Self::albedo`] share for one
    /// outgoing direction `wo` (the lobe's directional albedo, a table lookup), computed once.
    /// A vertex that evaluates several directions against one `wo` passes this to the `_at`
    /// methods instead of recomputing it; the results are bit-identical to the plain methods.
    pub fn outgoing(&self, wo: Vec3) -> Outgoing {
        let lobe_albedo = match &self.lobe {
            Some(lobe) if above(wo) => lobe.albedo(wo.z),
            _ => 0.0,
        };
        Outgoing { wo, lobe_albedo }
    }

    /// Solid-angle pdf (sr⁻¹) with which [`Self::sample`] returns `wi` given `wo`.
    ///
    /// This is the mixture `P_d·cos θᵢ/π + P_G·p_G(wi)`. The lobe density is not
    /// renormalised for the part of the lobe below the horizon (those samples fail), so
    /// the pdf integrates to at most 1 over the hemisphere.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.pdf_at(&self.outgoing(wo), wi)
    }

    /// [`Self::pdf`] for the outgoing direction prepared by [`Self::outgoing`].
    pub fn pdf_at(&self, o: &Outgoing, wi: Vec3) -> f32 {
        let wo = o.wo;
        if !(above(wo) && above(wi)) {
            return 0.0;
        }
        let Some(p_lobe) = self.lobe_probability(o) else {
            return 0.0;
        };
        let lobe_pdf = match &self.lobe {
            Some(lobe) if p_lobe > 0.0 => Some(lobe.pdf(wo, wi)),
            _ => None,
        };
        mix_pdf(p_lobe, wi, lobe_pdf)
    }

    /// Samples an incident direction for `wo` from `u` uniform in [0, 1)³.
    ///
    /// `u[0]` picks Lambert or the lobe, with probabilities proportional to their
    /// albedos at `wo` (by luminance); `u[1]`, `u[2]` place the direction (cosine-weighted
    /// hemisphere, or the lobe's exact exponential sampling around the mirror direction).
    /// Returns `None` when the lobe's direction falls below the horizon (for `wo` near
    /// grazing), when `wo` is not above the surface, or when kd and gr are both zero:
    /// such a sample contributes zero, which keeps the estimator unbiased.
    pub fn sample(&self, wo: Vec3, u: [f32; 3]) -> Option<BdfSample> {
        self.sample_at(&self.outgoing(wo), u)
    }

    /// [`Self::sample`] for the outgoing direction prepared by [`Self::outgoing`].
    pub fn sample_at(&self, o: &Outgoing, u: [f32; 3]) -> Option<BdfSample> {
        let wo = o.wo;
        if !above(wo) {
            return None;
        }
        let p_lobe = self.lobe_probability(o)?;
        let wi = match &self.lobe {
            Some(lobe) if u[0] < p_lobe => lobe.sample(wo, u[1], u[2]),
            _ => cosine_hemisphere(u[1], u[2]),
        };
        if !above(wi) {
            return None;
        }
        // pdf and f are what pdf_at and eval return (the same expressions, with the lobe's
        // exponential computed once for both), so they agree bit for bit.
        let (lobe_value, lobe_pdf) = match &self.lobe {
            Some(lobe) => {
                let (g, p) = lobe.value_and_pdf(wo, wi);
                (Some(g), (p_lobe > 0.0).then_some(p))
            }
            None => (None, None),
        };
        let pdf = mix_pdf(p_lobe, wi, lobe_pdf);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let f = self.mix_value(lobe_value);
        Some(BdfSample {
            wi,
            f,
            pdf,
            weight: f * (wi.z / pdf),
        })
    }

    /// Directional albedo µ(wo) = ∫ f(wo, wi) cos θᵢ dwi (dimensionless, ≤ 1 per channel):
    /// kd + gr·µ_G(wo), µ_G interpolated from the lobe's table. Zero below the surface.
    pub fn albedo(&self, wo: Vec3) -> Vec3 {
        self.albedo_at(&self.outgoing(wo))
    }

    /// [`Self::albedo`] for the outgoing direction prepared by [`Self::outgoing`].
    pub fn albedo_at(&self, o: &Outgoing) -> Vec3 {
        if !above(o.wo) {
            return Vec3::ZERO;
        }
        match &self.lobe {
            Some(_) => self.kd + self.gr * o.lobe_albedo,
            None => self.kd,
        }
    }

    /// Probability of sampling the lobe at `o.wo`, or `None` if nothing is reflected.
    fn lobe_probability(&self, o: &Outgoing) -> Option<f32> {
        let lobe = match &self.lobe {
            Some(_) => self.luminance_gr * o.lobe_albedo,
            None => 0.0,
        };
        let total = self.luminance_kd + lobe;
        (total > 0.0).then(|| lobe / total)
    }
}

impl fmt::Display for Bdf {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Bdf[kd = {}", self.kd)?;
        if let Some(delta) = self.delta() {
            write!(f, ", gr = {}, delta = {}°", self.gr, delta.to_degrees())?;
        }
        write!(f, "]")
    }
}

fn check_albedo(which: &'static str, value: Vec3) -> Result<(), BdfError> {
    if !value.is_finite() {
        Err(BdfError::NotFinite { which, value })
    } else if value.min_element() < 0.0 || value.max_element() > 1.0 {
        Err(BdfError::AlbedoOutOfRange { which, value })
    } else {
        Ok(())
    }
}

/// The mixture pdf `(1 − P_G)·cos θᵢ/π + P_G·p_G(wi)` from the lobe's pdf (`None` when the
/// lobe is not sampled): the one expression shared by [`Bdf::pdf_at`] and [`Bdf::sample_at`].
fn mix_pdf(p_lobe: f32, wi: Vec3, lobe_pdf: Option<f32>) -> f32 {
    let diffuse = (1.0 - p_lobe) * wi.z * FRAC_1_PI;
    match lobe_pdf {
        Some(p) => diffuse + p_lobe * p,
        None => diffuse,
    }
}

/// Strictly above the surface; rejects NaN so that no NaN propagates into f or pdf.
fn above(w: Vec3) -> bool {
    w.z > 0.0 && w.is_finite()
}

/// Cosine-weighted direction on the upper hemisphere (pdf cos θ/π).
fn cosine_hemisphere(u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let (sin_p, cos_p) = (TAU * u2).sin_cos();
    Vec3::new(r * cos_p, r * sin_p, (1.0 - u1).max(0.0).sqrt())
}
