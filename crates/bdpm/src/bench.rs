//! `bdpm bench`: throughput benchmarks.
use std::path::PathBuf;

use clap::Args;

use crate::common::CliResult;

/// Arguments of this subcommand.
#[derive(Args, Debug)]
pub(crate) struct BenchArgs {
    /// Scene file (TOML).
    scene: PathBuf,
}

/// Runs the subcommand.
pub(crate) fn run(args: BenchArgs) -> CliResult<()> {
    Err(format!(
        "{}: this subcommand is not implemented yet",
        args.scene.display()
    ))
}
