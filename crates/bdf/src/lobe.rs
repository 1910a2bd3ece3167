//! The Gaussian lobe of method.md §9: its normalisation constant C, its directional
//! albedo table, its value, pdf and sampling. Everything that depends only on Δ is
//! computed once per distinct Δ and shared through a process-wide cache.

use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::fmt;
use std::sync::{Arc, Mutex, OnceLock};

use glam::Vec3;

use crate::quadrature::GaussLegendre;

/// ε of the lobe's denominator `(ε + √cos σ)(ε + √cos γ)` (method.md §9).
pub const LOBE_EPSILON: f32 = 0.1;

/// Smallest lobe width Δ accepted by [`crate::Bdf::new`]: 0.05°, in radians.
pub const LOBE_WIDTH_MIN: f32 = DELTA_MIN as f32;
/// Largest lobe width Δ accepted by [`crate::Bdf::new`]: 90°, in radians.
pub const LOBE_WIDTH_MAX: f32 = DELTA_MAX as f32;
pub(crate) const DELTA_MIN: f64 = 0.05 * PI / 180.0;
pub(crate) const DELTA_MAX: f64 = FRAC_PI_2;

/// Exponent (1 − cos ϑ)/Δ² beyond which the lobe's value and pdf are 0: e^(−87) ≈ 1.6·10⁻³⁸
/// is about f32's smallest normal number.
const FALLOFF_CUTOFF: f32 = 87.0;

/// Entries of the directional-albedo table. The grid is graded towards grazing on the
/// scale of Δ (see [`AlbedoGrid`]), so linear interpolation errs by < 2e-4 relative
/// (measured: ~1e-4 at Δ = 0.05°, ~1e-5 for Δ of a few degrees).
const TABLE_SIZE: usize = 256;
/// Gauss–Legendre nodes per panel in the lobe's radial variable.
const RADIAL_NODES: usize = 40;
/// Gauss–Legendre nodes in the azimuth around the mirror direction.
const AZIMUTH_NODES: usize = 24;

/// Everything about a lobe of width Δ that does not depend on kd or g_r.
///
/// The table is built in f64; the per-direction work (value, pdf, sampling, albedo lookup)
/// runs in f32 from the `*_f32` copies below. It is the innermost work of the glossy
/// camera and photon stages, and f64 there cost ~24 % of a glossy run (docs/performance.md)
/// for precision the f32 inputs and outputs cannot carry: the tests in this file bound the
/// f32 results against the f64 formulas.
pub(crate) struct LobeTable {
    delta: f64,
    /// C of method.md §9: the largest constant with ∫ G cos ≤ 1 for every direction.
    c: f64,
    /// C in f32 (at most ~2·10⁵, for Δ = 0.05°).
    c_f32: f32,
    /// Δ² in f32, the scale of 1 − cos ϑ in sampling.
    delta2_f32: f32,
    /// 1/(2Δ²): the exponent (1 − cos ϑ)/Δ² is |chord|² times this.
    half_inv_delta2_f32: f32,
    /// 1 / (2π Δ² (1 − e^(−2/Δ²))): the sampling density of (1 − cos ϑ, φ) at ϑ = 0.
    pdf_norm_f32: f32,
    /// e^(−2/Δ²), the weight the exponential puts beyond the truncation at 1 − cos ϑ = 2
    /// (relative to its value at 0); zero in f32 for Δ ≲ 8°.
    tail_f32: f32,
    grid: AlbedoGrid,
    /// µ_G·(ε + √z) at the grid nodes, including C. The factor (ε + √z) is applied
    /// exactly at lookup: its square root near grazing defeats linear interpolation.
    albedo: Vec<f32>,
}

impl fmt::Debug for LobeTable {
    // The table itself is noise in a debug print; Δ and C identify the lobe.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("LobeTable")
            .field("delta", &self.delta)
            .field("c", &self.c)
            .finish_non_exhaustive()
    }
}

