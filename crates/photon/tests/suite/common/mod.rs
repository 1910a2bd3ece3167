//! Scene builders and statistics helpers shared by the integration tests.
#![allow(dead_code)]

use bdpm_bdf::Bdf;
use bdpm_geometry::{Geometry, TriangleMesh};
use bdpm_scene::{Camera, Material, PointLight, Scene};
use glam::Vec3;

pub(crate) fn camera() -> Camera {
    Camera::look_at(
        Vec3::new(0.5, 0.5, 0.05),
        Vec3::new(0.5, 0.5, 1.0),
        Vec3::Y,
        60.0,
        8,
        8,
    )
    .unwrap()
}

/// Scene from a mesh, one BDF per material index, and lights (position, flux).
pub(crate) fn scene(mesh: TriangleMesh, bdfs: Vec<Bdf>, lights: &[(Vec3, Vec3)]) -> Scene {
    let materials = bdfs
        .into_iter()
        .enumerate()
        .map(|(i, bdf)| Material::new(format!("m{i}"), bdf))
        .collect();
    let lights = lights
        .iter()
        .map(|&(position, flux)| PointLight { position, flux })
        .collect();
    Scene::new(Geometry::new(mesh).unwrap(), materials, lights, camera()).unwrap()
}

/// Closed unit cube with one Lambert material.
pub(crate) fn lambert_box(kd: Vec3, lights: &[(Vec3, Vec3)]) -> Scene {
    scene(
        TriangleMesh::cuboid(Vec3::ZERO, Vec3::ONE, true, 0),
        vec![Bdf::lambert(kd).unwrap()],
        lights,
    )
}

/// Upper critical value of the chi-square distribution with `dof` degrees of freedom at
/// significance 1e-3 (statrs).
pub(crate) fn chi2_critical_1e3(dof: usize) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    ChiSquared::new(dof as f64)
        .expect("at least one degree of freedom")
        .inverse_cdf(1.0 - 1e-3)
}

/// Pearson's statistic of observed counts against expected counts.
pub(crate) fn chi2(observed: &[u64], expected: &[f64]) -> f64 {
    observed
        .iter()
        .zip(expected)
        .map(|(&o, &e)| (o as f64 - e).powi(2) / e)
        .sum()
}
