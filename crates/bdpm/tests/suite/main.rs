//! Command-line tests of the `bdpm` binary (render, merge, weights, and the lab's commands).
//!
//! One test binary per package (the files are its modules), so CI links one executable
//! per package instead of one per file.

mod cli;
mod export;
mod preview;
mod round4_lab;
mod round4_light;
mod round4_settings;
mod round4_textures;
mod scripts;
mod study;

/// The `bdpm` binary this package built.
fn bdpm() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_bdpm"))
}

/// The path of `name` under the repository's scenes/ folder.
fn scene(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
}

/// The smallest render that still runs every stage: 16×16 pixels, 2,000 photons a pass, one
/// camera sample per pixel.
const TINY: [&str; 6] = ["--resolution", "16x16", "--photons", "2000", "--spp", "1"];

/// `bdpm render SCENE ARGS --quiet -o OUT`, its standard output and error piped, started and
/// not waited for.
fn spawn_render(
    scene: &std::path::Path,
    args: &[&str],
    out: &std::path::Path,
) -> std::process::Child {
    use std::process::Stdio;
    bdpm()
        .arg("render")
        .arg(scene)
        .args(args)
        .args(["--quiet", "-o"])
        .arg(out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start bdpm")
}

/// A fresh directory under the system temp dir, named after `tag`, removed when dropped.
fn temp_dir(tag: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("bdpm-{tag}-"))
        .tempdir()
        .expect("create temp dir")
}
