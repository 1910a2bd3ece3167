//! `bdpm render`: passes with a progress bar, then the EXR, PNG preview, noise map and JSON
//! report. An interrupt (SIGINT/SIGTERM) stops the render after the pass in flight and writes
//! what was accumulated (see [`crate::signal`]).
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Instant, SystemTime};

use bdpm_integrator::{
    Film, MemoryItem, Mode, Renderer, Stage, StageProbe, WeightStats, estimate_memory,
    first_hit_layers, human_bytes,
};
use bdpm_output::accum::{self, Identity, PassRecord};
use bdpm_output::cli::{
    CliResult, Overrides, StagePeaks, available_memory, default_output, parse_bytes, positive,
    prepare, progress_bar, thread_pool, whole,
};
use bdpm_output::exr::{self as exr_file, Precision, RGB, TechniqueSums};
use bdpm_output::files::{self, Outputs};
use bdpm_output::preview;
use bdpm_output::report;
use bdpm_output::say;
use bdpm_output::stats::{PixelStats, image_mean};
use clap::Args;
use glam::DVec3;

use crate::signal;

// The field docs are clap's help text, printed in a terminal: `<scene>` there is a
// placeholder, not an HTML tag.
#[allow(rustdoc::invalid_html_tags)]
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
    /// next --passes passes after the last one it holds; same scene and settings required.
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
    run_job(Job {
        scene: args.scene,
        overrides: args.overrides,
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
        merge: true,
    })
}

/// One run of the render driver: passes replayed from accumulation files, then passes
/// rendered, then the outputs.
struct Job {
    scene: PathBuf,
    overrides: Overrides,
    output: Option<PathBuf>,
    quiet: bool,
    techniques: bool,
    /// Write the first-hit `albedo` and `normal` layers.
    aov: bool,
    /// Sample type of the EXR's channels.
    precision: Precision,
    max_memory: Option<u64>,
    stage_memory: bool,
    /// First pass to render (default 0, or after the held passes when resuming).
    first_pass: Option<u32>,
    /// Passes to replay before rendering (`--resume`, `bdpm merge`).
    held: Option<accum::Accumulation>,
    /// The files the held passes came from, for the report.
    held_from: Vec<PathBuf>,
    /// Write OUT.accum.exr.
    accumulate: bool,
    time_budget: Option<f64>,
    target_noise: Option<f64>,
    /// `bdpm merge`: render no pass.
    merge: bool,
}

