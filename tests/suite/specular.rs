//! Mirrors and glass in the BDPM modes (issue 45): a planar mirror against the room it
//! mirrors, and a glass sphere's caustic against the `light` reference.

use std::path::Path;

use bdpm_integrator::{Film, RenderSettings};
use bdpm_load::load_scene_str;
use bdpm_scene::Scene;
use bdpm_suite::{films_agree, render, with_mode};

/// A `[[shape]]` quad of `material` through four corners.
pub(crate) fn quad(material: &str, corners: [[f64; 3]; 4]) -> String {
    let v: Vec<String> = corners
        .iter()
        .map(|c| format!("[{}, {}, {}]", c[0], c[1], c[2]))
        .collect();
    format!(
        "[[shape]]\ntype = \"quad\"\nmaterial = \"{material}\"\nvertices = [{}]\n\n",
        v.join(", ")
    )
}

/// The box x, y ∈ [0, 1], z ∈ [z0, z1] of quads: floor, ceiling and the x walls of `walls`,
/// the end walls z = z0 of `near` and z = z1 of `walls`.
pub(crate) fn room(z0: f64, z1: f64, near: &str) -> String {
    let w = "walls";
    [
        quad(w, [[0., 0., z0], [1., 0., z0], [1., 0., z1], [0., 0., z1]]),
        quad(w, [[0., 1., z0], [0., 1., z1], [1., 1., z1], [1., 1., z0]]),
        quad(w, [[0., 0., z0], [0., 0., z1], [0., 1., z1], [0., 1., z0]]),
        quad(w, [[1., 0., z0], [1., 1., z0], [1., 1., z1], [1., 0., z1]]),
        quad(
            near,
            [[0., 0., z0], [0., 1., z0], [1., 1., z0], [1., 0., z0]],
        ),
        quad(w, [[0., 0., z1], [1., 0., z1], [1., 1., z1], [0., 1., z1]]),
    ]
    .concat()
}

pub(crate) fn light(p: [f64; 3]) -> String {
    format!(
        "[[light]]\nposition = [{}, {}, {}]\nflux = [1.0, 1.0, 1.0]\n\n",
        p[0], p[1], p[2]
    )
}

const RENDER: &str = "[render]\nresolution = [24, 24]\nseed = 3\nradius = 0.004\n\n";