/// Returns the shared table for lobe width `delta` (radians), building it on first use.
pub(crate) fn lobe_table(delta: f32) -> Arc<LobeTable> {
    static CACHE: OnceLock<Mutex<HashMap<u32, Arc<LobeTable>>>> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    // Building never panics, so a poisoned lock still holds a consistent map.
    let mut map = cache.lock().unwrap_or_else(|e| e.into_inner());
    // Holding the lock while building makes concurrent first uses of one Δ build it once;
    // a build takes a few milliseconds.
    Arc::clone(
        map.entry(delta.to_bits())
            .or_insert_with(|| Arc::new(LobeTable::build(f64::from(delta)))),
    )
}

impl LobeTable {
    fn build(delta: f64) -> Self {
        let delta2 = delta * delta;
        let neg_mass = (-2.0 / delta2).exp_m1();
        let quad = LobeQuadrature::new(delta2);
        let grid = AlbedoGrid::new(delta);

        // I(z) = ∫ exp(−(1 − cos ϑ)/Δ²) cos γ / ((ε + √z)(ε + √cos γ)) dω, i.e. the lobe's
        // albedo with C = 1, at incidence cosine z.
        let unnormalised: Vec<f64> = (0..TABLE_SIZE).map(|i| quad.albedo(grid.node(i))).collect();

        // The maximum over incidence angles: at normal incidence for narrow lobes, near
        // grazing for wider ones. Refine the best node by golden-section search.
        let best = (0..TABLE_SIZE)
            .max_by(|&a, &b| unnormalised[a].total_cmp(&unnormalised[b]))
            .unwrap_or(0);
        let lo = grid.node(best.saturating_sub(1));
        let hi = grid.node((best + 1).min(TABLE_SIZE - 1));
        let max = golden_section_max(lo, hi, |z| quad.albedo(z)).max(unnormalised[best]);
        let c = 1.0 / max;
        let eps = f64::from(LOBE_EPSILON);

        Self {
            delta,
            c,
            c_f32: c as f32,
            delta2_f32: delta2 as f32,
            half_inv_delta2_f32: (0.5 / delta2) as f32,
            pdf_norm_f32: (1.0 / (TAU * delta2 * -neg_mass)) as f32,
            tail_f32: (-2.0 / delta2).exp() as f32,
            grid,
            albedo: (0..TABLE_SIZE)
                .map(|i| (c * unnormalised[i] * (eps + grid.node(i).sqrt())) as f32)
                .collect(),
        }
    }

    /// Δ in radians.
    pub(crate) fn delta(&self) -> f32 {
        self.delta as f32
    }

    /// The normalisation constant C.
    pub(crate) fn c(&self) -> f64 {
        self.c
    }

    /// Directional albedo µ_G(z) = ∫ G(ω, ωᵢ) cos θᵢ dωᵢ for cos θ = z ∈ [0, 1].
    pub(crate) fn albedo(&self, z: f32) -> f32 {
        let x = self.grid.position(z);
        let i = (x as usize).min(TABLE_SIZE - 2);
        let t = (x - i as f32).clamp(0.0, 1.0);
        let scaled = self.albedo[i] + t * (self.albedo[i + 1] - self.albedo[i]);
        scaled / (LOBE_EPSILON + z.clamp(0.0, 1.0).sqrt())
    }

    /// G(wo, wi) for directions above the surface. Written so that swapping the
    /// arguments performs the same floating-point operations: reciprocity is exact.
    pub(crate) fn value(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.value_from(wo, wi, self.falloff(wo, wi))
    }

