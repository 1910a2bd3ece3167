//! `bdpm render`: passes with a progress bar, then the EXR, PNG and JSON report.
use std::path::PathBuf;
use std::time::Instant;

use bdpm_integrator::{Film, Renderer};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use crate::common::{CliResult, Overrides, default_output, image_mean, prepare, thread_pool};
use crate::{output, report};

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
}

pub(crate) fn run(args: RenderArgs) -> CliResult<()> {
    let t_start = Instant::now();
    let loaded = prepare(&args.scene, &args.overrides)?;
    let load_seconds = t_start.elapsed().as_secs_f64();
    let (scene, settings) = (loaded.scene, loaded.settings);
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
