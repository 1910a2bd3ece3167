//! Rays whose direction has zero components, of either sign, hit what lies ahead: a ray along
//! −n of an axis-aligned wall (n = (0, 0, 1) gives (−0, −0, −1)) once missed every box because
//! the reciprocal of −0 and the traversal's octant disagreed on its sign.

use bdpm_geometry::{Geometry, TriangleMesh};
use glam::Vec3;

/// A unit square in the plane z = `z`, facing +z.
fn wall(z: f32) -> Geometry {
    let mut mesh = TriangleMesh::default();
    mesh.push_quad(
        [
            Vec3::new(0.0, 0.0, z),
            Vec3::new(1.0, 0.0, z),
            Vec3::new(1.0, 1.0, z),
            Vec3::new(0.0, 1.0, z),
        ],
        0,
    );
    Geometry::new(mesh).unwrap()
}

#[test]
fn rays_with_signed_zero_components_hit_the_wall_ahead() {
    let g = wall(0.0);
    for sx in [0.0f32, -0.0] {
        for sy in [0.0f32, -0.0] {
            let dir = Vec3::new(sx, sy, -1.0);
            for (x, y) in [(0.5, 0.5), (0.1, 0.9), (0.999, 0.001)] {
                let origin = Vec3::new(x, y, 0.05);
                let hit = g.intersect(origin, dir, f32::INFINITY);
                assert!(hit.is_some(), "dir {dir:?} from {origin:?} missed the wall");
                assert!((hit.unwrap().t - 0.05).abs() < 1e-6);
                assert!(
                    g.occluded(origin, origin + dir),
                    "shadow ray {dir:?} passed through"
                );
            }
        }
    }
    // The same as −n of the wall's normal.
    let n = g.normal(0);
    assert!(g.intersect(Vec3::new(0.5, 0.5, 0.05), -n, 1.0).is_some());
}
