//! Mitsuba 3 XML import: files Mitsuba and its data repository wrote (tests/data/mitsuba,
//! README there), the mapping of transforms, shapes, BSDFs, lights and the camera against
//! their definitions, and one-line errors for each class of bad input.

use std::f32::consts::PI;
use std::path::{Path, PathBuf};

use bdpm_load::{LoadError, load_mitsuba_str, load_scene};
use glam::Vec3;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/mitsuba")
        .join(name)
}

/// The 1-based line of the first line of `text` that contains `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).expect(needle) + 1
}

/// A scene around `body`: a camera looking down −z from z = 5 and a point light.
fn scene(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <string name="fov_axis" value="y"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="16"/></film>
    </sensor>
    <emitter type="point"><point name="position" x="0" y="0" z="3"/><rgb name="intensity" value="1"/></emitter>
{body}
</scene>"#
    )
}

fn load(text: &str) -> Result<bdpm_load::LoadedScene, LoadError> {
    load_mitsuba_str(text, Path::new("."), Path::new("t.xml"))
}

/// The error's one line, checked to name the file, `line` and `element`.
fn refused(text: &str, line: usize, element: &str) -> String {
    let e = load(text).expect_err("refused").to_string();
    assert!(!e.contains('\n'), "{e}");
    assert!(
        e.starts_with(&format!("t.xml: line {line}: {element}")),
        "{e}"
    );
    e
}

#[test]
fn mitsubas_own_cornell_box_is_refused_at_its_area_light() {
    let path = data("cornell-box-3.9.1.xml");
    let text = std::fs::read_to_string(&path).unwrap();
    let e = load_scene(&path).expect_err("area light").to_string();
    let line = line_of(&text, "<emitter type=\"area\"");
    assert!(
        e.contains(&format!("line {line}: <emitter type=\"area\">")),
        "{e}"
    );
    assert!(e.contains("issue 46"), "{e}");
    // Without it (a point light in its place), the rest of the file maps.
    let start = text.find("<emitter type=\"area\"").unwrap();
    let end = text[start..].find("</emitter>").unwrap() + start + "</emitter>".len();
    let edited = format!("{}{}", &text[..start], &text[end..]).replace(
        "</scene>",
        r#"<emitter type="point"><point name="position" x="0" y="0.9" z="0"/><rgb name="intensity" value="1"/></emitter></scene>"#,
    );
    let loaded = load_mitsuba_str(&edited, Path::new("."), &path).unwrap_or_else(|e| panic!("{e}"));
    let count = |kind: &str| text.matches(&format!("<shape type=\"{kind}\"")).count();
    // Each rectangle is 2 triangles, each cube 12.
    assert_eq!(
        loaded.report.triangles,
        2 * count("rectangle") + 12 * count("cube")
    );
    let camera = loaded.scene.camera();
    // fov_axis "smaller" of a square film is the vertical angle as written.
    assert_eq!(camera.vfov_degrees(), 39.3077f32);
    assert_eq!((camera.width(), camera.height()), (256, 256));
}

