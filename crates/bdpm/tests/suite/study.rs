//! End-to-end test of `bdpm study`: a tiny sphere-furnace study writes its CSV, plots and
//! table, and gives the same errors when run again (only the times may differ).
use std::path::{Path, PathBuf};
use std::process::Command;

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/sphere-furnace.toml")
}

/// Runs the study in `cwd` writing into `cwd/<out>`, where the reference is cached.
fn study(cwd: &Path, out: &str) -> String {
    let output = Command::new(env!("CARGO_BIN_EXE_bdpm"))
        .current_dir(cwd)
        .arg("study")
        .arg(scene())
        .args([
            "--modes",
            "bdd0,optimal",
            "--passes",
            "4",
            "--resolution",
            "8x8",
        ])
        .args([
            "--photons",
            "2000",
            "--spp",
            "2",
            "--threads",
            "2",
            "--quiet",
        ])
        .args(["-o", out])
        .output()
        .expect("run bdpm");
    assert!(
        output.status.success(),
        "bdpm study failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    std::fs::read_to_string(cwd.join(out).join("study.csv")).expect("study.csv")
}

/// The CSV without its time columns (wall_time_s, cpu_time_s).
fn without_times(csv: &str) -> Vec<String> {
    csv.lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            [0, 1, 3, 4, 5, 7, 8].map(|i| f[i]).join(",")
        })
        .collect()
}

#[test]
fn study_writes_csv_plots_and_table_deterministically() {
    let tmp = crate::temp_dir("study");
    let dir = tmp.path();
    let csv = study(dir, "a");
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].starts_with("mode,pass,wall_time_s,rmse,rel_rmse,mean_sqrt_v,cpu_time_s"));
    assert_eq!(lines.len(), 1 + 2 * 4, "{csv}");
    for line in &lines[1..] {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 9, "{line}");
        assert!(f[0] == "bdd0" || f[0] == "optimal", "{line}");
        for v in &f[2..5] {
            let x: f64 = v.parse().expect("a number");
            assert!(x.is_finite() && x >= 0.0, "{line}");
        }
        // √V is known from the second pass on.
        assert_eq!(f[5].is_empty(), f[1] == "1", "{line}");
        // relMSE, from the first pass.
        let rel_mse: f64 = f[8].parse().expect("relMSE");
        assert!(rel_mse.is_finite() && rel_mse >= 0.0, "{line}");
    }
    for name in [
        "study.md",
        "error-vs-time.png",
        "error-vs-time.svg",
        "sqrt-v.png",
        "sqrt-v.svg",
        "bdd0.png",
        "optimal.png",
    ] {
        let meta = std::fs::metadata(dir.join("a").join(name)).expect(name);
        assert!(meta.len() > 0, "{name} is empty");
    }
    let png = std::fs::read(dir.join("a/error-vs-time.png")).expect("png");
    assert_eq!(&png[1..4], b"PNG");
    let md = std::fs::read_to_string(dir.join("a/study.md")).expect("md");
    assert!(
        md.contains("| bdd0 |") && md.contains("| optimal |"),
        "{md}"
    );
    // Two passes in each half (even, odd): the regional choice is cross-validated.
    assert!(
        md.contains("Choosing the mode per 8 × 8-pixel block")
            && md.contains("cross-validated **1.000×**")
            && md.contains("Counting the kernel bias"),
        "{md}"
    );
    // The reference is cached in the study's directory, not under the working directory.
    assert!(!dir.join("out").exists());
    let cached: Vec<_> = std::fs::read_dir(dir.join("a"))
        .expect("a/")
        .filter_map(|e| e.ok())
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .starts_with("reference-sphere-furnace-8x8-")
        })
        .collect();
    assert_eq!(cached.len(), 1, "one cached reference");

    // Again, now with the cached reference: the same errors.
    let again = study(dir, "a");
    assert_eq!(without_times(&csv), without_times(&again));
    let md = std::fs::read_to_string(dir.join("a/study.md")).expect("md");
    assert!(md.contains("; cached "), "{md}");
}
