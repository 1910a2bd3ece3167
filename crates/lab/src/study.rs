//! `bdpm study`: error against run time for several modes.
//!
//! Each mode renders passes of the same scene and settings; after every pass the study records
//! the wall time (preparatory stages such as the radiance cache and the A/B table counted in
//! the first pass, so equal-time comparisons are honest), the RMSE of the running mean against
//! a reference, and the mean per-pass noise √V. Every error measure is over pixel
//! **luminance** (Rec. 709 weights). It writes `study.csv`, `study.md`, log-log plots of error
//! against time and a bar chart of mean √V (PNG and SVG), a preview PNG per mode, and the
//! figure of the modes' images against the reference (`figure.png`, `.html`, `.json`, see
//! `figure`).
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use bdpm_integrator::{
    Film, MemoryEstimate, MemoryItem, RenderSettings, Renderer, estimate_memory, human_bytes,
};
use bdpm_load::{LoadedScene, scene_hash};
use bdpm_output::accum::check_scene_hash;
use bdpm_output::cli::{
    CliResult, Overrides, parse_bytes, positive, prepare as cli_prepare, progress_bar, thread_pool,
    whole,
};
use bdpm_output::files::{refuse_inputs, stem_of, write_atomic};
use bdpm_output::memory::{self, MemoryLimit};
use bdpm_output::system::{load_average, peak_resident_memory, process_cpu_seconds};

use crate::plot;
use bdpm_output::preview::write_png;
use bdpm_output::stats::{PixelStats, luminance};
use clap::Args;
use indicatif::ProgressBar;

use crate::reference;
// The error measures moved to `metrics` (the figure uses them too); their old paths stay.
pub(crate) use crate::metrics::{mean, rel_epsilon, rel_mean, rel_mse, rmse};

// The field docs are clap's help text, printed in a terminal: `<scene>` there is a
// placeholder, not an HTML tag.
#[allow(rustdoc::invalid_html_tags)]
/// Arguments of this subcommand. The shared `--mode` is hidden: a study takes `--modes`
/// (and still refuses `--mode` with a message saying so).
#[derive(Args, Debug)]
#[command(mut_arg("mode", |a| a.hide(true)))]
pub struct StudyArgs {
    /// Scene file (TOML, or a Mitsuba 3 scene ending in .xml).
    scene: PathBuf,
    /// Render settings (--passes, --photons, --spp, --resolution, …) for every mode.
    #[command(flatten)]
    overrides: Overrides,
    // The help lists every key an entry may set, from the parser's own list.
    #[arg(long, value_delimiter = ',', help = crate::modes_help("compare"))]
    modes: Vec<String>,
    /// Give each mode this many seconds of wall time (preparation included) instead of a fixed
    /// number of passes; it stops after the pass that reaches the budget, and has at least
    /// one pass even when its preparation alone took longer (the report says so).
    #[arg(long, conflicts_with = "passes", allow_negative_numbers = true, value_parser = positive)]
    time_budget: Option<f64>,
    /// Reference image (EXR with R, G, B; a `stderr` layer is used when present). Default: a
    /// `light` render, cached in the output directory (its estimated time is printed after
    /// its first pass, its own error once it is done).
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Passes of the rendered reference (default: 16 × the study's passes).
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<u32>)]
    reference_passes: Option<u32>,
    /// Photons per pass of the rendered reference (default: the study's N_F).
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<u64>)]
    reference_photons: Option<u64>,
    /// The clock of the time axis, the equal-time comparison and the efficiency: `wall`, or
    /// `cpu` (the process's CPU time, user + system: steadier on a shared machine). Both are
    /// in the CSV either way.
    #[arg(long, default_value = "wall", value_parser = ["wall", "cpu"])]
    clock: String,
    /// Output directory (default: out/study-<scene>).
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
    /// Refuse to start when the estimated peak memory exceeds this, e.g. 8G or 512M (K, M,
    /// G, T are powers of 1024): every entry's renderer is prepared and held while the modes
    /// take their passes in turn, and the reference render comes first. Default: the memory
    /// available on this machine (MemAvailable of /proc/meminfo), no limit where unknown.
    #[arg(long, value_parser = parse_bytes)]
    max_memory: Option<u64>,
    /// Do not draw progress bars.
    #[arg(long)]
    quiet: bool,
}

/// The value at `t` of the curve through `points` (x ascending, all positive), interpolated
/// linearly in log x and log y. `None` outside the points' x range.
pub(crate) fn interpolate_loglog(points: &[(f64, f64)], t: f64) -> Option<f64> {
    let first = points.first()?;
    let last = points.last()?;
    if t.is_nan() || t <= 0.0 || t < first.0 || t > last.0 {
        return None;
    }
    for w in points.windows(2) {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        if t >= x0 && t <= x1 {
            if x1 <= x0 || y0 <= 0.0 || y1 <= 0.0 {
                return Some(y1);
            }
            let a = (t.ln() - x0.ln()) / (x1.ln() - x0.ln());
            return Some((y0.ln() + a * (y1.ln() - y0.ln())).exp());
        }
    }
    Some(first.1)
}

/// Efficiency 1/(V·t): inverse of the variance a unit of time buys. `mean_v` in
/// (W·m⁻²·sr⁻¹)², `seconds_per_pass` in s.
pub(crate) fn efficiency(mean_v: f64, seconds_per_pass: f64) -> f64 {
    1.0 / (mean_v * seconds_per_pass)
}

/// Side of the square pixel blocks over which [`regional_choice`] picks a variant.
pub(crate) const REGION_SIDE: usize = 8;

/// One variant's images for [`regional_choice`], luminance per pixel (row-major).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ModeImages<'a> {
    /// Per-pass variance V (W²·m⁻⁴·sr⁻²); empty without two passes.
    pub(crate) variance: &'a [f64],
    /// The mean over the passes (W·m⁻²·sr⁻¹).
    pub(crate) mean: &'a [f64],
    /// Passes K behind `mean` and `variance`.
    pub(crate) passes: usize,
}

/// What choosing the variant per image region would buy: see [`regional_choice`].
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RegionalChoice {
    /// The best single variant's figure over the best per-block mix's, both from all passes:
    /// ≥ 1, the most a per-region choice among the variants could gain.
    pub(crate) gain: f64,
    /// The same with the choices made on one half of the passes (even or odd) and judged on
    /// the other, the geometric mean of the two ways round: what a choice made from estimates
    /// keeps. Below 1 when the in-sample gain is the estimates' noise. `None` without two
    /// passes in each half.
    pub(crate) cross_validated: Option<f64>,
    /// Index of the best single variant.
    pub(crate) best_single: usize,
    /// Per variant, the share of the image's pixels whose block the best mix gives it.
    pub(crate) shares: Vec<f64>,
}

/// Each variant's part of relV and of the squared bias per block of pixels, and each block's
/// share of the pixels.
struct Blocks {
    /// `parts[b][k]`: Σ over block b's pixels of V_k/(R² + ε), divided by the image's pixels.
    parts: Vec<Vec<f64>>,
    /// `bias[b][k]`: the same sum of ((I_k − R)² − V_k/K_k − σ_R²)/(R² + ε), an unbiased
    /// estimate of the squared bias (noisy, can be negative).
    bias: Vec<Vec<f64>>,
    weight: Vec<f64>,
}

