//! Photon-pass throughput of `bdpm_photon`, on the `cornell-lambert` and `cornell-glossy`
//! scenes, each on a rayon pool of 1 and of 2 threads (the argument):
//!
//! - `trace`: `PhotonMap::trace` of 200,000 photons (pass 0, `light_visibility: true` as the
//!   renderer sets it for the modes whose weights use L₀ at x₁), tracing and grid build
//!   together, in photons emitted per second;
//! - `build`: the grid build alone (`PhotonMap::with_radius`, i.e. `from_parts`) of a map
//!   traced once before timing, in photons stored per second (the map is cloned outside the
//!   timer);
//! - `gather`: `PhotonMap::for_each_near` (summing the photons' power) at 65,536 fixed-seed
//!   surface points drawn with `Geometry::sample_surface`, with the scene's merge radius (the
//!   file's, else `scene_default_radius`, as the renderer does), in queries per second. At
//!   N_F = 200,000 and r = 1.75 mm a query finds few photons (about 0.03 on average in
//!   `cornell-lambert`, 0.1 in `cornell-glossy`), so this mostly times the grid lookup.
//!
//! Run: `cargo bench -p bdpm-suite --bench photons` (append e.g. `-- --sample-count 3` for a
//! quick look, or a filter such as `-- gather`).

use std::sync::LazyLock;

use bdpm_geometry::{Domain, Rng};
use bdpm_integrator::setup::scene_default_radius;
use bdpm_load::load_scene;
use bdpm_photon::{PhotonMap, TraceOptions};
use bdpm_scene::Scene;
use bdpm_suite::{scene_path, thread_pool};
use divan::Bencher;
use divan::counter::ItemsCount;
use glam::Vec3;
use rayon::prelude::*;

fn main() {
    divan::main();
}

/// Rayon thread counts every benchmark runs with.
const THREADS: &[usize] = &[1, 2];
/// N_F, photons emitted per traced pass.
const PHOTONS: u64 = 200_000;
/// Gather queries per timed iteration.
const QUERIES: usize = 65_536;
/// Master seed of the photon pass and of the query points.
const SEED: u64 = 1;

/// The photon pass every benchmark traces: pass 0 with the renderer's options.
fn options() -> TraceOptions {
    TraceOptions {
        light_visibility: true,
        ..TraceOptions::new(PHOTONS, SEED, 0)
    }
}

/// A scene with its merge radius, one traced photon map and the gather points.
struct Workload {
    scene: Scene,
    radius: f32,
    map: PhotonMap,
    queries: Vec<Vec3>,
}

impl Workload {
    fn load(name: &str) -> Workload {
        let loaded = load_scene(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
        let scene = loaded.scene;
        let radius = loaded
            .settings
            .radius
            .unwrap_or_else(|| scene_default_radius(&scene));
        let map = PhotonMap::trace(&scene, &options(), radius);
        let mut rng = Rng::new(SEED, Domain::Other, [0; 3]);
        let queries = (0..QUERIES)
            .map(|_| scene.geometry().sample_surface(rng.uniform3()).p)
            .collect();
        Workload {
            scene,
            radius,
            map,
            queries,
        }
    }

    fn bench_trace(&self, bencher: Bencher, threads: usize) {
        let pool = thread_pool(threads);
        let options = options();
        bencher
            .counter(ItemsCount::new(options.photons))
            .bench(|| pool.install(|| PhotonMap::trace(&self.scene, &options, self.radius)));
    }

    fn bench_build(&self, bencher: Bencher, threads: usize) {
        let pool = thread_pool(threads);
        bencher
            .counter(ItemsCount::new(self.map.photons().len()))
            .with_inputs(|| self.map.clone())
            .bench_local_values(|map| pool.install(|| map.with_radius(self.radius)));
    }

    fn bench_gather(&self, bencher: Bencher, threads: usize) {
        let pool = thread_pool(threads);
        bencher
            .counter(ItemsCount::new(self.queries.len()))
            .bench(|| {
                pool.install(|| {
                    self.queries
                        .par_iter()
                        .map(|&x| {
                            let mut power = Vec3::ZERO;
                            self.map.for_each_near(x, |p| power += p.power);
                            power
                        })
                        .reduce(|| Vec3::ZERO, |a, b| a + b)
                })
            });
    }
}

static LAMBERT: LazyLock<Workload> = LazyLock::new(|| Workload::load("cornell-lambert.toml"));
static GLOSSY: LazyLock<Workload> = LazyLock::new(|| Workload::load("cornell-glossy.toml"));

/// The preprint's Lambert Cornell box.
mod cornell_lambert {
    use super::*;

    #[divan::bench(args = THREADS, sample_count = 10)]
    fn trace(bencher: Bencher, threads: usize) {
        LAMBERT.bench_trace(bencher, threads);
    }

    #[divan::bench(args = THREADS, sample_count = 20)]
    fn build(bencher: Bencher, threads: usize) {
        LAMBERT.bench_build(bencher, threads);
    }

    #[divan::bench(args = THREADS, sample_count = 20)]
    fn gather(bencher: Bencher, threads: usize) {
        LAMBERT.bench_gather(bencher, threads);
    }
}

/// The preprint's glossy Cornell box.
mod cornell_glossy {
    use super::*;

    #[divan::bench(args = THREADS, sample_count = 10)]
    fn trace(bencher: Bencher, threads: usize) {
        GLOSSY.bench_trace(bencher, threads);
    }

    #[divan::bench(args = THREADS, sample_count = 20)]
    fn build(bencher: Bencher, threads: usize) {
        GLOSSY.bench_build(bencher, threads);
    }

    #[divan::bench(args = THREADS, sample_count = 20)]
    fn gather(bencher: Bencher, threads: usize) {
        GLOSSY.bench_gather(bencher, threads);
    }
}
