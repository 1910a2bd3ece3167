//! OBJ and PLY shapes: per-vertex normals and flat meshes, placement, and the errors, each one
//! line naming the scene file, the shape's field, the mesh file and what is wrong.

use bdpm_load::{LoadOptions, LoadedScene, MemoryLimit, load_scene, load_scene_with};
use glam::Vec3;

const HEAD: &str = r#"
[render]
resolution = [16, 16]
passes = 1

[camera]
position = [0.5, 0.5, -3.0]
look_at = [0.5, 0.5, 0.0]
vfov = 40.0

[[light]]
position = [0.5, 0.5, -1.0]
flux = 1.0

[material.grey]
kd = 0.5
"#;

/// A unit quad in z = 0 with tilted normals (1, 0, 1)/√2.
const QUAD_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 1 0 1\nf 1//1 2//1 3//1 4//1\n";

/// The same quad as an ASCII PLY, with or without normals.
fn quad_ply(normals: bool) -> String {
    let (props, n) = if normals {
        (
            "property float nx\nproperty float ny\nproperty float nz\n",
            " 1 0 1",
        )
    } else {
        ("", "")
    };
    format!(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n{props}\
         element face 1\nproperty list uchar uint vertex_indices\nend_header\n\
         0 0 0{n}\n1 0 0{n}\n1 1 0{n}\n0 1 0{n}\n4 0 1 2 3\n"
    )
}

/// Writes `mesh` as `name` and a scene naming it with `shape` extra lines, and loads it.
fn load_with(
    name: &str,
    mesh: &[u8],
    shape: &str,
    options: &LoadOptions,
) -> (tempfile::TempDir, Result<LoadedScene, String>) {
    let dir = tempfile::Builder::new()
        .prefix("bdpm-load-mesh-")
        .tempdir()
        .expect("temp dir");
    std::fs::write(dir.path().join(name), mesh).expect("write mesh");
    let kind = if name.ends_with(".ply") { "ply" } else { "obj" };
    let scene = format!(
        "{HEAD}\n[[shape]]\ntype = \"{kind}\"\nfile = \"{name}\"\nmaterial = \"grey\"\n{shape}\n"
    );
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, scene).expect("write scene");
    let loaded = load_scene_with(&path, options).map_err(|e| e.to_string());
    (dir, loaded)
}

fn load(name: &str, mesh: &[u8]) -> LoadedScene {
    let (_dir, loaded) = load_with(name, mesh, "", &LoadOptions::default());
    loaded.unwrap_or_else(|e| panic!("{e}"))
}

/// The error of loading `mesh` as `name`: one line naming the scene, the field and the file,
/// and containing `what`.
fn error_of(name: &str, mesh: &[u8], shape: &str, what: &str) {
    error_with(name, mesh, shape, &LoadOptions::default(), what);
}

fn error_with(name: &str, mesh: &[u8], shape: &str, options: &LoadOptions, what: &str) {
    let (dir, loaded) = load_with(name, mesh, shape, options);
    let Err(msg) = loaded else {
        panic!("{name} accepted: {}", String::from_utf8_lossy(mesh));
    };
    let scene = dir.path().join("scene.toml");
    let file = dir.path().join(name);
    assert!(!msg.contains('\n'), "{msg}");
    assert!(msg.starts_with(&format!("{}: ", scene.display())), "{msg}");
    assert!(msg.contains("shape[0].file"), "{msg}");
    assert!(msg.contains(&file.display().to_string()), "{msg}");
    assert!(msg.contains(what), "expected '{what}' in: {msg}");
}

