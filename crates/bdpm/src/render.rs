//! `bdpm render`: passes with a progress bar, then the EXR, PNG preview, noise map and JSON
//! report. An interrupt (SIGINT/SIGTERM) stops the render after the pass in flight and writes
//! what was accumulated (see [`crate::signal`]).
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Instant, SystemTime};

use bdpm_integrator::{
    Film, Mode, Renderer, Techniques, WeightStats, estimate_memory, human_bytes,
};
use clap::Args;
use glam::DVec3;
use indicatif::{ProgressBar, ProgressStyle};

use crate::common::{CliResult, Overrides, default_output, image_mean, prepare, say, thread_pool};
use crate::output::luminance;
use crate::{output, report, signal};

/// Arguments of this subcommand.
#[derive(Args, Debug)]
pub(crate) struct RenderArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    #[command(flatten)]
    overrides: Overrides,
    /// Output EXR path (default: the scene's `output`, else out/<scene>.exr).
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
    /// Do not draw a progress bar.
    #[arg(long)]
    quiet: bool,
    /// Also write the image split by technique as EXR layers direct, x0_raw, x0_weighted,
    /// x1_raw, x1_weighted (BDPM modes only; direct + x0_weighted + x1_weighted = the image).
    #[arg(long)]
    techniques: bool,
    /// Refuse to start a render whose estimated peak memory exceeds this, e.g. 8G, 512M,
    /// 100000K or a number of bytes (K, M, G, T are powers of 1024). Default: the memory
    /// available on this machine (MemAvailable of /proc/meminfo), no limit where unknown.
    #[arg(long, value_parser = parse_bytes)]
    max_memory: Option<u64>,
}

/// A byte count with an optional binary suffix (K, M, G, T; `B` or `iB` may follow).
fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let t = t
        .strip_suffix("iB")
        .or_else(|| t.strip_suffix('B'))
        .unwrap_or(t);
    let (digits, shift) = match t.chars().last().map(|c| c.to_ascii_uppercase()) {
        Some('K') => (&t[..t.len() - 1], 10),
        Some('M') => (&t[..t.len() - 1], 20),
        Some('G') => (&t[..t.len() - 1], 30),
        Some('T') => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    let bad = || format!("'{s}' is not a size such as 8G, 512M or 1000000");
    let value: f64 = digits.trim().parse().map_err(|_| bad())?;
    let bytes = value * (1u64 << shift) as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(bad());
    }
    Ok(bytes as u64)
}

/// MemAvailable of /proc/meminfo, bytes (`None` where there is no such file).
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// The process's peak resident memory so far (VmHWM of /proc/self/status), bytes.
fn peak_resident_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = text.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Per-pixel sums of the pass luminance and its square: the noise map shows √V of the
/// luminance itself, which the film's per-channel variances cannot give (they lack the
/// covariances between channels).
struct LuminanceFilm {
    sum: Vec<f64>,
    sum_sq: Vec<f64>,
    passes: u32,
}

impl LuminanceFilm {
    fn new(pixels: usize) -> LuminanceFilm {
        LuminanceFilm {
            sum: vec![0.0; pixels],
            sum_sq: vec![0.0; pixels],
            passes: 0,
        }
    }

    fn add_pass(&mut self, estimates: &[DVec3]) {
        for ((s, q), e) in self.sum.iter_mut().zip(&mut self.sum_sq).zip(estimates) {
            let l = luminance(*e);
            *s += l;
            *q += l * l;
        }
        self.passes += 1;
    }

    /// √(unbiased per-pass variance) per pixel; zero with fewer than two passes.
    fn noise(&self) -> Vec<f64> {
        if self.passes < 2 {
            return vec![0.0; self.sum.len()];
        }
        let k = self.passes as f64;
        self.sum
            .iter()
            .zip(&self.sum_sq)
            .map(|(s, q)| ((q - s * s / k) / (k - 1.0)).max(0.0).sqrt())
            .collect()
    }
}

/// Sums of the technique layers over passes.
struct TechniqueSums {
    sums: Vec<Techniques>,
}

impl TechniqueSums {
    fn add_pass(&mut self, pass: &[Techniques]) {
        for (s, t) in self.sums.iter_mut().zip(pass) {
            s.direct += t.direct;
            s.x0_raw += t.x0_raw;
            s.x0_weighted += t.x0_weighted;
            s.x1_raw += t.x1_raw;
            s.x1_weighted += t.x1_weighted;
        }
    }

    /// The named layers: means over `passes`.
    fn layers(&self, passes: u32) -> Vec<(&'static str, Vec<DVec3>)> {
        let k = passes.max(1) as f64;
        let layer = |f: fn(&Techniques) -> DVec3| self.sums.iter().map(|t| f(t) / k).collect();
        vec![
            ("direct", layer(|t| t.direct)),
            ("x0_raw", layer(|t| t.x0_raw)),
            ("x0_weighted", layer(|t| t.x0_weighted)),
            ("x1_raw", layer(|t| t.x1_raw)),
            ("x1_weighted", layer(|t| t.x1_weighted)),
        ]
    }
}

