//! `bdpm bench`: throughput benchmarks.
//!
//! For each thread count and mode: one warm-up pass, then `--repeats` runs of `--passes`
//! timed passes, each run with a fresh renderer (so the preparatory stages are timed too).
//! Photons per second come from the pass's "photons" stage (its "light tracing" stage for the
//! `light` mode) and N_F, camera samples per second from the "camera" stage and the sample
//! count. Every figure is the median over the runs. The machine is shared, so the report
//! records the core count and the load average before and after.
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use bdpm_integrator::{Mode, RenderSettings, Renderer, Stage, human_bytes};
use clap::Args;

use bdpm_output::cli::{
    CliResult, Overrides, parse_bytes, parse_resolution, prepare, thread_pool, whole,
};
use bdpm_output::files::stem_of;
use bdpm_output::memory::MemoryLimit;
use bdpm_output::system::{cpu_model, load_average, peak_resident_memory};

// The field docs are clap's help text, printed in a terminal: `<scene>` there is a
// placeholder, not an HTML tag.
#[allow(rustdoc::invalid_html_tags)]
/// Arguments of this subcommand.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scene file (TOML, or a Mitsuba 3 scene ending in .xml).
    scene: PathBuf,
    // The help lists every key an entry may set, from the parser's own list.
    #[arg(long, value_delimiter = ',', help = crate::modes_help("time"))]
    modes: Vec<String>,
    /// Image size as WxH (default: the scene's).
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// Photons emitted per pass, N_F (default: the scene's).
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<u64>)]
    photons: Option<u64>,
    /// Camera samples per pixel per pass, N_B (default: the scene's).
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<u32>)]
    spp: Option<u32>,
    /// Timed passes per run.
    #[arg(long, default_value_t = 2, allow_negative_numbers = true, value_parser = whole::<u32>)]
    passes: u32,
    /// Runs per mode and thread count; figures are medians over them.
    #[arg(long, default_value_t = 3, allow_negative_numbers = true, value_parser = whole::<u32>)]
    repeats: u32,
    /// Thread counts, comma-separated (default: 1 and all cores).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, value_parser = whole::<usize>)]
    threads_list: Vec<usize>,
    /// Master seed.
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<u64>)]
    seed: Option<u64>,
    /// Refuse to start when the estimated peak memory of an entry's renderer (one is held at a
    /// time) exceeds this, e.g. 8G or 512M (K, M, G, T are powers of 1024). Default: the
    /// memory available on this machine (MemAvailable of /proc/meminfo), no limit where
    /// unknown.
    #[arg(long, value_parser = parse_bytes)]
    max_memory: Option<u64>,
    /// Markdown output (default: out/bench-<scene>.md).
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
}

