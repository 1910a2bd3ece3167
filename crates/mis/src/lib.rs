//! MIS weights that mix the two photon-mapping strategies BDD=0 and BDD=1.
//!
//! This crate owns the weight functions of `method.md` §4 (eq. 8–11: `bdd0`, `bdd1`,
//! `threshold`, `algebraic-direct`, `algebraic`, `optimal`) and §8 (the peers'
//! `balance` and `power` heuristics on path densities, and `camis`, the balance heuristic
//! with the correlation-aware factor of Grittmann et al. 2021). Every mode is a variant of one
//! [`Heuristic`] enum; [`Heuristic::weight`] returns the weight w₁ of BDD=1 (the camera
//! path continues to x₁ and merges photons there) for one pair (x₀, x₁). The weight of
//! BDD=0 is w₀ = 1 − w₁ exactly ([`Weight::w0`]), which keeps the mix unbiased for any
//! weight function.
//!
//! **Architecture invariant:** this crate depends on nothing, not even a vector library.
//! It knows nothing about rays, BVHs, photons or caches; it sees only the scalars of
//! `method.md` §4 and §8 (f̃, L₀, L_d, b, κ, A, B, path densities), so any renderer can
//! call it. Where a renderer has RGB quantities it passes their luminances.
//!
//! **Numerics:** every weight is a pure function and never panics. For finite
//! non-negative inputs (radiance from 1e-30 to 1e30, N_B and N_F from 1, S from tiny to
//! huge, f̃ from 0) every output is finite: divisions are guarded (L = 0, f̃ = 0,
//! 1 − c·B ≤ ε, zero densities) and intermediate products saturate at `f64::MAX` instead
//! of overflowing. NaN or negative scalar inputs are treated as 0.
//!
//! **Units:** radiance in W·m⁻²·sr⁻¹, f̃ in sr⁻¹, merge area S in m², flux Φ in W,
//! area-measure densities in m⁻², distances in m. κ(L) = S·L·N_F/Φ is the photon count
//! of method.md §1 (formally per steradian, like N_B f̃ which it is added to); c·B and
//! the weights are dimensionless.
//!
//! # Example
//!
//! The algebraic weight (eq. 10) at a Lambert x₀ is 1/(1 + π κ(L)/N_B):
//!
//! ```
//! use bdpm_mis::{Budget, Heuristic, Pair};
//! use std::f64::consts::PI;
//!
//! let budget = Budget { camera_samples: 30.0, photons: 1e6, merge_area: 1e-5, flux: 1.0 };
//! let mut pair = Pair::default();
//! pair.x0.f_tilde = 1.0 / PI;
//! pair.x1.direct = 2.0;
//! pair.x1.indirect = 0.5;
//! let heuristic = Heuristic::parse("algebraic").unwrap();
//! assert!(heuristic.needs().radiance_cache);
//!
//! let w = heuristic.weight(&budget, &pair, None);
//! let expected = 1.0 / (1.0 + PI * budget.kappa(2.5) / 30.0);
//! assert!((w.w1 - expected).abs() < 1e-12);
//! assert_eq!(w.w0() + w.w1, 1.0);
//! ```

use std::fmt;

mod modes;
mod overlap;
pub use modes::{HeuristicKind, UnknownMode};
pub use overlap::{
    NoiseModel, effective_samples, lens_fraction, overlap_factor, overlap_factor_stratified,
};

/// The per-pass budget and merge settings shared by every weight of one render.
///
/// Preconditions: `camera_samples ≥ 1`, `photons ≥ 1`, `merge_area ≥ 0`, `flux > 0`.
/// Values outside them give finite (if meaningless) weights, never NaN.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Budget {
    /// N_B, camera samples per pixel per pass (≥ 1).
    pub camera_samples: f64,
    /// N_F, photons emitted per pass (≥ 1).
    pub photons: f64,
    /// S = π r², the merge (gather) disk area, m².
    pub merge_area: f64,
    /// Φ, total emitted flux (luminance), W.
    pub flux: f64,
}

impl Budget {
    /// κ(L) = S·L·N_F/Φ, the photon count of method.md §1 for radiance `radiance`
    /// (W·m⁻²·sr⁻¹): photons per pass in one merge disk, per steradian of arrival
    /// direction. Zero when L = 0 or S = 0; saturates at `f64::MAX`.
    pub fn kappa(&self, radiance: f64) -> f64 {
        mul(self.photon_density_factor(), nonneg(radiance))
    }

    /// c = (1 − 1/N_F)·S·N_F/(Φ·N_B), the correlation coefficient of method.md §4, in
    /// W⁻¹·m²; c·B is dimensionless. Zero when N_F = 1 (no photon is reused).
    pub fn c(&self) -> f64 {
        let n_b = nonneg(self.camera_samples);
        let c_n_b = self.correlation_factor();
        if c_n_b == 0.0 { 0.0 } else { sat(c_n_b / n_b) }
    }

    /// 1 − c·B for a pixel's B (W·m⁻², negative or NaN read as 0), with c·B clamped to 1 − ε
    /// where 1 − c·B ≤ [`CB_EPSILON`] (there the noise functional is no longer convex,
    /// method.md §4); the flag says whether it was. The one definition of the clamp, for the
    /// weights and for any report that counts clamped pixels.
    pub fn one_minus_cb(&self, big_b: f64) -> (f64, bool) {
        let cb = mul(self.c(), nonneg(big_b));
        if 1.0 - cb <= CB_EPSILON {
            (CB_EPSILON, true)
        } else {
            (1.0 - cb, false)
        }
    }

    /// S·N_F/Φ (W⁻¹·m²), the factor of κ(L) = (S·N_F/Φ)·L.
    fn photon_density_factor(&self) -> f64 {
        ratio_sat(
            mul(nonneg(self.merge_area), nonneg(self.photons)),
            self.flux,
        )
    }

