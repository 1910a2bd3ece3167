//! The render session behind `bdpm render` and `bdpm merge`, in four steps that the tests can
//! call one by one:
//!
//! 1. [`prepare`]: load the scene, check the held passes against this render's identity,
//!    claim the outputs and refuse a render that would not fit in memory, all before any large
//!    allocation; then [`RenderSession::new`] builds the renderer.
//! 2. [`RenderSession::replay`]: add the passes read from accumulation files, in pass order.
//! 3. [`RenderSession::run`]: render passes until one of the stop rules holds
//!    ([`StopReason`]).
//! 4. [`RenderSession::write`]: stage every output and commit them as a set.
use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime};

use bdpm_integrator::{
    Film, MemoryEstimate, MemoryItem, Mode, RenderError, Renderer, Stage, StageProbe, WeightStats,
    camera::first_hit_layers, estimate_memory, human_bytes, memory::Lower,
};
use bdpm_load::LoadedScene;
use bdpm_output::accum::{self, Identity, PassRecord};
use bdpm_output::cli::{self, CliResult, Overrides, default_output, progress_bar, thread_pool};
use bdpm_output::exr::{self as exr_file, Precision, RGB, TechniqueSums};
use bdpm_output::files::{self, OutputLock, Outputs, Staged};
use bdpm_output::header::Recorded;
use bdpm_output::memory::{self, MemoryLimit};
use bdpm_output::preview;
pub(crate) use bdpm_output::report::StopReason;
use bdpm_output::report::{self, PassPlan};
use bdpm_output::say;
use bdpm_output::stats::{PixelStats, image_mean};
use bdpm_output::system::{StagePeaks, available_memory};
use glam::DVec3;
use indicatif::ProgressBar;

/// One run of the render driver: passes replayed from accumulation files, then passes
/// rendered, then the outputs.
pub(crate) struct Job {
    /// The scene file.
    pub(crate) scene: PathBuf,
    /// The settings given on the command line (or stored in the parts of a merge).
    pub(crate) overrides: Overrides,
    /// The output EXR (default: the scene's `output`, else `out/<scene>.exr`).
    pub(crate) output: Option<PathBuf>,
    /// Draw no progress bar.
    pub(crate) quiet: bool,
    /// Write the technique layers.
    pub(crate) techniques: bool,
    /// Write the first-hit `albedo` and `normal` layers.
    pub(crate) aov: bool,
    /// Sample type of the EXR's channels.
    pub(crate) precision: Precision,
    /// `--max-memory`, bytes.
    pub(crate) max_memory: Option<u64>,
    /// Measure each stage's peak memory.
    pub(crate) stage_memory: bool,
    /// First pass to render (default 0, or after the held passes when resuming).
    pub(crate) first_pass: Option<u32>,
    /// Passes to replay before rendering (`--resume`, `bdpm merge`).
    pub(crate) held: Option<accum::Accumulation>,
    /// The files the held passes came from, for the report.
    pub(crate) held_from: Vec<PathBuf>,
    /// Write OUT.accum.exr.
    pub(crate) accumulate: bool,
    /// `--time-budget`, seconds of rendering.
    pub(crate) time_budget: Option<f64>,
    /// `--target-noise`: the mean relative standard error to stop below.
    pub(crate) target_noise: Option<f64>,
    /// `--preview-every`: seconds of wall time between previews (OUT.png and OUT.exr
    /// rewritten with the passes so far, at a pass boundary).
    pub(crate) preview_every: Option<f64>,
    /// `bdpm merge`: render no pass.
    pub(crate) merge: bool,
}

