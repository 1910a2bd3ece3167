//! Light through closed surfaces (issue 43, finding 5): a point light or the camera a few
//! micrometres outside a closed room must not see into it, in any mode, and a light just inside
//! must light it the same in every mode.
//!
//! Before the fix, `Geometry::occluded` stopped every shadow segment at 1 − 10⁻⁵ of its length,
//! so a surface within 10⁻⁵ of the segment's length of the light (10 µm in a 1 m room) was
//! never found: a light 1 or 10 µm above a closed room's ceiling lit the room (image mean
//! 1–2·10⁻³ of the room lit from inside) and light tracing saw through a wall 1 µm in front
//! of the camera.

use std::path::Path;

use bdpm_geometry::sampling::uniform_sphere;
use bdpm_geometry::{Domain, Rng};
use bdpm_integrator::{Film, Mode, RenderSettings, Renderer};
use bdpm_load::load_scene_str;
use bdpm_scene::Scene;
use bdpm_suite::{load, scene_path};
use glam::{DMat3, DVec3};
use rayon::prelude::*;

/// A closed cube [0, 1]³ of six quads, rotated by `rot` about its centre: walls and floor of
/// kd 0.5, the ceiling (y = 1 before the rotation) of kd `ceiling_kd`. `light` and the camera's
/// position and target are given in the unrotated room and rotated with it.
struct Room {
    rot: DMat3,
    ceiling_kd: f64,
    light: DVec3,
    camera: DVec3,
    look_at: DVec3,
    render: &'static str,
}

impl Room {
    fn place(&self, p: DVec3) -> DVec3 {
        let c = DVec3::splat(0.5);
        c + self.rot * (p - c)
    }

    fn point(&self, p: DVec3) -> String {
        let p = self.place(p);
        format!("[{:.9}, {:.9}, {:.9}]", p.x, p.y, p.z)
    }

    fn text(&self) -> String {
        let corner = |i: u32| DVec3::new((i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2) as f64);
        // Corners by bits (x, y, z); each face as four corners in order around it.
        let faces = [
            ("walls", [0, 1, 5, 4]), // floor y = 0
            ("ceiling", [2, 6, 7, 3]),
            ("walls", [0, 2, 3, 1]), // z = 0
            ("walls", [4, 5, 7, 6]), // z = 1
            ("walls", [0, 4, 6, 2]), // x = 0
            ("walls", [1, 3, 7, 5]), // x = 1
        ];
        let mut shapes = String::new();
        for (material, q) in faces {
            let v: Vec<String> = q.iter().map(|&i| self.point(corner(i))).collect();
            shapes += &format!(
                "[[shape]]\ntype = \"quad\"\nmaterial = \"{material}\"\nvertices = [{}]\n\n",
                v.join(", ")
            );
        }
        let up = self.rot * DVec3::Y;
        format!(
            "[render]\n{render}\n\n[camera]\nposition = {cam}\nlook_at = {look}\n\
             up = [{:.9}, {:.9}, {:.9}]\nvfov = 70\n\n[[light]]\nposition = {light}\n\
             flux = [1.0, 1.0, 1.0]\n\n[material.walls]\nkd = 0.5\n[material.ceiling]\n\
             kd = {kd}\n\n{shapes}",
            up.x,
            up.y,
            up.z,
            render = self.render,
            cam = self.point(self.camera),
            look = self.point(self.look_at),
            light = self.point(self.light),
            kd = self.ceiling_kd,
        )
    }

    fn scene(&self, case: &str) -> (Scene, RenderSettings) {
        let loaded = load_scene_str(&self.text(), Path::new("."), Path::new(case))
            .unwrap_or_else(|e| panic!("{case}: {e}"));
        (loaded.scene, loaded.settings)
    }
}

/// A rotation about an oblique axis, so that no face is aligned with the axes and the
/// vertices, the light and the ray tests all round.
fn oblique() -> DMat3 {
    DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7)
}