    /// N_B·c = (N_F − 1)·S/Φ (W⁻¹·m²), the factor of c·G̃ in the numerator of eq. 8.
    fn correlation_factor(&self) -> f64 {
        // (1 − 1/N_F)·N_F = N_F − 1, written so that N_F = 1 gives exactly 0.
        let reused = nonneg(self.photons - 1.0);
        ratio_sat(mul(nonneg(self.merge_area), reused), self.flux)
    }
}

/// Which quantities a mode needs, so the integrator computes only those (method.md §7).
/// Non-exhaustive: a new mode may need a new quantity; other crates read the flags and get
/// them from [`Heuristic::needs`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct Needs {
    /// Gather photons at x₀ (false only for `bdd1`).
    pub photons_at_x0: bool,
    /// Trace the camera path's second vertex x₁ (false only for `bdd0`).
    pub second_vertex: bool,
    /// w₁ differs from path to path, so the weight is evaluated; false for the pure
    /// strategies, whose w₁ is the constant [`Heuristic::fixed_w1`] (`bdd0`, `bdd1`).
    pub weighs: bool,
    /// The smallest distance from x₁ to a light ([`X1Inputs::light_distance`]; `threshold`).
    pub light_distance: bool,
    /// x₀'s acceptance area and the camera's density of x₀ within its pixel
    /// ([`X0Inputs::acceptance_area`], [`X0Inputs::primary_density`]; `camis`).
    pub primary_terms: bool,
    /// The light subpath's surrogate probability β ([`PathInputs::light_suffix`]; `camis`).
    pub light_suffix: bool,
    /// L₀(x₁→x₀) is needed by the weight itself (shadow rays from x₁).
    pub direct_at_x1: bool,
    /// L_d(x₁→x₀) from the directional radiance cache is needed (method.md §5).
    pub radiance_cache: bool,
    /// b(x₁→x₀) from the cache is needed (`optimal` only).
    pub cache_b: bool,
    /// The per-pixel A, B table of method.md §6 is needed (`optimal` only).
    pub pixel_table: bool,
    /// Path densities p_C, p_L are needed (`balance`, `power`).
    pub densities: bool,
    /// The weight weighs BDD=0 against BDD=1 through N_B, so under the footprint noise
    /// model (method.md §12) the renderer passes each pixel's N_eff as
    /// [`Budget::camera_samples`] (`algebraic-direct`, `algebraic`, `optimal`).
    pub effective_samples: bool,
    /// The BDF at x₁ for each light path's incoming direction towards x₀
    /// ([`PathInputs::x1_scattering`]; `optimal-path`).
    pub x1_scattering: bool,
    /// One-bounce paths (L₀(x₁)) get another weight than merge paths at the same (x₀, x₁),
    /// so the two are weighted apart ([`PathInputs::kind`]; `optimal-split`, `optimal-path`).
    pub path_kinds: bool,
    /// A correction factor per pixel, learnt by a pilot of `balance` on its own random
    /// stream, scales BDD=1's density ([`Weigher::with_correction`]; `corrected-balance`).
    pub balance_correction: bool,
}

/// What the weight of one full path through the pair (x₀, x₁) may depend on, in three groups:
/// what x₀ alone sets, what x₁ sends towards x₀ (the same for every path through the pair),
/// and what the path's light subpath adds.
///
/// The integrator fills what [`Heuristic::needs`] asks for; the rest may be 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pair {
    /// Inputs of the camera's first vertex x₀ (and the direction x₀→x₁).
    pub x0: X0Inputs,
    /// Radiance data of x₁ towards x₀.
    pub x1: X1Inputs,
    /// Inputs of the full path's light subpath.
    pub path: PathInputs,
}

/// The part of a [`Pair`] that x₀ and the direction v = x₀→x₁ set.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct X0Inputs {
    /// f̃(v, u; x₀) = f/µ at x₀ for v = x₀→x₁ and u towards the camera, sr⁻¹
    /// (Lambert: 1/π).
    pub f_tilde: f64,
    /// A, the acceptance area of `camis`'s surrogate probabilities, m²: a disk of angular
    /// radius 1° seen from the camera at x₀'s distance ([`acceptance_area`]). 0 (unset) makes
    /// the correlation factor 1, i.e. `camis` = `balance`.
    pub acceptance_area: f64,
    /// p_C(x₀), the camera's density of x₀ within its pixel, area measure, m⁻² (the inverse
    /// of the pixel's footprint area at x₀; `camis` only).
    pub primary_density: f64,
}

/// The part of a [`Pair`] that x₁ sets: the radiance it sends towards x₀, the same for every
/// path through the pair.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct X1Inputs {
    /// L₀(x₁→x₀), radiance leaving x₁ towards x₀ due to direct light, W·m⁻²·sr⁻¹.
    pub direct: f64,
    /// L_d(x₁→x₀), secondary radiance from the cache, W·m⁻²·sr⁻¹.
    pub indirect: f64,
    /// b(x₁→x₀) from the cache, W·m⁻²·sr⁻² (radiance times sr⁻¹).
    pub b: f64,
    /// The smallest distance |x₁ − x_LS| over all lights, m (`threshold` only).
    pub light_distance: f64,
}