    /// Solid-angle pdf of [`Self::sample`] at wi (not renormalised for the horizon cut).
    pub(crate) fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.pdf_from(self.falloff(wo, wi))
    }

    /// ([`Self::value`], [`Self::pdf`]) with one exponential: bit-identical to the two calls.
    pub(crate) fn value_and_pdf(&self, wo: Vec3, wi: Vec3) -> (f32, f32) {
        let falloff = self.falloff(wo, wi);
        (self.value_from(wo, wi, falloff), self.pdf_from(falloff))
    }

    fn value_from(&self, wo: Vec3, wi: Vec3, falloff: f32) -> f32 {
        let denom = (LOBE_EPSILON + wo.z.sqrt()) * (LOBE_EPSILON + wi.z.sqrt());
        self.c_f32 * falloff / denom
    }

    fn pdf_from(&self, falloff: f32) -> f32 {
        self.pdf_norm_f32 * falloff
    }

    /// exp(−(1 − cos ϑ)/Δ²), ϑ the angle between wi and the mirror image of wo.
    fn falloff(&self, wo: Vec3, wi: Vec3) -> f32 {
        // 1 − cos ϑ = |wi − mirror(wo)|²/2 keeps its precision for ϑ ≪ 1, where 1 − cos ϑ
        // from a dot product would cancel catastrophically for narrow lobes (in f32 it would
        // be noise below ϑ ≈ 3·10⁻⁴, the scale of a 0.05° lobe). Each difference here is of
        // two f32 inputs, so the exponent x carries a relative error of a few ulp and
        // exp(−x) one of a few ulp times x: < 10⁻⁵ wherever the lobe is not negligible.
        let chord2 = (wo.x + wi.x).powi(2) + (wo.y + wi.y).powi(2) + (wo.z - wi.z).powi(2);
        let x = chord2 * self.half_inv_delta2_f32;
        // Past x = 87 exp(−x) is below f32's smallest normal number, and libm's expf takes a
        // slow path there (for x > 104 one that sets errno) that showed up in profiles of
        // narrow lobes evaluated far from the mirror. The lobe is then < 10⁻³⁷ of its peak,
        // so it is 0; written as a select rather than a branch, as x is unpredictable.
        let falloff = (-x.min(FALLOFF_CUTOFF)).exp();
        if x < FALLOFF_CUTOFF { falloff } else { 0.0 }
    }

    /// Samples 1 − cos ϑ around mirror(wo) from the exponential density truncated to
    /// [0, 2] (exact inversion) and φ uniformly. May return a direction below the horizon.
    pub(crate) fn sample(&self, wo: Vec3, u1: f32, u2: f32) -> Vec3 {
        let mirror = Vec3::new(-wo.x, -wo.y, wo.z).normalize();
        // t = 1 − cos ϑ by inversion: t = −Δ²·ln(1 − u1·(1 − e^(−2/Δ²))), with the argument of
        // the logarithm written (1 − u1) + u1·e^(−2/Δ²). Formed as 1 + u1·(e^(−2/Δ²) − 1) in f32
        // it would lose all precision as u1 → 1 where the mass rounds to (nearly) 1, sending
        // tail samples of Δ ≈ 15°–25° far off. Here 1 − u1 is exact for u1 ≥ 1/2 (and for every
        // 24-bit uniform), so the logarithm's argument carries a relative error of an ulp or two
        // and t/Δ², the exponent that sets the pdf, an absolute one of ~10⁻⁷.
        let t = (-self.delta2_f32 * ((1.0 - u1) + u1 * self.tail_f32).ln()).clamp(0.0, 2.0);
        // cos ϑ = 1 − t rounds away most of t for narrow lobes, but the direction's angle from
        // the mirror is fixed by sin ϑ (from t, not from cos ϑ), which keeps its precision.
        let cos_t = 1.0 - t;
        let sin_t = (t * (2.0 - t)).max(0.0).sqrt();
        let (a, b) = mirror.any_orthonormal_pair();
        let (sin_p, cos_p) = (std::f32::consts::TAU * u2).sin_cos();
        (cos_t * mirror + sin_t * (cos_p * a + sin_p * b)).normalize()
    }
}

/// Quadrature of the lobe's albedo (with C = 1), in polar coordinates (ϑ, φ) around the
/// mirror direction, clipped to the upper hemisphere.
struct LobeQuadrature {
    delta2: f64,
    radial: GaussLegendre,
    azimuth: GaussLegendre,
}

impl LobeQuadrature {
    fn new(delta2: f64) -> Self {
        Self {
            delta2,
            radial: GaussLegendre::new(RADIAL_NODES),
            azimuth: GaussLegendre::new(AZIMUTH_NODES),
        }
    }

