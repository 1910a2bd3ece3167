//! `bdpm`: the command-line driver. It parses arguments, loads the scene, runs the integrator
//! and writes images, reports and plots. All rendering logic lives in the library crates;
//! this binary is the IO boundary.

mod accum;
mod bench;
mod colormap;
mod common;
mod compare;
mod font;
mod output;
mod predict;
mod render;
mod report;
mod signal;
mod study;
mod weights;

use std::process::ExitCode;

use clap::error::ErrorKind;
use clap::{Parser, Subcommand};

/// Bidirectional photon mapping with optimal MIS weights.
#[derive(Parser, Debug)]
#[command(name = "bdpm", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene to OUT.exr, with OUT.png (preview), OUT-noise.png (noise map) and OUT.json
    /// (run report) beside it. An interrupt stops after the pass in flight, writes what was
    /// rendered and exits with code 130; a second interrupt quits without writing.
    Render(render::RenderArgs),
    /// Merge partial renders (their OUT.accum.exr files, from `render --first-pass`) into the
    /// outputs of one render of all their passes, bit for bit: same scene, settings and seed
    /// required, pass sets must not overlap, argument order does not matter.
    Merge(render::MergeArgs),
    /// Map the weight w₀ = 1 − w₁ over every visible x₁ for a fixed x₀ (the preprint's Fig. 5):
    /// OUT.exr (channel w0) and OUT.png (log scale 0.008–1, x₀ marked). Modes whose weights
    /// depend on x₁ alone: bdd0, bdd1, threshold, algebraic-direct, algebraic, optimal.
    Weights(weights::WeightsArgs),
    /// Evaluate the noise model of method.md §12 per pixel for a mode's weights and compare it
    /// with the per-pass variance V of a render made with the same settings (--measured):
    /// OUT.exr (predicted and measured V, ratio, terms T0, T1, T2, T_jitter), OUT.png
    /// (log2 predicted/measured) and OUT.json (correlations, ratio quantiles, term shares).
    Predict(predict::PredictArgs),
    /// Error against run time for several modes: CSV, plots and a markdown table.
    Study(study::StudyArgs),
    /// Throughput benchmarks: photons/s and camera samples/s per mode, 1 and N threads.
    Bench(bench::BenchArgs),
    /// Compare two renders: bit-identical mean radiance or not, image means, and the fraction
    /// of pixels within k combined standard errors.
    Compare(compare::CompareArgs),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage_error(e),
    };
    let success = |()| ExitCode::SUCCESS;
    let result = match cli.command {
        Command::Render(args) => render::run(args),
        Command::Merge(args) => render::merge(args),
        Command::Weights(args) => weights::run(args).map(success),
        Command::Predict(args) => predict::run(args).map(success),
        Command::Study(args) => study::run(args).map(success),
        Command::Bench(args) => bench::run(args).map(success),
        Command::Compare(args) => compare::run(args),
    };
    match result {
        Ok(code) => code,
        Err(message) => {
            eprintln!("bdpm: error: {message}");
            ExitCode::FAILURE
        }
    }
}

/// A command-line error as one line on stderr with exit code 1, like every other user error
/// (clap's own has a usage block and exits with 2); help and version print as usual.
fn usage_error(e: clap::Error) -> ExitCode {
    if matches!(
        e.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        e.exit();
    }
    let text = e.render().to_string();
    let line = text
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or("error: bad arguments")
        .trim_start_matches("error:")
        .trim();
    eprintln!("bdpm: error: {line} (see bdpm --help)");
    ExitCode::FAILURE
}
