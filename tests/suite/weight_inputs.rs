//! The weight inputs of a candidate x₁ are one function of the point, whichever technique found
//! it (docs/method.md §2): a photon's previous vertex y_p, as the photon tracer records it, and
//! the camera's x₁ at the same point, as a camera ray finds it, must give the weights the same
//! numbers. If either side computed its light visibility, normal side or cache lookup its own
//! way, the two techniques would evaluate different w₁ and the mix would be biased.

use bdpm_cache::{CacheSettings, RadianceCache};
use bdpm_photon::{TraceOptions, trace_photons};
use bdpm_scene::WeightVertex;
use bdpm_suite::load;

/// Compares, for the continued vertices of `photons` light paths, the tracer's vertex with the
/// camera-side vertex of a ray that hits the same point from the same side. Returns how many
/// vertices were compared.
fn camera_and_photon_vertices_agree(scene_name: &str, photons: u64) -> usize {
    let (scene, _) = load(scene_name, 16, 16);
    let mut options = TraceOptions::new(photons, 11, 0);
    options.light_visibility = true;
    let vertices: Vec<WeightVertex> = trace_photons(&scene, &options, |a, out| {
        if a.continued {
            out.push(a.vertex.at);
        }
    });
    let cache = RadianceCache::build(
        &scene,
        &CacheSettings {
            bins: 16,
            cell_size: 0.1,
            photons: 200_000,
            seed: 3,
        },
    );
    let mut compared = 0;
    for y in &vertices {
        // A camera ray arriving along the normal from 5 cm off the surface, on y's side.
        let origin = y.p + y.n * 0.05;
        let hit = scene
            .geometry()
            .intersect(origin, -y.n, f32::INFINITY)
            .expect("a ray along -n from 5 cm off a surface hits it");
        if hit.prim != y.prim {
            // Another surface lies within 5 cm (a corner): not the same point.
            continue;
        }
        let sh = scene.shade(&hit, y.n);
        let x1 = scene.weight_vertex(&sh);
        compared += 1;
        assert_eq!(
            (x1.prim, x1.material, x1.n, x1.lights),
            (y.prim, y.material, y.n, y.lights),
            "camera and photon vertex differ at {:?}",
            y.p
        );
        assert!((x1.p - y.p).length() < 1e-5, "hit {:?} vs {:?}", x1.p, y.p);
        // L₀ towards a direction on the vertex's side, and the cache's (L_d, b), as the
        // weights read them for either vertex.
        let wo = (y.n + 0.3 * y.n.any_orthonormal_vector()).normalize();
        let (a, b) = (scene.direct_masked(&x1, wo), scene.direct_masked(y, wo));
        assert!(
            (a - b).abs().max_element() <= 1e-4 * b.max_element().max(1e-6),
            "L0 {a:?} vs {b:?} at {:?}",
            y.p
        );
        let (sa, sb) = (cache.slot(x1.prim, x1.p, wo), cache.slot(y.prim, y.p, wo));
        if sa != sb {
            // The two points straddle a cell edge (they are 1e-5 m apart): rare, and not a
            // difference of the formula.
            let edge = cache.slot(y.prim, y.p + (x1.p - y.p) * 0.5, wo);
            assert!(edge == sa || edge == sb, "slots {sa:?} vs {sb:?}");
            continue;
        }
        if let Some(s) = sa {
            assert_eq!(cache.at(s), cache.lookup(y.prim, y.p, wo));
        }
    }
    compared
}

#[test]
fn camera_x1_and_photon_previous_vertex_have_the_same_weight_inputs_lambert() {
    let n = camera_and_photon_vertices_agree("preprint/cornell-lambert.toml", 2_000);
    assert!(n > 1_000, "only {n} vertices compared");
}

#[test]
fn camera_x1_and_photon_previous_vertex_have_the_same_weight_inputs_glossy() {
    let n = camera_and_photon_vertices_agree("preprint/cornell-glossy.toml", 2_000);
    assert!(n > 1_000, "only {n} vertices compared");
}

/// The one place b is derived for a Lambert-only scene is the cache: a lookup returns
/// b = (k_d/π)·L_d (luminances, method.md §7), and a glossy scene's cache stores its own b.
#[test]
fn the_cache_returns_b_in_lambert_only_scenes() {
    let (scene, _) = load("preprint/cornell-lambert.toml", 16, 16);
    let settings = CacheSettings {
        bins: 16,
        cell_size: 0.2,
        photons: 100_000,
        seed: 5,
    };
    let cache = RadianceCache::build(&scene, &settings);
    assert!(!cache.stats().stores_b);
    let mut lit = 0;
    for prim in 0..scene.geometry().triangle_count() as u32 {
        let v = scene.geometry().vertices(prim);
        let p = (v[0] + v[1] + v[2]) / 3.0;
        let n = scene.geometry().normal(prim);
        for wo in [n, -n] {
            let (ld, b) = cache.lookup(prim, p, wo);
            let kd = scene.bdf(scene.geometry().material(prim)).kd();
            let expected = bdpm_bdf::luminance(kd) / std::f32::consts::PI * ld;
            assert_eq!(b, expected, "triangle {prim}");
            lit += usize::from(ld > 0.0);
        }
    }
    assert!(lit > 10, "only {lit} lit cell sides");
}