/// The part of a [`Pair`] that the full path's light subpath sets (density-based weights and
/// `optimal-path`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PathInputs {
    /// Which full path this weight is for (`balance`, `power`, `camis`, `optimal-split`,
    /// `optimal-path`).
    pub kind: PathKind,
    /// f₁(ω₂, x₁→x₀): the BDF at x₁ (luminance, sr⁻¹) for the light path's incoming
    /// direction ω₂ and the outgoing direction towards x₀ (`optimal-path`, merge paths only).
    pub x1_scattering: f64,
    /// p_C(x₀→x₁), area measure, m⁻²; the camera path at x₀ never absorbs.
    pub camera_density: f64,
    /// p_L(x₁→x₀), area measure, m⁻², including the photon's Russian roulette at x₁.
    pub light_density: f64,
    /// p_L(light→x₁), area measure, m⁻², including the choice of light
    /// ([`PathKind::OneBounce`] only).
    pub emission_density: f64,
    /// β, dimensionless in [0, 1]: the surrogate probability that the light subpath of a
    /// [`PathKind::Merge`] path lands in its acceptance regions, ∏ [`acceptance_probability`]
    /// over the light's densities of x₁ (from x₂), of x₂ (from x₃), … and of the first vertex
    /// (from the light, choice of light included) (`camis` only).
    pub light_suffix: f64,
}

/// Which full path a density-based weight is for (method.md §8).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PathKind {
    /// A merge path …x₂→x₁→x₀ (the photon at x₀ has been scattered at least twice).
    #[default]
    Merge,
    /// A one-bounce path light→x₁→x₀ (BDD=1 gets it through L₀(x₁)).
    OneBounce,
}

/// The per-pixel integrals A(u, x₀) and B(u, x₀) of method.md §4 and §6.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelTerms {
    /// A = ∫ W₁ f̃ L cos dv, W·m⁻²·sr⁻¹.
    pub a: f64,
    /// B = ∫ W₁ L cos dv, W·m⁻²; c·B is dimensionless.
    pub b: f64,
}

/// The result of one weight evaluation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Weight {
    /// The weight of BDD=1 (dimensionless); the weight of BDD=0 is 1 − w1 exactly.
    pub w1: f64,
    /// `optimal`: c·B was clamped to 1 − [`CB_EPSILON`].
    pub clamped_cb: bool,
    /// w1 was outside [0, 1] before the optional clamp (only `optimal` can do this).
    pub outside_unit: bool,
}

impl Weight {
    /// The weight of BDD=0, w₀ = 1 − w₁.
    pub fn w0(&self) -> f64 {
        1.0 - self.w1
    }

    /// A weight that needed no guard.
    fn plain(w1: f64) -> Self {
        Weight {
            w1,
            clamped_cb: false,
            outside_unit: false,
        }
    }
}

/// The constant ε of the c·B clamp (method.md §4): when 1 − c·B ≤ ε, c·B is taken as
/// 1 − ε, which caps the amplification 1/(1 − c·B) of A at 1/ε = 1000.
pub const CB_EPSILON: f64 = 1e-3;

/// The threshold radius R of eq. 11 used by [`Heuristic::parse`], m (the preprint's 20 cm).
pub const DEFAULT_THRESHOLD_RADIUS: f64 = 0.2;

/// One weighting mode of method.md §4 and §8. Its names and parsing come from the table in
/// `modes.rs`. Non-exhaustive: new modes are expected, so a match outside this crate needs a
/// `_ =>` arm.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Heuristic {
    /// w₁ = 0: merge photons at x₀ only.
    Bdd0,
    /// w₁ = 1: always continue to x₁ and merge there.
    Bdd1,
    /// Eq. 11: w₁ = 1 if x₁ is at least `radius` (m) from every light, else 0.
    Threshold {
        /// R, m.
        radius: f64,
    },
    /// Eq. 10 with L = L₀(x₁→x₀) only.
    AlgebraicDirect,
    /// Eq. 10 with L = L₀ + L_d.
    Algebraic,
    /// Eq. 8–9 in the division-safe form of method.md §4.
    Optimal {
        /// Clamp w₁ to [0, 1] (the unclamped weight is unbiased too).
        clamp_weights: bool,
    },
    /// Eq. 8 over a richer family: separate weights for the one-bounce paths light→x₁→x₀
    /// (BDD=1 gets them exactly through L₀(x₁)) and the merge paths …x₂→x₁→x₀ (BDD=1 merges
    /// photons at x₁ for them), each optimal for the noise model (method-notes.md, "optimal-split").
    OptimalSplit {
        /// Clamp w₁ to [0, 1] (the unclamped weight is unbiased too).
        clamp_weights: bool,
    },
    /// The optimal weight over the family w₁(x₀, x₁, ω₂) that may also depend on the light
    /// path's incoming direction at x₁: `optimal-split` for one-bounce paths, and for merge
    /// paths the photon's own BDF value f₁(ω₂, x₁→x₀) in place of its cell average b/L_d
    /// (method-notes.md, "optimal-path").
    OptimalPath {
        /// Clamp w₁ to [0, 1] (the unclamped weight is unbiased too).
        clamp_weights: bool,
    },
    /// Veach's balance heuristic on path densities (method.md §8).
    Balance,
    /// Veach's power heuristic (exponent 2) on path densities (method.md §8).
    Power,
    /// The balance heuristic with the correlation-aware factor of Grittmann, Georgiev and
    /// Slusallek (Eurographics 2021) on BDD=1's merge at x₁ (method-notes.md, "camis").
    ///
    /// For a [`PathKind::Merge`] path, BDD=1 merges at x₁ the photons of N_F light paths
    /// with one camera prefix (x₀, x₁), so those N_F paths are correlated through the prefix.
    /// The paper scales that merge's sample count by r = a/(a + β − a·β), with
    /// a = [`acceptance_probability`](p_C(x₀))·[`acceptance_probability`](p_C(x₀→x₁)) the
    /// camera prefix's and β ([`PathInputs::light_suffix`]) the light subpath's surrogate
    /// probability, giving w₁ = r·p_C/(r·p_C + p_L). BDD=0 merges at the primary vertex,
    /// which the paper (and its code) leaves uncorrelated (factor 1): x₀ is fixed by the
    /// pixel up to its footprint. For a [`PathKind::OneBounce`] path BDD=1 is a connection
    /// (L₀(x₁), next-event estimation), not a merge, so no factor applies and `camis` is
    /// exactly `balance`. r ∈ [0, 1] and r = 1 when β = 0, so `camis` never favours BDD=1
    /// more than `balance` does.
    Camis,
    /// The balance heuristic with BDD=1's density scaled by a per-pixel factor c learnt from
    /// data, in the style of Hua, Grittmann and Slusallek 2025 ("Correct your balance
    /// heuristic"): w₁ = c·p_C/(c·p_C + p_L) for every path kind, so BDD=0's merge at x₀ is
    /// corrected as much as BDD=1's (method-notes.md, "corrected-balance"). The factor comes
    /// from [`Weigher::with_correction`] (1 without one: `balance` exactly); see
    /// [`corrected_share`] for how a pilot scores candidate factors from `balance`'s own w₁.
    CorrectedBalance,
}

