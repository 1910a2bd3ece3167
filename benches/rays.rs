//! Ray-query throughput of `bdpm_geometry::Geometry`, in rays per second (divan's `item/s`).
//!
//! - `intersect`: closest hits of incoherent secondary-like rays, 65,536 per iteration:
//!   origins are surface points drawn with `Geometry::sample_surface` and pushed off the surface
//!   by `Geometry::spawn_offset` along the normal, directions uniform on the normal's hemisphere.
//! - `occluded`: shadow segments, 65,536 per iteration, from such points to other sampled
//!   surface points (each also pushed off its surface).
//! - `bvh_build`: `Geometry::new` (validation and 4-wide BVH build) of the large mesh, in
//!   triangles per second.
//! - `coincident_20k`: `Geometry::new` of 20,000 identical quads and of 20,000 quads stacked
//!   1 µm apart (the BVH build must stay O(n log n) on coincident input).
//!
//! Two geometries: the `cornell-lambert` scene (30 triangles; its surfaces are two-sided, so
//! each point uses the side facing the camera, the side a secondary ray leaves from; about 84 %
//! of the rays hit, the rest leave through the open front, and about 49 % of the segments are
//! blocked) and a UV sphere of 130,560 smooth-shaded triangles on a floor quad, built here
//! (outward normals; about 23 % of the rays hit and 58 % of the segments are blocked). Each
//! benchmark runs on a rayon pool of 1 and of 2 threads (the argument). Inputs are fixed-seed
//! and made before timing.
//!
//! Each ray benchmark runs on every [`Kernel`]: `bvh4` (the default, 4-wide BVH with f32
//! boxes) and `cwbvh` (obvhs's compressed 8-wide BVH, which it replaced), on the same queries;
//! the CWBVH runs on 1 thread only.
//!
//! Run: `cargo bench -p bdpm-suite --bench rays` (append e.g. `-- --sample-count 5` for a
//! quick look, or a filter such as `-- sphere`).

use std::sync::LazyLock;

use bdpm_geometry::sampling::uniform_sphere;
use bdpm_geometry::{Domain, Geometry, Kernel, Rng, TriangleMesh};
use bdpm_load::load_scene;
use bdpm_suite::{scene_path, sphere_on_floor, thread_pool, with_kernel};
use divan::Bencher;
use divan::counter::ItemsCount;
use glam::Vec3;
use rayon::prelude::*;

fn main() {
    divan::main();
}

/// Rayon thread counts every parallel benchmark runs with.
const THREADS: &[usize] = &[1, 2];
/// Rays (and shadow segments) per timed iteration.
const RAYS: usize = 65_536;
/// Seed of every input stream.
const SEED: u64 = 1;

/// A ray `origin + t·dir`, `dir` unit.
struct Ray {
    origin: Vec3,
    dir: Vec3,
}

/// A shadow segment between two points just off their surfaces.
struct Segment {
    from: Vec3,
    to: Vec3,
}

/// A geometry and the fixed query batches made on it.
struct Workload {
    geometry: Geometry,
    rays: Vec<Ray>,
    segments: Vec<Segment>,
}

impl Workload {
    /// Draws the batches. With `viewpoint`, surfaces count as two-sided and each point uses
    /// the side facing `viewpoint`; without it, the side of the geometric normal.
    fn new(geometry: Geometry, viewpoint: Option<Vec3>, stream: u64) -> Workload {
        let mut rng = Rng::new(SEED, Domain::Other, [stream, 0, 0]);
        let point = |rng: &mut Rng| {
            let s = geometry.sample_surface(rng.uniform3());
            let n = match viewpoint {
                Some(eye) if s.ng.dot(eye - s.p) < 0.0 => -s.ng,
                _ => s.ng,
            };
            (s.p + n * geometry.spawn_offset(s.prim), n)
        };
        let rays = (0..RAYS)
            .map(|_| {
                let (origin, n) = point(&mut rng);
                let d = uniform_sphere(rng.uniform2());
                let dir = if d.dot(n) < 0.0 { -d } else { d };
                Ray { origin, dir }
            })
            .collect();
        let segments = (0..RAYS)
            .map(|_| Segment {
                from: point(&mut rng).0,
                to: point(&mut rng).0,
            })
            .collect();
        Workload {
            geometry,
            rays,
            segments,
        }
    }

    /// Times closest-hit queries of the ray batch on `threads` threads.
    fn bench_intersect(&self, bencher: Bencher, threads: usize) {
        let pool = thread_pool(threads);
        bencher.counter(ItemsCount::new(self.rays.len())).bench(|| {
            pool.install(|| {
                self.rays
                    .par_iter()
                    .filter(|r| {
                        // black_box keeps the hit record (point, normals) from being
                        // optimised away.
                        divan::black_box(self.geometry.intersect(r.origin, r.dir, f32::INFINITY))
                            .is_some()
                    })
                    .count()
            })
        });
    }

    /// Times occlusion queries of the segment batch on `threads` threads.
    fn bench_occluded(&self, bencher: Bencher, threads: usize) {
        let pool = thread_pool(threads);
        bencher
            .counter(ItemsCount::new(self.segments.len()))
            .bench(|| {
                pool.install(|| {
                    self.segments
                        .par_iter()
                        .filter(|s| self.geometry.occluded(s.from, s.to))
                        .count()
                })
            });
    }
}

