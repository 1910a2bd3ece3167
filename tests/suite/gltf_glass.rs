//! A glass sphere from a glTF file (KHR_materials_transmission, _ior, _volume) renders bit for
//! bit like the same sphere from the scene file (`type = "dielectric"`): the loader's glTF
//! material mapping makes the same model of the same numbers (issue 45, item 1).

use std::fmt::Write as _;
use std::path::Path;

use bdpm_integrator::{Film, RenderSettings};
use bdpm_load::load_scene_str;
use bdpm_scene::Scene;
use bdpm_suite::{render, with_mode};

const HEAD: &str = "[render]\nresolution = [20, 20]\nseed = 5\nradius = 0.01\n\n\
    [camera]\nposition = [0.5, 0.6, 0.98]\nlook_at = [0.5, 0.2, 0.4]\nvfov = 60\n\n\
    [[light]]\nposition = [0.5, 0.85, 0.45]\nflux = 1.0\n\n\
    [material.walls]\nkd = [0.6, 0.5, 0.4]\n\n";

/// The glass of both files: ior 1.5, transmitted light tinted.
const TINT: [f32; 3] = [1.0, 0.9, 0.8];

/// The room x, y, z ∈ [0, 1] of `walls` quads, open towards the camera (z = 1).
fn room() -> String {
    let faces = [
        "[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]",
        "[0, 1, 0], [0, 1, 1], [1, 1, 1], [1, 1, 0]",
        "[0, 0, 0], [0, 0, 1], [0, 1, 1], [0, 1, 0]",
        "[1, 0, 0], [1, 1, 0], [1, 1, 1], [1, 0, 1]",
        "[0, 0, 0], [0, 1, 0], [1, 1, 0], [1, 0, 0]",
    ];
    faces
        .iter()
        .map(|v| format!("[[shape]]\ntype = \"quad\"\nmaterial = \"walls\"\nvertices = [{v}]\n\n"))
        .collect()
}

fn load(text: &str, dir: &Path) -> (Scene, RenderSettings) {
    let loaded =
        load_scene_str(text, dir, &dir.join("scene.toml")).unwrap_or_else(|e| panic!("{e}"));
    (loaded.scene, loaded.settings)
}

/// The TOML scene: the geodesic sphere (the first shape) of dielectric glass, flat-faceted as
/// the glTF copy (which [`write_gltf`] writes without normals).
fn toml_scene() -> String {
    let [r, g, b] = TINT;
    format!(
        "{HEAD}[material.glass]\ntype = \"dielectric\"\nior = 1.5\ntransmit_tint = [{r}, {g}, {b}]\n\n\
         [[shape]]\ntype = \"sphere\"\ncenter = [0.5, 0.25, 0.45]\nradius = 0.2\n\
         subdivisions = 6\nsmooth = false\nmaterial = \"glass\"\n\n{}",
        room()
    )
}

/// Writes the first `triangles` triangles of `scene` (non-indexed, no normals: flat, as the
/// TOML sphere) to `dir/sphere.gltf` with one glTF material, `material` (a JSON object).
fn write_gltf(scene: &Scene, triangles: u32, material: &str, dir: &Path) {
    let g = scene.geometry();
    let mut bin = Vec::new();
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for t in 0..triangles {
        for v in g.vertices(t) {
            for (k, c) in v.to_array().into_iter().enumerate() {
                bin.extend_from_slice(&c.to_le_bytes());
                (lo[k], hi[k]) = (lo[k].min(c), hi[k].max(c));
            }
        }
    }
    std::fs::write(dir.join("sphere.bin"), &bin).expect("write bin");
    let mut json = String::new();
    write!(
        json,
        r#"{{ "asset": {{ "version": "2.0" }},
  "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"],
  "buffers": [ {{ "byteLength": {len}, "uri": "sphere.bin" }} ],
  "bufferViews": [ {{ "buffer": 0, "byteLength": {len} }} ],
  "accessors": [ {{ "bufferView": 0, "componentType": 5126, "count": {count}, "type": "VEC3",
                    "min": {lo:?}, "max": {hi:?} }} ],
  "materials": [ {material} ],
  "meshes": [ {{ "primitives": [ {{ "attributes": {{ "POSITION": 0 }}, "material": 0 }} ] }} ],
  "nodes": [ {{ "mesh": 0 }} ],
  "scenes": [ {{ "nodes": [0] }} ] }}"#,
        len = bin.len(),
        count = 3 * triangles,
    )
    .expect("format");
    std::fs::write(dir.join("sphere.gltf"), json).expect("write gltf");
}

/// The glTF material of the sphere, with `roughness`.
fn glass_json(roughness: f32) -> String {
    format!(
        r#"{{ "name": "gltf-glass", "pbrMetallicRoughness": {{ "baseColorFactor": [{}, {}, {}, 1.0],
      "metallicFactor": 0.0, "roughnessFactor": {roughness} }},
    "extensions": {{ "KHR_materials_transmission": {{ "transmissionFactor": 1.0 }},
                    "KHR_materials_ior": {{ "ior": 1.5 }},
                    "KHR_materials_volume": {{ "thicknessFactor": 0.4 }} }} }}"#,
        TINT[0], TINT[1], TINT[2]
    )
}

fn film_bits(film: &Film) -> Vec<[u64; 3]> {
    film.mean()
        .iter()
        .map(|v| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()])
        .collect()
}

#[test]
fn a_gltf_glass_sphere_renders_bit_for_bit_like_the_toml_one() {
    let tmp = tempfile::Builder::new()
        .prefix("bdpm-suite-gltf-glass-")
        .tempdir()
        .expect("temp dir");
    let dir = tmp.path();
    let (toml, settings) = load(&toml_scene(), dir);
    // 20 · 6² facets, the sphere's, come first.
    let sphere = 720;
    let g = toml.geometry();
    assert!(toml.materials()[g.material(sphere - 1) as usize].is_delta());
    assert!(!toml.materials()[g.material(sphere) as usize].is_delta());
    let gltf_text = format!(
        "{HEAD}[[shape]]\ntype = \"gltf\"\nfile = \"sphere.gltf\"\n\n{}",
        room()
    );
    write_gltf(&toml, sphere, &glass_json(0.0), dir);
    let (gltf, _) = load(&gltf_text, dir);
    assert_eq!(gltf.geometry().triangle_count(), g.triangle_count());
    // The same glass, but rough: glTF's frosted glass is Lambert in bdpm, and the image
    // shows it (the comparison can tell the two apart).
    write_gltf(&toml, sphere, &glass_json(0.3), dir);
    let (frosted, _) = load(&gltf_text, dir);

    for mode in ["bdd1", "optimal-path"] {
        let s = with_mode(&settings, mode, 2, 2, 20_000);
        let a = render(&toml, &s);
        let b = render(&gltf, &s);
        let c = render(&frosted, &s);
        assert!(a.mean().iter().any(|v| v.x > 0.0), "{mode}: a black image");
        assert!(
            film_bits(&a) == film_bits(&b),
            "{mode}: the glTF glass renders other bits than the TOML glass"
        );
        let differ = film_bits(&a)
            .iter()
            .zip(film_bits(&c))
            .filter(|(x, y)| **x != *y)
            .count();
        assert!(
            differ > 20,
            "{mode}: frosted glass changed only {differ} pixels"
        );
    }
}
