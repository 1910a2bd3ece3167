//! Mitsuba's own Cornell box (issue 47): the XML Mitsuba 3.9.1 writes for
//! `mitsuba.cornell_box()` (crates/load/tests/data/mitsuba/cornell-box-3.9.1.xml), imported
//! with its area light, renders as scenes/cornell-box.toml, which describes the same box in
//! bdpm's format (written from the same function by scripts/mitsuba-cornell-box.py). The two
//! are independent renders (different seeds) of two descriptions of one scene: their images
//! must agree within a few standard errors in the unidirectional reference and in a BDPM mode.

use bdpm_load::load_scene;
use bdpm_suite::{films_agree, load, render, with_mode};

/// The imported box and the TOML box at 32 × 32, rendered alike in `path` and
/// `optimal-path` with seeds 1 and 2: ≥ 98 % of pixel channels within 4σ and the image means
/// within 4 standard errors, each mean's standard error under 1 % (so a missing light, a
/// light emitting on the wrong side or a wrong radiance fails by many σ).
#[test]
fn mitsubas_cornell_box_renders_as_the_toml_box() {
    let xml = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("crates/load/tests/data/mitsuba/cornell-box-3.9.1.xml");
    let mut imported = load_scene(&xml).unwrap_or_else(|e| panic!("{e}")).scene;
    imported.set_resolution(32, 32).expect("resolution");
    let (toml, settings) = load("cornell-box.toml", 32, 32);
    let mut failures = Vec::new();
    for (mode, passes, photons) in [("path", 64, 1), ("optimal-path", 16, 20_000)] {
        let a = with_mode(&settings, mode, passes, 4, photons);
        let b = bdpm_integrator::RenderSettings {
            seed: 2,
            ..a.clone()
        };
        let (within, diff, se) = films_agree(&render(&imported, &b), &render(&toml, &a), 4.0);
        eprintln!("{mode:>13}: within 4σ {within:.4}, image means {diff:+.5} ± {se:.5}");
        if within < 0.98 || diff.abs() > 4.0 * se || se > 0.01 {
            failures.push((mode, within, diff, se));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}