impl Heuristic {
    /// The same mode with its optional clamp of w₁ to [0, 1] set to `clamp` (the `optimal*`
    /// modes; the others are returned unchanged, their weights are in [0, 1] already).
    pub fn with_weight_clamp(self, clamp: bool) -> Heuristic {
        match self {
            Heuristic::Optimal { .. } => Heuristic::Optimal {
                clamp_weights: clamp,
            },
            Heuristic::OptimalSplit { .. } => Heuristic::OptimalSplit {
                clamp_weights: clamp,
            },
            Heuristic::OptimalPath { .. } => Heuristic::OptimalPath {
                clamp_weights: clamp,
            },
            other => other,
        }
    }

    /// What the integrator must compute for this mode (method.md §4 table and §7).
    pub fn needs(&self) -> Needs {
        // Every mixing mode gathers at x₀ and traces x₁; the pure strategies drop one.
        let mix = Needs {
            photons_at_x0: true,
            second_vertex: true,
            weighs: true,
            ..Needs::default()
        };
        match self {
            Heuristic::Bdd0 => Needs {
                photons_at_x0: true,
                ..Needs::default()
            },
            Heuristic::Bdd1 => Needs {
                second_vertex: true,
                ..Needs::default()
            },
            // Eq. 11 needs only x₁'s distance to the lights.
            Heuristic::Threshold { .. } => Needs {
                light_distance: true,
                ..mix
            },
            Heuristic::AlgebraicDirect => Needs {
                direct_at_x1: true,
                effective_samples: true,
                ..mix
            },
            Heuristic::Algebraic => Needs {
                direct_at_x1: true,
                radiance_cache: true,
                effective_samples: true,
                ..mix
            },
            Heuristic::Optimal { .. } => Needs {
                direct_at_x1: true,
                effective_samples: true,
                radiance_cache: true,
                cache_b: true,
                pixel_table: true,
                ..mix
            },
            Heuristic::OptimalSplit { .. } => Needs {
                direct_at_x1: true,
                effective_samples: true,
                radiance_cache: true,
                cache_b: true,
                pixel_table: true,
                path_kinds: true,
                ..mix
            },
            Heuristic::OptimalPath { .. } => Needs {
                direct_at_x1: true,
                effective_samples: true,
                radiance_cache: true,
                cache_b: true,
                pixel_table: true,
                x1_scattering: true,
                path_kinds: true,
                ..mix
            },
            Heuristic::Balance | Heuristic::Power => Needs {
                densities: true,
                ..mix
            },
            // The correlation factor's acceptance area, p_C(x₀) and β (method-notes.md, "camis").
            Heuristic::Camis => Needs {
                densities: true,
                primary_terms: true,
                light_suffix: true,
                ..mix
            },
            Heuristic::CorrectedBalance => Needs {
                densities: true,
                balance_correction: true,
                ..mix
            },
        }
    }

    /// w₁ of a mode that does not weigh ([`Needs::weighs`] false): 0 for `bdd0` (merge at x₀
    /// only), 1 for `bdd1`; `None` for every mode whose w₁ depends on the path.
    pub fn fixed_w1(&self) -> Option<f64> {
        match self {
            Heuristic::Bdd0 => Some(0.0),
            Heuristic::Bdd1 => Some(1.0),
            _ => None,
        }
    }

    /// The weight w₁ of BDD=1 for one pair (x₀, x₁).
    ///
    /// `pixel` holds the pixel's A, B (used by `optimal` only; `None` means A = B = 0,
    /// which reduces eq. 8 to W₁ with the b term). The output is finite for all finite
    /// non-negative inputs; see the crate docs for the guards. To weigh many pairs of one
    /// pixel, build a [`Weigher`] once: the same bits, without recomputing the factors they
    /// share.
    pub fn weight(&self, budget: &Budget, pair: &Pair, pixel: Option<&PixelTerms>) -> Weight {
        Weigher::new(*self, budget, pixel).weight(pair)
    }
}

/// A [`Heuristic`] ready to weigh the pairs of one pixel: the factors every weight of the
/// pixel shares (S·N_F/Φ of κ, and the correlation term N_B·c·G̃ of eq. 8 from the pixel's A
/// and B) computed once. [`Weigher::weight`] gives the bits [`Heuristic::weight`] gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weigher {
    heuristic: Heuristic,
    scale: Scale,
    /// N_B·c·G̃ with G̃ = A/(1 − c·B), sr⁻¹: the correlation term of eq. 8's numerator.
    correlation: f64,
    /// Whether c·B was clamped to 1 − [`CB_EPSILON`] for this pixel.
    clamped_cb: bool,
    /// `corrected-balance`'s factor on BDD=1's density for this pixel (dimensionless, 1 by
    /// default; the other modes ignore it).
    correction: f64,
}

