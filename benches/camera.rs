//! Render throughput of `bdpm_integrator::Renderer` on the `cornell-lambert` scene, per mode
//! (`path` and every BDPM mode of `bdpm_mis::Heuristic::ALL_NAMES`) and per rayon pool size
//! (the const parameter, 1 and 2 threads):
//!
//! - `render_pass`: one `Renderer::render_pass` at 64×64 pixels, N_B = 4 camera samples per
//!   pixel and N_F = 200,000 photons, in camera samples per second (64·64·4 = 16,384 samples
//!   per iteration). For the BDPM modes the time **includes the pass's photon tracing**
//!   (200,000 photons and their grid), so this is the rate of whole passes expressed per camera
//!   sample, not of the camera stage alone; `path` traces no photons. The renderer (radiance
//!   cache, A/B table) is built before timing, and every iteration renders pass 0 again.
//! - `prepare`: `Renderer::new` at 128×128 pixels with the same N_B and N_F for `algebraic`
//!   (radiance cache only) and `optimal` (radiance cache and the per-pixel A/B table), in
//!   seconds per renderer (no counter).
//!
//! Run: `cargo bench -p bdpm-suite --bench camera` (a few minutes; append e.g.
//! `-- --sample-count 2` for a quick look, or a filter such as `-- render_pass`).

use bdpm_integrator::Renderer;
use bdpm_mis::Heuristic;
use bdpm_suite::{load, thread_pool, with_mode};
use divan::Bencher;
use divan::counter::ItemsCount;

fn main() {
    divan::main();
}

/// Rayon thread counts every benchmark runs with.
const THREADS: &[usize] = &[1, 2];
/// Image side of `render_pass`, pixels.
const RENDER_SIDE: u32 = 64;
/// Image side of `prepare`, pixels.
const PREPARE_SIDE: u32 = 128;
/// N_B, camera samples per pixel per pass.
const SPP: u32 = 4;
/// N_F, photons emitted per pass (and by the radiance-cache pre-pass).
const PHOTONS: u64 = 200_000;
/// The scene every benchmark renders.
const SCENE: &str = "cornell-lambert.toml";

/// `path`, then every BDPM weight mode.
fn modes() -> impl Iterator<Item = &'static str> {
    std::iter::once("path").chain(Heuristic::ALL_NAMES.iter().copied())
}

#[divan::bench(consts = THREADS, args = modes(), sample_count = 5)]
fn render_pass<const THREADS: usize>(bencher: Bencher, mode: &str) {
    let (scene, settings) = load(SCENE, RENDER_SIDE, RENDER_SIDE);
    let settings = with_mode(&settings, mode, 1, SPP, PHOTONS);
    let pool = thread_pool(THREADS);
    let renderer = pool
        .install(|| Renderer::new(&scene, &settings))
        .unwrap_or_else(|e| panic!("{mode}: {e}"));
    let samples = u64::from(RENDER_SIDE * RENDER_SIDE * SPP);
    bencher
        .counter(ItemsCount::new(samples))
        .bench(|| pool.install(|| renderer.render_pass(0, &|_| {})));
}

#[divan::bench(consts = THREADS, args = ["algebraic", "optimal"], sample_count = 3)]
fn prepare<const THREADS: usize>(bencher: Bencher, mode: &str) {
    let (scene, settings) = load(SCENE, PREPARE_SIDE, PREPARE_SIDE);
    let settings = with_mode(&settings, mode, 1, SPP, PHOTONS);
    let pool = thread_pool(THREADS);
    bencher.bench(|| {
        pool.install(|| Renderer::new(&scene, &settings))
            .unwrap_or_else(|e| panic!("{mode}: {e}"))
    });
}