/// Median of a list (NaN for an empty one); the mean of the middle two for an even count.
pub(crate) fn median(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The medians of one (mode, thread count) cell.
#[derive(Clone, Debug)]
struct Cell {
    mode: String,
    threads: usize,
    /// Photons traced per second (NaN when the mode traces none).
    photons_per_s: f64,
    /// Camera samples per second.
    samples_per_s: f64,
    /// Wall time of one pass, s.
    pass_s: f64,
    /// Preparatory stages: (name, median s).
    prep: Vec<(String, f64)>,
}

fn rate(count: f64, seconds: f64) -> f64 {
    if seconds > 0.0 {
        count / seconds
    } else {
        f64::NAN
    }
}

fn fmt_rate(v: f64) -> String {
    if v.is_finite() {
        format!("{:.3}", v / 1e6)
    } else {
        "—".into()
    }
}

/// Times one mode at one thread count.
fn time_cell(
    scene: &bdpm_scene::Scene,
    settings: &bdpm_integrator::RenderSettings,
    name: &str,
    threads: usize,
    passes: u32,
    repeats: u32,
) -> CliResult<Cell> {
    let pool = thread_pool(Some(threads))?;
    let build = || {
        pool.install(|| Renderer::new(scene, settings))
            .map_err(|e| format!("--modes entry '{name}': {e}"))
    };
    // Warm-up: caches, page faults, the allocator, the CPU's clock.
    {
        let r = build()?;
        let _ = pool.install(|| r.render_pass(passes + repeats * passes, &|_| {}));
    }
    let photon_stage = if settings.mode == Mode::Light {
        Stage::LightTracing
    } else {
        Stage::Photons
    };
    let (mut photon_rates, mut sample_rates, mut pass_times) = (vec![], vec![], vec![]);
    let mut prep: Vec<(String, Vec<f64>)> = Vec::new();
    for rep in 0..repeats {
        let r = build()?;
        for st in r.stages() {
            match prep.iter_mut().find(|(n, _)| n == st.stage.name()) {
                Some((_, v)) => v.push(st.seconds),
                None => prep.push((st.stage.name().to_string(), vec![st.seconds])),
            }
        }
        let (mut photon_s, mut camera_s, mut samples) = (0.0, 0.0, 0u64);
        let t = Instant::now();
        for k in 0..passes {
            let out = pool.install(|| r.render_pass(rep * passes + k, &|_| {}));
            samples += out.samples;
            for (stage, secs) in &out.stage_seconds {
                if *stage == photon_stage {
                    photon_s += secs;
                } else if *stage == Stage::Camera {
                    camera_s += secs;
                }
            }
        }
        pass_times.push(t.elapsed().as_secs_f64() / passes as f64);
        photon_rates.push(if photon_s > 0.0 {
            rate((settings.photons * passes as u64) as f64, photon_s)
        } else {
            f64::NAN
        });
        sample_rates.push(rate(samples as f64, camera_s));
    }
    Ok(Cell {
        mode: name.to_string(),
        threads,
        photons_per_s: median(&photon_rates),
        samples_per_s: median(&sample_rates),
        pass_s: median(&pass_times),
        prep: prep.into_iter().map(|(n, v)| (n, median(&v))).collect(),
    })
}

/// The thread counts of `--threads-list` (default: 1 and every core), each checked.
fn threads_list(args: &BenchArgs, cores: usize) -> CliResult<Vec<usize>> {
    let mut list = if args.threads_list.is_empty() {
        vec![1, cores]
    } else {
        args.threads_list.clone()
    };
    list.dedup();
    // The cap of `--threads`, for the same reason: thousands of threads only queue.
    let max = (8 * cores).max(64);
    for &t in &list {
        if t == 0 || t > max {
            return Err(format!(
                "--threads-list: {t} threads is outside 1 to {max} (8 per core, {cores} cores)"
            ));
        }
    }
    Ok(list)
}

/// The timed cells and what the report says about the run that timed them.
struct Timing {
    cells: Vec<Cell>,
    /// Wall time of all cells, s.
    seconds: f64,
    load_before: String,
    load_after: String,
    /// The estimated peak of the largest entry's renderer (one is held at a time), bytes.
    estimate: u64,
}

/// Runs the subcommand: checks, a memory gate, the cells, the report.
pub(crate) fn run(args: BenchArgs) -> CliResult<()> {
    if args.passes == 0 {
        return Err("--passes must be at least 1 (timed passes per run)".into());
    }
    if args.repeats == 0 {
        return Err("--repeats must be at least 1 (runs per mode and thread count)".into());
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads_list = threads_list(&args, cores)?;
    let variants = crate::parse_modes(&args.modes)?;
    let overrides = Overrides {
        resolution: args.resolution,
        photons: args.photons,
        spp: args.spp,
        seed: args.seed,
        ..Overrides::default()
    };
    let loaded = prepare(&args.scene, &overrides)?;
    let (scene, base) = (loaded.scene, loaded.settings);
    // One renderer is held at a time (each cell prepares its own and drops it): the bench
    // needs what its largest entry needs.
    let estimates: Vec<_> = crate::entry_estimates(&scene, &variants, &base, &thread_pool(None)?)?
        .into_iter()
        .map(|(_, e)| e)
        .collect();
    let largest = estimates.iter().max_by_key(|e| e.total());
    if let Some(largest) = largest {
        crate::refuse_above_limit(
            &args.scene,
            "bench",
            largest,
            &variants,
            &estimates,
            MemoryLimit::of(args.max_memory),
        )?;
    }
    let load_before = load_average();
    let started = Instant::now();
    let mut cells = Vec::new();
    for &threads in &threads_list {
        for variant in &variants {
            let name = &variant.name;
            let s = variant.settings(&base)?;
            let cell = time_cell(&scene, &s, name, threads, args.passes, args.repeats)?;
            bdpm_output::say_err!(
                "{name:>16} {threads} thread(s): {} M photons/s, {} M samples/s, {:.3} s/pass",
                fmt_rate(cell.photons_per_s),
                fmt_rate(cell.samples_per_s),
                cell.pass_s
            );
            cells.push(cell);
        }
    }
    let timing = Timing {
        cells,
        seconds: started.elapsed().as_secs_f64(),
        load_before,
        load_after: load_average(),
        estimate: largest.map_or(0, |e| e.total()),
    };
    let md = report(&args, &base, &variants, &threads_list, &timing);
    let stem = stem_of(&args.scene, "scene");
    let path = args
        .output
        .unwrap_or_else(|| PathBuf::from("out").join(format!("bench-{stem}.md")));
    crate::publish(&path, &md)
}

/// The markdown report: the run, the table of cells and the speed-ups.
fn report(
    args: &BenchArgs,
    base: &RenderSettings,
    variants: &[crate::Variant],
    threads_list: &[usize],
    t: &Timing,
) -> String {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut md = String::new();
    let command: Vec<String> = std::env::args().collect();
    let _ = writeln!(
        md,
        "## Bench: {} at {}x{}, N_F = {}, N_B = {}, seed {}\n",
        args.scene.display(),
        base.width,
        base.height,
        base.photons,
        base.spp,
        base.seed
    );
    let _ = writeln!(md, "Command: `{}`\n", command.join(" "));
    let _ = writeln!(
        md,
        "Machine: {cores} cores ({}); load average (1, 5, 15 min) {} before, {} after; {:.0} s \
         in all. The machine is shared: figures are medians of {} runs of {} timed passes, each \
         after one warm-up pass. Memory: the largest entry's renderer (one is held at a time) \
         was estimated at {}; the measured peak resident memory (VmHWM) is {}.\n",
        cpu_model(),
        t.load_before,
        t.load_after,
        t.seconds,
        args.repeats,
        args.passes,
        human_bytes(t.estimate),
        peak_resident_memory().map_or("unknown".into(), human_bytes)
    );
    let _ = writeln!(
        md,
        "| mode | threads | M photons/s | M camera samples/s | s/pass | preparation (s) |"
    );
    let _ = writeln!(md, "|---|---:|---:|---:|---:|---|");
    for c in &t.cells {
        let prep = if c.prep.is_empty() {
            "—".to_string()
        } else {
            c.prep
                .iter()
                .map(|(n, s)| format!("{n} {s:.2}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {:.3} | {} |",
            c.mode,
            c.threads,
            fmt_rate(c.photons_per_s),
            fmt_rate(c.samples_per_s),
            c.pass_s,
            prep
        );
    }
    if threads_list.len() >= 2 {
        speed_ups(&mut md, variants, threads_list, &t.cells);
    }
    md
}

/// The table of speed-ups of the last thread count over the first.
fn speed_ups(md: &mut String, variants: &[crate::Variant], threads_list: &[usize], cells: &[Cell]) {
    let (t1, tn) = (threads_list[0], threads_list[threads_list.len() - 1]);
    let _ = writeln!(
        md,
        "\nSpeed-up of {tn} threads over {t1} (ratio of the medians above):\n"
    );
    let _ = writeln!(md, "| mode | photons | camera samples | pass time |");
    let _ = writeln!(md, "|---|---:|---:|---:|");
    for name in variants.iter().map(|v| &v.name) {
        let find = |t: usize| cells.iter().find(|c| &c.mode == name && c.threads == t);
        if let (Some(a), Some(b)) = (find(t1), find(tn)) {
            let ratio = |x: f64, y: f64| {
                if x.is_finite() && y.is_finite() && x > 0.0 {
                    format!("{:.2}×", y / x)
                } else {
                    "—".into()
                }
            };
            let _ = writeln!(
                md,
                "| {name} | {} | {} | {} |",
                ratio(a.photons_per_s, b.photons_per_s),
                ratio(a.samples_per_s, b.samples_per_s),
                ratio(b.pass_s, a.pass_s)
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(median(&[]).is_nan());
        assert_eq!(median(&[f64::NAN, 5.0]), 5.0);
    }
}
