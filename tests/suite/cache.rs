//! The directional radiance cache against the sphere furnace's exact, uniform L_d
//! (method.md §5 and §10: L_d = k·E_ind/π everywhere).

use bdpm_cache::{CacheSettings, RadianceCache};
use bdpm_load::load_scene_str;
use bdpm_suite::{Furnace, scene_path};

/// The repository's furnace with a coarser sphere (1280 facets), so that each cell (one per
/// facet) receives thousands of photon arrivals.
fn coarse_furnace() -> bdpm_scene::Scene {
    let path = scene_path("sphere-furnace.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let text = text.replace("subdivisions = 32", "subdivisions = 8");
    assert!(
        text.contains("subdivisions = 8"),
        "the furnace scene changed its tessellation key"
    );
    load_scene_str(&text, path.parent().unwrap(), &path)
        .unwrap()
        .scene
}

#[test]
fn cache_reproduces_the_uniform_furnace_radiance() {
    let scene = coarse_furnace();
    let furnace = Furnace::of(&scene);
    let exact = furnace.albedo * furnace.indirect_irradiance() / std::f64::consts::PI;
    let settings = CacheSettings {
        bins: 100,
        cell_size: 10.0,
        photons: 8_000_000,
        seed: 7,
    };
    let cache = RadianceCache::build(&scene, &settings);
    // A Lambert-only scene gets one bin per cell and no b (method.md §7).
    assert_eq!(cache.stats().bins, 1);
    assert!(!cache.stats().stores_b);
    let inside: Vec<_> = cache
        .cells()
        .into_iter()
        .filter(|c| c.arrivals > 0)
        .collect();
    // Photons arrive only on the inner side.
    assert!(inside.iter().all(|c| c.side == inside[0].side));
    assert_eq!(inside.len(), scene.geometry().triangle_count());
    let total_area: f64 = inside.iter().map(|c| c.area).sum();
    let mean: f64 = inside.iter().map(|c| c.mean_ld * c.area).sum::<f64>() / total_area;
    eprintln!(
        "area-weighted mean L_d {mean:.6} vs exact {exact:.6} ({:+.4})",
        mean / exact - 1.0
    );
    assert!(
        (mean / exact - 1.0).abs() < 0.02,
        "mean L_d {mean} vs {exact}"
    );
    // "Enough photons": with n arrivals a cell's relative noise is about 1.2/√n (photon powers
    // vary through roulette), so 10% is ≥ 5 standard errors once n ≥ 3600.
    let populated: Vec<_> = inside.iter().filter(|c| c.arrivals >= 3600).collect();
    assert!(
        populated.len() > inside.len() / 2,
        "only {} of {} cells are populated",
        populated.len(),
        inside.len()
    );
    let worst = populated
        .iter()
        .map(|c| (c.mean_ld / exact - 1.0).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "{} populated cells, worst relative deviation {worst:.4}",
        populated.len()
    );
    assert!(worst < 0.10, "a populated cell is off by {worst}");
}

#[test]
fn glossy_scenes_get_directional_bins_and_b() {
    let path = scene_path("preprint/cornell-glossy.toml");
    let scene = bdpm_load::load_scene(&path).unwrap().scene;
    let settings = CacheSettings {
        bins: 100,
        cell_size: 0.25,
        photons: 200_000,
        seed: 3,
    };
    let cache = RadianceCache::build(&scene, &settings);
    assert_eq!(cache.stats().bins, 100);
    assert!(cache.stats().stores_b);
    // Every lookup is finite and non-negative.
    for c in cache.cells().iter().step_by(7) {
        assert!(c.mean_ld.is_finite() && c.mean_ld >= 0.0);
    }
}
