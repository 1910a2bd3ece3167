//! The lab of `bdpm`: the commands that measure the renderer rather than render with it
//! (`study`, `bench`, `compare`, `predict`). Their files, plots, maps and statistics come from
//! `bdpm-output`, as the renderer's do.
//!
//! Why a library linked into the one `bdpm` binary behind its default-on cargo feature `lab`,
//! and not a second binary: the README, the docs, `scripts/bit-check.sh`, the Slurm scripts
//! and the CLI tests all call `bdpm compare`, `bdpm study`, `bdpm bench` and `bdpm predict`,
//! and keep working unchanged; `cargo build -p bdpm --no-default-features` builds the
//! renderer alone (`render`, `merge`, `weights`), without this crate.
use std::path::Path;
use std::process::ExitCode;

use bdpm_integrator::Mode;
use bdpm_output::cli::CliResult;
use bdpm_output::files::write_atomic;
use clap::Subcommand;

mod bench;
mod compare;
mod predict;
mod reference;
mod study;

pub use bench::BenchArgs;
pub use compare::CompareArgs;
pub use predict::PredictArgs;
pub use study::StudyArgs;

/// The lab's subcommands, flattened into `bdpm`'s own.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Evaluate the noise model of method.md §12 per pixel for a mode's weights and compare it
    /// with the per-pass variance V of a render made with the same settings (--measured):
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
}

/// Runs a lab subcommand; the error is one line for the user.
pub fn run(command: Command) -> Result<ExitCode, String> {
    let success = |()| ExitCode::SUCCESS;
    match command {
        Command::Predict(args) => predict::run(args).map(success),
        Command::Study(args) => study::run(args).map(success),
        Command::Bench(args) => bench::run(args).map(success),
        Command::Compare(args) => compare::run(args),
    }
}

/// The modes of `--modes` (names as given, trimmed) and what they parse to; every BDPM weight
/// mode when the list is empty. Study and bench compare the same default set.
fn parse_modes(list: &[String]) -> CliResult<(Vec<String>, Vec<Mode>)> {
    let names: Vec<String> = if list.is_empty() {
        bdpm_mis::Heuristic::ALL_NAMES
            .iter()
            .map(|s| s.to_string())
            .collect()
    } else {
        list.iter().map(|s| s.trim().to_string()).collect()
    };
    let modes = names
        .iter()
        .map(|n| {
            Mode::parse(n).ok_or_else(|| {
                format!(
                    "--modes: unknown mode '{n}'; expected some of {}",
                    Mode::names().join(", ")
                )
            })
        })
        .collect::<CliResult<_>>()?;
    Ok((names, modes))
}

/// Writes a markdown report to `path` and prints it, then where it went.
fn publish(path: &Path, md: &str) -> CliResult<()> {
    write_atomic(path, md.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
    bdpm_output::say!("{md}");
    bdpm_output::say!("wrote {}", path.display());
    Ok(())
}
