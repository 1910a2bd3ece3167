//! `bdpm predict`: the noise model of method.md §12 evaluated per pixel for a mode's weights
//! ([`bdpm_integrator::Renderer::predict_variance`]) against the per-pass variance V measured
//! by a render made with the same settings. Writes OUT.exr (predicted and measured V, their
//! ratio and the model's four terms), OUT.png (log₂ of predicted/measured in a diverging false
//! colour) and OUT.json, and prints the summary.
//!
//! Measured V per pixel is taken from the render's `noise` layer (√V per pass, RGB) as
//! 0.2126·R² + 0.7152·G² + 0.0722·B² of √V: exactly the variance of the luminance when the
//! three channels' noise is fully correlated, as in grey scenes; for coloured scenes it is a
//! luminance-weighted mean of the channel variances, an approximation.
//!
//! With `--headroom` it also evaluates the functional for the unclamped `optimal-split`, its
//! minimiser over weights w₁(x₀, x₁) that may differ between one-bounce and merge paths (the
//! family in which the model evaluates every mode, `balance` included): the floor below which
//! no weight of that family can bring V, by the model. The ratio of the mode's predicted V to that floor, per pixel, is the most any such
//! weight could gain there (OUT.exr layers `floor_V` and `headroom`, OUT-headroom.png). The
//! floor weighs with the model's own cache and on the mode's radius map, so that it minimises
//! the very functional the mode is evaluated in.
//!
//! The model reads L_d and b from a radiance cache of its own (`--model-cache-photons`, 100
//! bins), the weights from the render's; the run is refused up front when the memory it is
//! estimated to need exceeds what is available.
use std::path::{Path, PathBuf};

use bdpm_integrator::prepare::{MODEL_CACHE_PHOTONS, model_cache_item, model_cache_settings};
use bdpm_integrator::{
    Mode, Prediction, RenderError, RenderSettings, Renderer, Setting, estimate_memory, human_bytes,
};
use bdpm_mis::Heuristic;
use clap::Args;
use serde::Serialize;

use bdpm_load::{LoadedScene, scene_hash};
use bdpm_output::accum::{check_scene_hash, estimator_hash};
use bdpm_output::cli::{
    CliResult, Overrides, flag_of, parse_bytes, prepare as cli_prepare, thread_pool,
};
use bdpm_output::colormap::{ColourMap, Legend, compose, format_value};
use bdpm_output::files::stem_of;
use bdpm_output::header::{self, Recorded};
use bdpm_output::memory::{self, MemoryLimit};
use bdpm_output::raster::Canvas;
use bdpm_output::{exr, files, say};

/// Side of the pixel blocks over which V is also compared (summed over the block's pixels):
/// blocks average out most of the measured V's own sampling error.
const BLOCK: u32 = 8;
/// The PNG's colour scale spans log₂(predicted/measured) from −LOG2_RANGE to +LOG2_RANGE
/// (a factor of 8 either way).
const LOG2_RANGE: f64 = 3.0;
/// The headroom map's scale: log₂(predicted V / floor) within ±0.5 (a factor of √2 either way;
/// the ratio is ≥ 1 up to the model's sampling noise).
const HEADROOM_LOG2_RANGE: f64 = 0.5;
/// The floor of `--headroom`: the functional's minimiser over weights w₁(x₀, x₁) per path
/// kind.
const FLOOR: Heuristic = Heuristic::OptimalSplit {
    clamp_weights: false,
};
/// Colour of pixels that are not compared (no surface).
const NOT_COMPARED: [u8; 3] = [0, 0, 0];

/// Arguments of this subcommand.
#[derive(Args, Debug)]
pub struct PredictArgs {
    /// The render to compare with (OUT.exr of `bdpm render`, with its `noise` layer): its
    /// header names the scene and the settings flags, which need not be repeated (a settings
    /// flag given again must have the recorded value). Or a scene file (TOML or Mitsuba 3 .xml), with the render
    /// as --measured.
    #[arg(value_name = "RENDER.exr|SCENE.toml")]
    input: PathBuf,
    #[command(flatten)]
    overrides: Overrides,
    /// The render to compare with, when the first argument is the scene file.
    #[arg(long = "measured", value_name = "RENDER.exr")]
    measured_arg: Option<PathBuf>,
    /// The scene file: the first argument, or the one the render's header names.
    #[arg(skip)]
    scene: PathBuf,
    /// The render: --measured, or the first argument.
    #[arg(skip)]
    measured: PathBuf,
    /// Output EXR path (default: the measured file's stem + `-predict.exr`); the PNG and JSON
    /// go beside it.
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
    /// Also predict V for the unclamped `optimal-split` (the functional's minimiser over
    /// weights w₁(x₀, x₁) per path kind) and report the mode's predicted V over it, per pixel: the most that any
    /// such weight could gain, by the model.
    #[arg(long)]
    headroom: bool,
    /// Photons of the model's own radiance cache, at least (default 8000000, with 100 bins per
    /// cell side): the model reads L_d and b at x₁ from it, the weights from the render's.
    #[arg(long, default_value_t = MODEL_CACHE_PHOTONS, value_parser = clap::value_parser!(u64).range(1..))]
    model_cache_photons: u64,
    /// Refuse to start when the estimated peak memory (the mode's renderer, the model's
    /// cache, and with --headroom the floor's renderer) exceeds this, e.g. 8G or 512M (K, M,
    /// G, T are powers of 1024). Default: the memory available on this machine
    /// (MemAvailable of /proc/meminfo), no limit where unknown.
    #[arg(long, value_parser = parse_bytes)]
    max_memory: Option<u64>,
}

