//! Smooth spheres (vertex normals on the geodesic facets) through mirrors and glass: camera
//! paths and light paths see the same scene only if light paths carry Veach's adjoint
//! correction for shading normals at delta vertices (crates/scene/src/delta.rs).

use crate::specular::{agree_where, light, load, quad, room, sees_glass};
use bdpm_suite::{render, with_mode};

/// A coarse smooth mirror sphere and a coarse smooth glass sphere (subdivisions 2: shading
/// normals up to ≈ 9° off their facets) on the floor of a closed Lambert room, with a Lambert
/// plate under the light that hides both spheres from it (so that no path has a delta vertex
/// right after the light, which `path` could not sample). Every other path through the spheres
/// is sampled by both references: `path` from the camera (radiance mode at the delta vertices)
/// and `light` from the light (importance mode, connecting to the camera at the floor or a
/// wall). They must agree wherever the camera sees no sphere. Without the adjoint factor the
/// light paths' images differ by the amount docs/results.md ("Smooth spheres") gives.
#[test]
fn camera_and_light_paths_agree_through_smooth_spheres() {
    let text = format!(
        "[render]\nresolution = [24, 24]\nseed = 5\n\n\
         [camera]\nposition = [0.5, 0.55, 0.98]\nlook_at = [0.5, 0.15, 0.4]\n\
         up = [0.0, 1.0, 0.0]\nvfov = 60\n\n{}\
         [material.walls]\nkd = 0.6\n\n[material.mirror]\ntype = \"mirror\"\n\n\
         [material.glass]\ntype = \"dielectric\"\nior = 1.5\n\n\
         [[shape]]\ntype = \"sphere\"\ncenter = [0.3, 0.17, 0.45]\nradius = 0.16\n\
         subdivisions = 2\nmaterial = \"mirror\"\n\n\
         [[shape]]\ntype = \"sphere\"\ncenter = [0.7, 0.17, 0.45]\nradius = 0.16\n\
         subdivisions = 2\nmaterial = \"glass\"\n\n{}{}",
        light([0.5, 0.9, 0.45]),
        quad(
            "walls",
            [
                [0.3, 0.8, 0.25],
                [0.7, 0.8, 0.25],
                [0.7, 0.8, 0.65],
                [0.3, 0.8, 0.65]
            ]
        ),
        room(0.0, 1.0, "walls"),
    );
    let (scene, settings) = load(&text);
    let (w, h) = (scene.camera().width(), scene.camera().height());
    let no_sphere: Vec<bool> = (0..w * h)
        .map(|i| !sees_glass(&scene, i % w, i / w))
        .collect();
    let spheres = no_sphere.iter().filter(|k| !**k).count();
    assert!(
        spheres > 40 && spheres < 300,
        "{spheres} pixels see a sphere"
    );
    let path = render(&scene, &with_mode(&settings, "path", 64, 128, 1));
    let light_film = render(&scene, &with_mode(&settings, "light", 64, 1, 400_000));
    let (within, diff, se) = agree_where(&light_film, &path, &no_sphere, 4.0);
    eprintln!("light vs path: within {within:.4}, mean {diff:+.4} ± {se:.4}");
    assert!(
        within >= 0.98 && diff.abs() < 4.0 * se && se < 0.004,
        "light vs path: within {within}, mean {diff:+} ± {se}"
    );
}
