//! Built-in shapes: triangle counts, which way the front faces point, placement, and the
//! example of docs/scene-format.md.

use std::f32::consts::PI;
use std::path::Path;

use bdpm_load::{LoadedScene, load_scene_str};
use glam::Vec3;

const HEAD: &str = r#"
[camera]
position = [0.0, 0.0, -5.0]
look_at = [0.0, 0.0, 0.0]
vfov = 40

[[light]]
position = [0.0, 0.0, 0.0]
flux = 1

[material.m]
kd = 0.5
"#;

fn load(shapes: &str) -> LoadedScene {
    let text = format!("{HEAD}{shapes}");
    load_scene_str(&text, Path::new("."), Path::new("shapes.toml"))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Sign of (front normal) · (centroid − centre) for every triangle: +1 all outward, −1 all inward.
fn facing(s: &LoadedScene, centre: Vec3) -> f32 {
    let g = &s.scene.geometry();
    let signs: Vec<f32> = (0..g.triangle_count() as u32)
        .map(|t| {
            let v = g.vertices(t);
            g.normal(t)
                .dot((v[0] + v[1] + v[2]) / 3.0 - centre)
                .signum()
        })
        .collect();
    assert!(signs.iter().all(|&x| x == signs[0]), "mixed orientation");
    signs[0]
}

#[test]
fn box_faces_outward_by_default_and_inward_on_request() {
    let shape = "[[shape]]\ntype = \"box\"\nmin = [1, 2, 3]\nmax = [2, 4, 6]\nmaterial = \"m\"\n";
    let s = load(shape);
    assert_eq!(s.report.triangles, 12);
    assert_eq!(facing(&s, Vec3::new(1.5, 3.0, 4.5)), 1.0);
    assert!((s.scene.geometry().total_area() - 2.0 * (2.0 + 3.0 + 6.0)).abs() < 1e-4);
    let (lo, hi) = s.scene.geometry().bounds();
    assert_eq!(
        (lo, hi),
        (Vec3::new(1.0, 2.0, 3.0), Vec3::new(2.0, 4.0, 6.0))
    );

    let s = load(&format!(
        "{shape}facing = \"inside\"\nopen = [\"-z\", \"+y\"]\n"
    ));
    assert_eq!(s.report.triangles, 8);
    assert_eq!(facing(&s, Vec3::new(1.5, 3.0, 4.5)), -1.0);
    // The −z face is open: a ray from inside towards −z escapes, one towards +z does not.
    let g = &s.scene.geometry();
    assert!(
        g.intersect(Vec3::new(1.5, 3.0, 4.5), Vec3::NEG_Z, f32::INFINITY)
            .is_none()
    );
    assert!(
        g.intersect(Vec3::new(1.5, 3.0, 4.5), Vec3::Z, f32::INFINITY)
            .is_some()
    );
}

#[test]
fn box_placement_with_negative_scale() {
    let shape = "[[shape]]\ntype = \"box\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nscale = [-2, 1, 1]\ntranslate = [0, 0, 1]\nmaterial = \"m\"\n";
    let s = load(shape);
    let (lo, hi) = s.scene.geometry().bounds();
    assert_eq!(
        (lo, hi),
        (Vec3::new(-2.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 2.0))
    );
    assert_eq!(facing(&s, Vec3::new(-1.0, 0.5, 1.5)), 1.0);
}

#[test]
fn quad_keeps_vertex_order_and_split() {
    let shape = "[[shape]]\ntype = \"quad\"\nvertices = [[0,0,0],[0,0,100],[100,0,100],[100,0,0]]\nscale = 0.01\nmaterial = \"m\"\n";
    let s = load(shape);
    let g = &s.scene.geometry();
    assert_eq!(
        g.vertices(0),
        [
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0)
        ]
    );
    assert_eq!(
        g.vertices(1),
        [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 0.0)
        ]
    );
    assert_eq!(g.normal(0), Vec3::Y);
}

#[test]
fn sphere_counts_area_and_facing() {
    for (subdivisions, facing_key, sign) in [
        (1, "outside", 1.0),
        (8, "outside", 1.0),
        (32, "inside", -1.0),
    ] {
        let shape = format!(
            "[[shape]]\ntype = \"sphere\"\ncenter = [0.5, -1, 2]\nradius = 2\nsubdivisions = {subdivisions}\nfacing = \"{facing_key}\"\nmaterial = \"m\"\n"
        );
        let s = load(&shape);
        let centre = Vec3::new(0.5, -1.0, 2.0);
        assert_eq!(s.report.triangles, 20 * subdivisions * subdivisions);
        assert_eq!(s.report.degenerate_triangles, 0);
        assert_eq!(facing(&s, centre), sign);
        let ratio = s.scene.geometry().total_area() as f32 / (4.0 * PI * 4.0);
        assert!(ratio < 1.0, "inscribed");
        if subdivisions == 32 {
            assert!((ratio - 1.0).abs() < 0.001, "area ratio {ratio}");
        }
    }
}

#[test]
fn default_sphere_subdivisions() {
    let s = load("[[shape]]\ntype = \"sphere\"\nradius = 1\nmaterial = \"m\"\n");
    assert_eq!(s.report.triangles, 5120);
}

#[test]
fn documented_example_loads() {
    let doc = include_str!("../../../../docs/scene-format.md");
    let start = doc.find("## Example").expect("example section");
    let body = &doc[start..];
    let open = body.find("```toml\n").expect("toml block") + "```toml\n".len();
    let close = body[open..].find("```").expect("end of block") + open;
    let example = &body[open..close];
    // The example's glTF file does not exist here; everything before it must load as is.
    let cut = example
        .rfind("[[shape]]\ntype = \"gltf\"")
        .expect("gltf shape");
    let s = load_scene_str(&example[..cut], Path::new("."), Path::new("example.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.settings.width, 320);
    assert_eq!(s.report.triangles, 10 + 20 * 24 * 24);
    let err = load_scene_str(example, Path::new("."), Path::new("example.toml"))
        .expect_err("no teapot here");
    assert!(
        err.to_string()
            .contains("teapot.glb (from shape[2].file): cannot read"),
        "{err}"
    );
}
