//! The JSON run report and the EXR header attributes: what ran, with which settings, and what
//! each stage cost.
use std::path::Path;

use bdpm_integrator::{
    Film, MemoryEstimate, RenderSettings, Renderer, Stage, WeightStats, settings::SettingsRecord,
};
use bdpm_load::LoadReport;
use serde::Serialize;

use crate::files::Outputs;
use crate::stats::{image_mean, standard_error_of_mean};

/// Everything the report is made from.
pub struct RunFacts<'a> {
    /// The scene file as given.
    pub scene_path: &'a Path,
    /// The settings the render ran with.
    pub settings: &'a RenderSettings,
    /// The prepared renderer (radius in use, preparatory stages).
    pub renderer: &'a Renderer<'a>,
    /// Facts from loading the scene.
    pub load: &'a LoadReport,
    /// The film of every pass the outputs hold.
    pub film: &'a Film,
    /// Worker threads.
    pub threads: usize,
    /// Camera samples of every pass held, replayed ones included.
    pub samples: u64,
    /// Camera samples of the passes rendered in this run (not replayed), for the rate.
    pub rendered_samples: u64,
    /// Loading the scene, s.
    pub load_seconds: f64,
    /// Preparing the renderer (cache, pixel table), s.
    pub prepare_seconds: f64,
    /// Rendering the passes of this run, s.
    pub render_seconds: f64,
    /// Per-pass stages summed over this run's passes: (name, s).
    pub pass_stages: &'a [(Stage, f64)],
    /// The files of the run.
    pub outputs: &'a Outputs,
    /// Image mean of every pass held, per channel, W·m⁻²·sr⁻¹.
    pub pass_means: &'a [[f64; 3]],
    /// Weight evaluations of this run's passes.
    pub weights: &'a WeightStats,
    /// The largest photon map of a pass, bytes.
    pub photon_map_bytes: u64,
    /// Photons stored over every pass held.
    pub photons_stored: u64,
    /// This run's identifier, also in the EXR header as `bdpm.run_id`.
    pub run_id: &'a str,
    /// Whether the merge radius was given (scene file or `--radius`).
    pub radius_given: bool,
    /// The warnings printed on stdout, one line each.
    pub warnings: &'a [String],
    /// The memory estimate made before the render, and what it was compared with.
    pub memory: MemoryFacts<'a>,
    /// Which passes the outputs hold, where they came from and why the render stopped.
    pub plan: &'a PassPlan,
}

/// Which passes a run's outputs hold and why it stopped (partial renders, merge, resume and
/// budgets; docs/distributed.md).
#[derive(Serialize, Clone, Debug)]
pub struct PassPlan {
    /// Every pass the outputs hold, as ranges of global pass indices (e.g. `0-3,6-9`).
    pub passes_held: String,
    /// First pass rendered by this run (`None` when it rendered none, e.g. `bdpm merge`).
    pub first_pass_rendered: Option<u32>,
    /// Passes rendered by this run.
    pub passes_rendered: u32,
    /// Passes replayed from accumulation files (`--resume`, `bdpm merge`).
    pub passes_replayed: u32,
    /// The accumulation files replayed.
    pub replayed_from: Vec<String>,
    /// Why the render stopped.
    pub stop_reason: StopReason,
    /// `--time-budget`, seconds of rendering.
    pub time_budget_seconds: Option<f64>,
    /// `--target-noise`: the mean relative standard error to stop below.
    pub target_noise: Option<f64>,
    /// Mean over pixels with a non-zero mean of the luminance's standard error of the mean
    /// divided by its mean (dimensionless; `None` with fewer than two passes).
    pub mean_relative_standard_error: Option<f64>,
    /// The accumulation file written beside the EXR, if any.
    pub accumulation_file: Option<String>,
    /// `--preview-every`: seconds of wall time between previews (OUT.png and OUT.exr
    /// rewritten with the passes so far during the render).
    pub preview_every_seconds: Option<f64>,
    /// Previews written during the render (0 without `--preview-every`).
    pub previews_written: u32,
    /// Wall time spent writing them, seconds (included in the render time).
    pub preview_seconds: f64,
}

/// Why a render stopped: the JSON report's `plan.stop_reason` and the EXR header's
/// `bdpm.stop_reason` (written as [`StopReason::name`]).
#[derive(Serialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// Every pass asked for was rendered (or, for `bdpm merge`, replayed).
    Completed,
    /// An interrupt (SIGINT, SIGTERM, SIGHUP) stopped the render after the pass in flight.
    Interrupted,
    /// `--time-budget`: the render time reached the budget during the last pass rendered.
    TimeBudget,
    /// `--target-noise`: the image's mean relative standard error fell below the target.
    TargetNoise,
}

