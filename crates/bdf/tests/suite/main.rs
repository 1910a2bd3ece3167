//! Integration tests of bdpm-bdf: BDF properties, proptests and sampling statistics, the
//! Fresnel terms and the delta models.
//!
//! One test binary per package (the files are its modules), so CI links one executable
//! per package instead of one per file.

mod common;
mod fresnel;
mod glass;
mod properties;
mod proptests;
mod sampling;
mod specular;
