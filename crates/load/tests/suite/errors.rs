//! Bad input is rejected with a one-line message naming the file and the field.

use std::path::Path;

use bdpm_load::load_scene_str;

const GOOD: &str = r#"
[render]
resolution = [32, 32]
passes = 1

[camera]
position = [0.0, 0.0, -3.0]
look_at = [0.0, 0.0, 0.0]
vfov = 40.0

[[light]]
position = [0.0, 0.5, 0.0]
flux = 1.0

[material.red]
kd = [0.6, 0.1, 0.1]

[[shape]]
type = "box"
min = [-1.0, -1.0, -1.0]
max = [1.0, 1.0, 1.0]
facing = "inside"
material = "red"
"#;

/// Loads `text` as `scenes/bad.toml` and returns the error message, which must be one line
/// naming that file.
fn error_of(text: &str) -> String {
    match load_scene_str(text, Path::new("scenes"), Path::new("scenes/bad.toml")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("scenes/bad.toml: "), "{msg}");
            assert!(!msg.contains('\n'), "{msg}");
            msg
        }
    }
}

fn with(from: &str, to: &str) -> String {
    assert!(GOOD.contains(from), "{from}");
    GOOD.replacen(from, to, 1)
}

#[test]
fn the_base_scene_loads() {
    let s = load_scene_str(GOOD, Path::new("scenes"), Path::new("scenes/bad.toml")).expect("valid");
    assert_eq!(s.report.triangles, 12);
    assert_eq!(s.settings.passes, 1);
    assert_eq!(
        s.settings.photons,
        bdpm_settings::RenderSettings::default().photons
    );
}

#[test]
fn missing_vfov() {
    let msg = error_of(&with("vfov = 40.0\n", ""));
    assert!(msg.contains("camera.vfov: missing"), "{msg}");
}

#[test]
fn missing_camera() {
    let text = GOOD.replace(
        "[camera]\nposition = [0.0, 0.0, -3.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40.0\n",
        "",
    );
    let msg = error_of(&text);
    assert!(msg.contains(": camera: missing [camera]"), "{msg}");
}

#[test]
fn negative_albedo() {
    let msg = error_of(&with("kd = [0.6, 0.1, 0.1]", "kd = [0.6, -0.1, 0.1]"));
    assert!(
        msg.contains("material.red.kd: green channel -0.1 is outside [0, 1]"),
        "{msg}"
    );
}

#[test]
fn albedo_above_one() {
    let msg = error_of(&with("kd = [0.6, 0.1, 0.1]", "kd = 1.2"));
    assert!(
        msg.ends_with("material.red.kd: 1.2 is outside [0, 1]"),
        "{msg}"
    );
}

#[test]
fn kd_plus_gr_above_one() {
    let msg = error_of(&with(
        "kd = [0.6, 0.1, 0.1]",
        "kd = [0.6, 0.1, 0.1]\ngr = 0.5\ndelta = 3",
    ));
    assert!(msg.contains("material.red: kd + gr"), "{msg}");
    assert!(msg.contains("exceeds 1"), "{msg}");
}

#[test]
fn lobe_without_width() {
    let msg = error_of(&with("kd = [0.6, 0.1, 0.1]", "kd = 0.2\ngr = 0.5"));
    assert!(msg.contains("material.red.delta: missing"), "{msg}");
}

#[test]
fn lobe_width_out_of_range() {
    let msg = error_of(&with(
        "kd = [0.6, 0.1, 0.1]",
        "kd = 0.2\ngr = 0.5\ndelta = 0.01",
    ));
    assert!(
        msg.contains("material.red.delta: 0.01 is outside [0.05, 90]"),
        "{msg}"
    );
}

#[test]
fn unknown_key_is_a_typo() {
    let msg = error_of(&with("passes = 1", "pases = 1"));
    assert!(
        msg.contains("line 4, column 1: unknown field `pases`, expected one of"),
        "{msg}"
    );
}

