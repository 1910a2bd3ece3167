//! The mirror and glass scenes of issue 45 (scenes/smallvcm-spheres.toml,
//! scenes/mirror-caustic.toml, scenes/cornell-glass-block.toml): each loads and renders tiny
//! with finite, non-negative radiance, light where the camera sees a mirror or glass first,
//! and, in mirror-caustic, the caustic seen in the mirror.

use std::path::Path;

use bdpm_integrator::{Film, RenderSettings};
use bdpm_load::load_scene_str;
use bdpm_scene::Scene;
use bdpm_suite::{load, render, scene_path, with_mode};

const RES: u32 = 16;

/// Renders and checks that no estimate was dropped and every pixel is finite and ≥ 0.
fn render_checked(name: &str, scene: &Scene, settings: &RenderSettings) -> Film {
    let film = render(scene, settings);
    let mode = settings.mode.name();
    assert_eq!(film.dropped(), 0, "{name} {mode}");
    for (i, v) in film.mean().iter().enumerate() {
        assert!(
            v.is_finite() && v.min_element() >= 0.0,
            "{name} {mode}: pixel {i} is {v}"
        );
    }
    film
}

/// Whether the centre of pixel (x, y) sees a mirror or glass first.
fn sees_delta(scene: &Scene, x: u32, y: u32) -> bool {
    let cam = scene.camera();
    let d = cam.ray_direction(x as f32 + 0.5, y as f32 + 0.5);
    scene
        .geometry()
        .intersect(cam.position(), d, f32::INFINITY)
        .is_some_and(|h| scene.is_delta(h.material))
}

/// The mean luminance-free radiance (channel sum / 3) of the pixels where `keep` is true, and
/// how many there are.
fn mean_where(film: &Film, keep: impl Fn(u32, u32) -> bool) -> (f64, usize) {
    let (mut sum, mut n) = (0.0, 0usize);
    for (i, v) in film.mean().iter().enumerate() {
        let (x, y) = (i as u32 % RES, i as u32 / RES);
        if keep(x, y) {
            sum += v.element_sum() / 3.0;
            n += 1;
        }
    }
    (sum / n.max(1) as f64, n)
}

/// Each scene renders finite and non-black in `balance` and `path`, and the pixels that see a
/// mirror or glass first show something (the room in the mirror, the box through the glass).
#[test]
fn specular_scenes_render_and_show_their_mirrors_and_glass() {
    for name in [
        "smallvcm-spheres.toml",
        "mirror-caustic.toml",
        "cornell-glass-block.toml",
    ] {
        let (scene, settings) = load(name, RES, RES);
        for mode in ["balance", "path"] {
            let film = render_checked(name, &scene, &with_mode(&settings, mode, 2, 4, 40_000));
            let (all, _) = mean_where(&film, |_, _| true);
            let (delta, n) = mean_where(&film, |x, y| sees_delta(&scene, x, y));
            eprintln!("{name} {mode}: image mean {all:.4e}, {n} delta pixels mean {delta:.4e}");
            assert!(all > 0.0, "{name} {mode}: black image");
            assert!(n >= 4, "{name}: only {n} pixels see a mirror or glass");
            assert!(delta > 0.0, "{name} {mode}: black mirror or glass");
        }
    }
}

/// scenes/mirror-caustic.toml: the camera looks at the mirror image of the glass sphere's
/// caustic, so the image centre, lit by L–S–S–D–S–E paths, is several times brighter than the
/// same pixels with the mirror made Lambert (kd 0.5, where they see the back wall lit
/// directly), in `balance` (which merges the caustic's photons on the floor). The camera is
/// zoomed in (vfov 6° instead of 40°) so that the spot covers a few of the 16 × 16 pixels: at
/// 40° a pixel would hold the spot and the sphere's shadow around it, which together carry
/// about the light the floor would get without the sphere. The check fails if photons are not
/// carried through the glass or the camera path not through the mirror (measured: about 17×).
#[test]
fn the_mirror_caustic_is_seen_in_the_mirror() {
    let path = scene_path("mirror-caustic.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let mirror = "type = \"mirror\"\nreflectance = 0.95\n";
    assert!(
        text.contains(mirror),
        "{}: mirror material changed",
        path.display()
    );
    let fov = "vfov = 40\n";
    assert!(
        text.contains(fov),
        "{}: field of view changed",
        path.display()
    );
    let text = text.replace(fov, "vfov = 6\n");
    let lambert = text.replace(mirror, "kd = 0.5\n");
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut brightness = Vec::new();
    for text in [&text, &lambert] {
        let loaded = load_scene_str(text, dir, &path).unwrap_or_else(|e| panic!("{e}"));
        let mut scene = loaded.scene;
        scene.set_resolution(RES, RES).unwrap();
        let settings = with_mode(&loaded.settings, "balance", 4, 4, 100_000);
        let settings = RenderSettings {
            width: RES,
            height: RES,
            ..settings
        };
        let film = render_checked("mirror-caustic", &scene, &settings);
        let centre = |x: u32, y: u32| {
            (RES / 2 - 1..=RES / 2).contains(&x) && (RES / 2 - 1..=RES / 2).contains(&y)
        };
        brightness.push(mean_where(&film, centre).0);
    }
    eprintln!(
        "mirror-caustic centre: mirror {:.4e}, Lambert {:.4e}",
        brightness[0], brightness[1]
    );
    assert!(
        brightness[0] > 3.0 * brightness[1],
        "the mirrored caustic {:.4e} is not 3x the Lambert back wall {:.4e}",
        brightness[0],
        brightness[1]
    );
}
