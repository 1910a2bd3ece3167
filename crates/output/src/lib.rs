//! What the `bdpm` commands write and share, in one place for the renderer's CLI and the lab
//! (study, bench, compare, predict): files and formats (EXR, PNG, atomic writes, output
//! locks and output sets), the preview and the false-colour maps, the JSON run report, the
//! accumulation file of partial renders, the record of how a render was made that its
//! header keeps (`header`), the per-pixel statistics with the one luminance,
//! the memory gates' arithmetic, the command-line settings every command takes (and their
//! flags' names in messages), and the machine's numbers the reports record (`system`, the one
//! module that reads /proc). Scenes are read by `bdpm-load` (`cli::prepare` calls it with the
//! flags); the lab's plots are the lab's. Everything drawn (legends, colour bars) is drawn
//! with plotters, in the DejaVu Sans font embedded in the binary (`font`).
//!
//! Errors are one line of text for the user (`Result<_, String>`): this crate is the IO
//! boundary, and its callers only print them.

pub mod accum;
pub mod cli;
pub mod colormap;
pub mod exr;
pub mod files;
mod flags;
pub mod font;
pub mod header;
pub mod memory;
pub mod preview;
pub mod raster;
pub mod report;
pub mod stats;
pub mod system;

// The README (the crate's page on crates.io) as a hidden item, so that `cargo test --doc`
// compiles and runs its example; the crate documentation above stays as it is.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
