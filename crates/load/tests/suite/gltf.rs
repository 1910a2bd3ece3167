//! glTF 2.0 input: transforms, normals, materials, the TOML override, KHR_lights_punctual,
//! the three ways of storing buffers, and errors that name the file.

use std::f32::consts::PI;
use std::path::{Path, PathBuf};

use base64::Engine;
use bdpm_load::{LoadError, LoadedScene, load_scene};
use glam::Vec3;

/// A fresh directory for one test, removed when dropped.
fn temp_dir(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("bdpm-load-test-{name}-"))
        .tempdir()
        .expect("temp dir")
}

/// The binary buffer: a unit quad's positions (48 bytes), tilted normals (48 bytes) and
/// u16 indices (12 bytes).
fn buffer_bytes() -> Vec<u8> {
    let mut b = Vec::new();
    for p in [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ] {
        p.iter().for_each(|c| b.extend_from_slice(&c.to_le_bytes()));
    }
    let s = 0.5f32.sqrt();
    for _ in 0..4 {
        [s, 0.0f32, s]
            .iter()
            .for_each(|c| b.extend_from_slice(&c.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    assert_eq!(b.len(), 108);
    b
}

/// glTF JSON whose buffer 0 is `buffer` (a `"uri": ...` member, or empty for a GLB chunk).
/// `count0` is the vertex count of accessor 0 (4 is valid).
fn gltf_json(buffer: &str, count0: usize) -> String {
    let sep = if buffer.is_empty() { "" } else { ", " };
    format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{ "KHR_lights_punctual": {{ "lights": [
    {{ "type": "point", "color": [1.0, 0.5, 0.25], "intensity": 2.0 }},
    {{ "type": "spot", "spot": {{ "outerConeAngle": 0.7 }} }}
  ] }} }},
  "buffers": [ {{ "byteLength": 108{sep}{buffer} }} ],
  "bufferViews": [
    {{ "buffer": 0, "byteOffset": 0, "byteLength": 48 }},
    {{ "buffer": 0, "byteOffset": 48, "byteLength": 48 }},
    {{ "buffer": 0, "byteOffset": 96, "byteLength": 12 }}
  ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": {count0}, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] }},
    {{ "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" }},
    {{ "bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR" }},
    {{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] }}
  ],
  "materials": [
    {{ "name": "painted", "pbrMetallicRoughness": {{ "baseColorFactor": [0.2, 0.4, 0.6, 1.0] }} }},
    {{ "name": "red", "pbrMetallicRoughness": {{ "baseColorFactor": [0.0, 1.0, 0.0, 1.0] }} }},
    {{ "pbrMetallicRoughness": {{ "baseColorFactor": [0.3, 0.3, 0.3, 1.0] }} }}
  ],
  "meshes": [
    {{ "primitives": [ {{ "attributes": {{ "POSITION": 0, "NORMAL": 1 }}, "indices": 2, "material": 0 }} ] }},
    {{ "primitives": [ {{ "attributes": {{ "POSITION": 0 }}, "indices": 2, "material": 1 }} ] }},
    {{ "primitives": [
      {{ "attributes": {{ "POSITION": 3 }} }},
      {{ "attributes": {{ "POSITION": 0 }}, "mode": 1 }}
    ] }},
    {{ "primitives": [ {{ "attributes": {{ "POSITION": 0 }}, "indices": 2, "material": 2 }} ] }}
  ],
  "nodes": [
    {{ "mesh": 0, "translation": [1, 2, 3], "scale": [2, 1, 1] }},
    {{ "mesh": 1, "translation": [0, 0, 5], "children": [2] }},
    {{ "translation": [0, 1, 0], "extensions": {{ "KHR_lights_punctual": {{ "light": 0 }} }} }},
    {{ "mesh": 2 }},
    {{ "extensions": {{ "KHR_lights_punctual": {{ "light": 1 }} }} }},
    {{ "mesh": 3, "translation": [10, 0, 0] }}
  ],
  "scenes": [ {{ "nodes": [0, 1, 3, 4, 5] }} ],
  "scene": 0
}}"#
    )
}

