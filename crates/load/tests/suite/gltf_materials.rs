//! glTF materials → bdpm's models (docs/scene-format.md, "glTF materials"): smooth metal is a
//! perfect mirror, smooth transmission a dielectric, the rest Lambert with a warning naming
//! the material; out-of-range values are refused in one line naming the file and material.

use base64::Engine;
use bdpm_load::{LoadError, LoadedScene, MATERIAL_WARNINGS_SHOWN, load_scene};
use glam::Vec3;

/// A glTF file with one triangle per entry of `materials` (JSON objects), triangle i using
/// material i, and `extra` top-level members (such as `"extensionsRequired": [...]`).
fn gltf_with(materials: &[&str], extra: &str) -> String {
    let mut bytes = Vec::new();
    for c in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bytes.extend_from_slice(&c.to_le_bytes());
    }
    let data = base64::engine::general_purpose::STANDARD.encode(&bytes);
    let primitives: Vec<String> = (0..materials.len())
        .map(|i| format!(r#"{{ "attributes": {{ "POSITION": 0 }}, "material": {i} }}"#))
        .collect();
    format!(
        r#"{{ "asset": {{ "version": "2.0" }},
  "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"],
  {extra}
  "buffers": [ {{ "byteLength": 36, "uri": "data:application/octet-stream;base64,{data}" }} ],
  "bufferViews": [ {{ "buffer": 0, "byteLength": 36 }} ],
  "accessors": [ {{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                    "min": [0, 0, 0], "max": [1, 1, 0] }} ],
  "images": [ {{ "uri": "never-read.png" }} ],
  "textures": [ {{ "source": 0 }} ],
  "materials": [ {} ],
  "meshes": [ {{ "primitives": [ {} ] }} ],
  "nodes": [ {{ "mesh": 0 }} ],
  "scenes": [ {{ "nodes": [0] }} ] }}"#,
        materials.join(",\n"),
        primitives.join(", ")
    )
}

/// Loads `gltf` as `m.gltf` from a scene file with `toml_extra` appended (and `shapes` copies
/// of the file's shape).
fn load_with(gltf: &str, toml_extra: &str, shapes: usize) -> Result<LoadedScene, LoadError> {
    let tmp = tempfile::Builder::new()
        .prefix("bdpm-load-test-gltf-materials-")
        .tempdir()
        .expect("temp dir");
    let dir = tmp.path();
    std::fs::write(dir.join("m.gltf"), gltf).expect("write gltf");
    let mut toml = String::from(
        "[camera]\nposition = [0.3, 0.3, -3.0]\nlook_at = [0.3, 0.3, 0.0]\nvfov = 40\n\n\
         [[light]]\nposition = [0.3, 0.3, -1.0]\nflux = 1.0\n\n",
    );
    toml.push_str(toml_extra);
    for _ in 0..shapes {
        toml.push_str("[[shape]]\ntype = \"gltf\"\nfile = \"m.gltf\"\n\n");
    }
    std::fs::write(dir.join("scene.toml"), toml).expect("write toml");
    load_scene(&dir.join("scene.toml"))
}

fn load(materials: &[&str]) -> LoadedScene {
    load_with(&gltf_with(materials, ""), "", 1).unwrap_or_else(|e| panic!("{e}"))
}

/// The scene material of triangle `t`.
fn material(s: &LoadedScene, t: u32) -> &bdpm_scene::Material {
    &s.scene.materials()[s.scene.geometry().material(t) as usize]
}

/// The one warning line of material `index`, which must contain every one of `words`.
fn assert_warned(s: &LoadedScene, index: usize, name: &str, words: &[&str]) {
    let prefix = format!("glTF m.gltf: material {index} ('{name}'): ");
    let lines: Vec<&String> = s
        .report
        .material_warnings
        .iter()
        .filter(|l| l.starts_with(&prefix))
        .collect();
    assert!(
        lines.iter().any(|l| words.iter().all(|w| l.contains(w))),
        "no warning of {prefix} with {words:?}: {:?}",
        s.report.material_warnings
    );
    assert!(
        s.report.warnings().iter().any(|w| w.starts_with(&prefix)),
        "{:?}",
        s.report.warnings()
    );
}

const MIRROR: &str = r#"{ "name": "chrome", "pbrMetallicRoughness": {
    "baseColorFactor": [0.9, 0.8, 0.7, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.05 } }"#;

const GLASS: &str = r#"{ "name": "glass", "pbrMetallicRoughness": {
    "baseColorFactor": [1.0, 0.9, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.0 },
  "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0 },
                  "KHR_materials_ior": { "ior": 1.33 },
                  "KHR_materials_volume": { "thicknessFactor": 0.1 } } }"#;