/// Every mode: `path`, `light`, each weight mode, and each weight mode with BDD=0 by light
/// tracing (`bdd1` has no BDD=0 part).
fn every_mode(settings: &RenderSettings) -> Vec<RenderSettings> {
    let mut out = Vec::new();
    for name in Mode::names() {
        let mode = Mode::parse(name).expect("a listed mode");
        out.push(RenderSettings {
            mode,
            ..settings.clone()
        });
        if matches!(mode, Mode::Bdpm(_)) && name != "bdd1" {
            out.push(RenderSettings {
                mode,
                light_tracing: true,
                ..settings.clone()
            });
        }
    }
    out
}

/// Renders `settings` and returns the film.
fn render(scene: &Scene, settings: &RenderSettings, case: &str) -> Film {
    let renderer = Renderer::new(scene, settings).unwrap_or_else(|e| panic!("{case}: {e}"));
    let mut film = Film::new(settings.width, settings.height);
    for pass in 0..settings.passes {
        let out = renderer.render_pass(pass, &|_| {});
        film.add_pass(&out.estimates, out.dropped);
    }
    film
}

/// Renders every mode and adds a line to `failures` for each one with a pixel that is not
/// exactly zero.
fn black_in_every_mode(
    scene: &Scene,
    settings: &RenderSettings,
    case: &str,
    failures: &mut Vec<String>,
) {
    for s in every_mode(settings) {
        let film = render(scene, &s, case);
        let mean = film.mean();
        let lit = mean.iter().filter(|v| **v != DVec3::ZERO).count();
        if lit > 0 {
            let lit_mean = mean.iter().map(|v| v.x).sum::<f64>() / lit as f64;
            failures.push(format!(
                "{case} {}{}: {lit} of {} pixels lit (mean of those {lit_mean:.3e})",
                s.mode,
                if s.light_tracing {
                    "+light_tracing"
                } else {
                    ""
                },
                mean.len()
            ));
        }
    }
}