/// The measured render: √V per pixel (RGB) and its `bdpm.*` header attributes.
struct Measured {
    width: u32,
    height: u32,
    /// Per-pass variance of the pixel luminance (see the module docs), (W·m⁻²·sr⁻¹)².
    variance: Vec<f64>,
    /// The render's mean luminance per pixel, W·m⁻²·sr⁻¹ (the R of relV).
    mean: Vec<f64>,
    attributes: Vec<(String, String)>,
}

impl Measured {
    fn attribute(&self, key: &str) -> Option<&str> {
        self.attributes
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

fn read_measured(path: &Path) -> CliResult<Measured> {
    let layer = exr::ExrLayer::read(path)?;
    let find = |name: &str| -> CliResult<&[f64]> {
        layer.channel(name).ok_or_else(|| {
            format!(
                "{}: no channel {name} (the noise layer of `bdpm render`)",
                path.display()
            )
        })
    };
    let (r, g, b) = (find("noise.R")?, find("noise.G")?, find("noise.B")?);
    let [wr, wg, wb] = bdpm_bdf::LUMINANCE_WEIGHTS;
    let variance = r
        .iter()
        .zip(g)
        .zip(b)
        // Not `stats::luminance` of the squares: this order of the products is what the
        // outputs were made with, and it keeps their bits.
        .map(|((r, g), b)| wr * r * r + wg * g * g + wb * b * b)
        .collect();
    let (r, g, b) = (find("R")?, find("G")?, find("B")?);
    let mean = r
        .iter()
        .zip(g)
        .zip(b)
        .map(|((r, g), b)| wr * r + wg * g + wb * b)
        .collect();
    Ok(Measured {
        width: layer.width,
        height: layer.height,
        variance,
        mean,
        attributes: layer.attributes,
    })
}

/// The settings that change V and that the render's header records: a mismatch makes the
/// comparison meaningless, so it is an error (the seed may differ).
fn check_settings(
    m: &Measured,
    s: &RenderSettings,
    r: &Renderer<'_>,
    path: &Path,
) -> CliResult<()> {
    let expected = [
        ("mode", s.mode.name().to_string()),
        ("spp", s.spp.to_string()),
        ("photons_per_pass", s.photons.to_string()),
        ("pixel_jitter", s.pixel_jitter.to_string()),
        ("noise_model", s.noise_model.name().to_string()),
        ("sampler", s.sampler.name().to_string()),
        ("radius_m", r.radius().to_string()),
    ];
    let mismatches: Vec<String> = expected
        .iter()
        .filter_map(|(k, v)| match m.attribute(k) {
            Some(got) if got != v => Some(format!("{k} {got} (prediction: {v})")),
            None => Some(format!("{k} missing (prediction: {v})")),
            _ => None,
        })
        .collect();
    if mismatches.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{}: rendered with other settings: {}",
            path.display(),
            mismatches.join(", ")
        ))
    }
}

/// Agreement of predicted and measured V over a set of samples (pixels or blocks).
#[derive(Serialize, Debug, Clone, PartialEq)]
pub(crate) struct Agreement {
    /// Samples compared: both V finite and ≥ 0 ([`ratio`]); the ratio quantiles are over all
    /// of them.
    count: usize,
    /// Of them, samples where the model predicts no noise at all but some was measured
    /// (ratio 0).
    predicted_zero: usize,
    /// Samples where neither predicts nor measures noise: they agree (ratio 1).
    both_zero: usize,
    /// Pearson correlation of ln V (predicted against measured), over the samples where both
    /// are positive.
    correlation_log: f64,
    /// Pearson correlation of V.
    correlation: f64,
    /// Median of predicted/measured.
    ratio_median: f64,
    /// 10 % quantile of predicted/measured.
    ratio_q10: f64,
    /// 90 % quantile of predicted/measured.
    ratio_q90: f64,
}

/// predicted/measured V of one sample: 1 where both are 0 (they agree), 0 where only the
/// prediction is (the model misses all of the noise), infinite where only the measurement
/// is; `None` where either is not finite or negative.
pub(crate) fn ratio(predicted: f64, measured: f64) -> Option<f64> {
    let usable = |v: f64| v.is_finite() && v >= 0.0;
    if !(usable(predicted) && usable(measured)) {
        return None;
    }
    Some(match (predicted > 0.0, measured > 0.0) {
        (false, false) => 1.0,
        (_, true) => predicted / measured,
        (true, false) => f64::INFINITY,
    })
}

/// Shares of the model's terms in the predicted total, summed over the compared pixels.
#[derive(Serialize, Debug, Clone, PartialEq)]
struct Shares {
    t0: f64,
    t1: f64,
    t2: f64,
    t_jitter: f64,
}

