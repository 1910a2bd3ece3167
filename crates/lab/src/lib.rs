//! The lab of `bdpm`: the commands that measure the renderer rather than render with it
//! (`study`, `bench`, `compare`, `predict`, `figure`). Their files, plots, maps and statistics come from
//! `bdpm-output`, as the renderer's do.
//!
//! Why a library linked into the one `bdpm` binary behind its default-on cargo feature `lab`,
//! and not a second binary: the README, the docs, `scripts/bit-check.sh`, the Slurm scripts
//! and the CLI tests all call `bdpm compare`, `bdpm study`, `bdpm bench` and `bdpm predict`,
//! and keep working unchanged; `cargo build -p bdpm --no-default-features` builds the
//! renderer alone (`render`, `merge`, `weights`), without this crate.
use std::path::Path;
use std::process::ExitCode;

use bdpm_integrator::{
    MemoryEstimate, Mode, PartialSettings, RenderSettings, estimate_memory, human_bytes,
    settings::Written,
};
use bdpm_output::cli::CliResult;
use bdpm_output::files::write_atomic;
use bdpm_output::memory::{self, MemoryLimit};
use bdpm_scene::Scene;
use clap::Subcommand;

mod bench;
mod compare;
mod figure;
#[cfg(test)]
mod figure_browser_test;
mod figure_cli;
mod figure_page;
mod figure_sheet;
mod metrics;
mod plot;
mod predict;
mod reference;
mod study;

pub use bench::BenchArgs;
pub use compare::CompareArgs;
pub use figure_cli::FigureArgs;
pub use predict::PredictArgs;
pub use study::StudyArgs;

/// The lab's subcommands, flattened into `bdpm`'s own.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Evaluate the noise model of method.md §12 per pixel for a render's weights and compare
    /// it with the per-pass variance V it measured (`bdpm predict RENDER.exr`: the scene and
    /// settings come from its header):
    /// OUT.exr (predicted and measured V, ratio, terms T0, T1, T2, T_jitter), OUT.png
    /// (log2 predicted/measured) and OUT.json (correlations, ratio quantiles, term shares).
    Predict(PredictArgs),
    /// Error against run time for several modes: CSV, plots and a markdown table.
    Study(StudyArgs),
    /// Throughput benchmarks: photons/s and camera samples/s per mode, 1 and N threads.
    Bench(BenchArgs),
    /// Compare two renders: bit-identical mean radiance or not, image means, and the fraction
    /// of pixels within k combined standard errors.
    Compare(CompareArgs),
    /// A comparison figure: the images beside the reference at one exposure, crops, maps of
    /// relative error and of FLIP, and rel. RMSE, relMSE, FLIP mean and time under each, as
    /// DIR/figure.png, a self-contained DIR/figure.html flip-book and DIR/figure.json.
    Figure(FigureArgs),
}

/// Runs a lab subcommand; the error is one line for the user.
pub fn run(command: Command) -> Result<ExitCode, String> {
    let success = |()| ExitCode::SUCCESS;
    match command {
        Command::Predict(args) => predict::run(args).map(success),
        Command::Study(args) => study::run(args).map(success),
        Command::Bench(args) => bench::run(args).map(success),
        Command::Compare(args) => compare::run(args),
        Command::Figure(args) => figure_cli::run(args).map(success),
    }
}

/// The keys a `--modes` entry may set ([`Variant`]), each converted by the scene file's
/// conversion of its `[render]` value ([`PartialSettings::set`]): the one list that the
/// parser, its messages and the `--modes` help text ([`modes_help`]) read.
const KEYS: [&str; 10] = [
    "sampler",
    "light_tracing",
    "adaptive_radius",
    "radius",
    "spp",
    "photons",
    "cache_photons",
    "cache_bins",
    "pixel_table_rays",
    "direct_boost",
];

/// The help text of a `--modes` flag that `verb`s the entries (`compare`, `time`), with
/// every key an entry may set.
pub(crate) fn modes_help(verb: &str) -> String {
    format!(
        "Modes to {verb}, comma-separated (default: every BDPM mode); each may carry settings \
         of its own, MODE[:KEY=VALUE]… with KEY one of {} (e.g. \
         `optimal-path:radius=0.2px:cache_photons=500000`)",
        KEYS.join(", ")
    )
}