#[test]
fn unknown_key_in_a_shape() {
    let msg = error_of(&with(
        "facing = \"inside\"",
        "facing = \"inside\"\nradius = 2.0",
    ));
    assert!(msg.contains("unknown field `radius`"), "{msg}");
    assert!(msg.contains("line "), "{msg}");
}

#[test]
fn unknown_shape_type() {
    let msg = error_of(&with("type = \"box\"", "type = \"cube\""));
    assert!(msg.contains("unknown variant `cube`"), "{msg}");
}

#[test]
fn unknown_mode() {
    let msg = error_of(&with("passes = 1", "passes = 1\nmode = \"fast\""));
    assert!(
        msg.contains("render.mode: unknown mode 'fast'; expected one of path, "),
        "{msg}"
    );
}

#[test]
fn unknown_material_reference() {
    let msg = error_of(&with("material = \"red\"", "material = \"blue\""));
    assert!(
        msg.contains("shape[0].material: unknown material 'blue' (defined: red)"),
        "{msg}"
    );
}

#[test]
fn nan_position() {
    let msg = error_of(&with(
        "position = [0.0, 0.5, 0.0]",
        "position = [0.0, nan, 0.0]",
    ));
    assert!(
        msg.contains("light[0].position: [0, NaN, 0] is not finite"),
        "{msg}"
    );
}

#[test]
fn infinite_box_corner() {
    let msg = error_of(&with("max = [1.0, 1.0, 1.0]", "max = [1.0, inf, 1.0]"));
    assert!(msg.contains("shape[0].max: "), "{msg}");
    assert!(msg.contains("not finite"), "{msg}");
}

#[test]
fn infinite_camera_position() {
    let msg = error_of(&with(
        "position = [0.0, 0.0, -3.0]",
        "position = [0.0, 0.0, -inf]",
    ));
    assert!(msg.contains("camera.position: "), "{msg}");
}

#[test]
fn resolution_zero() {
    let msg = error_of(&with("resolution = [32, 32]", "resolution = [32, 0]"));
    assert!(
        msg.contains("render.resolution[1]: 0 is outside [1, 16384]"),
        "{msg}"
    );
}

#[test]
fn zero_passes_photons_spp() {
    for (key, field) in [
        ("passes = 0", "render.passes"),
        ("photons = 0", "render.photons"),
        ("spp = 0", "render.spp"),
    ] {
        let msg = error_of(&with(
            "passes = 1",
            &format!("passes = 1\n{key}").replace("passes = 1\npasses = 0", "passes = 0"),
        ));
        assert!(
            msg.contains(&format!("{field}: 0 is outside [1, ")),
            "{msg}"
        );
    }
}

#[test]
fn negative_or_nan_radius() {
    for v in ["-0.1", "0.0", "nan", "inf"] {
        let msg = error_of(&with("passes = 1", &format!("passes = 1\nradius = {v}")));
        assert!(msg.contains("render.radius: "), "{msg}");
    }
}

#[test]
fn vfov_out_of_range() {
    for v in ["0.0", "179.0", "-5", "nan"] {
        let msg = error_of(&with("vfov = 40.0", &format!("vfov = {v}")));
        assert!(msg.contains("camera.vfov: "), "{msg}");
    }
}

#[test]
fn negative_flux() {
    let msg = error_of(&with("flux = 1.0", "flux = [1.0, -1.0, 1.0]"));
    assert!(
        msg.contains("light[0].flux: green channel -1 must be >= 0"),
        "{msg}"
    );
}

#[test]
fn far_away_vertex() {
    let msg = error_of(&with("max = [1.0, 1.0, 1.0]", "max = [1.0, 1e30, 1.0]"));
    assert!(msg.contains("shape[0]: vertex "), "{msg}");
    assert!(msg.contains("is beyond"), "{msg}");
}

#[test]
fn no_light() {
    let msg = error_of(&with(
        "[[light]]\nposition = [0.0, 0.5, 0.0]\nflux = 1.0\n",
        "",
    ));
    assert!(msg.contains(": light: the scene has no light"), "{msg}");
}

