//! Warps from uniform numbers in [0, 1)² to directions, with their solid-angle densities.
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Shirley–Chiu concentric map from the unit square to the unit disk (area preserving).
#[inline]
pub fn concentric_disk(u: [f32; 2]) -> Vec2 {
    let a = 2.0 * u[0] - 1.0;
    let b = 2.0 * u[1] - 1.0;
    if a == 0.0 && b == 0.0 {
        return Vec2::ZERO;
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, (PI / 4.0) * (b / a))
    } else {
        (b, PI / 2.0 - (PI / 4.0) * (a / b))
    };
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// Uniform direction on the unit sphere; density `1/(4π)` per steradian.
#[inline]
pub fn uniform_sphere(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`uniform_sphere`] in sr⁻¹.
pub const UNIFORM_SPHERE_PDF: f32 = 1.0 / (4.0 * PI);

/// Uniform point on a triangle as barycentrics (b1, b2), weight of v0 = 1 − b1 − b2.
#[inline]
pub fn uniform_triangle(u: [f32; 2]) -> (f32, f32) {
    // Square-root parametrisation: exact area uniformity, no rejection.
    let s = u[0].sqrt();
    (1.0 - s, u[1] * s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Domain, Rng};

    #[test]
    fn uniform_sphere_is_centred() {
        let mut rng = Rng::new(4, Domain::Other, [0; 3]);
        let n = 200_000;
        let mut mean = glam::DVec3::ZERO;
        for _ in 0..n {
            let d = uniform_sphere(rng.uniform2());
            mean += d.as_dvec3();
        }
        mean /= n as f64;
        // Each coordinate has variance 1/3: 5 SE ≈ 6.5e-3.
        assert!(mean.abs().max_element() < 6.5e-3, "{mean}");
    }
}