/// What [`prepare`] establishes before the renderer is built: the loaded scene, the passes to
/// render, the claimed outputs and the memory estimate. The session borrows it.
pub(crate) struct Prepared {
    job: Job,
    loaded: LoadedScene,
    identity: Identity,
    scene_hash: String,
    /// The files the held passes came from.
    held_from: Vec<PathBuf>,
    /// First pass to render, global index.
    first: u32,
    /// One past the last pass to render.
    end: u32,
    /// Passes to render (0 for a merge).
    to_render: u32,
    outputs: Outputs,
    /// Held until the files are in place, so that a second render to the same output is
    /// refused.
    _lock: OutputLock,
    pool: rayon::ThreadPool,
    estimate: MemoryEstimate,
    /// The memory limit compared with, bytes, and where it came from.
    limit: (Option<u64>, &'static str),
    peaks: StagePeaks,
    /// Loading the scene, s.
    load_seconds: f64,
}

/// Step 1: loads the scene and makes every check that can fail before the render starts.
/// Returns what the session needs and the held passes, which [`RenderSession::replay`] takes.
pub(crate) fn prepare(job: Job) -> CliResult<(Prepared, Vec<PassRecord>)> {
    let started = SystemTime::now();
    let t_start = Instant::now();
    // The loader checks each texture, glTF buffer and the geometry against the limit before
    // allocating it; the render's estimate below adds the rest.
    let limit = MemoryLimit::of(job.max_memory);
    let mut loaded = cli::prepare_within(&job.scene, &job.overrides, limit)?;
    let load_seconds = t_start.elapsed().as_secs_f64();
    let gltf = &loaded.report.gltf_files;
    let identity = Identity::of(&job.scene, gltf, &loaded.settings, &job.overrides)?;
    let scene_hash = bdpm_load::scene_hash(&job.scene, gltf).map_err(|e| e.to_string())?;
    let mut job = job;
    let (held, held_from) = held_passes(
        job.held.take(),
        std::mem::take(&mut job.held_from),
        &job.scene,
        &identity,
        &loaded,
    )?;
    let settings = &mut loaded.settings;
    let first = match (job.first_pass, held.last()) {
        (Some(k), _) => k,
        (None, Some(last)) => last
            .index
            .checked_add(1)
            .ok_or("no pass left after pass 4294967295")?,
        (None, None) => 0,
    };
    let to_render = if job.merge {
        settings.passes = held.len() as u32;
        0
    } else {
        settings.passes
    };
    let end = first
        .checked_add(to_render)
        .ok_or("--first-pass + --passes exceeds the last pass index, 4294967295")?;
    if job.techniques && matches!(settings.mode, Mode::Path | Mode::Light) {
        return Err(format!(
            "--techniques: mode '{}' is a single technique with no layers to split; use a BDPM mode (e.g. --mode optimal)",
            settings.mode
        ));
    }
    let requested = job
        .output
        .clone()
        .or(loaded.output.clone())
        .unwrap_or_else(|| default_output(&job.scene));
    // Before any work: a directory that cannot be written, an output name that is a
    // directory or a device, or a second render to the same output is refused now, not after
    // the render. The lock is held until the files are in place.
    let outputs = Outputs::beside(&requested);
    let mut inputs: Vec<&Path> = held_from.iter().map(PathBuf::as_path).collect();
    inputs.push(&job.scene);
    let lock = files::claim(&requested, &outputs, job.accumulate, &inputs, started)?;
    let pool = thread_pool(job.overrides.threads)?;
    let kept = held.len() as u64 + u64::from(to_render);
    let (estimate, limit) = memory_gate(&job, &loaded, &pool, kept)?;
    let prepared = Prepared {
        job,
        loaded,
        identity,
        scene_hash,
        held_from,
        first,
        end,
        to_render,
        outputs,
        _lock: lock,
        pool,
        estimate,
        limit,
        peaks: StagePeaks::default(),
        load_seconds,
    };
    Ok((prepared, held))
}

/// The held passes and the files they came from, after checking that they belong to this
/// render (of `scene`) and have its pixel count.
fn held_passes(
    held: Option<accum::Accumulation>,
    held_from: Vec<PathBuf>,
    scene: &Path,
    identity: &Identity,
    loaded: &LoadedScene,
) -> CliResult<(Vec<PassRecord>, Vec<PathBuf>)> {
    let Some(h) = held else {
        return Ok((Vec::new(), Vec::new()));
    };
    if let Some(why) = identity.mismatch(&h.identity) {
        return Err(format!(
            "{}: not a part of this render of {}: {why}",
            h.path.display(),
            scene.display()
        ));
    }
    let s = &loaded.settings;
    if let Some(r) = h.passes.first()
        && r.estimates.len() != s.width as usize * s.height as usize
    {
        return Err(format!(
            "{}: its passes do not have {}x{} pixels",
            held_from[0].display(),
            s.width,
            s.height
        ));
    }
    Ok((h.passes, held_from))
}

/// The memory estimate of the render with `kept` passes held for the accumulation file, and
/// the limit it was compared with; an error naming what to lower when it does not fit.
/// Made before the cache, the pixel table, the film or any photon map is allocated: a render
/// that would run out of memory after minutes of work is refused now.
fn memory_gate(
    job: &Job,
    loaded: &LoadedScene,
    pool: &rayon::ThreadPool,
    kept: u64,
) -> CliResult<(MemoryEstimate, (Option<u64>, &'static str))> {
    let settings = &loaded.settings;
    let pixels = settings.width as u64 * settings.height as u64;
    let mut estimate = pool.install(|| estimate_memory(&loaded.scene, settings, job.techniques));
    if job.merge {
        // A merge prepares the renderer and renders no pass.
        estimate = memory::without_passes(estimate, settings);
    }
    if job.accumulate {
        // The passes of the accumulation file: held (read from files, or rendered and kept)
        // until the file is written, plus the copy the writer encodes, or the reader decodes.
        estimate.items.push(MemoryItem {
            name: "passes kept for the accumulation file",
            bytes: kept * pixels * accum::BYTES_PER_PIXEL_PASS,
            lifetime: memory::Lifetime::Held,
            lower: Lower::Other(if job.merge {
                "the passes merged at once (merge fewer parts, then merge the results)"
            } else {
                "--passes (or drop --accumulate)"
            }),
        });
        estimate.items.sort_by_key(|i| std::cmp::Reverse(i.bytes));
    }
    let (limit, limit_source) = match job.max_memory {
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
            job.scene.display(),
            human_bytes(estimate.total()),
            parts.join(", "),
            limit_source,
            human_bytes(limit),
            memory::lower(estimate.scalable_largest())
        ));
    }
    Ok((estimate, (limit, limit_source)))
}