fn run_job(args: Job) -> CliResult<ExitCode> {
    let started = SystemTime::now();
    let t_start = Instant::now();
    let loaded = prepare(&args.scene, &args.overrides)?;
    let load_seconds = t_start.elapsed().as_secs_f64();
    let (scene, mut settings) = (loaded.scene, loaded.settings);
    let identity = Identity::of(
        &args.scene,
        &loaded.report.gltf_files,
        &settings,
        &args.overrides,
    )?;
    let scene_hash = accum::scene_hash(&args.scene, &loaded.report.gltf_files)?;
    let (held, held_from) = match args.held {
        Some(h) => {
            if let Some(why) = identity.mismatch(&h.identity) {
                return Err(format!(
                    "{}: not a part of this render of {}: {why}",
                    h.path.display(),
                    args.scene.display()
                ));
            }
            (h.passes, args.held_from)
        }
        None => (Vec::new(), Vec::new()),
    };
    if let Some(r) = held.first()
        && r.estimates.len() != settings.width as usize * settings.height as usize
    {
        return Err(format!(
            "{}: its passes do not have {}x{} pixels",
            held_from[0].display(),
            settings.width,
            settings.height
        ));
    }
    let first = match (args.first_pass, held.last()) {
        (Some(k), _) => k,
        (None, Some(last)) => last
            .index
            .checked_add(1)
            .ok_or("no pass left after pass 4294967295")?,
        (None, None) => 0,
    };
    let to_render = if args.merge {
        settings.passes = held.len() as u32;
        0
    } else {
        settings.passes
    };
    let end = first
        .checked_add(to_render)
        .ok_or("--first-pass + --passes exceeds the last pass index, 4294967295")?;
    if args.techniques && matches!(settings.mode, Mode::Path | Mode::Light) {
        return Err(format!(
            "--techniques: mode '{}' is a single technique with no layers to split; use a BDPM mode (e.g. --mode optimal)",
            settings.mode
        ));
    }
    let pixels = settings.width as usize * settings.height as usize;
    let requested = args
        .output
        .or(loaded.output)
        .unwrap_or_else(|| default_output(&args.scene));
    // Before any work: a directory that cannot be written, an output name that is a
    // directory or a device, or a second render to the same output is refused now, not after
    // the render. The lock is held until the files are in place.
    let outputs = Outputs::beside(&requested);
    let mut inputs: Vec<&Path> = held_from.iter().map(PathBuf::as_path).collect();
    inputs.push(&args.scene);
    let _lock = files::claim(&requested, &outputs, args.accumulate, &inputs, started)?;
    let pool = thread_pool(args.overrides.threads)?;
    let threads = pool.current_num_threads();

    // Before the cache, the pixel table, the film or any photon map is allocated: a render
    // that would run out of memory after minutes of work is refused now, naming what to lower.
    let mut estimate = pool.install(|| estimate_memory(&scene, &settings, args.techniques));
    if args.accumulate {
        // The passes of the accumulation file: held (read from files, or rendered and kept)
        // until the file is written, plus the copy the writer encodes, or the reader decodes.
        let kept = held.len() as u64 + u64::from(to_render);
        estimate.items.push(MemoryItem {
            name: "passes kept for the accumulation file",
            bytes: kept * pixels as u64 * accum::BYTES_PER_PIXEL_PASS,
            lower: if args.merge {
                "the passes merged at once (merge fewer parts, then merge the results)"
            } else {
                "--passes (or drop --accumulate)"
            },
        });
        estimate.items.sort_by_key(|i| std::cmp::Reverse(i.bytes));
    }
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
    let peaks = StagePeaks::default();
    let probe = args.stage_memory.then_some(&peaks as &dyn StageProbe);
    probe.inspect(|p| p.enter(Stage::Prepare));
    let mut renderer = pool
        .install(|| Renderer::new(&scene, &settings))
        .map_err(|e| format!("{}: {e}", args.scene.display()))?
        .with_technique_layers(args.techniques);
    if let Some(p) = probe {
        p.leave(Stage::Prepare);
        renderer.set_stage_probe(p);
    }
    let prepare_seconds = t_prepare.elapsed().as_secs_f64();
    let radius_given = loaded.report.radius_given || args.overrides.radius.is_some();
    let mut warnings = loaded.report.warnings();
    warnings.extend(renderer.warnings());
    for w in &warnings {
        say!("warning: {w}");
    }

    let bar = progress_bar(
        args.quiet,
        Some(to_render as u64 * renderer.work_per_pass()),
        "{spinner} [{elapsed_precise}] {bar:40} {percent:>3}% pass {msg} (eta {eta})",
    );
    let mut film = Film::new(settings.width, settings.height);
    let mut luma = PixelStats::new(pixels);
    let mut techniques = args.techniques.then(|| TechniqueSums::new(pixels));
    let mut samples = 0u64;
    let mut pass_means = Vec::new();
    let mut stage_totals: Vec<(Stage, f64)> = Vec::new();
    let mut weights = WeightStats::default();
    let mut photon_map_bytes = 0u64;
    let mut photons_stored = 0u64;
    // Held passes are replayed first: they all precede the passes rendered now, so the film
    // adds every pass in pass order, exactly as one render of all of them would.
    let mut records: Vec<PassRecord> = Vec::new();
    let replayed = held.len() as u32;
    for rec in held {
        film.add_pass(&rec.estimates, rec.dropped);
        luma.add_pass(&rec.estimates);
        pass_means.push(image_mean(&rec.estimates));
        samples += rec.samples;
        photons_stored += rec.photons_stored;
        records.push(rec);
    }
    let mut held_indices: Vec<u32> = records.iter().map(|r| r.index).collect();
    let replayed_samples = samples;
    let mut stop_reason = "completed";
    let mut rendered = 0u32;
    let t_render = Instant::now();
    for pass in first..end {
        if signal::requested() {
            break;
        }
        bar.set_message(format!("{}/{}", pass - first + 1, to_render));
        let out = pool.install(|| renderer.render_pass(pass, &|n| bar.inc(n)));
        rendered += 1;
        held_indices.push(pass);
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
        if args.accumulate {
            records.push(PassRecord {
                index: pass,
                estimates: out.estimates,
                dropped: out.dropped,
                samples: out.samples,
                photons_stored: out.photons_stored,
            });
        }
        let last = pass + 1 == end;
        if let Some(b) = args.time_budget
            && t_render.elapsed().as_secs_f64() >= b
            && !last
        {
            stop_reason = "time_budget";
            break;
        }
        if let Some(x) = args.target_noise
            && luma.mean_relative_stderr().is_some_and(|e| e < x)
            && !last
        {
            stop_reason = "target_noise";
            break;
        }
    }
    let render_seconds = t_render.elapsed().as_secs_f64();
    let rendered_samples = samples - replayed_samples;
    bar.finish_and_clear();
    if args.merge && signal::requested() {
        return Ok(merge_interrupted());
    }
    signal::begin_writing();
    // A merge renders no pass: a signal from here on only waits for the files, and the merge
    // is complete, not interrupted.
    let interrupted = !args.merge && signal::requested();
    if interrupted {
        stop_reason = "interrupted";
    }
    if interrupted && film.passes() == 0 {
        bdpm_output::say_err!(
            "bdpm: interrupted before the first pass finished: nothing was written ({})",
            args.scene.display()
        );
        return Ok(ExitCode::from(signal::EXIT_INTERRUPTED));
    }

    // The files are written as a set: each to a temporary file beside its target, and only
    // when all four are complete are they renamed into place, the EXR last. A full disk or a
    // kill before that leaves the previous set whole (docs/robustness.md, "Outputs as a set").
    let run_id = files::run_id();
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
    let mut header = report::header_attributes(&settings, &renderer, radius_given, &scene_hash);
    header.push(("passes_done".into(), film.passes().to_string()));
    header.push(("interrupted".into(), interrupted.to_string()));
    header.push(("pass_list".into(), accum::ranges(&held_indices)));
    header.push(("stop_reason".into(), stop_reason.into()));
    header.push(("run_id".into(), run_id.clone()));
    let mut layers = techniques
        .as_ref()
        .map(|t| t.layers(film.passes()))
        .unwrap_or_default();
    if args.aov {
        let first = pool.install(|| first_hit_layers(&scene, &settings));
        layers.push(("albedo", RGB, first.albedo));
        layers.push(("normal", ["X", "Y", "Z"], first.normal));
    }
    let exr =
        exr_file::stage_exr_with_layers(&outputs.exr, &film, &header, &layers, args.precision)
            .map_err(named(&outputs.exr))?;
    drop(layers);
    let png = preview::encode_png(&film)
        .and_then(|bytes| files::stage_bytes(&outputs.png, &bytes))
        .map_err(named(&outputs.png))?;
    let noise_png = preview::encode_noise_png(
        (settings.width, settings.height),
        &luma.noise(),
        film.passes(),
    )
    .and_then(|bytes| files::stage_bytes(&outputs.noise_png, &bytes))
    .map_err(named(&outputs.noise_png))?;
    let accum_path = args.accumulate.then(|| outputs.accum.clone());
    let accum_file = match &accum_path {
        Some(path) => Some(
            accum::stage(
                path,
                (settings.width, settings.height),
                &identity,
                std::mem::take(&mut records),
                &header,
            )
            .map_err(named(path))?,
        ),
        None => None,
    };
    drop(records);
    let plan = report::PassPlan {
        passes_held: accum::ranges(&held_indices),
        first_pass_rendered: (rendered > 0).then_some(first),
        passes_rendered: rendered,
        passes_replayed: replayed,
        replayed_from: held_from.iter().map(|p| p.display().to_string()).collect(),
        stop_reason,
        time_budget_seconds: args.time_budget,
        target_noise: args.target_noise,
        mean_relative_standard_error: luma.mean_relative_stderr(),
        accumulation_file: accum_path.as_ref().map(|p| p.display().to_string()),
    };
    let run = report::RunReport::new(report::RunFacts {
        plan: &plan,
        scene_path: &args.scene,
        settings: &settings,
        renderer: &renderer,
        load: &loaded.report,
        film: &film,
        threads,
        samples,
        rendered_samples,
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
            peak_resident: peaks.overall(),
            stage_peaks: peaks.stages(),
        },
    });
    let json = files::stage_bytes(&outputs.json, run.to_json().as_bytes())
        .map_err(named(&outputs.json))?;
    // The EXR stays last: the commit point of the set.
    let mut staged = vec![png, noise_png, json];
    staged.extend(accum_file);
    staged.push(exr);
    files::commit_all(staged)?;
    if interrupted {
        say!(
            "interrupted after {} of {} passes; the outputs hold those passes",
            rendered,
            to_render
        );
    } else if stop_reason != "completed" {
        say!(
            "stopped by --{} after {rendered} of {to_render} passes",
            stop_reason.replace('_', "-")
        );
    }
    if replayed > 0 {
        say!(
            "replayed {replayed} passes ({}) from {}",
            accum::ranges(&held_indices[..replayed as usize]),
            held_from
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    say!(
        "rendered {} ({}x{}, mode {}, {} new passes, {} in all) in {:.2} s: {:.3} M samples/s on {} threads",
        args.scene.display(),
        settings.width,
        settings.height,
        settings.mode,
        rendered,
        film.passes(),
        render_seconds,
        rendered_samples as f64 / render_seconds.max(1e-9) / 1e6,
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