/// Panics with every failure, one a line.
fn assert_none(failures: &[String]) {
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

const SMALL: &str = "resolution = [8, 8]\npasses = 1\nspp = 2\nphotons = 4000\nseed = 3";

/// A point light 1 µm, 10 µm and 1 mm above the ceiling of a closed room (axis-aligned and
/// rotated) leaves the room exactly black in every mode. Before the fix the 1 and 10 µm
/// lights lit it in every mode.
#[test]
fn a_light_just_outside_a_closed_room_leaves_it_black_in_every_mode() {
    let mut failures = Vec::new();
    for (rot, tilt) in [(DMat3::IDENTITY, "axis-aligned"), (oblique(), "rotated")] {
        for gap in [1e-6, 1e-5, 1e-3] {
            let room = Room {
                rot,
                ceiling_kd: 0.5,
                light: DVec3::new(0.5, 1.0 + gap, 0.5),
                camera: DVec3::new(0.5, 0.5, 0.05),
                look_at: DVec3::new(0.5, 0.6, 1.0),
                render: SMALL,
            };
            let case = format!("<{tilt} room, light {gap:e} m above the ceiling>");
            let (scene, settings) = room.scene(&case);
            black_in_every_mode(&scene, &settings, &case, &mut failures);
        }
    }
    assert_none(&failures);
}

/// scenes/cornell-light-near-ceiling.toml (open at the front, the camera outside) with its
/// light moved 1 µm and 10 µm above the ceiling (y = 2.744 m): every mode renders black.
#[test]
fn the_near_ceiling_cornell_box_with_its_light_above_the_ceiling_is_black() {
    let mut failures = Vec::new();
    let text = std::fs::read_to_string(scene_path("cornell-light-near-ceiling.toml"))
        .expect("read the scene");
    let original = "position = [1.39, 2.741, 1.398]";
    assert!(text.contains(original), "the scene's light moved");
    for y in ["2.744001", "2.74401"] {
        let moved = text.replace(original, &format!("position = [1.39, {y}, 1.398]"));
        let case = format!("<cornell-light-near-ceiling, light at y = {y} m>");
        let loaded = load_scene_str(&moved, Path::new("."), Path::new(&case))
            .unwrap_or_else(|e| panic!("{case}: {e}"));
        let mut scene = loaded.scene;
        scene.set_resolution(8, 8).expect("resolution");
        let settings = RenderSettings {
            width: 8,
            height: 8,
            passes: 1,
            spp: 2,
            photons: 4000,
            ..loaded.settings
        };
        black_in_every_mode(&scene, &settings, &case, &mut failures);
    }
    assert_none(&failures);
}

/// The camera 1 µm and 10 µm in front of a closed room's wall, looking at it, with the light
/// inside: the wall's outside is all it sees, black in every mode. Before the fix the light
/// tracing of `light` and of the weight modes with `light_tracing` saw through the wall.
#[test]
fn a_camera_just_outside_a_closed_room_sees_no_light_from_inside() {
    let mut failures = Vec::new();
    for (rot, tilt) in [(DMat3::IDENTITY, "axis-aligned"), (oblique(), "rotated")] {
        for gap in [1e-6, 1e-5] {
            let room = Room {
                rot,
                ceiling_kd: 0.5,
                light: DVec3::new(0.5, 0.9, 0.5),
                camera: DVec3::new(0.5, 0.5, -gap),
                look_at: DVec3::new(0.5, 0.5, 1.0),
                render: SMALL,
            };
            let case = format!("<{tilt} room, camera {gap:e} m outside>");
            let (scene, settings) = room.scene(&case);
            black_in_every_mode(&scene, &settings, &case, &mut failures);
        }
    }
    assert_none(&failures);
}

/// Image mean (first channel) of each pass.
fn pass_means(scene: &Scene, settings: &RenderSettings, case: &str) -> Vec<f64> {
    let renderer = Renderer::new(scene, settings).unwrap_or_else(|e| panic!("{case}: {e}"));
    (0..settings.passes)
        .map(|pass| {
            let out = renderer.render_pass(pass, &|_| {});
            assert_eq!(out.dropped, 0, "{case}: non-finite samples");
            out.estimates.iter().map(|v| v.x).sum::<f64>() / out.estimates.len() as f64
        })
        .collect()
}

/// Mean and standard error of the mean of independent passes.
fn mean_and_error(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Asserts that the modes' image means agree pairwise within `k` standard errors.
fn assert_modes_agree(scene: &Scene, settings: &RenderSettings, modes: &[&str], case: &str) {
    let results: Vec<(&str, f64, f64)> = modes
        .iter()
        .map(|&m| {
            let s = RenderSettings {
                mode: Mode::parse(m).expect("mode"),
                ..settings.clone()
            };
            let (mean, err) = mean_and_error(&pass_means(scene, &s, case));
            (m, mean, err)
        })
        .collect();
    eprintln!("{case}: {results:?}");
    for (i, a) in results.iter().enumerate() {
        assert!(a.1 > 0.0, "{case}: {} is black", a.0);
        for b in &results[i + 1..] {
            let z = (a.1 - b.1) / (a.2 * a.2 + b.2 * b.2).sqrt();
            assert!(
                z.abs() < 4.0,
                "{case}: {} {:.5e} ± {:.1e} and {} {:.5e} ± {:.1e} differ by {z:.1} σ",
                a.0,
                a.1,
                a.2,
                b.0,
                b.1,
                b.2
            );
        }
    }
}

const AGREE: &str = "resolution = [16, 16]\npasses = 16\nspp = 4\nphotons = 20000\nseed = 5";

/// A light 1 µm and 10 µm below the ceiling lights the room, and `path`, `light` and `balance`
/// give the same image mean within 4σ. The ceiling is black here: a grey one above a light
/// δ away holds a spot of irradiance ∝ 1/δ² and radius ≈ δ that re-emits a quarter of the flux,
/// which `light` and the mix sample through photons but path tracing essentially never hits
/// (it then reads 32 % low with a small error bar); that case is compared between `light` and
/// `balance` alone.
#[test]
fn a_light_just_inside_lights_the_room_the_same_in_every_reference() {
    for (rot, tilt) in [(DMat3::IDENTITY, "axis-aligned"), (oblique(), "rotated")] {
        for gap in [1e-6, 1e-5] {
            for (ceiling_kd, modes) in [
                (0.0, &["path", "light", "balance"][..]),
                (0.5, &["light", "balance"][..]),
            ] {
                let room = Room {
                    rot,
                    ceiling_kd,
                    light: DVec3::new(0.5, 1.0 - gap, 0.5),
                    camera: DVec3::new(0.5, 0.5, 0.05),
                    look_at: DVec3::new(0.5, 0.6, 1.0),
                    render: AGREE,
                };
                let case =
                    format!("<{tilt} room, light {gap:e} m below a ceiling of kd {ceiling_kd}>");
                let (scene, settings) = room.scene(&case);
                assert_modes_agree(&scene, &settings, modes, &case);
            }
        }
    }
}
/// No scene of the repository has a light within a surface's ray offset (the near-ceiling
/// Cornell box's is 3 mm below the ceiling, against an offset of 2·10⁻⁵ m).
#[test]
fn the_repository_scenes_have_no_light_near_a_surface() {
    for dir in ["", "preprint"] {
        let mut names: Vec<String> = std::fs::read_dir(scene_path(dir))
            .expect("scenes/")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".toml"))
            .collect();
        names.sort();
        assert!(!names.is_empty());
        for name in names {
            let path = if dir.is_empty() {
                name
            } else {
                format!("{dir}/{name}")
            };
            let (scene, _) = load(&path, 8, 8);
            assert_eq!(scene.lights_near_surfaces(), [], "{path}");
        }
    }
}

