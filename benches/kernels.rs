//! The two ray kernels side by side, interleaved: closest hits and shadow segments per second
//! on one thread, for `Kernel::Bvh4` (the default) and `Kernel::Cwbvh` (obvhs's CWBVH), on the
//! same queries as `benches/rays.rs` (the `cornell-lambert` scene's 30 triangles and a UV
//! sphere of 130,560 triangles on a floor quad).
//!
//! Why besides `rays.rs`: on a shared machine a divan run of one kernel and then the other
//! sees different loads. Here the kernels alternate batch by batch, each batch is timed in
//! the thread's own CPU time (`/proc/thread-self/schedstat`, so time spent descheduled is not
//! counted), and the best of several batches is kept. It also checks that both kernels
//! return equal hits (every field) and equal occlusion answers on every query.
//!
//! Run: `cargo bench -p bdpm-suite --bench kernels` (Linux only: it reads /proc).

use std::hint::black_box;

use bdpm_geometry::sampling::uniform_sphere;
use bdpm_geometry::{Domain, Geometry, Kernel, Rng};
use bdpm_load::load_scene;
use bdpm_suite::{scene_path, sphere_on_floor, with_kernel};
use glam::Vec3;

/// Queries per batch.
const QUERIES: usize = 1 << 16;
/// Batches per kernel and query kind; the fastest is reported.
const ROUNDS: usize = 5;

/// This thread's CPU time, nanoseconds (scheduler statistics, updated at every tick).
fn cpu_ns() -> u64 {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").expect("Linux /proc");
    text.split_whitespace()
        .next()
        .and_then(|s| s.parse().ok())
        .expect("schedstat's first field")
}

/// Rays leaving sampled surface points (the side facing `viewpoint`, if any, else the normal's
/// side) and segments between two such points, drawn as `benches/rays.rs` draws them.
fn queries(g: &Geometry, viewpoint: Option<Vec3>, stream: u64) -> [Vec<(Vec3, Vec3)>; 2] {
    let mut rng = Rng::new(1, Domain::Other, [stream, 0, 0]);
    let point = |rng: &mut Rng| {
        let s = g.sample_surface(rng.uniform3());
        let n = match viewpoint {
            Some(eye) if s.ng.dot(eye - s.p) < 0.0 => -s.ng,
            _ => s.ng,
        };
        (s.p + n * g.spawn_offset(s.prim), n)
    };
    let rays = (0..QUERIES)
        .map(|_| {
            let (o, n) = point(&mut rng);
            let d = uniform_sphere(rng.uniform2());
            (o, if d.dot(n) < 0.0 { -d } else { d })
        })
        .collect();
    let segments = (0..QUERIES)
        .map(|_| (point(&mut rng).0, point(&mut rng).0))
        .collect();
    [rays, segments]
}

/// Times both kernels on `scene`'s queries and prints rays per second.
fn compare(scene: &str, kernels: &[Geometry; 2], viewpoint: Option<Vec3>, stream: u64) {
    let [rays, segments] = queries(&kernels[0], viewpoint, stream);
    let same_hits = rays.iter().all(|&(o, d)| {
        kernels[0].intersect(o, d, f32::INFINITY) == kernels[1].intersect(o, d, f32::INFINITY)
    });
    let same_occlusion = segments
        .iter()
        .all(|&(a, b)| kernels[0].occluded(a, b) == kernels[1].occluded(a, b));
    // Small scenes repeat the batch so that each timing spans many scheduler ticks.
    let repeat = if kernels[0].triangle_count() < 1000 {
        12
    } else {
        3
    };
    let mut best = [[u64::MAX; 2]; 2];
    for _ in 0..ROUNDS {
        for (k, g) in kernels.iter().enumerate() {
            let start = cpu_ns();
            for _ in 0..repeat {
                for &(o, d) in &rays {
                    black_box(g.intersect(o, d, f32::INFINITY));
                }
            }
            best[k][0] = best[k][0].min(cpu_ns() - start);
            let start = cpu_ns();
            for _ in 0..repeat {
                for &(a, b) in &segments {
                    black_box(g.occluded(a, b));
                }
            }
            best[k][1] = best[k][1].min(cpu_ns() - start);
        }
    }
    println!(
        "{scene} ({} triangles): equal hits {same_hits}, equal occlusion {same_occlusion}",
        kernels[0].triangle_count()
    );
    let rate = |ns: u64| (repeat * QUERIES) as f64 / ns as f64 * 1e3;
    for (k, name) in ["bvh4", "cwbvh"].iter().enumerate() {
        println!(
            "  {name:<6} closest hit {:6.2} M rays/s   shadow {:6.2} M rays/s",
            rate(best[k][0]),
            rate(best[k][1])
        );
    }
    println!(
        "  bvh4 / cwbvh: closest hit {:.2}×, shadow {:.2}×",
        best[1][0] as f64 / best[0][0] as f64,
        best[1][1] as f64 / best[0][1] as f64
    );
}

fn main() {
    let loaded = load_scene(&scene_path("cornell-lambert.toml")).unwrap_or_else(|e| panic!("{e}"));
    let eye = loaded.scene.camera().position();
    let g = loaded.scene.geometry();
    let cornell = [with_kernel(g, Kernel::Bvh4), with_kernel(g, Kernel::Cwbvh)];
    compare("cornell-lambert", &cornell, Some(eye), 0);
    let mesh = sphere_on_floor();
    let sphere = [
        Geometry::with_kernel(mesh.clone(), Kernel::Bvh4).expect("valid mesh"),
        Geometry::with_kernel(mesh, Kernel::Cwbvh).expect("valid mesh"),
    ];
    compare("sphere_130k", &sphere, None, 1);
}