impl Prepared {
    /// Whether this is a `bdpm merge` (no pass rendered).
    pub(crate) fn is_merge(&self) -> bool {
        self.job.merge
    }

    /// The scene file.
    pub(crate) fn scene_path(&self) -> &Path {
        &self.job.scene
    }
}

/// A render in progress: the renderer and everything accumulated from the passes so far.
pub(crate) struct RenderSession<'a> {
    prep: &'a Prepared,
    renderer: Renderer<'a>,
    /// Preparing the renderer (cache, pixel table), s.
    prepare_seconds: f64,
    /// Whether the merge radius was given (scene file or `--radius`).
    radius_given: bool,
    /// Warnings so far; the ones of preparation are printed when the session starts.
    warnings: Vec<String>,
    bar: ProgressBar,
    film: Film,
    luma: PixelStats,
    techniques: Option<TechniqueSums>,
    /// Camera samples of every pass held, and of the replayed ones alone.
    samples: u64,
    replayed_samples: u64,
    pass_means: Vec<[f64; 3]>,
    stage_totals: Vec<(Stage, f64)>,
    weights: WeightStats,
    photon_map_bytes: u64,
    photons_stored: u64,
    /// Passes kept for the accumulation file.
    records: Vec<PassRecord>,
    /// Global indices of every pass held, in the order added.
    held_indices: Vec<u32>,
    replayed: u32,
    rendered: u32,
    /// Rendering the passes of this run, s.
    render_seconds: f64,
    /// Previews written (`--preview-every`), and the wall time they took, s (part of
    /// `render_seconds`).
    previews: u32,
    preview_seconds: f64,
}