#[test]
fn a_smooth_metal_is_a_perfect_mirror_of_the_base_colour() {
    let s = load(&[MIRROR]);
    let m = material(&s, 0);
    assert_eq!(m.name, "chrome");
    match m.delta {
        Some(bdpm_bdf::Material::Mirror(mirror)) => {
            assert_eq!(mirror.reflectance(), Vec3::new(0.9, 0.8, 0.7));
            assert_eq!(mirror.conductor_index(), None);
        }
        ref other => panic!("not a mirror: {other:?}"),
    }
    assert_eq!((s.report.gltf_mirrors, s.report.gltf_dielectrics), (1, 0));
    assert!(s.report.warnings().is_empty(), "{:?}", s.report.warnings());
}

#[test]
fn smooth_transmission_is_glass_with_the_files_ior_and_a_base_colour_tint() {
    let s = load(&[GLASS]);
    match material(&s, 0).delta {
        Some(bdpm_bdf::Material::Dielectric(d)) => {
            assert_eq!(d.eta(), 1.33);
            assert_eq!(d.transmit_tint(), Vec3::new(1.0, 0.9, 0.8));
            assert_eq!(d.reflect_tint(), Vec3::ONE);
        }
        ref other => panic!("not a dielectric: {other:?}"),
    }
    assert_eq!((s.report.gltf_mirrors, s.report.gltf_dielectrics), (0, 1));
    assert!(s.report.warnings().is_empty(), "{:?}", s.report.warnings());
    // Without KHR_materials_ior: glTF's 1.5; without a volume: thin-walled, warned.
    let thin = r#"{ "name": "pane", "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.0 },
      "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0 } } }"#;
    let s = load(&[thin]);
    match material(&s, 0).delta {
        Some(bdpm_bdf::Material::Dielectric(d)) => assert_eq!(d.eta(), 1.5),
        ref other => panic!("not a dielectric: {other:?}"),
    }
    assert_warned(&s, 0, "pane", &["thin-walled", "ior 1.5"]);
}

#[test]
fn what_a_mirror_or_glass_cannot_show_is_named_in_a_warning() {
    let textured_mirror = r#"{ "name": "tm", "pbrMetallicRoughness": { "roughnessFactor": 0.0,
      "baseColorTexture": { "index": 0 }, "metallicRoughnessTexture": { "index": 0 } } }"#;
    let absorbing = r#"{ "name": "tinted", "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.01 },
      "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0 },
                      "KHR_materials_volume": { "thicknessFactor": 0.2, "attenuationDistance": 0.5,
                                                "attenuationColor": [0.5, 1.0, 1.0] } } }"#;
    let partial = r#"{ "name": "half", "pbrMetallicRoughness": { "metallicFactor": 0.4, "roughnessFactor": 0.0,
        "baseColorTexture": { "index": 0 } },
      "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0,
                                                      "transmissionTexture": { "index": 0 } },
                      "KHR_materials_volume": { "thicknessFactor": 0.2 } } }"#;
    let s = load(&[textured_mirror, absorbing, partial]);
    assert_eq!((s.report.gltf_mirrors, s.report.gltf_dielectrics), (1, 2));
    // The mirror's texture is neither applied nor decoded (its image does not exist).
    assert_eq!((s.report.textured_materials, s.report.textures), (0, 0));
    assert_warned(
        &s,
        0,
        "tm",
        &["perfect mirror", "baseColorTexture is not applied"],
    );
    assert_warned(&s, 0, "tm", &["metallicRoughnessTexture is not read"]);
    assert_warned(&s, 1, "tinted", &["attenuation", "0.5 m", "ignored"]);
    assert_warned(&s, 2, "half", &["share", "0.6", "dropped"]);
    assert_warned(&s, 2, "half", &["baseColorTexture is not applied"]);
    assert_warned(
        &s,
        2,
        "half",
        &["transmission and metallic-roughness textures"],
    );
}

#[test]
fn rough_or_partial_metal_and_transmission_stay_lambert_with_a_warning() {
    let rough_metal =
        r#"{ "name": "steel", "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.5, 0.5, 1] } }"#;
    let partial_metal = r#"{ "name": "alloy", "pbrMetallicRoughness": { "metallicFactor": 0.5, "roughnessFactor": 0.0 } }"#;
    let frosted = r#"{ "name": "frosted", "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.3 },
      "extensions": { "KHR_materials_transmission": { "transmissionFactor": 0.9 } } }"#;
    let milky = r#"{ "name": "milky", "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.0 },
      "extensions": { "KHR_materials_transmission": { "transmissionFactor": 0.3 } } }"#;
    let plastic = r#"{ "name": "plastic", "pbrMetallicRoughness": { "baseColorFactor": [0.2, 0.3, 0.4, 1],
      "metallicFactor": 0.0, "roughnessFactor": 0.0 }, "extensions": { "KHR_materials_ior": { "ior": 0 } } }"#;
    let s = load(&[rough_metal, partial_metal, frosted, milky, plastic]);
    for t in 0..5 {
        assert!(!material(&s, t).is_delta(), "{t}");
    }
    assert_eq!(material(&s, 0).bdf.kd(), Vec3::splat(0.5));
    assert_eq!(material(&s, 4).bdf.kd(), Vec3::new(0.2, 0.3, 0.4));
    assert_warned(
        &s,
        0,
        "steel",
        &["rough metal", "roughnessFactor 1 > 0.05", "Lambert"],
    );
    assert_warned(
        &s,
        1,
        "alloy",
        &["partly metallic", "metallicFactor 0.5", "Lambert"],
    );
    assert_warned(
        &s,
        2,
        "frosted",
        &["rough transmission", "0.3 > 0.05", "opaque Lambert"],
    );
    assert_warned(
        &s,
        3,
        "milky",
        &["partial transmission", "0.3 < 0.5", "opaque Lambert"],
    );
    // A smooth plastic is Lambert as before, without a warning (its ior, even glTF's 0, is
    // not read).
    assert_eq!(
        s.report.material_warnings.len(),
        4,
        "{:?}",
        s.report.material_warnings
    );
    assert_eq!((s.report.gltf_mirrors, s.report.gltf_dielectrics), (0, 0));
}