/// One entry of `--modes`: a mode, and settings of its own on top of the shared ones
/// (`MODE[:KEY=VALUE]…` with KEY one of [`KEYS`]: `sampler`, `radius` (metres, or pixel
/// footprints as `1.2px`), `spp`, `photons`, the weights' preparation `cache_photons`,
/// `cache_bins`, `pixel_table_rays`, and `direct_boost`, `light_tracing`,
/// `adaptive_radius`), so that configurations are compared side by side in one run, e.g.
/// `balance:sampler=independent,balance,optimal-path:radius=0.2px:cache_photons=500000`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Variant {
    /// The entry as given (trimmed): its name in tables, plots and files.
    pub(crate) name: String,
    /// The mode and the entry's own settings, in the shape of a scene file's `[render]`.
    settings: PartialSettings,
}

impl Variant {
    /// Parses one entry; the error names the entry and what is wrong with it. Names and
    /// radii are checked here, so that a typo stops the command before any work; the ranges
    /// are checked against the shared settings ([`Variant::settings`]).
    fn parse(entry: &str) -> CliResult<Variant> {
        let name = entry.trim().to_string();
        let mut parts = name.split(':');
        let mode_name = parts.next().unwrap_or_default();
        mode_name
            .parse::<Mode>()
            .map_err(|e| format!("--modes: '{name}': {e}"))?;
        let mut settings = PartialSettings {
            mode: Some(mode_name.to_string()),
            ..PartialSettings::default()
        };
        for part in parts {
            let bad = |why: &str| format!("--modes: '{part}' in '{name}': {why}");
            let (key, value) = part
                .split_once('=')
                .ok_or_else(|| bad(&format!("expected KEY=VALUE ({})", KEYS.join(", "))))?;
            if !KEYS.contains(&key) {
                return Err(bad(&format!(
                    "unknown key; expected one of {}",
                    KEYS.join(", ")
                )));
            }
            // The scene file's conversion of a `[render]` value, with its messages.
            settings
                .set(key, &Written::from_text(value))
                .map_err(|e| bad(&e.message))?;
        }
        Ok(Variant { name, settings })
    }

    /// The shared settings with this entry's mode and its own settings, validated.
    pub(crate) fn settings(&self, shared: &RenderSettings) -> CliResult<RenderSettings> {
        let mut s = shared.clone();
        // Combinations are checked on the entry's final settings (`apply` leaves them).
        self.settings
            .apply(&mut s)
            .and_then(|()| s.validate())
            .map_err(|e| format!("--modes: '{}': {}: {e}", self.name, e.setting()))?;
        Ok(s)
    }
}

/// The entries of `--modes` ([`Variant`]); every BDPM weight mode when the list is empty.
/// Study and bench compare the same default set.
fn parse_modes(list: &[String]) -> CliResult<Vec<Variant>> {
    if list.is_empty() {
        return bdpm_mis::Heuristic::ALL_NAMES
            .iter()
            .map(|n| Variant::parse(n))
            .collect();
    }
    let variants: Vec<Variant> = list
        .iter()
        .map(|e| Variant::parse(e))
        .collect::<CliResult<_>>()?;
    for (i, v) in variants.iter().enumerate() {
        if variants[..i].iter().any(|w| w.name == v.name) {
            return Err(format!("--modes: '{}' is given twice", v.name));
        }
    }
    Ok(variants)
}

/// Each entry's render settings (the shared `base` with the entry's own) and the memory its
/// renderer is estimated to need ([`estimate_memory`]), in the order given.
fn entry_estimates(
    scene: &Scene,
    variants: &[Variant],
    base: &RenderSettings,
    pool: &rayon::ThreadPool,
) -> CliResult<Vec<(RenderSettings, MemoryEstimate)>> {
    variants
        .iter()
        .map(|v| {
            let s = v.settings(base)?;
            let e = pool.install(|| estimate_memory(scene, &s, false));
            Ok((s, e))
        })
        .collect()
}