#[test]
fn public_mitsuba_scenes_render_or_are_refused_element_by_element() {
    let refusals = [
        (
            "mitsuba-data/scenes/cbox/cbox.xml",
            "<emitter type=\"area\">",
        ),
        (
            "mitsuba-data/docs/scenes/shape_rectangle.xml",
            "<emitter type=\"envmap\">",
        ),
        (
            "mitsuba-data/docs/scenes/shape_disk.xml",
            "<emitter type=\"envmap\">",
        ),
        (
            "mitsuba-data/docs/scenes/shape_sphere_basic.xml",
            "<emitter type=\"envmap\">",
        ),
    ];
    for (name, element) in refusals {
        let e = load_scene(&data(name)).expect_err(name).to_string();
        assert!(
            !e.contains('\n') && e.contains(element) && e.contains(": line "),
            "{name}: {e}"
        );
    }
    let loaded =
        load_scene(&data("mitsuba-data/scenes/hello.xml")).unwrap_or_else(|e| panic!("{e}"));
    let lights = loaded.scene.lights();
    assert_eq!(lights.len(), 2);
    assert_eq!(lights[0].position, Vec3::new(2.0, -6.0, 4.5));
    assert!(
        (lights[0].flux - Vec3::splat(4.0 * PI * 10.0))
            .abs()
            .max_element()
            < 1e-4
    );
    // The teapot's faces, as its PLY header declares them.
    let ply = std::fs::read(data("mitsuba-data/common/meshes/teapot.ply")).unwrap();
    let header =
        String::from_utf8_lossy(&ply[..ply.windows(10).position(|w| w == b"end_header").unwrap()])
            .to_string();
    let faces: usize = header
        .lines()
        .find_map(|l| l.strip_prefix("element face "))
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    assert_eq!(loaded.report.triangles, faces);
    // No fov: Mitsuba's 50 mm focal length on the 36 × 24 mm diagonal, 1024 × 768.
    let diagonal = (36.0f64.hypot(24.0) / 100.0).atan();
    let vertical = 2.0 * (diagonal.tan() / (1.0f64 + (4.0 / 3.0f64).powi(2)).sqrt()).atan();
    assert!((f64::from(loaded.scene.camera().vfov_degrees()) - vertical.to_degrees()).abs() < 1e-4);
    assert!(
        loaded
            .report
            .warnings()
            .iter()
            .any(|w| w.contains("<integrator type=\"direct\">"))
    );
}

#[test]
fn transforms_compose_in_mitsubas_order() {
    // translate, then scale by 2 (later elements multiply from the left): (−1, −1) → (0, −2).
    let body = r#"<shape type="rectangle"><transform name="to_world"><translate x="1"/><scale value="2"/><rotate z="1" angle="90"/><matrix value="1 0 0 0  0 1 0 0  0 0 1 0.5  0 0 0 1"/></transform></shape>"#;
    let loaded = load(&scene(body)).unwrap_or_else(|e| panic!("{e}"));
    let g = loaded.scene.geometry();
    let v = g.vertices(0)[0];
    // (0, −2, 0) rotated 90° about z is (2, 0, 0), then lifted by 0.5 in z.
    assert!(
        (v - Vec3::new(2.0, 0.0, 0.5)).abs().max_element() < 1e-6,
        "{v}"
    );
    // Default parameters and the camera's lookat.
    let text = scene("<shape type=\"cube\"/>")
        .replace("value=\"32\"", "value=\"$w\"")
        .replace(
            "<scene version=\"3.0.0\">",
            "<scene version=\"3.0.0\"><default name=\"w\" value=\"48\"/>",
        );
    let loaded = load(&text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded.scene.camera().width(), 48);
    assert_eq!(loaded.scene.camera().forward(), Vec3::new(0.0, 0.0, -1.0));
    assert_eq!(loaded.report.triangles, 12);
}

#[test]
fn builtin_shapes_have_their_defined_areas() {
    let area = |body: &str| {
        load(&scene(body))
            .unwrap_or_else(|e| panic!("{e}"))
            .scene
            .geometry()
            .total_area()
    };
    assert!((area("<shape type=\"rectangle\"/>") - 4.0).abs() < 1e-6);
    assert!((area("<shape type=\"cube\"/>") - 24.0).abs() < 1e-5);
    // A 256-gon inscribed in the unit circle: π · sin(2π/256)/(2π/256).
    let t = std::f64::consts::TAU / 256.0;
    assert!((area("<shape type=\"disk\"/>") - std::f64::consts::PI * t.sin() / t).abs() < 1e-5);
    let sphere = load(&scene(
        "<shape type=\"sphere\"><float name=\"radius\" value=\"0.5\"/></shape>",
    ))
    .unwrap();
    assert_eq!(sphere.report.triangles, 5120);
    assert!(
        (sphere.scene.geometry().total_area() - std::f64::consts::PI).abs()
            < 0.01 * std::f64::consts::PI
    );
}

