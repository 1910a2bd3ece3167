//! Throughput of the MIS weight functions, `bdpm_mis::Heuristic::weight`, in weight
//! evaluations per second, for every mode of `Heuristic::ALL_NAMES` (parsed with
//! `Heuristic::parse`, so `threshold` has R = 0.2 m and `optimal` no clamp):
//!
//! - `weight`: one thread, 4,096 pre-generated pairs per iteration;
//! - `weight_parallel`: a rayon pool of 1 and of 2 threads (the const parameter), the same
//!   4,096 pairs evaluated 64 times over per iteration (262,144 evaluations), so that each
//!   thread reads its inputs from cache as a renderer would and memory bandwidth is not what
//!   is timed.
//!
//! Each w₁ is stored to an output slice allocated before timing. `bdd0`, `bdd1` and
//! `threshold` cost next to nothing, so their figures are the floor of the loop itself.
//!
//! The pairs are fixed-seed and realistic for the Cornell box at N_B = 4, N_F = 200,000 and
//! r = 1.75 mm: f̃ Lambert (1/π) or glossy (10⁻²–10³ sr⁻¹), L₀ zero (x₁ shadowed) a quarter
//! of the time and else 10⁻⁴–1 W·m⁻²·sr⁻¹, L_d 10⁻⁴–10⁻¹, densities 10⁻²–10² m⁻², both path
//! kinds, and per-pixel A, B (used by `optimal` only, passed to every mode as a renderer with
//! a table would) of 10⁻⁴–1.
//!
//! Run: `cargo bench -p bdpm-suite --bench weights` (append e.g. `-- --sample-count 10` for a
//! quick look, or a filter such as `-- optimal`).

use std::sync::LazyLock;

use bdpm_geometry::{Domain, Rng};
use bdpm_mis::{Budget, Heuristic, Pair, PathInputs, PathKind, PixelTerms, X0Inputs, X1Inputs};
use bdpm_suite::thread_pool;
use divan::Bencher;
use divan::counter::ItemsCount;
use rayon::prelude::*;

fn main() {
    divan::main();
}

/// Rayon thread counts of `weight_parallel`.
const THREADS: &[usize] = &[1, 2];
/// Pairs per batch.
const PAIRS: usize = 4096;
/// Times `weight_parallel` evaluates the batch per iteration.
const REPEATS: usize = 64;
/// Seed of the pair stream.
const SEED: u64 = 1;

/// One weight evaluation's inputs.
struct Input {
    pair: Pair,
    pixel: PixelTerms,
}

/// The Cornell box's budget: N_B = 4, N_F = 200,000, S = π r² with r = 2.796 m / 1600, Φ = 1 W.
fn budget() -> Budget {
    let radius = 2.796 / 1600.0;
    Budget {
        camera_samples: 4.0,
        photons: 200_000.0,
        merge_area: std::f64::consts::PI * radius * radius,
        flux: 1.0,
    }
}

/// A log-uniform draw in [lo, hi).
fn log_uniform(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    lo * (hi / lo).powf(rng.uniform_f64())
}

static INPUTS: LazyLock<Vec<Input>> = LazyLock::new(|| {
    let mut rng = Rng::new(SEED, Domain::Other, [0; 3]);
    (0..PAIRS)
        .map(|_| {
            let f_tilde = if rng.uniform() < 0.6 {
                std::f64::consts::FRAC_1_PI
            } else {
                log_uniform(&mut rng, 1e-2, 1e3)
            };
            let direct = if rng.uniform() < 0.25 {
                0.0
            } else {
                log_uniform(&mut rng, 1e-4, 1.0)
            };
            let indirect = log_uniform(&mut rng, 1e-4, 1e-1);
            let mut pair = Pair {
                x0: X0Inputs {
                    f_tilde,
                    ..Default::default()
                },
                x1: X1Inputs {
                    direct,
                    indirect,
                    b: (direct + indirect) * log_uniform(&mut rng, 1e-1, 1e1),
                    light_distance: 3.0 * rng.uniform_f64(),
                },
                path: PathInputs {
                    kind: if rng.uniform() < 0.5 {
                        PathKind::Merge
                    } else {
                        PathKind::OneBounce
                    },
                    camera_density: log_uniform(&mut rng, 1e-2, 1e2),
                    light_density: log_uniform(&mut rng, 1e-2, 1e2),
                    emission_density: log_uniform(&mut rng, 1e-3, 1e1),
                    ..Default::default()
                },
            };
            let pixel = PixelTerms {
                a: log_uniform(&mut rng, 1e-4, 1.0),
                b: log_uniform(&mut rng, 1e-4, 1.0),
            };
            // Drawn last so that the other modes' inputs stay those of earlier runs.
            pair.x0.acceptance_area = log_uniform(&mut rng, 1e-3, 1e-1);
            pair.x0.primary_density = log_uniform(&mut rng, 1e2, 1e4);
            pair.path.light_suffix = log_uniform(&mut rng, 1e-9, 1.0);
            pair.path.x1_scattering = log_uniform(&mut rng, 1e-2, 1e2);
            Input { pair, pixel }
        })
        .collect()
});

/// Writes w₁ of every pair of the batch to `out` (as a renderer keeps each weight). The stores
/// have no dependency chain, unlike a running sum, so they do not set the pace, and the final
/// `black_box` keeps them (and so every evaluation) from being optimised away.
fn weigh_batch(heuristic: Heuristic, budget: &Budget, inputs: &[Input], out: &mut [f64]) {
    for (w1, i) in out.iter_mut().zip(inputs) {
        *w1 = heuristic.weight(budget, &i.pair, Some(&i.pixel)).w1;
    }
    divan::black_box(out);
}

fn parse(mode: &str) -> Heuristic {
    Heuristic::parse(mode).unwrap_or_else(|| panic!("unknown mode {mode}"))
}

#[divan::bench(args = Heuristic::ALL_NAMES)]
fn weight(bencher: Bencher, mode: &str) {
    let heuristic = parse(mode);
    let budget = budget();
    let inputs = &*INPUTS;
    let mut out = vec![0.0; inputs.len()];
    bencher
        .counter(ItemsCount::new(inputs.len()))
        .bench_local(|| weigh_batch(heuristic, &budget, inputs, &mut out));
}

#[divan::bench(consts = THREADS, args = Heuristic::ALL_NAMES, sample_count = 50)]
fn weight_parallel<const THREADS: usize>(bencher: Bencher, mode: &str) {
    let heuristic = parse(mode);
    let budget = budget();
    let inputs = &*INPUTS;
    let pool = thread_pool(THREADS);
    // One output batch per repeat, allocated before timing.
    let mut out = vec![0.0; REPEATS * inputs.len()];
    bencher.counter(ItemsCount::new(out.len())).bench_local(|| {
        pool.install(|| {
            out.par_chunks_mut(inputs.len())
                .for_each(|out| weigh_batch(heuristic, &budget, inputs, out));
        })
    });
}