impl Weigher {
    /// The weigher of `heuristic` for `budget` and one pixel's A, B (`None`: A = B = 0).
    pub fn new(heuristic: Heuristic, budget: &Budget, pixel: Option<&PixelTerms>) -> Self {
        let (a, b) = pixel.map_or((0.0, 0.0), |p| (p.a, p.b));
        let (one_minus_cb, clamped_cb) = budget.one_minus_cb(b);
        let g_tilde = sat(nonneg(a) / one_minus_cb);
        Weigher {
            heuristic,
            scale: Scale::new(budget),
            correlation: mul(budget.correlation_factor(), g_tilde),
            clamped_cb,
            correction: 1.0,
        }
    }

    /// The merge area S this weigher reads, m² (the budget's, which a per-pixel radius scales).
    pub fn merge_area(&self) -> f64 {
        self.scale.budget.merge_area
    }

    /// The same weigher with `corrected-balance`'s factor c on BDD=1's density for this pixel
    /// (dimensionless; NaN or negative read as 0, i.e. BDD=0 only). Only
    /// [`Heuristic::CorrectedBalance`] reads it.
    pub fn with_correction(self, c: f64) -> Self {
        Weigher {
            correction: nonneg(c),
            ..self
        }
    }

    /// w₁ when BDD=0's paths are sampled by light tracing (every photon arrival connected to
    /// the camera) instead of merged at x₀ (method-notes.md, "Light tracing in place of the
    /// merge at x₀"). `ratio` = N_B·S·p_C(x₀) (dimensionless: N_B camera samples per pixel,
    /// S the merge area, p_C(x₀) the camera's density of x₀ within its pixel, m⁻²) is BDD=0's
    /// density of a path over light tracing's: a merge finds a photon with probability
    /// N_B·p_C·S, a connection finds it once. A ratio of 0 (or NaN, or negative) gives w₁ = 0:
    /// the camera cannot sample that x₀.
    ///
    /// - `balance`, `camis`, `corrected-balance`: BDD=1's share with light tracing's density
    ///   in BDD=0's place, [`corrected_share`]`(w₁, ratio)` (exact for `balance`; `camis`
    ///   keeps its correlation factor on BDD=1's merge); `power` likewise with ratio².
    /// - The model-based modes: the noise model with light tracing's BDD=0 photon noise,
    ///   Φ·p_C/N_F per unit of ∫(1 − w₁)²f²L cos, in place of the merge's Φ·N_eff/(N_F·S·N_B):
    ///   the same functional with `ratio` in place of N_eff (method-notes.md), so every N f̃
    ///   of the weights reads `ratio` (κ, b/L and the pixel's A, B and correlation term are
    ///   the merge's).
    /// - `bdd0`, `bdd1`, `threshold`: as [`Self::weight`] (they do not read densities).
    pub fn weight_light_traced(&self, pair: &Pair, ratio: f64) -> Weight {
        let ratio = nonneg(ratio);
        let fixed = matches!(
            self.heuristic,
            Heuristic::Bdd0 | Heuristic::Bdd1 | Heuristic::Threshold { .. }
        );
        if fixed {
            return self.weight(pair);
        }
        if ratio == 0.0 {
            return Weight::plain(0.0);
        }
        match self.heuristic {
            Heuristic::Balance | Heuristic::Camis | Heuristic::CorrectedBalance => {
                let w = self.weight(pair);
                Weight {
                    w1: corrected_share(w.w1, ratio),
                    ..w
                }
            }
            Heuristic::Power => {
                let w = self.weight(pair);
                Weight {
                    w1: corrected_share(w.w1, mul(ratio, ratio)),
                    ..w
                }
            }
            _ => {
                let mut scaled = *self;
                scaled.scale.budget.camera_samples = ratio;
                scaled.weight(pair)
            }
        }
    }

    /// The heuristic it weighs with.
    pub fn heuristic(&self) -> Heuristic {
        self.heuristic
    }

    /// The weight w₁ of BDD=1 for one pair (x₀, x₁) of the pixel; see [`Heuristic::weight`].
    pub fn weight(&self, pair: &Pair) -> Weight {
        let scale = &self.scale;
        match self.heuristic {
            Heuristic::Bdd0 => Weight::plain(0.0),
            Heuristic::Bdd1 => Weight::plain(1.0),
            // method.md §4, eq. 11.
            Heuristic::Threshold { radius } => Weight::plain(if pair.x1.light_distance >= radius {
                1.0
            } else {
                0.0
            }),
            // method.md §4, eq. 10 with L_d dropped.
            Heuristic::AlgebraicDirect => {
                Weight::plain(algebraic(scale, pair.x0.f_tilde, pair.x1.direct))
            }
            // method.md §4, eq. 10.
            Heuristic::Algebraic => {
                Weight::plain(algebraic(scale, pair.x0.f_tilde, total_radiance(pair)))
            }
            // method.md §4, eq. 8–9.
            Heuristic::Optimal { clamp_weights } => self.optimal(pair, clamp_weights),
            Heuristic::OptimalSplit { clamp_weights } => {
                let f1 = split_scattering(pair);
                self.optimal_per_path(pair, f1, clamp_weights)
            }
            Heuristic::OptimalPath { clamp_weights } => {
                let f1 = match pair.path.kind {
                    PathKind::Merge => nonneg(pair.path.x1_scattering),
                    PathKind::OneBounce => 0.0,
                };
                self.optimal_per_path(pair, f1, clamp_weights)
            }
            // method.md §8.
            Heuristic::Balance => Weight::plain(density_share(&scale.budget, pair, 1)),
            Heuristic::Power => Weight::plain(density_share(&scale.budget, pair, 2)),
            Heuristic::Camis => Weight::plain(camis(&scale.budget, pair)),
            Heuristic::CorrectedBalance => Weight::plain(corrected_share(
                density_share(&scale.budget, pair, 1),
                self.correction,
            )),
        }
    }