impl StopReason {
    /// The name in the report and the header: `completed`, `interrupted`, `time_budget` or
    /// `target_noise`.
    pub fn name(self) -> &'static str {
        match self {
            StopReason::Completed => "completed",
            StopReason::Interrupted => "interrupted",
            StopReason::TimeBudget => "time_budget",
            StopReason::TargetNoise => "target_noise",
        }
    }

    /// The command-line flag whose rule stopped the render (`--time-budget`,
    /// `--target-noise`); `None` for a complete or interrupted render.
    pub fn flag(self) -> Option<&'static str> {
        match self {
            StopReason::TimeBudget => Some("--time-budget"),
            StopReason::TargetNoise => Some("--target-noise"),
            StopReason::Completed | StopReason::Interrupted => None,
        }
    }
}

/// The memory estimate and its limit.
pub struct MemoryFacts<'a> {
    /// The estimate, made before anything large was allocated.
    pub estimate: &'a MemoryEstimate,
    /// The limit compared with, bytes (`None`: unknown, not checked).
    pub limit: Option<u64>,
    /// `--max-memory` or `available memory`.
    pub limit_source: &'static str,
    /// Peak resident memory of the process when the report was made, bytes.
    pub peak_resident: Option<u64>,
    /// Peak resident memory of each stage (`prepare`, then the pass stages), bytes.
    pub stage_peaks: Vec<(Stage, u64)>,
}

/// The memory estimate in the report: estimated and measured peak, bytes.
#[derive(Serialize)]
struct MemoryOut {
    estimate_bytes: u64,
    items: Vec<MemoryItemOut>,
    /// Photons stored per photon emitted, from the estimate's pilot trace (0 for `path`).
    stored_per_emitted: f64,
    limit_bytes: Option<u64>,
    limit_source: &'static str,
    /// VmHWM when the report was written (Linux), to compare with the estimate.
    measured_peak_bytes: Option<u64>,
    /// The peak resident memory of each stage (Linux), bytes: `prepare` (loading excluded:
    /// cache and A/B table), then each pass stage's largest peak over the passes.
    stage_peaks: Vec<StagePeakOut>,
}

#[derive(Serialize)]
struct StagePeakOut {
    stage: &'static str,
    peak_bytes: u64,
}

#[derive(Serialize)]
struct MemoryItemOut {
    name: &'static str,
    bytes: u64,
}

/// Weight evaluations of the BDPM mix and how many were anomalous (method.md §4).
#[derive(Serialize)]
struct WeightsOut {
    evaluations: u64,
    outside_unit_interval: u64,
    outside_unit_fraction: f64,
    clamped_cb: u64,
}

/// The photon maps of the passes.
#[derive(Serialize)]
struct PhotonsOut {
    stored_total: u64,
    largest_map_bytes: u64,
}

#[derive(Serialize)]
struct StageOut {
    name: String,
    seconds: f64,
    bytes: u64,
    detail: String,
}

#[derive(Serialize)]
struct SceneOut {
    path: String,
    triangles: usize,
    degenerate_triangles: usize,
    materials: usize,
    lights: usize,
    gltf: GltfOut,
}

/// What the glTF files held that bdpm converted, skipped or simplified (counts).
#[derive(Serialize)]
struct GltfOut {
    files: usize,
    /// Triangle strips and fans, converted to triangle lists.
    strips_and_fans: usize,
    /// Point and line primitives, skipped.
    skipped_points_and_lines: usize,
    /// Spot and directional lights, skipped.
    skipped_lights: usize,
    /// Cameras, ignored.
    skipped_cameras: usize,
    /// Materials whose kd is baseColorFactor × a base-colour texture.
    textured_materials: usize,
    /// Images decoded (base-colour and emissive textures).
    textures: usize,
    /// Materials whose emission is emissiveFactor × emissiveStrength × an emissive texture.
    emission_textured_materials: usize,
    /// Materials whose normal, occlusion or metallic-roughness textures were ignored.
    other_textures: usize,
    /// Materials made perfect mirrors (smooth metal).
    mirrors: usize,
    /// Materials made smooth dielectrics (smooth transmission).
    dielectrics: usize,
    /// What glTF materials needed approximated, one line each (all of them; the `warnings`
    /// list the first few).
    material_warnings: Vec<String>,
}