    /// I(z) = ∫_{ω.z>0} exp(−(1 − cos ϑ)/Δ²) cos γ / ((ε + √z)(ε + √cos γ)) dω.
    fn albedo(&self, cos_s: f64) -> f64 {
        let eps = f64::from(LOBE_EPSILON);
        let delta2 = self.delta2;
        let cos_s = cos_s.clamp(0.0, 1.0);
        let sin_s = (1.0 - cos_s * cos_s).max(0.0).sqrt();
        // With τ = (1 − cos ϑ)/Δ² and s = 1 − e^(−τ), dω = Δ² e^τ ds dφ: the Gaussian factor
        // cancels and s ∈ [0, 1 − e^(−2/Δ²)] resolves the lobe on the scale of Δ.
        let s_max = -(-2.0 / delta2).exp_m1();
        // The lobe starts to cross the horizon at ϑ = π/2 − σ; the integrand has a kink
        // there, so it gets a panel boundary.
        let s_kink = (-(-(1.0 - sin_s) / delta2).exp_m1()).min(s_max);
        let ring = |s: f64| {
            let t = (-delta2 * (-s).ln_1p()).min(2.0);
            let cos_t = 1.0 - t;
            let sin_t = (t * (2.0 - t)).max(0.0).sqrt();
            // In a frame whose first tangent lies in the plane of the mirror direction and
            // the normal, cos γ = base + amp·cos φ.
            let base = cos_t * cos_s;
            let amp = sin_t * sin_s;
            let phi_max = if base >= amp {
                PI
            } else if base <= -amp {
                0.0
            } else {
                (-base / amp).acos()
            };
            2.0 * self.azimuth.integrate(0.0, phi_max, |phi| {
                let cos_g = (base + amp * phi.cos()).max(0.0);
                cos_g / (eps + cos_g.sqrt())
            })
        };
        let integral =
            self.radial.integrate(0.0, s_kink, ring) + self.radial.integrate(s_kink, s_max, ring);
        delta2 * integral / (eps + cos_s.sqrt())
    }
}

/// Grid of cosines z_j = s·sinh(A·j/(n − 1)) on [0, 1] with s = Δ: spacing ~Δ/50 near
/// grazing, where the horizon clips the lobe, and a constant ~2% ratio elsewhere.
#[derive(Clone, Copy, Debug)]
struct AlbedoGrid {
    scale: f64,
    span: f64,
    /// 1/s in f32, for the lookup.
    inv_scale_f32: f32,
    /// (n − 1)/A in f32, for the lookup.
    nodes_per_span_f32: f32,
}

impl AlbedoGrid {
    fn new(delta: f64) -> Self {
        let span = (1.0 / delta).asinh();
        Self {
            scale: delta,
            span,
            inv_scale_f32: (1.0 / delta) as f32,
            nodes_per_span_f32: ((TABLE_SIZE - 1) as f64 / span) as f32,
        }
    }

    fn node(&self, i: usize) -> f64 {
        let w = i as f64 / (TABLE_SIZE - 1) as f64;
        (self.scale * (self.span * w).sinh()).min(1.0)
    }

    /// Fractional index of z in the grid, in [0, n − 1] (up to rounding).
    fn position(&self, z: f32) -> f32 {
        let x = z.clamp(0.0, 1.0) * self.inv_scale_f32;
        // asinh(x) = ln(x + √(x² + 1)) directly rather than std's asinh (which goes through
        // hypot and ln_1p, the costly part of a lookup). Near x = 0 this loses relative, not
        // absolute, precision: the index errs by < 10⁻⁴ of a grid step everywhere, which is
        // what matters for linear interpolation.
        (x + (x * x + 1.0).sqrt()).ln() * self.nodes_per_span_f32
    }
}

