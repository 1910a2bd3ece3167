//! A photon map over your own points: build `bdpm_photon::grid::PointGrid` from plain
//! positions (no bdpm scene, camera or BDF), run range queries, and check them against brute
//! force. Then a density estimate the way a photon-mapping renderer would make one.
//!
//! `cargo run --release -p bdpm-grid --example point_grid`

use std::f32::consts::PI;
use std::time::Instant;

use bdpm_grid::PointGrid;
use glam::Vec3;

/// A small deterministic generator (SplitMix64), so the example needs no extra crates.
fn uniform(state: &mut u64) -> f32 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
}

fn main() {
    // 200 000 "photons" uniformly on the unit floor square (y = 0), each carrying 1 W / N.
    let n = 200_000;
    let power = 1.0 / n as f32;
    let mut s = 1u64;
    let points: Vec<Vec3> = (0..n)
        .map(|_| Vec3::new(uniform(&mut s), 0.0, uniform(&mut s)))
        .collect();
    let radius = 0.02; // m
    let t = Instant::now();
    let grid = PointGrid::new(&points, radius);
    println!(
        "built a grid of {} points, radius {radius} m, in {:.1} ms",
        grid.len(),
        t.elapsed().as_secs_f64() * 1e3
    );

    // Range queries must return exactly the points brute force finds.
    let queries = 200;
    let mut total = 0;
    for _ in 0..queries {
        let x = Vec3::new(uniform(&mut s), 0.0, uniform(&mut s));
        let mut found = Vec::new();
        grid.for_each_near(x, |i| found.push(i));
        found.sort_unstable();
        let brute: Vec<usize> = (0..n)
            .filter(|&i| (points[i] - x).length_squared() <= radius * radius)
            .collect();
        assert_eq!(found, brute, "range query at {x} differs from brute force");
        total += found.len();
    }
    println!("{queries} range queries agree with brute force ({total} points found)");

    // Density estimate of the irradiance at the floor's centre: 1 W over 1 m², so 1 W/m².
    let mut sum = 0.0;
    grid.for_each_near(Vec3::new(0.5, 0.0, 0.5), |_| sum += power);
    let irradiance = sum / (PI * radius * radius);
    println!("irradiance estimate at the centre: {irradiance:.3} W/m² (exact 1)");
    // ~250 points in the disc: a 4 standard-error band is about ±25 %.
    assert!((irradiance - 1.0).abs() < 0.3, "{irradiance}");
}