    /// Eq. 8–9 in the division-safe form of method.md §4:
    /// G̃ = A/(1 − c·B), w₁ = N_B (f̃ + c·G̃)/D = W₁ + N_B·c·G̃/D.
    fn optimal(&self, pair: &Pair, clamp: bool) -> Weight {
        let terms = OptimalTerms::new(
            &self.scale,
            pair.x0.f_tilde,
            total_radiance(pair),
            pair.x1.b,
        );
        let w1 = if terms.denominator == 0.0 {
            // f̃ = 0 and L = 0: the direction carries no BDD=1 contribution at x₀, and the
            // ratio is 0/0 or c·G̃/0. This crate chooses w₁ = 0.
            0.0
        } else {
            sat(terms.partial() + sat(self.correlation / terms.denominator))
        };
        self.finish(w1, clamp)
    }

    /// The optimal weight of a path whose x₁ scatters it with BDF value `f1` (sr⁻¹; 0 for a
    /// one-bounce path, whose L₀(x₁) BDD=1 computes exactly). Stationarity of the §12
    /// functional over weights that may depend on the light path's incoming direction at x₁
    /// gives w₁ = (N_B f̃ + g)/[(N_B f̃ + f₁)(1 + κ(Q))] with
    /// Q = L₀/(N_B f̃) + ∫ ℓ/(N_B f̃ + f₁) dω₂, g = N_B·c·G̃; approximating f₁ by β = b/L_d
    /// inside Q, in division-safe form:
    /// w₁ = (N_B f̃ + g)·(N_B f̃ + β)·[N_B f̃/(N_B f̃ + f₁)] / D″ (method-notes.md).
    /// `optimal-split` passes f₁ = β for merge paths, `optimal-path` the photon's own value.
    fn optimal_per_path(&self, pair: &Pair, f1: f64, clamp: bool) -> Weight {
        let t = SplitTerms::new(
            &self.scale,
            pair.x0.f_tilde,
            pair.x1.direct,
            pair.x1.indirect,
            pair.x1.b,
        );
        let w1 = if t.denominator == 0.0 {
            0.0
        } else {
            // N_B f̃/(N_B f̃ + f₁): 1 for one-bounce paths, 0 where f̃ = 0 and f₁ > 0.
            let share = if f1 == 0.0 {
                1.0
            } else if t.camera == 0.0 {
                0.0
            } else {
                t.camera / sat(t.camera + f1)
            };
            let numerator = mul(
                mul(sat(t.camera + self.correlation), sat(t.camera + t.beta)),
                share,
            );
            sat(numerator / t.denominator)
        };
        self.finish(w1, clamp)
    }

    /// The [`Weight`] of an optimal mode from its unclamped w₁.
    fn finish(&self, w1: f64, clamp: bool) -> Weight {
        let outside_unit = !(0.0..=1.0).contains(&w1);
        Weight {
            w1: if clamp { w1.clamp(0.0, 1.0) } else { w1 },
            clamped_cb: self.clamped_cb,
            outside_unit,
        }
    }
}

/// A budget with the factor S·N_F/Φ of κ(L) computed once.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Scale {
    budget: Budget,
    /// S·N_F/Φ, W⁻¹·m².
    kappa_factor: f64,
}

impl Scale {
    fn new(budget: &Budget) -> Self {
        Scale {
            budget: *budget,
            kappa_factor: budget.photon_density_factor(),
        }
    }

    /// [`Budget::kappa`], the same bits.
    fn kappa(&self, radiance: f64) -> f64 {
        mul(self.kappa_factor, nonneg(radiance))
    }

    /// N_B f̃ (sr⁻¹) for f̃ in sr⁻¹.
    fn camera(&self, f_tilde: f64) -> f64 {
        mul(nonneg(self.budget.camera_samples), nonneg(f_tilde))
    }
}

impl fmt::Display for Heuristic {
    /// Writes [`Heuristic::name`], with the parameter where it differs from `parse`'s.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Heuristic::Threshold { radius } if radius != DEFAULT_THRESHOLD_RADIUS => {
                write!(f, "threshold (R = {radius} m)")
            }
            Heuristic::Optimal {
                clamp_weights: true,
            } => f.write_str("optimal (clamped)"),
            Heuristic::OptimalSplit {
                clamp_weights: true,
            } => f.write_str("optimal-split (clamped)"),
            Heuristic::OptimalPath {
                clamp_weights: true,
            } => f.write_str("optimal-path (clamped)"),
            _ => f.write_str(self.name()),
        }
    }
}

/// W₁ = N_B f̃ / D of method.md §4, with D = N_B f̃ + b/L + κ(L): the per-direction
/// weight used to accumulate the pixel integrals A and B (method.md §6).
///
/// `f_tilde` in sr⁻¹, `radiance` = L(x₁→x₀) = L₀ + L_d in W·m⁻²·sr⁻¹, `b` in
/// W·m⁻²·sr⁻². Guards: L = 0 takes b/L = 0 (so W₁ = 1 when f̃ > 0); f̃ = 0 gives
/// W₁ = 0. The result is in [0, 1].
pub fn w1_partial(budget: &Budget, f_tilde: f64, radiance: f64, b: f64) -> f64 {
    let terms = OptimalTerms::new(&Scale::new(budget), f_tilde, radiance, b);
    terms.partial()
}

