//! `bdpm render`: passes with a progress bar, then the EXR, PNG preview, noise map and JSON
//! report. An interrupt (SIGINT/SIGTERM) stops the render after the pass in flight and writes
//! what was accumulated (see [`crate::signal`]).
use std::path::PathBuf;
use std::process::ExitCode;

use bdpm_integrator::human_bytes;
use bdpm_output::accum;
use bdpm_output::cli::{CliResult, Overrides, parse_bytes, positive, whole};
use bdpm_output::exr::Precision;
use bdpm_output::header;
use bdpm_output::system::available_memory;
use clap::Args;

use crate::session::{self, Job, RenderSession, StopReason};
use crate::signal;

// The field docs are clap's help text, printed in a terminal: `<scene>` there is a
// placeholder, not an HTML tag.
#[allow(rustdoc::invalid_html_tags)]
/// Arguments of this subcommand.
#[derive(Args, Debug)]
pub(crate) struct RenderArgs {
    /// Scene file (TOML, or a Mitsuba 3 scene ending in .xml); with --resume, the one the
    /// accumulation file names by default.
    #[arg(required_unless_present = "resume")]
    scene: Option<PathBuf>,
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
    /// Also write denoiser inputs as EXR layers albedo.R/G/B (directional albedo of the
    /// surface first seen, in [0, 1]) and normal.X/Y/Z (its world-space unit shading normal),
    /// averaged over the pixel's camera samples of pass 0; 0 where nothing is seen.
    #[arg(long)]
    aov: bool,
    /// Sample type of the EXR's colour and layer channels (OUT.accum.exr stays exact).
    #[arg(long, value_enum, value_name = "P", default_value = "float")]
    exr_precision: Precision,
    /// Refuse to start a render whose estimated peak memory exceeds this, e.g. 8G, 512M,
    /// 100000K or a number of bytes (K, M, G, T are powers of 1024). Default: the memory
    /// available on this machine (MemAvailable of /proc/meminfo), no limit where unknown.
    #[arg(long, value_parser = parse_bytes)]
    max_memory: Option<u64>,
    /// Report each stage's peak memory (JSON memory.stage_peaks; Linux). It resets the
    /// kernel's high-water mark per stage, so `time -f %M` then sees the last stage only.
    #[arg(long)]
    stage_memory: bool,
    /// Global index of the first pass: a partial render of passes K..K+N (with --passes N)
    /// whose random streams are those of the same passes of a full render. Writes
    /// OUT.accum.exr for `bdpm merge` and `--resume`.
    #[arg(long, value_name = "K", value_parser = whole::<u32>)]
    first_pass: Option<u32>,
    /// Continue the render held by this accumulation file (finished or interrupted) with the
    /// next --passes passes after the last one it holds, with the scene and settings flags its
    /// header records (a settings flag given again must have the recorded value).
    #[arg(long, value_name = "PREVIOUS.accum.exr")]
    resume: Option<PathBuf>,
    /// Also write OUT.accum.exr, every pass's estimates for `bdpm merge` and `--resume`
    /// (24 bytes per pixel per pass before compression; implied by --first-pass and --resume).
    #[arg(long)]
    accumulate: bool,
    /// Stop after the pass during which the render time reaches SECONDS (--passes stays the
    /// upper limit).
    #[arg(long, value_name = "SECONDS", value_parser = positive)]
    time_budget: Option<f64>,
    /// Stop after the first pass that brings the image's mean relative standard error (of
    /// the luminance, over pixels with a non-zero mean) below X, e.g. 0.05 (--passes stays the
    /// upper limit).
    #[arg(long, value_name = "X", value_parser = positive)]
    target_noise: Option<f64>,
    /// Rewrite OUT.png and OUT.exr with the passes so far whenever SECONDS of wall time have
    /// passed since the last preview (checked after each pass; written as a set, each file
    /// replaced whole). The report's plan.previews_written counts them.
    // `-1` is a value here, refused by `positive` with a message naming the flag.
    #[arg(long, value_name = "SECONDS", value_parser = positive, allow_negative_numbers = true)]
    preview_every: Option<f64>,
}