#[test]
fn sphere_radius_and_subdivisions() {
    let sphere = "type = \"sphere\"\nradius = R\nsubdivisions = S\nmaterial = \"red\"\n[[shape]]\ntype = \"box\"";
    let msg = error_of(&with(
        "type = \"box\"",
        &sphere.replace('R', "-1.0").replace('S', "4"),
    ));
    assert!(
        msg.contains("shape[0].radius: -1 must be a finite number > 0"),
        "{msg}"
    );
    let msg = error_of(&with(
        "type = \"box\"",
        &sphere.replace('R', "1.0").replace('S', "100000"),
    ));
    assert!(
        msg.contains("shape[0].subdivisions: 100000 is outside [1, 256]"),
        "{msg}"
    );
}

#[test]
fn quad_with_three_vertices() {
    let quad = "type = \"quad\"\nmaterial = \"red\"\nvertices = [[0,0,0],[1,0,0],[1,1,0]]\n[[shape]]\ntype = \"box\"";
    let msg = error_of(&with("type = \"box\"", quad));
    assert!(
        msg.contains("shape[0].vertices: 3 points given; a quad has 4"),
        "{msg}"
    );
}

#[test]
fn quad_with_nan_vertex() {
    let quad = "type = \"quad\"\nmaterial = \"red\"\nvertices = [[0,0,0],[1,0,0],[1,nan,0],[0,1,0]]\n[[shape]]\ntype = \"box\"";
    let msg = error_of(&with("type = \"box\"", quad));
    assert!(msg.contains("shape[0].vertices[2]: "), "{msg}");
}

#[test]
fn wrong_type_gives_line_and_column() {
    let msg = error_of(&with("passes = 1", "passes = \"many\""));
    assert!(msg.contains("line 4, column 10: "), "{msg}");
}

#[test]
fn garbage_never_panics() {
    // Every prefix of a valid file, and a few byte flips, give Ok or an error, never a panic.
    for end in (0..GOOD.len()).filter(|&i| GOOD.is_char_boundary(i)) {
        let _ = load_scene_str(&GOOD[..end], Path::new("."), Path::new("x.toml"));
    }
    let bytes = GOOD.as_bytes();
    for i in 0..bytes.len() {
        for b in [b'0', b'-', b'[', b'"', b'e', b'\n'] {
            let mut v = bytes.to_vec();
            v[i] = b;
            if let Ok(text) = String::from_utf8(v) {
                let _ = load_scene_str(&text, Path::new("."), Path::new("x.toml"));
            }
        }
    }
}

// ---- Issue 15: validation in the precision the renderer uses; nothing dropped in silence.

#[test]
fn extra_values_in_fixed_size_arrays_are_refused() {
    let m = error_of(&with("resolution = [32, 32]", "resolution = [32, 32, 3]"));
    assert!(
        m.contains("render.resolution") && m.contains("3 values"),
        "{m}"
    );
    let m = error_of(&with(
        "position = [0.0, 0.5, 0.0]",
        "position = [0.0, 0.5, 0.0, 7.0]",
    ));
    assert!(
        m.contains("exactly 3 numbers") && m.contains("invalid length 4"),
        "{m}"
    );
    let m = error_of(&with("kd = [0.6, 0.1, 0.1]", "kd = [0.6, 0.1, 0.1, 0.1]"));
    assert!(m.contains("invalid length 4"), "{m}");
}

#[test]
fn numbers_are_reported_as_written_not_after_f32_rounding() {
    let m = error_of(&with(
        "position = [0.0, 0.5, 0.0]",
        "position = [1e300, 0.5, 0.0]",
    ));
    assert!(
        m.contains("light[0].position") && m.contains("1e300"),
        "{m}"
    );
    assert!(!m.contains("inf"), "{m}");
    let m = error_of(&with("vfov = 40.0", "vfov = 1e300"));
    assert!(m.contains("camera.vfov: 1e300 is outside"), "{m}");
    let m = error_of(&with("passes = 1", "passes = 1\nradius = 1e300"));
    assert!(m.contains("render.radius: 1e300"), "{m}");
}

