//! A scene built in code (no scene file), rendered with the `balance` mix for a few passes,
//! and checked against what a closed form says: a floor lit by one point light, seen from
//! above, whose pixels under the light carry the direct radiance k_d/π·I·cos/d².
//!
//! Run it as the example `render_in_code` of the package `bdpm-integrator` (`cargo run` in
//! release mode); the test command runs it too.

use bdpm_bdf::Bdf;
use bdpm_geometry::{Geometry, TriangleMesh};
use bdpm_integrator::{Film, Mode, RenderSettings, Renderer};
use bdpm_scene::{Camera, PointLight, Scene};
use glam::Vec3;

fn main() {
    let mut mesh = TriangleMesh::default();
    // A 2 m × 2 m floor at y = 0, facing +y.
    mesh.push_rect(Vec3::ZERO, Vec3::Z, Vec3::X, 0);
    let kd = 0.5;
    let flux = 4.0 * std::f32::consts::PI; // W, so that I = Φ/4π = 1 W·sr⁻¹
    let scene = Scene::one_material(
        Geometry::new(mesh).expect("a valid mesh"),
        Bdf::lambert(Vec3::splat(kd)).expect("albedo below 1"),
        vec![PointLight {
            position: Vec3::new(0.0, 1.0, 0.0),
            flux: Vec3::splat(flux),
        }],
        Camera::look_at(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, Vec3::Z, 20.0, 32, 32)
            .expect("a valid camera"),
    )
    .expect("a valid scene");

    let settings = RenderSettings {
        width: 32,
        height: 32,
        passes: 4,
        photons: 20_000,
        spp: 4,
        mode: Mode::parse("balance").expect("a mode"),
        ..RenderSettings::default()
    };
    let renderer = Renderer::new(&scene, &settings).expect("valid settings");
    let mut film = Film::new(settings.width, settings.height);
    for pass in 0..settings.passes {
        let out = renderer.render_pass(pass, &|_| {});
        film.add_pass(&out.estimates, out.dropped);
    }
    // The centre pixel looks at the point under the light: direct radiance kd/π · I / 1 m²;
    // a single floor has no indirect light.
    let centre = film.mean()[(16 * 32 + 16) as usize].x;
    let exact = f64::from(kd) / std::f64::consts::PI;
    println!("centre pixel {centre:.5} W·m⁻²·sr⁻¹, closed form {exact:.5}");
    assert!((centre - exact).abs() < 0.02 * exact, "{centre} vs {exact}");
}
