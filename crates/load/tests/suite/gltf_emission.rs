//! glTF emission (docs/scene-format.md, "glTF materials"): Le = `emissiveFactor` ×
//! KHR_materials_emissive_strength × the `emissiveTexture` at the point's texture coordinates
//! (the set its reference names), sRGB-decoded as base colour is.

use base64::Engine;
use bdpm_load::{LoadError, LoadedScene, load_scene};
use bdpm_scene::srgb_to_linear;
use glam::{Vec2, Vec3};

/// The two texels of the emissive image, sRGB codes: left (u < ½) and right.
const TEXELS: [[u8; 3]; 2] = [[255, 128, 0], [0, 64, 255]];

/// A 2 × 1 RGB PNG of [`TEXELS`], as a data URI.
fn png_uri() -> String {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, 2, 1);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().expect("png header");
    writer.write_image_data(&TEXELS.concat()).expect("png data");
    writer.finish().expect("png end");
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&out)
    )
}

/// A glTF file of two unit squares in the plane z = 0 facing +z: mesh 0 (material 0, at the
/// origin) and mesh 1 (material 1, moved 2 m along x). TEXCOORD_0 is zero everywhere;
/// TEXCOORD_1 is (x, 1 − y). `materials` are the two material objects; `image` the image's
/// uri.
fn gltf(materials: [&str; 2], image: &str) -> String {
    let mut bytes = Vec::new();
    let corners = [[0.0f32, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    for [x, y] in corners {
        for c in [x, y, 0.0] {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    for _ in corners {
        bytes.extend_from_slice(&[0u8; 8]);
    }
    for [x, y] in corners {
        for c in [x, 1.0 - y] {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    let data = base64::engine::general_purpose::STANDARD.encode(&bytes);
    let prim = |m: usize| {
        format!(
            r#"{{ "primitives": [ {{ "attributes": {{ "POSITION": 0, "TEXCOORD_0": 1, "TEXCOORD_1": 2 }}, "indices": 3, "material": {m} }} ] }}"#
        )
    };
    format!(
        r#"{{ "asset": {{ "version": "2.0" }},
  "extensionsUsed": ["KHR_materials_emissive_strength"],
  "buffers": [ {{ "byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}" }} ],
  "bufferViews": [ {{ "buffer": 0, "byteLength": 48 }},
                   {{ "buffer": 0, "byteOffset": 48, "byteLength": 32 }},
                   {{ "buffer": 0, "byteOffset": 80, "byteLength": 32 }},
                   {{ "buffer": 0, "byteOffset": 112, "byteLength": 12 }} ],
  "accessors": [ {{ "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                    "min": [0, 0, 0], "max": [1, 1, 0] }},
                 {{ "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2" }},
                 {{ "bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2" }},
                 {{ "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" }} ],
  "images": [ {{ "uri": "{image}" }} ],
  "samplers": [ {{ "wrapS": 33071, "wrapT": 33071 }} ],
  "textures": [ {{ "source": 0, "sampler": 0 }} ],
  "materials": [ {}, {} ],
  "meshes": [ {}, {} ],
  "nodes": [ {{ "mesh": 0 }}, {{ "mesh": 1, "translation": [2, 0, 0] }} ],
  "scenes": [ {{ "nodes": [0, 1] }} ] }}"#,
        materials[0],
        materials[1],
        prim(0),
        prim(1),
        len = bytes.len(),
    )
}

/// The sign's material: factor [2, 1, 0.5] × strength 3 × the texture read through TEXCOORD_1.
const SIGN: &str = r#"{ "name": "sign", "emissiveFactor": [2, 1, 0.5],
    "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 3 } },
    "emissiveTexture": { "index": 0, "texCoord": 1 },
    "pbrMetallicRoughness": { "metallicFactor": 0 } }"#;
/// A material with an emissive texture but no emissive factor: it emits nothing.
const DARK: &str = r#"{ "name": "dark", "emissiveTexture": { "index": 0 },
    "pbrMetallicRoughness": { "metallicFactor": 0 } }"#;

/// Loads `gltf` as `e.gltf` from a scene file with a point light, plus `toml_extra`.
fn load_with(gltf: &str, toml_extra: &str) -> Result<LoadedScene, LoadError> {
    let tmp = tempfile::Builder::new()
        .prefix("bdpm-load-test-gltf-emission-")
        .tempdir()
        .expect("temp dir");
    let dir = tmp.path();
    std::fs::write(dir.join("e.gltf"), gltf).expect("write gltf");
    let toml = format!(
        "[camera]\nposition = [0.5, 0.5, 3.0]\nlook_at = [0.5, 0.5, 0.0]\nvfov = 40\n\n\
         [[light]]\nposition = [0.5, 0.5, 1.0]\nflux = 1.0\n\n{toml_extra}\
         [[shape]]\ntype = \"gltf\"\nfile = \"e.gltf\"\n"
    );
    std::fs::write(dir.join("scene.toml"), toml).expect("write toml");
    load_scene(&dir.join("scene.toml"))
}

#[test]
fn an_emissive_texture_multiplies_factor_and_strength_through_its_own_texcoord_set() {
    let s = load_with(&gltf([SIGN, DARK], &png_uri()), "").unwrap_or_else(|e| panic!("{e}"));
    let scene = &s.scene;
    // The sign's two triangles emit; the dark square does not.
    assert_eq!(scene.emitters().len(), 2);
    let le = Vec3::new(2.0, 1.0, 0.5) * 3.0;
    let lin = |t: [u8; 3]| Vec3::from_array(t.map(|c| srgb_to_linear(f32::from(c) / 255.0)));
    for e in scene.emitters() {
        let m = scene.geometry().material(e.prim);
        assert_eq!(scene.materials()[m as usize].name, "sign");
        assert!(scene.emission_texture(m).is_some());
        let v = scene.geometry().vertices(e.prim);
        for (k, bary) in [Vec2::ZERO, Vec2::X, Vec2::Y].into_iter().enumerate() {
            // Near vertex k: x = 0 reads the left texel (clamped), x = 1 the right one.
            let bary = bary * 0.98 + Vec2::splat(0.01);
            let texel = if v[k].x < 0.5 { TEXELS[0] } else { TEXELS[1] };
            let want = le * lin(texel);
            let got = scene.emission_at(e.prim, bary);
            assert!(
                (got - want).abs().max_element() < 1e-4 * want.max_element(),
                "vertex {:?}: {got} against {want}",
                v[k]
            );
        }
        // The light distribution's weight is the triangle's mean Le: between the texels'.
        let (lo, hi) = (le * lin(TEXELS[0]), le * lin(TEXELS[1]));
        assert!(e.radiance.cmpge(lo.min(hi)).all() && e.radiance.cmple(lo.max(hi)).all());
    }
    let dark = scene
        .materials()
        .iter()
        .position(|m| m.name == "dark")
        .expect("the dark material");
    assert!(!scene.materials()[dark].emits());
    assert!(scene.emission_texture(dark as u32).is_none());
    let r = &s.report;
    assert_eq!(
        (r.emission_textured_materials, r.textures, r.other_textures),
        (1, 1, 0)
    );
    assert!(
        !r.warnings().iter().any(|w| w.contains("emissive")),
        "{:?}",
        r.warnings()
    );
}

#[test]
fn a_toml_material_of_the_same_name_wins_without_the_texture() {
    let toml = "[material.sign]\nkd = 0.2\nemission = 4.0\n\n";
    let s = load_with(&gltf([SIGN, DARK], &png_uri()), toml).unwrap_or_else(|e| panic!("{e}"));
    let scene = &s.scene;
    assert_eq!(scene.emitters().len(), 2);
    for e in scene.emitters() {
        assert!(
            scene
                .emission_texture(scene.geometry().material(e.prim))
                .is_none()
        );
        assert_eq!(
            scene.emission_at(e.prim, Vec2::splat(0.3)),
            Vec3::splat(4.0)
        );
    }
    assert_eq!(s.report.emission_textured_materials, 0);
}

#[test]
fn a_missing_emissive_image_is_an_error_naming_the_file_and_the_texture() {
    let e = load_with(&gltf([SIGN, DARK], "missing.png"), "").expect_err("no image");
    let msg = e.to_string();
    assert!(
        msg.contains("missing.png") && msg.contains("emissive texture"),
        "{msg}"
    );
    // The dark material's texture is never read: nothing to multiply.
    let s = load_with(
        &gltf([r#"{ "emissiveFactor": [1, 1, 1] }"#, DARK], "missing.png"),
        "",
    );
    assert!(s.is_ok(), "{:?}", s.err());
}