#[test]
fn subnormal_and_unusably_small_radii_are_refused() {
    // Subnormal in f32: 1/(2r) is infinite, which crashed the photon grid.
    let m = error_of(&with("passes = 1", "passes = 1\nradius = 1e-39"));
    assert!(
        m.contains("render.radius: 1e-39") && m.contains("normal"),
        "{m}"
    );
    // Normal in f32, but r² underflows and 1/(πr²) is infinite.
    let m = error_of(&with("passes = 1", "passes = 1\nradius = 1e-30"));
    assert!(
        m.contains("render.radius") && m.contains("smallest usable"),
        "{m}"
    );
    // The smallest accepted radius loads.
    let ok = with("passes = 1", "passes = 1\nradius = 1e-18");
    assert!(load_scene_str(&ok, Path::new("scenes"), Path::new("scenes/bad.toml")).is_ok());
}

#[test]
fn a_duplicate_key_is_named() {
    let m = error_of(&with("passes = 1", "passes = 1\npasses = 2"));
    assert!(m.contains("duplicate key `passes`"), "{m}");
}

#[test]
fn direct_boost_is_between_one_and_64() {
    for bad in ["0", "65"] {
        let m = error_of(&with(
            "passes = 1",
            &format!("passes = 1\ndirect_boost = {bad}"),
        ));
        assert!(m.contains("render.direct_boost"), "{bad}: {m}");
    }
    for good in ["1", "64"] {
        let text = with("passes = 1", &format!("passes = 1\ndirect_boost = {good}"));
        let loaded = load_scene_str(&text, Path::new("scenes"), Path::new("scenes/bad.toml"));
        let boost = loaded.map(|l| l.settings.direct_boost);
        assert_eq!(boost.ok(), good.parse().ok(), "{good}");
    }
}

#[test]
fn pixel_table_rays_are_capped() {
    let m = error_of(&with(
        "passes = 1",
        "passes = 1\npixel_table_rays = 4000000000",
    ));
    assert!(
        m.contains("render.pixel_table_rays") && m.contains("16384"),
        "{m}"
    );
}

#[test]
fn the_report_says_whether_the_radius_was_given() {
    let load = |t: &str| load_scene_str(t, Path::new("scenes"), Path::new("scenes/x.toml"));
    assert!(!load(GOOD).expect("valid").report.radius_given);
    let given = with("passes = 1", "passes = 1\nradius = 0.01");
    assert!(load(&given).expect("valid").report.radius_given);
}

#[test]
fn radius_in_pixels_loads_and_bad_text_is_named() {
    let ok = with("passes = 1", "passes = 1\nradius = \"1.5px\"");
    let loaded = load_scene_str(&ok, Path::new("scenes"), Path::new("scenes/bad.toml")).unwrap();
    assert_eq!(loaded.settings.radius, None);
    assert_eq!(loaded.settings.radius_px, Some(1.5));
    assert!(loaded.report.radius_given);
    let metres = with("passes = 1", "passes = 1\nradius = \"0.02m\"");
    let loaded =
        load_scene_str(&metres, Path::new("scenes"), Path::new("scenes/bad.toml")).unwrap();
    assert_eq!(
        (loaded.settings.radius, loaded.settings.radius_px),
        (Some(0.02), None)
    );
    for (v, why) in [
        ("\"1.5 pixels\"", "not a radius"),
        ("\"-2px\"", "positive"),
        ("\"2000px\"", "pixel footprints in (0, 1000]"),
    ] {
        let m = error_of(&with("passes = 1", &format!("passes = 1\nradius = {v}")));
        assert!(m.contains("render.radius: ") && m.contains(why), "{v}: {m}");
    }
}

