//! `bdpm`: the command-line driver. It parses arguments, loads the scene, runs the integrator
//! pass by pass with a progress bar, and writes the EXR, the PNG preview and the JSON run
//! report. All rendering logic lives in the library crates; this binary is the IO boundary.

mod output;
mod report;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use bdpm_integrator::{Film, Mode, RenderSettings, Renderer};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

/// Bidirectional photon mapping with optimal MIS weights.
#[derive(Parser, Debug)]
#[command(name = "bdpm", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene to OUT.exr, with OUT.png (preview) and OUT.json (run report) beside it.
    Render(RenderArgs),
}

/// Settings that override the scene file's `[render]` table.
#[derive(Args, Debug, Clone, Default)]
struct Overrides {
    /// Integrator and weight mode: path, bdd0, bdd1, threshold, algebraic-direct, algebraic,
    /// optimal, balance, power.
    #[arg(long)]
    mode: Option<String>,
    /// Number of passes.
    #[arg(long)]
    passes: Option<u32>,
    /// Image size as WxH, e.g. 256x256.
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// Photons emitted per pass (N_F).
    #[arg(long)]
    photons: Option<u64>,
    /// Camera samples per pixel per pass (N_B).
    #[arg(long)]
    spp: Option<u32>,
    /// Merge radius, metres.
    #[arg(long)]
    radius: Option<f32>,
    /// Master seed of all random streams.
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

#[derive(Args, Debug)]
struct RenderArgs {
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
}

fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WxH"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in '{s}'"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in '{s}'"))?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!(
            "resolution '{s}' must be between 1x1 and 16384x16384"
        ));
    }
    Ok((w, h))
}

/// An error for the user: one line, no backtrace.
type CliResult<T> = Result<T, String>;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("bdpm: error: {message}");
            ExitCode::FAILURE
        }
    }
}

/// Applies command-line overrides to the settings loaded from the scene file.
fn apply_overrides(settings: &mut RenderSettings, o: &Overrides) -> CliResult<()> {
    if let Some(name) = &o.mode {
        settings.mode = Mode::parse(name).ok_or_else(|| {
            format!(
                "--mode: unknown mode '{name}'; expected one of {}",
                Mode::names().join(", ")
            )
        })?;
    }
    if let Some(p) = o.passes {
        if p == 0 {
            return Err("--passes must be at least 1".into());
        }
        settings.passes = p;
    }
    if let Some((w, h)) = o.resolution {
        settings.width = w;
        settings.height = h;
    }
    if let Some(n) = o.photons {
        if n == 0 {
            return Err("--photons must be at least 1".into());
        }
        settings.photons = n;
    }
    if let Some(n) = o.spp {
        if n == 0 {
            return Err("--spp must be at least 1".into());
        }
        settings.spp = n;
    }
    if let Some(r) = o.radius {
        if !(r.is_finite() && r > 0.0) {
            return Err(format!(
                "--radius must be a positive number of metres, not {r}"
            ));
        }
        settings.radius = Some(r);
    }
    if let Some(s) = o.seed {
        settings.seed = s;
    }
    Ok(())
}

fn thread_pool(threads: Option<usize>) -> CliResult<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        if t == 0 {
            return Err("--threads must be at least 1".into());
        }
        b = b.num_threads(t);
    }
    b.build()
        .map_err(|e| format!("cannot start worker threads: {e}"))
}

/// Mean over pixels of one pass's estimates, per channel.
fn image_mean(estimates: &[glam::DVec3]) -> [f64; 3] {
    let sum: glam::DVec3 = estimates.iter().copied().sum();
    (sum / estimates.len().max(1) as f64).to_array()
}

fn default_output(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().map(|s| s.to_string_lossy().into_owned());
    PathBuf::from("out").join(format!("{}.exr", stem.unwrap_or_else(|| "render".into())))
}

fn render(args: RenderArgs) -> CliResult<()> {
    let t_start = Instant::now();
    let loaded = bdpm_load::load_scene(&args.scene).map_err(|e| e.to_string())?;
    let load_seconds = t_start.elapsed().as_secs_f64();
    let mut scene = loaded.scene;
    let mut settings = loaded.settings;
    apply_overrides(&mut settings, &args.overrides)?;
    if (scene.camera.width, scene.camera.height) != (settings.width, settings.height) {
        scene.camera = scene
            .camera
            .with_resolution(settings.width, settings.height)
            .map_err(|e| format!("--resolution: {e}"))?;
    }
    let exr_path = args
        .output
        .or(loaded.output)
        .unwrap_or_else(|| default_output(&args.scene));
    let pool = thread_pool(args.overrides.threads)?;
    let threads = pool.current_num_threads();

    let t_prepare = Instant::now();
    let renderer = pool
        .install(|| Renderer::new(&scene, &settings))
        .map_err(|e| format!("{}: {e}", args.scene.display()))?;
    let prepare_seconds = t_prepare.elapsed().as_secs_f64();

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
    let mut film = Film::new(settings.width, settings.height);
    let mut samples = 0u64;
    let mut pass_means = Vec::new();
    let mut stage_totals: Vec<(&'static str, f64)> = Vec::new();
    let t_render = Instant::now();
    for pass in 0..settings.passes {
        bar.set_message(format!("{}/{}", pass + 1, settings.passes));
        let out = pool.install(|| renderer.render_pass(pass, &|n| bar.inc(n)));
        film.add_pass(&out.estimates, out.dropped);
        pass_means.push(image_mean(&out.estimates));
        samples += out.samples;
        for (name, secs) in out.stage_seconds {
            match stage_totals.iter_mut().find(|(n, _)| *n == name) {
                Some(entry) => entry.1 += secs,
                None => stage_totals.push((name, secs)),
            }
        }
    }
    let render_seconds = t_render.elapsed().as_secs_f64();
    bar.finish_and_clear();

    let outputs = output::Outputs::beside(&exr_path);
    let header = report::header_attributes(&settings, &renderer);
    output::write_exr(&outputs.exr, &film, &header)
        .map_err(|e| format!("{}: {e}", outputs.exr.display()))?;
    output::write_png(&outputs.png, &film)
        .map_err(|e| format!("{}: {e}", outputs.png.display()))?;
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
        interrupted: false,
        pass_means: &pass_means,
    });
    output::write_atomic(&outputs.json, run.to_json().as_bytes())
        .map_err(|e| format!("{}: {e}", outputs.json.display()))?;
    println!(
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
    if film.dropped() > 0 {
        println!(
            "warning: {} non-finite samples were dropped",
            film.dropped()
        );
    }
    println!(
        "wrote {}, {}, {}",
        outputs.exr.display(),
        outputs.png.display(),
        outputs.json.display()
    );
    Ok(())
}
