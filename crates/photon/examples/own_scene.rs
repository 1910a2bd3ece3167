//! Photon tracing over your own scene type: implement `bdpm_photon::PhotonScene` (pick a
//! light, intersect and shade, scatter, spawn, light visibility) and get bdpm's random walk and
//! photon map. The scene here is analytic: a point light of 1 W at the centre of a hollow
//! sphere of radius 1 m whose inside is Lambert with albedo ρ = 0.5. Every bounce spreads
//! light evenly over a sphere, so the irradiance of the light that has scattered at least
//! once (what the stored photons estimate) is E_dir·ρ/(1 − ρ) with E_dir = Φ/(4πR²).
//!
//! `cargo run --release -p bdpm-photon --example own_scene`

use std::f32::consts::PI;

use bdpm_geometry::Frame;
use bdpm_photon::{PhotonMap, PhotonScene, Scatter, TraceOptions};
use bdpm_scene::{PointLight, Shading};
use glam::Vec3;

/// The renderer's own scene: a sphere seen from inside, one light at its centre.
struct HollowSphere {
    radius: f32,
    albedo: f32,
    flux: f32,
}

impl PhotonScene for HollowSphere {
    fn pick_light(&self, _u: f32) -> (usize, f32) {
        (0, 1.0)
    }

    fn light(&self, _index: usize) -> PointLight {
        PointLight {
            position: Vec3::ZERO,
            flux: Vec3::splat(self.flux),
        }
    }

    fn intersect(&self, origin: Vec3, dir: Vec3) -> Option<Shading> {
        // From inside, the ray leaves through the far root of |o + t·d|² = R².
        let b = origin.dot(dir);
        let c = origin.length_squared() - self.radius * self.radius;
        let t = -b + (b * b - c).max(0.0).sqrt();
        let p = origin + t * dir;
        let inward = -p / self.radius;
        Some(Shading {
            p,
            ng: inward,
            frame: Frame::from_normal(inward),
            material: 0,
            prim: 0,
            bary: glam::Vec2::ZERO,
        })
    }

    fn scatter(&self, sh: &Shading, _incoming: Vec3, u: [f32; 3]) -> (f32, Option<Scatter>) {
        // Lambert: cosine-distributed directions, so f·cos/pdf = ρ.
        let (r, phi) = (u[1].sqrt(), 2.0 * PI * u[2]);
        let local = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - r * r).max(0.0).sqrt());
        let scatter = Scatter {
            direction: sh.frame.to_world(local),
            f: Vec3::splat(self.albedo / PI),
            pdf: local.z / PI,
            weight: Vec3::splat(self.albedo),
        };
        (self.albedo.min(0.95), (local.z > 0.0).then_some(scatter))
    }

    fn spawn(&self, sh: &Shading, dir: Vec3) -> Vec3 {
        sh.p + sh.ng * (1e-4 * sh.ng.dot(dir).signum())
    }

    fn visible_light_mask(&self, _sh: &Shading) -> u32 {
        1 // nothing in a sphere hides its centre
    }
}

fn main() {
    let scene = HollowSphere {
        radius: 1.0,
        albedo: 0.5,
        flux: 1.0,
    };
    let n = 200_000;
    let r = 0.1; // merge radius, m
    let map = PhotonMap::trace(&scene, &TraceOptions::new(n, 1, 0), r);
    let area = 4.0 * PI * scene.radius * scene.radius;
    let exact = scene.flux / area * scene.albedo / (1.0 - scene.albedo);
    println!(
        "{n} photons emitted, {} stored (≥ 1 scattering), {} path vertices",
        map.photons().len(),
        map.vertices().len()
    );

    // All stored power spread over the sphere.
    let total: f32 = map.photons().iter().map(|p| p.power.x).sum();
    let mean = total / area;
    println!("mean indirect irradiance {mean:.5} W/m² (exact {exact:.5})");
    assert!((mean / exact - 1.0).abs() < 0.02, "{mean} vs {exact}");

    // A density estimate at one point: on a sphere the points within distance r cover πr²
    // exactly, so the usual disc estimate has no bias from curvature.
    let x = Vec3::new(0.0, -1.0, 0.0);
    let mut sum = 0.0;
    map.for_each_near(x, |p| sum += p.power.x);
    let local = sum / (PI * r * r);
    println!("density estimate at {x}: {local:.5} W/m²");
    assert!((local / exact - 1.0).abs() < 0.2, "{local} vs {exact}");

    // Every stored photon's previous vertex y_p is preceded by the rest of its light path:
    // one vertex per scattering before it, depths counting down to 0.
    for p in map.photons() {
        let y = map.vertex(p.prev);
        for k in 0..=y.depth as u32 {
            assert_eq!(map.vertex(p.prev - k).depth as u32, y.depth as u32 - k);
        }
    }
}
