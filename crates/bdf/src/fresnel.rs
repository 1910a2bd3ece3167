//! Fresnel reflectance of smooth interfaces, and the mirror and refraction directions.
//!
//! Cosines are measured against the local normal +z. For a dielectric, +z points into the
//! **exterior** medium and η = η_interior / η_exterior, so a negative cosine means the wave
//! arrives from the interior side, where the relative index is 1/η. Scalars are computed in
//! f64 (a handful of operations per call) so that the grazing and critical-angle cancellations
//! `1 − sin²θ` lose nothing; results are returned in f32.

use glam::{DVec3, Vec3};

/// Reflectance of the two linear polarisations at a smooth interface (dimensionless, each in
/// [0, 1]): `s` (electric field perpendicular to the plane of incidence) and `p` (parallel to
/// it). Unpolarised light sees their mean, [`Self::unpolarised`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Polarised {
    /// R_s = |r_⊥|², the perpendicular (s, TE) polarisation.
    pub s: f32,
    /// R_p = |r_∥|², the parallel (p, TM) polarisation; zero at Brewster's angle.
    pub p: f32,
}

impl Polarised {
    /// The unpolarised reflectance (R_s + R_p)/2.
    pub fn unpolarised(self) -> f32 {
        0.5 * (self.s + self.p)
    }
}

/// The cosine of the transmitted angle for incidence cosine `cos_i` ≥ 0 and relative index
/// `eta` = η_t/η_i, or `None` under total internal reflection (sin²θ_t ≥ 1). The one test of
/// total internal reflection, shared by the Fresnel term and [`refract`] so that they agree.
fn transmitted_cos(cos_i: f64, eta: f64) -> Option<f64> {
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    (sin2_t < 1.0).then(|| (1.0 - sin2_t).sqrt())
}

/// `cos_i` (against +z) and `eta` (interior/exterior) seen from the side the wave comes from:
/// (|cos θ_i|, η_t/η_i). A wave from inside (cos_i < 0) sees the inverse ratio.
fn oriented(cos_i: f32, eta: f32) -> (f64, f64) {
    let c = f64::from(cos_i).clamp(-1.0, 1.0);
    let eta = f64::from(eta);
    if c < 0.0 { (-c, 1.0 / eta) } else { (c, eta) }
}

/// Polarised reflectances of a smooth dielectric interface, in f64 (see [`fresnel_dielectric`]).
fn dielectric_parts(cos_i: f32, eta: f32) -> (f64, f64) {
    let (c, eta) = oriented(cos_i, eta);
    let Some(t) = transmitted_cos(c, eta) else {
        return (1.0, 1.0);
    };
    let r_s = (c - eta * t) / (c + eta * t);
    let r_p = (eta * c - t) / (eta * c + t);
    (r_s * r_s, r_p * r_p)
}

/// The s and p reflectances of a smooth dielectric interface: see [`fresnel_dielectric`] for
/// the arguments. Under total internal reflection both are 1.
pub fn fresnel_dielectric_polarised(cos_i: f32, eta: f32) -> Polarised {
    let (s, p) = dielectric_parts(cos_i, eta);
    Polarised {
        s: s as f32,
        p: p as f32,
    }
}

/// Unpolarised Fresnel reflectance F_r of a smooth dielectric interface (dimensionless, in
/// [0, 1]); the transmittance is 1 − F_r.
///
/// `cos_i` is the cosine of the angle between the incident direction (pointing away from the
/// surface, like `wo`) and the normal +z, which points into the exterior; `eta` =
/// η_interior/η_exterior > 0. A negative `cos_i` is a wave inside, which sees 1/η. Returns 1
/// under total internal reflection, ((η − 1)/(η + 1))² at normal incidence, and tends to 1 at
/// grazing incidence.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let (s, p) = dielectric_parts(cos_i, eta);
    (0.5 * (s + p)) as f32
}

/// A complex number in f64: just what the conductor's Fresnel equations need.
#[derive(Clone, Copy, Debug)]
struct Complex {
    re: f64,
    im: f64,
}

impl Complex {
    fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }

    fn real(re: f64) -> Self {
        Self::new(re, 0.0)
    }

    fn add(self, o: Self) -> Self {
        Self::new(self.re + o.re, self.im + o.im)
    }

    fn sub(self, o: Self) -> Self {
        Self::new(self.re - o.re, self.im - o.im)
    }

    fn mul(self, o: Self) -> Self {
        Self::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }

    fn scale(self, k: f64) -> Self {
        Self::new(self.re * k, self.im * k)
    }

    fn norm_sqr(self) -> f64 {
        self.re * self.re + self.im * self.im
    }

    fn div(self, o: Self) -> Self {
        let d = o.norm_sqr();
        Self::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }

    /// The principal square root (real part ≥ 0).
    fn sqrt(self) -> Self {
        let m = self.norm_sqr().sqrt();
        let re = (0.5 * (m + self.re)).max(0.0).sqrt();
        let im = (0.5 * (m - self.re)).max(0.0).sqrt();
        Self::new(re, if self.im < 0.0 { -im } else { im })
    }
}

