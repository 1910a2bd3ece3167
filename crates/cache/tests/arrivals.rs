//! A cache filled from arrivals the caller supplies equals the one `build` fills from its own
//! photon pass, when the caller supplies that very pass: `from_arrivals` is the same
//! accumulation, not a second implementation.

use bdpm_bdf::{Bdf, luminance};
use bdpm_cache::{CacheArrival, CacheSettings, RadianceCache};
use bdpm_geometry::{Domain, Geometry, TriangleMesh};
use bdpm_photon::{TraceOptions, trace_photons};
use bdpm_scene::{Camera, PointLight, Scene};
use glam::Vec3;

/// A closed unit cube of `bdf` with a 1 W light inside.
fn cube(bdf: Bdf) -> Scene {
    Scene::one_material(
        Geometry::new(TriangleMesh::cuboid(Vec3::ZERO, Vec3::ONE, true, 0)).unwrap(),
        bdf,
        vec![PointLight {
            position: Vec3::new(0.4, 0.6, 0.5),
            flux: Vec3::ONE,
        }],
        Camera::look_at(
            Vec3::new(0.5, 0.5, 0.1),
            Vec3::new(0.5, 0.5, 1.0),
            Vec3::Y,
            60.0,
            8,
            8,
        )
        .unwrap(),
    )
    .unwrap()
}

#[test]
fn from_arrivals_of_the_cache_pass_equals_build() {
    for bdf in [
        Bdf::lambert(Vec3::splat(0.6)).unwrap(),
        Bdf::new(Vec3::splat(0.3), Vec3::splat(0.4), 0.3).unwrap(),
    ] {
        let scene = cube(bdf);
        let settings = CacheSettings {
            bins: 16,
            cell_size: 0.2,
            photons: 20_000,
            seed: 3,
        };
        let built = RadianceCache::build(&scene, &settings);
        // The pass `build` traces, made by the caller.
        let options = TraceOptions {
            domain: Domain::CachePhoton,
            ..TraceOptions::new(settings.photons, settings.seed, 0)
        };
        let arrivals = trace_photons(&scene, &options, |a, out| {
            if let (true, Some(s)) = (a.vertex.depth >= 1, a.scatter) {
                out.push(CacheArrival {
                    prim: a.vertex.at.prim,
                    position: a.vertex.at.p,
                    normal: a.vertex.at.n,
                    direction: s.direction,
                    energy: luminance(a.power * s.weight),
                    f: luminance(s.f),
                });
            }
        });
        let supplied =
            RadianceCache::from_arrivals(&scene, settings.bins, settings.cell_size, arrivals);
        assert_eq!(built.stats(), supplied.stats());
        assert!(built.stats().arrivals > 10_000);
        assert_eq!(built.cells(), supplied.cells());
        let (p, wo) = (
            Vec3::new(0.3, 0.0, 0.7),
            Vec3::new(0.2, 1.0, -0.3).normalize(),
        );
        let prim = (0..12)
            // A floor triangle (y = 0), where p lies.
            .find(|&t| {
                built.slot(t, p, wo).is_some()
                    && scene.geometry().vertices(t).iter().all(|v| v.y == 0.0)
            })
            .unwrap();
        assert_eq!(built.lookup(prim, p, wo), supplied.lookup(prim, p, wo));
        assert!(built.lookup(prim, p, wo).0 > 0.0);
    }
}