/// Refuses a command over `variants` whose estimated peak `total` exceeds `limit`, in one line
/// that names the scene, the estimate and its parts, the limit, and the entry that needs the
/// most alone (`entries`: each variant's own estimate) with the setting to lower.
fn refuse_above_limit(
    scene: &Path,
    command: &str,
    total: &MemoryEstimate,
    variants: &[Variant],
    entries: &[MemoryEstimate],
    limit: MemoryLimit,
) -> CliResult<()> {
    if limit.exceeded_by(total.total()).is_none() {
        return Ok(());
    }
    let largest = variants
        .iter()
        .zip(entries)
        .max_by_key(|(_, e)| e.total())
        .map(|(v, e)| {
            let part = e.scalable_largest();
            format!(
                "; its largest entry, --modes '{}', needs about {} alone, most of it {}: lower {} \
                 (for the entry or for all)",
                v.name,
                human_bytes(e.total()),
                part.name,
                memory::lower(part)
            )
        })
        .unwrap_or_default();
    Err(format!(
        "{}: the {command} needs about {} ({}), more than {}{largest}, or raise --max-memory",
        scene.display(),
        human_bytes(total.total()),
        memory::parts(total),
        limit.describe()
    ))
}

/// Writes a markdown report to `path` and prints it, then where it went.
fn publish(path: &Path, md: &str) -> CliResult<()> {
    write_atomic(path, md.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
    bdpm_output::say!("{md}");
    bdpm_output::say!("wrote {}", path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variants_parse_and_apply_their_settings() {
        let v = parse_modes(&["balance:sampler=independent:radius=0.01:spp=1:photons=5000".into()])
            .unwrap();
        let s = v[0].settings(&RenderSettings::default()).unwrap();
        assert_eq!(s.mode, Mode::parse("balance").unwrap());
        assert_eq!(s.sampler, bdpm_integrator::Sampler::Independent);
        assert_eq!((s.radius, s.spp, s.photons), (Some(0.01), 1, 5000));
        let px = parse_modes(&["balance:radius=1.5px".into()]).unwrap();
        let s = px[0].settings(&RenderSettings::default()).unwrap();
        assert_eq!((s.radius, s.radius_px), (None, Some(1.5)));
        let prep = parse_modes(&[
            "optimal-path:cache_photons=500000:cache_bins=36:pixel_table_rays=8".into(),
        ])
        .unwrap();
        let s = prep[0].settings(&RenderSettings::default()).unwrap();
        assert_eq!(
            (s.cache_photons, s.cache_bins, s.pixel_table_rays),
            (Some(500_000), 36, Some(8))
        );
        let plain = parse_modes(&["optimal-path".into()]).unwrap();
        assert_eq!(
            plain[0].settings(&RenderSettings::default()).unwrap().spp,
            RenderSettings::default().spp
        );
        for bad in [
            "nope",
            "balance:sampler=sobol",
            "balance:radius",
            "balance:colour=red",
            "balance:spp=-1",
            "optimal-path:cache_photons=many",
            "optimal-path:pixel_table_rays=-2",
            "optimal-path:cache_bins=1.5",
        ] {
            assert!(parse_modes(&[bad.into()]).is_err(), "{bad}");
        }
        // A count's range is checked as the entry is read, with the bound.
        let e = parse_modes(&["balance:spp=0".into()]).unwrap_err();
        assert!(e.ends_with("0 is outside [1, 4294967295]"), "{e}");
        // A combination is checked on the entry's final settings.
        let unjittered = RenderSettings {
            pixel_jitter: false,
            ..RenderSettings::default()
        };
        let lt = parse_modes(&["balance:light_tracing=true".into()]).unwrap();
        assert!(lt[0].settings(&unjittered).is_err());
        assert!(parse_modes(&["balance".into(), "balance".into()]).is_err());
        assert_eq!(
            parse_modes(&[]).unwrap().len(),
            bdpm_mis::Heuristic::ALL_NAMES.len()
        );
    }
}