/// The integrand factor of the pixel integrals for `optimal-split`, in W·m⁻²·sr⁻²: the
/// radiance of the direction weighted as the split weights weigh it without their correlation
/// term, N_B f̃·M with M = [L₀(N_B f̃ + β) + L_d N_B f̃]/D″ (method-notes.md, "optimal-split").
/// The renderer accumulates A += (this)·f̃·cos/p and B += (this)·cos/p; for `optimal` the same
/// role is played by W₁·L. Inputs as in [`Pair`]; the result is finite and non-negative.
pub fn split_weighted_radiance(
    budget: &Budget,
    f_tilde: f64,
    direct: f64,
    indirect: f64,
    b: f64,
) -> f64 {
    let t = SplitTerms::new(&Scale::new(budget), f_tilde, direct, indirect, b);
    if t.denominator == 0.0 {
        return 0.0;
    }
    let m = sat(mul(nonneg(direct), t.camera + t.beta) + mul(nonneg(indirect), t.camera));
    sat(t.camera * ratio_sat(m, t.denominator))
}

/// L = L₀ + L_d of one pair, W·m⁻²·sr⁻¹.
fn total_radiance(pair: &Pair) -> f64 {
    sat(nonneg(pair.x1.direct) + nonneg(pair.x1.indirect))
}

/// Eq. 10: w₁ = N_B f̃ / (N_B f̃ + κ(L)).
///
/// Evaluated as 1/(1 + κ/(N_B f̃)), which is monotone non-increasing in L even after
/// rounding. f̃ = 0 gives 0 (also when L = 0, where the ratio is 0/0).
fn algebraic(scale: &Scale, f_tilde: f64, radiance: f64) -> f64 {
    share(scale.camera(f_tilde), scale.kappa(radiance), 1, 0.0)
}

/// N_B f̃ and the denominator D of W₁ (method.md §4) for one direction.
struct OptimalTerms {
    /// N_B f̃, sr⁻¹.
    camera: f64,
    /// D = N_B f̃ + b/L + κ(L), sr⁻¹.
    denominator: f64,
}

impl OptimalTerms {
    fn new(scale: &Scale, f_tilde: f64, radiance: f64, b: f64) -> Self {
        let radiance = nonneg(radiance);
        let camera = scale.camera(f_tilde);
        // L = 0 means x₁ is unlit, hence b = 0 too: take b/L = 0 (method.md §4 guards).
        let b_over_l = if radiance == 0.0 {
            0.0
        } else {
            ratio_sat(nonneg(b), radiance)
        };
        let denominator = sat(camera + b_over_l + scale.kappa(radiance));
        OptimalTerms {
            camera,
            denominator,
        }
    }

    /// W₁ = N_B f̃ / D; 0 when f̃ = 0 (including D = 0).
    fn partial(&self) -> f64 {
        if self.camera == 0.0 {
            0.0
        } else {
            self.camera / self.denominator
        }
    }
}

/// The scalars of the split weights for one direction: N_B f̃, β = b/L_d, and
/// D″ = (N_B f̃ + β)(N_B f̃ + κ(L₀)) + κ(L_d)·N_B f̃.
struct SplitTerms {
    /// N_B f̃, sr⁻¹.
    camera: f64,
    /// β = b/L_d, sr⁻¹ (0 where L_d = 0: no secondary light, so no photon noise at x₁).
    beta: f64,
    /// D″, sr⁻².
    denominator: f64,
}

impl SplitTerms {
    fn new(scale: &Scale, f_tilde: f64, direct: f64, indirect: f64, b: f64) -> Self {
        let camera = scale.camera(f_tilde);
        let indirect = nonneg(indirect);
        let beta = if indirect == 0.0 {
            0.0
        } else {
            ratio_sat(nonneg(b), indirect)
        };
        let denominator = sat(mul(sat(camera + beta), sat(camera + scale.kappa(direct)))
            + mul(scale.kappa(indirect), camera));
        SplitTerms {
            camera,
            beta,
            denominator,
        }
    }
}

/// The x₁ scattering that `optimal-split` assumes for a path: none for one-bounce paths (L₀(x₁)
/// is exact), the cell's average β = b/L_d for merge paths.
fn split_scattering(pair: &Pair) -> f64 {
    match pair.path.kind {
        PathKind::OneBounce => 0.0,
        PathKind::Merge => {
            let indirect = nonneg(pair.x1.indirect);
            if indirect == 0.0 {
                0.0
            } else {
                ratio_sat(nonneg(pair.x1.b), indirect)
            }
        }
    }
}

/// Method.md §8: the balance (`power` = 1) or power (`power` = 2) heuristic on
/// area-measure path densities. Both densities 0 (or both infinite) give w₁ = ½.
fn density_share(budget: &Budget, pair: &Pair, power: i32) -> f64 {
    let camera = nonneg(pair.path.camera_density);
    let light = match pair.path.kind {
        // η = S·N_F and the common prefix …x₂→x₁ cancel.
        PathKind::Merge => nonneg(pair.path.light_density),
        // The photon technique pays η = S·N_F for the merge at x₀.
        PathKind::OneBounce => product(&[
            nonneg(budget.merge_area),
            nonneg(budget.photons),
            nonneg(pair.path.emission_density),
            nonneg(pair.path.light_density),
        ]),
    };
    share(camera, light, power, 0.5)
}

/// tan 1°: the angular radius of `camis`'s acceptance disk, the value the paper's code uses.
pub const ACCEPTANCE_ANGLE_TAN: f64 = 0.017_455_064_928_217_585;

