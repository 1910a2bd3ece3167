//! `bdpm export --to mitsuba` as a user runs it: the set of files it writes (and no temporary
//! file left), the resolution override, the lobe's warning, and one-line errors for a format
//! it does not write and an output that is not a directory. The export's contents are tested
//! in crates/export/tests/export.rs.
use crate::{bdpm, scene};
use std::path::Path;
use std::process::{Command, Output};

fn run(cmd: &mut Command) -> (Output, String, String) {
    let out = cmd.output().expect("run bdpm");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    (out, stdout, stderr)
}

/// Files under `dir`, relative, sorted; hidden ones (temporaries) included.
fn files(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            let sub = path.file_name().unwrap().to_string_lossy().into_owned();
            out.extend(files(&path).into_iter().map(|f| format!("{sub}/{f}")));
        } else {
            out.push(path.file_name().unwrap().to_string_lossy().into_owned());
        }
    }
    out.sort();
    out
}

#[test]
fn export_writes_the_set_at_the_resolution_asked() {
    let dir = crate::temp_dir("export");
    let out = dir.path().join("glossy");
    let (status, stdout, stderr) = run(bdpm()
        .arg("export")
        .arg(scene("preprint/cornell-glossy.toml"))
        .args(["--to", "mitsuba", "--resolution", "32x24", "-o"])
        .arg(&out));
    assert!(status.status.success(), "{stderr}");
    assert!(
        stdout.contains("scene.xml") && stdout.contains("3 shapes"),
        "{stdout}"
    );
    // The two lobe materials are stand-ins: one warning line each.
    assert_eq!(stderr.matches("warning: material").count(), 2, "{stderr}");
    assert_eq!(
        files(&out),
        [
            "export.json",
            "meshes/mat0-glossy.ply",
            "meshes/mat1-left_wall.ply",
            "meshes/mat2-matte.ply",
            "scene.xml"
        ]
    );
    let xml = std::fs::read_to_string(out.join("scene.xml")).unwrap();
    assert!(
        xml.contains(r#"<integer name="width" value="32"/>"#),
        "{xml}"
    );
    assert!(
        xml.contains(r#"<integer name="height" value="24"/>"#),
        "{xml}"
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("export.json")).unwrap()).unwrap();
    assert_eq!(report["warnings"].as_array().unwrap().len(), 2);
    assert_eq!(report["resolution"], serde_json::json!([32, 24]));
}

#[test]
fn unknown_formats_and_file_outputs_are_one_line_errors() {
    let dir = crate::temp_dir("export-errors");
    let (status, _, stderr) = run(bdpm()
        .arg("export")
        .arg(scene("cornell-lambert.toml"))
        .args(["--to", "pbrt", "-o"])
        .arg(dir.path().join("x")));
    assert_eq!(status.status.code(), Some(1));
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("pbrt") && stderr.contains("mitsuba"),
        "{stderr}"
    );
    let file = dir.path().join("a-file");
    std::fs::write(&file, b"x").unwrap();
    let (status, _, stderr) = run(bdpm()
        .arg("export")
        .arg(scene("cornell-lambert.toml"))
        .args(["--to", "mitsuba", "-o"])
        .arg(&file));
    assert_eq!(status.status.code(), Some(1));
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains(&file.display().to_string()) && stderr.contains("not a directory"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read(&file).unwrap(),
        b"x",
        "the file is left alone"
    );
}