/// A scene file that places `file` with scale 0.5 and translation (0, 0, 1), and defines a
/// TOML material "red" that overrides the glTF one of that name.
fn scene_toml(file: &str) -> String {
    format!(
        r#"
[camera]
position = [0.5, 0.5, -3.0]
look_at = [0.5, 0.5, 0.0]
vfov = 40

[material.red]
kd = [0.9, 0.1, 0.1]

[[shape]]
type = "gltf"
file = "{file}"
scale = 0.5
translate = [0.0, 0.0, 1.0]
"#
    )
}

fn write_scene(dir: &Path, gltf_name: &str, gltf: &[u8]) -> PathBuf {
    std::fs::write(dir.join(gltf_name), gltf).expect("write gltf");
    let toml = dir.join("scene.toml");
    std::fs::write(&toml, scene_toml(gltf_name)).expect("write toml");
    toml
}

fn data_uri_json() -> String {
    let b64 = base64::engine::general_purpose::STANDARD.encode(buffer_bytes());
    gltf_json(
        &format!(r#""uri": "data:application/octet-stream;base64,{b64}""#),
        4,
    )
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

/// Everything the test file encodes, checked on a loaded scene.
fn check(s: &LoadedScene, gltf_path: &Path) {
    let g = &s.scene.geometry();
    // Mesh 0 (2) + mesh 1 (2) + mesh 2's triangle (1) + mesh 3 (2); the line primitive is skipped.
    assert_eq!(s.report.triangles, 7);
    assert_eq!(s.report.skipped_primitives, 1);
    assert_eq!(s.report.skipped_lights, 1);
    assert_eq!(s.report.flat_primitives, 3);
    assert_eq!(s.report.computed_normals, 0);
    assert_eq!(s.report.gltf_files, vec![gltf_path.to_path_buf()]);
    // TOML "red", glTF "painted", the default, and the unnamed material 2.
    assert_eq!(s.report.materials, 4);

    // Node 0: T(1,2,3)·S(2,1,1), then the TOML placement p·0.5 + (0,0,1).
    let v = g.vertices(0);
    assert!(close(v[2], Vec3::new(1.5, 1.5, 2.5), 1e-6), "{v:?}");
    let hit = g
        .intersect(Vec3::new(1.0, 1.25, 0.0), Vec3::Z, f32::INFINITY)
        .expect("node 0 quad");
    assert!((hit.p.z - 2.5).abs() < 1e-6);
    let m = &s.scene.materials()[hit.material as usize];
    assert_eq!(m.name, "painted");
    assert_eq!(m.bdf.kd(), Vec3::new(0.2, 0.4, 0.6));
    // Normal (1,0,1)/√2 under scale (2,1,1): the inverse transpose gives (0.5,0,1) normalised.
    assert!(
        close(hit.ns, Vec3::new(0.5, 0.0, 1.0).normalize(), 1e-5),
        "ns {}",
        hit.ns
    );

    // Node 1 uses glTF material "red", overridden by the TOML definition.
    let hit = g
        .intersect(Vec3::new(0.1, 0.4, 0.0), Vec3::Z, f32::INFINITY)
        .expect("node 1 quad");
    assert!((hit.p.z - 3.5).abs() < 1e-6);
    let m = &s.scene.materials()[hit.material as usize];
    assert_eq!(m.name, "red");
    assert_eq!(m.bdf.kd(), Vec3::new(0.9, 0.1, 0.1));
    assert_eq!(hit.ns, hit.ng, "no normals in the file: flat");

    // Node 3: a non-indexed triangle without material: the default Lambert 0.8.
    let hit = g
        .intersect(Vec3::new(0.4, 0.1, 0.0), Vec3::Z, f32::INFINITY)
        .expect("node 3 triangle");
    assert!((hit.p.z - 1.0).abs() < 1e-6);
    let m = &s.scene.materials()[hit.material as usize];
    assert_eq!(m.name, "gltf:default");
    assert_eq!(m.bdf.kd(), Vec3::splat(0.8));

    // Node 5: an unnamed material gets a generated name.
    let hit = g
        .intersect(Vec3::new(5.25, 0.25, 0.0), Vec3::Z, f32::INFINITY)
        .expect("node 5 quad");
    let m = &s.scene.materials()[hit.material as usize];
    assert!(
        m.name.starts_with("gltf:") && m.name.ends_with("#2"),
        "{}",
        m.name
    );
    assert_eq!(m.bdf.kd(), Vec3::splat(0.3));

    // The point light of node 2 (child of node 1): (0,1,0) + (0,0,5), then the placement.
    assert_eq!(s.scene.lights().len(), 1);
    let light = s.scene.lights()[0];
    assert!(
        close(light.position, Vec3::new(0.0, 0.5, 3.5), 1e-6),
        "{}",
        light.position
    );
    let expected = 4.0 * PI * 2.0 * Vec3::new(1.0, 0.5, 0.25);
    assert!(close(light.flux, expected, 1e-5), "{}", light.flux);
}

#[test]
fn gltf_with_data_uri_buffer() {
    let tmp = temp_dir("data-uri");
    let dir = tmp.path();
    let toml = write_scene(dir, "t.gltf", data_uri_json().as_bytes());
    let s = load_scene(&toml).unwrap_or_else(|e| panic!("{e}"));
    check(&s, &dir.join("t.gltf"));
}

#[test]
fn gltf_with_external_buffer() {
    let tmp = temp_dir("external");
    let dir = tmp.path();
    std::fs::create_dir_all(dir.join("meshes")).expect("dir");
    std::fs::write(dir.join("meshes/t.bin"), buffer_bytes()).expect("write bin");
    let toml = write_scene(
        dir,
        "meshes/t.gltf",
        gltf_json(r#""uri": "t.bin""#, 4).as_bytes(),
    );
    let s = load_scene(&toml).unwrap_or_else(|e| panic!("{e}"));
    check(&s, &dir.join("meshes/t.gltf"));
}

#[test]
fn gltf_binary_glb() {
    let tmp = temp_dir("glb");
    let dir = tmp.path();
    let toml = write_scene(dir, "t.glb", &glb(&gltf_json("", 4), &buffer_bytes()));
    let s = load_scene(&toml).unwrap_or_else(|e| panic!("{e}"));
    check(&s, &dir.join("t.glb"));
}

fn error_of(dir: &Path, toml: &Path) -> (LoadError, String) {
    let e = match load_scene(toml) {
        Ok(_) => panic!("accepted {}", toml.display()),
        Err(e) => e,
    };
    let msg = e.to_string();
    assert!(!msg.contains('\n'), "{msg}");
    assert!(msg.contains(&dir.display().to_string()), "{msg}");
    (e, msg)
}

#[test]
fn missing_gltf_file() {
    let tmp = temp_dir("missing");
    let dir = tmp.path();
    let toml = dir.join("scene.toml");
    std::fs::write(&toml, scene_toml("meshes/a.gltf")).expect("write");
    let (_, msg) = error_of(dir, &toml);
    assert!(
        msg.contains("meshes/a.gltf (from shape[0].file): cannot read: "),
        "{msg}"
    );
}

#[test]
fn missing_external_buffer() {
    let tmp = temp_dir("missing-bin");
    let dir = tmp.path();
    let toml = write_scene(
        dir,
        "t.gltf",
        gltf_json(r#""uri": "gone.bin""#, 4).as_bytes(),
    );
    let (_, msg) = error_of(dir, &toml);
    assert!(
        msg.contains("gone.bin (from shape[0].file, buffer 0 of "),
        "{msg}"
    );
    assert!(msg.contains("cannot read"), "{msg}");
}

#[test]
fn garbage_gltf_file() {
    let tmp = temp_dir("garbage");
    let dir = tmp.path();
    let bytes: Vec<u8> = (0..4096u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    let toml = write_scene(dir, "t.gltf", &bytes);
    let (e, msg) = error_of(dir, &toml);
    assert!(matches!(e, LoadError::Gltf { .. }), "{msg}");
    assert!(
        msg.contains("t.gltf (from shape[0].file): not a valid glTF 2.0 file"),
        "{msg}"
    );
}

#[test]
fn bad_json() {
    let tmp = temp_dir("bad-json");
    let dir = tmp.path();
    let toml = write_scene(
        dir,
        "t.gltf",
        br#"{ "asset": { "version": "2.0" }, "nodes": [ "#,
    );
    let (_, msg) = error_of(dir, &toml);
    assert!(
        msg.contains("t.gltf (from shape[0].file): not a valid glTF 2.0 file"),
        "{msg}"
    );
}

#[test]
fn accessor_out_of_range() {
    let tmp = temp_dir("accessor");
    let dir = tmp.path();
    let b64 = base64::engine::general_purpose::STANDARD.encode(buffer_bytes());
    let json = gltf_json(
        &format!(r#""uri": "data:application/octet-stream;base64,{b64}""#),
        100,
    );
    let toml = write_scene(dir, "t.gltf", json.as_bytes());
    let (_, msg) = error_of(dir, &toml);
    assert!(
        msg.contains(
            "t.gltf (from shape[0].file): mesh 0 primitive 0: POSITION: accessor 0 reaches past"
        ),
        "{msg}"
    );
}

#[test]
fn truncated_and_corrupted_files_never_panic() {
    let tmp = temp_dir("fuzz");
    let dir = tmp.path();
    let json = data_uri_json();
    let binary = glb(&gltf_json("", 4), &buffer_bytes());
    for source in [json.as_bytes(), binary.as_slice()] {
        for cut in (0..source.len()).step_by(97) {
            let toml = write_scene(dir, "t.gltf", &source[..cut]);
            let _ = load_scene(&toml);
        }
        for i in (0..source.len()).step_by(3) {
            for b in [b'0', b'9', b'-', b'"', b'}', 0xff, 0] {
                let mut v = source.to_vec();
                v[i] = b;
                let toml = write_scene(dir, "t.gltf", &v);
                let _ = load_scene(&toml);
            }
        }
    }
}

// ---- Issue 15: strips and fans, reported skips, confined buffer URIs, real files.

/// glTF using the unit quad's positions (accessor 0) as a strip, a fan and points, with a
/// textured material on the strip (a dielectric: glTF's default metallicFactor 1 would add a
/// rough-metal warning) and a camera node.
fn modes_json(buffer_uri: &str) -> String {
    format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "buffers": [ {{ "byteLength": 108, "uri": "{buffer_uri}" }} ],
  "bufferViews": [ {{ "buffer": 0, "byteOffset": 0, "byteLength": 48 }} ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] }}
  ],
  "images": [ {{ "uri": "wood.png" }} ],
  "textures": [ {{ "source": 0 }} ],
  "materials": [
    {{ "name": "wood", "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0 }}, "metallicFactor": 0 }} }}
  ],
  "cameras": [ {{ "type": "perspective", "perspective": {{ "yfov": 0.8, "znear": 0.1 }} }} ],
  "meshes": [
    {{ "primitives": [ {{ "attributes": {{ "POSITION": 0 }}, "mode": 5, "material": 0 }} ] }},
    {{ "primitives": [ {{ "attributes": {{ "POSITION": 0 }}, "mode": 6 }} ] }},
    {{ "primitives": [ {{ "attributes": {{ "POSITION": 0 }}, "mode": 0 }} ] }}
  ],
  "nodes": [
    {{ "mesh": 0 }},
    {{ "mesh": 1, "translation": [0, 0, 1] }},
    {{ "mesh": 2 }},
    {{ "camera": 0, "translation": [0, 0, 5] }}
  ],
  "scenes": [ {{ "nodes": [0, 1, 2, 3] }} ]
}}"#
    )
}

/// A scene file with a light that places `file` as it is.
fn plain_scene(file: &str) -> String {
    format!(
        r#"
[camera]
position = [0.5, 0.5, -3.0]
look_at = [0.5, 0.5, 0.0]
vfov = 40

[[light]]
position = [0.5, 0.5, -1.0]
flux = 1.0

[[shape]]
type = "gltf"
file = "{file}"
"#
    )
}

fn load_in(dir: &Path, gltf_name: &str, gltf: &str) -> Result<LoadedScene, LoadError> {
    std::fs::write(dir.join(gltf_name), gltf).expect("write gltf");
    let toml = dir.join("scene.toml");
    std::fs::write(&toml, plain_scene(gltf_name)).expect("write toml");
    load_scene(&toml)
}

#[test]
fn strips_and_fans_become_triangle_lists_and_skips_are_counted() {
    let tmp = temp_dir("modes");
    let dir = tmp.path();
    std::fs::write(dir.join("quad.bin"), buffer_bytes()).expect("write bin");
    // A 1×1 sRGB image of value 188 = linear 0.5 (the strip has no TEXCOORD_0: it reads
    // the texel at (0, 0)).
    std::fs::write(dir.join("wood.png"), png_bytes(1, 1, &[188, 188, 188])).expect("write png");
    let s = load_in(dir, "m.gltf", &modes_json("quad.bin")).expect("loads");
    // Strip (0,1,2), (1,3,2) and fan (1,2,0), (2,3,0): four triangles; the points skipped.
    assert_eq!(s.report.triangles, 4);
    assert_eq!(s.report.strips_and_fans, 2);
    assert_eq!(s.report.skipped_primitives, 1);
    assert_eq!(s.report.skipped_cameras, 1);
    assert_eq!(s.report.textured_materials, 1);
    assert_eq!(s.report.textures, 1);
    let warnings = s.report.warnings();
    assert_eq!(warnings.len(), 2, "{warnings:?}");
    assert!(
        !warnings.iter().any(|w| w.contains("texture")),
        "{warnings:?}"
    );
    // The strip's triangles are the specification's (v0, v1, v2), (v1, v3, v2); the fan's
    // (v1, v2, v0), (v2, v3, v0), both facing +z like the quad.
    let g = &s.scene.geometry();
    let q = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let up = Vec3::Z;
    let mut expected = vec![[q[0], q[1], q[2]], [q[1], q[3], q[2]]];
    expected.extend([[q[1], q[2], q[0]], [q[2], q[3], q[0]]].map(|t| t.map(|v| v + up)));
    let mut found: Vec<[Vec3; 3]> = (0..4).map(|k| g.vertices(k)).collect();
    found.sort_by(|a, b| format!("{a:?}").cmp(&format!("{b:?}")));
    expected.sort_by(|a, b| format!("{a:?}").cmp(&format!("{b:?}")));
    assert_eq!(found, expected);
    for k in 0..4 {
        let [a, b, c] = g.vertices(k);
        if a.z == 1.0 {
            assert!((b - a).cross(c - a).z > 0.0, "fan triangle {k} flipped");
        }
    }
    // The fan (at z = 1) covers the whole quad: both diagonals' halves are hit.
    for (x, y) in [(0.8, 0.2), (0.2, 0.8)] {
        let hit = g
            .intersect(Vec3::new(x, y, 0.5), Vec3::Z, f32::INFINITY)
            .expect("fan hit");
        assert!((hit.p.z - 1.0).abs() < 1e-6);
    }
}

#[test]
fn buffer_uris_are_confined_to_the_gltf_directory() {
    let tmp = temp_dir("confine");
    let dir = tmp.path();
    let sub = dir.join("models");
    std::fs::create_dir_all(&sub).expect("mkdir");
    std::fs::write(dir.join("outside.bin"), buffer_bytes()).expect("write");
    std::fs::write(sub.join("quad.bin"), buffer_bytes()).expect("write");
    std::fs::write(sub.join("wood.png"), png_bytes(1, 1, &[188, 188, 188])).expect("write");
    let load = |uri: &str| {
        std::fs::write(sub.join("m.gltf"), modes_json(uri)).expect("write gltf");
        let toml = dir.join("scene.toml");
        std::fs::write(&toml, plain_scene("models/m.gltf")).expect("write toml");
        load_scene(&toml).map(|_| ()).map_err(|e| e.to_string())
    };
    assert_eq!(load("quad.bin"), Ok(()));
    assert_eq!(load("./quad%2Ebin"), Ok(()));
    let outside = dir.join("outside.bin");
    for (uri, needle) in [
        ("../outside.bin", "'..'"),
        ("%2E%2E/outside.bin", "'..'"),
        (outside.to_str().expect("utf-8"), "absolute"),
        ("file:///etc/hostname", "scheme"),
    ] {
        let e = load(uri).expect_err(uri);
        assert!(e.contains("buffer 0") && e.contains(needle), "{uri}: {e}");
        assert!(e.contains("models/m.gltf") && !e.contains('\n'), "{e}");
    }
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&outside, sub.join("link.bin")).expect("symlink");
        let e = load("link.bin").expect_err("symlink out");
        assert!(e.contains("outside the glTF file's directory"), "{e}");
        // A FIFO as the buffer or as the glTF file must not hang the loader, and an endless
        // device must not be read.
        let fifo = sub.join("fifo.bin");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            let e = load("fifo.bin").expect_err("fifo buffer");
            assert!(e.contains("not a regular file"), "{e}");
            let toml = dir.join("fifo.toml");
            std::fs::write(&toml, plain_scene("models/fifo.bin")).expect("write toml");
            let e = load_scene(&toml).expect_err("fifo gltf").to_string();
            assert!(e.contains("not a regular file"), "{e}");
        }
        let toml = dir.join("zero.toml");
        std::fs::write(&toml, plain_scene("/dev/zero")).expect("write toml");
        let e = load_scene(&toml).expect_err("/dev/zero").to_string();
        assert!(e.contains("not a regular file"), "{e}");
        let e = load_scene(Path::new("/dev/zero"))
            .expect_err("scene")
            .to_string();
        assert!(
            e.contains("/dev/zero") && e.contains("not a regular file"),
            "{e}"
        );
    }
}

