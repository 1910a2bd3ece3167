//! Times `HashGrid::build` alone on 1 and 2 threads: N points (default 640,000, what a Lambert
//! paper pass stores) spread uniformly over five walls of a 5.5 m box, merge radius 1.75 mm,
//! median and fastest of 21 builds each, in milliseconds. The grid's counting sort used to be a
//! serial stretch of every photon pass (docs/performance.md).
//!
//! Run: `cargo bench -p bdpm-grid --bench grid_build [-- N]` (a benchmark target without the
//! test harness: `cargo bench` runs its `main`, `cargo test` does not).

#[path = "common/walls.rs"]
mod walls;

use bdpm_grid::HashGrid;

fn main() {
    // `cargo bench` passes `--bench` (and any filter given) to a harness-less bench: flags
    // are not N.
    let n: usize = match std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .map(|s| s.parse())
    {
        None => 640_000,
        Some(Ok(n)) => n,
        Some(Err(e)) => {
            eprintln!("grid_build: N must be a count of points: {e}");
            std::process::exit(2);
        }
    };
    let points = walls::wall_points(n);
    for threads in [1, 2] {
        let pool = match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
            Ok(pool) => pool,
            Err(e) => {
                eprintln!("grid_build: cannot start {threads} threads: {e}");
                std::process::exit(1);
            }
        };
        let mut ms: Vec<f64> = (0..21)
            .map(|_| {
                let t = std::time::Instant::now();
                std::hint::black_box(pool.install(|| HashGrid::build(&points, 0.00175)));
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        ms.sort_by(f64::total_cmp);
        println!(
            "{n} points, {threads} thread(s): median {:.2} ms, fastest {:.2} ms",
            ms[ms.len() / 2],
            ms[0]
        );
    }
}
