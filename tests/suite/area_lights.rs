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

/// The same sphere with a Gaussian lobe (kd 0.25, gr 0.5, Δ = 12°): its directional albedo
/// µ(ωₒ) varies with the angle, so radiance is no longer one constant but lies between
/// Le/(1 − min µ) and Le/(1 − max µ); the exact answer is not closed-form, so every mode
/// must agree with `path` (an independent estimator: no merge, MIS at every vertex) pixel
/// by pixel, and `path` must lie within those bounds.
#[test]
fn every_mode_agrees_with_path_in_the_lobe_furnace() {
    let text = std::fs::read_to_string(bdpm_suite::scene_path("emissive-furnace.toml"))
        .expect("the scene file");
    let text = text.replace("kd = 0.5\n", "kd = 0.25\ngr = 0.5\ndelta = 12\n");
    let (mut scene, mut settings) = crate::specular::load(&text);
    scene.set_resolution(16, 16).expect("valid resolution");
    (settings.width, settings.height) = (16, 16);
    settings.sampler = bdpm_integrator::RenderSettings::default().sampler;
    let reference = render(&scene, &with_mode(&settings, "path", 96, 4, 1));
    // µ(ωₒ) = kd + gr·µ_G(cos θₒ) over the directions, from the BDF's own albedo.
    let bdf = scene.bdf(0);
    let albedo = |z: f32| {
        let wo = glam::Vec3::new((1.0 - z * z).sqrt(), 0.0, z);
        f64::from(bdf.albedo(wo).x)
    };
    let mus: Vec<f64> = (1..=100).map(|i| albedo(i as f32 / 100.0)).collect();
    let (lo, hi) = mus
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &m| (a.min(m), b.max(m)));
    let mean: f64 = reference.mean().iter().map(|v| v.x).sum::<f64>() / 256.0;
    eprintln!(
        "path mean {mean}, bounds [{}, {}]",
        1.0 / (1.0 - lo),
        1.0 / (1.0 - hi)
    );
    assert!(
        mean >= 1.0 / (1.0 - lo) && mean <= 1.0 / (1.0 - hi),
        "{mean}"
    );
    let mut failures = Vec::new();
    for mode in all_modes().into_iter().filter(|&m| m != "path") {
        let mut s = with_mode(&settings, mode, 16, 4, 20_000);
        s.radius = Some(0.05);
        s.threshold_radius = 0.9;
        let film = render(&scene, &s);
        let (within, diff, se) = bdpm_suite::films_agree(&film, &reference, 4.0);
        eprintln!("{mode:>16}: within {within:.4}, mean {diff:+.4} ± {se:.4}");
        if !(within >= 0.98 && diff.abs() < (4.0 * se).max(0.005) && se < 0.005) {
            failures.push(format!("{mode}: within {within}, mean {diff:+} ± {se}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// scenes/cornell-box.toml (Mitsuba's Cornell box, its area light) with a point light added
/// beside the area light, so photons and direct light share one distribution over both kinds:
/// every mode agrees with `path` pixel by pixel and in the image mean.
#[test]
fn point_and_area_lights_together_agree_with_path() {
    let text = std::fs::read_to_string(bdpm_suite::scene_path("cornell-box.toml"))
        .expect("the scene file");
    let text = text.replace(
        "[material.white]",
        "[[light]]\nposition = [0.4, 0.5, 0.3]\nflux = [2.0, 2.0, 2.0]\n\n[material.white]",
    );
    let (mut scene, mut settings) = crate::specular::load(&text);
    scene.set_resolution(20, 20).expect("valid resolution");
    (settings.width, settings.height) = (20, 20);
    settings.sampler = bdpm_integrator::RenderSettings::default().sampler;
    settings.radius = Some(0.01);
    let reference = render(&scene, &with_mode(&settings, "path", 512, 8, 1));
    let mut failures = Vec::new();
    for mode in ["light", "bdd0", "bdd1", "optimal-path", "balance", "camis"] {
        let s = with_mode(&settings, mode, 24, 4, 50_000);
        let film = render(&scene, &s);
        let (within, diff, se) = bdpm_suite::films_agree(&film, &reference, 4.0);
        eprintln!("{mode:>16}: within {within:.4}, mean {diff:+.4} ± {se:.4}");
        if !(within >= 0.98 && diff.abs() < (4.0 * se).max(0.01) && se < 0.01) {
            failures.push(format!("{mode}: within {within}, mean {diff:+} ± {se}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A room whose wall z = 0 is a perfect mirror, lit by a small two-sided area light, against
/// the room twice as long with the mirrored light added (as the point-light test in
/// `specular`): seen in the mirror (Le through a delta vertex), lit through it (area light →
/// mirror → x₀, which only the merge at x₀ samples in the mix) and lit directly.
#[test]
fn an_area_light_seen_in_and_lighting_through_a_mirror() {
    use crate::specular::{load, quad, room};
    let render_table = "[render]\nresolution = [24, 24]\nseed = 3\nradius = 0.004\n\n";
    let camera = "[camera]\nposition = [0.5, 0.5, 0.9]\nlook_at = [0.5, 0.45, 0.0]\n\
                  up = [0.0, 1.0, 0.0]\nvfov = 70\n\n";
    let materials = "[material.walls]\nkd = 0.5\n\n[material.mirror]\ntype = \"mirror\"\n\n\
                     [material.lamp]\nkd = 0.0\nemission = 20.0\ntwo_sided_emission = true\n\n";
    let lamp = |z: f64| {
        let (x0, x1, y) = (0.25, 0.35, 0.8);
        quad(
            "lamp",
            [
                [x0, y, z - 0.05],
                [x1, y, z - 0.05],
                [x1, y, z + 0.05],
                [x0, y, z + 0.05],
            ],
        )
    };
    let mirrored = format!(
        "{render_table}{camera}{materials}{}{}",
        lamp(0.55),
        room(0.0, 1.0, "mirror")
    );
    let unfolded = format!(
        "{render_table}{camera}{materials}{}{}{}",
        lamp(0.55),
        lamp(-0.55),
        room(-1.0, 1.0, "walls")
    );
    let (scene_m, settings) = load(&mirrored);
    let (scene_u, _) = load(&unfolded);
    let mut failures = Vec::new();
    // Not `light`: its light tracing cannot reach the camera through the mirror, so it misses
    // the indirect light seen in it (as with point lights, docs/results.md).
    for mode in ["path", "bdd0", "bdd1", "balance", "optimal"] {
        let passes = if mode == "path" { 256 } else { 64 };
        let s = with_mode(&settings, mode, passes, 4, 60_000);
        let (a, b) = (render(&scene_m, &s), render(&scene_u, &s));
        let (within, diff, se) = bdpm_suite::films_agree(&a, &b, 4.0);
        eprintln!("{mode:>8}: within {within:.4}, mean {diff:+.4} ± {se:.4}");
        assert_eq!(a.dropped() + b.dropped(), 0, "{mode}");
        // `path` lights the walls through the mirror only when a BDF sample hits the small
        // lamp there (no light sample reaches through a mirror): rare, large values, a
        // heavy-tailed estimate whose typical render lies below its expectation in 8 % of the
        // pixels (docs/results.md, "Area lights"), so `path` is held to the image mean here.
        let pixels_ok = mode == "path" || within >= 0.98;
        if !(pixels_ok && diff.abs() < (4.0 * se).max(0.005) && se < 0.015) {
            failures.push(format!("{mode}: within {within}, mean {diff:+} ± {se}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The measurement behind `bdpm_scene::SPHERICAL_MIN` (docs/method-notes.md, "Area lights:
/// sampling"), not a check, so ignored by default:
/// `cargo test --release -p bdpm-suite --test suite spherical_sampling_threshold -- --ignored --nocapture`.
/// At the first surface seen through each pixel centre of scenes/cornell-box.toml and
/// scenes/cornell-box-small-light.toml (128², one thread), 64 one-sample estimates of the
/// area lights' direct light (the light sample with its shadow ray) for each threshold: the
/// sum over pixels of one estimate's relative variance (Var/mean², luminance; dominated by
/// penumbrae), the summed variance over the summed mean² (dominated by the brightest pixels,
/// near the light), the wall time of all of them (least of 3 runs) and each one's efficiency
/// 1/(V·time) against area sampling's.
#[test]
#[ignore]
fn spherical_sampling_threshold() {
    use bdpm_geometry::Rng;
    use std::time::Instant;
    for name in ["cornell-box.toml", "cornell-box-small-light.toml"] {
        let (mut scene, _) = load(name, 128, 128);
        let mut base = None;
        for min in [f64::INFINITY, 2.0, 1.0, 0.5, 0.2, 0.1, 0.05, 0.0] {
            scene.set_spherical_min(min);
            let mut time = f64::INFINITY;
            let mut rel_v = (0.0, 0.0);
            for _ in 0..3 {
                let start = Instant::now();
                rel_v = direct_relative_variance(
                    &scene,
                    64,
                    &mut Rng::new(7, bdpm_geometry::Domain::Other, [0; 3]),
                );
                time = time.min(start.elapsed().as_secs_f64());
            }
            let (v0, w0, t0) = *base.get_or_insert((rel_v.0, rel_v.1, time));
            let (v, w) = (rel_v.0 / v0, rel_v.1 / w0);
            let t = time / t0;
            eprintln!(
                "{name}: Ω_min {min:>5}: Σ relV {v:.3}×, ΣV/Σmean² {w:.3}×, time {t:.3}× ({time:.3} s), efficiency {:.3}× and {:.3}×",
                1.0 / (v * t),
                1.0 / (w * t)
            );
        }
    }
}

/// Over the pixel centres' first surfaces, of one light-sample estimate of the area lights'
/// direct light (luminance), from `n` estimates each: (Σ Var/mean², Σ Var/Σ mean²).
fn direct_relative_variance(
    scene: &bdpm_scene::Scene,
    n: u32,
    rng: &mut bdpm_geometry::Rng,
) -> (f64, f64) {
    let cam = scene.camera();
    let (w, h) = (128, 128);
    let (mut total, mut var, mut mean2) = (0.0, 0.0, 0.0);
    for y in 0..h {
        for x in 0..w {
            let dir = cam.ray_direction(x as f32 + 0.5, y as f32 + 0.5);
            let Some(hit) = scene
                .geometry()
                .intersect(cam.position(), dir, f32::INFINITY)
            else {
                continue;
            };
            let sh = scene.shade(&hit, -dir);
            let (mut sum, mut sum2) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let c = bdpm_suite::lum(scene.direct_area(&sh, -dir, rng.uniform3(), false)) as f64;
                sum += c;
                sum2 += c * c;
            }
            let mean = sum / n as f64;
            if mean > 0.0 {
                let v = (sum2 / n as f64 - mean * mean).max(0.0);
                total += v / (mean * mean);
                var += v;
                mean2 += mean * mean;
            }
        }
    }
    (total, var / mean2)
}

/// The stiff scene (scenes/cornell-box-small-light.toml) seen close up where the back wall
/// meets the 5 cm light, whose triangles cover up to about 2 sr there: `path` (light samples
/// weighed against BDF hits with `emitter_pdf`) and `light` (light samples alone) with
/// solid-angle sampling from 0.2 sr agree with `path` under area sampling everywhere, pixel by
/// pixel and in the image mean. A density that sampling and `emitter_pdf` disagreed on, or a
/// sampler not uniform in solid angle, would bias the first two.
#[test]
fn solid_angle_and_area_sampling_agree_near_a_small_light() {
    let text = std::fs::read_to_string(bdpm_suite::scene_path("cornell-box-small-light.toml"))
        .expect("the scene file");
    let text = text
        .replace("position = [0.0, 0.0, 3.9]", "position = [0.0, 0.6, -0.3]")
        .replace("look_at = [0.0, 0.0, 2.9]", "look_at = [0.0, 0.9, -1.0]")
        .replace("vfov = 39.3077", "vfov = 30");
    let (mut scene, mut settings) = crate::specular::load(&text);
    scene.set_resolution(16, 16).expect("valid resolution");
    (settings.width, settings.height) = (16, 16);
    settings.sampler = bdpm_integrator::RenderSettings::default().sampler;
    let (mut area, _) = crate::specular::load(&text);
    area.set_resolution(16, 16).expect("valid resolution");
    area.set_spherical_min(f64::INFINITY);
    let reference = render(&area, &with_mode(&settings, "path", 256, 4, 1));
    let mut failures = Vec::new();
    for mode in ["path", "light"] {
        let film = render(&scene, &with_mode(&settings, mode, 128, 4, 20_000));
        let (within, diff, se) = bdpm_suite::films_agree(&film, &reference, 4.0);
        eprintln!("{mode:>6}: within {within:.4}, mean {diff:+.4} ± {se:.4}");
        // 0.015: `path` here has 0.0124 with a pixel's channels taken as fully correlated
        // (`bdpm_suite::films_agree`); the cap of 0.01 was set on the smaller standard error
        // that summed them as independent.
        if !(within >= 0.98 && diff.abs() < 4.0 * se && se < 0.015) {
            failures.push(format!("{mode}: within {within}, mean {diff:+} ± {se}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A textured emitter with a closed form (issue 46, item 1): a 1.4 m × 0.6 m panel 1 m above a
/// Lambert floor (kd 0.5), facing down, black (kd 0), x from −0.5 to 0.9 m, whose emissive
/// texture is two texels read at u = x + ½ (clamp to edge): Le = 1 on its part x < 0 and 4 on
/// the larger part x > 0, blended bilinearly between the texel centres (u = ¼, ¾). Nothing
/// else reflects, so
/// - seen from below, each pixel is the mean of Le(u) over its footprint on the panel, and
/// - the floor's radiance is kd·Σ Le_half·F_half: the two halves' form factors from the floor
///   point, the closed form of a rectangle parallel to a point's plane. The image is a
///   one-pixel-wide column along the line under the two parts' border: each pixel's
///   footprint is symmetric about it, so the bilinear blend (odd about the border) adds
///   exactly nothing to its mean, and the two sharp parts are exact there. The parts are
///   unequal, so light samples and BDF hits that took the triangle's mean Le instead of Le at
///   their point miss the floor's mean by 8 standard errors (and the camera's by hundreds).
///
/// `path` (MIS with BDF hits on the emitter), `light` and BDPM modes: ≥ 95 % of the pixels
/// within 4 standard errors (all but one of the floor's 24) and the image mean within 4 of its
/// own, below 1 % of the mean.
#[test]
fn a_textured_emitter_seen_directly_and_lighting_a_floor_is_exact() {
    use bdpm_scene::{Camera, EmissionTextures, Material, Scene, Texture, Wrap};
    use glam::{Vec2, Vec3};
    let (x0, x1, b, h, kd) = (-0.5f64, 0.9f64, 0.3f64, 1.0f64, 0.5f64);
    let (left, right, factor) = (0.25f32, 1.0f32, 4.0f32);
    let le = |u: f64| {
        // The bilinear blend of two texels with centres at u = ¼ and ¾, clamped beyond.
        let t = ((u - 0.25) / 0.5).clamp(0.0, 1.0);
        f64::from(factor) * (f64::from(left) * (1.0 - t) + f64::from(right) * t)
    };
    let scene = |camera: Camera| {
        let mut mesh = bdpm_geometry::TriangleMesh::default();
        mesh.push_rect(Vec3::ZERO, Vec3::Z * 20.0, Vec3::X * 20.0, 0);
        let centre = Vec3::new((x0 + x1) as f32 / 2.0, h as f32, 0.0);
        let half = Vec3::X * ((x1 - x0) / 2.0) as f32;
        mesh.push_rect(centre, half, Vec3::Z * b as f32, 1);
        let geometry = bdpm_geometry::Geometry::new(mesh).expect("geometry");
        let texcoords = (0..geometry.triangle_count() as u32)
            .map(|t| geometry.vertices(t).map(|p| Vec2::new(p.x + 0.5, 0.5)))
            .collect();
        let lambert = |k: f32| bdpm_bdf::Bdf::lambert(Vec3::splat(k)).expect("albedo");
        let materials = vec![
            Material::new("floor", lambert(kd as f32)),
            Material::new("panel", lambert(0.0)).with_emission(Vec3::splat(factor), false),
        ];
        let texels = vec![Vec3::splat(left), Vec3::splat(right)];
        let texture = Texture::new(2, 1, texels, Wrap::ClampToEdge, Wrap::ClampToEdge);
        Scene::new(geometry, materials, Vec::new(), camera)
            .and_then(|s| {
                s.with_emission_textures(EmissionTextures {
                    textures: vec![None, Some(std::sync::Arc::new(texture.expect("texels")))],
                    texcoords,
                })
            })
            .expect("scene")
    };
    let eye = Vec3::new(0.0, 0.5, 0.0);
    let up_view = scene(Camera::look_at(eye, Vec3::Y, Vec3::Z, 40.0, 12, 6).expect("camera"));
    let down_view = scene(Camera::look_at(eye, Vec3::ZERO, Vec3::Z, 70.0, 1, 24).expect("camera"));
    // Each pixel's exact mean: an s × s grid of rays through the pixel, each ray's value
    // closed-form (Le at its panel point; the floor's kd·Σ Le·F at its floor point).
    let pixel_means = |s: &Scene, value: &dyn Fn(f64, f64) -> f64, plane_y: f64| {
        let cam = s.camera();
        let n = 32;
        let mut out = Vec::new();
        for y in 0..cam.height() {
            for x in 0..cam.width() {
                let mut sum = 0.0;
                for j in 0..n {
                    for i in 0..n {
                        let fx = x as f32 + (i as f32 + 0.5) / n as f32;
                        let fy = y as f32 + (j as f32 + 0.5) / n as f32;
                        let d = cam.ray_direction(fx, fy).as_dvec3();
                        let t = (plane_y - f64::from(eye.y)) / d.y;
                        sum += value(t * d.x, t * d.z);
                    }
                }
                out.push(sum / f64::from(n * n));
            }
        }
        out
    };
    let seen = pixel_means(
        &up_view,
        &|x, z| {
            if x > x0 && x < x1 && z.abs() < b {
                le(x + 0.5)
            } else {
                0.0
            }
        },
        h,
    );
    // The form factor from a point to the rectangle [xa, xb] × [za, zb] (relative to it) in a
    // parallel plane at height h, by the corner formula with signs.
    let corner = |x: f64, z: f64| {
        let (p, q) = (x / h, z / h);
        let (sp, sq) = ((1.0 + p * p).sqrt(), (1.0 + q * q).sqrt());
        (p / sp * (q / sp).atan() + q / sq * (p / sq).atan()) / (2.0 * std::f64::consts::PI)
    };
    let form = |xa: f64, xb: f64, za: f64, zb: f64| {
        corner(xb, zb) - corner(xa, zb) - corner(xb, za) + corner(xa, za)
    };
    let floor = pixel_means(
        &down_view,
        &|x, z| {
            kd * (le(0.0) * form(x0 - x, -x, -b - z, b - z)
                + le(1.0) * form(-x, x1 - x, -b - z, b - z))
        },
        0.0,
    );
    let mut failures = Vec::new();
    for mode in ["path", "light", "bdd0", "bdd1", "optimal-path", "balance"] {
        for (name, view, exact) in [("seen", &up_view, &seen), ("floor", &down_view, &floor)] {
            let mut settings = bdpm_integrator::RenderSettings {
                width: view.camera().width(),
                height: view.camera().height(),
                radius: Some(0.01),
                ..Default::default()
            };
            settings.seed = 7;
            let film = render(view, &with_mode(&settings, mode, 32, 16, 20_000));
            let (mean, se) = (film.mean(), film.standard_error());
            let within = mean
                .iter()
                .zip(&se)
                .zip(exact.iter())
                .filter(|((m, s), e)| (m.x - **e).abs() <= 4.0 * s.x + 1e-5 * **e)
                .count() as f64
                / exact.len() as f64;
            let n = exact.len() as f64;
            let diff = mean.iter().map(|m| m.x).sum::<f64>() / n - exact.iter().sum::<f64>() / n;
            let se_mean = se.iter().map(|s| s.x * s.x).sum::<f64>().sqrt() / n;
            let rel = se_mean * n / exact.iter().sum::<f64>();
            eprintln!("{mode:>12} {name}: within {within:.3}, mean {diff:+.5} ± {se_mean:.5}");
            if within < 0.95 || diff.abs() > 4.0 * se_mean + 1e-6 || rel > 0.01 {
                failures.push(format!(
                    "{mode} {name}: within {within}, {diff} ± {se_mean}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// `direct_boost` in a scene with area lights (the integrator's `direct` module): every pixel
/// that the light's outline crosses (found here independently: a 16 × 16 lattice of camera
/// rays per pixel, some of whose first hits emit and some not, at least 2 of each) takes more
/// than one direct-light sample per camera sample, and those pixels' summed per-pass variance
/// falls at least 3-fold against one direct-light sample. Before the 5 × 5 probe lattice, the
/// four probes at the pixel's quarter centres missed the outline where it passed outside them.
#[test]
fn the_light_s_outline_takes_more_direct_light_samples() {
    let (scene, settings) = load("cornell-box.toml", 64, 64);
    let cam = scene.camera();
    let emits = |x: f32, y: f32| {
        let hit = scene.walk_to_non_delta(
            cam.position(),
            cam.ray_direction(x, y),
            bdpm_bdf::Transport::Radiance,
            || 0.5,
        );
        hit.is_some_and(|w| scene.emitted(w.sh.prim, w.sh.bary, w.wo).max_element() > 0.0)
    };
    let outline: Vec<(u32, u32)> = (0..64 * 64)
        .map(|i| (i % 64, i / 64))
        .filter(|&(x, y)| {
            let n = (0..256)
                .filter(|k| {
                    let (dx, dy) = ((k % 16) as f32 + 0.5, (k / 16) as f32 + 0.5);
                    emits(x as f32 + dx / 16.0, y as f32 + dy / 16.0)
                })
                .count();
            (2..=254).contains(&n)
        })
        .collect();
    assert!(outline.len() >= 8, "the light's outline: {outline:?}");
    let mut s = with_mode(&settings, "optimal-path", 32, 4, 20_000);
    s.direct_boost = 16;
    let renderer = bdpm_integrator::Renderer::new(&scene, &s).unwrap_or_else(|e| panic!("{e}"));
    let direct = renderer.direct_samples().expect("the outline is boosted");
    let missed: Vec<_> = outline
        .iter()
        .filter(|&&(x, y)| direct.at(x, y) == 1)
        .collect();
    eprintln!(
        "{} outline pixels, {} boosted in all, missed {missed:?}",
        outline.len(),
        direct.boosted()
    );
    assert!(
        missed.is_empty(),
        "outline pixels with one sample: {missed:?}"
    );
    let variance = |film: &bdpm_integrator::Film| summed_pass_variance(film, &outline, 64);
    let boosted = variance(&bdpm_suite::render_with(&renderer));
    s.direct_boost = 1;
    let plain = variance(&render(&scene, &s));
    eprintln!("outline per-pass variance {boosted:.4e}, one sample {plain:.4e}");
    assert!(boosted * 3.0 < plain, "{boosted:.4e} against {plain:.4e}");
}

/// The per-pass variance of `film`'s luminance summed over `pixels` of an image `width` wide.
fn summed_pass_variance(film: &bdpm_integrator::Film, pixels: &[(u32, u32)], width: u32) -> f64 {
    let v = film.pass_variance();
    pixels
        .iter()
        .map(|&(x, y)| bdpm_bdf::luminance(v[(y * width + x) as usize].as_vec3()) as f64)
        .sum()
}

/// The point where the ray from `origin` along `dir` meets the scene, if it is glossy: its
/// shading and the mirror direction of `dir` about its normal.
fn glossy_mirror(
    scene: &bdpm_scene::Scene,
    origin: glam::Vec3,
    dir: glam::Vec3,
) -> Option<(bdpm_scene::Shading, glam::Vec3)> {
    let hit = scene.geometry().intersect(origin, dir, f32::INFINITY)?;
    let sh = scene.shade(&hit, -dir);
    if scene.bdf_at(&sh).is_lambert() {
        return None;
    }
    let n = sh.frame.n;
    let mirror = 2.0 * n.dot(-dir) * n + dir;
    Some((sh, mirror))
}

/// Whether the ray from `sh` along `dir` meets an emitter.
fn meets_emitter(scene: &bdpm_scene::Scene, sh: &bdpm_scene::Shading, dir: glam::Vec3) -> bool {
    scene
        .geometry()
        .intersect(scene.spawn(sh, dir), dir, f32::INFINITY)
        .is_some_and(|h| scene.emitted(h.prim, h.uv, -dir).max_element() > 0.0)
}

/// The light's reflection in the glossy back wall of the glossy box: its pixels take more
/// direct-light samples, each weighed against a BDF ray of its own (the light sample alone
/// through a 1.5° lobe is a rare event), and their per-pass variance falls by more than half.
#[test]
fn the_light_s_glossy_reflection_takes_more_direct_light_samples() {
    let (scene, settings) = load("cornell-box-glossy.toml", 64, 64);
    let cam = scene.camera();
    // Pixels whose centre sees a glossy surface reflecting the emitter in its mirror direction.
    let reflects_light = |x: f32, y: f32| {
        glossy_mirror(&scene, cam.position(), cam.ray_direction(x, y))
            .is_some_and(|(sh, mirror)| meets_emitter(&scene, &sh, mirror))
    };
    let pixels: Vec<(u32, u32)> = (0..64 * 64)
        .map(|i| (i % 64, i / 64))
        .filter(|&(x, y)| reflects_light(x as f32 + 0.5, y as f32 + 0.5))
        .collect();
    assert!(pixels.len() >= 8, "the light's reflection: {pixels:?}");
    let mut s = with_mode(&settings, "optimal-path", 32, 4, 20_000);
    s.direct_boost = 16;
    let renderer = bdpm_integrator::Renderer::new(&scene, &s).unwrap_or_else(|e| panic!("{e}"));
    let direct = renderer
        .direct_samples()
        .expect("the reflection is boosted");
    let boosted = pixels.iter().filter(|&&(x, y)| direct.at(x, y) > 1).count();
    let variance = |film: &bdpm_integrator::Film| summed_pass_variance(film, &pixels, 64);
    let with_boost = variance(&bdpm_suite::render_with(&renderer));
    s.direct_boost = 1;
    let plain = variance(&render(&scene, &s));
    eprintln!(
        "{} reflection pixels, {boosted} boosted; per-pass variance {with_boost:.4e}, one sample {plain:.4e}",
        pixels.len()
    );
    assert!(
        boosted * 2 >= pixels.len(),
        "{boosted} of {} boosted",
        pixels.len()
    );
    assert!(
        with_boost * 2.0 < plain,
        "{with_boost:.4e} against {plain:.4e}"
    );
}

/// The light's reflection in the back wall seen in the glossy side walls (camera → side wall →
/// back wall → light, BDD=1's one-bounce paths at a glossy x₁; pixels with a point of a 4 × 4
/// grid whose mirror path twice reflected meets the light): those pixels take more than
/// one x₁ per camera sample (crate::one_bounce), and where they take one direct-light sample
/// (so that only x₁'s count differs) their per-pass variance falls by more than half. The
/// image agrees pixel by pixel with the render that takes one x₁ everywhere.
#[test]
fn the_light_s_double_glossy_reflection_takes_more_x1() {
    let (scene, settings) = load("cornell-box-glossy.toml", 64, 64);
    let cam = scene.camera();
    let twice_reflected = |x: f32, y: f32| {
        let Some((sh0, v0)) = glossy_mirror(&scene, cam.position(), cam.ray_direction(x, y)) else {
            return false;
        };
        glossy_mirror(&scene, scene.spawn(&sh0, v0), v0)
            .is_some_and(|(sh1, v1)| meets_emitter(&scene, &sh1, v1))
    };
    let pixels: Vec<(u32, u32)> = (0..64 * 64)
        .map(|i| (i % 64, i / 64))
        .filter(|&(x, y)| {
            (0..16).any(|k| {
                let (dx, dy) = ((k % 4) as f32 + 0.5, (k / 4) as f32 + 0.5);
                twice_reflected(x as f32 + dx / 4.0, y as f32 + dy / 4.0)
            })
        })
        .collect();
    assert!(pixels.len() >= 8, "the double reflection: {pixels:?}");
    let mut s = with_mode(&settings, "optimal-path", 32, 4, 20_000);
    s.direct_boost = 16;
    let renderer = bdpm_integrator::Renderer::new(&scene, &s).unwrap_or_else(|e| panic!("{e}"));
    let n = renderer
        .one_bounce_samples()
        .expect("the double reflection takes more x1");
    let m = |x, y| renderer.direct_samples().map_or(1, |d| d.at(x, y));
    let boosted = pixels.iter().filter(|&&(x, y)| n.at(x, y) > 1).count();
    let only_x1: Vec<(u32, u32)> = pixels
        .iter()
        .copied()
        .filter(|&(x, y)| n.at(x, y) > 1 && m(x, y) == 1)
        .collect();
    let with_boost = bdpm_suite::render_with(&renderer);
    s.direct_boost = 1;
    let plain = render(&scene, &s);
    let (v_boost, v_plain) = (
        summed_pass_variance(&with_boost, &only_x1, 64),
        summed_pass_variance(&plain, &only_x1, 64),
    );
    let (within, diff, se) = bdpm_suite::films_agree(&with_boost, &plain, 4.0);
    eprintln!(
        "{} double-reflection pixels, {boosted} take more x1, {} of them one direct sample: \
         per-pass variance {v_boost:.4e} against {v_plain:.4e}; images within {within:.4}, \
         mean {diff:+.4} ± {se:.4}",
        pixels.len(),
        only_x1.len()
    );
    assert!(
        boosted * 2 >= pixels.len(),
        "{boosted} of {} boosted",
        pixels.len()
    );
    assert!(only_x1.len() >= 4, "{only_x1:?}");
    assert!(
        v_boost * 2.0 < v_plain,
        "{v_boost:.4e} against {v_plain:.4e}"
    );
    assert!(
        within >= 0.98 && diff.abs() < 4.0 * se,
        "{within} {diff} {se}"
    );
}