/// Arguments of `bdpm merge`.
#[derive(Args, Debug)]
pub(crate) struct MergeArgs {
    /// Accumulation files of the parts (OUT.accum.exr of `bdpm render --first-pass`), in any
    /// order.
    #[arg(required = true, value_name = "PART.accum.exr")]
    parts: Vec<PathBuf>,
    /// Output EXR path; OUT.png, OUT-noise.png, OUT.json and OUT.accum.exr go beside it.
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    /// Load the scene from this file instead of the path stored in the parts (its contents
    /// must be the same: the hash is checked).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Do not draw a progress bar.
    #[arg(long)]
    quiet: bool,
    /// Worker threads for preparing the renderer (default: all cores).
    #[arg(long, value_parser = whole::<usize>)]
    threads: Option<usize>,
    /// Refuse to merge when the estimated peak memory (the renderer's, plus the parts'
    /// passes held and written: 48 bytes per pixel per pass) exceeds this, e.g. 8G or 512M.
    /// Default: the memory available on this machine.
    #[arg(long, value_parser = parse_bytes)]
    max_memory: Option<u64>,
}

/// Refuses to read accumulation files whose passes alone would exceed `max_memory` (default:
/// the available memory), judged from their headers: the full estimate, with the renderer's
/// part, follows once the scene is loaded, but reading comes first.
fn refuse_to_read(paths: &[PathBuf], max_memory: Option<u64>, advice: &str) -> CliResult<()> {
    let (limit, source) = match max_memory {
        Some(b) => (Some(b), "--max-memory"),
        None => (available_memory(), "available memory"),
    };
    let Some(limit) = limit else {
        return Ok(());
    };
    let mut total = 0u64;
    for p in paths {
        total = total.saturating_add(accum::held_bytes(p)?);
    }
    if total > limit {
        return Err(format!(
            "{}: the passes to read need about {} ({} bytes per pixel per pass), more than the {source} of {}; {advice} (or raise --max-memory)",
            paths
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
            human_bytes(total),
            accum::BYTES_PER_PIXEL_PASS,
            human_bytes(limit)
        ));
    }
    Ok(())
}

/// What an interrupted merge does: nothing is written (the parts are unchanged, and a rerun
/// of the same merge loses nothing); exit code [`signal::EXIT_INTERRUPTED`].
fn merge_interrupted() -> ExitCode {
    bdpm_output::say_err!("bdpm: merge interrupted: nothing was written");
    ExitCode::from(signal::EXIT_INTERRUPTED)
}

/// Runs the subcommand. Exit code 0 after a complete render, [`signal::EXIT_INTERRUPTED`]
/// after an interrupted one (whose outputs hold the passes done, if any).
pub(crate) fn run(args: RenderArgs) -> CliResult<ExitCode> {
    // Installed first, so that an interrupt during loading and preparation also stops the
    // render cleanly (before its first pass) rather than killing it.
    signal::install(signal::Stop::AfterPass)?;
    if args.resume.is_some() && args.first_pass.is_some() {
        return Err(
            "--resume continues after the passes the file holds; do not also give --first-pass"
                .into(),
        );
    }
    let accumulate = args.accumulate || args.first_pass.is_some() || args.resume.is_some();
    if args.techniques && accumulate {
        return Err("--techniques cannot be combined with --first-pass, --resume or --accumulate: the accumulation file does not keep the technique layers".into());
    }
    let held = match &args.resume {
        Some(path) => {
            refuse_to_read(
                std::slice::from_ref(path),
                args.max_memory,
                "resume from a file with fewer passes",
            )?;
            Some(accum::read(path)?)
        }
        None => None,
    };
    let (scene, overrides) = match &held {
        Some(h) => (
            args.scene.unwrap_or_else(|| h.identity.scene.clone()),
            header::over_recorded(&h.path, &h.identity.overrides, &args.overrides)?,
        ),
        // Without --resume clap requires the scene.
        None => (
            args.scene.ok_or("give the scene file (TOML)")?,
            args.overrides,
        ),
    };
    run_job(Job {
        scene,
        overrides,
        output: args.output,
        quiet: args.quiet,
        techniques: args.techniques,
        aov: args.aov,
        precision: args.exr_precision,
        max_memory: args.max_memory,
        stage_memory: args.stage_memory,
        first_pass: args.first_pass,
        held_from: held.iter().map(|h| h.path.clone()).collect(),
        held,
        accumulate,
        time_budget: args.time_budget,
        target_noise: args.target_noise,
        preview_every: args.preview_every,
        merge: false,
    })
}

