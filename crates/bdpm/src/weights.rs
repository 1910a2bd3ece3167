//! `bdpm weights`: the weight map of the preprint's Fig. 5.
use std::path::PathBuf;

use clap::Args;

use crate::common::CliResult;

/// Arguments of this subcommand.
#[derive(Args, Debug)]
pub(crate) struct WeightsArgs {
    /// Scene file (TOML).
    scene: PathBuf,
}

/// Runs the subcommand.
pub(crate) fn run(args: WeightsArgs) -> CliResult<()> {
    Err(format!(
        "{}: this subcommand is not implemented yet",
        args.scene.display()
    ))
}