/// A light within its surface's ray offset is reported with its index and distance; one
/// 1 mm away is not.
#[test]
fn a_light_within_the_ray_offset_of_a_surface_is_reported() {
    for (gap, expect) in [(1e-6, true), (-1e-6, true), (0.0, true), (1e-3, false)] {
        let room = Room {
            rot: oblique(),
            ceiling_kd: 0.5,
            light: DVec3::new(0.5, 1.0 + gap, 0.5),
            camera: DVec3::new(0.5, 0.5, 0.05),
            look_at: DVec3::new(0.5, 0.6, 1.0),
            render: SMALL,
        };
        let (scene, _) = room.scene("<near>");
        let near = scene.lights_near_surfaces();
        assert_eq!(near.len(), usize::from(expect), "gap {gap}: {near:?}");
        if let Some(w) = near.first() {
            assert_eq!(w.light, 0);
            // The light's and the vertices' coordinates round by up to 1.2·10⁻⁷ m each.
            assert!(
                (f64::from(w.distance) - gap.abs()).abs() < 3e-7,
                "gap {gap}: distance {}",
                w.distance
            );
            assert!(w.distance < w.offset, "{w:?}");
            let text = w.to_string();
            assert!(text.starts_with("light[0] "), "{text}");
        }
    }
}

/// Photons from the sphere furnace's light (inside a closed geodesic sphere of 20 480
/// triangles, whose edges are all shared) never leave it: of these 10⁷ rays from the light, 4
/// passed between two triangles without the watertight edge test (`NEAR_EDGE` set to 0),
/// none with it.
#[test]
fn rays_from_a_light_inside_a_closed_mesh_never_leave_it() {
    let (scene, _) = load("sphere-furnace.toml", 8, 8);
    let (g, light) = (scene.geometry(), scene.lights()[0].position);
    let escaped: u32 = (0..10u64)
        .into_par_iter()
        .map(|chunk| {
            let mut rng = Rng::new(1, Domain::Other, [chunk, 0, 0]);
            (0..1_000_000)
                .map(|_| {
                    let d = uniform_sphere(rng.uniform2());
                    u32::from(g.intersect(light, d, f32::INFINITY).is_none())
                })
                .sum::<u32>()
        })
        .sum();
    assert_eq!(escaped, 0, "{escaped} of 10⁷ rays left the sphere");
}