#[derive(Serialize)]
struct Report<'a> {
    scene: String,
    measured: String,
    mode: &'a str,
    width: u32,
    height: u32,
    spp: u32,
    photons_per_pass: u64,
    pixel_jitter: bool,
    noise_model: &'a str,
    sampler: &'a str,
    radius_m: f32,
    pixel_table_rays: u32,
    /// Passes K of the measured render.
    passes: u32,
    /// √(2/(K − 1)): relative standard error of one pixel's measured V (Gaussian pass
    /// estimates); a block's is smaller, by up to √(pixels in the block).
    measured_relative_se_per_pixel: f64,
    pixels_without_surface: usize,
    pixels_without_measured_noise: usize,
    /// Image means over the pixels with a surface, W²·m⁻⁴·sr⁻².
    image_mean_predicted_v: f64,
    image_mean_measured_v: f64,
    /// relV, the mean over the compared pixels of V/(L² + ε) with L the measured render's
    /// mean and ε = 0.01·mean(L)² (as `bdpm study`): predicted and measured.
    rel_v_predicted: f64,
    rel_v_measured: f64,
    term_shares: Shares,
    per_pixel: Agreement,
    block_size: u32,
    blocks: Agreement,
    /// The renderer's preparatory stages, the model's own cache among them.
    preparation: Vec<Preparation>,
    /// With `--headroom`: the mode's predicted V against the model's floor.
    #[serde(skip_serializing_if = "Option::is_none")]
    headroom: Option<Headroom>,
}

/// The mode's predicted V against the floor of the functional (the unclamped `optimal-split`
/// evaluated with the same cache and directions and its own pixel table).
#[derive(Serialize)]
struct Headroom {
    /// What the floor is.
    floor: &'static str,
    /// Image means over the compared pixels, W²·m⁻⁴·sr⁻².
    image_mean_floor_v: f64,
    /// Image mean of the mode's predicted V over the image mean of the floor.
    image_mean_ratio: f64,
    /// Share of the mode's predicted V that no weight changes (T_jitter).
    weight_independent_share: f64,
    /// Per pixel: "ratio" fields are the mode's predicted V over the floor.
    per_pixel: Agreement,
    /// The same over blocks of `block_size` pixels.
    blocks: Agreement,
}

/// Pearson correlation of two equally long samples (NaN for fewer than two or no spread).
fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    if a.len() < 2 {
        return f64::NAN;
    }
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma).powi(2);
        sbb += (y - mb).powi(2);
    }
    sab / (saa * sbb).sqrt()
}

/// The q-quantile of sorted values, interpolated linearly between order statistics.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let x = q * (sorted.len() - 1) as f64;
    let i = x.floor() as usize;
    let j = (i + 1).min(sorted.len() - 1);
    let f = x - i as f64;
    // At an order statistic exactly, that value: 0 × ∞ would make an infinite neighbour NaN.
    if f == 0.0 {
        sorted[i]
    } else {
        sorted[i] + f * (sorted[j] - sorted[i])
    }
}

/// Compares pairs (predicted, measured) by their [`ratio`]; pairs where either is not finite
/// or negative are left out, and the log correlation leaves out the ones with a zero.
pub(crate) fn agreement(pairs: &[(f64, f64)]) -> Agreement {
    let kept: Vec<(f64, f64)> = pairs
        .iter()
        .copied()
        .filter(|&(p, m)| ratio(p, m).is_some())
        .collect();
    let positive: Vec<(f64, f64)> = kept
        .iter()
        .copied()
        .filter(|(p, m)| *p > 0.0 && *m > 0.0)
        .collect();
    let (lp, lm): (Vec<f64>, Vec<f64>) = positive.iter().map(|(p, m)| (p.ln(), m.ln())).unzip();
    let (p, m): (Vec<f64>, Vec<f64>) = kept.iter().copied().unzip();
    let mut ratios: Vec<f64> = kept.iter().filter_map(|&(p, m)| ratio(p, m)).collect();
    ratios.sort_by(f64::total_cmp);
    Agreement {
        count: kept.len(),
        predicted_zero: kept.iter().filter(|(p, m)| *p == 0.0 && *m > 0.0).count(),
        both_zero: kept.iter().filter(|(p, m)| *p == 0.0 && *m == 0.0).count(),
        correlation_log: pearson(&lp, &lm),
        correlation: pearson(&p, &m),
        ratio_median: quantile(&ratios, 0.5),
        ratio_q10: quantile(&ratios, 0.1),
        ratio_q90: quantile(&ratios, 0.9),
    }
}

/// Sums predicted and measured V over `BLOCK`×`BLOCK` blocks, over the pixels with a surface
/// and a finite measurement; blocks without such pixels are left out.
fn block_sums(predicted: &[f64], measured: &[f64], width: u32, height: u32) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for by in (0..height).step_by(BLOCK as usize) {
        for bx in (0..width).step_by(BLOCK as usize) {
            let (mut p, mut m, mut n) = (0.0, 0.0, 0usize);
            for y in by..(by + BLOCK).min(height) {
                for x in bx..(bx + BLOCK).min(width) {
                    let i = (y * width + x) as usize;
                    if predicted[i].is_finite() && measured[i].is_finite() {
                        p += predicted[i];
                        m += measured[i];
                        n += 1;
                    }
                }
            }
            if n > 0 {
                out.push((p, m));
            }
        }
    }
    out
}