impl Blocks {
    fn new(
        modes: &[ModeImages<'_>],
        reference: &[f64],
        ref_var: &[f64],
        width: usize,
        side: usize,
    ) -> Option<Blocks> {
        let n = reference.len();
        let fits = |m: &ModeImages<'_>| m.variance.len() == n && m.mean.len() == n && m.passes > 1;
        if width == 0 || side == 0 || ref_var.len() != n || !modes.iter().all(fits) {
            return None;
        }
        let eps = rel_epsilon(reference);
        let (bw, bh) = (width.div_ceil(side), (n / width).div_ceil(side));
        let mut parts = vec![vec![0.0f64; modes.len()]; bw * bh];
        let mut bias = parts.clone();
        let mut weight = vec![0.0f64; bw * bh];
        for (i, r) in reference.iter().enumerate() {
            let b = (i / width / side) * bw + (i % width) / side;
            let scale = 1.0 / ((r * r + eps) * n as f64);
            weight[b] += 1.0 / n as f64;
            for (k, m) in modes.iter().enumerate() {
                let v = m.variance[i];
                parts[b][k] += v * scale;
                bias[b][k] += ((m.mean[i] - r).powi(2) - v / m.passes as f64 - ref_var[i]) * scale;
            }
        }
        parts
            .iter()
            .chain(&bias)
            .flatten()
            .all(|p| p.is_finite())
            .then_some(Blocks {
                parts,
                bias,
                weight,
            })
    }

    /// The figure of merit of the mix that gives block b variant `choice[b]`, less is
    /// better: relV·(time per pass) without a `time`, and relMSE after `time` s (squared
    /// bias plus relV over the passes that time buys) with one.
    fn merit(&self, choice: &[usize], seconds: &[f64], time: Option<f64>) -> f64 {
        let pick = |rows: &[Vec<f64>]| -> f64 { choice.iter().zip(rows).map(|(&c, p)| p[c]).sum() };
        let t: f64 = choice
            .iter()
            .zip(&self.weight)
            .map(|(&c, w)| w * seconds[c])
            .sum();
        match time {
            None => pick(&self.parts) * t,
            Some(time) => pick(&self.bias) + pick(&self.parts) * t / time,
        }
    }

    /// The best single variant (every block the same) and the best mix found.
    fn best(&self, seconds: &[f64], time: Option<f64>) -> (Vec<usize>, Vec<usize>) {
        let k = seconds.len();
        let blocks = self.parts.len();
        let singles: Vec<f64> = (0..k)
            .map(|j| self.merit(&vec![j; blocks], seconds, time))
            .collect();
        let single = (0..k)
            .min_by(|&a, &b| singles[a].total_cmp(&singles[b]))
            .unwrap_or(0);
        let (mut best, mut choice) = (singles[single], vec![single; blocks]);
        // The candidates minimise, block by block, bias + c·relV + λ·time, which makes the
        // mix's terms separable: c is the time per pass over `time` (1 without one, where
        // the bias is not counted), λ from 2⁻¹² to 2¹² in units of the best single variant's
        // relV per second, and 0.
        let t0 = seconds[single];
        let rel_v0: f64 = self.parts.iter().map(|p| p[single]).sum();
        let cs: Vec<f64> = match time {
            None => vec![1.0],
            Some(time) => (-16..=16)
                .map(|e| t0 / time * (e as f64 / 4.0).exp2())
                .collect(),
        };
        let bias_weight = if time.is_some() { 1.0 } else { 0.0 };
        for &c in &cs {
            let scale = c * rel_v0 / t0;
            let lambdas =
                std::iter::once(0.0).chain((-48..=48).map(|e| scale * (e as f64 / 4.0).exp2()));
            for lambda in lambdas {
                let pick: Vec<usize> = (0..blocks)
                    .map(|b| {
                        let cost = |j: usize| {
                            bias_weight * self.bias[b][j]
                                + c * self.parts[b][j]
                                + lambda * self.weight[b] * seconds[j]
                        };
                        (0..k)
                            .min_by(|&x, &y| cost(x).total_cmp(&cost(y)))
                            .unwrap_or(0)
                    })
                    .collect();
                let m = self.merit(&pick, seconds, time);
                if m < best {
                    (best, choice) = (m, pick);
                }
            }
        }
        (vec![single; blocks], choice)
    }
}

/// The most that choosing among the variants per `side` × `side` block of pixels (a radius or
/// a weight per pixel, say) could gain over the best single variant.
///
/// `modes[k]` holds variant k's images from all its passes, `halves[h][k]` from its even
/// (h = 0) or odd passes only; `seconds[k]` its time per pass; `reference` the reference
/// luminance (relV's R) and `ref_var` its variance per pixel. A mix that gives block b variant
/// k_b has relV Σ_b relV_b(k_b) (each block's part of the image's mean) and, with a pass's
/// cost spread evenly over the pixels, time per pass t = Σ_b (n_b/N)·t(k_b). Without `time`
/// the figure is relV·t, whose inverse is the efficiency in relV, and the kernel bias is left
/// out; with `time` it is the relMSE after that many seconds, Σ_b bias²_b(k_b) + relV·t/time,
/// the squared bias estimated per block from the mean's error against the reference. The
/// figure is minimised over mixes that minimise a separable bias + c·relV + λ·t (a sweep
/// over c and λ; every single variant is a candidate too). The in-sample gain flatters the
/// mix (the least of noisy estimates); the cross-validated one does not.
///
/// `None` with fewer than two variants or a variant without finite variances.
pub(crate) fn regional_choice(
    modes: &[ModeImages<'_>],
    halves: [&[ModeImages<'_>]; 2],
    seconds: &[f64],
    reference: &[f64],
    ref_var: &[f64],
    (width, side): (usize, usize),
    time: Option<f64>,
) -> Option<RegionalChoice> {
    let k = modes.len();
    if k < 2 || seconds.len() != k || seconds.iter().any(|t| !(t.is_finite() && *t > 0.0)) {
        return None;
    }
    if time.is_some_and(|t| !(t.is_finite() && t > 0.0)) {
        return None;
    }
    let all = Blocks::new(modes, reference, ref_var, width, side)?;
    let (single, mix) = all.best(seconds, time);
    let gain = all.merit(&single, seconds, time) / all.merit(&mix, seconds, time);
    let folds: Option<Vec<Blocks>> = halves
        .iter()
        .map(|h| {
            (h.len() == k)
                .then(|| Blocks::new(h, reference, ref_var, width, side))
                .flatten()
        })
        .collect();
    let cross_validated = folds.map(|f| {
        let judged = |chosen_on: &Blocks, judge: &Blocks| {
            let (single, mix) = chosen_on.best(seconds, time);
            judge.merit(&single, seconds, time) / judge.merit(&mix, seconds, time)
        };
        (judged(&f[0], &f[1]) * judged(&f[1], &f[0])).sqrt()
    });
    let mut shares = vec![0.0; k];
    for (&c, w) in mix.iter().zip(&all.weight) {
        shares[c] += w;
    }
    Some(RegionalChoice {
        gain,
        cross_validated,
        best_single: single[0],
        shares,
    })
}

/// The report's paragraph on [`regional_choice`] among the study's modes, in relV
/// efficiency and in relMSE at the equal-time point `time` (empty when it has no answer:
/// one mode, or one pass).
fn regional_paragraph(
    runs: &[ModeRun],
    reference: &[f64],
    ref_var: &[f64],
    width: usize,
    clock: &str,
    time: f64,
) -> String {
    let modes: Vec<ModeImages<'_>> = runs
        .iter()
        .map(|r| ModeImages {
            variance: &r.variance,
            mean: &r.mean,
            passes: r.points.len(),
        })
        .collect();
    let halves: [Vec<ModeImages<'_>>; 2] = [0, 1].map(|h| {
        runs.iter()
            .map(|r| ModeImages {
                variance: &r.half_variances[h],
                mean: &r.half_means[h],
                // Passes 1, 3, … are the even half (index 0).
                passes: (r.points.len() + 1 - h) / 2,
            })
            .collect()
    });
    let seconds: Vec<f64> = runs.iter().map(ModeRun::seconds_per_pass).collect();
    let choose = |time| {
        regional_choice(
            &modes,
            [&halves[0], &halves[1]],
            &seconds,
            reference,
            ref_var,
            (width, REGION_SIDE),
            time,
        )
    };
    let Some(c) = choose(None) else {
        return String::new();
    };
    let shares = |c: &RegionalChoice| -> String {
        runs.iter()
            .zip(&c.shares)
            .filter(|(_, s)| **s > 0.0)
            .map(|(r, s)| format!("`{}` {:.0} %", r.name, 100.0 * s))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let cv = |c: &RegionalChoice| match c.cross_validated {
        Some(g) => format!("cross-validated **{g:.3}×**"),
        None => "not cross-validated (too few passes)".into(),
    };
    let mut text = format!(
        "Choosing the mode per {side} × {side}-pixel block instead of one for the image (a radius \
         or a weight per pixel, say), kernel bias left out: {gain:.3}× the efficiency in relV \
         (1/(relV · {clock} time per pass)) of the best single mode, `{best}`, in sample, with \
         the blocks given to {shares}; {cv} (chosen on the even passes and judged on the odd \
         ones, and the other way round: the in-sample figure flatters the mix, the least of \
         noisy estimates). A pass's time is taken as spread evenly over the pixels.",
        side = REGION_SIDE,
        gain = c.gain,
        best = runs[c.best_single].name,
        shares = shares(&c),
        cv = cv(&c),
    );
    if let Some(b) = choose(Some(time)) {
        text.push_str(&format!(
            " Counting the kernel bias (per block, the squared error of the mean less its \
             variance and the reference's), relMSE at {time:.2} s: the best single mode `{best}` \
             has {gain:.3}× the mix's in sample, with the blocks given to {shares}; {cv}.",
            best = runs[b.best_single].name,
            gain = b.gain,
            shares = shares(&b),
            cv = cv(&b),
        ));
    }
    text
}

/// The record of one pass of one mode.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PassPoint {
    pub(crate) pass: u32,
    /// Time since the mode started, preparation included, s, on the study's clock
    /// (`--clock`).
    pub(crate) time: f64,
    /// Wall time since the mode started, preparation included, s.
    pub(crate) wall_s: f64,
    /// Process CPU time since the mode started, preparation included, s (NaN if unknown).
    pub(crate) cpu_s: f64,
    pub(crate) rmse: f64,
    pub(crate) rel_rmse: f64,
    /// relMSE: mean over pixels of (I − R)²/(R² + ε), ε = 0.01·mean(R)² ([`rel_mse`]).
    pub(crate) rel_mse: f64,
    /// Mean over pixels of √V; NaN after the first pass.
    pub(crate) mean_sqrt_v: f64,
    /// Mean over pixels of √V / reference (pixels where the reference is positive); NaN after
    /// the first pass.
    pub(crate) mean_rel_sqrt_v: f64,
}

/// Everything a study keeps of one mode.
#[derive(Clone, Debug)]
pub(crate) struct ModeRun {
    pub(crate) name: String,
    /// Preparatory stages (name, s).
    pub(crate) stages: Vec<(String, f64)>,
    pub(crate) points: Vec<PassPoint>,
    /// Mean over pixels of V after the last pass.
    pub(crate) mean_v: f64,
    /// relV: mean over pixels of V/(R² + ε) after the last pass ([`rel_mse`]'s ε).
    pub(crate) rel_v: f64,
    /// V per pixel after the last pass (luminance, W²·m⁻⁴·sr⁻²); empty after one pass.
    pub(crate) variance: Vec<f64>,
    /// V per pixel from the even passes (first, third, …) and from the odd ones; empty with
    /// fewer than two passes in the half.
    pub(crate) half_variances: [Vec<f64>; 2],
    /// The luminance per pixel after the last pass (W·m⁻²·sr⁻¹), and over the even and the
    /// odd passes alone.
    pub(crate) mean: Vec<f64>,
    pub(crate) half_means: [Vec<f64>; 2],
    pub(crate) dropped: u64,
}

impl ModeRun {
    pub(crate) fn prep_seconds(&self) -> f64 {
        self.stages.iter().fold(0.0, |a, s| a + s.1)
    }
    pub(crate) fn total_seconds(&self) -> f64 {
        self.points.last().map_or(0.0, |p| p.time)
    }
    pub(crate) fn seconds_per_pass(&self) -> f64 {
        self.total_seconds() / self.points.len().max(1) as f64
    }
    pub(crate) fn final_point(&self) -> Option<&PassPoint> {
        self.points.last()
    }
}

/// A mode while the study runs it.
struct ModeState<'a> {
    name: String,
    /// Passes to take (without a time budget).
    passes: u32,
    /// The mode's wall time so far, preparation included, s.
    wall: f64,
    /// The mode's process CPU time so far, preparation included, s (NaN if unknown).
    cpu: f64,
    /// The mode's time on the study's clock when its preparation ended, s.
    prepared_at: f64,
    renderer: Renderer<'a>,
    stages: Vec<(String, f64)>,
    film: Film,
    lum: PixelStats,
    /// `lum` over the even passes (0, 2, …) and over the odd ones.
    halves: [PixelStats; 2],
    points: Vec<PassPoint>,
}

/// What [`Study::finish`] hands the report: the runs, each mode's image for the figure, the
/// previews written and the notes.
struct Finished {
    runs: Vec<ModeRun>,
    images: Vec<crate::figure::Entry>,
    files: Vec<String>,
    notes: Vec<String>,
}

/// The reference's own error, as the amounts it adds to a squared-error figure.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ErrorFloor {
    /// Mean over pixels of the reference's variance (W²·m⁻⁴·sr⁻²).
    pub(crate) mse: f64,
    /// The same divided per pixel by R² + ε ([`rel_mean`]).
    pub(crate) rel_mse: f64,
}

/// Luminance of each pixel (Rec. 709), in the pixels' unit.
pub(crate) fn luminances(pixels: &[glam::DVec3]) -> Vec<f64> {
    pixels.iter().map(|c| luminance(*c)).collect()
}

/// A reference's own variance per pixel (W²·m⁻⁴·sr⁻²): the square of the luminance of its
/// standard error (an upper bound for coloured pixels), or 0 for `len` pixels without one.
pub(crate) fn reference_variance(stderr: Option<&[glam::DVec3]>, len: usize) -> Vec<f64> {
    match stderr {
        Some(se) => se.iter().map(|c| luminance(*c).powi(2)).collect(),
        None => vec![0.0; len],
    }
}

/// `measured − floor`: a squared-error figure of the image alone, without the reference's own
/// error `floor`; at least 1 % of `floor`, a positive stand-in for "below what the reference
/// can resolve" that the log-log interpolation needs. Unchanged when `floor` is 0.
pub(crate) fn without_floor(measured: f64, floor: f64) -> f64 {
    if floor > 0.0 {
        (measured - floor).max(0.01 * floor)
    } else {
        measured
    }
}

/// The common time at which modes are compared: the smallest final time over the modes
/// (every mode ran at least that long).
pub(crate) fn equal_time(runs: &[ModeRun]) -> f64 {
    runs.iter()
        .map(ModeRun::total_seconds)
        .fold(f64::INFINITY, f64::min)
}

/// A mode's relative RMSE at time `t` (log-log interpolation), `None` before its first pass.
pub(crate) fn rel_rmse_at(run: &ModeRun, t: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = run.points.iter().map(|p| (p.time, p.rel_rmse)).collect();
    interpolate_loglog(&pts, t)
}

/// A mode's relMSE at time `t` (log-log interpolation), `None` before its first pass.
pub(crate) fn rel_mse_at(run: &ModeRun, t: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = run.points.iter().map(|p| (p.time, p.rel_mse)).collect();
    interpolate_loglog(&pts, t)
}

/// The CSV of all pass records.
pub(crate) fn csv(runs: &[ModeRun]) -> String {
    let mut s = String::from(
        "mode,pass,wall_time_s,rmse,rel_rmse,mean_sqrt_v,cpu_time_s,mean_rel_sqrt_v,rel_mse\n",
    );
    let opt = |v: f64, digits: usize| {
        if v.is_finite() {
            format!("{v:.digits$e}")
        } else {
            String::new()
        }
    };
    for r in runs {
        for p in &r.points {
            let cpu = if p.cpu_s.is_finite() {
                format!("{:.2}", p.cpu_s)
            } else {
                String::new()
            };
            let _ = writeln!(
                s,
                "{},{},{:.4},{:.6e},{:.6e},{},{},{},{:.6e}",
                r.name,
                p.pass,
                p.wall_s,
                p.rmse,
                p.rel_rmse,
                opt(p.mean_sqrt_v, 6),
                cpu,
                opt(p.mean_rel_sqrt_v, 6),
                p.rel_mse
            );
        }
    }
    s
}

/// Facts about the reference for the report.
#[derive(Clone, Debug)]
struct RefFacts {
    origin: String,
    mean_lum: f64,
    /// RMSE-equivalent of the reference's own standard error (an upper bound: the luminance of
    /// the per-channel standard errors), when known.
    floor: Option<f64>,
    /// The reference's own error in relMSE (0 without a stderr layer).
    rel_mse_floor: f64,
}

impl RefFacts {
    /// What is known of the reference's own error, for the report and the terminal.
    fn own_error(&self) -> String {
        match self.floor {
            Some(f) => format!(
                "its own error (RMSE-equivalent of its standard error, an upper bound) is \
                 {f:.3e} W·m⁻²·sr⁻¹ = {:.3}% relative",
                100.0 * f / self.mean_lum
            ),
            None => "its own error is unknown (no stderr layer)".into(),
        }
    }

