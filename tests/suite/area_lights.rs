//! Area lights (issue 46): the emissive furnace's exact answer in every mode, and a lobe
//! furnace where every mode must agree with `path`.

use bdpm_suite::{load, render, with_mode};

/// Every mode of the mode table plus the two references.
fn all_modes() -> Vec<&'static str> {
    let mut modes = vec!["path", "light"];
    modes.extend(bdpm_mis::Heuristic::ALL_NAMES.iter().copied());
    modes
}

/// The closed sphere whose inside emits Le = 1 and reflects with Lambert albedo 0.5 has
/// radiance Le/(1 − a) = 2 everywhere: every mode's image mean within 1 % (the mean's own
/// standard error far below that, so the test can fail) and ≥ 99 % of pixels within 4 SE.
#[test]
fn every_mode_matches_the_emissive_furnace() {
    let (scene, settings) = load("emissive-furnace.toml", 16, 16);
    let exact = vec![2.0f64; 16 * 16];
    let mut failures = Vec::new();
    for mode in all_modes() {
        // `path` is cheap per pass and heavy-tailed per pixel: more passes.
        let passes = if mode == "path" { 64 } else { 16 };
        let mut s = with_mode(&settings, mode, passes, 4, 20_000);
        s.radius = Some(0.05);
        s.threshold_radius = 0.9;
        let film = render(&scene, &s);
        let a = bdpm_suite::agreement(&film, &exact, 4.0);
        eprintln!("{mode:>16}: {a:?}");
        let ok = a.mean_relative_error.abs() < 0.01 && a.within >= 0.99;
        if !ok || a.mean_relative_se > 0.003 || film.dropped() != 0 {
            failures.push((mode, a));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
