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
fn mitsubas_own_cornell_box_loads_with_its_area_light() {
    let path = data("cornell-box-3.9.1.xml");
    let text = std::fs::read_to_string(&path).unwrap();
    let loaded = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
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
    // The light: the rectangle scaled by (0.23, 0.19) and turned to face down, emitting the
    // file's radiance from its front side, with the white BSDF it refers to.
    let scene = &loaded.scene;
    assert!(scene.lights().is_empty());
    let g = scene.geometry();
    let emitting: Vec<u32> = (0..g.triangle_count() as u32)
        .filter(|&t| scene.materials()[g.material(t) as usize].emits())
        .collect();
    assert_eq!(emitting.len(), 2);
    let area: f64 = emitting.iter().map(|&t| f64::from(g.area(t))).sum();
    assert!(
        (area - 4.0 * 0.23 * 0.19).abs() < 1e-6,
        "light area {area} m²"
    );
    for &t in &emitting {
        let [a, b, c] = g.vertices(t);
        let n = (b - a).cross(c - a).normalize();
        assert!((n - Vec3::NEG_Y).length() < 1e-6, "front side {n}");
        let m = &scene.materials()[g.material(t) as usize];
        assert_eq!(m.emission, Vec3::new(18.387, 13.9873, 6.75357));
        assert!(!m.two_sided_emission);
        assert_eq!(m.bdf.kd(), Vec3::new(0.885809, 0.698859, 0.666422));
    }
}

#[test]
fn area_emitters_make_their_shapes_material_emit_from_the_front() {
    let body = r#"
    <bsdf type="twosided" id="grey"><bsdf type="diffuse"><rgb name="reflectance" value="0.25"/></bsdf></bsdf>
    <shape type="rectangle"><ref id="grey"/><emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter></shape>
    <shape type="rectangle"><ref id="grey"/><emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter>
        <transform name="to_world"><translate z="-1"/></transform></shape>
    <shape type="disk"><emitter type="area"><spectrum name="radiance" value="4"/></emitter>
        <boolean name="flip_normals" value="true"/><transform name="to_world"><translate z="-2"/></transform></shape>
    <shape type="cube"><ref id="grey"/><transform name="to_world"><translate z="-5"/></transform></shape>"#;
    let loaded = load(&scene(body)).unwrap_or_else(|e| panic!("{e}"));
    let scene = &loaded.scene;
    let g = scene.geometry();
    let m = scene.materials();
    let material_of = |t: u32| &m[g.material(t) as usize];
    // The two rectangles share one emitting copy of "grey", the cube keeps "grey" itself:
    // a twosided BSDF does not make Mitsuba's area emitter two-sided.
    assert_eq!(g.material(0), g.material(2));
    let r0 = material_of(0);
    assert_eq!(r0.emission, Vec3::new(1.0, 2.0, 3.0));
    assert!(!r0.two_sided_emission);
    assert_eq!(r0.bdf.kd(), Vec3::splat(0.25));
    let cube = material_of(g.triangle_count() as u32 - 1);
    assert!(!cube.emits() && cube.bdf.kd() == Vec3::splat(0.25));
    // The disk has no BSDF: Mitsuba's default diffuse 0.5, emitting 4 from its flipped front.
    let disk = material_of(4);
    assert_eq!(disk.emission, Vec3::splat(4.0));
    assert_eq!(disk.bdf.kd(), Vec3::splat(0.5));
    let [a, b, c] = g.vertices(4);
    assert!(
        (b - a).cross(c - a).z < 0.0,
        "flip_normals turns the front to −z"
    );
    // Two rectangles (4 m² each) at Le = (1, 2, 3), a disk of area ≈ π at Le = 4, and the
    // point light of scene(): the flux the light distribution sees is π·Le·A per emitter.
    let t = std::f64::consts::TAU / 256.0;
    let disk_area = std::f64::consts::PI * t.sin() / t;
    let expected = (glam::DVec3::new(1.0, 2.0, 3.0) * 8.0 + glam::DVec3::splat(4.0 * disk_area))
        * std::f64::consts::PI
        + glam::DVec3::splat(4.0 * std::f64::consts::PI);
    let flux = scene.total_flux().as_dvec3();
    assert!(
        ((flux - expected) / expected).abs().max_element() < 1e-5,
        "{flux} vs {expected}"
    );
}

#[test]
fn public_mitsuba_scenes_render_or_are_refused_element_by_element() {
    let refusals = [
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
    // The Cornell box of Mitsuba's data repository: OBJ meshes, spectral reflectances (taken
    // as rgb with a warning each) and an area light on the luminaire.
    let cbox =
        load_scene(&data("mitsuba-data/scenes/cbox/cbox.xml")).unwrap_or_else(|e| panic!("{e}"));
    let g = cbox.scene.geometry();
    let lit: Vec<u32> = (0..g.triangle_count() as u32)
        .filter(|&t| cbox.scene.materials()[g.material(t) as usize].emits())
        .collect();
    assert!(!lit.is_empty());
    for t in lit {
        let [a, b, c] = g.vertices(t);
        assert!(
            (b - a).cross(c - a).y < 0.0,
            "the luminaire emits downwards"
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
            r#"<shape type="rectangle"><emitter type="area"><texture name="radiance" type="bitmap"/></emitter></shape>"#,
            "<texture type=\"bitmap\">",
            "missing <string name=\"filename\">",
        ),
        (
            r#"<shape type="rectangle"><emitter type="area"><spectrum name="radiance" filename="d65.spd"/></emitter></shape>"#,
            "<spectrum name=\"radiance\">",
            "spectra from files",
        ),
        (
            r#"<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1, -1, 1"/></emitter></shape>"#,
            "<emitter type=\"area\">",
            "negative",
        ),
        (
            r#"<emitter type="area"><rgb name="radiance" value="1"/></emitter>"#,
            "<emitter type=\"area\">",
            "nested in the <shape>",
        ),
        (
            r#"<shape type="shapegroup" id="g"><shape type="cube"><emitter type="area"/></shape></shape>"#,
            "<emitter type=\"area\">",
            "in a shapegroup",
        ),
        (
            r#"<shape type="instance"><emitter type="area"/></shape>"#,
            "<emitter type=\"area\">",
            "instances cannot replicate emitters",
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