#[test]
fn values_the_models_reject_are_refused_naming_file_material_and_field() {
    let cases = [
        (
            GLASS.replace("\"ior\": 1.33", "\"ior\": 0"),
            "KHR_materials_ior.ior 0 is outside [0.01, 100]",
        ),
        (
            GLASS.replace("\"ior\": 1.33", "\"ior\": 250"),
            "KHR_materials_ior.ior 250 is outside [0.01, 100]",
        ),
        (
            GLASS.replace("\"thicknessFactor\": 0.1", "\"thicknessFactor\": -1"),
            "KHR_materials_volume.thicknessFactor -1 is not a finite number >= 0",
        ),
        (
            GLASS.replace("\"transmissionFactor\": 1.0", "\"transmissionFactor\": 2"),
            "KHR_materials_transmission.transmissionFactor 2 is outside [0, 1]",
        ),
        (
            MIRROR.replace("\"metallicFactor\": 1.0", "\"metallicFactor\": 1.5"),
            "pbrMetallicRoughness.metallicFactor 1.5 is outside [0, 1]",
        ),
        (
            MIRROR.replace("\"roughnessFactor\": 0.05", "\"roughnessFactor\": -0.1"),
            "pbrMetallicRoughness.roughnessFactor -0.1 is outside [0, 1]",
        ),
        (
            MIRROR.replace("0.9, 0.8", "1.2, 0.8"),
            "baseColorFactor [1.2, 0.8, 0.7] has a channel outside [0, 1]",
        ),
        (
            MIRROR.replace("\"roughnessFactor\": 0.05", "\"roughnessFactor\": 1e39"),
            "pbrMetallicRoughness.roughnessFactor inf is outside [0, 1]",
        ),
    ];
    for (material, what) in cases {
        let first = r#"{ "name": "fine", "pbrMetallicRoughness": { "metallicFactor": 0 } }"#;
        let e = load_with(&gltf_with(&[first, &material], ""), "", 1)
            .expect_err(what)
            .to_string();
        assert_eq!(e.lines().count(), 1, "{e}");
        assert!(e.contains("m.gltf (from shape[0].file)"), "{e}");
        assert!(e.contains("material 1 ('"), "{e}");
        assert!(e.contains(what), "{e}\nwanted: {what}");
    }
}

#[test]
fn required_material_extensions_are_read_and_a_toml_name_still_wins() {
    let required = r#""extensionsRequired": ["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"],"#;
    let s = load_with(
        &gltf_with(&[MIRROR, GLASS], required),
        "[material.chrome]\nkd = 0.3\n\n",
        1,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    // "chrome" is the scene file's Lambert; "glass" is mapped.
    assert!(!material(&s, 0).is_delta());
    assert_eq!(material(&s, 0).bdf.kd(), Vec3::splat(0.3));
    assert!(material(&s, 1).is_delta());
    assert_eq!((s.report.gltf_mirrors, s.report.gltf_dielectrics), (0, 1));
}

#[test]
fn many_warnings_are_listed_in_full_in_the_report_and_counted_past_the_first_few() {
    let n = MATERIAL_WARNINGS_SHOWN + 3;
    let names: Vec<String> = (0..n)
        .map(|i| {
            format!(
                r#"{{ "name": "metal{i}", "pbrMetallicRoughness": {{ "roughnessFactor": 0.5 }} }}"#
            )
        })
        .collect();
    let list: Vec<&str> = names.iter().map(String::as_str).collect();
    // The file twice: each line once.
    let s = load_with(&gltf_with(&list, ""), "", 2).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.report.material_warnings.len(), n);
    let warnings = s.report.warnings();
    assert_eq!(warnings.len(), MATERIAL_WARNINGS_SHOWN + 1, "{warnings:?}");
    assert!(
        warnings[MATERIAL_WARNINGS_SHOWN].starts_with("glTF: 3 more material approximation(s)"),
        "{warnings:?}"
    );
}