#[test]
fn mirror_and_dielectric_materials_load_as_delta_materials() {
    for (text, delta) in [
        ("type = \"mirror\"", true),
        ("type = \"mirror\"\nreflectance = 0.9", true),
        (
            "type = \"mirror\"\neta = [0.2, 0.4, 1.4]\nk = [4.0, 2.4, 1.6]",
            true,
        ),
        ("type = \"dielectric\"\nior = 1.5", true),
        (
            "type = \"dielectric\"\nior = 1.33\ntransmit_tint = [0.9, 1.0, 0.9]",
            true,
        ),
        ("type = \"smooth\"\nkd = 0.3", false),
    ] {
        let s = load_scene_str(
            &with("kd = [0.6, 0.1, 0.1]", text),
            Path::new("scenes"),
            Path::new("scenes/bad.toml"),
        )
        .unwrap_or_else(|e| panic!("{text}: {e}"));
        assert_eq!(s.scene.is_delta(0), delta, "{text}");
        assert_eq!(s.scene.has_delta(), delta, "{text}");
    }
}

#[test]
fn material_types_refuse_what_they_do_not_read() {
    let cases = [
        (
            "type = \"metal\"",
            "material.red.type: \"metal\" is not a material type (one of: smooth, mirror, dielectric)",
        ),
        (
            "type = \"mirror\"\nkd = 0.5",
            "material.red.kd: a mirror material has no key kd (its keys: reflectance, eta, k)",
        ),
        ("type = \"dielectric\"", "material.red.ior: missing"),
        (
            "type = \"dielectric\"\nior = 0.0",
            "material.red.ior: 0 is outside [0.01",
        ),
        (
            "type = \"mirror\"\neta = 1.5",
            "material.red.k: missing (a conductor's index needs both eta and k",
        ),
        (
            "type = \"mirror\"\nreflectance = 1.5",
            "material.red.reflectance",
        ),
        (
            "kd = 0.5\nior = 1.5",
            "material.red.ior: a smooth material has no key ior",
        ),
    ];
    for (text, expected) in cases {
        let msg = error_of(&with("kd = [0.6, 0.1, 0.1]", text));
        assert!(msg.contains(expected), "{text}: {msg}");
    }
}

#[test]
fn emission_is_read_and_checked() {
    // The light replaced by an emitting box: the scene loads without any [[light]].
    let lit = GOOD
        .replacen("[[light]]\nposition = [0.0, 0.5, 0.0]\nflux = 1.0\n", "", 1)
        .replacen(
            "kd = [0.6, 0.1, 0.1]",
            "kd = [0.6, 0.1, 0.1]\nemission = [1.0, 2.0, 3.0]\ntwo_sided_emission = true",
            1,
        );
    let s = load_scene_str(&lit, Path::new("scenes"), Path::new("scenes/bad.toml")).expect("valid");
    assert!(s.scene.lights().is_empty());
    assert_eq!(s.scene.emitters().len(), 12);
    let m = &s.scene.materials()[0];
    assert_eq!(m.emission, glam::Vec3::new(1.0, 2.0, 3.0));
    assert!(m.two_sided_emission);
    let msg = error_of(&with(
        "kd = [0.6, 0.1, 0.1]",
        "kd = 0.5\nemission = [1.0, -1.0, 0.0]",
    ));
    assert!(
        msg.contains("material.red.emission") && msg.contains("green"),
        "{msg}"
    );
    let msg = error_of(&with(
        "kd = [0.6, 0.1, 0.1]",
        "kd = 0.5\ntwo_sided_emission = 1",
    ));
    // serde's own message: the line and column of the key, and the type expected.
    assert!(
        msg.contains("line 17") && msg.contains("expected a boolean"),
        "{msg}"
    );
    // No light and no emission: the message says both ways to light the scene.
    let dark = GOOD.replacen("[[light]]\nposition = [0.0, 0.5, 0.0]\nflux = 1.0\n", "", 1);
    let msg = error_of(&dark);
    assert!(msg.contains("emission"), "{msg}");
}