    /// A warning when the reference's own relative error is at least half the smallest
    /// final rel. RMSE of the modes (`runs`, the reference's error subtracted): their error
    /// figures are then differences of near numbers, and a longer reference is needed.
    fn warning(&self, runs: &[ModeRun]) -> Option<String> {
        let own = self.floor? / self.mean_lum;
        let (name, best) = runs
            .iter()
            .filter_map(|r| Some((&r.name, r.final_point()?.rel_rmse)))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        (own >= 0.5 * best).then(|| {
            format!(
                "the reference's own error ({:.2}% relative) is not small against the modes' \
                 errors (the smallest, `{name}`'s, {:.2}% after subtracting it): the figures \
                 are uncertain; render a longer reference (--reference-passes) or give a \
                 converged one (--reference)",
                100.0 * own,
                100.0 * best
            )
        })
    }
}

/// The report's paragraphs before the table: the reference, its own error (with a warning
/// when it is not small) and how the figures are made.
fn preamble(s: &mut String, refs: &RefFacts, runs: &[ModeRun], baseline: &str, clock: &str) {
    let subtracted = if refs.floor.is_some() {
        format!(
            " Every error figure (RMSE, rel. RMSE, relMSE) has the reference's own error \
             subtracted: its variance per pixel from the squared error (relMSE {:.3e}), floored \
             at 1 % of it.",
            refs.rel_mse_floor
        )
    } else {
        String::new()
    };
    let _ = writeln!(
        s,
        "Reference: {}; mean luminance {:.4e} W·m⁻²·sr⁻¹; {}.\n",
        refs.origin,
        refs.mean_lum,
        refs.own_error()
    );
    if let Some(w) = refs.warning(runs) {
        let _ = writeln!(s, "**Warning:** {w}.\n");
    }
    let t_eq = equal_time(runs);
    let _ = writeln!(
        s,
        "Errors are over pixel luminance. Times include the preparatory stages (radiance \
         cache, A/B table; their wall time is the \"prep\" column) spread over the passes. \
         V is the per-pass variance of a pixel; relV and relMSE divide each pixel's V and \
         squared error by R² + ε (R the reference, ε = 0.01·mean(R)²) before the mean over \
         pixels, so that a few bright or edge pixels do not dominate them as they dominate \
         mean V and rel. RMSE. The comparison clock is **{clock}** time: the \"at {t_eq:.2} s\" \
         columns interpolate each mode's curve in log-log at the smallest final {clock} time \
         of all modes; efficiency is 1/(mean V · {clock} time per pass), and in relV \
         1/(relV · {clock} time per pass), relative to `{baseline}`. Without bias, relMSE after \
         K passes is relV/K.{subtracted}\n"
    );
}

/// The markdown report: settings, reference, and the per-mode table.
fn markdown(
    header: &str,
    refs: &RefFacts,
    runs: &[ModeRun],
    baseline: &str,
    clock: &str,
    after_table: &str,
    files: &[String],
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{header}\n");
    preamble(&mut s, refs, runs, baseline, clock);
    let t_eq = equal_time(runs);
    let _ = writeln!(
        s,
        "| mode | passes | prep (s) | wall s/pass | CPU s/pass | mean V | relV | rel. RMSE | relMSE | rel. RMSE at {t_eq:.2} s | relMSE at {t_eq:.2} s | efficiency vs {baseline} | efficiency in relV |"
    );
    let _ = writeln!(
        s,
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    let baseline_run = runs.iter().find(|r| r.name == baseline);
    let base = baseline_run.map(|r| efficiency(r.mean_v, r.seconds_per_pass()));
    let base_rel = baseline_run.map(|r| efficiency(r.rel_v, r.seconds_per_pass()));
    let sci = |v: f64| {
        if v.is_finite() {
            format!("{v:.4e}")
        } else {
            "—".into()
        }
    };
    let ratio = |v: f64, base: Option<f64>, spp: f64| match base {
        Some(b) if v > 0.0 => format!("{:.2}", efficiency(v, spp) / b),
        _ => "—".into(),
    };
    for r in runs {
        let Some(last) = r.final_point() else {
            continue;
        };
        let k = r.points.len() as f64;
        let at = rel_rmse_at(r, t_eq).map_or("—".into(), |v| format!("{:.3}%", 100.0 * v));
        let mse_at = rel_mse_at(r, t_eq).map_or("—".into(), sci);
        let cpu = if last.cpu_s.is_finite() {
            format!("{:.3}", last.cpu_s / k)
        } else {
            "—".into()
        };
        let _ = writeln!(
            s,
            "| {} | {} | {:.2} | {:.3} | {} | {} | {} | {:.3}% | {} | {} | {} | {} | {} |",
            r.name,
            r.points.len(),
            r.prep_seconds(),
            last.wall_s / k,
            cpu,
            sci(r.mean_v),
            sci(r.rel_v),
            100.0 * last.rel_rmse,
            sci(last.rel_mse),
            at,
            mse_at,
            ratio(r.mean_v, base, r.seconds_per_pass()),
            ratio(r.rel_v, base_rel, r.seconds_per_pass()),
        );
    }
    if !after_table.is_empty() {
        let _ = writeln!(s, "\n{after_table}");
    }
    let dropped: u64 = runs.iter().map(|r| r.dropped).sum();
    if dropped > 0 {
        let _ = writeln!(s, "\n{dropped} non-finite samples were dropped in total.");
    }
    let _ = writeln!(s, "\nFiles: {}.", files.join(", "));
    s
}

/// The preview file of a `--modes` entry: its name with every character but letters, digits,
/// '.', '_' and '-' replaced by '_' (an entry such as `balance:sampler=independent` has ':'
/// and '=', which do not belong in file names), and `.png`.
fn preview_name(entry: &str) -> String {
    let stem: String = entry
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("{stem}.png")
}

/// Runs the subcommand: [`prepare`] (scene, reference), [`Study::modes`] (every renderer),
/// [`Study::run`] (the passes, round-robin), [`Study::write`] (previews, CSV, plots, report).
pub(crate) fn run(args: StudyArgs) -> CliResult<()> {
    let study = prepare(&args)?;
    let mut modes = study.modes()?;
    study.run(&mut modes);
    study.write(modes)
}

/// A study after [`prepare`]: the scene, the modes to run and the reference they are measured
/// against.
struct Study<'a> {
    args: &'a StudyArgs,
    variants: Vec<crate::Variant>,
    loaded: LoadedScene,
    pool: rayon::ThreadPool,
    /// The scene file's stem, for titles.
    stem: String,
    /// The output directory.
    dir: PathBuf,
    /// The reference's mean radiance per pixel (W·m⁻²·sr⁻¹), for the figure.
    ref_rgb: Vec<glam::DVec3>,
    /// The reference's luminance per pixel, and its image mean.
    ref_lum: Vec<f64>,
    /// The reference's variance per pixel (luminance; zeros without a stderr layer).
    ref_var: Vec<f64>,
    ref_mean: f64,
    floor: ErrorFloor,
    refs: RefFacts,
    /// The load average before the modes ran.
    load_before: String,
    /// Whether the time axis is the process CPU time.
    use_cpu: bool,
    /// The estimated peak of the modes' renderers held together, and of the reference
    /// render when there was one.
    memory: MemoryEstimate,
    reference_memory: Option<MemoryEstimate>,
}

/// Checks the arguments, loads the scene, refuses a study that would not fit in memory, and
/// reads or renders the reference.
fn prepare(args: &StudyArgs) -> CliResult<Study<'_>> {
    if args.overrides.mode.is_some() {
        return Err("study: use --modes (a comma-separated list), not --mode".into());
    }
    if let Some(b) = args.time_budget
        && !(b.is_finite() && b > 0.0)
    {
        return Err(format!(
            "--time-budget must be a positive number of seconds, not {b}"
        ));
    }
    let variants = crate::parse_modes(&args.modes)?;
    check_preview_names(&variants)?;
    let loaded = cli_prepare(&args.scene, &args.overrides)?;
    let pool = thread_pool(args.overrides.threads)?;
    let stem = stem_of(&args.scene, "scene");
    let dir = args
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(format!("study-{stem}")));
    let limit = MemoryLimit::of(args.max_memory);
    let memory = memory_gate(args, &variants, &loaded, &pool, limit)?;
    claim_directory(&dir)?;
    let (reference, reference_memory) =
        study_reference(args, &variants, &loaded, &dir, &pool, limit)?;
    let (w, h) = (loaded.settings.width, loaded.settings.height);
    if (reference.width, reference.height) != (w, h) {
        return Err(format!(
            "{}: reference is {}x{} but the study renders {w}x{h}",
            reference.path.display(),
            reference.width,
            reference.height
        ));
    }
    let ref_lum = luminances(&reference.mean);
    let ref_mean = mean(&ref_lum);
    if ref_mean.is_nan() || ref_mean <= 0.0 {
        return Err(format!(
            "{}: the reference image is black; relative errors are undefined",
            reference.path.display()
        ));
    }
    // The reference's own variance per pixel (its squared standard error), subtracted from
    // every squared error below: E[(I − R)²] = MSE(I) + Var(R) for an independent R.
    let ref_var = reference_variance(reference.stderr.as_deref(), ref_lum.len());
    let floor = ErrorFloor {
        mse: mean(&ref_var),
        rel_mse: rel_mean(&ref_var, &ref_lum),
    };
    let refs = RefFacts {
        origin: reference.origin.clone(),
        mean_lum: ref_mean,
        floor: reference.stderr.as_ref().map(|_| floor.mse.sqrt()),
        rel_mse_floor: floor.rel_mse,
    };
    if !args.quiet {
        bdpm_output::say_err!("reference: {}", refs.own_error());
    }
    let load_before = load_average();
    let use_cpu = args.clock == "cpu";
    if use_cpu && process_cpu_seconds().is_none() {
        return Err("--clock cpu: the process CPU time is not available here".into());
    }
    Ok(Study {
        args,
        variants,
        loaded,
        pool,
        stem,
        dir,
        ref_rgb: reference.mean,
        ref_lum,
        ref_var,
        ref_mean,
        floor,
        refs,
        load_before,
        use_cpu,
        memory,
        reference_memory,
    })
}