#[derive(Serialize)]
struct Timing {
    load_s: f64,
    prepare_s: f64,
    render_s: f64,
    samples_per_second: f64,
    pass_stages: Vec<StageOut>,
}

/// The run report written as OUT.json.
#[derive(Serialize)]
pub struct RunReport {
    version: &'static str,
    /// Equal to the EXR's `bdpm.run_id` when the two files come from the same run.
    run_id: String,
    scene: SceneOut,
    settings: SettingsRecord,
    threads: usize,
    passes_done: u32,
    interrupted: bool,
    camera_samples: u64,
    dropped_samples: u64,
    prepared_stages: Vec<StageOut>,
    timing: Timing,
    weights: WeightsOut,
    photons: PhotonsOut,
    mean_radiance: [f64; 3],
    /// Standard error of the image mean from the spread of the per-pass image means (this
    /// accounts for correlations between pixels within a pass).
    mean_radiance_standard_error: [f64; 3],
    mean_noise_sqrt_v: [f64; 3],
    pass_image_means: Vec<[f64; 3]>,
    /// Which passes, from where, and why the render stopped.
    plan: PassPlan,
    /// EXR, PNG preview, noise map PNG, JSON report.
    outputs: [String; 4],
    /// Warnings printed on stdout (skipped glTF content, a merge radius near the scene's
    /// size, a black image, dropped samples), one line each.
    warnings: Vec<String>,
    /// The memory estimate made before rendering, its limit and the measured peak.
    memory: MemoryOut,
    /// Which path kinds through mirrors and glass the render sampled.
    paths: PathsOut,
}

/// [`bdpm_integrator::PathsRan`] as the report writes it.
#[derive(Serialize)]
struct PathsOut {
    delta_materials: usize,
    camera_through_delta: bool,
    x1_through_delta: bool,
    caustics_merged_at_x0: bool,
    photons_through_delta: bool,
    light_connections: bool,
}

impl From<bdpm_integrator::PathsRan> for PathsOut {
    fn from(p: bdpm_integrator::PathsRan) -> PathsOut {
        PathsOut {
            delta_materials: p.delta_materials,
            camera_through_delta: p.camera_through_delta,
            x1_through_delta: p.x1_through_delta,
            caustics_merged_at_x0: p.caustics_merged_at_x0,
            photons_through_delta: p.photons_through_delta,
            light_connections: p.light_connections,
        }
    }
}

impl SceneOut {
    /// The scene file at `path` and what the loader found in it.
    fn of(path: &Path, load: &LoadReport) -> SceneOut {
        SceneOut {
            path: path.display().to_string(),
            triangles: load.triangles,
            degenerate_triangles: load.degenerate_triangles,
            materials: load.materials,
            lights: load.lights,
            gltf: GltfOut {
                files: load.gltf_files.len(),
                strips_and_fans: load.strips_and_fans,
                skipped_points_and_lines: load.skipped_primitives,
                skipped_lights: load.skipped_lights,
                skipped_cameras: load.skipped_cameras,
                textured_materials: load.textured_materials,
                textures: load.textures,
                emission_textured_materials: load.emission_textured_materials,
                other_textures: load.other_textures,
                mirrors: load.gltf_mirrors,
                dielectrics: load.gltf_dielectrics,
                material_warnings: load.material_warnings.clone(),
            },
        }
    }
}

impl Timing {
    /// The run's times, and the time of each stage of its passes.
    fn of(f: &RunFacts<'_>) -> Timing {
        Timing {
            load_s: f.load_seconds,
            prepare_s: f.prepare_seconds,
            render_s: f.render_seconds,
            samples_per_second: f.rendered_samples as f64 / f.render_seconds.max(1e-9),
            pass_stages: f
                .pass_stages
                .iter()
                .map(|(n, s)| StageOut {
                    name: n.name().into(),
                    seconds: *s,
                    bytes: 0,
                    detail: String::new(),
                })
                .collect(),
        }
    }
}

impl MemoryOut {
    /// The estimate, its limit and the measured peaks.
    fn of(m: &MemoryFacts<'_>) -> MemoryOut {
        MemoryOut {
            estimate_bytes: m.estimate.total(),
            items: m
                .estimate
                .items
                .iter()
                .map(|i| MemoryItemOut {
                    name: i.name,
                    bytes: i.bytes,
                })
                .collect(),
            stored_per_emitted: m.estimate.stored_per_emitted,
            limit_bytes: m.limit,
            limit_source: m.limit_source,
            measured_peak_bytes: m.peak_resident,
            stage_peaks: m
                .stage_peaks
                .iter()
                .map(|&(stage, peak_bytes)| StagePeakOut {
                    stage: stage.name(),
                    peak_bytes,
                })
                .collect(),
        }
    }
}

