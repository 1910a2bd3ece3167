//! `cornell-lambert` at a small resolution: every mode against an independent reference.
//!
//! The reference is the `light` mode (exact direct light plus light tracing connected to the
//! camera). `path` converges slowly here because the ceiling spot above the light is a small,
//! very bright secondary source (method.md §10); light paths find it every time. `path` is
//! itself one of the modes compared with the reference.

use std::sync::OnceLock;

use bdpm_integrator::RenderSettings;
use bdpm_integrator::{Film, Renderer};
use bdpm_scene::Scene;
use bdpm_suite::{block_map, films_agree, load, lum, render, render_with, with_mode};

const RES: u32 = 16;
/// Merge radius for the tests, m: large enough for ~1 photon per gather at 10⁵ photons per
/// pass. Its kernel bias is confined to a 1 cm band along edges (a few % of an edge pixel at
/// this resolution, far below the per-pixel noise) and shows in no test.
const RADIUS: f32 = 0.01;

fn scene() -> &'static (Scene, RenderSettings) {
    static SCENE: OnceLock<(Scene, RenderSettings)> = OnceLock::new();
    SCENE.get_or_init(|| load("preprint/cornell-lambert.toml", RES, RES))
}

fn glossy() -> &'static (Scene, RenderSettings) {
    static SCENE: OnceLock<(Scene, RenderSettings)> = OnceLock::new();
    SCENE.get_or_init(|| load("preprint/cornell-glossy.toml", RES, RES))
}

fn reference() -> &'static Film {
    static REF: OnceLock<Film> = OnceLock::new();
    REF.get_or_init(|| {
        let (scene, settings) = scene();
        render(scene, &with_mode(settings, "light", 32, 256, 1_000_000))
    })
}

/// The glossy scene's reference: `path`, which at this resolution converges to ±0.13% in the
/// image mean and agrees with the `light` mode (99.6% of pixels within 4σ, image mean −0.05%).
fn glossy_reference() -> &'static Film {
    static REF: OnceLock<Film> = OnceLock::new();
    REF.get_or_init(|| {
        let (scene, settings) = glossy();
        render(scene, &with_mode(settings, "path", 64, 2048, 1))
    })
}

fn settings_for(mode: &str) -> RenderSettings {
    let (_, settings) = scene();
    let (passes, spp, photons) = match mode {
        // The pure BDD=1 strategy and `path` meet the ceiling spot only through x₁: they need
        // many camera samples before their per-pass variance is well estimated.
        "path" => (32, 2048, 1),
        "bdd1" => (48, 1024, 200_000),
        _ => (32, 128, 200_000),
    };
    let mut s = with_mode(settings, mode, passes, spp, photons);
    s.radius = Some(RADIUS);
    s
}

fn check(mode: &str, film: &Film) -> Result<(), String> {
    check_against(mode, film, reference())
}

fn check_against(mode: &str, film: &Film, reference: &Film) -> Result<(), String> {
    let (within, mean_diff, mean_se) = films_agree(film, reference, 4.0);
    eprintln!(
        "{mode:>16}: within 4σ {within:.4}, image mean {mean_diff:+.4} (naive SE {mean_se:.4})"
    );
    if within >= 0.99 && mean_diff.abs() < 0.01 {
        Ok(())
    } else {
        Err(format!("{mode}: within {within:.4}, mean {mean_diff:+.4}"))
    }
}

