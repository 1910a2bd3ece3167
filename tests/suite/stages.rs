//! What a render prepares depends on the mode and the scene (method.md §7): no cache unless
//! a mode uses it, one angular bin where all surfaces are Lambert, A/B only for `optimal`.

use bdpm_integrator::Renderer;
use bdpm_suite::{load, with_mode};

fn stage_names(scene: &str, mode: &str) -> Vec<(String, String)> {
    let (scene, settings) = load(scene, 16, 16);
    let s = with_mode(&settings, mode, 1, 1, 20_000);
    let r = Renderer::new(&scene, &s).unwrap();
    r.stages()
        .iter()
        .map(|st| (st.stage.name().to_string(), st.detail.clone()))
        .collect()
}

#[test]
fn modes_prepare_only_what_they_need() {
    for mode in [
        "path",
        "light",
        "bdd0",
        "bdd1",
        "threshold",
        "balance",
        "power",
        "camis",
    ] {
        assert!(
            stage_names("preprint/cornell-lambert.toml", mode).is_empty(),
            "{mode} prepared something"
        );
    }
    // The model-based weights use each pixel's N_eff (method.md §12): footprints, no cache.
    let direct = stage_names("preprint/cornell-lambert.toml", "algebraic-direct");
    assert_eq!(
        direct.iter().map(|s| s.0.as_str()).collect::<Vec<_>>(),
        ["pixel footprints"]
    );
    let algebraic = stage_names("preprint/cornell-lambert.toml", "algebraic");
    assert_eq!(
        algebraic.iter().map(|s| s.0.as_str()).collect::<Vec<_>>(),
        ["radiance cache", "pixel footprints"]
    );
    for mode in ["optimal", "optimal-split", "optimal-path"] {
        let stages = stage_names("preprint/cornell-lambert.toml", mode);
        assert_eq!(
            stages.iter().map(|s| s.0.as_str()).collect::<Vec<_>>(),
            ["radiance cache", "pixel table"],
            "{mode}"
        );
        assert!(stages[1].1.contains("footprint noise model"), "{stages:?}");
    }
    // The data-driven correction of `balance` learns its factors from a pilot, and needs
    // nothing else.
    let corrected = stage_names("preprint/cornell-lambert.toml", "corrected-balance");
    assert_eq!(
        corrected.iter().map(|s| s.0.as_str()).collect::<Vec<_>>(),
        ["balance correction"]
    );
}

/// `corrected-balance`'s factors are candidates or blends of them, and the pilot finds pixels
/// where `balance` is not the best candidate (else the mode would be `balance` under a name).
#[test]
fn the_balance_correction_learns_factors_in_the_candidates_range() {
    let (scene, settings) = load("cornell-lambert.toml", 32, 32);
    let s = with_mode(&settings, "corrected-balance", 1, 8, 100_000);
    let r = Renderer::new(&scene, &s).unwrap();
    let factors = r.correction().expect("the mode learns factors").factors();
    assert_eq!(factors.len(), 32 * 32);
    let candidates = bdpm_integrator::correction::CANDIDATES;
    let (lo, hi) = (candidates[0], candidates[candidates.len() - 1]);
    assert!(
        factors
            .iter()
            .all(|&c| (lo as f32..=hi as f32).contains(&c)),
        "{factors:?}"
    );
    assert!(
        factors.iter().any(|&c| (c - 1.0).abs() > 0.01),
        "{factors:?}"
    );
    // The pilot has its own streams: another seed learns other factors.
    let mut s2 = s.clone();
    s2.seed += 1;
    let other = Renderer::new(&scene, &s2).unwrap();
    assert_ne!(other.correction().unwrap().factors(), factors);
}

/// Without jitter every sample of a pixel shares x₀ (ρ = 1), and under the pinhole model the
/// weights use N_B: either way no footprints are computed.
#[test]
fn centred_samples_and_the_pinhole_model_need_no_footprints() {
    let (scene, settings) = load("preprint/cornell-lambert.toml", 16, 16);
    for (jitter, model) in [
        (false, bdpm_integrator::NoiseModel::Footprint),
        (true, bdpm_integrator::NoiseModel::Pinhole),
    ] {
        let mut s = with_mode(&settings, "algebraic-direct", 1, 1, 20_000);
        s.pixel_jitter = jitter;
        s.noise_model = model;
        let r = Renderer::new(&scene, &s).unwrap();
        assert!(r.stages().is_empty(), "{:?}", r.stages());
        let mut s = with_mode(&settings, "optimal", 1, 1, 20_000);
        s.pixel_jitter = jitter;
        s.noise_model = model;
        let r = Renderer::new(&scene, &s).unwrap();
        assert!(r.stages()[1].detail.contains("pinhole"), "{:?}", r.stages());
    }
}

#[test]
fn lambert_scenes_get_one_bin_and_glossy_scenes_get_k_bins() {
    let lambert = stage_names("preprint/cornell-lambert.toml", "optimal");
    assert!(
        lambert[0].1.contains(" 1 bin(s) per side") && lambert[0].1.contains("derived"),
        "{:?}",
        lambert[0]
    );
    let glossy = stage_names("preprint/cornell-glossy.toml", "optimal");
    assert!(
        glossy[0].1.contains(" 100 bin(s) per side") && glossy[0].1.contains("b stored"),
        "{:?}",
        glossy[0]
    );
}

/// `bdd0` traces no x₁ and `bdd1` gathers no photons at x₀ (their technique layers stay zero),
/// while a mix uses both; and the weighted layers sum to the image.
#[test]
fn pure_strategies_skip_the_other_technique() {
    let (scene, settings) = load("preprint/cornell-lambert.toml", 16, 16);
    let layers = |mode: &str| {
        let s = with_mode(&settings, mode, 1, 4, 50_000);
        let r = Renderer::new(&scene, &s)
            .unwrap()
            .with_technique_layers(true);
        let out = r.render_pass(0, &|_| {});
        let t = out.techniques.unwrap();
        for (e, t) in out.estimates.iter().zip(&t) {
            assert!(
                (t.total() - *e).abs().max_element() <= 1e-9 + 1e-6 * e.abs().max_element(),
                "{mode}: layers do not sum to the image"
            );
        }
        let sum = |f: fn(&bdpm_integrator::Techniques) -> f64| t.iter().map(f).sum::<f64>();
        (sum(|t| t.x0_raw.x), sum(|t| t.x1_raw.x))
    };
    let (x0, x1) = layers("bdd0");
    assert!(x0 > 0.0 && x1 == 0.0, "bdd0: {x0} {x1}");
    let (x0, x1) = layers("bdd1");
    assert!(x0 == 0.0 && x1 > 0.0, "bdd1: {x0} {x1}");
    let (x0, x1) = layers("threshold");
    assert!(x0 > 0.0 && x1 > 0.0, "threshold: {x0} {x1}");
}
