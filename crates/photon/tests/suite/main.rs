//! Integration tests of bdpm-photon: the photon map and photon statistics.
//!
//! One test binary per package (the files are its modules), so CI links one executable
//! per package instead of one per file.

mod common;
mod map;
mod statistics;
