//! A radiance cache over your own mesh, filled with arrivals you supply: a renderer with its
//! own scene type implements `CacheSurfaces` (triangles and Lambert albedos) and hands the
//! cache the scatterings its own photon pass made. Here: a 1 m² floor of albedo 0.5 that
//! receives 1 W of secondary light evenly, so it reflects 0.5 W/m² and, being Lambert, its
//! radiance is L_d = 0.5/π W·m⁻²·sr⁻¹ everywhere and in every direction.
//!
//! `cargo run --release -p bdpm-cache --example own_mesh`

use std::f32::consts::PI;

use bdpm_cache::{CacheArrival, CacheSurfaces, RadianceCache};
use glam::Vec3;

/// The renderer's own mesh: a list of triangles, one Lambert albedo for all.
struct Mesh {
    triangles: Vec<[Vec3; 3]>,
    albedo: f32,
}

impl CacheSurfaces for Mesh {
    fn triangle_count(&self) -> usize {
        self.triangles.len()
    }
    fn triangle(&self, prim: u32) -> [Vec3; 3] {
        self.triangles[prim as usize]
    }
    fn normal(&self, prim: u32) -> Vec3 {
        let [a, b, c] = self.triangles[prim as usize];
        (b - a).cross(c - a).normalize()
    }
    fn area(&self, prim: u32) -> f32 {
        let [a, b, c] = self.triangles[prim as usize];
        0.5 * (b - a).cross(c - a).length()
    }
    fn lambert_only(&self) -> bool {
        true
    }
    fn lambert_albedo(&self, _prim: u32) -> f32 {
        self.albedo
    }
}

/// A small deterministic generator (SplitMix64), so the example needs no extra crates.
fn uniform(state: &mut u64) -> f32 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
}

fn main() {
    // The unit floor square at y = 0, facing +y (counter-clockwise seen from above).
    let v = |x: f32, z: f32| Vec3::new(x, 0.0, z);
    let mesh = Mesh {
        triangles: vec![
            [v(0.0, 0.0), v(1.0, 1.0), v(1.0, 0.0)],
            [v(0.0, 0.0), v(0.0, 1.0), v(1.0, 1.0)],
        ],
        albedo: 0.5,
    };
    assert!(mesh.normal(0).y > 0.0 && mesh.normal(1).y > 0.0);

    // The renderer's photon pass: 1 W (luminance) arriving uniformly over the floor in N
    // photons, each scattered once by the Lambert BDF (cosine-distributed direction, so the
    // sample weight f·cos/pdf is the albedo).
    let n = 400_000;
    let mut s = 7u64;
    let arrivals = (0..n).map(|_| {
        let (x, z) = (uniform(&mut s), uniform(&mut s));
        let prim = if z > x { 1 } else { 0 };
        let (r, phi) = (uniform(&mut s).sqrt(), 2.0 * PI * uniform(&mut s));
        let direction = Vec3::new(r * phi.cos(), (1.0 - r * r).sqrt(), r * phi.sin());
        CacheArrival {
            prim,
            position: v(x, z),
            normal: Vec3::Y,
            direction,
            energy: 1.0 / n as f32 * mesh.albedo,
            f: mesh.albedo / PI,
        }
    });
    let cache = RadianceCache::from_arrivals(&mesh, 1, 0.25, arrivals);
    let stats = cache.stats();
    assert_eq!(stats.filled_fraction, 0.5);
    println!(
        "{} cells per side, {} arrivals, {:.0} % of cell sides filled (every front side: the backs see no light)",
        stats.cells,
        stats.arrivals,
        stats.filled_fraction * 100.0
    );

    let exact = mesh.albedo / PI;
    let up = Vec3::new(0.3, 1.0, 0.1).normalize();
    let mut worst = 0.0f32;
    for (x, z) in [(0.5, 0.5), (0.1, 0.8), (0.9, 0.05), (0.3, 0.31)] {
        let prim = if z > x { 1 } else { 0 };
        let (ld, b) = cache.lookup(prim, v(x, z), up);
        println!("L_d at ({x}, 0, {z}) = {ld:.4} W·m⁻²·sr⁻¹ (exact {exact:.4}), b = {b:.5}");
        // Lambert: b = (k_d/π)·L_d exactly.
        assert!((b - mesh.albedo / PI * ld).abs() <= 1e-6 * ld);
        worst = worst.max((ld / exact - 1.0).abs());
        // Seen from below, the floor's back side received nothing.
        assert_eq!(cache.lookup(prim, v(x, z), -up), (0.0, 0.0));
    }
    // Each cell gets ~5 500 arrivals: a relative standard error of ~1.3 %.
    println!("largest relative error {:.1} %", worst * 100.0);
    assert!(worst < 0.08, "{worst}");
}
