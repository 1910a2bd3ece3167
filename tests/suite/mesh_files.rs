//! OBJ and PLY meshes against the built-in shapes: the Cornell box's quads written by the
//! test as an OBJ, an ASCII PLY and a binary little-endian PLY load to the very triangles of
//! the TOML quads, and render to the same image bits.

use std::fmt::Write as _;
use std::path::Path;

use bdpm_geometry::Geometry;
use bdpm_integrator::Renderer;
use bdpm_load::load_scene;
use bdpm_suite::{render_with, scene_path, with_mode};
use glam::Vec3;

/// The geometry's triangles as the quads they were split from: triangles 2k and 2k + 1 are
/// (a, b, c) and (a, c, d), the built-in quad's split.
fn quads(g: &Geometry) -> Vec<[Vec3; 4]> {
    assert_eq!(g.triangle_count() % 2, 0);
    (0..g.triangle_count() as u32 / 2)
        .map(|k| {
            let (t, u) = (g.vertices(2 * k), g.vertices(2 * k + 1));
            assert_eq!((u[0], u[1]), (t[0], t[2]), "quad {k} split otherwise");
            [t[0], t[1], t[2], u[2]]
        })
        .collect()
}

/// An OBJ of the quads (f32 written shortest-exact, so read back bit for bit).
fn obj(quads: &[[Vec3; 4]]) -> String {
    let mut s = String::from("# written by the test\nmtllib none.mtl\no box\n");
    for q in quads {
        for v in q {
            writeln!(s, "v {} {} {}", v.x, v.y, v.z).unwrap();
        }
    }
    for k in 0..quads.len() {
        let b = 4 * k + 1;
        writeln!(s, "f {} {} {} {}", b, b + 1, b + 2, b + 3).unwrap();
    }
    s
}

fn ply_header(format: &str, quads: &[[Vec3; 4]]) -> String {
    format!(
        "ply\nformat {format} 1.0\ncomment written by the test\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        4 * quads.len(),
        quads.len()
    )
}

fn ply_ascii(quads: &[[Vec3; 4]]) -> Vec<u8> {
    let mut s = ply_header("ascii", quads);
    for v in quads.iter().flatten() {
        writeln!(s, "{} {} {}", v.x, v.y, v.z).unwrap();
    }
    for k in 0..quads.len() {
        let b = 4 * k;
        writeln!(s, "4 {} {} {} {}", b, b + 1, b + 2, b + 3).unwrap();
    }
    s.into_bytes()
}

fn ply_binary(quads: &[[Vec3; 4]]) -> Vec<u8> {
    let mut out = ply_header("binary_little_endian", quads).into_bytes();
    for v in quads.iter().flatten() {
        for c in v.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for k in 0..quads.len() as i32 {
        out.push(4);
        for i in 4 * k..4 * k + 4 {
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
    out
}

/// A small image's mean and variance, bit for bit.
fn image_bits(scene_file: &Path) -> Vec<u64> {
    let loaded = load_scene(scene_file).unwrap_or_else(|e| panic!("{e}"));
    let mut scene = loaded.scene;
    scene.set_resolution(24, 24).expect("resolution");
    let settings = bdpm_integrator::RenderSettings {
        width: 24,
        height: 24,
        ..with_mode(&loaded.settings, "balance", 2, 2, 20_000)
    };
    let film = render_with(&Renderer::new(&scene, &settings).unwrap_or_else(|e| panic!("{e}")));
    let mut out = Vec::new();
    for v in film.mean().iter().chain(film.pass_variance().iter()) {
        out.extend(v.to_array().map(f64::to_bits));
    }
    assert!(film.mean().iter().any(|v| v.x > 0.0), "black image");
    out
}

#[test]
fn obj_and_ply_files_render_the_cornell_box_bit_for_bit() {
    let builtin_path = scene_path("cornell-lambert.toml");
    let builtin = load_scene(&builtin_path).unwrap_or_else(|e| panic!("{e}"));
    let g = builtin.scene.geometry();
    let quads = quads(g);
    assert_eq!(quads.len(), 15);
    // Everything but the shapes, which are all of material "grey".
    let text = std::fs::read_to_string(&builtin_path).expect("scene");
    let head = &text[..text.find("[[shape]]").expect("shapes")];

    let dir = tempfile::Builder::new()
        .prefix("bdpm-mesh-files-")
        .tempdir()
        .expect("temp dir");
    let files: [(&str, &str, Vec<u8>); 3] = [
        ("box.obj", "obj", obj(&quads).into_bytes()),
        ("box-ascii.ply", "ply", ply_ascii(&quads)),
        ("box-binary.ply", "ply", ply_binary(&quads)),
    ];
    let reference = image_bits(&builtin_path);
    for (name, kind, bytes) in files {
        std::fs::write(dir.path().join(name), bytes).expect("write mesh");
        let scene_file = dir.path().join(format!("{name}.toml"));
        let toml =
            format!("{head}[[shape]]\ntype = \"{kind}\"\nfile = \"{name}\"\nmaterial = \"grey\"\n");
        std::fs::write(&scene_file, toml).expect("write scene");
        let loaded = load_scene(&scene_file).unwrap_or_else(|e| panic!("{name}: {e}"));
        let h = loaded.scene.geometry();
        assert_eq!(h.triangle_count(), g.triangle_count(), "{name}");
        for k in 0..g.triangle_count() as u32 {
            assert_eq!(h.vertices(k), g.vertices(k), "{name}: triangle {k}");
            assert_eq!(h.normal(k), g.normal(k), "{name}: triangle {k}");
            assert_eq!(h.material(k), g.material(k), "{name}: triangle {k}");
        }
        assert!(
            image_bits(&scene_file) == reference,
            "{name}: the image differs from the built-in quads'"
        );
    }
}