#[test]
fn bsdfs_map_to_bdpms_materials() {
    let body = r#"
    <bsdf type="dielectric" id="glass"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.25"/></bsdf>
    <bsdf type="twosided" id="blend"><bsdf type="blendbsdf"><float name="weight" value="0.25"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.4"/></bsdf>
        <bsdf type="roughconductor"><float name="alpha" value="0.1"/><string name="material" value="none"/><rgb name="specular_reflectance" value="0.8"/></bsdf></bsdf></bsdf>
    <bsdf type="conductor" id="gold"><string name="material" value="Au"/></bsdf>
    <shape type="rectangle"><ref id="glass"/></shape>
    <shape type="cube"><ref id="blend"/></shape>
    <shape type="disk"><ref id="gold"/></shape>"#;
    let loaded = load(&scene(body)).unwrap_or_else(|e| panic!("{e}"));
    let m = loaded.scene.materials();
    match &m[0].delta {
        Some(bdpm_bdf::Material::Dielectric(d)) => assert_eq!(d.eta(), 1.2f32),
        other => panic!("{other:?}"),
    }
    let bdf = &m[1].bdf;
    assert!((bdf.kd() - Vec3::splat(0.3)).abs().max_element() < 1e-7);
    assert!((bdf.gr() - Vec3::splat(0.2)).abs().max_element() < 1e-7);
    assert!((bdf.delta().unwrap() - 0.1 * std::f32::consts::SQRT_2).abs() < 1e-7);
    assert!(matches!(m[2].delta, Some(bdpm_bdf::Material::Mirror(_))));
    let warnings = loaded.report.warnings().join("\n");
    assert!(
        warnings.contains("material \"Au\"") && warnings.contains("Gaussian lobe"),
        "{warnings}"
    );
}

#[test]
fn bad_input_is_a_one_line_error_naming_file_line_and_element() {
    // Malformed XML: the parser's position.
    let e = load("<scene version=\"3.0.0\">\n<shape type=\"cube\">\n</scene>")
        .expect_err("malformed")
        .to_string();
    assert!(
        e.starts_with("t.xml: line 3") && e.contains("malformed XML"),
        "{e}"
    );
    let body_line = 9; // scene() puts the body on its 9th line
    let cases = [
        (
            r#"<shape type="ply"><string name="filename" value="missing.ply"/></shape>"#,
            "<shape type=\"ply\">",
            "missing.ply",
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><translate x="NaN"/></transform></shape>"#,
            "<translate>",
            "not finite",
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><rotate y="1" angle="inf"/></transform></shape>"#,
            "<rotate>",
            "not finite",
        ),
        (
            r#"<shape type="cube"><transform name="to_world"><scale value="0"/></transform></shape>"#,
            "<shape type=\"cube\">",
            "zero area",
        ),
        (
            r#"<shape type="cube"><bsdf type="thindielectric"/></shape>"#,
            "<bsdf type=\"thindielectric\">",
            "not supported",
        ),
        (
            r#"<emitter type="spot"/>"#,
            "<emitter type=\"spot\">",
            "point lights only",
        ),
        (
            r#"<shape type="cylinder"/>"#,
            "<shape type=\"cylinder\">",
            "not supported",
        ),
        (
            r#"<shape type="cube"><bsdf type="diffuse"><rgb name="reflectance" value="$albedo"/></bsdf></shape>"#,
            "<rgb name=\"reflectance\">",
            "$albedo",
        ),
        (
            r#"<shape type="cube"><ref id="nowhere"/></shape>"#,
            "<ref id=\"nowhere\">",
            "no <bsdf id=\"nowhere\">",
        ),
        (
            r#"<shape type="cube"><bsdf type="diffuse"><rgb name="reflectance" value="1.5"/></bsdf></shape>"#,
            "<bsdf type=\"diffuse\">",
            "outside [0, 1]",
        ),
        (
            r#"<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"#,
            "<emitter type=\"area\">",
            "issue 46",
        ),
        (
            r#"<medium type="homogeneous"/>"#,
            "<medium type=\"homogeneous\">",
            "not supported",
        ),
    ];
    for (body, element, what) in cases {
        let e = refused(&scene(body), body_line, element);
        assert!(e.contains(what), "{body}: {e}");
    }
    let e = load("<scene version=\"0.6.0\"/>")
        .expect_err("version")
        .to_string();
    assert!(
        e.contains("line 1: <scene>") && e.contains("2.x.x or 3.x.x"),
        "{e}"
    );
}
