//! Mitsuba bitmap textures: PNG and EXR files as a diffuse reflectance and an area emitter's
//! radiance, texture coordinates from PLY and OBJ files in Mitsuba's convention, the codes
//! and factor behind exported EXR texels, and one-line errors for missing, corrupt and
//! unsupported bitmaps.

use std::path::Path;

use bdpm_load::{LoadOptions, MemoryLimit, load_scene, load_scene_with};
use bdpm_scene::{Wrap, srgb8_to_linear};
use glam::{Vec2, Vec3};

/// A scene file `scene.xml` in `dir` around `body` (a camera and a point light), with the
/// body on line 8.
fn write_scene(dir: &Path, body: &str) -> std::path::PathBuf {
    let text = format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <emitter type="point"><point name="position" x="0" y="0" z="3"/><rgb name="intensity" value="1"/></emitter>
{body}
</scene>"#
    );
    let path = dir.join("scene.xml");
    std::fs::write(&path, text).unwrap();
    path
}

/// A 2 × 1 RGB PNG of 8-bit texels.
fn png(texels: [[u8; 3]; 2]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut e = png::Encoder::new(&mut out, 2, 1);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    let mut w = e.write_header().unwrap();
    w.write_image_data(&texels.concat()).unwrap();
    w.finish().unwrap();
    out
}

/// A float RGB EXR of `width` × 1 texels.
fn exr(texels: &[Vec3]) -> Vec<u8> {
    use exr::prelude::{SpecificChannels, WritableImage};
    let channels = SpecificChannels::rgb(|p: exr::math::Vec2<usize>| {
        let t = texels[p.0];
        (t.x, t.y, t.z)
    });
    let image = exr::prelude::Image::from_channels((texels.len(), 1), channels);
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut bytes).unwrap();
    bytes.into_inner()
}

/// One triangle with texture coordinates (0.1, 0.2), (0.3, 0.4), (0.5, 0.6).
const PLY: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nproperty float u\nproperty float v\nelement face 1\n\
property list uchar uint vertex_indices\nend_header\n\
-1 -1 0 0.1 0.2\n1 -1 0 0.3 0.4\n0 1 0 0.5 0.6\n3 0 1 2\n";
const OBJ: &str =
    "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nvt 0.1 0.2\nvt 0.3 0.4\nvt 0.5 0.6\nf 1/1 2/2 3/3\n";

#[test]
fn png_reflectance_reads_through_ply_and_obj_texture_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("t.png"), png([[255, 128, 0], [10, 20, 30]])).unwrap();
    std::fs::write(dir.path().join("t.ply"), PLY).unwrap();
    std::fs::write(dir.path().join("t.obj"), OBJ).unwrap();
    // The PLY's texture nested, the OBJ's a reference to a top-level one of the same file.
    let bsdf = r#"<bsdf type="diffuse"><texture name="reflectance" type="bitmap"><string name="filename" value="t.png"/><string name="wrap_mode" value="clamp"/></texture></bsdf>"#;
    let body = format!(
        r#"<shape type="ply"><string name="filename" value="t.ply"/>{bsdf}</shape>
<texture type="bitmap" id="tex"><string name="filename" value="t.png"/></texture>
<shape type="obj"><string name="filename" value="t.obj"/><bsdf type="diffuse"><ref name="reflectance" id="tex"/></bsdf></shape>"#
    );
    let loaded = load_scene(&write_scene(dir.path(), &body)).unwrap_or_else(|e| panic!("{e}"));
    let s = &loaded.scene;
    assert_eq!(loaded.report.textures, 1, "one decode for both shapes");
    let t = s.texture(s.geometry().material(0)).expect("textured");
    assert_eq!(t.size(), (2, 1));
    let lin = |c: [u8; 3]| Vec3::from(c.map(srgb8_to_linear));
    assert_eq!(t.texel(0, 0), lin([255, 128, 0]));
    assert_eq!(t.texel(1, 0), lin([10, 20, 30]));
    let u = s
        .texture(s.geometry().material(1))
        .expect("textured by reference");
    assert!(std::sync::Arc::ptr_eq(t.image(), u.image()));
    assert_eq!(t.wraps(), (Wrap::ClampToEdge, Wrap::ClampToEdge));
    assert_eq!(u.wraps(), (Wrap::Repeat, Wrap::Repeat));
    assert_eq!(
        s.materials()[s.geometry().material(0) as usize].bdf.kd(),
        Vec3::ONE
    );
    let uv = |a: f32, b: f32, c: f32| [Vec2::new(0.1, a), Vec2::new(0.3, b), Vec2::new(0.5, c)];
    // The PLY's v as written; the OBJ's flipped, as Mitsuba reads vt (in f32).
    assert_eq!(s.texcoords(0), Some(uv(0.2, 0.4, 0.6)));
    assert_eq!(
        s.texcoords(1),
        Some(uv(1.0 - 0.2f32, 1.0 - 0.4f32, 1.0 - 0.6f32))
    );
}