/// Default output: beside the measured render, `<stem>-predict.exr`.
fn default_output(measured: &Path) -> PathBuf {
    let stem = stem_of(measured, "render");
    measured.with_file_name(format!("{stem}-predict.exr"))
}

/// Runs the subcommand: [`prepare`] (scene, measured render, checks), [`Setup::predict`]
/// (the model's V, and the floor with `--headroom`), [`Setup::compare`] (the agreement
/// figures), [`Setup::write`] (EXR, PNGs, JSON, summary).
pub(crate) fn run(args: PredictArgs) -> CliResult<()> {
    let args = resolve(args)?;
    let setup = prepare(&args)?;
    let predicted = setup.predict()?;
    let comparison = setup.compare(&predicted);
    setup.write(&predicted, &comparison)
}

/// The scene, the render and the settings flags of `args`: from the render's header (scene and
/// flags, with the explicit flags over them, [`header::over_recorded`]), with `--measured`
/// the first argument as the scene. A render of a bdpm that kept no record takes the flags
/// as given, and needs the scene named.
fn resolve(mut args: PredictArgs) -> CliResult<PredictArgs> {
    let (scene, measured) = match args.measured_arg.take() {
        Some(m) => (Some(args.input.clone()), m),
        None => (None, args.input.clone()),
    };
    if scene.is_none()
        && measured
            .extension()
            .is_some_and(|e| e == "toml" || e == "xml")
    {
        return Err(format!(
            "{}: a scene file needs the render to compare with: --measured RENDER.exr (or give the render alone: bdpm predict RENDER.exr)",
            measured.display()
        ));
    }
    let attributes = exr::read_attributes(&measured)?;
    let recorded = Recorded::from_attributes(&measured, &attributes)?;
    if let Some(r) = &recorded {
        args.overrides = header::over_recorded(&measured, &r.overrides, &args.overrides)?;
    }
    args.scene = match (scene, recorded) {
        (Some(s), _) => s,
        (None, Some(r)) => r.scene,
        (None, None) => {
            return Err(format!(
                "{}: its header names no scene (made by an older bdpm); give it: bdpm predict SCENE.toml --measured {} with the render's settings flags",
                measured.display(),
                measured.display()
            ));
        }
    };
    args.measured = measured;
    Ok(args)
}

/// A prediction after [`prepare`]: the scene and settings, the measured render and the
/// output paths, all checked.
struct Setup<'a> {
    args: &'a PredictArgs,
    loaded: LoadedScene,
    measured: Measured,
    /// Passes the measured render did.
    passes: u32,
    scene_hash: String,
    exr_path: PathBuf,
    png_path: PathBuf,
    json_path: PathBuf,
    headroom_path: PathBuf,
    pool: rayon::ThreadPool,
}

/// What the model predicts: the mode's V, the floor's (with `--headroom`) and the merge
/// radius the renderer used, m.
struct Predicted {
    prediction: Prediction,
    floor: Option<Prediction>,
    radius: f32,
    preparation: Vec<Preparation>,
}

/// One preparatory stage of the mode's renderer, as the report lists it.
#[derive(Serialize, Clone)]
struct Preparation {
    stage: &'static str,
    /// Wall time, seconds.
    seconds: f64,
    detail: String,
}

/// The prediction set against the measurement: the report and the per-pixel maps written.
struct Comparison<'a> {
    report: Report<'a>,
    /// Predicted over measured V per pixel.
    ratio: Vec<f64>,
    /// Measured V where the model sees a surface, NaN elsewhere.
    measured_on_surface: Vec<f64>,
    /// Predicted V over the floor per pixel (with `--headroom`).
    headroom_ratio: Option<Vec<f64>>,
}

/// Loads the scene, reads the measured render and checks that it is a render of this scene
/// with these settings and enough passes, and that no output would overwrite an input.
fn prepare(args: &PredictArgs) -> CliResult<Setup<'_>> {
    let loaded = cli_prepare(&args.scene, &args.overrides)?;
    let settings = &loaded.settings;
    let mode = settings.mode;
    if matches!(mode, Mode::Path | Mode::Light) {
        return Err(format!(
            "--mode {mode}: the noise model is for the BDPM modes ({})",
            bdpm_mis::Heuristic::ALL_NAMES.join(", ")
        ));
    }
    let measured = read_measured(&args.measured)?;
    if (measured.width, measured.height) != (settings.width, settings.height) {
        return Err(format!(
            "{}: the render is {}x{} but the prediction is for {}x{} (give --resolution)",
            args.measured.display(),
            measured.width,
            measured.height,
            settings.width,
            settings.height
        ));
    }
    // The passes the render did, not the ones it was asked for: a render stopped by a budget
    // or an interrupt measured V from fewer.
    let passes: u32 = measured
        .attribute("passes_done")
        .and_then(|p| p.parse().ok())
        .ok_or_else(|| {
            format!(
                "{}: no bdpm.passes_done attribute (not a render of this bdpm)",
                args.measured.display()
            )
        })?;
    if passes < 2 {
        return Err(format!(
            "{}: {passes} pass done: V was not measured (need at least 2 passes)",
            args.measured.display()
        ));
    }
    let expected_hash =
        scene_hash(&args.scene, &loaded.report.gltf_files).map_err(|e| e.to_string())?;
    check_scene_hash(
        &args.measured,
        &measured.attributes,
        &expected_hash,
        "the measured render",
        true,
    )?;
    let exr_path = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.measured))
        .with_extension("exr");
    let png_path = exr_path.with_extension("png");
    let json_path = exr_path.with_extension("json");
    let headroom_path = headroom_png_path(&exr_path);
    let mut members = vec![exr_path.as_path(), &png_path, &json_path];
    if args.headroom {
        members.push(&headroom_path);
    }
    files::refuse_inputs(&members, &[&args.measured, &args.scene], &[])?;
    let pool = thread_pool(args.overrides.threads)?;
    Ok(Setup {
        args,
        loaded,
        measured,
        passes,
        scene_hash: expected_hash,
        exr_path,
        png_path,
        json_path,
        headroom_path,
        pool,
    })
}

