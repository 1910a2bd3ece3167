//! Command-line tests of the `bdpm` binary (render, merge, weights, and the lab's commands).
//!
//! One test binary per package (the files are its modules), so CI links one executable
//! per package instead of one per file.

mod cli;
mod export;
mod round4_lab;
mod round4_light;
mod round4_settings;
mod round4_textures;
mod scripts;
mod study;

/// A fresh directory under the system temp dir, named after `tag`, removed when dropped.
fn temp_dir(tag: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("bdpm-{tag}-"))
        .tempdir()
        .expect("create temp dir")
}
