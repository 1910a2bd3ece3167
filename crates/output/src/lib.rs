//! What the `bdpm` commands write and share, in one place for the renderer's CLI and the lab
//! (study, bench, compare, predict): image IO (EXR, PNG, atomic writes, output locks and
//! output sets), the preview and the false-colour maps, the plots, the JSON run report, the
//! accumulation file of partial renders, the per-pixel statistics with the one luminance,
//! and the command-line settings every command takes. Everything drawn (legends, colour bars,
//! plots) is drawn with plotters, with the DejaVu Sans font embedded in the binary.
//!
//! Errors are one line of text for the user (`Result<_, String>`): this crate is the IO
//! boundary, and its callers only print them.

pub mod accum;
pub mod cli;
pub mod colormap;
pub mod exr;
pub mod files;
pub mod memory;
pub mod plot;
pub mod preview;
pub mod report;
pub mod stats;