impl Setup<'_> {
    /// Prepares the renderer, checks that the measured render used its settings, and
    /// evaluates the model (and, with `--headroom`, the floor).
    fn predict(&self) -> CliResult<Predicted> {
        let (args, scene, settings, pool) = (
            self.args,
            &self.loaded.scene,
            &self.loaded.settings,
            &self.pool,
        );
        memory_gate(args, scene, settings, pool)?;
        let renderer = pool
            .install(|| Renderer::new(scene, settings))
            .map_err(|e| format!("{}: {e}", args.scene.display()))?;
        // Refused before the model's inputs are built: the model is of the merge at x₀.
        if let Some(h) = renderer.heuristic().filter(|_| renderer.light_traced()) {
            return Err(format!(
                "{}: {} ({} false)",
                args.scene.display(),
                RenderError::LightTracing(h.name()),
                flag_of(Setting::LightTracing)
            ));
        }
        let photons = args.model_cache_photons;
        let renderer = pool.install(|| renderer.with_model_cache(photons));
        check_settings(&self.measured, settings, &renderer, &args.measured)?;
        // Every other setting (depth, cache, table, clamp, …), which the header lists no
        // field of.
        let estimator = estimator_hash(settings);
        if self.measured.attribute("estimator_hash") != Some(estimator.as_str()) {
            return Err(format!(
                "{}: rendered with other settings (estimator hash {}, the prediction's is {estimator}): \
                 give predict the render's settings",
                args.measured.display(),
                self.measured
                    .attribute("estimator_hash")
                    .unwrap_or("missing")
            ));
        }
        let prediction = pool
            .install(|| renderer.predict_variance())
            .map_err(|e| e.to_string())?;
        let floor = if args.headroom {
            let s = floor_settings(settings, photons);
            let map = renderer.radius_map().cloned();
            let r = pool
                .install(|| {
                    Renderer::new(scene, &s).map(|r| {
                        let r = match map {
                            Some(m) => r.with_radius_map(m),
                            None => r,
                        };
                        r.with_model_cache(photons)
                    })
                })
                .map_err(|e| format!("{}: {e}", args.scene.display()))?;
            Some(
                pool.install(|| r.predict_variance_for(FLOOR))
                    .map_err(|e| e.to_string())?,
            )
        } else {
            None
        };
        let preparation = renderer
            .stages()
            .iter()
            .map(|st| Preparation {
                stage: st.stage.name(),
                seconds: st.seconds,
                detail: st.detail.clone(),
            })
            .collect();
        Ok(Predicted {
            prediction,
            floor,
            radius: renderer.radius(),
            preparation,
        })
    }

    /// Compares the prediction with the measured V: per pixel, over blocks, term shares and,
    /// with `--headroom`, against the floor.
    fn compare(&self, predicted: &Predicted) -> Comparison<'static> {
        let (settings, measured) = (&self.loaded.settings, &self.measured);
        let (p, floor) = (&predicted.prediction, &predicted.floor);
        let mv = &measured.variance;
        let ratios: Vec<f64> = p
            .total
            .iter()
            .zip(mv)
            .map(|(p, m)| ratio(*p, *m).unwrap_or(f64::NAN))
            .collect();
        let surface: Vec<usize> = (0..mv.len()).filter(|&i| p.total[i].is_finite()).collect();
        let compared: Vec<usize> = surface
            .iter()
            .copied()
            .filter(|&i| mv[i].is_finite() && mv[i] > 0.0)
            .collect();
        let sum = |v: &[f64]| compared.iter().map(|&i| v[i]).sum::<f64>();
        let total = sum(&p.total);
        let share = |v: &[f64]| {
            if total > 0.0 {
                sum(v) / total
            } else {
                f64::NAN
            }
        };
        let n = compared.len().max(1) as f64;
        // relV over the compared pixels, with the measured render's mean as R (study's ε).
        let lum: Vec<f64> = compared.iter().map(|&i| measured.mean[i]).collect();
        let pick = |v: &[f64]| -> Vec<f64> { compared.iter().map(|&i| v[i]).collect() };
        let rel_v = |v: &[f64]| crate::study::rel_mean(&pick(v), &lum);
        let pairs: Vec<(f64, f64)> = p.total.iter().copied().zip(mv.iter().copied()).collect();
        // Blocks: only surface pixels count, in both sums.
        let measured_on_surface: Vec<f64> = mv
            .iter()
            .zip(&p.total)
            .map(|(m, t)| if t.is_finite() { *m } else { f64::NAN })
            .collect();
        let blocks = block_sums(
            &p.total,
            &measured_on_surface,
            settings.width,
            settings.height,
        );
        let headroom_ratio: Option<Vec<f64>> = floor.as_ref().map(|f| {
            p.total
                .iter()
                .zip(&f.total)
                .map(|(m, f)| ratio(*m, *f).unwrap_or(f64::NAN))
                .collect()
        });
        let headroom = floor
            .as_ref()
            .map(|f| headroom(p, f, &compared, total, n, (settings.width, settings.height)));
        let report = Report {
            scene: self.args.scene.display().to_string(),
            measured: self.args.measured.display().to_string(),
            mode: settings.mode.name(),
            width: settings.width,
            height: settings.height,
            spp: settings.spp,
            photons_per_pass: settings.photons,
            pixel_jitter: settings.pixel_jitter,
            noise_model: settings.noise_model.name(),
            sampler: settings.sampler.name(),
            radius_m: predicted.radius,
            pixel_table_rays: settings
                .pixel_table_rays
                .unwrap_or(bdpm_integrator::settings::PINHOLE_TABLE_RAYS),
            passes: self.passes,
            measured_relative_se_per_pixel: (2.0 / (self.passes as f64 - 1.0)).sqrt(),
            pixels_without_surface: mv.len() - surface.len(),
            pixels_without_measured_noise: surface.len() - compared.len(),
            image_mean_predicted_v: total / n,
            image_mean_measured_v: sum(mv) / n,
            rel_v_predicted: rel_v(&p.total),
            rel_v_measured: rel_v(mv),
            term_shares: Shares {
                t0: share(&p.t0),
                t1: share(&p.t1),
                t2: share(&p.t2),
                t_jitter: share(&p.t_jitter),
            },
            per_pixel: agreement(&pairs),
            block_size: BLOCK,
            blocks: agreement(&blocks),
            preparation: predicted.preparation.clone(),
            headroom,
        };
        Comparison {
            report,
            ratio: ratios,
            measured_on_surface,
            headroom_ratio,
        }
    }

    /// Writes OUT.exr, OUT.png (and OUT-headroom.png), OUT.json, and prints the summary.
    fn write(&self, predicted: &Predicted, c: &Comparison<'_>) -> CliResult<()> {
        let (args, settings) = (self.args, &self.loaded.settings);
        let (p, floor) = (&predicted.prediction, &predicted.floor);
        let (exr_path, png_path, json_path) = (&self.exr_path, &self.png_path, &self.json_path);
        let attributes = vec![
            ("version".to_string(), env!("CARGO_PKG_VERSION").to_string()),
            ("scene".into(), args.scene.display().to_string()),
            ("scene_hash".into(), self.scene_hash.clone()),
            ("measured".into(), args.measured.display().to_string()),
            ("mode".into(), settings.mode.name().into()),
            ("passes".into(), self.passes.to_string()),
            ("spp".into(), settings.spp.to_string()),
            ("photons_per_pass".into(), settings.photons.to_string()),
            ("radius_m".into(), predicted.radius.to_string()),
            ("units".into(), "V and terms in W2 m-4 sr-2".into()),
        ];
        let mut layers: Vec<(&str, &[f64])> = vec![
            ("predicted_V", &p.total),
            ("measured_V", &c.measured_on_surface),
            ("ratio", &c.ratio),
            ("T0", &p.t0),
            ("T1", &p.t1),
            ("T2", &p.t2),
            ("T_jitter", &p.t_jitter),
        ];
        if let (Some(f), Some(h)) = (floor, &c.headroom_ratio) {
            layers.push(("floor_V", &f.total));
            layers.push(("headroom", h));
        }
        exr::write_exr_channels(
            exr_path,
            (settings.width, settings.height),
            &layers,
            &attributes,
        )
        .map_err(|e| format!("{}: {e}", exr_path.display()))?;
        ratio_png(p, &c.ratio, LOG2_RANGE, "predicted / measured V")
            .and_then(|canvas| canvas.write_png(png_path))
            .map_err(|e| format!("{}: {e}", png_path.display()))?;
        let mut written = vec![exr_path.clone(), png_path.clone(), json_path.clone()];
        if let Some(h) = &c.headroom_ratio {
            let path = &self.headroom_path;
            ratio_png(p, h, HEADROOM_LOG2_RANGE, "predicted V / floor")
                .and_then(|canvas| canvas.write_png(path))
                .map_err(|e| format!("{}: {e}", path.display()))?;
            written.push(path.clone());
        }
        let json = serde_json::to_string_pretty(&c.report).map_err(|e| format!("JSON: {e}"))?;
        files::write_atomic(json_path, json.as_bytes())
            .map_err(|e| format!("{}: {e}", json_path.display()))?;

        print_summary(&c.report);
        let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
        say!("wrote {}", names.join(", "));
        Ok(())
    }
}

