//! Solid-angle sampling of a triangle seen from a point: a direction uniform over the
//! spherical triangle that the planar one projects to on the unit sphere about the point
//! (Arvo 1995, "Stratified sampling of spherical triangles"), and the solid angle Ω of that
//! spherical triangle (Van Oosterom and Strackee 1983), whose inverse is the direction's
//! density, sr⁻¹.
//!
//! Computed in f64: the angles of a small spherical triangle sum to π plus its area, which
//! f32 would resolve to about 10⁻⁷ sr, and the arc construction divides by sines of those
//! angles. Callers keep their f32 positions; only this arithmetic is wider.

use glam::{DVec3, Vec3};

/// The solid angle (sr) of triangle `v` seen from `p`: Ω = 2·atan2(|a·(b × c)|, 1 + a·b +
/// b·c + c·a) for the unit directions a, b, c from `p` to the vertices (Van Oosterom and
/// Strackee's formula, exact up to rounding for any Ω in [0, 2π]). 0 for a degenerate
/// triangle or a point on its plane.
pub fn solid_angle(p: Vec3, v: [Vec3; 3]) -> f64 {
    let Some([a, b, c]) = directions(p, v) else {
        return 0.0;
    };
    solid_angle_of(a, b, c)
}

/// Unit directions from `p` to the vertices `v`, in f64; `None` if `p` is on a vertex.
fn directions(p: Vec3, v: [Vec3; 3]) -> Option<[DVec3; 3]> {
    let p = p.as_dvec3();
    let d = v.map(|x| (x.as_dvec3() - p).normalize_or_zero());
    (d.iter().all(|x| *x != DVec3::ZERO)).then_some(d)
}

fn solid_angle_of(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let triple = a.dot(b.cross(c)).abs();
    let denom = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    2.0 * triple.atan2(denom)
}

/// The angle between two unit vectors, accurate near 0 and π (where acos of the dot product
/// loses half its digits).
fn angle_between(x: DVec3, y: DVec3) -> f64 {
    if x.dot(y) < 0.0 {
        std::f64::consts::PI - 2.0 * ((x + y).length() / 2.0).min(1.0).asin()
    } else {
        2.0 * ((y - x).length() / 2.0).min(1.0).asin()
    }
}

/// The component of unit `x` orthogonal to unit `axis`, normalised (zero if `x` is along it).
fn orthogonal(x: DVec3, axis: DVec3) -> DVec3 {
    (x - axis * x.dot(axis)).normalize_or_zero()
}

/// A unit direction uniform over the spherical triangle of `v` seen from `p` (numbers `u`),
/// as the point where it meets the planar triangle: (barycentrics (b₁, b₂) of `v[1]`, `v[2]`,
/// the solid angle Ω in sr, whose inverse is the density). `None` for a degenerate triangle,
/// a point on its plane or a sample lost to rounding.
pub fn sample(p: Vec3, v: [Vec3; 3], u: [f32; 2]) -> Option<(f32, f32, f64)> {
    let [a, b, c] = directions(p, v)?;
    let omega = solid_angle_of(a, b, c);
    let n_ab = a.cross(b).normalize_or_zero();
    let n_bc = b.cross(c).normalize_or_zero();
    let n_ca = c.cross(a).normalize_or_zero();
    if omega <= 0.0 || n_ab == DVec3::ZERO || n_bc == DVec3::ZERO || n_ca == DVec3::ZERO {
        return None;
    }
    // The interior angles at a, b, c: between the great circles through each pair.
    let alpha = angle_between(n_ab, -n_ca);
    let beta = angle_between(n_bc, -n_ab);
    let gamma = angle_between(n_ca, -n_bc);
    // Arvo's construction: the sub-triangle (a, b, c') of area u₀·A fixes c' on the arc a–c,
    // then the direction is on the arc b–c' at a cosine uniform in u₁.
    let area = (alpha + beta + gamma - std::f64::consts::PI).max(0.0);
    let sub = u[0] as f64 * area;
    let (s, t) = (sub - alpha).sin_cos();
    let (sin_a, cos_a) = alpha.sin_cos();
    let uu = t - cos_a;
    let vv = s + sin_a * a.dot(b);
    let q = ((vv * t - uu * s) * cos_a - vv) / ((vv * s + uu * t) * sin_a);
    if !q.is_finite() {
        return None;
    }
    let q = q.clamp(-1.0, 1.0);
    let c_sub = a * q + orthogonal(c, a) * (1.0 - q * q).max(0.0).sqrt();
    let z = 1.0 - u[1] as f64 * (1.0 - c_sub.dot(b));
    let w = b * z + orthogonal(c_sub, b) * (1.0 - z * z).max(0.0).sqrt();
    let (b1, b2) = barycentrics(p.as_dvec3(), v.map(Vec3::as_dvec3), w)?;
    Some((b1 as f32, b2 as f32, omega))
}

