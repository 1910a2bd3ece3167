//! Helpers shared by the integration tests: random numbers, directions, the polar frame
//! around a mirror direction, and a Gauss–Legendre rule.

#![allow(dead_code, unreachable_pub)]

use glam::{DVec3, Vec3};
use rand_pcg::Pcg64;
use rand_pcg::rand_core::{Rng, SeedableRng};

pub fn rng(seed: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seed)
}

/// Uniform in [0, 1).
pub fn uf(rng: &mut Pcg64) -> f32 {
    (rng.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
}

pub fn u3(rng: &mut Pcg64) -> [f32; 3] {
    [uf(rng), uf(rng), uf(rng)]
}

/// Outgoing direction at polar angle `theta_deg` and a fixed, non-axial azimuth.
pub fn direction(theta_deg: f64) -> Vec3 {
    let (st, ct) = theta_deg.to_radians().sin_cos();
    let (sp, cp) = 0.7f64.sin_cos();
    DVec3::new(st * cp, st * sp, ct).as_vec3()
}

/// Uniformly distributed direction on the upper hemisphere.
pub fn uniform_hemisphere(rng: &mut Pcg64) -> Vec3 {
    let z = 1.0 - uf(rng);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (std::f32::consts::TAU * uf(rng)).sin_cos();
    Vec3::new(r * c, r * s, z)
}

pub fn close(a: Vec3, b: Vec3, rel: f32) -> bool {
    (a - b).abs().max_element() <= rel * a.abs().max(b.abs()).max_element().max(1e-30)
}

/// Polar coordinates (t = 1 − cos ϑ, φ) around the mirror image r of wo, in the frame whose
/// first tangent `a` lies in the plane of r and the normal (a.z ≥ 0) and whose second
/// tangent is horizontal; so a direction's height is cos ϑ·r.z + sin ϑ·sin σ·cos φ.
pub struct MirrorFrame {
    pub r: DVec3,
    pub a: DVec3,
    pub b: DVec3,
}

impl MirrorFrame {
    pub fn new(wo: Vec3) -> Self {
        let r = DVec3::new(-f64::from(wo.x), -f64::from(wo.y), f64::from(wo.z)).normalize();
        let a = (DVec3::Z - r.z * r).try_normalize().unwrap_or(DVec3::X);
        let b = r.cross(a);
        Self { r, a, b }
    }

    pub fn cos_sigma(&self) -> f64 {
        self.r.z
    }

    pub fn sin_sigma(&self) -> f64 {
        self.a.z
    }

    /// (t, φ) of a direction, t = 1 − cos ϑ ∈ [0, 2], φ ∈ [−π, π].
    pub fn coords(&self, w: Vec3) -> (f64, f64) {
        let w = w.as_dvec3();
        let t = 0.5 * (w - self.r).length_squared();
        (t.clamp(0.0, 2.0), w.dot(self.b).atan2(w.dot(self.a)))
    }

    pub fn direction(&self, t: f64, phi: f64) -> Vec3 {
        let cos_t = 1.0 - t;
        let sin_t = (t * (2.0 - t)).max(0.0).sqrt();
        let (s, c) = phi.sin_cos();
        (cos_t * self.r + sin_t * (c * self.a + s * self.b))
            .normalize()
            .as_vec3()
    }

    /// Half-width of the azimuth range above the horizon at t: |φ| < φ_max(t).
    pub fn phi_max(&self, t: f64) -> f64 {
        let base = (1.0 - t) * self.cos_sigma();
        let amp = (t * (2.0 - t)).max(0.0).sqrt() * self.sin_sigma();
        if base >= amp {
            std::f64::consts::PI
        } else if base <= -amp {
            0.0
        } else {
            (-base / amp).acos()
        }
    }
}

/// n-point Gauss–Legendre nodes and weights on [−1, 1] (an independent copy of the
/// crate's private rule, so the tests do not rely on it).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut d = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let k = k as f64;
                    let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                    p0 = p1;
                    p1 = p2;
                }
                d = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / d;
                x -= dx;
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * d * d))
        })
        .collect()
}

/// p-value of a chi-square statistic with `dof` degrees of freedom: the upper tail
/// P(X ≥ chi2) of the chi-square distribution (statrs).
pub fn chi2_p_value(chi2: f64, dof: usize) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    ChiSquared::new(dof as f64)
        .expect("at least one degree of freedom")
        .sf(chi2)
}