/// The mode's predicted V `p` against the floor `f` over the compared pixels (`total`: the
/// sum of `p` over them, `n` their count).
fn headroom(
    p: &Prediction,
    f: &Prediction,
    compared: &[usize],
    total: f64,
    n: f64,
    (width, height): (u32, u32),
) -> Headroom {
    let sum = |v: &[f64]| compared.iter().map(|&i| v[i]).sum::<f64>();
    let compared_pairs: Vec<(f64, f64)> =
        compared.iter().map(|&i| (p.total[i], f.total[i])).collect();
    let on_surface = |v: &[f64]| -> Vec<f64> {
        (0..v.len())
            .map(|i| {
                if compared.binary_search(&i).is_ok() {
                    v[i]
                } else {
                    f64::NAN
                }
            })
            .collect()
    };
    let floor_sum = sum(&f.total);
    Headroom {
        floor: "optimal-split, unclamped",
        image_mean_floor_v: floor_sum / n,
        image_mean_ratio: total / floor_sum,
        weight_independent_share: if total > 0.0 {
            sum(&p.t_jitter) / total
        } else {
            f64::NAN
        },
        per_pixel: agreement(&compared_pairs),
        blocks: agreement(&block_sums(
            &on_surface(&p.total),
            &on_surface(&f.total),
            width,
            height,
        )),
    }
}

