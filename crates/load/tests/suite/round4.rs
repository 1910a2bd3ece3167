//! Round four (issue 43): KHR_texture_transform, and the loader's memory limit, on scenes
//! made by the test.
use std::path::Path;

use bdpm_load::{LoadOptions, MemoryLimit, load_scene, load_scene_with};
use glam::{Vec2, Vec3};

fn temp_dir() -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix("bdpm-load-test-round4-")
        .tempdir()
        .expect("temp dir")
}

/// A 2 × 1 RGB PNG: black on the left (u < ½), white on the right.
fn black_white_png() -> Vec<u8> {
    let mut out = Vec::new();
    let mut e = png::Encoder::new(&mut out, 2, 1);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    let mut w = e.write_header().expect("header");
    w.write_image_data(&[0, 0, 0, 255, 255, 255]).expect("data");
    w.finish().expect("end");
    out
}

/// One triangle whose three vertices all have uv = (0.25, 0.5) (the black texel's centre),
/// textured with clamped edges, `transform` the JSON of the KHR_texture_transform of its
/// base-colour texture reference ("" for none).
fn write_scene(dir: &Path, transform: &str) {
    let mut bin = Vec::new();
    for c in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&c.to_le_bytes());
    }
    for _ in 0..3 {
        for c in [0.25f32, 0.5] {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    std::fs::write(dir.join("tri.bin"), &bin).expect("write bin");
    std::fs::write(dir.join("bw.png"), black_white_png()).expect("write png");
    let ext = if transform.is_empty() {
        String::new()
    } else {
        format!(r#", "extensions": {{ "KHR_texture_transform": {transform} }}"#)
    };
    let gltf = format!(
        r#"{{ "asset": {{ "version": "2.0" }},
  "extensionsUsed": ["KHR_texture_transform"],
  "buffers": [ {{ "byteLength": 60, "uri": "tri.bin" }} ],
  "bufferViews": [ {{ "buffer": 0, "byteLength": 36 }}, {{ "buffer": 0, "byteOffset": 36, "byteLength": 24 }} ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] }},
    {{ "bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2" }} ],
  "images": [ {{ "uri": "bw.png" }} ],
  "samplers": [ {{ "wrapS": 33071, "wrapT": 33071 }} ],
  "textures": [ {{ "source": 0, "sampler": 0 }} ],
  "materials": [ {{ "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0{ext} }} }} }} ],
  "meshes": [ {{ "primitives": [ {{ "attributes": {{ "POSITION": 0, "TEXCOORD_0": 1 }}, "material": 0 }} ] }} ],
  "nodes": [ {{ "mesh": 0 }} ], "scenes": [ {{ "nodes": [0] }} ] }}"#
    );
    std::fs::write(dir.join("tri.gltf"), gltf).expect("write gltf");
    let toml = r#"
[camera]
position = [0.3, 0.3, -3.0]
look_at = [0.3, 0.3, 0.0]
vfov = 40

[[light]]
position = [0.3, 0.3, -1.0]
flux = 1.0

[[shape]]
type = "mesh"
file = "tri.gltf"
"#;
    std::fs::write(dir.join("scene.toml"), toml).expect("write toml");
}

/// kd at the triangle's centroid.
fn kd(dir: &Path) -> Vec3 {
    let loaded = load_scene(&dir.join("scene.toml")).unwrap_or_else(|e| panic!("{e}"));
    let s = &loaded.scene;
    s.kd_at(s.geometry().material(0), 0, Vec2::splat(1.0 / 3.0))
}

/// KHR_texture_transform was ignored: the texture read at the untransformed coordinates.
/// It is applied now: an offset of ½ in u moves the black texel's centre (0.25) to the white
/// one's (0.75); a rotation by π about the origin with an offset (1, 1) maps (0.25, 0.5) to
/// (0.75, 0.5) too; a scale of 3 to (0.75, 1.5), white under clamping.
#[test]
fn texture_transforms_are_applied() {
    let tmp = temp_dir();
    let dir = tmp.path();
    write_scene(dir, "");
    assert_eq!(kd(dir), Vec3::ZERO);
    for transform in [
        r#"{ "offset": [0.5, 0.0] }"#,
        r#"{ "offset": [1.0, 1.0], "rotation": 3.14159265 }"#,
        r#"{ "scale": [3.0, 3.0] }"#,
    ] {
        write_scene(dir, transform);
        let kd = kd(dir);
        assert!(
            (kd - Vec3::ONE).abs().max_element() < 1e-5,
            "{transform}: kd {kd}"
        );
    }
}

/// The loader's memory limit: an image whose decode would exceed it is refused from its
/// header, naming the image, its size, the bytes and the bound; the same scene loads
/// without a limit.
#[test]
fn the_memory_limit_refuses_an_image_before_decoding_it() {
    let tmp = temp_dir();
    let dir = tmp.path();
    write_scene(dir, "");
    // 512 × 512 grey texels: a few hundred bytes of PNG, 1 MiB to decode (1 byte a texel
    // decoded, 3 kept).
    let mut png = Vec::new();
    let mut e = png::Encoder::new(&mut png, 512, 512);
    e.set_color(png::ColorType::Grayscale);
    e.set_depth(png::BitDepth::Eight);
    let mut w = e.write_header().expect("header");
    w.write_image_data(&vec![90; 512 * 512]).expect("data");
    w.finish().expect("end");
    std::fs::write(dir.join("bw.png"), png).expect("write png");
    let options = LoadOptions {
        memory_limit: Some(MemoryLimit {
            bytes: 100 << 10,
            source: "memory limit".into(),
            remedy: Some("raise the limit if the machine has it".into()),
        }),
    };
    let e = load_scene_with(&dir.join("scene.toml"), &options)
        .expect_err("512² texels need more than 100 KiB")
        .to_string();
    for needle in [
        "tri.gltf",
        "image 0",
        "512×512 texels",
        "1.0 MiB",
        "more than the memory limit of 100.0 KiB; raise the limit if the machine has it",
    ] {
        assert!(e.contains(needle), "'{needle}' not in: {e}");
    }
    assert!(load_scene(&dir.join("scene.toml")).is_ok());
}