#[test]
fn normals_are_read_and_placed_and_meshes_without_them_are_flat() {
    let tilted = Vec3::new(1.0, 0.0, 1.0).normalize();
    let cases: [(&str, Vec<u8>, bool); 4] = [
        ("quad.obj", QUAD_OBJ.into(), true),
        (
            "flat.obj",
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n".into(),
            false,
        ),
        ("quad.ply", quad_ply(true).into_bytes(), true),
        ("flat.ply", quad_ply(false).into_bytes(), false),
    ];
    for (name, mesh, smooth) in cases {
        let s = load(name, &mesh);
        let g = s.scene.geometry();
        assert_eq!(g.triangle_count(), 2, "{name}");
        assert_eq!(
            g.vertices(1),
            [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            "{name}"
        );
        let hit = g
            .intersect(Vec3::new(0.3, 0.6, -1.0), Vec3::Z, f32::INFINITY)
            .expect("quad");
        if smooth {
            assert!((hit.ns - tilted).length() < 1e-6, "{name}: ns {}", hit.ns);
        } else {
            assert_eq!(hit.ns, hit.ng, "{name}: flat");
        }
        assert_eq!(
            s.report.gltf_files.len(),
            1,
            "hashed with the scene's identity"
        );
    }
    // Scale (2, 1, 1): positions scaled, the normal by the inverse transpose.
    let (_dir, s) = load_with(
        "quad.obj",
        QUAD_OBJ.as_bytes(),
        "scale = [2.0, 1.0, 1.0]\ntranslate = [0.0, 0.0, 1.0]",
        &LoadOptions::default(),
    );
    let s = s.unwrap_or_else(|e| panic!("{e}"));
    let g = s.scene.geometry();
    assert_eq!(g.vertices(0)[2], Vec3::new(2.0, 1.0, 1.0));
    let hit = g
        .intersect(Vec3::new(0.5, 0.6, -1.0), Vec3::Z, f32::INFINITY)
        .expect("placed quad");
    let expected = Vec3::new(0.5, 0.0, 1.0).normalize();
    assert!((hit.ns - expected).length() < 1e-5, "ns {}", hit.ns);
}

#[test]
fn obj_errors_name_the_files_and_what_is_wrong() {
    let cases: [(&str, &str); 5] = [
        (
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 9\n",
            "face vertex index out of bounds",
        ),
        ("v 0 0 0\nv 1 0 x\nv 1 1 0\nf 1 2 3\n", "line 2"),
        ("v 0 0 0\nv 1 0 nan\nv 1 1 0\nf 1 2 3\n", "vertex 1"),
        ("v 0 0 0\nv 1 0 inf\nv 1 1 0\nf 1 2 3\n", "not finite"),
        ("v 0 0 0\nv 1 0 0\nv 1 1 0\nl 1 2\n", "has no faces"),
    ];
    for (text, what) in cases {
        error_of("m.obj", text.as_bytes(), "", what);
    }
}

#[test]
fn a_missing_mesh_file_is_named() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("scene.toml");
    let scene =
        format!("{HEAD}\n[[shape]]\ntype = \"ply\"\nfile = \"gone.ply\"\nmaterial = \"grey\"\n");
    std::fs::write(&path, scene).expect("write");
    let msg = load_scene(&path).expect_err("missing file").to_string();
    assert!(
        msg.contains("shape[0].file") && msg.contains("gone.ply"),
        "{msg}"
    );
    assert!(msg.contains("cannot read"), "{msg}");
    assert!(!msg.contains('\n'), "{msg}");
}

#[test]
fn ply_errors_name_the_files_and_what_is_wrong() {
    let good = quad_ply(false);
    let cases: [(String, &str); 7] = [
        (
            good.replace("4 0 1 2 3", "4 0 1 2 7"),
            "names vertex 7, but the file has 4 vertices",
        ),
        (good.replace("1 1 0\n", "1 1e39 0\n"), "not finite"),
        (good.replace("1 1 0\n", "1 x 0\n"), "'vertex'"),
        (
            good.replace("element face 1", "element face 0")
                .replace("4 0 1 2 3\n", ""),
            "has no faces",
        ),
        (
            good.replace("property float z\n", ""),
            "no scalar property 'z'",
        ),
        (good.replace("format ascii", "format nonsense"), "header"),
        (good.replace("4 0 1 2 3\n", ""), "'face'"),
    ];
    for (text, what) in cases {
        error_of("m.ply", text.as_bytes(), "", what);
    }
    // Binary, cut short in the vertex data.
    let mut binary = good
        .replace("format ascii", "format binary_little_endian")
        .split("end_header\n")
        .next()
        .unwrap()
        .to_string()
        .into_bytes();
    binary.extend_from_slice(b"end_header\n");
    binary.extend_from_slice(&[0u8; 20]);
    error_of("m.ply", &binary, "", "'vertex'");
    // Binary with a NaN coordinate.
    let mut nan = binary[..binary.len() - 20].to_vec();
    for c in [
        0.0f32,
        0.0,
        0.0,
        1.0,
        0.0,
        0.0,
        1.0,
        f32::NAN,
        0.0,
        0.0,
        1.0,
        0.0,
    ] {
        nan.extend_from_slice(&c.to_le_bytes());
    }
    nan.push(4);
    for i in 0u32..4 {
        nan.extend_from_slice(&i.to_le_bytes());
    }
    error_of(
        "m.ply",
        &nan,
        "",
        "vertex 2 at [1.0, NaN, 0.0] is not finite",
    );
}

#[test]
fn a_ply_header_over_the_memory_limit_is_refused_before_the_data() {
    // A header that declares a billion faces over a few bytes: refused from the header alone.
    let text = quad_ply(false).replace("element face 1", "element face 1000000000");
    let options = LoadOptions {
        memory_limit: Some(MemoryLimit {
            bytes: 200 << 20,
            source: "memory limit".into(),
            remedy: None,
        }),
    };
    error_with(
        "m.ply",
        text.as_bytes(),
        "",
        &options,
        "1000000000 faces as its header declares",
    );
    error_with(
        "m.ply",
        text.as_bytes(),
        "",
        &options,
        "more than the memory limit",
    );
}

#[test]
fn a_degenerate_triangle_is_warned_about_not_refused() {
    let s = load(
        "d.obj",
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n",
    );
    assert_eq!(s.report.degenerate_triangles, 1);
    assert_eq!(s.report.warnings().len(), 1);
}