impl RunReport {
    /// The report of a run.
    pub fn new(f: RunFacts<'_>) -> RunReport {
        let noise: Vec<glam::DVec3> = f
            .film
            .pass_variance()
            .into_iter()
            .map(|v| v.map(f64::sqrt))
            .collect();
        RunReport {
            version: env!("CARGO_PKG_VERSION"),
            run_id: f.run_id.to_string(),
            scene: SceneOut::of(f.scene_path, f.load),
            // The settings as asked for, with the merge radius and the weight clamp in force.
            settings: f.settings.record(
                f.renderer.radius(),
                f.radius_given,
                f.renderer.pixel_footprint(),
            ),
            threads: f.threads,
            passes_done: f.film.passes(),
            interrupted: f.plan.stop_reason == StopReason::Interrupted,
            camera_samples: f.samples,
            dropped_samples: f.film.dropped(),
            prepared_stages: f
                .renderer
                .stages()
                .iter()
                .map(|s| StageOut {
                    name: s.stage.name().into(),
                    seconds: s.seconds,
                    bytes: s.bytes,
                    detail: s.detail.clone(),
                })
                .collect(),
            timing: Timing::of(&f),
            weights: WeightsOut {
                evaluations: f.weights.evaluations,
                outside_unit_interval: f.weights.outside_unit,
                outside_unit_fraction: f.weights.outside_unit as f64
                    / f.weights.evaluations.max(1) as f64,
                clamped_cb: f.weights.clamped_cb,
            },
            photons: PhotonsOut {
                stored_total: f.photons_stored,
                largest_map_bytes: f.photon_map_bytes,
            },
            mean_radiance: image_mean(&f.film.mean()),
            mean_radiance_standard_error: standard_error_of_mean(f.pass_means),
            pass_image_means: f.pass_means.to_vec(),
            plan: f.plan.clone(),
            mean_noise_sqrt_v: image_mean(&noise),
            outputs: f.outputs.all().map(|p| p.display().to_string()),
            warnings: f.warnings.to_vec(),
            memory: MemoryOut::of(&f.memory),
            paths: f.renderer.paths_ran().into(),
        }
    }

    /// The report as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }
}

/// The settings as EXR header attributes (`bdpm.mode`, `bdpm.seed`, …), and the scene's
/// identity `bdpm.scene_hash` ([`bdpm_load::scene_hash`]), which `predict --measured` and
/// `study --reference` check, and `bdpm.estimator_hash` ([`crate::accum::estimator_hash`]),
/// which `predict --measured` checks.
pub fn header_attributes(
    s: &RenderSettings,
    r: &Renderer<'_>,
    radius_given: bool,
    scene_hash: &str,
) -> Vec<(String, String)> {
    let mut v = vec![
        ("version".to_string(), env!("CARGO_PKG_VERSION").to_string()),
        ("scene_hash".to_string(), scene_hash.to_string()),
        (
            "estimator_hash".to_string(),
            crate::accum::estimator_hash(s),
        ),
    ];
    // The same record as the JSON report's, with the radius in use.
    v.extend(
        s.record(r.radius(), radius_given, r.pixel_footprint())
            .header_attributes()
            .into_iter()
            .map(|(k, val)| (k.to_string(), val)),
    );
    for st in r.stages() {
        v.push((
            format!("stage.{}", st.stage.name().replace(' ', "_")),
            format!("{:.3} s", st.seconds),
        ));
    }
    v
}

#[cfg(test)]
mod tests {
    use super::StopReason;

    /// The report's serialised reason and the header's name are one spelling.
    #[test]
    fn stop_reason_names_agree() {
        for r in [
            StopReason::Completed,
            StopReason::Interrupted,
            StopReason::TimeBudget,
            StopReason::TargetNoise,
        ] {
            let json = serde_json::to_value(r).unwrap();
            assert_eq!(json, r.name(), "{r:?}");
            assert_eq!(
                r.flag()
                    .map(|f| f.trim_start_matches("--").replace('-', "_")),
                matches!(r, StopReason::TimeBudget | StopReason::TargetNoise)
                    .then(|| r.name().to_string())
            );
        }
    }
}