/// Runs the subcommand. Exit code 0 after a complete render, [`signal::EXIT_INTERRUPTED`]
/// after an interrupted one (whose outputs hold the passes done, if any).
pub(crate) fn run(args: RenderArgs) -> CliResult<ExitCode> {
    // Installed first, so that an interrupt during loading and preparation also stops the
    // render cleanly (before its first pass) rather than killing it.
    signal::install()?;
    let started = SystemTime::now();
    let t_start = Instant::now();
    let loaded = prepare(&args.scene, &args.overrides)?;
    let load_seconds = t_start.elapsed().as_secs_f64();
    let (scene, settings) = (loaded.scene, loaded.settings);
    if args.techniques && matches!(settings.mode, Mode::Path | Mode::Light) {
        return Err(format!(
            "--techniques: mode '{}' is a single technique with no layers to split; use a BDPM mode (e.g. --mode optimal)",
            settings.mode
        ));
    }
    let requested = args
        .output
        .or(loaded.output)
        .unwrap_or_else(|| default_output(&args.scene));
    // Before any work: a directory that cannot be written, an output name that is a
    // directory or a device, or a second render to the same output is refused now, not after
    // the render. The lock is held until the files are in place.
    let outputs = output::Outputs::beside(&requested);
    let _lock = output::claim(&requested, &outputs, started)?;
    let pool = thread_pool(args.overrides.threads)?;
    let threads = pool.current_num_threads();

    // Before the cache, the pixel table, the film or any photon map is allocated: a render
    // that would run out of memory after minutes of work is refused now, naming what to lower.
    let estimate = pool.install(|| estimate_memory(&scene, &settings, args.techniques));
    let (limit, limit_source) = match args.max_memory {
        Some(b) => (Some(b), "--max-memory"),
        None => (available_memory(), "available memory"),
    };
    if let Some(limit) = limit
        && estimate.total() > limit
    {
        let parts: Vec<String> = estimate
            .items
            .iter()
            .filter(|i| i.bytes * 100 >= estimate.total())
            .map(|i| format!("{} {}", i.name, human_bytes(i.bytes)))
            .collect();
        return Err(format!(
            "{}: the render needs about {} ({}), more than the {} of {}; lower {} (or raise --max-memory)",
            args.scene.display(),
            human_bytes(estimate.total()),
            parts.join(", "),
            limit_source,
            human_bytes(limit),
            estimate.scalable_largest().lower
        ));
    }

    let t_prepare = Instant::now();
    let renderer = pool
        .install(|| Renderer::new(&scene, &settings))
        .map_err(|e| format!("{}: {e}", args.scene.display()))?
        .with_technique_layers(args.techniques);
    let prepare_seconds = t_prepare.elapsed().as_secs_f64();
    let radius_given = loaded.report.radius_given || args.overrides.radius.is_some();
    let mut warnings = loaded.report.warnings();
    warnings.extend(before_render_warnings(&scene, &settings, &renderer));
    for w in &warnings {
        say!("warning: {w}");
    }

    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        let bar = ProgressBar::new(settings.passes as u64 * renderer.work_per_pass());
        let style = ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {percent:>3}% pass {msg} (eta {eta})",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar());
        bar.set_style(style);
        bar
    };
    let pixels = settings.width as usize * settings.height as usize;
    let mut film = Film::new(settings.width, settings.height);
    let mut luma = LuminanceFilm::new(pixels);
    let mut techniques = args.techniques.then(|| TechniqueSums {
        sums: vec![Techniques::default(); pixels],
    });
    let mut samples = 0u64;
    let mut pass_means = Vec::new();
    let mut stage_totals: Vec<(&'static str, f64)> = Vec::new();
    let mut weights = WeightStats::default();
    let mut photon_map_bytes = 0u64;
    let mut photons_stored = 0u64;
    let t_render = Instant::now();
    for pass in 0..settings.passes {
        if signal::requested() {
            break;
        }
        bar.set_message(format!("{}/{}", pass + 1, settings.passes));
        let out = pool.install(|| renderer.render_pass(pass, &|n| bar.inc(n)));
        film.add_pass(&out.estimates, out.dropped);
        luma.add_pass(&out.estimates);
        if let (Some(sums), Some(t)) = (&mut techniques, &out.techniques) {
            sums.add_pass(t);
        }
        pass_means.push(image_mean(&out.estimates));
        samples += out.samples;
        weights.add(&out.weights);
        photon_map_bytes = photon_map_bytes.max(out.photon_map_bytes);
        photons_stored += out.photons_stored;
        for (name, secs) in out.stage_seconds {
            match stage_totals.iter_mut().find(|(n, _)| *n == name) {
                Some(entry) => entry.1 += secs,
                None => stage_totals.push((name, secs)),
            }
        }
    }
    let render_seconds = t_render.elapsed().as_secs_f64();
    bar.finish_and_clear();
    signal::begin_writing();
    let interrupted = signal::requested();
    if interrupted && film.passes() == 0 {
        eprintln!(
            "bdpm: interrupted before the first pass finished: nothing was written ({})",
            args.scene.display()
        );
        return Ok(ExitCode::from(signal::EXIT_INTERRUPTED));
    }

    // The files are written as a set: each to a temporary file beside its target, and only
    // when all four are complete are they renamed into place, the EXR last. A full disk or a
    // kill before that leaves the previous set whole (docs/robustness.md, "Outputs as a set").
    let run_id = output::run_id();
    let known_before = warnings.len();
    if film.mean().iter().all(|c| *c == DVec3::ZERO) {
        warnings.push(format!(
            "the image is black: no light reached the camera in {} passes (is the light sealed \
             inside a closed object, or the camera inside one?)",
            film.passes()
        ));
    }
    if film.dropped() > 0 {
        warnings.push(format!(
            "{} non-finite samples were dropped",
            film.dropped()
        ));
    }
    let mut header = report::header_attributes(&settings, &renderer, radius_given);
    header.push(("passes_done".into(), film.passes().to_string()));
    header.push(("interrupted".into(), interrupted.to_string()));
    header.push(("run_id".into(), run_id.clone()));
    let layers = techniques
        .as_ref()
        .map(|t| t.layers(film.passes()))
        .unwrap_or_default();
    let exr = output::stage_exr_with_layers(&outputs.exr, &film, &header, &layers)
        .map_err(named(&outputs.exr))?;
    drop(layers);
    let png = output::encode_png(&film)
        .and_then(|bytes| output::stage_bytes(&outputs.png, &bytes))
        .map_err(named(&outputs.png))?;
    let noise_png = output::encode_noise_png(
        (settings.width, settings.height),
        &luma.noise(),
        film.passes(),
    )
    .and_then(|bytes| output::stage_bytes(&outputs.noise_png, &bytes))
    .map_err(named(&outputs.noise_png))?;
    let run = report::RunReport::new(report::RunFacts {
        scene_path: &args.scene,
        settings: &settings,
        renderer: &renderer,
        load: &loaded.report,
        film: &film,
        threads,
        samples,
        load_seconds,
        prepare_seconds,
        render_seconds,
        pass_stages: &stage_totals,
        outputs: &outputs,
        interrupted,
        pass_means: &pass_means,
        weights: &weights,
        photon_map_bytes,
        photons_stored,
        run_id: &run_id,
        radius_given,
        warnings: &warnings,
        memory: report::MemoryFacts {
            estimate: &estimate,
            limit,
            limit_source,
            peak_resident: peak_resident_memory(),
        },
    });
    let json = output::stage_bytes(&outputs.json, run.to_json().as_bytes())
        .map_err(named(&outputs.json))?;
    output::commit_all(vec![png, noise_png, json, exr])?;
    if interrupted {
        say!(
            "interrupted after {} of {} passes; the outputs hold those passes",
            film.passes(),
            settings.passes
        );
    }
    say!(
        "rendered {} ({}x{}, mode {}, {} passes) in {:.2} s: {:.3} M samples/s on {} threads",
        args.scene.display(),
        settings.width,
        settings.height,
        settings.mode,
        film.passes(),
        render_seconds,
        samples as f64 / render_seconds.max(1e-9) / 1e6,
        threads
    );
    for w in &warnings[known_before..] {
        say!("warning: {w}");
    }
    let written: Vec<String> = outputs
        .all()
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    say!("wrote {}", written.join(", "));
    Ok(if interrupted {
        ExitCode::from(signal::EXIT_INTERRUPTED)
    } else {
        ExitCode::SUCCESS
    })
}

/// An error message prefixed with the file it concerns.
fn named(path: &Path) -> impl Fn(String) -> String + '_ {
    move |e| format!("{}: {e}", path.display())
}

/// A merge radius above this fraction of the scene's largest extent draws a warning: the
/// density estimate then averages photons over a large part of the scene.
const LARGE_RADIUS_FRACTION: f32 = 0.1;

/// Warnings known before the first pass: a merge radius that is a large part of the scene.
fn before_render_warnings(
    scene: &bdpm_scene::Scene,
    settings: &bdpm_integrator::RenderSettings,
    renderer: &Renderer<'_>,
) -> Vec<String> {
    let mut warnings = Vec::new();
    let (lo, hi) = scene.geometry.bounds();
    let extent = (hi - lo).max_element();
    let r = renderer.radius();
    if matches!(settings.mode, Mode::Bdpm(_)) && r > LARGE_RADIUS_FRACTION * extent {
        warnings.push(format!(
            "the merge radius {r} m is {:.0}% of the scene's largest extent ({extent} m): photons \
             are merged across large parts of the scene, so the image is strongly blurred and biased",
            100.0 * r / extent
        ));
    }
    warnings
}