/// Runs `bdpm merge`: checks that the parts belong to one render and do not overlap, then
/// replays their passes in pass order into a fresh film and writes the outputs of `render`
/// (and a merged accumulation file), with the bits of one render of the union of the passes.
pub(crate) fn merge(args: MergeArgs) -> CliResult<ExitCode> {
    signal::install(signal::Stop::WithoutWriting)?;
    refuse_to_read(&args.parts, args.max_memory, "merge fewer parts at once")?;
    let mut parts = Vec::with_capacity(args.parts.len());
    for p in &args.parts {
        parts.push(accum::read(p)?);
        if signal::requested() {
            return Ok(merge_interrupted());
        }
    }
    let (held, sources) = accum::combine(parts)?;
    let mut overrides = Overrides::from_args(&held.identity.overrides)
        .map_err(|e| format!("{}: {e}", held.path.display()))?;
    overrides.threads = args.threads;
    run_job(Job {
        scene: args.scene.unwrap_or_else(|| held.identity.scene.clone()),
        overrides,
        output: Some(args.output),
        quiet: args.quiet,
        techniques: false,
        aov: false,
        precision: Precision::Float,
        max_memory: args.max_memory,
        stage_memory: false,
        first_pass: None,
        held: Some(held),
        held_from: sources,
        accumulate: true,
        time_budget: None,
        target_noise: None,
        preview_every: None,
        merge: true,
    })
}

/// Runs a job through the session's steps and turns interrupts into exit codes: a merge
/// interrupted writes nothing; a render interrupted during its preparation (radiance cache,
/// pixel table, pilots) stops within a chunk of that work and writes nothing, nor does one
/// interrupted before its first pass ends; otherwise the outputs hold the passes done.
fn run_job(job: Job) -> CliResult<ExitCode> {
    let (prepared, held) = session::prepare(job)?;
    signal::set_preparing(true);
    let started = RenderSession::new(&prepared, &signal::requested)?;
    signal::set_preparing(false);
    let mut session = match started {
        Ok(session) => session,
        Err(_) if prepared.is_merge() => return Ok(merge_interrupted()),
        Err(stage) => {
            // The held passes of a resume stay in their accumulation file, unchanged.
            bdpm_output::say_err!(
                "bdpm: interrupted during preparation ({stage}): nothing was rendered and nothing was written ({})",
                prepared.scene_path().display()
            );
            return Ok(ExitCode::from(signal::EXIT_INTERRUPTED));
        }
    };
    session.replay(held);
    let stop = session.run(&signal::requested);
    if prepared.is_merge() && signal::requested() {
        return Ok(merge_interrupted());
    }
    signal::begin_writing();
    // A merge renders no pass: a signal from here on only waits for the files, and the merge
    // is complete, not interrupted.
    let stop = if !prepared.is_merge() && signal::requested() {
        StopReason::Interrupted
    } else {
        stop
    };
    if stop == StopReason::Interrupted && session.passes() == 0 {
        bdpm_output::say_err!(
            "bdpm: interrupted before the first pass finished: nothing was written ({})",
            prepared.scene_path().display()
        );
        return Ok(ExitCode::from(signal::EXIT_INTERRUPTED));
    }
    session.write(stop)?;
    Ok(if stop == StopReason::Interrupted {
        ExitCode::from(signal::EXIT_INTERRUPTED)
    } else {
        ExitCode::SUCCESS
    })
}
