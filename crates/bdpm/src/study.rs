//! `bdpm study`: error against run time for several modes.
use std::path::PathBuf;

use clap::Args;

use crate::common::CliResult;

/// Arguments of this subcommand.
#[derive(Args, Debug)]
pub(crate) struct StudyArgs {
    /// Scene file (TOML).
    scene: PathBuf,
}

/// Runs the subcommand.
pub(crate) fn run(args: StudyArgs) -> CliResult<()> {
    Err(format!(
        "{}: this subcommand is not implemented yet",
        args.scene.display()
    ))
}
