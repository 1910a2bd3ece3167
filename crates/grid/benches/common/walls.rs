// Test points shared by the `grid_build` bench and the grid's sort-path measurement
// (`grid::measure`): photons as a Cornell pass stores them, on walls.

use bdpm_core::{Domain, Rng};
use glam::Vec3;

/// `n` points (m) uniform over five walls of a box of side 5.5 m, from a fixed seed.
pub(crate) fn wall_points(n: usize) -> Vec<Vec3> {
    let side = 5.5;
    let mut rng = Rng::new(1, Domain::Other, [0; 3]);
    (0..n)
        .map(|_| {
            let [a, b, w] = rng.uniform3();
            let (a, b) = (a * side, b * side);
            match (w * 5.0) as u32 {
                0 => Vec3::new(a, b, 0.0),
                1 => Vec3::new(a, 0.0, b),
                2 => Vec3::new(0.0, a, b),
                3 => Vec3::new(a, b, side),
                _ => Vec3::new(side, a, b),
            }
        })
        .collect()
}