static CORNELL: LazyLock<Workload> = LazyLock::new(|| {
    let loaded = load_scene(&scene_path("cornell-lambert.toml")).unwrap_or_else(|e| panic!("{e}"));
    let eye = loaded.scene.camera().position();
    Workload::new(loaded.scene.into_geometry(), Some(eye), 0)
});

static CORNELL_CWBVH: LazyLock<Workload> = LazyLock::new(|| {
    let loaded = load_scene(&scene_path("cornell-lambert.toml")).unwrap_or_else(|e| panic!("{e}"));
    let eye = loaded.scene.camera().position();
    let geometry = with_kernel(loaded.scene.geometry(), Kernel::Cwbvh);
    Workload::new(geometry, Some(eye), 0)
});

static SPHERE_MESH: LazyLock<TriangleMesh> = LazyLock::new(|| {
    let mesh = sphere_on_floor();
    assert!(mesh.triangle_count() >= 100_000);
    mesh
});

static SPHERE: LazyLock<Workload> = LazyLock::new(|| {
    let geometry = Geometry::new(SPHERE_MESH.clone()).expect("valid mesh");
    assert_eq!(geometry.degenerate_count(), 0);
    Workload::new(geometry, None, 1)
});

static SPHERE_CWBVH: LazyLock<Workload> = LazyLock::new(|| {
    let geometry = Geometry::with_kernel(SPHERE_MESH.clone(), Kernel::Cwbvh).expect("valid mesh");
    Workload::new(geometry, None, 1)
});

/// The `cornell-lambert` scene's 30 triangles.
mod cornell_lambert {
    use super::*;

    #[divan::bench(args = THREADS, sample_count = 20)]
    fn intersect(bencher: Bencher, threads: usize) {
        CORNELL.bench_intersect(bencher, threads);
    }

    #[divan::bench(args = THREADS, sample_count = 20)]
    fn occluded(bencher: Bencher, threads: usize) {
        CORNELL.bench_occluded(bencher, threads);
    }

    #[divan::bench(args = [1], sample_count = 20)]
    fn intersect_cwbvh(bencher: Bencher, threads: usize) {
        CORNELL_CWBVH.bench_intersect(bencher, threads);
    }

    #[divan::bench(args = [1], sample_count = 20)]
    fn occluded_cwbvh(bencher: Bencher, threads: usize) {
        CORNELL_CWBVH.bench_occluded(bencher, threads);
    }
}

/// The UV sphere of 130,560 triangles on a floor quad.
mod sphere_130k {
    use super::*;

    #[divan::bench(args = THREADS, sample_count = 20)]
    fn intersect(bencher: Bencher, threads: usize) {
        SPHERE.bench_intersect(bencher, threads);
    }

    #[divan::bench(args = THREADS, sample_count = 20)]
    fn occluded(bencher: Bencher, threads: usize) {
        SPHERE.bench_occluded(bencher, threads);
    }

    #[divan::bench(args = [1], sample_count = 20)]
    fn intersect_cwbvh(bencher: Bencher, threads: usize) {
        SPHERE_CWBVH.bench_intersect(bencher, threads);
    }

    #[divan::bench(args = [1], sample_count = 20)]
    fn occluded_cwbvh(bencher: Bencher, threads: usize) {
        SPHERE_CWBVH.bench_occluded(bencher, threads);
    }

    /// `Geometry::new` of the mesh, counted in triangles; the mesh is cloned outside the timer.
    #[divan::bench(args = THREADS, sample_count = 10)]
    fn bvh_build(bencher: Bencher, threads: usize) {
        let pool = thread_pool(threads);
        let mesh = &*SPHERE_MESH;
        bencher
            .counter(ItemsCount::new(mesh.triangle_count()))
            .with_inputs(|| mesh.clone())
            .bench_local_values(|mesh| pool.install(|| Geometry::new(mesh)));
    }
}

/// Coincident triangles (issue 15 item 5): `Geometry::new` of 20,000 identical quads (40,000
/// triangles, all but two left out as duplicates) and of 20,000 distinct quads stacked 1 µm
/// apart, counted in triangles. obvhs's PLOC builder, used before, took 97 s on the first.
mod coincident_20k {
    use super::*;

    /// `count` unit quads at z = 1 + k·`step` m, as one mesh.
    fn stack(count: usize, step: f32) -> TriangleMesh {
        let mut mesh = TriangleMesh::default();
        for k in 0..count {
            let z = 1.0 + k as f32 * step;
            mesh.push_quad(
                [
                    Vec3::new(0.0, 0.0, z),
                    Vec3::new(1.0, 0.0, z),
                    Vec3::new(1.0, 1.0, z),
                    Vec3::new(0.0, 1.0, z),
                ],
                0,
            );
        }
        mesh
    }

    #[divan::bench(sample_count = 5)]
    fn identical(bencher: Bencher) {
        let mesh = stack(20_000, 0.0);
        bencher
            .counter(ItemsCount::new(mesh.triangle_count()))
            .with_inputs(|| mesh.clone())
            .bench_local_values(Geometry::new);
    }

    #[divan::bench(sample_count = 5)]
    fn one_micrometre_apart(bencher: Bencher) {
        let mesh = stack(20_000, 1e-6);
        bencher
            .counter(ItemsCount::new(mesh.triangle_count()))
            .with_inputs(|| mesh.clone())
            .bench_local_values(Geometry::new);
    }
}