/// Refuses a prediction whose estimated peak memory exceeds `--max-memory` (default: the
/// available memory), naming what to lower, before anything large is allocated: the mode's
/// preparation as a render's estimate counts it and the model's cache build, and with
/// `--headroom` the floor's renderer, prepared while the mode's is held
/// ([`memory::held_together`]).
fn memory_gate(
    args: &PredictArgs,
    scene: &bdpm_scene::Scene,
    settings: &RenderSettings,
    pool: &rayon::ThreadPool,
) -> CliResult<()> {
    let mut mode = pool.install(|| estimate_memory(scene, settings, false));
    mode.items
        .push(model_cache_item(&mode, args.model_cache_photons));
    let mut renderers = vec![mode];
    if args.headroom {
        let floor = floor_settings(settings, args.model_cache_photons);
        renderers.push(pool.install(|| estimate_memory(scene, &floor, false)));
    }
    let estimate = memory::held_together(&renderers);
    let limit = MemoryLimit::of(args.max_memory);
    match limit.exceeded_by(estimate.total()) {
        Some(_) => Err(format!(
            "{}: the prediction needs about {} ({}), more than {}; lower {} (or raise \
             --max-memory)",
            args.scene.display(),
            human_bytes(estimate.total()),
            memory::parts(&estimate),
            limit.describe(),
            memory::lower(estimate.scalable_largest())
        )),
        None => Ok(()),
    }
}

/// The settings of the floor's renderer (`--headroom`): the unclamped `optimal-split`, which
/// reads its own A and B, so its renderer builds the pixel table; its weights read the cache
/// the model reads (`photons` photons), so that it is the functional's minimiser.
fn floor_settings(settings: &RenderSettings, photons: u64) -> RenderSettings {
    let mut s = model_cache_settings(settings, photons);
    s.mode = Mode::Bdpm(FLOOR.kind());
    // With a radius per block, the mode's map: the floor's own pilot would draw another.
    s.adaptive_radius = false;
    s
}

fn print_summary(r: &Report<'_>) {
    say!(
        "predict {} mode {}: measured V from K = {} passes (relative SE per pixel ~{:.2}, less over blocks)",
        r.scene,
        r.mode,
        r.passes,
        r.measured_relative_se_per_pixel
    );
    for p in &r.preparation {
        say!("  {} ({:.2} s): {}", p.stage, p.seconds, p.detail);
    }
    say!(
        "image mean V: predicted {:.4e}, measured {:.4e} (ratio {:.3}; per pixel, the median of predicted/measured is {:.3}); {} pixels without a surface, {} without measured noise",
        r.image_mean_predicted_v,
        r.image_mean_measured_v,
        r.image_mean_predicted_v / r.image_mean_measured_v,
        r.per_pixel.ratio_median,
        r.pixels_without_surface,
        r.pixels_without_measured_noise
    );
    let a = &r.per_pixel;
    if a.predicted_zero + a.both_zero > 0 {
        say!(
            "{} pixels with no predicted noise: {} of them measured noise (ratio 0, counted in the ratios below and drawn at the scale's low end), {} measured none (they agree: ratio 1)",
            a.predicted_zero + a.both_zero,
            a.predicted_zero,
            a.both_zero
        );
    }
    say!(
        "relV: predicted {:.4e}, measured {:.4e} (ratio {:.3})",
        r.rel_v_predicted,
        r.rel_v_measured,
        r.rel_v_predicted / r.rel_v_measured
    );
    let s = &r.term_shares;
    say!(
        "term shares of predicted V: T0 {:.1}%, T1 {:.1}%, T2 {:.1}%, T_jitter {:.1}%",
        100.0 * s.t0,
        100.0 * s.t1,
        100.0 * s.t2,
        100.0 * s.t_jitter
    );
    for (name, a) in [
        ("per pixel", &r.per_pixel),
        (&format!("{0}x{0} blocks", r.block_size) as &str, &r.blocks),
    ] {
        say!(
            "{name} ({}): predicted/measured median {:.3} [10% {:.3}, 90% {:.3}], correlation of log V {:.3}, of V {:.3}",
            a.count,
            a.ratio_median,
            a.ratio_q10,
            a.ratio_q90,
            a.correlation_log,
            a.correlation
        );
    }
    if let Some(h) = &r.headroom {
        say!(
            "headroom over the floor ({}): image mean V {:.4e}, mode/floor {:.4}; per pixel median {:.4} [10% {:.4}, 90% {:.4}]; {}x{} blocks median {:.4} [10% {:.4}, 90% {:.4}]; weight-independent share {:.1}%",
            h.floor,
            h.image_mean_floor_v,
            h.image_mean_ratio,
            h.per_pixel.ratio_median,
            h.per_pixel.ratio_q10,
            h.per_pixel.ratio_q90,
            r.block_size,
            r.block_size,
            h.blocks.ratio_median,
            h.blocks.ratio_q10,
            h.blocks.ratio_q90,
            100.0 * h.weight_independent_share
        );
    }
}

