//! Scene builders and statistics helpers shared by the integration tests.
#![allow(dead_code)]

use bdpm_bdf::Bdf;
use bdpm_geometry::{Geometry, TriangleMesh};
use bdpm_scene::{Camera, Material, PointLight, Scene};
use glam::Vec3;

/// Six quads of the cube [0, size]³ (normals inward by winding; surfaces are two-sided anyway).
pub(crate) fn cube_mesh(size: f32, material: u32) -> TriangleMesh {
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z) * size;
    let mut mesh = TriangleMesh::default();
    for q in [
        [v(0., 0., 0.), v(1., 0., 0.), v(1., 0., 1.), v(0., 0., 1.)],
        [v(0., 1., 0.), v(0., 1., 1.), v(1., 1., 1.), v(1., 1., 0.)],
        [v(0., 0., 0.), v(0., 0., 1.), v(0., 1., 1.), v(0., 1., 0.)],
        [v(1., 0., 0.), v(1., 1., 0.), v(1., 1., 1.), v(1., 0., 1.)],
        [v(0., 0., 0.), v(0., 1., 0.), v(1., 1., 0.), v(1., 0., 0.)],
        [v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)],
    ] {
        mesh.push_quad(q, material);
    }
    mesh
}

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
        .map(|(i, bdf)| Material {
            name: format!("m{i}"),
            bdf,
        })
        .collect();
    let lights = lights
        .iter()
        .map(|&(position, flux)| PointLight { position, flux })
        .collect();
    Scene::new(Geometry::new(mesh).unwrap(), materials, lights, camera()).unwrap()
}

/// Closed unit cube with one Lambert material.
pub(crate) fn lambert_box(kd: Vec3, lights: &[(Vec3, Vec3)]) -> Scene {
    scene(cube_mesh(1.0, 0), vec![Bdf::lambert(kd).unwrap()], lights)
}

/// Icosahedron subdivided `level` times and projected on the sphere of radius `radius` at the
/// origin: 20·4^level flat triangles.
pub(crate) fn icosphere(level: u32, radius: f32, material: u32) -> TriangleMesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut pos: Vec<Vec3> = [
        (-1., t, 0.),
        (1., t, 0.),
        (-1., -t, 0.),
        (1., -t, 0.),
        (0., -1., t),
        (0., 1., t),
        (0., -1., -t),
        (0., 1., -t),
        (t, 0., -1.),
        (t, 0., 1.),
        (-t, 0., -1.),
        (-t, 0., 1.),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, pos: &mut Vec<Vec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                pos.push(((pos[a as usize] + pos[b as usize]) * 0.5).normalize());
                pos.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = midpoint(a, b, &mut pos);
            let bc = midpoint(b, c, &mut pos);
            let ca = midpoint(c, a, &mut pos);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let n = tris.len();
    TriangleMesh {
        positions: pos.into_iter().map(|p| p * radius).collect(),
        normals: Vec::new(),
        indices: tris,
        materials: vec![material; n],
    }
}

/// Upper critical value of the chi-square distribution with `dof` degrees of freedom at
/// significance `alpha` ∈ {1e-3} (Wilson–Hilferty; accurate to < 1 % for dof ≥ 2).
pub(crate) fn chi2_critical_1e3(dof: usize) -> f64 {
    let z = 3.090_232; // upper 1e-3 quantile of N(0, 1)
    let k = dof as f64;
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + z * a.sqrt()).powi(3)
}

/// Pearson's statistic of observed counts against expected counts.
pub(crate) fn chi2(observed: &[u64], expected: &[f64]) -> f64 {
    observed
        .iter()
        .zip(expected)
        .map(|(&o, &e)| (o as f64 - e).powi(2) / e)
        .sum()
}
