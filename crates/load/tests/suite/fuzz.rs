//! A fuzz harness for the scene loaders: random byte edits, truncations and token insertions
//! applied to the repository's scene files and to a glTF file, which must give `Ok` or an
//! error, never a panic (proptest reports a panic as a failure, with a shrunk input).
//!
//! The default run is bounded for CI (256 cases per target). Run longer with e.g.
//! `PROPTEST_CASES=100000 cargo test --release -p bdpm-load --test suite fuzz::`.

use std::path::{Path, PathBuf};

use bdpm_load::{load_scene, load_scene_str};
use proptest::prelude::*;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn seeds() -> Vec<String> {
    [
        "cornell-lambert.toml",
        "cornell-glossy.toml",
        "preprint/cornell-lambert.toml",
        "sphere-furnace.toml",
    ]
    .iter()
    .map(|f| std::fs::read_to_string(repo().join("scenes").join(f)).unwrap())
    .chain(std::iter::once(
        std::fs::read_to_string(repo().join("docs/scene-format.md")).unwrap_or_default(),
    ))
    .collect()
}

/// Tokens that stress the parser and the range checks.
const TOKENS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "1e38",
    "1e-45",
    "16385",
    "\"\"",
    "[]",
    "[[shape]]",
    "[render]",
    "=",
    "\n",
    "type = \"sphere\"",
    "subdivisions = 256",
    "resolution = [0, 0]",
    "kd = 2",
    "delta = 0",
    "vertices = [[0,0,0]]",
    "file = \"missing.gltf\"",
    "mode = \"x\"",
];

#[derive(Debug, Clone)]
enum Edit {
    Byte(usize, u8),
    Truncate(usize),
    Insert(usize, usize),
    Delete(usize, usize),
}

fn apply(mut bytes: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        let n = bytes.len().max(1);
        match *e {
            Edit::Byte(i, b) => {
                if !bytes.is_empty() {
                    bytes[i % n] = b;
                }
            }
            Edit::Truncate(i) => bytes.truncate(i % n),
            Edit::Insert(i, t) => {
                let at = (i % n).min(bytes.len());
                let tok = TOKENS[t % TOKENS.len()].as_bytes();
                bytes.splice(at..at, tok.iter().copied());
            }
            Edit::Delete(i, len) => {
                let at = (i % n).min(bytes.len());
                let end = (at + len % 64).min(bytes.len());
                bytes.drain(at..end);
            }
        }
    }
    bytes
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    let edit = prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Byte(i, b)),
        any::<usize>().prop_map(Edit::Truncate),
        (any::<usize>(), any::<usize>()).prop_map(|(i, t)| Edit::Insert(i, t)),
        (any::<usize>(), any::<usize>()).prop_map(|(i, l)| Edit::Delete(i, l)),
    ];
    prop::collection::vec(edit, 1..6)
}

/// A small valid glTF (one quad with normals, a named material, a point light) as JSON with
/// an embedded buffer.
fn gltf_seed() -> Vec<u8> {
    let positions: [[f32; 3]; 4] = [[0., 0., 0.], [1., 0., 0.], [1., 0., 1.], [0., 0., 1.]];
    let mut buf = Vec::new();
    for p in positions {
        for c in p {
            buf.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 2, 1, 0, 3, 2] {
        buf.extend_from_slice(&i.to_le_bytes());
    }
    use base64::Engine;
    let b64 = base64::engine::general_purpose::STANDARD.encode(&buf);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
"nodes":[{{"mesh":0,"translation":[0,0.5,0]}},{{"extensions":{{"KHR_lights_punctual":{{"light":0}}}},"translation":[0.5,1,0.5]}}],
"extensionsUsed":["KHR_lights_punctual"],
"extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"point","intensity":2.0,"color":[1,1,1]}}]}}}},
"materials":[{{"name":"grey","pbrMetallicRoughness":{{"baseColorFactor":[0.5,0.5,0.5,1]}}}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
"buffers":[{{"byteLength":{len},"uri":"data:application/octet-stream;base64,{b64}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,0,1]}},
{{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}}]}}"#,
        len = buf.len()
    )
    .into_bytes()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_scene_files_never_panic(which in 0usize..4, e in edits()) {
        let seeds = seeds();
        let text = String::from_utf8_lossy(&apply(seeds[which].clone().into_bytes(), &e)).into_owned();
        let _ = load_scene_str(&text, &repo().join("scenes"), Path::new("<fuzz>"));
    }

    #[test]
    fn mutated_gltf_files_never_panic(e in edits()) {
        let tmp = tempfile::Builder::new().prefix("bdpm-fuzz-").tempdir().unwrap();
        let dir = tmp.path();
        let gltf = dir.join("m.gltf");
        std::fs::write(&gltf, apply(gltf_seed(), &e)).unwrap();
        let scene = dir.join("s.toml");
        std::fs::write(&scene, "[camera]\nposition = [0.5, 2, -2]\nlook_at = [0.5, 0, 0.5]\nvfov = 40\n[[shape]]\ntype = \"mesh\"\nfile = \"m.gltf\"\n").unwrap();
        let _ = load_scene(&scene);
    }
}

#[test]
fn the_unmutated_gltf_seed_loads() {
    // The harness is worthless if its seed is already rejected.
    let tmp = tempfile::Builder::new()
        .prefix("bdpm-fuzz-seed-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    std::fs::write(dir.join("m.gltf"), gltf_seed()).unwrap();
    let scene = dir.join("s.toml");
    std::fs::write(&scene, "[camera]\nposition = [0.5, 2, -2]\nlook_at = [0.5, 0, 0.5]\nvfov = 40\n[[shape]]\ntype = \"mesh\"\nfile = \"m.gltf\"\n").unwrap();
    let loaded = load_scene(&scene).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded.scene.lights().len(), 1);
    assert_eq!(loaded.report.triangles, 2);
}
