//! `bdpm`: the command-line driver. It parses arguments, loads the scene, runs the integrator
//! and writes images and reports (through `bdpm-output`). All rendering logic lives in the
//! library crates; this binary is the IO boundary. The lab's subcommands (study, bench,
//! compare, predict) come from `bdpm-lab` with the default feature `lab`.

mod export;
mod render;
mod session;
mod signal;
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
    /// rendered and exits with code 130 (during the preparation it stops at once and writes
    /// nothing); a second interrupt quits without writing.
    Render(render::RenderArgs),
    /// Merge partial renders (their OUT.accum.exr files, from `render --first-pass`) into the
    /// outputs of one render of all their passes, bit for bit: same scene, settings and seed
    /// required, pass sets must not overlap, argument order does not matter.
    Merge(render::MergeArgs),
    /// Map the weight w₀ = 1 − w₁ over every visible x₁ for a fixed x₀ (the preprint's Fig. 5);
    /// the help names the modes that have one ([`weights::about`]).
    #[command(about = weights::about())]
    Weights(weights::WeightsArgs),
    /// Write the scene for another renderer: `--to mitsuba -o DIR` writes DIR/scene.xml (Mitsuba 3),
    /// the triangles bdpm renders as DIR/meshes/*.ply, textures as DIR/textures/*.exr and the
    /// report DIR/export.json (every approximation listed, and printed as a warning).
    Export(export::ExportArgs),
    /// Every mode name, one per line, in the mode table's order: for scripts
    /// (scripts/bit-check.sh renders each), so that no script keeps a list of its own.
    #[command(hide = true)]
    Modes,
    /// The lab: study, bench, compare, predict.
    #[cfg(feature = "lab")]
    #[command(flatten)]
    Lab(bdpm_lab::Command),
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
        Command::Export(args) => export::run(args).map(success),
        Command::Modes => {
            for name in bdpm_settings::Mode::names() {
                bdpm_output::say!("{name}");
            }
            Ok(ExitCode::SUCCESS)
        }
        #[cfg(feature = "lab")]
        Command::Lab(command) => bdpm_lab::run(command),
    };
    match result {
        Ok(code) => code,
        Err(message) => {
            bdpm_output::say_err!("bdpm: error: {message}");
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
    let mut lines = text.lines().skip_while(|l| !l.starts_with("error:"));
    let mut line = lines
        .next()
        .unwrap_or("error: bad arguments")
        .trim_start_matches("error:")
        .trim()
        .to_string();
    // The lines after the first until a blank one carry the rest of the message: "the
    // following required arguments were not provided:" lists them there, an invalid value
    // the accepted ones ("[possible values: true, false]"), an unknown flag a "tip: …".
    let more: Vec<&str> = lines.map(str::trim).take_while(|l| !l.is_empty()).collect();
    if line.ends_with(':') {
        line = format!("{line} {}", more.join(", "));
    } else if !more.is_empty() {
        line = format!("{line}; {}", more.join("; "));
    }
    bdpm_output::say_err!("bdpm: error: {line} (see bdpm --help)");
    ExitCode::FAILURE
}