/// The acceptance area A = π·(d₀·tan 1°)² of `camis`'s surrogate probabilities, m², for x₀ at
/// distance `primary_distance` (m) from the camera: a disk that subtends 1° from the camera,
/// a fixed fraction of the image rather than of the merge radius, so the surrogate does not
/// depend on r. NaN or negative distances give 0; saturates at `f64::MAX`.
pub fn acceptance_area(primary_distance: f64) -> f64 {
    let radius = mul(nonneg(primary_distance), ACCEPTANCE_ANGLE_TAN);
    mul(std::f64::consts::PI, mul(radius, radius))
}

/// min(p·A, 1), the surrogate probability that a vertex sampled with area density `density`
/// (m⁻²) lands in an acceptance region of area `area` (m²); dimensionless in [0, 1].
/// NaN or negative inputs count as 0, and 0·∞ = 0.
pub fn acceptance_probability(density: f64, area: f64) -> f64 {
    mul(nonneg(density), nonneg(area)).min(1.0)
}

/// The correlation-aware factor r = a/(a + β − a·β) for camera-prefix and light-subpath
/// surrogate probabilities a, β (clamped into [0, 1]), written as a/(a + β(1 − a)) so that it
/// stays in [0, 1] after rounding. a = β = 0 gives 1 (no information: no correction, as in the
/// paper's code); β = 0 with a > 0 gives exactly 1, and a = 1 gives exactly 1.
pub fn correlation_factor(camera: f64, light: f64) -> f64 {
    let a = nonneg(camera).min(1.0);
    let b = nonneg(light).min(1.0);
    if a == 0.0 {
        if b == 0.0 { 1.0 } else { 0.0 }
    } else {
        a / (a + b * (1.0 - a))
    }
}

/// [`Heuristic::Camis`]: the balance heuristic with BDD=1's merge at x₁ counted r times.
fn camis(budget: &Budget, pair: &Pair) -> f64 {
    match pair.path.kind {
        // BDD=1 connects to the light at x₁ and BDD=0 merges at the primary vertex: neither
        // merge is correlated in the paper's sense, so this is `balance` bit for bit.
        PathKind::OneBounce => density_share(budget, pair, 1),
        PathKind::Merge => {
            let area = nonneg(pair.x0.acceptance_area);
            // Without an acceptance area there is no surrogate to compare: no correction.
            let r = if area == 0.0 {
                1.0
            } else {
                let camera = acceptance_probability(pair.x0.primary_density, area)
                    * acceptance_probability(pair.path.camera_density, area);
                correlation_factor(camera, pair.path.light_suffix)
            };
            // Unsaturated, with 0·∞ = 0, so that r = 1 reproduces `balance` exactly, ∞ included.
            let camera_density = product(&[r, nonneg(pair.path.camera_density)]);
            share(camera_density, nonneg(pair.path.light_density), 1, 0.5)
        }
    }
}

/// The balance weight w₁ = p_C/(p_C + p_L) with BDD=1's density scaled by `c`:
/// c·p_C/(c·p_C + p_L) = c·w₁/(c·w₁ + 1 − w₁), written in w₁ alone so that a pilot that knows
/// only `balance`'s w₁ of a path can score any candidate c (`corrected-balance`).
///
/// `w1` is clamped into [0, 1] (NaN read as 0) and `c` read as 0 where NaN or negative. c = 1
/// returns w₁ exactly; c = 0 gives 0 and c = +∞ gives 1 wherever w₁ > 0. The result is in
/// [0, 1] and non-decreasing in c and in w₁.
pub fn corrected_share(w1: f64, c: f64) -> f64 {
    let w1 = nonneg(w1).min(1.0);
    if c == 1.0 {
        return w1;
    }
    // Both zero only where c·w₁ = 0 and w₁ = 1, i.e. c = 0: BDD=1 is switched off.
    share(mul(nonneg(c), w1), 1.0 - w1, 1, 0.0)
}

/// aᵖ/(aᵖ + bᵖ) for a, b ≥ 0 (possibly +∞), as 1/(1 + (b/a)ᵖ).
///
/// This form is monotone non-decreasing in a and non-increasing in b after rounding.
/// `a = 0` gives 0, except `a = b = 0` which gives `both_zero`; `a = b = ∞` gives ½.
fn share(a: f64, b: f64, power: i32, both_zero: f64) -> f64 {
    if a == 0.0 {
        if b == 0.0 { both_zero } else { 0.0 }
    } else if a.is_infinite() && b.is_infinite() {
        0.5
    } else {
        // a > 0, so b/a is in [0, ∞]; 1/(1 + ∞) = 0.
        1.0 / (1.0 + (b / a).powi(power))
    }
}

/// `x` if it is positive (including +∞), else 0: NaN and negative inputs become 0.
fn nonneg(x: f64) -> f64 {
    if x > 0.0 { x } else { 0.0 }
}

/// Saturates +∞ to `f64::MAX` (inputs are never NaN here).
fn sat(x: f64) -> f64 {
    x.min(f64::MAX)
}

/// The saturated product of two non-negative numbers, with 0·∞ = 0.
fn mul(a: f64, b: f64) -> f64 {
    if a == 0.0 || b == 0.0 {
        0.0
    } else {
        sat(a * b)
    }
}

/// The product of non-negative factors (unsaturated), with 0·∞ = 0.
fn product(factors: &[f64]) -> f64 {
    if factors.contains(&0.0) {
        0.0
    } else {
        factors.iter().product()
    }
}

/// The saturated ratio num/den of non-negative numbers; 0 when num = 0 (also 0/0), and
/// `f64::MAX` for num > 0 over den = 0.
fn ratio_sat(num: f64, den: f64) -> f64 {
    if num == 0.0 {
        0.0
    } else {
        sat(num / nonneg(den))
    }
}

#[cfg(test)]
mod tests;

// The README (the crate's page on crates.io) as a hidden item, so that `cargo test --doc`
// compiles and runs its example; the crate documentation above stays as it is.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