pub(crate) fn load(text: &str) -> (Scene, RenderSettings) {
    let loaded = load_scene_str(text, Path::new("."), Path::new("inline.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    (loaded.scene, loaded.settings)
}

/// A room whose wall z = 0 is a perfect mirror, seen from inside, looking at the mirror, and
/// the room twice as long (z ∈ [−1, 1]) with the mirror image of the light added: the camera
/// sees the same radiance in both, pixel by pixel (unfolding a perfect planar mirror). It
/// takes every path kind through the mirror: seen in it (…–D–S–E), lit through it (L–S–D…),
/// and a mirror between x₀ and x₁, which only the merge at x₀ samples.
#[test]
fn a_planar_mirror_shows_the_room_it_mirrors() {
    mirror_against_unfolded("kd = 0.5", &["bdd0", "bdd1", "balance", "optimal"]);
}

/// The same with glossy walls: a glossy x₀ sees x₁ through the mirror, and BDD=1 follows the
/// mirror to it (with `Mix::chain_w1`, the lobe's share of x₀'s albedo; all of it in `bdd1`).
#[test]
fn a_planar_mirror_shows_the_glossy_room_it_mirrors() {
    mirror_against_unfolded(
        "kd = 0.25\ngr = 0.5\ndelta = 12",
        &["bdd1", "balance", "optimal"],
    );
}

/// The room whose wall z = 0 is a perfect mirror and its unfolding (the room twice as long with
/// the mirrored light added), walls of `walls` (a material's keys), the same camera looking at
/// the mirror; and the mirror room's settings.
fn mirror_rooms(walls: &str) -> (Scene, Scene, RenderSettings) {
    let camera = "[camera]\nposition = [0.5, 0.5, 0.9]\nlook_at = [0.5, 0.45, 0.0]\n\
                  up = [0.0, 1.0, 0.0]\nvfov = 70\n\n";
    let walls = format!("[material.walls]\n{walls}\n\n");
    let mirror = "[material.mirror]\ntype = \"mirror\"\n\n";
    let lit = [0.3, 0.75, 0.55];
    let mirrored = format!(
        "{RENDER}{camera}{}{walls}{mirror}{}",
        light(lit),
        room(0.0, 1.0, "mirror")
    );
    let unfolded = format!(
        "{RENDER}{camera}{}{}{walls}{}",
        light(lit),
        light([lit[0], lit[1], -lit[2]]),
        room(-1.0, 1.0, "walls")
    );
    let (scene_m, settings) = load(&mirrored);
    let (scene_u, _) = load(&unfolded);
    (scene_m, scene_u, settings)
}

/// Renders the mirror room and its unfolding with walls of `walls` (a material's keys) in each
/// of `modes` and checks that they agree pixel by pixel.
fn mirror_against_unfolded(walls: &str, modes: &[&str]) {
    let (scene_m, scene_u, settings) = mirror_rooms(walls);
    let mut failures = Vec::new();
    for &mode in modes {
        let s = with_mode(&settings, mode, 16, 4, 60_000);
        let (a, b) = (render(&scene_m, &s), render(&scene_u, &s));
        let (within, diff, se) = films_agree(&a, &b, 4.0);
        eprintln!("{mode:>8}: within {within:.4}, mean {diff:+.4} ± {se:.4}");
        assert_eq!(a.dropped() + b.dropped(), 0, "{mode}");
        if !(within >= 0.98 && diff.abs() < (4.0 * se).max(0.005) && se < 0.01) {
            failures.push(format!("{mode}: within {within}, mean {diff:+} ± {se}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Whether any of the centre and corners of pixel (x, y) sees the glass first.
pub(crate) fn sees_glass(scene: &Scene, x: u32, y: u32) -> bool {
    let cam = scene.camera();
    [(0.5, 0.5), (0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
        .iter()
        .any(|(dx, dy)| {
            let d = cam.ray_direction(x as f32 + dx, y as f32 + dy);
            scene
                .geometry()
                .intersect(cam.position(), d, f32::INFINITY)
                .is_some_and(|h| scene.is_delta(h.material))
        })
}

/// [`films_agree`] over the pixels where `keep` is true: the fraction of their channels within
/// `k` combined standard errors, and the relative difference of the means with its error.
pub(crate) fn agree_where(a: &Film, b: &Film, keep: &[bool], k: f64) -> (f64, f64, f64) {
    let (ma, mb) = (a.mean(), b.mean());
    let (sa, sb) = (a.standard_error(), b.standard_error());
    let (mut within, mut total) = (0usize, 0usize);
    let (mut sum_a, mut sum_b, mut var) = (0.0f64, 0.0f64, 0.0f64);
    for i in (0..ma.len()).filter(|&i| keep[i]) {
        for c in 0..3 {
            let s2 = sa[i][c].powi(2) + sb[i][c].powi(2);
            within += usize::from((ma[i][c] - mb[i][c]).abs() <= k * s2.sqrt());
            total += 1;
            sum_a += ma[i][c];
            sum_b += mb[i][c];
            var += s2;
        }
    }
    (
        within as f64 / total as f64,
        (sum_a - sum_b) / sum_b,
        var.sqrt() / sum_b,
    )
}

/// A glass sphere over the floor of a closed room focuses the light onto the floor: every
/// BDPM mode (merging the caustic at x₀, or at x₁ when a wall sees it) agrees with the `light`
/// reference (light tracing connects each photon's floor arrival to the camera, code that
/// shares nothing with the merges) wherever the camera sees no glass; and the modes agree
/// with each other through the glass.
#[test]
fn a_glass_sphere_caustic_agrees_with_light_tracing() {
    let camera = "[camera]\nposition = [0.5, 0.6, 0.98]\nlook_at = [0.5, 0.1, 0.4]\n\
                  up = [0.0, 1.0, 0.0]\nvfov = 60\n\n";
    let materials = "[material.walls]\nkd = 0.5\n\n\
                     [material.glass]\ntype = \"dielectric\"\nior = 1.5\n\n";
    let sphere = "[[shape]]\ntype = \"sphere\"\ncenter = [0.5, 0.25, 0.45]\nradius = 0.2\n\
                  subdivisions = 16\nmaterial = \"glass\"\n\n";
    let text = format!(
        "{RENDER}{camera}{}{materials}{sphere}{}",
        light([0.5, 0.85, 0.45]),
        room(0.0, 1.0, "walls")
    );
    let (scene, settings) = load(&text);
    let (w, h) = (scene.camera().width(), scene.camera().height());
    let no_glass: Vec<bool> = (0..w * h)
        .map(|i| !sees_glass(&scene, i % w, i / w))
        .collect();
    let glass = no_glass.iter().filter(|k| !**k).count();
    assert!(glass > 20 && glass < 200, "{glass} pixels see the glass");
    let reference = render(&scene, &with_mode(&settings, "light", 48, 4, 100_000));
    let bdd0 = render(&scene, &with_mode(&settings, "bdd0", 32, 4, 100_000));
    let every = vec![true; (w * h) as usize];
    let mut failures = Vec::new();
    for mode in ["bdd0", "bdd1", "balance", "optimal"] {
        let other;
        let film = if mode == "bdd0" {
            &bdd0
        } else {
            other = render(&scene, &with_mode(&settings, mode, 32, 4, 100_000));
            &other
        };
        assert_eq!(film.dropped(), 0, "{mode}");
        let (within, diff, se) = agree_where(film, &reference, &no_glass, 4.0);
        eprintln!("{mode:>8} vs light: within {within:.4}, mean {diff:+.4} ± {se:.4}");
        if !(within >= 0.98 && diff.abs() < (4.0 * se).max(0.005) && se < 0.01) {
            failures.push(format!(
                "{mode} vs light: within {within}, mean {diff:+} ± {se}"
            ));
        }
        let (within, diff, se) = agree_where(film, &bdd0, &every, 4.0);
        eprintln!("{mode:>8} vs bdd0: within {within:.4}, mean {diff:+.4} ± {se:.4}");
        if mode != "bdd0" && !(within >= 0.98 && diff.abs() < (4.0 * se).max(0.005)) {
            failures.push(format!(
                "{mode} vs bdd0: within {within}, mean {diff:+} ± {se}"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A furnace with a glass shell around its light: the sphere furnace (method.md §10: the inside
/// of a sphere of radius R = 1 m, Lambert albedo k = 0.5) with its point light at the centre,
/// enclosed in a clear glass shell (IOR 1.5, radii 0.24 and 0.25 m, concentric geodesic spheres
/// whose facets are parallel). The light's rays cross the shell along radii (each facet pair a
/// slab: displaced by micrometres, not turned), so the direct irradiance on the wall stays
/// Φ/(4πR²) everywhere, now brought only by photons through the glass (the shadow rays are
/// blocked); the wall's radiance is then uniform, and a lossless glass object in a uniform
/// isotropic radiance field is invisible. Every pixel, through the glass or not, must show
/// L = kΦ/(4π²R²(1 − k)). (The shell fills most of the view: `light` could not check this.)
#[test]
fn a_glass_shell_in_the_furnace_is_invisible() {
    let text = format!(
        "{}[camera]\nposition = [-0.5, 0.0, 0.0]\nlook_at = [0.5, 0.0, 0.0]\n\
         up = [0.0, 1.0, 0.0]\nvfov = 60\n\n{}\
         [material.inside]\nkd = 0.5\n\n[material.glass]\ntype = \"dielectric\"\nior = 1.5\n\n\
         [[shape]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n\
         subdivisions = 32\nfacing = \"inside\"\nmaterial = \"inside\"\n\n\
         [[shape]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 0.25\n\
         subdivisions = 32\nmaterial = \"glass\"\n\n\
         [[shape]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 0.24\n\
         subdivisions = 32\nfacing = \"inside\"\nmaterial = \"glass\"\n\n",
        RENDER.replace("radius = 0.004", "radius = 0.05"),
        light([0.0, 0.0, 0.0]),
    );
    let (scene, settings) = load(&text);
    let k = 0.5;
    let exact = k / (4.0 * std::f64::consts::PI.powi(2) * (1.0 - k));
    let (w, h) = (scene.camera().width(), scene.camera().height());
    let glass: Vec<bool> = (0..w * h)
        .map(|i| sees_glass(&scene, i % w, i / w))
        .collect();
    let seen = glass.iter().filter(|g| **g).count();
    assert!(seen > 30, "{seen} pixels see the glass");
    let mut failures = Vec::new();
    for mode in ["bdd1", "balance", "optimal"] {
        let film = render(&scene, &with_mode(&settings, mode, 24, 4, 150_000));
        assert_eq!(film.dropped(), 0, "{mode}");
        let (mean, se) = (film.mean(), film.standard_error());
        let n = mean.len() as f64;
        let m = mean.iter().map(|v| v.x).sum::<f64>() / n;
        let m_se = se.iter().map(|s| s.x * s.x).sum::<f64>().sqrt() / n;
        let within = |keep: bool| {
            let pixels: Vec<usize> = (0..mean.len()).filter(|&i| glass[i] == keep).collect();
            let ok = pixels
                .iter()
                .filter(|&&i| (mean[i].x - exact).abs() <= 4.0 * se[i].x);
            ok.count() as f64 / pixels.len() as f64
        };
        let (through, beside) = (within(true), within(false));
        let rel = m / exact - 1.0;
        eprintln!(
            "{mode:>8}: mean {rel:+.4} ± {:.4}, within 4σ: {through:.3} through the glass, \
             {beside:.3} beside it",
            m_se / exact
        );
        if !(rel.abs() < (4.0 * m_se / exact).max(0.01) && through >= 0.97 && beside >= 0.97) {
            failures.push(format!("{mode}: mean {rel:+}, within {through} / {beside}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The model-based weights' per-pixel inputs see through a planar mirror: a pixel that sees
/// the room in the mirror gets the ρ (and so N_eff) of its footprint on the x₀ behind the
/// mirror, which is the footprint the unfolded room's pixel has on the mirror image of that
/// x₀ (ray differentials reflected by the plane: equal up to rounding), and A, B of that x₀.
/// Before the table followed delta chains, these pixels had ρ = 0 and A = B = 0.
#[test]
fn the_pixel_table_sees_through_a_planar_mirror() {
    let (scene_m, scene_u, settings) = mirror_rooms("kd = 0.5");
    let mut s = with_mode(&settings, "optimal", 1, 4, 20_000);
    s.radius = Some(0.03);
    let table = |scene: &Scene| {
        bdpm_integrator::Renderer::new(scene, &s)
            .expect("valid settings")
            .pixel_table()
            .expect("optimal builds a table")
            .clone()
    };
    let (tm, tu) = (table(&scene_m), table(&scene_u));
    let (mut mirror_pixels, mut shared) = (0, 0);
    for y in 0..24 {
        for x in 0..24 {
            let cam = scene_m.camera();
            let d = cam.ray_direction(x as f32 + 0.5, y as f32 + 0.5);
            let hit = scene_m
                .geometry()
                .intersect(cam.position(), d, f32::INFINITY);
            if !hit.is_some_and(|h| scene_m.is_delta(scene_m.shade(&h, -d).material)) {
                continue;
            }
            mirror_pixels += 1;
            let (a, b) = (tm.get(x, y), tu.get(x, y));
            assert!(
                (a.overlap - b.overlap).abs() <= 1e-4 + 1e-3 * b.overlap,
                "pixel ({x}, {y}): rho {} through the mirror, {} unfolded",
                a.overlap,
                b.overlap
            );
            assert_eq!(a.camera_samples > 1.0, b.camera_samples > 1.0);
            assert!(
                a.terms.a > 0.0 && a.terms.b > 0.0,
                "pixel ({x}, {y}): A, B 0"
            );
            shared += usize::from(a.overlap > 0.05);
        }
    }
    eprintln!("{mirror_pixels} mirror pixels, {shared} with rho > 0.05");
    assert!(mirror_pixels > 200 && shared > mirror_pixels / 2);
}

/// Unpolarised Fresnel reflectance of a smooth interface into a medium of relative index
/// `eta` at the cosine `cos_i` of incidence (written here from the textbook formula, not the
/// code under test).
fn fresnel(cos_i: f64, eta: f64) -> f64 {
    let sin_t2 = (1.0 - cos_i * cos_i) / (eta * eta);
    let cos_t = (1.0 - sin_t2).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Energy through a glass slab: a camera outside an open room looks at it through a thin
/// plane-parallel slab (IOR 4, so that the faces reflect F ≈ 0.36 and the internal
/// reflections matter). Light that the front face reflects, or that leaves the slab towards
/// the camera after internal reflections, goes into the empty space behind the camera; what
/// gets through is (1 − F)² Σ F²ᵏ = (1 − F)/(1 + F) of the room's radiance, with F of the
/// pixel's angle of incidence at both faces (the η² of entering and leaving cancel), against
/// (1 − F)² = 0.41 without the internal reflections. Each pixel is checked against the room
/// rendered without the slab times that closed form, within 4σ. The slab is small and far
/// from the room, so the light it sends back into the room is below 10⁻⁴ of the image.
#[test]
fn a_glass_slab_transmits_its_closed_form() {
    let header = "[render]\nresolution = [24, 24]\nseed = 5\nradius = 0.01\n\n";
    let camera = "[camera]\nposition = [0.5, 0.5, 4.0]\nlook_at = [0.5, 0.45, 0.0]\n\
                  up = [0.0, 1.0, 0.0]\nvfov = 12\n\n";
    let walls = "[material.walls]\nkd = [0.6, 0.5, 0.4]\n\n";
    let w = "walls";
    let open_room = [
        quad(w, [[0., 0., 0.], [1., 0., 0.], [1., 0., 1.], [0., 0., 1.]]),
        quad(w, [[0., 1., 0.], [0., 1., 1.], [1., 1., 1.], [1., 1., 0.]]),
        quad(w, [[0., 0., 0.], [0., 0., 1.], [0., 1., 1.], [0., 1., 0.]]),
        quad(w, [[1., 0., 0.], [1., 1., 0.], [1., 1., 1.], [1., 0., 1.]]),
        quad(w, [[0., 0., 0.], [0., 1., 0.], [1., 1., 0.], [1., 0., 0.]]),
    ]
    .concat();
    let eta = 4.0;
    let slab = format!(
        "[material.glass]\ntype = \"dielectric\"\nior = {eta}\n\n[[shape]]\ntype = \"box\"\n\
         min = [0.3, 0.3, 3.8]\nmax = [0.7, 0.7, 3.801]\nmaterial = \"glass\"\n\n"
    );
    let base = format!(
        "{header}{camera}{}{walls}{open_room}",
        light([0.5, 0.8, 0.5])
    );
    let (plain, settings) = load(&base);
    let (glass, _) = load(&format!("{base}{slab}"));
    let cam = plain.camera();
    let mut failures = Vec::new();
    for mode in ["bdd0", "bdd1", "balance", "optimal", "path"] {
        let s = with_mode(&settings, mode, 16, 4, 60_000);
        let (a, b) = (render(&glass, &s), render(&plain, &s));
        let (ma, mb, sa, sb) = (a.mean(), b.mean(), a.standard_error(), b.standard_error());
        let (mut within, mut total) = (0usize, 0usize);
        let (mut sum_a, mut sum_b, mut var) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..ma.len() {
            let (x, y) = ((i % 24) as f32 + 0.5, (i / 24) as f32 + 0.5);
            let cos_i = f64::from(cam.ray_direction(x, y).z.abs());
            let f = fresnel(cos_i, eta);
            let t = (1.0 - f) / (1.0 + f);
            for c in 0..3 {
                let s = (sa[i][c].powi(2) + (t * sb[i][c]).powi(2)).sqrt();
                within += usize::from((ma[i][c] - t * mb[i][c]).abs() <= 4.0 * s);
                total += 1;
                (sum_a, sum_b, var) = (sum_a + ma[i][c], sum_b + t * mb[i][c], var + s * s);
            }
        }
        let (within, diff, se) = (
            within as f64 / total as f64,
            sum_a / sum_b - 1.0,
            var.sqrt() / sum_b,
        );
        eprintln!("slab {mode:>8}: within {within:.4}, mean {diff:+.4} ± {se:.4}");
        if !(within >= 0.98 && diff.abs() < 4.0 * se + 0.003 && se < 0.01) {
            failures.push(format!("{mode}: within {within}, mean {diff:+} ± {se}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The run report's account of the path kinds through mirrors and glass: none in a scene
/// without them; in the glass-caustic room, camera chains in every mode, photons through the
/// glass but for `path`, caustics merged at x₀ where the mode merges there, and BDD=1 through
/// the glass only where its weight can be non-zero (`bdd1`; Lambert walls give 0 otherwise).
#[test]
fn the_report_says_which_paths_through_glass_ran() {
    let (plain, settings) = bdpm_suite::load("cornell-lambert.toml", 8, 8);
    let s = with_mode(&settings, "balance", 1, 1, 1000);
    let ran = bdpm_integrator::Renderer::new(&plain, &s)
        .expect("valid")
        .paths_ran();
    assert_eq!(ran, bdpm_integrator::PathsRan::default());
    assert!(ran.summary().is_none());
    let (glass, settings) = bdpm_suite::load("glass-caustic.toml", 8, 8);
    for (mode, x1, photons, caustics) in [
        ("balance", false, true, true),
        ("bdd1", true, true, false),
        ("path", true, false, false),
    ] {
        let s = with_mode(&settings, mode, 1, 1, 1000);
        let ran = bdpm_integrator::Renderer::new(&glass, &s)
            .expect("valid")
            .paths_ran();
        assert_eq!(ran.delta_materials, 1, "{mode}");
        assert!(ran.camera_through_delta, "{mode}");
        assert_eq!(ran.x1_through_delta, x1, "{mode}");
        assert_eq!(ran.photons_through_delta, photons, "{mode}");
        assert_eq!(ran.caustics_merged_at_x0, caustics, "{mode}");
        assert!(
            ran.summary()
                .is_some_and(|l| l.contains("1 delta material)"))
        );
    }
}