/// OUT-headroom.png beside OUT.exr.
fn headroom_png_path(exr: &Path) -> PathBuf {
    let stem = stem_of(exr, "");
    exr.with_file_name(format!("{stem}-headroom.png"))
}

/// A ratio map: log₂(ratio) from −`range` (blue) through 0 (white) to +`range` (red), ratios
/// beyond either end (0 and ∞ included) at that end, black where nothing is compared, with
/// the colour bar titled `title`.
fn ratio_png(p: &Prediction, ratio: &[f64], range: f64, title: &str) -> CliResult<Canvas> {
    let position = |r: f64| (r.log2() / range + 1.0) * 0.5;
    let colours: Vec<[u8; 3]> = ratio
        .iter()
        .map(|&r| {
            // A ratio of 0 (no noise predicted where some was measured) or ∞ takes the end
            // of the scale, as any ratio beyond it does; only pixels without a surface are
            // not compared.
            if r.is_nan() {
                NOT_COMPARED
            } else {
                ColourMap::Diverging.colour(position(r))
            }
        })
        .collect();
    let ticks = [-1.0, -2.0 / 3.0, -1.0 / 3.0, 0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0]
        .iter()
        .map(|&k| {
            let r = (k * range).exp2();
            (position(r), format_value(r))
        })
        .collect();
    let legend = Legend {
        title: vec![
            title.into(),
            "log2 scale".into(),
            "black: no surface".into(),
        ],
        ticks,
    };
    Ok(compose(p.width, p.height, &colours, &legend, ColourMap::Diverging)?.canvas)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agreement_of_identical_and_scaled_samples() {
        let pairs: Vec<(f64, f64)> = (1..=20).map(|i| (2.0 * i as f64, i as f64)).collect();
        let a = agreement(&pairs);
        assert_eq!(a.count, 20);
        assert!((a.correlation - 1.0).abs() < 1e-12);
        assert!((a.correlation_log - 1.0).abs() < 1e-12);
        assert_eq!((a.ratio_median, a.ratio_q10, a.ratio_q90), (2.0, 2.0, 2.0));
        // Non-finite or negative pairs are left out; a pair measured without noise but
        // predicted with some has ratio ∞.
        let b = agreement(&[
            (1.0, 0.0),
            (f64::NAN, 1.0),
            (-1.0, 1.0),
            (1.0, 1.0),
            (2.0, 1.0),
        ]);
        assert_eq!((b.count, b.predicted_zero, b.both_zero), (3, 0, 0));
        assert_eq!(b.ratio_median, 2.0);
    }

    #[test]
    fn pixels_without_predicted_noise_are_compared_not_dropped() {
        assert_eq!(ratio(0.0, 0.0), Some(1.0));
        assert_eq!(ratio(0.0, 2.0), Some(0.0));
        assert_eq!(ratio(1.0, 0.0), Some(f64::INFINITY));
        assert_eq!(ratio(1.0, 4.0), Some(0.25));
        assert_eq!(ratio(f64::NAN, 1.0), None);
        // Two pixels the model predicts no noise for: one measured some (ratio 0), one none
        // (they agree, ratio 1); both count, and move the median.
        let a = agreement(&[(0.0, 1.0), (0.0, 0.0), (2.0, 1.0), (3.0, 1.0), (4.0, 1.0)]);
        assert_eq!((a.count, a.predicted_zero, a.both_zero), (5, 1, 1));
        assert_eq!((a.ratio_median, a.ratio_q10), (2.0, 0.4));
    }

    #[test]
    fn quantiles_interpolate() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(quantile(&v, 0.5), 3.0);
        assert!((quantile(&v, 0.1) - 1.4).abs() < 1e-12);
        assert!(quantile(&[], 0.5).is_nan());
    }

    #[test]
    fn blocks_sum_surface_pixels_only() {
        // 9×9: four blocks (8×8, 1×8, 8×1, 1×1); one pixel without a surface.
        let mut p = vec![1.0; 81];
        let m = vec![2.0; 81];
        p[0] = f64::NAN;
        let b = block_sums(&p, &m, 9, 9);
        assert_eq!(b, vec![(63.0, 126.0), (8.0, 16.0), (8.0, 16.0), (1.0, 2.0)]);
    }
}
