//! Stiff and extreme cases (method.md §11): every mode at a tiny resolution must give finite
//! output everywhere, drop no sample as non-finite, and keep its technique layers finite.
//! Where an exact answer exists it is checked elsewhere (tests/suite/furnace.rs); here the point is
//! that nothing blows up.

use std::path::Path;

use bdpm_integrator::{Film, Mode, Renderer, Stage};
use bdpm_load::load_scene_str;

/// A closed 1 m room (inward faces) with a block, seen from inside, parameterised by the parts
/// that the cases vary.
fn room(render: &str, materials: &str, light: &str, camera: &str, extra: &str) -> String {
    format!(
        r#"
[render]
resolution = [8, 8]
passes = 2
spp = 2
photons = 3000
{render}

[camera]
{camera}

{light}

{materials}

[[shape]]
type = "box"
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
facing = "inside"
material = "walls"

[[shape]]
type = "box"
min = [0.55, 0.0, 0.5]
max = [0.8, 0.3, 0.75]
material = "block"
{extra}
"#
    )
}

const CAMERA: &str = "position = [0.5, 0.5, 0.05]\nlook_at = [0.5, 0.5, 1.0]\nvfov = 70";
const LIGHT: &str = "[[light]]\nposition = [0.5, 0.9, 0.5]\nflux = [1.0, 1.0, 1.0]";
const LAMBERT: &str = "[material.walls]\nkd = 0.5\n[material.block]\nkd = [0.7, 0.4, 0.2]";
const GLOSSY: &str = "[material.walls]\nkd = 0.3\ngr = 0.6\ndelta = 1.5\n[material.block]\nkd = 0.2\ngr = 0.8\ndelta = 5";

/// Runs every mode on the scene text and checks that all outputs are finite.
fn survive(case: &str, text: &str) {
    let loaded = load_scene_str(text, Path::new("."), Path::new(&format!("<{case}>")))
        .unwrap_or_else(|e| panic!("{case}: {e}"));
    let (scene, settings) = (loaded.scene, loaded.settings);
    for name in Mode::names() {
        let mut s = settings.clone();
        s.mode = Mode::parse(name).unwrap();
        let mut renderer =
            Renderer::new(&scene, &s).unwrap_or_else(|e| panic!("{case} {name}: {e}"));
        let bdpm = matches!(s.mode, Mode::Bdpm(_));
        if bdpm {
            renderer = renderer.with_technique_layers(true);
        }
        let mut film = Film::new(s.width, s.height);
        for pass in 0..s.passes {
            let out = renderer.render_pass(pass, &|_| {});
            assert_eq!(out.dropped, 0, "{case} {name}: non-finite samples");
            if let Some(t) = &out.techniques {
                for t in t {
                    for v in [t.direct, t.x0_raw, t.x0_weighted, t.x1_raw, t.x1_weighted] {
                        assert!(
                            v.is_finite(),
                            "{case} {name}: non-finite technique layer {t:?}"
                        );
                    }
                }
            }
            film.add_pass(&out.estimates, out.dropped);
        }
        for v in film.pass_variance().iter().chain(&film.standard_error()) {
            assert!(
                v.is_finite() && v.min_element() >= 0.0,
                "{case} {name}: variance {v}"
            );
        }
        // Optimal weights may leave [0, 1] (method.md §4), so a noisy pixel mean can be
        // negative there while staying unbiased; every other mode's samples are non-negative.
        let signed = name == "optimal";
        for v in film.mean() {
            assert!(
                v.is_finite() && (signed || v.min_element() >= 0.0),
                "{case} {name}: mean {v}"
            );
        }
    }
}

#[test]
fn light_a_tenth_of_a_millimetre_from_a_wall() {
    let light = "[[light]]\nposition = [0.5, 0.9999, 0.5]\nflux = [1.0, 1.0, 1.0]";
    survive(
        "light 1e-4 m from the ceiling",
        &room("", LAMBERT, light, CAMERA, ""),
    );
}

#[test]
fn merge_radius_from_a_micrometre_to_a_third_of_the_room() {
    survive(
        "r = 1e-6 m",
        &room("radius = 1e-6", LAMBERT, LIGHT, CAMERA, ""),
    );
    survive(
        "r = 0.3 m",
        &room("radius = 0.3", LAMBERT, LIGHT, CAMERA, ""),
    );
    survive(
        "r = 0.3 m glossy",
        &room("radius = 0.3", GLOSSY, LIGHT, CAMERA, ""),
    );
}

