//! Round four (issue 43): a light within a surface's ray offset is named, with its distance,
//! in a `warning:` line on stdout and in the run report; a light 1 mm away is not.
use std::process::Command;

/// A closed 1 m room of quads (a box facing inside) lit by a light at height `y`.
fn room(y: &str) -> String {
    format!(
        r#"[render]
resolution = [8, 8]
passes = 1
spp = 1
photons = 1000

[camera]
position = [0.5, 0.5, 0.05]
look_at = [0.5, 0.5, 1.0]
vfov = 70

[[light]]
position = [0.5, 0.6, 0.5]
flux = [1.0, 1.0, 1.0]

[[light]]
position = [0.5, {y}, 0.5]
flux = [1.0, 1.0, 1.0]

[material.walls]
kd = 0.5

[[shape]]
type = "box"
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
facing = "inside"
material = "walls"
"#
    )
}

#[test]
fn a_light_within_a_surfaces_ray_offset_is_named_in_a_warning() {
    let dir = super::temp_dir("round4-light");
    // The second light 1 µm above the ceiling (its offset is 2⁻¹⁷ m ≈ 7.6 µm), then 1 mm.
    for (y, warned) in [("1.000001", true), ("1.001", false)] {
        let scene = dir.path().join(format!("room-{y}.toml"));
        std::fs::write(&scene, room(y)).expect("write scene");
        let out = Command::new(env!("CARGO_BIN_EXE_bdpm"))
            .arg("render")
            .arg(&scene)
            .args(["--quiet", "-o"])
            .arg(dir.path().join(format!("room-{y}.exr")))
            .output()
            .expect("run bdpm");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{stdout}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let line = stdout
            .lines()
            .find(|l| l.starts_with("warning: light["))
            .map(str::to_owned);
        assert_eq!(line.is_some(), warned, "y = {y}: {stdout}");
        let report: serde_json::Value = serde_json::from_slice(
            &std::fs::read(dir.path().join(format!("room-{y}.json"))).expect("report"),
        )
        .expect("JSON");
        let in_report = report["warnings"]
            .as_array()
            .expect("warnings")
            .iter()
            .filter_map(|w| w.as_str())
            .find(|w| w.starts_with("light["))
            .map(str::to_owned);
        assert_eq!(in_report.is_some(), warned, "y = {y}: {report}");
        if let (Some(line), Some(w)) = (line, in_report) {
            // The second light, its position, and its distance (1 µm less f32 rounding: the
            // light's y is 1.00000095).
            assert!(
                line.starts_with("warning: light[1] at (0.5, 1.000001, 0.5) m is 9.54e-7 m"),
                "{line}"
            );
            assert!(line.contains("7.63e-6 m"), "{line}");
            assert_eq!(line.trim_start_matches("warning: "), w);
        }
    }
}
