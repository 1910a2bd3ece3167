//! Same scene, settings and seed → the same image bits, whatever the thread count.

use bdpm_integrator::Renderer;
use bdpm_suite::{load, render_with, with_mode};

fn bits(film: &bdpm_integrator::Film) -> Vec<u64> {
    let mut out = Vec::new();
    for v in film.mean().iter().chain(film.pass_variance().iter()) {
        out.extend(v.to_array().map(f64::to_bits));
    }
    out
}

#[test]
fn images_do_not_depend_on_the_thread_count() {
    let (scene, settings) = load("preprint/cornell-glossy.toml", 24, 24);
    // (mode, direct-light samples near the light, a radius per block of pixels from a pilot,
    // light tracing in BDD=0's place).
    let modes = [
        ("path", 1, false, false),
        ("light", 1, false, false),
        ("optimal", 1, false, false),
        ("balance", 1, false, false),
        ("corrected-balance", 1, false, false),
        ("balance", 16, false, false),
        ("optimal-path", 1, true, false),
        ("balance", 1, true, true),
    ];
    for (mode, direct_boost, adaptive_radius, light_tracing) in modes {
        let s = bdpm_integrator::RenderSettings {
            direct_boost,
            adaptive_radius,
            light_tracing,
            ..with_mode(&settings, mode, 2, 2, 20_000)
        };
        let render_on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let renderer = Renderer::new(&scene, &s).unwrap();
                assert_eq!(
                    renderer.direct_samples().is_some(),
                    direct_boost > 1,
                    "{mode}: pixels near the light take more direct-light samples"
                );
                render_with(&renderer)
            })
        };
        let one = render_on(1);
        let two = render_on(2);
        assert!(one.mean().iter().any(|v| v.x > 0.0), "{mode}: black image");
        assert!(bits(&one) == bits(&two), "{mode}: 1 and 2 threads differ");
        // A different seed must change the bits, or the comparison above proves nothing.
        let other = {
            let mut s2 = s.clone();
            s2.seed += 1;
            render_with(&Renderer::new(&scene, &s2).unwrap())
        };
        assert!(bits(&other) != bits(&one), "{mode}: the seed has no effect");
    }
}

/// The weight inputs of a photon's previous vertex, computed once per photon for Lambert
/// vertices (`Mix::prev_inputs`), give the same image bits as computing them at every visit,
/// in every mode that reads them, on a Lambert-only scene (isotropic cache), on the glossy
/// one (where only `algebraic-direct` has no directional cache and so uses them), and on the
/// glossy one with a one-bin cache (isotropic, storing b).
#[test]
fn precomputed_photon_inputs_keep_the_bits() {
    for (scene_file, bins) in [
        ("preprint/cornell-lambert.toml", None),
        ("preprint/cornell-glossy.toml", None),
        ("preprint/cornell-glossy.toml", Some(1)),
    ] {
        let (scene, mut settings) = load(scene_file, 24, 24);
        if let Some(bins) = bins {
            settings.cache_bins = bins;
        }
        for mode in [
            "algebraic-direct",
            "algebraic",
            "optimal",
            "optimal-path",
            "threshold",
        ] {
            let s = with_mode(&settings, mode, 1, 4, 40_000);
            let once = Renderer::new(&scene, &s).unwrap();
            let per_visit = Renderer::new(&scene, &s)
                .unwrap()
                .with_per_visit_inputs(true);
            let a = once.render_pass(0, &|_| {}).estimates;
            let b = per_visit.render_pass(0, &|_| {}).estimates;
            assert!(
                a.iter().any(|v| v.x > 0.0),
                "{scene_file} {bins:?} {mode}: black"
            );
            assert!(
                a == b,
                "{scene_file} {bins:?} {mode}: precomputed inputs changed the image"
            );
        }
    }
}
