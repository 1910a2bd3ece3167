//! The Gaussian lobe of method.md §9: its normalisation constant C, its directional
//! albedo table, its value, pdf and sampling. Everything that depends only on Δ is
//! computed once per distinct Δ and shared through a process-wide cache.

use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::fmt;
use std::sync::{Arc, Mutex, OnceLock};

use glam::{DVec3, Vec3};

use crate::quadrature::GaussLegendre;

/// ε of the lobe's denominator `(ε + √cos σ)(ε + √cos γ)` (method.md §9).
pub const LOBE_EPSILON: f32 = 0.1;

/// Smallest lobe width Δ accepted by [`crate::Bdf::new`]: 0.05°, in radians.
pub const LOBE_WIDTH_MIN: f32 = DELTA_MIN as f32;
/// Largest lobe width Δ accepted by [`crate::Bdf::new`]: 90°, in radians.
pub const LOBE_WIDTH_MAX: f32 = DELTA_MAX as f32;
pub(crate) const DELTA_MIN: f64 = 0.05 * PI / 180.0;
pub(crate) const DELTA_MAX: f64 = FRAC_PI_2;

/// Entries of the directional-albedo table. The grid is graded towards grazing on the
/// scale of Δ (see [`AlbedoGrid`]), so linear interpolation errs by < 2e-4 relative
/// (measured: ~1e-4 at Δ = 0.05°, ~1e-5 for Δ of a few degrees).
const TABLE_SIZE: usize = 256;
/// Gauss–Legendre nodes per panel in the lobe's radial variable.
const RADIAL_NODES: usize = 40;
/// Gauss–Legendre nodes in the azimuth around the mirror direction.
const AZIMUTH_NODES: usize = 24;

/// Everything about a lobe of width Δ that does not depend on kd or g_r.
pub(crate) struct LobeTable {
    delta: f64,
    delta2: f64,
    /// C of method.md §9: the largest constant with ∫ G cos ≤ 1 for every direction.
    c: f64,
    /// 1 / (2π Δ² (1 − e^(−2/Δ²))): the sampling density of (1 − cos ϑ, φ) at ϑ = 0.
    pdf_norm: f64,
    /// e^(−2/Δ²) − 1, the (negated) mass of the truncated exponential on [0, 2].
    neg_mass: f64,
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
            delta2,
            c,
            pdf_norm: 1.0 / (TAU * delta2 * -neg_mass),
            neg_mass,
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
        let x = self.grid.position(f64::from(z));
        let i = (x as usize).min(TABLE_SIZE - 2);
        let t = (x - i as f64).clamp(0.0, 1.0) as f32;
        let scaled = self.albedo[i] + t * (self.albedo[i + 1] - self.albedo[i]);
        scaled / (LOBE_EPSILON + z.clamp(0.0, 1.0).sqrt())
    }

    /// G(wo, wi) for directions above the surface. Written so that swapping the
    /// arguments performs the same floating-point operations: reciprocity is exact.
    pub(crate) fn value(&self, wo: Vec3, wi: Vec3) -> f32 {
        let eps = f64::from(LOBE_EPSILON);
        let denom = (eps + f64::from(wo.z).sqrt()) * (eps + f64::from(wi.z).sqrt());
        (self.c * (-self.exponent(wo, wi)).exp() / denom) as f32
    }

    /// Solid-angle pdf of [`Self::sample`] at wi (not renormalised for the horizon cut).
    pub(crate) fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        (self.pdf_norm * (-self.exponent(wo, wi)).exp()) as f32
    }

    /// (1 − cos ϑ)/Δ², ϑ the angle between wi and the mirror image of wo.
    fn exponent(&self, wo: Vec3, wi: Vec3) -> f64 {
        // 1 − cos ϑ = |wi − mirror(wo)|²/2 keeps its precision for ϑ ≪ 1, where 1 − cos ϑ
        // from a dot product would cancel catastrophically for narrow lobes.
        let (o, i) = (wo.as_dvec3(), wi.as_dvec3());
        let chord2 = (o.x + i.x).powi(2) + (o.y + i.y).powi(2) + (o.z - i.z).powi(2);
        0.5 * chord2 / self.delta2
    }

    /// Samples 1 − cos ϑ around mirror(wo) from the exponential density truncated to
    /// [0, 2] (exact inversion) and φ uniformly. May return a direction below the horizon.
    pub(crate) fn sample(&self, wo: Vec3, u1: f32, u2: f32) -> Vec3 {
        let mirror = DVec3::new(-f64::from(wo.x), -f64::from(wo.y), f64::from(wo.z)).normalize();
        let t = (-self.delta2 * (f64::from(u1) * self.neg_mass).ln_1p()).clamp(0.0, 2.0);
        let cos_t = 1.0 - t;
        let sin_t = (t * (2.0 - t)).max(0.0).sqrt();
        let (a, b) = mirror.any_orthonormal_pair();
        let (sin_p, cos_p) = (TAU * f64::from(u2)).sin_cos();
        (cos_t * mirror + sin_t * (cos_p * a + sin_p * b))
            .normalize()
            .as_vec3()
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
}

impl AlbedoGrid {
    fn new(delta: f64) -> Self {
        Self {
            scale: delta,
            span: (1.0 / delta).asinh(),
        }
    }

    fn node(&self, i: usize) -> f64 {
        let w = i as f64 / (TABLE_SIZE - 1) as f64;
        (self.scale * (self.span * w).sinh()).min(1.0)
    }

    /// Fractional index of z in the grid, in [0, n − 1].
    fn position(&self, z: f64) -> f64 {
        let w = (z.clamp(0.0, 1.0) / self.scale).asinh() / self.span;
        w * (TABLE_SIZE - 1) as f64
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
            let quad = LobeQuadrature::new(table.delta2);
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
}