/// Polarised reflectances of a conductor with complex relative index η + ik, in f64.
fn conductor_parts(cos_i: f32, eta: f32, k: f32) -> (f64, f64) {
    let c = f64::from(cos_i).abs().min(1.0);
    let n = Complex::new(f64::from(eta), f64::from(k));
    let sin2_i = (1.0 - c * c).max(0.0);
    // Snell's law with a complex index: cos θ_t = √(1 − sin²θ_i/n²), principal branch.
    let cos_t = Complex::real(1.0)
        .sub(Complex::real(sin2_i).div(n.mul(n)))
        .sqrt();
    let nc = n.scale(c);
    let n_cos_t = n.mul(cos_t);
    let r_s = Complex::real(c)
        .sub(n_cos_t)
        .div(Complex::real(c).add(n_cos_t));
    let r_p = nc.sub(cos_t).div(nc.add(cos_t));
    (r_s.norm_sqr(), r_p.norm_sqr())
}

/// The s and p reflectances of one channel of a conductor: see [`fresnel_conductor`].
pub fn fresnel_conductor_polarised(cos_i: f32, eta: f32, k: f32) -> Polarised {
    let (s, p) = conductor_parts(cos_i, eta, k);
    Polarised {
        s: s as f32,
        p: p as f32,
    }
}

/// Unpolarised Fresnel reflectance of a smooth conductor, per RGB channel (dimensionless, in
/// [0, 1]).
///
/// `eta + i·k` is the metal's complex index of refraction relative to the exterior medium,
/// one per channel (η > 0, k ≥ 0; k = 0 is a dielectric seen from outside). `cos_i` is the
/// incidence cosine against the normal; a conductor is opaque, so its sign is ignored. At
/// normal incidence F = ((η − 1)² + k²)/((η + 1)² + k²); at grazing incidence F → 1.
pub fn fresnel_conductor(cos_i: f32, eta: Vec3, k: Vec3) -> Vec3 {
    let channel = |e: f32, k: f32| {
        let (s, p) = conductor_parts(cos_i, e, k);
        (0.5 * (s + p)) as f32
    };
    Vec3::new(
        channel(eta.x, k.x),
        channel(eta.y, k.y),
        channel(eta.z, k.z),
    )
}

/// The mirror image of `w` about the normal +z: (−x, −y, z). Both point away from the surface.
pub fn reflect(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

/// The refraction of `w` (unit, pointing away from the surface, on either side) through a
/// smooth interface with normal +z into the exterior and `eta` = η_interior/η_exterior.
///
/// Returns the transmitted direction (unit, pointing away from the surface on the other side)
/// and the relative index η_t/η_i of the crossing, seen from `w`'s side (η for `w` outside,
/// 1/η inside); `None` under total internal reflection or for `w` in the tangent plane. The
/// result obeys Snell's law, η_i sin θ_i = η_t sin θ_t, and refracting it again returns `w`.
pub fn refract(w: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    if w.z == 0.0 || !w.is_finite() {
        return None;
    }
    let (c, eta_t) = oriented(w.z, eta);
    let t = transmitted_cos(c, eta_t)?;
    // The tangential component scales by 1/η_t and flips; the normal one becomes ∓cos θ_t.
    let wd = w.as_dvec3();
    let side = wd.z.signum();
    let out = DVec3::new(-wd.x / eta_t, -wd.y / eta_t, -side * t);
    Some((out.normalize().as_vec3(), eta_t as f32))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn complex_sqrt_squares_back() {
        for (re, im) in [
            (4.0, 0.0),
            (-4.0, 0.0),
            (3.0, 4.0),
            (-3.0, -4.0),
            (0.0, 2.0),
        ] {
            let z = Complex::new(re, im);
            let r = z.sqrt();
            let back = r.mul(r);
            assert!(r.re >= 0.0);
            assert!((back.re - re).abs() < 1e-12 && (back.im - im).abs() < 1e-12);
        }
    }

    #[test]
    fn oriented_inverts_eta_inside() {
        assert_eq!(oriented(0.5, 1.5), (0.5, 1.5));
        assert_eq!(oriented(-0.5, 2.0), (0.5, 0.5));
    }
}
