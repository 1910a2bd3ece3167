//! A BVH over your own triangles: build a `Geometry` from a mesh, cast closest-hit and shadow
//! rays, and check the hits against the plane equation by hand.
//!
//! `cargo run --release -p bdpm-geometry --example rays`

use bdpm_geometry::{Geometry, TriangleMesh};
use glam::Vec3;

fn main() {
    // A floor (y = 0, material 0) and, above part of it, a 1 m² shelf (y = 1, material 1).
    let mut mesh = TriangleMesh::default();
    mesh.push_rect(Vec3::ZERO, 2.0 * Vec3::Z, 2.0 * Vec3::X, 0);
    mesh.push_rect(Vec3::new(0.5, 1.0, 0.5), 0.5 * Vec3::Z, 0.5 * Vec3::X, 1);
    let geometry = Geometry::new(mesh).expect("a valid mesh");
    println!(
        "{} triangles, {:.1} m² of surface, kernel {:?}",
        geometry.triangle_count(),
        geometry.total_area(),
        geometry.kernel()
    );

    // Straight down from 3 m: over the shelf the ray stops at y = 1, elsewhere at the floor.
    let mut over_shelf = 0;
    for i in 0..40 {
        let x = -1.95 + 0.1 * i as f32;
        let origin = Vec3::new(x, 3.0, 0.5);
        let hit = geometry
            .intersect(origin, Vec3::NEG_Y, f32::INFINITY)
            .expect("the floor is under every ray");
        let expected_y = if (0.0..=1.0).contains(&x) { 1.0 } else { 0.0 };
        assert!(
            (hit.p.y - expected_y).abs() < 1e-5,
            "x = {x}: hit {:?}",
            hit.p
        );
        assert!((hit.t - (3.0 - expected_y)).abs() < 1e-5);
        over_shelf += usize::from(hit.material == 1);
    }
    println!("40 rays down: {over_shelf} stopped on the shelf, the rest on the floor");

    // A shadow ray from the floor under the shelf to a point above it is blocked; one beside
    // the shelf is not.
    let light = Vec3::new(0.5, 2.5, 0.5);
    assert!(geometry.occluded(Vec3::new(0.5, 0.0, 0.5), light));
    assert!(!geometry.occluded(Vec3::new(-1.5, 0.0, 0.5), light));
    println!("shadow rays: under the shelf blocked, beside it clear");
}