#[test]
fn one_camera_sample_and_one_photon() {
    survive(
        "N_B = N_F = 1",
        &room("spp = 1\nphotons = 1", LAMBERT, LIGHT, CAMERA, "")
            .replace("spp = 2\nphotons = 3000\n", ""),
    );
}

#[test]
fn black_and_lossless_surfaces() {
    let black = "[material.walls]\nkd = 0.0\n[material.block]\nkd = 0.0";
    survive("kd = 0", &room("", black, LIGHT, CAMERA, ""));
    let lossless = "[material.walls]\nkd = 0.4\ngr = 0.6\ndelta = 10\n[material.block]\nkd = 1.0";
    survive("kd + gr = 1", &room("", lossless, LIGHT, CAMERA, ""));
}

#[test]
fn lobe_widths_from_a_tenth_of_a_degree_to_sixty() {
    for delta in [0.1, 60.0] {
        let m = format!(
            "[material.walls]\nkd = 0.1\ngr = 0.9\ndelta = {delta}\n[material.block]\nkd = 0.2\ngr = 0.7\ndelta = {delta}"
        );
        survive(
            &format!("delta = {delta}"),
            &room("", &m, LIGHT, CAMERA, ""),
        );
    }
}

#[test]
fn grazing_camera_and_grazing_light() {
    let camera = "position = [0.02, 0.001, 0.02]\nlook_at = [1.0, 0.0005, 1.0]\nvfov = 20";
    let light = "[[light]]\nposition = [0.98, 0.0005, 0.98]\nflux = [1.0, 1.0, 1.0]";
    survive("grazing", &room("", GLOSSY, light, camera, ""));
}

#[test]
fn empty_cache_cells_and_stiff_pixel_tables() {
    // Few photons into 4096 bins: nearly every cell and bin stays empty.
    survive(
        "empty cells",
        &room("photons = 20\ncache_bins = 4096", GLOSSY, LIGHT, CAMERA, "")
            .replace("photons = 3000\n", ""),
    );
    // A huge radius and many photons make κ ≫ N_B, so c·B approaches 1 and is clamped.
    let text = room(
        "radius = 0.3\nphotons = 20000\npixel_table_rays = 16",
        LAMBERT,
        LIGHT,
        CAMERA,
        "",
    )
    .replace("photons = 3000\n", "");
    survive("c·B → 1", &text);
    // The clamp itself needs κ ≫ N_B in the A/B pre-pass, which gathers no photons, so more
    // photons cost only the cache pass here.
    let text = text.replace("photons = 20000", "photons = 200000");
    let loaded = load_scene_str(&text, Path::new("."), Path::new("<cB>")).unwrap();
    let mut s = loaded.settings.clone();
    s.mode = Mode::parse("optimal").unwrap();
    let r = Renderer::new(&loaded.scene, &s).unwrap();
    let table = r
        .stages()
        .iter()
        .find(|st| st.stage == Stage::PixelTable)
        .expect("optimal builds the table");
    assert!(
        !table.detail.contains(" 0 pixels with c*B clamped"),
        "expected clamped pixels: {}",
        table.detail
    );
}

#[test]
fn unlit_second_vertices_and_degenerate_triangles() {
    // A wall splits the room; the light is in the half the camera does not see directly, so
    // many x₁ have L₀ = 0 and the camera half is lit only indirectly, through a gap.
    let wall = "[[shape]]\ntype = \"quad\"\nvertices = [[0.0, 0.0, 0.6], [1.0, 0.0, 0.6], [1.0, 0.9, 0.6], [0.0, 0.9, 0.6]]\nmaterial = \"walls\"";
    let light = "[[light]]\nposition = [0.5, 0.5, 0.9]\nflux = [1.0, 1.0, 1.0]";
    survive("L = 0 at x1", &room("", LAMBERT, light, CAMERA, wall));
    let degenerate = "[[shape]]\ntype = \"quad\"\nvertices = [[0.3, 0.3, 0.3], [0.3, 0.3, 0.3], [0.3, 0.3, 0.3], [0.3, 0.3, 0.3]]\nmaterial = \"walls\"";
    let text = room("", LAMBERT, LIGHT, CAMERA, degenerate);
    let loaded = load_scene_str(&text, Path::new("."), Path::new("<degenerate>")).unwrap();
    assert_eq!(loaded.report.degenerate_triangles, 2);
    survive("degenerate triangles", &text);
}