#[test]
fn every_mode_agrees_with_the_light_reference() {
    let (scene, _) = scene();
    let mut failures = Vec::new();
    for mode in std::iter::once("path").chain(bdpm_mis::Heuristic::ALL_NAMES.iter().copied()) {
        let film = render(scene, &settings_for(mode));
        if let Err(e) = check(mode, &film) {
            failures.push(e);
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// method.md §2: weighting each photon at x₀ by 1 − w₁(x₀, y_p) is unbiased for any weight,
/// here the strongly varying threshold rule with an R that puts many x₁ inside; weighting the
/// photon sum with the camera's own x₁ (the preprint's eq. 2–3 read literally) is biased, and
/// the same comparison must detect it.
#[test]
fn per_photon_weighting_is_unbiased_and_camera_x1_weighting_is_not() {
    let (scene, _) = scene();
    let mut s = settings_for("threshold");
    s.threshold_radius = 1.2;
    let renderer = Renderer::new(scene, &s).unwrap();
    let good = render_with(&renderer);
    check("threshold R=1.2", &good).unwrap();

    let biased = Renderer::new(scene, &s)
        .unwrap()
        .with_camera_x1_weighting(true);
    let bad = render_with(&biased);
    let (within, mean_diff, mean_se) = films_agree(&bad, reference(), 4.0);
    eprintln!("camera-x1 variant: within {within:.4}, image mean {mean_diff:+.4} ± {mean_se:.4}");
    // The same per-pixel criterion that the unbiased estimator passes (≥ 99% within 4σ) must
    // fail clearly.
    assert!(
        within < 0.9,
        "the biased variant was not detected: within {within:.4}, mean {mean_diff:+.4}"
    );
}

/// `cornell-glossy`: `algebraic`, `optimal` and `optimal-path` against the `path` reference (the optimal-weights
/// issue's check). Two kinds of path here have heavy-tailed estimates: a glossy x₀ reflecting
/// the light in a glossy x₁ (found by BDD=1 only when the sampled x₁ direction meets the light's
/// lobe) and glossy merges with few photons in the lobe. A render whose passes missed the rare
/// large values reads low with a small standard error, so the per-pixel 4σ criterion needs
/// enough camera samples and photons per gather: 128 samples per pixel per pass and r = 1.5 cm
/// (its kernel bias is a few 0.1% in the image mean; seeds 1–4 gave −0.7% … −0.3%, SE 0.3%).
/// `camis` is here too because its weight walks the light path through glossy vertices, where
/// a mismatch between its two evaluations would show.
#[test]
fn glossy_modes_agree_with_the_path_reference() {
    let (scene, settings) = glossy();
    let mut failures = Vec::new();
    // `optimal-path` once more with a radius per block of pixels (`adaptive_radius`): ½, 1 or
    // 1.4 times the radius, its S in the weights and the pixel table; the blocks at 1.4 r
    // carry more kernel bias, which must stay inside the tolerance.
    let modes = [
        ("algebraic", false),
        ("optimal", false),
        ("optimal-path", false),
        ("camis", false),
        ("optimal-path", true),
    ];
    for (mode, adaptive_radius) in modes {
        let mut s = with_mode(settings, mode, 96, 128, 250_000);
        s.radius = Some(0.015);
        s.adaptive_radius = adaptive_radius;
        let renderer = Renderer::new(scene, &s).unwrap();
        if adaptive_radius {
            // Four 8 × 8 blocks: the test means something only if they do not all keep r.
            let blocks = renderer.radius_map().expect("a radius map").blocks();
            assert!(blocks[1] < 4, "every block at r: {blocks:?}");
        }
        let film = render_with(&renderer);
        let name = format!(
            "glossy {mode}{}",
            if adaptive_radius { " adaptive" } else { "" }
        );
        if let Err(e) = check_against(&name, &film, glossy_reference()) {
            failures.push(e);
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Light tracing in BDD=0's place (`light_tracing`, method-notes.md): each photon arrival is
/// connected to the camera with BDD=0's weight 1 − w₁, w₁ the mode's weight against light
/// tracing's density. Every mixing mode must stay unbiased, and a mix whose splats weigh with
/// the merge's two-way w₁ while the camera side uses the light-traced one (the two sides of a
/// path disagree) must fail the same check.
#[test]
fn light_traced_mixes_agree_with_the_light_reference_and_one_sided_weights_do_not() {
    let (scene, settings) = scene();
    let mut failures = Vec::new();
    // Half the merge tests' passes and photons: connections see the ceiling spot at once.
    let traced = |mode: &str| {
        let mut s = with_mode(settings, mode, 16, 64, 100_000);
        s.radius = Some(RADIUS);
        s.light_tracing = true;
        s
    };
    // One mode per branch of `Weigher::weight_light_traced` and of the splat: w₁ = 0 (`bdd0`),
    // a fixed weight (`threshold`), the balance family (`balance`; `camis` with its walk of
    // the light path; `corrected-balance` with its pilot), `power`, and the noise model with
    // the path's inputs (`optimal-path`) and with x₁'s alone (`algebraic`). The samples are
    // stratified, as in every test here (`load`): with independent ones the camera side's
    // direct light on the ceiling spot is heavy-tailed at 16 passes (bdd0 by merges and by light
    // tracing both read +1.3 % against a `light` render at seed 1, the same camera streams).
    let modes = [
        "bdd0",
        "threshold",
        "balance",
        "camis",
        "corrected-balance",
        "power",
        "optimal-path",
        "algebraic",
    ];
    for mode in modes {
        let film = render(scene, &traced(mode));
        if let Err(e) = check(&format!("{mode} + light tracing"), &film) {
            failures.push(e);
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");

    // Few camera samples and a small radius put N_B·S·p_C(x₀) far from 1, so the two weights
    // differ.
    let mut s = traced("balance");
    s.spp = 4;
    s.radius = Some(0.002);
    let one_sided = Renderer::new(scene, &s)
        .unwrap()
        .with_two_way_splat_weights(true);
    let bad = render_with(&one_sided);
    let (within, mean_diff, mean_se) = films_agree(&bad, reference(), 4.0);
    eprintln!(
        "two-way splat weights: within {within:.4}, image mean {mean_diff:+.4} ± {mean_se:.4}"
    );
    assert!(
        within < 0.9 || mean_diff.abs() > 0.05,
        "the one-sided weights were not detected: within {within:.4}, mean {mean_diff:+.4}"
    );
}

/// `cornell-glossy` with light tracing in BDD=0's place, against the independent `path`
/// reference: the connection evaluates the glossy BDF towards the camera, and the weights
/// read the light path's f₁ (`optimal-path`). Once more each with a radius per block of
/// pixels: a splat weighs with the S of the pixel it lands in, as that pixel's camera samples
/// do, and BDD=1's gathers reach 1.4 r. At 16² light tracing carries most of every block, so
/// the pilot would give no block 1.4 r; the test sets the map (blocks at ½ r, r, 1.4 r, 1.4 r).
#[test]
fn light_traced_glossy_mixes_agree_with_the_path_reference() {
    let (scene, settings) = glossy();
    let mut failures = Vec::new();
    for (mode, per_block) in [
        ("balance", false),
        ("optimal-path", false),
        ("balance", true),
        ("optimal-path", true),
    ] {
        let mut s = with_mode(settings, mode, 32, 128, 250_000);
        s.radius = Some(0.015);
        s.light_tracing = true;
        let mut renderer = Renderer::new(scene, &s).unwrap();
        if per_block {
            renderer = renderer.with_radius_map(block_map(RES, &[0.1, 0.45, 0.9, 0.9]));
            let blocks = renderer.radius_map().expect("a radius map").blocks();
            assert_eq!(blocks, [1, 1, 2], "blocks at 1/2 r, r, 1.4 r");
        }
        let film = render_with(&renderer);
        let name = format!(
            "glossy {mode} + light tracing{}",
            if per_block { ", radius per block" } else { "" }
        );
        if let Err(e) = check_against(&name, &film, glossy_reference()) {
            failures.push(e);
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// `direct_boost` (the integrator's `direct` module): the pixel that holds the ceiling spot
/// above the light takes more direct-light samples per camera sample, in the mix and in the
/// `light` reference's direct term; each render stays unbiased against the light reference
/// (one direct-light sample), and that pixel's per-pass variance falls. The same render with
/// one direct-light sample (the scene file's setting) is the comparison.
#[test]
fn direct_boost_is_unbiased_and_quiets_the_ceiling_spot() {
    let (scene, _) = scene();
    for mode in ["balance", "light"] {
        let mut s = settings_for(mode);
        assert_eq!(s.direct_boost, 1, "the preprint file's setting");
        let plain = render(scene, &s);
        s.direct_boost = 16;
        let renderer = Renderer::new(scene, &s).unwrap_or_else(|e| panic!("{e}"));
        let direct = renderer
            .direct_samples()
            .expect("the ceiling spot takes more than one direct-light sample");
        let boosted: Vec<usize> = (0..RES * RES)
            .filter(|&i| direct.at(i % RES, i / RES) > 1)
            .map(|i| i as usize)
            .collect();
        eprintln!(
            "{mode}: boosted pixels {boosted:?}, M {:?}",
            boosted
                .iter()
                .map(|&i| direct.at(i as u32 % RES, i as u32 / RES))
                .collect::<Vec<_>>()
        );
        assert!(!boosted.is_empty() && boosted.len() <= 4, "{boosted:?}");
        let film = render_with(&renderer);
        check(&format!("{mode}, direct_boost 16"), &film).unwrap();
        let variance = |f: &Film| -> f64 {
            let v = f.pass_variance();
            boosted.iter().map(|&i| lum(v[i].as_vec3()) as f64).sum()
        };
        let (v_boost, v_plain) = (variance(&film), variance(&plain));
        eprintln!(
            "{mode}: per-pass variance of the boosted pixels {v_boost:.4e} against {v_plain:.4e}"
        );
        assert!(
            v_boost < 0.5 * v_plain,
            "{mode}: {v_boost:.4e} against {v_plain:.4e}"
        );
    }
}