/// Where the ray from `p` along `w` meets the plane of triangle `v`: its barycentrics
/// (b₁, b₂) of `v[1]`, `v[2]`, clamped into the triangle (rounding can put a direction at an
/// edge a hair outside). `None` if the ray is parallel to the plane.
fn barycentrics(p: DVec3, v: [DVec3; 3], w: DVec3) -> Option<(f64, f64)> {
    let e1 = v[1] - v[0];
    let e2 = v[2] - v[0];
    let s1 = w.cross(e2);
    let det = s1.dot(e1);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let s = p - v[0];
    let mut b1 = (s.dot(s1) / det).clamp(0.0, 1.0);
    let mut b2 = (w.dot(s.cross(e1)) / det).clamp(0.0, 1.0);
    if b1 + b2 > 1.0 {
        let sum = b1 + b2;
        b1 /= sum;
        b2 /= sum;
    }
    Some((b1, b2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_stats::mean_se;
    use bdpm_core::{Domain, Rng};

    /// ∫ g(ω) dω over the triangle's solid angle by a midpoint quadrature in area measure
    /// (g·cos θₑ/d² dA), independent of the formulas under test.
    fn quadrature(p: Vec3, v: [Vec3; 3], g: impl Fn(DVec3) -> f64) -> f64 {
        let [a, b, c] = v.map(Vec3::as_dvec3);
        let p = p.as_dvec3();
        let n = (b - a).cross(c - a);
        let area = n.length() / 2.0;
        let n = n.normalize();
        let k = 600;
        let mut sum = 0.0;
        // Sub-triangles of a k × k split: the upright ones at (i, j) and the inverted ones.
        for i in 0..k {
            for j in 0..k - i {
                let mut at = |b1: f64, b2: f64| {
                    let x = a + (b - a) * b1 + (c - a) * b2;
                    let to = x - p;
                    let d2 = to.length_squared();
                    let w = to / d2.sqrt();
                    sum += g(w) * w.dot(n).abs() / d2;
                };
                let (i, j, k) = (i as f64, j as f64, k as f64);
                at((i + 1.0 / 3.0) / k, (j + 1.0 / 3.0) / k);
                if i + j + 2.0 <= k {
                    at((i + 2.0 / 3.0) / k, (j + 2.0 / 3.0) / k);
                }
            }
        }
        sum * area / (k * k) as f64
    }

    fn triangles() -> Vec<(Vec3, [Vec3; 3])> {
        let tri = [
            Vec3::new(-0.3, 1.0, -0.2),
            Vec3::new(0.4, 1.0, -0.1),
            Vec3::new(0.1, 1.0, 0.5),
        ];
        vec![
            // Far, near, oblique and nearly grazing views of one triangle.
            (Vec3::new(0.0, -3.0, 0.0), tri),
            (Vec3::new(0.05, 0.9, 0.05), tri),
            (Vec3::new(1.5, 0.2, 0.3), tri),
            (Vec3::new(2.0, 0.97, 0.1), tri),
        ]
    }

    #[test]
    fn solid_angle_of_a_rectangle_is_the_closed_form() {
        // A rectangle a × b at height h above its centre: Ω = 4·asin(ab/√((a² + 4h²)(b² +
        // 4h²))), as the sum of its two triangles.
        for (a, b, h) in [
            (0.4f32, 0.2f32, 1.0f32),
            (2.0, 1.0, 0.01),
            (1e-3, 2e-3, 5.0),
        ] {
            let (x, z) = (a / 2.0, b / 2.0);
            let c = [
                Vec3::new(-x, h, -z),
                Vec3::new(x, h, -z),
                Vec3::new(x, h, z),
                Vec3::new(-x, h, z),
            ];
            let omega = solid_angle(Vec3::ZERO, [c[0], c[1], c[2]])
                + solid_angle(Vec3::ZERO, [c[0], c[2], c[3]]);
            let (a, b, h) = (a as f64, b as f64, h as f64);
            let exact =
                4.0 * (a * b / ((a * a + 4.0 * h * h) * (b * b + 4.0 * h * h)).sqrt()).asin();
            assert!(
                (omega - exact).abs() < 1e-5 * exact,
                "{omega} against {exact}"
            );
        }
    }

    /// E[g/p] over the samples is ∫ g dω by quadrature (in σ), for g = 1 (so Ω itself: the
    /// density 1/Ω integrates to 1 over the solid angle) and a g that is not flat, which a
    /// sampler that is not uniform in solid angle would miss; and every sample lies on the
    /// triangle.
    #[test]
    fn samples_are_uniform_in_solid_angle() {
        let mut rng = Rng::new(11, Domain::Other, [0; 3]);
        let k = DVec3::new(0.3, 0.8, -0.5).normalize();
        let gs: [&dyn Fn(DVec3) -> f64; 2] = [&|_| 1.0, &|w: DVec3| (1.0 + w.dot(k)).powi(3)];
        for (p, v) in triangles() {
            let omega = solid_angle(p, v);
            let exact_omega = quadrature(p, v, |_| 1.0);
            assert!(
                (omega - exact_omega).abs() < 1e-3 * exact_omega,
                "Ω {omega} against {exact_omega}"
            );
            for g in gs {
                let exact = quadrature(p, v, g);
                let (mean, se) = mean_se(100_000, || {
                    let (b1, b2, o) = sample(p, v, rng.uniform2()).unwrap();
                    assert!(b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 + 1e-6);
                    let x = v[0] * (1.0 - b1 - b2) + v[1] * b1 + v[2] * b2;
                    g((x - p).as_dvec3().normalize()) * o
                });
                let tol = 4.0 * se + 1e-3 * exact;
                assert!(
                    (mean - exact).abs() < tol,
                    "from {p}: {mean} ± {se} against {exact}"
                );
            }
        }
    }

    /// The two strata of u₀ split the solid angle in halves: the construction maps area
    /// fractions to u₀ (what stratification relies on).
    #[test]
    fn the_first_number_splits_the_area() {
        let (p, v) = triangles()[1];
        let omega = solid_angle(p, v);
        let mut rng = Rng::new(12, Domain::Other, [0; 3]);
        // The sub-triangle (v0, v1, c') of u₀ = 1/2 has half the solid angle: a direction with
        // u₀ < 1/2 lies in it, one with u₀ > 1/2 does not.
        let (b1, b2, _) = sample(p, v, [0.5, 1.0]).unwrap();
        let c_half = v[0] * (1.0 - b1 - b2) + v[1] * b1 + v[2] * b2;
        let half = solid_angle(p, [v[0], v[1], c_half]);
        assert!(
            (half - omega / 2.0).abs() < 1e-4 * omega,
            "{half} of {omega}"
        );
        // Central projection maps great arcs to segments: the spherical sub-triangle is the
        // planar triangle (v0, v1, c_half).
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let inside = |x: Vec3| {
            let t = [v[0], v[1], c_half];
            (0..3).all(|i| (t[(i + 1) % 3] - t[i]).cross(x - t[i]).dot(n) >= 0.0)
        };
        let mut tested = 0;
        for _ in 0..1000 {
            let u = rng.uniform2();
            if (u[0] - 0.5).abs() < 1e-3 {
                continue;
            }
            let (b1, b2, _) = sample(p, v, u).unwrap();
            let x = v[0] * (1.0 - b1 - b2) + v[1] * b1 + v[2] * b2;
            assert_eq!(inside(x), u[0] < 0.5, "u = {u:?}");
            tested += 1;
        }
        assert!(tested > 900);
    }

    #[test]
    fn degenerate_views_give_nothing() {
        let v = [Vec3::ZERO, Vec3::X, Vec3::Z];
        // On the triangle's plane, on a vertex, and a triangle with no area.
        assert_eq!(solid_angle(Vec3::new(2.0, 0.0, 2.0), v), 0.0);
        assert!(sample(Vec3::new(2.0, 0.0, 2.0), v, [0.5, 0.5]).is_none());
        assert!(sample(Vec3::ZERO, v, [0.5, 0.5]).is_none());
        let flat = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        assert!(sample(Vec3::Y, flat, [0.5, 0.5]).is_none());
    }
}