/// Refuses an output directory that is a file, creates it, and checks that a file can be
/// created in it: before the reference and the modes run, not after.
fn claim_directory(dir: &Path) -> CliResult<()> {
    if std::fs::metadata(dir).is_ok_and(|m| !m.is_dir()) {
        return Err(format!(
            "-o {}: it is a file; study writes a directory (of CSV, plots and previews)",
            dir.display()
        ));
    }
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("-o {}: cannot create the directory: {e}", dir.display()))?;
    let probe = dir.join(format!(".bdpm-study-probe-{}", std::process::id()));
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .map_err(|e| format!("-o {}: cannot write in the directory: {e}", dir.display()))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Refuses entries whose previews would be one file ([`preview_name`] maps every character
/// but letters, digits, '.', '_' and '-' to '_', and a file system may ignore case): one
/// preview would replace the other.
fn check_preview_names(variants: &[crate::Variant]) -> CliResult<()> {
    for (i, v) in variants.iter().enumerate() {
        let file = preview_name(&v.name);
        if let Some(w) = variants[..i]
            .iter()
            .find(|w| preview_name(&w.name).eq_ignore_ascii_case(&file))
        {
            return Err(format!(
                "--modes: '{}' and '{}' would both write the preview {file}; write the entries \
                 so that they differ in letters, digits, '.', '_' or '-'",
                w.name, v.name
            ));
        }
    }
    Ok(())
}

/// Refuses, before the reference or any mode runs, a study whose renderers would not fit in
/// memory together: every entry's renderer is prepared and held, then the modes take their
/// passes one at a time ([`memory::held_together`]), beside the reference image. Returns the
/// estimate.
fn memory_gate(
    args: &StudyArgs,
    variants: &[crate::Variant],
    loaded: &LoadedScene,
    pool: &rayon::ThreadPool,
    limit: MemoryLimit,
) -> CliResult<MemoryEstimate> {
    let estimates: Vec<MemoryEstimate> =
        crate::entry_estimates(&loaded.scene, variants, &loaded.settings, pool)?
            .into_iter()
            .map(|(_, e)| e)
            .collect();
    let mut total = memory::held_together(&estimates);
    let pixels = loaded.settings.width as u64 * loaded.settings.height as u64;
    total.items.push(MemoryItem {
        name: "reference image",
        bytes: pixels * REFERENCE_BYTES_PER_PIXEL,
        lifetime: memory::Lifetime::Shared,
        lower: bdpm_integrator::memory::Lower::Setting(bdpm_integrator::Setting::Resolution),
    });
    crate::refuse_above_limit(&args.scene, "study", &total, variants, &estimates, limit)?;
    Ok(total)
}

/// Bytes per pixel of the reference the study holds: its mean and standard error (RGB, f64)
/// and its luminance and variance (f64).
const REFERENCE_BYTES_PER_PIXEL: u64 = 2 * 24 + 2 * 8;

/// The reference: read from `--reference` (which must not be one of the study's outputs) or
/// a `light` render, cached in the study's directory `dir`; with the estimated peak memory of
/// the render when there was one.
fn study_reference(
    args: &StudyArgs,
    variants: &[crate::Variant],
    loaded: &LoadedScene,
    dir: &Path,
    pool: &rayon::ThreadPool,
    limit: MemoryLimit,
) -> CliResult<(reference::Reference, Option<MemoryEstimate>)> {
    let settings = &loaded.settings;
    let hash = scene_hash(&args.scene, &loaded.report.gltf_files).map_err(|e| e.to_string())?;
    if let Some(path) = &args.reference {
        let mut members: Vec<PathBuf> = variants
            .iter()
            .map(|v| dir.join(preview_name(&v.name)))
            .collect();
        members.extend(["study.csv", "study.md"].map(|n| dir.join(n)));
        for stem in ["error-vs-time", "sqrt-v"] {
            members.extend(["png", "svg"].map(|e| dir.join(stem).with_extension(e)));
        }
        members.extend(crate::figure_cli::members(dir));
        let members: Vec<&Path> = members.iter().map(PathBuf::as_path).collect();
        refuse_inputs(&members, &[path], &[])?;
    }
    let mut rendered = None;
    let reference = match &args.reference {
        Some(path) => {
            let mut r = reference::read_exr(path)?;
            // A reference of another scene gives errors that mean nothing; one made by
            // another program (no attribute) is taken on trust.
            check_scene_hash(path, &r.attributes, &hash, "the reference", false)?;
            r.origin = format!("read from {}", path.display());
            r
        }
        None => {
            let passes = match args.reference_passes {
                Some(0) => return Err("--reference-passes must be at least 1".into()),
                Some(p) => p,
                None => settings.passes.saturating_mul(16),
            };
            let photons = match args.reference_photons {
                Some(0) => return Err("--reference-photons must be at least 1".into()),
                Some(n) => n,
                None => settings.photons,
            };
            let rs = reference::reference_settings(settings, passes, photons);
            let path = reference::cache_path(dir, &args.scene, &hash, &rs);
            if !path.exists() {
                rendered = Some(reference_memory_gate(args, loaded, &rs, pool, limit)?);
            }
            let mut r =
                reference::cached_or_render(&loaded.scene, &hash, &rs, &path, pool, args.quiet)?;
            r.origin = format!(
                "`light` mode, {passes} passes of N_F = {photons}, N_B = {}, seed {}; {}",
                rs.spp, rs.seed, r.origin
            );
            r
        }
    };
    Ok((reference, rendered))
}

/// Refuses a reference render (settings `rs`) that would not fit in memory, naming the
/// flags that shape it; returns its estimate.
fn reference_memory_gate(
    args: &StudyArgs,
    loaded: &LoadedScene,
    rs: &RenderSettings,
    pool: &rayon::ThreadPool,
    limit: MemoryLimit,
) -> CliResult<MemoryEstimate> {
    let e = pool.install(|| estimate_memory(&loaded.scene, rs, false));
    match limit.exceeded_by(e.total()) {
        Some(_) => Err(format!(
            "{}: the study's reference render (`light`, N_F = {}) needs about {} ({}), more \
             than {}; lower --reference-photons or --resolution, give --reference FILE, or \
             raise --max-memory",
            args.scene.display(),
            rs.photons,
            human_bytes(e.total()),
            memory::parts(&e),
            limit.describe()
        )),
        None => Ok(e),
    }
}

impl Study<'_> {
    /// The process CPU time, s (NaN where unknown).
    fn cpu_now(&self) -> f64 {
        process_cpu_seconds().unwrap_or(f64::NAN)
    }

    /// Prepares every mode's renderer; its clock starts with its preparation.
    fn modes(&self) -> CliResult<Vec<ModeState<'_>>> {
        let (w, h) = (self.loaded.settings.width, self.loaded.settings.height);
        let mut states = Vec::new();
        for variant in &self.variants {
            let name = &variant.name;
            let s = variant.settings(&self.loaded.settings)?;
            let (t0, c0) = (Instant::now(), self.cpu_now());
            let renderer = self
                .pool
                .install(|| Renderer::new(&self.loaded.scene, &s))
                .map_err(|e| {
                    format!("{}: --modes entry '{name}': {e}", self.args.scene.display())
                })?;
            let stages = renderer
                .stages()
                .iter()
                .map(|st| (st.stage.name().to_string(), st.seconds))
                .collect();
            // The mode's clock: preparation plus its passes, not the metrics computed between.
            let (wall, cpu) = (t0.elapsed().as_secs_f64(), self.cpu_now() - c0);
            states.push(ModeState {
                name: name.clone(),
                passes: s.passes,
                wall,
                cpu,
                prepared_at: if self.use_cpu { cpu } else { wall },
                renderer,
                stages,
                film: Film::new(w, h),
                lum: PixelStats::new(w as usize * h as usize),
                halves: [0, 1].map(|_| PixelStats::new(w as usize * h as usize)),
                points: Vec::new(),
            });
        }
        Ok(states)
    }

    /// Whether a mode has had its passes, or its time budget. Every mode has at least one
    /// pass: one whose preparation alone took the budget is reported with it, not dropped.
    fn done(&self, m: &ModeState<'_>) -> bool {
        if m.points.is_empty() {
            return false;
        }
        match self.args.time_budget {
            Some(budget) => (if self.use_cpu { m.cpu } else { m.wall }) >= budget,
            None => m.points.len() as u32 >= m.passes,
        }
    }

    /// Renders the passes. Every renderer is prepared first, then the passes are taken
    /// round-robin, one pass of each mode in turn, so that a change in what else the machine
    /// runs (which moves every timing here by ±10 %) falls on all modes alike and their time
    /// ratios stay fair.
    fn run(&self, states: &mut [ModeState<'_>]) {
        let len = self.args.time_budget.is_none().then(|| {
            states
                .iter()
                .map(|m| m.passes as u64 * m.renderer.work_per_pass())
                .sum()
        });
        let template = if len.is_some() {
            "{prefix:>16} [{elapsed_precise}] {bar:32} {percent:>3}% {msg}"
        } else {
            "{prefix:>16} [{elapsed_precise}] {spinner} {msg}"
        };
        let bar = progress_bar(self.args.quiet, len, template);
        bar.set_prefix("study");
        while states.iter().any(|m| !self.done(m)) {
            for m in states.iter_mut().filter(|m| !self.done(m)) {
                self.pass(m, &bar);
            }
        }
        bar.finish_and_clear();
    }

    /// Renders the next pass of one mode and records its point.
    fn pass(&self, m: &mut ModeState<'_>, bar: &ProgressBar) {
        let (ref_lum, floor) = (&self.ref_lum, self.floor);
        let pass = m.points.len() as u32;
        bar.set_message(format!("{} pass {}", m.name, pass + 1));
        let (t, c) = (Instant::now(), self.cpu_now());
        let out = self
            .pool
            .install(|| m.renderer.render_pass(pass, &|n| bar.inc(n)));
        m.wall += t.elapsed().as_secs_f64();
        m.cpu += self.cpu_now() - c;
        m.film.add_pass(&out.estimates, out.dropped);
        m.lum.add_pass(&out.estimates);
        m.halves[pass as usize % 2].add_pass(&out.estimates);
        let image = m.lum.mean();
        let e = without_floor(rmse(&image, ref_lum).powi(2), floor.mse).sqrt();
        let var = m.lum.variance();
        let sqrt_v = var.as_ref().map_or(f64::NAN, |v| {
            mean(&v.iter().map(|x| x.sqrt()).collect::<Vec<_>>())
        });
        let rel_sqrt_v = var.as_ref().map_or(f64::NAN, |v| {
            let rel: Vec<f64> = v
                .iter()
                .zip(ref_lum)
                .filter(|(_, r)| **r > 0.0)
                .map(|(x, r)| x.sqrt() / r)
                .collect();
            mean(&rel)
        });
        m.points.push(PassPoint {
            pass: pass + 1,
            time: if self.use_cpu { m.cpu } else { m.wall },
            wall_s: m.wall,
            cpu_s: m.cpu,
            rmse: e,
            rel_rmse: e / self.ref_mean,
            rel_mse: without_floor(rel_mse(&image, ref_lum), floor.rel_mse),
            mean_sqrt_v: sqrt_v,
            mean_rel_sqrt_v: rel_sqrt_v,
        });
    }

    /// Writes each mode's preview and turns the modes into their runs; returns the runs, the
    /// previews written and the notes for the report (a mode whose preparation alone took
    /// longer than the time budget).
    fn finish(&self, states: Vec<ModeState<'_>>) -> CliResult<Finished> {
        let mut runs = Vec::new();
        let mut images = Vec::new();
        let mut files = Vec::new();
        let mut notes = Vec::new();
        for m in states {
            if let Some(budget) = self.args.time_budget
                && m.prepared_at >= budget
            {
                notes.push(format!(
                    "`{}`'s preparation took {:.2} s of {} time, more than the time budget of \
                     {budget} s: it had {} pass(es), {:.2} s in all",
                    m.name,
                    m.prepared_at,
                    self.args.clock,
                    m.points.len(),
                    m.points.last().map_or(m.prepared_at, |p| p.time)
                ));
            }
            let variance = m.lum.variance();
            let mean_v = variance.as_ref().map_or(f64::NAN, |v| mean(v));
            let rel_v = variance
                .as_ref()
                .map_or(f64::NAN, |v| rel_mean(v, &self.ref_lum));
            let preview = self.dir.join(preview_name(&m.name));
            write_png(&preview, &m.film).map_err(|e| format!("{}: {e}", preview.display()))?;
            files.push(preview.display().to_string());
            images.push(crate::figure::Entry {
                name: m.name.clone(),
                rgb: m.film.mean(),
                seconds: m.points.last().map(|p| p.time),
            });
            let run = ModeRun {
                name: m.name,
                stages: m.stages,
                points: m.points,
                mean_v,
                rel_v,
                variance: variance.unwrap_or_default(),
                half_variances: m
                    .halves
                    .each_ref()
                    .map(|h| h.variance().unwrap_or_default()),
                mean: m.lum.mean(),
                half_means: m.halves.each_ref().map(PixelStats::mean),
                dropped: m.film.dropped(),
            };
            if !self.args.quiet {
                let last = run.final_point().map(|p| p.rel_rmse).unwrap_or(f64::NAN);
                bdpm_output::say_err!(
                    "{:>16}: {} passes in {:.1} s, rel. RMSE {:.3}%",
                    run.name,
                    run.points.len(),
                    run.total_seconds(),
                    100.0 * last
                );
            }
            runs.push(run);
        }
        if !self.args.quiet {
            for n in notes.iter().chain(&self.refs.warning(&runs)) {
                bdpm_output::say_err!("note: {}", n.replace('`', ""));
            }
        }
        Ok(Finished {
            runs,
            images,
            files,
            notes,
        })
    }

    /// The paragraphs after the report's table: the regional choice, then the notes.
    fn after_table(&self, runs: &[ModeRun], notes: &[String]) -> String {
        let regional = regional_paragraph(
            runs,
            &self.ref_lum,
            &self.ref_var,
            self.loaded.settings.width as usize,
            &self.args.clock,
            equal_time(runs),
        );
        std::iter::once(regional)
            .chain(notes.iter().map(|n| format!("Note: {n}.")))
            .filter(|p| !p.is_empty())
            .collect::<Vec<_>>()
            .join("\n\n")
    }

    /// Writes the previews, the CSV, the plots and the markdown report.
    fn write(&self, states: Vec<ModeState<'_>>) -> CliResult<()> {
        let Finished {
            runs,
            images,
            files,
            notes,
        } = self.finish(states)?;
        let (args, settings, dir) = (self.args, &self.loaded.settings, &self.dir);
        let (stem, w, h) = (&self.stem, settings.width, settings.height);
        let csv_path = dir.join("study.csv");
        write_atomic(&csv_path, csv(&runs).as_bytes())
            .map_err(|e| format!("{}: {e}", csv_path.display()))?;
        let plot_err = plot::LogLogPlot {
            title: format!("{stem} {w}x{h}: error against time"),
            x_label: format!("{} time, s (preparation included)", args.clock),
            y_label: "relative RMSE of luminance".into(),
            series: runs
                .iter()
                .map(|r| plot::Series {
                    name: r.name.clone(),
                    points: r.points.iter().map(|p| (p.time, p.rel_rmse)).collect(),
                })
                .collect(),
            floor: self
                .refs
                .floor
                .map(|f| ("reference's own error".to_string(), f / self.ref_mean)),
        };
        let err_stem = dir.join("error-vs-time");
        plot::write_loglog(&err_stem, &plot_err)?;
        let plot_v = plot::BarPlot {
            title: format!(
                "{stem} {w}x{h}: mean per-pass noise (N_F = {}, N_B = {})",
                settings.photons, settings.spp
            ),
            y_label: "mean √V of luminance, W·m⁻²·sr⁻¹".into(),
            bars: runs
                .iter()
                .map(|r| {
                    (
                        r.name.clone(),
                        r.final_point().map_or(f64::NAN, |p| p.mean_sqrt_v),
                    )
                })
                .collect(),
        };
        let v_stem = dir.join("sqrt-v");
        plot::write_bars(&v_stem, &plot_v)?;
        let baseline = if self.variants.iter().any(|v| v.name == "bdd0") {
            "bdd0".to_string()
        } else {
            self.variants[0].name.clone()
        };
        let mut all_files = vec![csv_path.display().to_string()];
        for stem in [&err_stem, &v_stem] {
            for ext in ["png", "svg"] {
                all_files.push(stem.with_extension(ext).display().to_string());
            }
        }
        all_files.extend(files);
        all_files.extend(self.figure(images)?);
        let md = markdown(
            &self.header(),
            &self.refs,
            &runs,
            &baseline,
            &args.clock,
            &self.after_table(&runs, &notes),
            &all_files,
        );
        crate::publish(&dir.join("study.md"), &md)
    }

    /// Writes the figure of the modes' images against the reference (figure.png, .html,
    /// .json; crops where the error is largest); returns the paths written.
    fn figure(&self, images: Vec<crate::figure::Entry>) -> CliResult<Vec<String>> {
        let settings = &self.loaded.settings;
        let fig = crate::figure::build(crate::figure::Inputs {
            width: settings.width,
            height: settings.height,
            reference: self.ref_rgb.clone(),
            reference_error: self.refs.floor.map(|f| f / self.ref_mean),
            entries: images,
            crops: Vec::new(),
            auto_crops: 2,
        });
        let title = format!(
            "{}: the modes at {} against the reference",
            self.stem,
            match self.args.time_budget {
                Some(b) => format!("{b} s of {} time each", self.args.clock),
                None => format!("{} passes each", settings.passes),
            }
        );
        let written = crate::figure_cli::write_set(&self.dir, &fig, &title)?;
        Ok(written.iter().map(|p| p.display().to_string()).collect())
    }

    /// The report's heading: scene, settings, command and load average.
    fn header(&self) -> String {
        let (args, settings) = (self.args, &self.loaded.settings);
        let header = format!(
            "## Study: {} at {}x{}, N_F = {} photons and N_B = {} camera samples per pixel per pass, {}, seed {}, {} threads",
            args.scene.display(),
            settings.width,
            settings.height,
            settings.photons,
            settings.spp,
            match args.time_budget {
                Some(b) => format!("{b} s per mode"),
                None => format!("{} passes", settings.passes),
            },
            settings.seed,
            self.pool.current_num_threads()
        );
        let command: Vec<String> = std::env::args().collect();
        format!(
            "{header}\n\nCommand: `{}`\n\nLoad average (1, 5, 15 min) {} before the modes ran, {} after: \
             wall times depend on what else the machine runs.\n\n{}",
            command.join(" "),
            self.load_before,
            load_average(),
            self.memory_line()
        )
    }

    /// The memory estimates the study was admitted with, and the measured peak.
    fn memory_line(&self) -> String {
        let reference = self.reference_memory.as_ref().map_or(String::new(), |e| {
            format!(
                ", the reference render before them at {} ({})",
                human_bytes(e.total()),
                memory::parts(e)
            )
        });
        let peak = peak_resident_memory().map_or("unknown".into(), human_bytes);
        format!(
            "Memory: the modes' renderers held together were estimated at {} ({}){reference}; \
             the measured peak resident memory (VmHWM) is {peak}.",
            human_bytes(self.memory.total()),
            memory::parts(&self.memory)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rmse_of_known_images() {
        assert_eq!(rmse(&[1.0, 2.0], &[1.0, 2.0]), 0.0);
        // Differences 3 and 4: √((9 + 16)/2).
        assert!((rmse(&[3.0, 0.0], &[0.0, 4.0]) - 12.5f64.sqrt()).abs() < 1e-12);
        assert_eq!(rmse(&[], &[]), 0.0);
    }

    #[test]
    fn loglog_interpolation_is_exact_on_power_laws() {
        // y = 2 t^(-1/2): a straight line in log-log, so interpolation is exact.
        let pts: Vec<(f64, f64)> = [1.0, 4.0, 16.0]
            .iter()
            .map(|t: &f64| (*t, 2.0 / t.sqrt()))
            .collect();
        for t in [1.0, 2.0, 4.0, 9.0, 16.0] {
            let y = interpolate_loglog(&pts, t).expect("inside the range");
            assert!((y - 2.0 / t.sqrt()).abs() < 1e-12, "t = {t}: {y}");
        }
        assert_eq!(interpolate_loglog(&pts, 0.5), None);
        assert_eq!(interpolate_loglog(&pts, 17.0), None);
        assert_eq!(interpolate_loglog(&[], 1.0), None);
    }

    #[test]
    fn relative_metrics_of_known_images() {
        // Reference (0, 2): mean 1, ε = 0.01. Errors (1, 1): 1/0.01 and 1/4.01.
        let r = [0.0, 2.0];
        let expected = 0.5 * (1.0 / 0.01 + 1.0 / 4.01);
        assert!((rel_mse(&[1.0, 3.0], &r) - expected).abs() < 1e-12);
        assert!((rel_mean(&[1.0, 1.0], &r) - expected).abs() < 1e-12);
        assert_eq!(rel_mse(&r, &r), 0.0);
        assert!((rel_epsilon(&r) - 0.01).abs() < 1e-15);
    }

    #[test]
    fn the_references_error_is_subtracted_down_to_a_positive_floor() {
        assert_eq!(without_floor(5.0, 0.0), 5.0);
        assert_eq!(without_floor(5.0, 2.0), 3.0);
        assert_eq!(without_floor(1.0, 2.0), 0.02);
    }

    /// A 16 × 8 image of two 8 × 8 blocks, `left` on the left one and `right` on the right.
    fn halves(left: f64, right: f64) -> Vec<f64> {
        (0..128)
            .map(|i| if i % 16 < 8 { left } else { right })
            .collect()
    }

    /// The reference of the regional tests (R = 1, no error of its own) and its variance.
    fn flat() -> (Vec<f64>, Vec<f64>) {
        (vec![1.0; 128], vec![0.0; 128])
    }

    /// The images of a variant with per-pass variance `v` over K = 4 passes and no bias: the
    /// mean's squared error is exactly V/K.
    fn unbiased(v: &[f64]) -> Images {
        (
            v.to_vec(),
            v.iter().map(|v| 1.0 + (v / 4.0).sqrt()).collect(),
        )
    }

    /// A variant's (V, mean) per pixel.
    type Images = (Vec<f64>, Vec<f64>);

    fn images(im: &Images) -> ModeImages<'_> {
        ModeImages {
            variance: &im.0,
            mean: &im.1,
            passes: 4,
        }
    }

    /// [`regional_choice`] of 16 × 8 images in 8 × 8 blocks.
    fn choice(
        modes: &[&Images],
        halves: Option<[&[&Images]; 2]>,
        seconds: &[f64],
        time: Option<f64>,
    ) -> Option<RegionalChoice> {
        let (reference, ref_var) = flat();
        let modes: Vec<ModeImages<'_>> = modes.iter().map(|m| images(m)).collect();
        let halves: [Vec<ModeImages<'_>>; 2] = match halves {
            Some(h) => h.map(|h| h.iter().map(|m| images(m)).collect()),
            None => [Vec::new(), Vec::new()],
        };
        regional_choice(
            &modes,
            [&halves[0], &halves[1]],
            seconds,
            &reference,
            &ref_var,
            (16, 8),
            time,
        )
    }

    #[test]
    fn regional_choice_of_variants_better_in_different_halves() {
        let (a, b) = (unbiased(&halves(1.0, 4.0)), unbiased(&halves(4.0, 1.0)));
        let c = choice(&[&a, &b], None, &[1.0, 1.0], None).unwrap();
        // Either alone: relV ∝ (1 + 4)/2; each half its better variant: ∝ 1.
        assert!((c.gain - 2.5).abs() < 1e-12, "{c:?}");
        assert_eq!(c.shares, vec![0.5, 0.5]);
        assert_eq!(c.cross_validated, None);
    }

    #[test]
    fn regional_choice_weighs_relv_against_the_mix_s_time() {
        let a = unbiased(&halves(1.0, 1.0));
        // One variant better everywhere at the same cost: nothing to gain.
        let b = unbiased(&halves(2.0, 3.0));
        let c = choice(&[&a, &b], None, &[1.0, 1.0], None).unwrap();
        assert_eq!(
            (c.gain, c.best_single, c.shares.clone()),
            (1.0, 0, vec![1.0, 0.0])
        );
        // Half the variance everywhere for twice the time: any mix is worse than either
        // alone ((1 − f/2)(1 + f) ≥ 1), although per block relV·t ties.
        let half = unbiased(&halves(0.5, 0.5));
        let c = choice(&[&a, &half], None, &[1.0, 2.0], None).unwrap();
        assert!((c.gain - 1.0).abs() < 1e-12, "{c:?}");
        // A quarter of the variance on the left for twice the time: the left block to it
        // gives relV ∝ 0.625 at 1.5 s, against 1 at 1 s for the cheap variant alone.
        let left = unbiased(&halves(0.25, 1.0));
        let c = choice(&[&a, &left], None, &[1.0, 2.0], None).unwrap();
        assert!((c.gain - 16.0 / 15.0).abs() < 1e-12, "{c:?}");
        assert_eq!((c.best_single, c.shares.clone()), (0, vec![0.5, 0.5]));
    }

    #[test]
    fn regional_choice_cross_validated_sees_through_noise() {
        // In the even passes variant 0 looks better on the left, in the odd ones on the
        // right, and over all passes the two are alike: a choice made on one half loses on
        // the other (relV ∝ 2 against 1.5 for either variant alone).
        let (a0, b0) = (unbiased(&halves(1.0, 2.0)), unbiased(&halves(2.0, 1.0)));
        let all = unbiased(&halves(1.5, 1.5));
        let c = choice(
            &[&all, &all],
            Some([&[&a0, &b0], &[&b0, &a0]]),
            &[1.0, 1.0],
            None,
        )
        .unwrap();
        assert_eq!(c.gain, 1.0);
        assert!((c.cross_validated.unwrap() - 0.75).abs() < 1e-12, "{c:?}");
        // Where the halves agree, the choice keeps its gain.
        let (a, b) = (unbiased(&halves(1.0, 4.0)), unbiased(&halves(4.0, 1.0)));
        let c = choice(&[&a, &b], Some([&[&a, &b], &[&a, &b]]), &[1.0, 1.0], None).unwrap();
        assert!((c.cross_validated.unwrap() - 2.5).abs() < 1e-12, "{c:?}");
    }

    #[test]
    fn regional_choice_at_a_time_counts_the_bias() {
        // The same variance, each variant biased by 1 (relative, squared) on one side: in
        // relV nothing to choose; in relMSE after 1 s (one pass of 1 s) either alone has
        // 0.5 + 1, each side its unbiased variant 1.
        let biased = |left: f64, right: f64| {
            let b2 = halves(left, right);
            (
                halves(1.0, 1.0),
                b2.iter()
                    .map(|b| 1.0 + (0.25 + b).sqrt())
                    .collect::<Vec<_>>(),
            )
        };
        let (a, b) = (biased(1.0, 0.0), biased(0.0, 1.0));
        let c = choice(&[&a, &b], None, &[1.0, 1.0], None).unwrap();
        assert_eq!(c.gain, 1.0);
        let c = choice(&[&a, &b], None, &[1.0, 1.0], Some(1.0)).unwrap();
        assert!((c.gain - 1.5).abs() < 1e-12, "{c:?}");
        assert_eq!(c.shares, vec![0.5, 0.5]);
        // After 10 s the variance is a tenth: 0.5 + 0.1 against 0.1.
        let c = choice(&[&a, &b], None, &[1.0, 1.0], Some(10.0)).unwrap();
        assert!((c.gain - 6.0).abs() < 1e-9, "{c:?}");
    }

    #[test]
    fn regional_choice_needs_two_variants_with_variances() {
        let a = unbiased(&halves(1.0, 1.0));
        assert!(choice(&[&a], None, &[1.0], None).is_none());
        let nan = unbiased(&halves(f64::NAN, 1.0));
        assert!(choice(&[&a, &nan], None, &[1.0, 1.0], None).is_none());
        assert!(choice(&[&a, &a], None, &[1.0, 0.0], None).is_none());
        assert!(choice(&[&a, &a], None, &[1.0, 1.0], Some(0.0)).is_none());
    }

    #[test]
    fn efficiency_is_inverse_of_variance_times_time() {
        assert!((efficiency(0.5, 4.0) - 0.5).abs() < 1e-12);
        // Half the variance at twice the time: equally efficient.
        assert_eq!(efficiency(1.0, 2.0), efficiency(0.5, 4.0));
    }

    #[test]
    fn equal_time_and_rmse_at_it() {
        let run = |name: &str, pts: &[(f64, f64)]| ModeRun {
            name: name.into(),
            stages: vec![("cache".into(), 0.5)],
            points: pts
                .iter()
                .enumerate()
                .map(|(i, (t, e))| PassPoint {
                    pass: i as u32 + 1,
                    time: *t,
                    wall_s: *t,
                    cpu_s: f64::NAN,
                    mean_rel_sqrt_v: f64::NAN,
                    rmse: *e,
                    rel_rmse: *e,
                    rel_mse: e * e,
                    mean_sqrt_v: f64::NAN,
                })
                .collect(),
            mean_v: 1.0,
            rel_v: 1.0,
            variance: Vec::new(),
            half_variances: [Vec::new(), Vec::new()],
            mean: Vec::new(),
            half_means: [Vec::new(), Vec::new()],
            dropped: 0,
        };
        let runs = [
            run("a", &[(1.0, 0.4), (4.0, 0.2)]),
            run("b", &[(2.0, 0.1), (3.0, 0.08)]),
        ];
        assert_eq!(equal_time(&runs), 3.0);
        let a = rel_rmse_at(&runs[0], 3.0).expect("inside");
        assert!((a - 0.4 * (3.0f64).powf(-0.5)).abs() < 1e-12);
        let b = rel_rmse_at(&runs[1], 3.0).expect("at its last point");
        assert!((b - 0.08).abs() < 1e-12);
        assert!((runs[0].seconds_per_pass() - 2.0).abs() < 1e-12);
        assert_eq!(runs[0].prep_seconds(), 0.5);
        let m = rel_mse_at(&runs[1], 3.0).expect("at its last point");
        assert!((m - 0.0064).abs() < 1e-12);
        let text = csv(&runs);
        assert!(text.starts_with("mode,pass,wall_time_s,rmse,rel_rmse,mean_sqrt_v,"));
        assert_eq!(text.lines().count(), 5);
    }
}