/// The glTF 2.0 files of Debian's `assimp-testmodels` package (real exporters' output and
/// deliberately broken files), when installed: each must load or fail with one line naming
/// the file, never panic. Prints which load and which fail, with the message.
#[test]
fn real_gltf_collection_loads_or_fails_cleanly() {
    let root = Path::new("/usr/share/assimp/models/glTF2");
    if !root.is_dir() {
        eprintln!(
            "skipped: {} is absent (apt-get install assimp-testmodels to run this test)",
            root.display()
        );
        return;
    }
    let mut files = Vec::new();
    let mut dirs = vec![root.to_path_buf()];
    while let Some(d) = dirs.pop() {
        for entry in std::fs::read_dir(&d).expect("read dir").flatten() {
            let p = entry.path();
            if p.is_dir() {
                dirs.push(p);
            } else if p
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
            {
                files.push(p);
            }
        }
    }
    files.sort();
    let tmp = temp_dir("assimp");
    let dir = tmp.path();
    let (mut loaded, mut failed) = (0, 0);
    for file in &files {
        let toml = dir.join("scene.toml");
        let text = plain_scene(&file.display().to_string());
        std::fs::write(&toml, text).expect("write toml");
        let name = file
            .strip_prefix(root)
            .unwrap_or(file)
            .display()
            .to_string();
        match std::panic::catch_unwind(|| load_scene(&toml)) {
            Err(_) => panic!("{name}: the loader panicked"),
            Ok(Ok(s)) => {
                loaded += 1;
                let r = &s.report;
                eprintln!(
                    "loads  {name}: {} triangles, {} strips/fans, skipped {} points/lines, {} lights, {} cameras, {} textured materials",
                    r.triangles,
                    r.strips_and_fans,
                    r.skipped_primitives,
                    r.skipped_lights,
                    r.skipped_cameras,
                    r.textured_materials
                );
            }
            Ok(Err(e)) => {
                failed += 1;
                let m = e.to_string();
                assert!(!m.contains('\n'), "{name}: {m}");
                // The glTF file, or the scene file when nothing renderable was left.
                assert!(
                    m.contains(&file.display().to_string()) || m.contains("scene.toml"),
                    "{name}: {m}"
                );
                eprintln!("fails  {name}: {m}");
            }
        }
    }
    eprintln!("{loaded} of {} files load, {failed} fail", files.len());
    assert!(loaded > 0, "none of {} files loaded", files.len());
    // The asset generator's primitive-mode files: modes 4–6 (triangles, strips, fans) load
    // with triangles; 0–3 (points, lines) are skipped.
    let modes = root.join("glTF-Asset-Generator/Mesh_PrimitiveMode");
    if modes.is_dir() {
        let mut strips_or_fans = 0;
        for k in 0..16 {
            let file = modes.join(format!("Mesh_PrimitiveMode_{k:02}.gltf"));
            let toml = dir.join("mode.toml");
            std::fs::write(&toml, plain_scene(&file.display().to_string())).expect("write");
            if let Ok(s) = load_scene(&toml) {
                strips_or_fans += s.report.strips_and_fans;
            }
        }
        assert!(
            strips_or_fans > 0,
            "no strip or fan found in {}",
            modes.display()
        );
    }
}

/// An 8-bit sRGB RGB PNG of `width` × `height` texels (row-major from the top).
fn png_bytes(width: u32, height: u32, rgb: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().expect("png header");
    writer.write_image_data(rgb).expect("png data");
    writer.finish().expect("png end");
    out
}