impl<'a> RenderSession<'a> {
    /// The rest of step 1: builds the renderer (radiance cache, pixel table) and prints the
    /// warnings of loading and preparation. The preparation asks `interrupted()` between
    /// chunks of its work ([`Renderer::new_until`]) and gives up when it says so: `Ok(Err)`
    /// with the stage it was in.
    pub(crate) fn new(
        prep: &'a Prepared,
        interrupted: &(dyn Fn() -> bool + Sync),
    ) -> CliResult<Result<RenderSession<'a>, Stage>> {
        let (job, settings) = (&prep.job, &prep.loaded.settings);
        let t_prepare = Instant::now();
        let probe = job.stage_memory.then_some(&prep.peaks as &dyn StageProbe);
        probe.inspect(|p| p.enter(Stage::Prepare));
        let renderer = prep
            .pool
            .install(|| Renderer::new_until(&prep.loaded.scene, settings, interrupted));
        let mut renderer = match renderer {
            Err(RenderError::Interrupted(stage)) => return Ok(Err(stage)),
            other => other.map_err(|e| format!("{}: {e}", job.scene.display()))?,
        }
        .with_technique_layers(job.techniques);
        if let Some(p) = probe {
            p.leave(Stage::Prepare);
            renderer.set_stage_probe(p);
        }
        let prepare_seconds = t_prepare.elapsed().as_secs_f64();
        let radius_given = prep.loaded.report.radius_given || job.overrides.radius.is_some();
        let mut warnings = prep.loaded.report.warnings();
        warnings.extend(renderer.warnings());
        for w in &warnings {
            say!("warning: {w}");
        }
        let bar = progress_bar(
            job.quiet,
            Some(prep.to_render as u64 * renderer.work_per_pass()),
            "{spinner} [{elapsed_precise}] {bar:40} {percent:>3}% pass {msg} (eta {eta})",
        );
        let pixels = settings.width as usize * settings.height as usize;
        Ok(Ok(RenderSession {
            prep,
            renderer,
            prepare_seconds,
            radius_given,
            warnings,
            bar,
            film: Film::new(settings.width, settings.height),
            luma: PixelStats::new(pixels),
            techniques: job.techniques.then(|| TechniqueSums::new(pixels)),
            samples: 0,
            replayed_samples: 0,
            pass_means: Vec::new(),
            stage_totals: Vec::new(),
            weights: WeightStats::default(),
            photon_map_bytes: 0,
            photons_stored: 0,
            records: Vec::new(),
            held_indices: Vec::new(),
            replayed: 0,
            rendered: 0,
            render_seconds: 0.0,
            previews: 0,
            preview_seconds: 0.0,
        }))
    }

    /// Step 2: adds the held passes. They all precede the passes rendered now, so the film
    /// adds every pass in pass order, exactly as one render of all of them would.
    pub(crate) fn replay(&mut self, held: Vec<PassRecord>) {
        for rec in held {
            self.film.add_pass(&rec.estimates, rec.dropped);
            self.luma.add_pass(&rec.estimates);
            self.pass_means.push(image_mean(&rec.estimates));
            self.samples += rec.samples;
            self.replayed_samples += rec.samples;
            self.photons_stored += rec.photons_stored;
            self.held_indices.push(rec.index);
            self.replayed += 1;
            self.records.push(rec);
        }
    }

    /// Step 3: renders the passes first..end, stopping early when `interrupted()` says so
    /// before a pass, or after a pass (not the last) when the time budget is spent or the
    /// target noise reached.
    pub(crate) fn run(&mut self, interrupted: &dyn Fn() -> bool) -> StopReason {
        let (job, first, end) = (&self.prep.job, self.prep.first, self.prep.end);
        let t_render = Instant::now();
        let mut last_preview = t_render;
        let mut stop = StopReason::Completed;
        for pass in first..end {
            if interrupted() {
                stop = StopReason::Interrupted;
                break;
            }
            self.bar
                .set_message(format!("{}/{}", pass - first + 1, self.prep.to_render));
            self.render_pass(pass);
            let last = pass + 1 == end;
            if let Some(b) = job.time_budget
                && t_render.elapsed().as_secs_f64() >= b
                && !last
            {
                stop = StopReason::TimeBudget;
                break;
            }
            if let Some(x) = job.target_noise
                && self.luma.mean_relative_stderr().is_some_and(|e| e < x)
                && !last
            {
                stop = StopReason::TargetNoise;
                break;
            }
            // After the last pass the final outputs follow at once: no preview of them.
            if let Some(every) = job.preview_every
                && !last
                && last_preview.elapsed().as_secs_f64() >= every
            {
                self.write_preview();
                last_preview = Instant::now();
            }
        }
        self.render_seconds += t_render.elapsed().as_secs_f64();
        self.bar.finish_and_clear();
        stop
    }

    /// Renders pass `pass` (a global index) and adds it.
    pub(crate) fn render_pass(&mut self, pass: u32) {
        let bar = &self.bar;
        let renderer = &self.renderer;
        let out = self
            .prep
            .pool
            .install(|| renderer.render_pass(pass, &|n| bar.inc(n)));
        self.rendered += 1;
        self.held_indices.push(pass);
        self.film.add_pass(&out.estimates, out.dropped);
        self.luma.add_pass(&out.estimates);
        if let (Some(sums), Some(t)) = (&mut self.techniques, &out.techniques) {
            sums.add_pass(t);
        }
        self.pass_means.push(image_mean(&out.estimates));
        self.samples += out.samples;
        self.weights.add(&out.weights);
        self.photon_map_bytes = self.photon_map_bytes.max(out.photon_map_bytes);
        self.photons_stored += out.photons_stored;
        for (name, secs) in out.stage_seconds {
            match self.stage_totals.iter_mut().find(|(n, _)| *n == name) {
                Some(entry) => entry.1 += secs,
                None => self.stage_totals.push((name, secs)),
            }
        }
        if self.prep.job.accumulate {
            self.records.push(PassRecord {
                index: pass,
                estimates: out.estimates,
                dropped: out.dropped,
                samples: out.samples,
                photons_stored: out.photons_stored,
            });
        }
    }

    /// Rewrites OUT.png and OUT.exr with the passes so far, as a set (EXR last, each renamed
    /// into place whole: a reader sees the previous preview or the new one, never a torn
    /// file). A failure (a full disk) does not stop the render: it becomes a warning of the
    /// report, and the final write tries again.
    fn write_preview(&mut self) {
        let t = Instant::now();
        match self.stage_preview() {
            Ok(()) => self.previews += 1,
            Err(e) => self
                .warnings
                .push(format!("a preview was not written: {e}")),
        }
        self.preview_seconds += t.elapsed().as_secs_f64();
    }

    /// Stages and commits the preview set: the EXR with the film's layers and the technique
    /// layers (not the first-hit ones, which cost a pass of primary rays and do not change),
    /// and the PNG.
    fn stage_preview(&self) -> CliResult<()> {
        let header = self.header(None, &files::run_id());
        let (outputs, job) = (&self.prep.outputs, &self.prep.job);
        let layers = self
            .techniques
            .as_ref()
            .map(|t| t.layers(self.film.passes()))
            .unwrap_or_default();
        let exr = exr_file::stage_exr_with_layers(
            &outputs.exr,
            &self.film,
            &header,
            &layers,
            job.precision,
        )
        .map_err(named(&outputs.exr))?;
        let png = preview::encode_png(&self.film)
            .and_then(|bytes| files::stage_bytes(&outputs.png, &bytes))
            .map_err(named(&outputs.png))?;
        files::commit_all(vec![png, exr])
    }

    /// Passes the film holds, replayed and rendered.
    pub(crate) fn passes(&self) -> u32 {
        self.film.passes()
    }

    /// Step 4: writes the outputs as a set (each to a temporary file beside its target, all
    /// renamed into place once complete, the EXR last: a full disk or a kill before that
    /// leaves the previous set whole; docs/robustness.md, "Outputs as a set"), then prints the
    /// summary.
    pub(crate) fn write(mut self, stop: StopReason) -> CliResult<()> {
        let run_id = files::run_id();
        let known_before = self.warnings.len();
        if self.film.mean().iter().all(|c| *c == DVec3::ZERO) {
            self.warnings.push(format!(
                "the image is black: no light reached the camera in {} passes (is the light sealed \
                 inside a closed object, or the camera inside one?)",
                self.film.passes()
            ));
        }
        if self.film.dropped() > 0 {
            self.warnings.push(format!(
                "{} non-finite samples were dropped",
                self.film.dropped()
            ));
        }
        let header = self.header(Some(stop), &run_id);
        let exr = self.stage_exr(&header)?;
        let outputs = &self.prep.outputs;
        let png = preview::encode_png(&self.film)
            .and_then(|bytes| files::stage_bytes(&outputs.png, &bytes))
            .map_err(named(&outputs.png))?;
        let settings = &self.prep.loaded.settings;
        let noise_png = preview::encode_noise_png(
            (settings.width, settings.height),
            &self.luma.noise(),
            self.film.passes(),
        )
        .and_then(|bytes| files::stage_bytes(&outputs.noise_png, &bytes))
        .map_err(named(&outputs.noise_png))?;
        let accum_path = self.prep.job.accumulate.then(|| outputs.accum.clone());
        let accum_file = match &accum_path {
            Some(path) => Some(
                accum::stage(
                    path,
                    (settings.width, settings.height),
                    &self.prep.identity,
                    std::mem::take(&mut self.records),
                    &header,
                )
                .map_err(named(path))?,
            ),
            None => None,
        };
        let json = self.stage_report(stop, accum_path.as_deref(), &run_id)?;
        // The EXR stays last: the commit point of the set.
        let mut staged = vec![png, noise_png, json];
        staged.extend(accum_file);
        staged.push(exr);
        files::commit_all(staged)?;
        self.say_summary(stop, known_before);
        Ok(())
    }

    /// The EXR header's attributes (also stored in the accumulation file); `stop` is `None`
    /// for a preview written while the render runs (`bdpm.stop_reason` = `running`,
    /// `bdpm.preview` = `true`).
    fn header(&self, stop: Option<StopReason>, run_id: &str) -> Vec<(String, String)> {
        let prep = self.prep;
        let mut header = report::header_attributes(
            &prep.loaded.settings,
            &self.renderer,
            self.radius_given,
            &prep.scene_hash,
        );
        header.push(("passes_done".into(), self.film.passes().to_string()));
        let interrupted = stop == Some(StopReason::Interrupted);
        header.push(("interrupted".into(), interrupted.to_string()));
        header.push(("pass_list".into(), accum::ranges(&self.held_indices)));
        header.push((
            "stop_reason".into(),
            stop.map_or("running", StopReason::name).into(),
        ));
        if stop.is_none() {
            header.push(("preview".into(), "true".into()));
        }
        header.push(("run_id".into(), run_id.to_string()));
        // What `predict RENDER.exr` reads instead of repeated flags.
        let recorded = Recorded {
            scene: prep.identity.scene.clone(),
            overrides: prep.identity.overrides.clone(),
        };
        header.extend(recorded.attributes());
        header
    }

    /// Stages the EXR with its layers (techniques, first-hit albedo and normal).
    fn stage_exr(&self, header: &[(String, String)]) -> CliResult<Staged> {
        let (prep, path) = (self.prep, &self.prep.outputs.exr);
        let mut layers = self
            .techniques
            .as_ref()
            .map(|t| t.layers(self.film.passes()))
            .unwrap_or_default();
        if prep.job.aov {
            let first = prep
                .pool
                .install(|| first_hit_layers(&prep.loaded.scene, &prep.loaded.settings));
            layers.push(("albedo", RGB, first.albedo));
            layers.push(("normal", ["X", "Y", "Z"], first.normal));
        }
        exr_file::stage_exr_with_layers(path, &self.film, header, &layers, prep.job.precision)
            .map_err(named(path))
    }

    /// Stages the JSON run report.
    fn stage_report(
        &self,
        stop: StopReason,
        accum_path: Option<&Path>,
        run_id: &str,
    ) -> CliResult<Staged> {
        let prep = self.prep;
        let job = &prep.job;
        let plan = PassPlan {
            passes_held: accum::ranges(&self.held_indices),
            first_pass_rendered: (self.rendered > 0).then_some(prep.first),
            passes_rendered: self.rendered,
            passes_replayed: self.replayed,
            replayed_from: prep
                .held_from
                .iter()
                .map(|p| p.display().to_string())
                .collect(),
            stop_reason: stop,
            time_budget_seconds: job.time_budget,
            target_noise: job.target_noise,
            mean_relative_standard_error: self.luma.mean_relative_stderr(),
            accumulation_file: accum_path.map(|p| p.display().to_string()),
            preview_every_seconds: job.preview_every,
            previews_written: self.previews,
            preview_seconds: self.preview_seconds,
        };
        let run = report::RunReport::new(report::RunFacts {
            plan: &plan,
            scene_path: &job.scene,
            settings: &prep.loaded.settings,
            renderer: &self.renderer,
            load: &prep.loaded.report,
            film: &self.film,
            threads: prep.pool.current_num_threads(),
            samples: self.samples,
            rendered_samples: self.samples - self.replayed_samples,
            load_seconds: prep.load_seconds,
            prepare_seconds: self.prepare_seconds,
            render_seconds: self.render_seconds,
            pass_stages: &self.stage_totals,
            outputs: &prep.outputs,
            pass_means: &self.pass_means,
            weights: &self.weights,
            photon_map_bytes: self.photon_map_bytes,
            photons_stored: self.photons_stored,
            run_id,
            radius_given: self.radius_given,
            warnings: &self.warnings,
            memory: report::MemoryFacts {
                estimate: &prep.estimate,
                limit: prep.limit.0,
                limit_source: prep.limit.1,
                peak_resident: prep.peaks.overall(),
                stage_peaks: prep.peaks.stages(),
            },
        });
        let path = &prep.outputs.json;
        files::stage_bytes(path, run.to_json().as_bytes()).map_err(named(path))
    }

    /// Prints why the render stopped, what it replayed and rendered, the warnings found
    /// while writing and the files written.
    fn say_summary(&self, stop: StopReason, known_before: usize) {
        let prep = self.prep;
        let (rendered, to_render, replayed) = (self.rendered, prep.to_render, self.replayed);
        if stop == StopReason::Interrupted {
            say!(
                "interrupted after {rendered} of {to_render} passes; the outputs hold those passes"
            );
        } else if let Some(flag) = stop.flag() {
            say!("stopped by {flag} after {rendered} of {to_render} passes");
        }
        if replayed > 0 {
            say!(
                "replayed {replayed} passes ({}) from {}",
                accum::ranges(&self.held_indices[..replayed as usize]),
                prep.held_from
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        let settings = &prep.loaded.settings;
        say!(
            "rendered {} ({}x{}, mode {}, {} new passes, {} in all) in {:.2} s: {:.3} M samples/s on {} threads",
            prep.job.scene.display(),
            settings.width,
            settings.height,
            settings.mode,
            rendered,
            self.film.passes(),
            self.render_seconds,
            (self.samples - self.replayed_samples) as f64 / self.render_seconds.max(1e-9) / 1e6,
            prep.pool.current_num_threads()
        );
        if let Some(line) = self.renderer.paths_ran().summary() {
            say!("{line}");
        }
        for w in &self.warnings[known_before..] {
            say!("warning: {w}");
        }
        let written: Vec<String> = prep
            .outputs
            .all()
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        say!("wrote {}", written.join(", "));
    }
}

/// An error message prefixed with the file it concerns.
fn named(path: &Path) -> impl Fn(String) -> String + '_ {
    move |e| format!("{}: {e}", path.display())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    /// A job rendering the preprint's Lambert Cornell box small, into a fresh directory.
    fn job(dir: &str, passes: u32) -> (Job, PathBuf) {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let out = std::env::temp_dir().join(format!("bdpm-session-{}-{dir}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        std::fs::create_dir_all(&out).unwrap();
        let args: Vec<String> = [
            "--resolution",
            "12x10",
            "--passes",
            &passes.to_string(),
            "--photons",
            "3000",
            "--spp",
            "1",
            "--threads",
            "2",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let job = Job {
            scene: root.join("scenes/preprint/cornell-lambert.toml"),
            overrides: Overrides::from_args(&args).unwrap(),
            output: Some(out.join("r.exr")),
            quiet: true,
            techniques: false,
            aov: false,
            precision: Precision::Float,
            max_memory: None,
            stage_memory: false,
            first_pass: None,
            held: None,
            held_from: Vec::new(),
            accumulate: false,
            time_budget: None,
            target_noise: None,
            preview_every: None,
            merge: false,
        };
        (job, out)
    }

    /// The EXR header's text attributes written with the `bdpm.` prefix, and the JSON report.
    fn written(out: &Path) -> (std::collections::HashMap<String, String>, serde_json::Value) {
        let meta = exr::meta::MetaData::read_from_file(out.join("r.exr"), false).unwrap();
        let mut attributes = std::collections::HashMap::new();
        for (k, v) in &meta.headers[0].own_attributes.other {
            if let exr::prelude::AttributeValue::Text(t) = v {
                attributes.insert(k.to_string(), t.to_string());
            }
        }
        let json = std::fs::read_to_string(out.join("r.json")).unwrap();
        (attributes, serde_json::from_str(&json).unwrap())
    }

    /// The steps one by one: prepare, one pass rendered by hand, a second by `run` stopped by
    /// the time budget, write; the stop reason and the pass counts reach header and report.
    #[test]
    fn steps_stop_on_time_budget_and_write_the_reason() {
        let (mut j, out) = job("budget", 3);
        j.time_budget = Some(1e-9);
        let (prepared, held) = prepare(j).unwrap();
        assert!(held.is_empty());
        let mut session = RenderSession::new(&prepared, &|| false).unwrap().unwrap();
        session.replay(held);
        assert_eq!(session.passes(), 0);
        // Every pass takes longer than the budget: `run` stops after its first one, which is
        // not the last of the three.
        let stop = session.run(&|| false);
        assert_eq!(stop, StopReason::TimeBudget);
        assert_eq!(session.passes(), 1);
        session.write(stop).unwrap();
        let (header, report) = written(&out);
        assert_eq!(header["bdpm.stop_reason"], "time_budget");
        assert_eq!(header["bdpm.interrupted"], "false");
        assert_eq!(header["bdpm.passes_done"], "1");
        assert_eq!(header["bdpm.pass_list"], "0");
        assert_eq!(report["plan"]["stop_reason"], "time_budget");
        assert_eq!(report["plan"]["passes_rendered"], 1);
        assert_eq!(report["interrupted"], false);
        std::fs::remove_dir_all(out).unwrap();
    }

    /// The preparation asks `interrupted` as it goes and gives up when it says so, naming the
    /// stage it was in: stopped at each ask in turn, it names its stages in the order they
    /// run (the pixel table again after the adaptive radius's pilot), and it completes once
    /// the answer comes after the last ask.
    #[test]
    fn an_interrupt_stops_the_preparation_in_its_stage() {
        use std::sync::atomic::{AtomicU32, Ordering};
        let (mut j, out) = job("prepare-interrupt", 1);
        j.overrides.mode = Some("optimal".into());
        j.overrides.adaptive_radius = Some(true);
        let (prepared, _) = prepare(j).unwrap();
        let mut stages: Vec<Stage> = Vec::new();
        let mut completed = false;
        for after in 0..10_000 {
            let asked = AtomicU32::new(0);
            let stop = || asked.fetch_add(1, Ordering::SeqCst) >= after;
            match RenderSession::new(&prepared, &stop).unwrap() {
                Ok(_) => {
                    completed = true;
                    break;
                }
                Err(stage) if stages.last() != Some(&stage) => stages.push(stage),
                Err(_) => {}
            }
        }
        assert!(completed, "still stopped after 10000 asks");
        assert_eq!(
            stages,
            [
                Stage::RadianceCache,
                Stage::PixelTable,
                Stage::RadiusMap,
                Stage::PixelTable,
                Stage::DirectSamples
            ]
        );
        let _ = std::fs::remove_dir_all(out);
    }

    /// An interrupt asked for before the second pass: one pass held, `interrupted` in the
    /// header and the report; with no interrupt all passes run and the reason is `completed`.
    #[test]
    fn interrupt_stops_before_the_next_pass() {
        let (j, out) = job("interrupt", 3);
        let (prepared, held) = prepare(j).unwrap();
        let mut session = RenderSession::new(&prepared, &|| false).unwrap().unwrap();
        session.replay(held);
        let asked = Cell::new(0);
        let stop = session.run(&|| {
            asked.set(asked.get() + 1);
            asked.get() > 1
        });
        assert_eq!(stop, StopReason::Interrupted);
        assert_eq!((asked.get(), session.passes()), (2, 1));
        session.write(stop).unwrap();
        let (header, report) = written(&out);
        assert_eq!(header["bdpm.stop_reason"], "interrupted");
        assert_eq!(header["bdpm.interrupted"], "true");
        assert_eq!(report["plan"]["stop_reason"], "interrupted");
        assert_eq!(report["interrupted"], true);
        drop(prepared);

        let (j, out2) = job("complete", 2);
        let (prepared, held) = prepare(j).unwrap();
        let mut session = RenderSession::new(&prepared, &|| false).unwrap().unwrap();
        session.replay(held);
        session.render_pass(0);
        session.render_pass(1);
        session.write(StopReason::Completed).unwrap();
        let (header, _) = written(&out2);
        assert_eq!(header["bdpm.stop_reason"], "completed");
        assert_eq!(header["bdpm.pass_list"], "0-1");
        std::fs::remove_dir_all(out).unwrap();
        std::fs::remove_dir_all(out2).unwrap();
    }
}