/// Maximum of a unimodal f on [a, b] by golden-section search.
fn golden_section_max(mut a: f64, mut b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let r = 0.5 * (5f64.sqrt() - 1.0);
    let mut x1 = b - r * (b - a);
    let mut x2 = a + r * (b - a);
    let (mut f1, mut f2) = (f(x1), f(x2));
    let mut best = f(a).max(f(b));
    for _ in 0..40 {
        if f1 > f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - r * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + r * (b - a);
            f2 = f(x2);
        }
        best = best.max(f1).max(f2);
        if b - a < 1e-9 {
            break;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_delta_shares_one_table() {
        let a = lobe_table(0.123);
        let b = lobe_table(0.123);
        assert!(Arc::ptr_eq(&a, &b));
        assert!(!Arc::ptr_eq(&a, &lobe_table(0.124)));
    }

    #[test]
    fn quadrature_converges() {
        // The production rule against a much finer one, over the range of Δ and angles.
        for deg in [0.05f64, 0.5, 1.5, 5.0, 30.0, 90.0] {
            let delta2 = deg.to_radians().powi(2);
            let coarse = LobeQuadrature::new(delta2);
            let fine = LobeQuadrature {
                delta2,
                radial: GaussLegendre::new(400),
                azimuth: GaussLegendre::new(200),
            };
            for z in [0.0, 1e-4, 0.003, 0.02, 0.1, 0.5, 0.9, 1.0] {
                let (c, f) = (coarse.albedo(z), fine.albedo(z));
                assert!((c / f - 1.0).abs() < 1e-4, "Δ={deg}° z={z}: {c} vs {f}");
            }
        }
    }

    #[test]
    fn interpolated_albedo_matches_quadrature() {
        for deg in [0.05f32, 0.5, 5.0, 30.0, 90.0] {
            let table = lobe_table(deg.to_radians());
            let quad = LobeQuadrature::new(table.delta * table.delta);
            for k in 0..97 {
                // Off-node cosines, dense near grazing.
                let z = (k as f64 / 96.0).powi(3) * 0.999_7 + 1.3e-6;
                let want = table.c * quad.albedo(z);
                let got = f64::from(table.albedo(z as f32));
                assert!(
                    (got / want - 1.0).abs() < 2e-4,
                    "Δ={deg}° z={z}: {got} vs {want}"
                );
            }
        }
    }
    /// The f64 formulas the library used before its per-direction work moved to f32: the
    /// reference the f32 code is held to.
    mod reference {
        use super::*;
        use glam::DVec3;

        /// (1 − cos ϑ)/Δ² from the chord, in f64.
        pub(super) fn exponent(t: &LobeTable, wo: Vec3, wi: Vec3) -> f64 {
            let (o, i) = (wo.as_dvec3(), wi.as_dvec3());
            let chord2 = (o.x + i.x).powi(2) + (o.y + i.y).powi(2) + (o.z - i.z).powi(2);
            0.5 * chord2 / (t.delta * t.delta)
        }

        pub(super) fn value(t: &LobeTable, wo: Vec3, wi: Vec3) -> f64 {
            let eps = f64::from(LOBE_EPSILON);
            let denom = (eps + f64::from(wo.z).sqrt()) * (eps + f64::from(wi.z).sqrt());
            t.c * (-exponent(t, wo, wi)).exp() / denom
        }

        fn neg_mass(t: &LobeTable) -> f64 {
            (-2.0 / (t.delta * t.delta)).exp_m1()
        }

        pub(super) fn pdf(t: &LobeTable, wo: Vec3, wi: Vec3) -> f64 {
            let delta2 = t.delta * t.delta;
            (-exponent(t, wo, wi)).exp() / (TAU * delta2 * -neg_mass(t))
        }

        pub(super) fn sample(t: &LobeTable, wo: Vec3, u1: f32, u2: f32) -> DVec3 {
            let delta2 = t.delta * t.delta;
            let mirror =
                DVec3::new(-f64::from(wo.x), -f64::from(wo.y), f64::from(wo.z)).normalize();
            let tt = (-delta2 * (f64::from(u1) * neg_mass(t)).ln_1p()).clamp(0.0, 2.0);
            let cos_t = 1.0 - tt;
            let sin_t = (tt * (2.0 - tt)).max(0.0).sqrt();
            let (a, b) = mirror.any_orthonormal_pair();
            let (sin_p, cos_p) = (TAU * f64::from(u2)).sin_cos();
            (cos_t * mirror + sin_t * (cos_p * a + sin_p * b)).normalize()
        }

        pub(super) fn albedo(t: &LobeTable, z: f64) -> f64 {
            let g = t.grid;
            let x = (z.clamp(0.0, 1.0) / g.scale).asinh() / g.span * (TABLE_SIZE - 1) as f64;
            let i = (x as usize).min(TABLE_SIZE - 2);
            let f = (x - i as f64).clamp(0.0, 1.0);
            let (a, b) = (f64::from(t.albedo[i]), f64::from(t.albedo[i + 1]));
            (a + f * (b - a)) / (f64::from(LOBE_EPSILON) + z.clamp(0.0, 1.0).sqrt())
        }
    }

    /// Widths from the narrowest to the widest, with 15°–25° where the truncated
    /// exponential's mass 1 − e^(−2/Δ²) stops rounding to 1 in f32.
    const WIDTHS_DEG: [f32; 10] = [0.05, 0.2, 0.5, 1.5, 5.0, 15.0, 20.0, 25.0, 45.0, 90.0];
    const VIEW_DEG: [f32; 7] = [0.0, 1.0, 30.0, 60.0, 85.0, 89.0, 89.9];

    fn direction(theta_deg: f32, phi: f32) -> Vec3 {
        let (s, c) = theta_deg.to_radians().sin_cos();
        Vec3::new(s * phi.cos(), s * phi.sin(), c).normalize()
    }

    /// Incident directions around the mirror of wo at ϑ = k·Δ, plus a spread over the
    /// hemisphere, all above the horizon.
    fn incident_directions(delta: f32, wo: Vec3) -> Vec<Vec3> {
        let mirror = Vec3::new(-wo.x, -wo.y, wo.z).normalize();
        let (a, b) = mirror.any_orthonormal_pair();
        let mut out = Vec::new();
        for k in [0.0f32, 1e-3, 0.05, 0.3, 1.0, 2.0, 3.0, 5.0, 8.0, 12.0] {
            let theta = (k * delta).min(std::f32::consts::PI);
            for j in 0..8 {
                let phi = j as f32 * std::f32::consts::FRAC_PI_4 + 0.1;
                let w = theta.cos() * mirror + theta.sin() * (phi.cos() * a + phi.sin() * b);
                out.push(w.normalize());
            }
        }
        for i in 0..24 {
            for j in 0..12 {
                out.push(direction(
                    i as f32 * 3.75 + 0.5,
                    j as f32 * std::f32::consts::FRAC_PI_6 + 0.2,
                ));
            }
        }
        out.retain(|w| w.z > 0.0);
        out
    }

    /// Relative tolerance of the f32 value and pdf at exponent x = (1 − cos ϑ)/Δ²: a few ulp
    /// of f32 (6·10⁻⁸) for the arithmetic, plus the error of x (a few ulp of x) carried
    /// through the exponential. At the peak (x ≤ 1) this is ≤ 3·10⁻⁶; 1 − cos ϑ from an f32
    /// dot product instead of the chord errs by 10–100 % there for Δ ≤ 0.5°.
    fn tolerance(x: f64) -> f64 {
        2e-6 + 1e-6 * x
    }

    #[test]
    fn f32_value_and_pdf_match_the_f64_formulas() {
        let mut worst = 0.0f64;
        let mut checked = 0;
        for deg in WIDTHS_DEG {
            let delta = deg.to_radians();
            let table = lobe_table(delta);
            for view in VIEW_DEG {
                let wo = direction(view, 0.7);
                for wi in incident_directions(delta, wo) {
                    let x = reference::exponent(&table, wo, wi);
                    let (g, p) = table.value_and_pdf(wo, wi);
                    assert_eq!((g, p), (table.value(wo, wi), table.pdf(wo, wi)));
                    for (what, got, want) in [
                        ("value", g, reference::value(&table, wo, wi)),
                        ("pdf", p, reference::pdf(&table, wo, wi)),
                    ] {
                        // Past x = 87 the f32 lobe is cut to 0 (FALLOFF_CUTOFF): it is then
                        // below 10⁻³⁷ of its peak and only has to stay tiny.
                        if x > 80.0 {
                            assert!(f64::from(got) < 1e-30, "{what} Δ={deg}° x={x}: {got}");
                            continue;
                        }
                        let rel = (f64::from(got) / want - 1.0).abs();
                        assert!(
                            rel <= tolerance(x),
                            "{what} Δ={deg}° θo={view}° wi={wi} x={x}: {got} vs {want} ({rel:.2e})"
                        );
                        worst = worst.max(rel / tolerance(x));
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 10_000, "{checked}");
        eprintln!("worst error / tolerance of value and pdf: {worst:.3} over {checked} points");
    }

    #[test]
    fn f32_sampling_matches_the_f64_formula() {
        // Uniform numbers the way the renderer makes them (24-bit), including both ends.
        let mut us: Vec<f32> = (0..=64).map(|k| k as f32 / 64.0).collect();
        us.extend([
            1.0 / 16_777_216.0,
            1.0 - 1.0 / 16_777_216.0,
            1.0 - 16.0 / 16_777_216.0,
        ]);
        us.retain(|&u| u < 1.0);
        let mut worst = 0.0f64;
        for deg in WIDTHS_DEG {
            let delta = deg.to_radians();
            let table = lobe_table(delta);
            for view in VIEW_DEG {
                let wo = direction(view, 0.7);
                let mirror = Vec3::new(-wo.x, -wo.y, wo.z).normalize().as_dvec3();
                for &u1 in &us {
                    for &u2 in us.iter().step_by(4) {
                        let got = table.sample(wo, u1, u2);
                        let want = reference::sample(&table, wo, u1, u2);
                        assert!((got.length() - 1.0).abs() < 1e-6, "{got}");
                        let name = format!("Δ={deg}° θo={view}° u=({u1}, {u2}): {got} vs {want}");
                        // The sample's density is a function of the exponent x = (1 − cos ϑ)/Δ²
                        // alone, in the measure d(cos ϑ)·dφ: what must match is x and the
                        // azimuth. An error dx in x is a relative error dx of the pdf at the
                        // sample. Allowed: 10⁻⁶ relative, plus what rounding the direction to
                        // f32 (a chord of ~6·10⁻⁸ per component; 4·10⁻⁷ allowed) does to x,
                        // √(2x)·4·10⁻⁷/Δ, which f64 sampling had too.
                        let d = f64::from(delta);
                        let x_of = |w: glam::DVec3| 0.5 * (w - mirror).length_squared() / (d * d);
                        let (x_got, x_want) = (x_of(got.as_dvec3()), x_of(want));
                        let tol = 1e-6 * (1.0 + x_want) + (2.0 * x_want).sqrt() * 4e-7 / d;
                        let dx = (x_got - x_want).abs();
                        assert!(dx <= tol, "{name}: x {x_got} vs {x_want}");
                        // The azimuthal part of the difference (perpendicular to both the
                        // mirror and the radial direction), as a chord: ≤ 10⁻⁶, some 17 ulp of a
                        // unit vector (the frame, sin_cos and the normalisation each add a few;
                        // measured up to ~7). The pdf does not depend on the azimuth.
                        let e_phi = mirror.cross(want).normalize_or_zero();
                        let azimuthal = (got.as_dvec3() - want).dot(e_phi).abs();
                        assert!(azimuthal <= 1e-6, "{name}: azimuthal error {azimuthal:.2e}");
                        worst = worst.max(dx / tol).max(azimuthal / 1e-6);
                    }
                }
            }
        }
        eprintln!("worst sample error / tolerance (exponent or azimuth): {worst:.3}");
    }

    #[test]
    fn f32_albedo_lookup_matches_the_f64_lookup() {
        let mut worst = 0.0f64;
        for deg in WIDTHS_DEG {
            let table = lobe_table(deg.to_radians());
            for k in 0..=4000 {
                // Dense near grazing, where the grid is too.
                let z = (k as f32 / 4000.0).powi(3);
                let got = f64::from(table.albedo(z));
                let want = reference::albedo(&table, f64::from(z));
                let rel = if want == 0.0 {
                    got
                } else {
                    (got / want - 1.0).abs()
                };
                // The index errs by < 10⁻⁴ of a step and the table moves ≤ ~2 % per step.
                assert!(rel < 2e-6, "Δ={deg}° z={z}: {got} vs {want} ({rel:.2e})");
                worst = worst.max(rel);
            }
        }
        eprintln!("worst relative error of the albedo lookup: {worst:.2e}");
    }
}