#[test]
fn exr_radiance_comes_back_as_codes_and_factor_or_as_linear_texels() {
    let dir = tempfile::tempdir().unwrap();
    // As bdpm-export writes an emissive texture: table value × the emission factor, in f32.
    let codes = [[255u8, 128, 0], [0, 0, 90]];
    let factor = Vec3::new(10.0, 9.0, 7.5);
    let texels: Vec<Vec3> = codes
        .iter()
        .map(|c| Vec3::from(c.map(srgb8_to_linear)) * factor)
        .collect();
    std::fs::write(dir.path().join("e.exr"), exr(&texels)).unwrap();
    // Values on no table × factor: linear texels scaled by each channel's largest value.
    std::fs::write(
        dir.path().join("f.exr"),
        exr(&[Vec3::new(0.3, 2.0, 0.0), Vec3::new(0.7, 1.0, 0.0)]),
    )
    .unwrap();
    std::fs::write(dir.path().join("t.ply"), PLY).unwrap();
    let shape = |file: &str| {
        format!(
            r#"<shape type="ply"><string name="filename" value="t.ply"/><emitter type="area"><texture name="radiance" type="bitmap"><string name="filename" value="{file}"/><boolean name="raw" value="true"/></texture></emitter></shape>"#
        )
    };
    let body = shape("e.exr") + "\n" + &shape("f.exr");
    let loaded = load_scene(&write_scene(dir.path(), &body)).unwrap_or_else(|e| panic!("{e}"));
    let s = &loaded.scene;
    let (m0, m1) = (s.geometry().material(0), s.geometry().material(1));
    assert_eq!(s.materials()[m0 as usize].emission, factor);
    let t = s.emission_texture(m0).expect("emissive texture");
    for (x, c) in codes.iter().enumerate() {
        assert_eq!(t.texel(x as u32, 0), Vec3::from(c.map(srgb8_to_linear)));
    }
    assert_eq!(
        s.emission_texcoords(0).map(|t| t[2]),
        Some(Vec2::new(0.5, 0.6))
    );
    assert_eq!(
        s.materials()[m1 as usize].emission,
        Vec3::new(0.7, 2.0, 0.0)
    );
    let t = s.emission_texture(m1).expect("emissive texture");
    assert_eq!(t.texel(0, 0), Vec3::new(0.3 / 0.7, 1.0, 0.0));
    assert_eq!(t.texel(1, 0), Vec3::new(1.0, 0.5, 0.0));
}

/// The error's one line, checked to name the scene file, line 8 and `element`, and to say
/// `what`.
fn refused(dir: &Path, body: &str, element: &str, what: &str) {
    let path = write_scene(dir, body);
    let e = load_scene(&path).expect_err("refused").to_string();
    assert!(!e.contains('\n'), "{e}");
    let start = format!("{}: line 8: {element}", path.display());
    assert!(e.starts_with(&start) && e.contains(what), "{e}");
}

#[test]
fn bad_bitmaps_are_one_line_errors_naming_file_line_and_element() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("t.ply"), PLY).unwrap();
    let mut corrupt_png = png([[1, 2, 3], [4, 5, 6]]);
    corrupt_png.truncate(40);
    std::fs::write(d.join("corrupt.png"), corrupt_png).unwrap();
    std::fs::write(d.join("corrupt.exr"), b"\x76\x2f\x31\x01garbage").unwrap();
    std::fs::write(d.join("t.gif"), b"GIF89a....").unwrap();
    std::fs::write(d.join("ok.png"), png([[1, 2, 3], [4, 5, 6]])).unwrap();
    let shape = |texture: &str| {
        format!(
            r#"<shape type="ply"><string name="filename" value="t.ply"/><bsdf type="diffuse"><texture name="reflectance" type="bitmap">{texture}</texture></bsdf></shape>"#
        )
    };
    let file = |f: &str| format!(r#"<string name="filename" value="{f}"/>"#);
    let bitmap = "<texture type=\"bitmap\">";
    let cases = [
        (shape(&file("missing.png")), bitmap, "missing.png: cannot open"),
        (shape(&file("corrupt.png")), bitmap, "corrupt.png: cannot decode PNG"),
        (shape(&file("corrupt.exr")), bitmap, "corrupt.exr: cannot decode OpenEXR"),
        (shape(&file("t.gif")), bitmap, "not an OpenEXR, PNG or JPEG image"),
        (shape(""), bitmap, "missing <string name=\"filename\">"),
        (
            shape(&(file("ok.png") + r#"<string name="wrap_mode" value="border"/>"#)),
            "<string name=\"wrap_mode\">",
            "wrap_mode \"border\" is not supported",
        ),
        (
            shape(&(file("ok.png") + r#"<transform name="to_uv"><scale x="2"/></transform>"#)),
            "<transform name=\"to_uv\">",
            "to_uv other than the identity",
        ),
        (
            r#"<shape type="ply"><string name="filename" value="t.ply"/><bsdf type="conductor"><texture name="specular_reflectance" type="bitmap"/></bsdf></shape>"#.to_string(),
            bitmap,
            "a texture is not supported here",
        ),
        (
            r#"<shape type="ply"><string name="filename" value="t.ply"/><bsdf type="diffuse"><texture name="reflectance" type="checkerboard"/></bsdf></shape>"#.to_string(),
            "<texture type=\"checkerboard\">",
            "texture type \"checkerboard\" is not supported",
        ),
    ];
    for (body, element, what) in &cases {
        refused(d, body, element, what);
    }
    // Mitsuba's nearest-neighbour filter is warned: bdpm samples bilinearly.
    let body = shape(&(file("ok.png") + r#"<string name="filter_type" value="nearest"/>"#));
    let loaded = load_scene(&write_scene(d, &body)).unwrap_or_else(|e| panic!("{e}"));
    let warnings = loaded.report.import_warnings.join("\n");
    assert!(
        warnings.contains("line 8: <string name=\"filter_type\">")
            && warnings.contains("bilinearly"),
        "{warnings}"
    );
    // The texels go through the memory budget: a limit below the file's bytes refuses it.
    let options = LoadOptions {
        memory_limit: Some(MemoryLimit {
            bytes: 16,
            source: "memory limit".into(),
            remedy: None,
        }),
    };
    let e = load_scene_with(&write_scene(d, &shape(&file("ok.png"))), &options)
        .expect_err("over the limit")
        .to_string();
    assert!(
        e.contains("line 8: <texture type=\"bitmap\">") && e.contains("more than the memory limit"),
        "{e}"
    );
}
