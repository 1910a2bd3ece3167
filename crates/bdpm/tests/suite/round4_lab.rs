//! Round four (issue 43): the lab commands under adversarial use. The memory gates of
//! `study`, `bench`, `predict`, `weights` and `merge`; a study's time budget, preview names,
//! output directory and reference; `compare` of identical files; `predict`'s pixels without
//! predicted noise; the `--modes` help. Each test failed with the binary before its fix.
use crate::{bdpm, scene};
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Runs `cmd` and fails the test if it is still running after `seconds` (a command that
/// should refuse at once but starts working instead, until memory runs out).
fn run_within(cmd: &mut Command, seconds: u64) -> Output {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run bdpm");
    let start = Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if start.elapsed() > Duration::from_secs(seconds) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("still running after {seconds} s: {cmd:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().expect("output")
}

fn run(cmd: &mut Command) -> Output {
    run_within(cmd, 600)
}

fn assert_success(out: &Output) {
    assert!(
        out.status.success(),
        "bdpm failed ({:?}):\nstdout: {}\nstderr: {}",
        out.status,
        text(&out.stdout),
        text(&out.stderr)
    );
}

/// Exit code 1 (not a panic's 101) and exactly one line on stderr containing every `needle`.
fn assert_one_line_error(out: &Output, needles: &[&str]) {
    let stderr = text(&out.stderr);
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "not one line: {stderr}");
    assert!(lines[0].starts_with("bdpm: error: "), "{stderr}");
    for n in needles {
        assert!(lines[0].contains(n), "'{n}' not in: {stderr}");
    }
}

fn read_json(path: &Path) -> serde_json::Value {
    let s = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&s).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The names of the items of a report's memory estimate.
fn memory_items(json: &serde_json::Value) -> Vec<String> {
    json["memory"]["items"]
        .as_array()
        .expect("memory.items")
        .iter()
        .map(|i| i["name"].as_str().expect("name").to_string())
        .collect()
}

/// A float channel of an EXR's first layer.
fn exr_channel(path: &Path, name: &str) -> Vec<f32> {
    let image = exr::prelude::read_all_flat_layers_from_file(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let channel = image.layer_data[0]
        .channel_data
        .list
        .iter()
        .find(|c| c.name.to_string() == name)
        .unwrap_or_else(|| panic!("no channel {name}"));
    match &channel.sample_data {
        exr::prelude::FlatSamples::F32(v) => v.clone(),
        _ => panic!("{name} is not float32"),
    }
}

/// A study (`study`) or bench above `--max-memory` is refused at once, in one line that names
/// the entry, its estimate and the limit, before the reference or any mode runs: an entry of
/// 10⁹ photons per pass (about 150 GiB), and four entries that each fit alone but not held
/// together (each keeps its film). Before, study and bench had no estimate: they traced until
/// memory ran out.
#[test]
fn study_and_bench_above_the_memory_limit_are_refused_before_any_work() {
    let tmp = crate::temp_dir("r4-memory");
    let dir = tmp.path();
    let entries = "optimal,balance:photons=1000000000";
    for command in ["study", "bench"] {
        let out = run_within(
            bdpm()
                .current_dir(dir)
                .arg(command)
                .arg(scene("cornell-lambert.toml"))
                .args(["--modes", entries, "--max-memory", "8G", "-o"])
                .arg(dir.join(command)),
            60,
        );
        assert_one_line_error(
            &out,
            &[
                "cornell-lambert.toml",
                &format!("the {command} needs about"),
                "--modes 'balance:photons=1000000000'",
                "photon map per pass",
                "more than the --max-memory of 8.0 GiB",
                "lower --photons",
            ],
        );
        assert!(!dir.join(command).exists(), "{command} wrote its output");
    }
    assert!(!dir.join("out").exists(), "a reference was rendered");

    // Each of four entries fits alone under 1.5 × one render's estimate; their four films
    // held together do not.
    let flags = ["--resolution", "512x512", "--photons", "1000", "--spp", "1"];
    let one = dir.join("one.exr");
    assert_success(&run(bdpm()
        .arg("render")
        .arg(scene("cornell-lambert.toml"))
        .args(flags)
        .args(["--mode", "bdd0", "--passes", "1", "--quiet", "-o"])
        .arg(&one)));
    let alone = read_json(&one.with_extension("json"))["memory"]["estimate_bytes"]
        .as_u64()
        .expect("estimate");
    let limit = (alone + alone / 2).to_string();
    let out = run_within(
        bdpm()
            .current_dir(dir)
            .arg("study")
            .arg(scene("cornell-lambert.toml"))
            .args(flags)
            .args(["--modes", "bdd0,bdd1,balance,power", "--passes", "2"])
            .args(["--max-memory", &limit, "-o"])
            .arg(dir.join("four")),
        60,
    );
    assert_one_line_error(
        &out,
        &[
            "the study needs about",
            "film and output images",
            "--max-memory",
        ],
    );
    assert!(!dir.join("four").exists());
    // The same four one at a time, as bench holds them, fit.
    let out = run(bdpm()
        .arg("bench")
        .arg(scene("cornell-lambert.toml"))
        .args(flags)
        .args(["--modes", "bdd0,bdd1,balance,power", "--passes", "1"])
        .args(["--repeats", "1", "--threads-list", "1"])
        .args(["--max-memory", &limit, "-o"])
        .arg(dir.join("bench.md")));
    assert_success(&out);
    let md = std::fs::read_to_string(dir.join("bench.md")).expect("bench.md");
    assert!(md.contains("Memory: the largest entry's renderer"), "{md}");
}

/// The study's own reference render, at the settings of the small studies below.
fn small() -> Vec<&'static str> {
    [&crate::TINY[..], &["--threads", "2"]].concat()
}

/// With a time budget that a mode's preparation alone exceeds, the mode still has a pass and
/// is reported (a CSV row, a table row and a note); before, it had none and vanished from the
/// CSV and the table, with a black preview and exit code 0.
#[test]
fn a_time_budget_shorter_than_a_preparation_does_not_drop_the_mode() {
    let tmp = crate::temp_dir("r4-budget");
    let dir = tmp.path();
    let out = run(bdpm()
        .current_dir(dir)
        .arg("study")
        .arg(scene("cornell-lambert.toml"))
        .args(small())
        .args(["--modes", "bdd0,optimal-path", "--time-budget", "0.000001"])
        .args(["--reference-passes", "2", "--quiet", "-o", "s"]));
    assert_success(&out);
    let csv = std::fs::read_to_string(dir.join("s/study.csv")).expect("csv");
    for mode in ["bdd0", "optimal-path"] {
        assert!(
            csv.lines().any(|l| l.starts_with(&format!("{mode},1,"))),
            "{mode}: {csv}"
        );
    }
    let md = std::fs::read_to_string(dir.join("s/study.md")).expect("md");
    assert!(md.contains("| optimal-path | 1 |"), "{md}");
    assert!(
        md.contains("Note: `optimal-path`'s preparation took")
            && md.contains("more than the time budget of 0.000001 s: it had 1 pass(es)"),
        "{md}"
    );
}

/// Two entries whose names differ only in characters that the preview's file name replaces
/// by '_' would write one preview: refused before any work, naming both and the file.
/// Before, the second preview replaced the first.
#[test]
fn entries_that_would_write_one_preview_are_refused() {
    let tmp = crate::temp_dir("r4-previews");
    let dir = tmp.path();
    let out = run_within(
        bdpm()
            .current_dir(dir)
            .arg("study")
            .arg(scene("cornell-lambert.toml"))
            .args(small())
            .args(["--modes", "balance:radius= 0.01,balance:radius=+0.01"])
            .args(["--passes", "2", "--quiet", "-o", "s"]),
        60,
    );
    assert_one_line_error(
        &out,
        &[
            "'balance:radius= 0.01' and 'balance:radius=+0.01'",
            "balance_radius__0.01.png",
        ],
    );
    assert!(!dir.join("s").exists() && !dir.join("out").exists());
}

/// `study -o FILE` is refused before any work ("is a file; study writes a directory"; before,
/// after the reference and every mode had run, "cannot create the directory"). The rendered
/// reference is cached in the study's directory, not in ./out whatever -o says; its cost is
/// announced before it starts and estimated from its first pass, and its own error is said.
#[test]
fn the_study_writes_a_directory_that_holds_its_reference() {
    let tmp = crate::temp_dir("r4-dir");
    let dir = tmp.path();
    std::fs::write(dir.join("taken"), b"keep").unwrap();
    let out = run_within(
        bdpm()
            .current_dir(dir)
            .arg("study")
            .arg(scene("cornell-lambert.toml"))
            .args(small())
            .args(["--modes", "bdd0", "--passes", "2", "--quiet", "-o", "taken"]),
        60,
    );
    assert_one_line_error(&out, &["-o taken", "is a file; study writes a directory"]);
    assert_eq!(std::fs::read(dir.join("taken")).unwrap(), b"keep");
    assert!(!dir.join("out").exists());

    let out = run(bdpm()
        .current_dir(dir)
        .arg("study")
        .arg(scene("cornell-lambert.toml"))
        .args(small())
        .args(["--modes", "bdd0,balance", "--passes", "2", "-o", "s"]));
    assert_success(&out);
    let stderr = text(&out.stderr);
    for needle in [
        "reference: rendering 32 passes of `light` (N_F = 2000, N_B = 1) to cache as s/reference-cornell-lambert-16x16-",
        "reference: its first pass took",
        "s for all 32",
        "reference: its own error (RMSE-equivalent of its standard error, an upper bound) is",
    ] {
        assert!(stderr.contains(needle), "'{needle}' not in: {stderr}");
    }
    assert!(!dir.join("out").exists(), "cached under ./out");
    let cached = std::fs::read_dir(dir.join("s"))
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with("reference-"))
        .count();
    assert_eq!(cached, 1);
    let md = std::fs::read_to_string(dir.join("s/study.md")).expect("md");
    assert!(
        md.contains("Memory: the modes' renderers held together were estimated at")
            && md.contains("the reference render before them at"),
        "{md}"
    );
}

/// `compare` of a file with its own copy: rel. RMSE and relMSE 0. Before, the second file's
/// variance was subtracted and the floor shown: 4.98 % for bit-identical files.
#[test]
fn compare_gives_no_error_for_identical_files() {
    let tmp = crate::temp_dir("r4-compare");
    let dir = tmp.path();
    let a = dir.join("a.exr");
    assert_success(&run(bdpm()
        .arg("render")
        .arg(scene("cornell-lambert.toml"))
        .args(small())
        .args(["--mode", "balance", "--passes", "3", "--quiet", "-o"])
        .arg(&a)));
    let b = dir.join("b.exr");
    std::fs::copy(&a, &b).unwrap();
    let out = run(bdpm().arg("compare").arg(&a).arg(&b));
    assert_success(&out);
    let stdout = text(&out.stdout);
    assert!(stdout.contains("bit-identical"), "{stdout}");
    assert!(
        stdout.contains("rel. RMSE 0.000%, relMSE 0.0000e0 (the images are equal)"),
        "{stdout}"
    );
}

/// `predict` on the Lambert box: pixels where the model predicts no noise at all are
/// compared, not dropped (their count is reported and they enter the ratios), so the per-pixel
/// figures cover every pixel with a surface; the summary prints the per-pixel median beside
/// the image-mean ratio. `predict` and `weights` take `--max-memory`; with `--headroom` the
/// floor's renderer is in the estimate.
#[test]
fn predict_compares_pixels_without_predicted_noise_and_takes_a_memory_limit() {
    let tmp = crate::temp_dir("r4-predict");
    let dir = tmp.path();
    let settings = [
        "--resolution",
        "64x64",
        "--passes",
        "4",
        "--photons",
        "100000",
    ];
    let measured = dir.join("m.exr");
    assert_success(&run(bdpm()
        .arg("render")
        .arg(scene("cornell-lambert.toml"))
        .args(settings)
        .args(["--quiet", "-o"])
        .arg(&measured)));
    let predict = |extra: &[&str]| {
        run(bdpm()
            .arg("predict")
            .arg(scene("cornell-lambert.toml"))
            .args(settings)
            .args(["--model-cache-photons", "1000000", "--measured"])
            .arg(&measured)
            .args(extra)
            .arg("-o")
            .arg(dir.join("p.exr")))
    };
    let out = predict(&[]);
    assert_success(&out);
    let report = read_json(&dir.join("p.json"));
    let per_pixel = &report["per_pixel"];
    let count = per_pixel["count"].as_u64().expect("count");
    let without_surface = report["pixels_without_surface"].as_u64().expect("surface");
    assert_eq!(count + without_surface, 64 * 64, "{report}");
    let (p, m) = (
        exr_channel(&dir.join("p.exr"), "predicted_V"),
        exr_channel(&dir.join("p.exr"), "measured_V"),
    );
    let zero = p
        .iter()
        .zip(&m)
        .filter(|(p, m)| **p == 0.0 && **m > 0.0)
        .count() as u64;
    assert!(
        zero > 0,
        "no pixel without predicted noise: the case is not tested"
    );
    assert_eq!(per_pixel["predicted_zero"].as_u64(), Some(zero), "{report}");
    let stdout = text(&out.stdout);
    let median = per_pixel["ratio_median"].as_f64().expect("median");
    for needle in [
        format!("per pixel, the median of predicted/measured is {median:.3}"),
        format!("{zero} of them measured noise (ratio 0"),
    ] {
        assert!(stdout.contains(&needle), "'{needle}' not in: {stdout}");
    }

    let out = predict(&["--headroom", "--max-memory", "1M"]);
    assert_one_line_error(
        &out,
        &[
            "the prediction needs about",
            "more than the --max-memory of 1.0 MiB",
        ],
    );
    let out = run(bdpm()
        .arg("weights")
        .arg(scene("cornell-lambert.toml"))
        .args([
            "--mode",
            "optimal",
            "--resolution",
            "64x64",
            "--pixel",
            "32,32",
        ])
        .args(["--max-memory", "1M", "-o"])
        .arg(dir.join("w.exr")));
    assert_one_line_error(
        &out,
        &[
            "the weight map needs about",
            "more than the --max-memory of 1.0 MiB",
        ],
    );
    assert!(!dir.join("w.exr").exists());
}

/// A merge renders no pass: its estimate leaves out the photon map of a pass, which the
/// render of the same settings counts. Before, the merge's estimate held it too.
#[test]
fn a_merge_is_estimated_without_the_photon_map_it_does_not_trace() {
    let tmp = crate::temp_dir("r4-merge");
    let dir = tmp.path();
    assert_success(&run(bdpm()
        .arg("render")
        .arg(scene("cornell-lambert.toml"))
        .args(small())
        .args([
            "--mode",
            "balance",
            "--passes",
            "2",
            "--accumulate",
            "--quiet",
        ])
        .arg("-o")
        .arg(dir.join("p.exr"))));
    assert_success(&run(bdpm()
        .arg("merge")
        .arg(dir.join("p.accum.exr"))
        .args(["--quiet", "-o"])
        .arg(dir.join("m.exr"))));
    let render = memory_items(&read_json(&dir.join("p.json")));
    let merge = memory_items(&read_json(&dir.join("m.json")));
    assert!(
        render.iter().any(|n| n == "photon map per pass"),
        "{render:?}"
    );
    assert!(
        !merge.iter().any(|n| n == "photon map per pass"),
        "{merge:?}"
    );
    assert!(
        merge
            .iter()
            .any(|n| n == "passes kept for the accumulation file"),
        "{merge:?}"
    );
}

/// The `--modes` help of study and bench lists every key an entry takes: the list of the
/// parser's own message for an unknown key. Before, it listed 7 of the 10.
#[test]
fn the_modes_help_lists_every_key_an_entry_takes() {
    let out = run(bdpm()
        .arg("study")
        .arg(scene("cornell-lambert.toml"))
        .args(["--modes", "balance:colour=red"]));
    assert_one_line_error(&out, &["unknown key; expected one of"]);
    let stderr = text(&out.stderr);
    let keys: Vec<&str> = stderr
        .split("expected one of ")
        .nth(1)
        .expect("the list")
        .trim()
        .split(", ")
        .collect();
    assert!(keys.len() >= 10, "{keys:?}");
    for command in ["study", "bench"] {
        let help = text(&run(bdpm().arg(command).arg("--help")).stdout);
        let modes = help
            .split("--modes <MODES>")
            .nth(1)
            .expect("--modes in the help");
        let modes = &modes[..modes.find("\n      --").unwrap_or(modes.len())];
        for key in &keys {
            assert!(
                modes.contains(key),
                "{command} --help: '{key}' not in {modes}"
            );
        }
    }
}

/// The lab's own flags are checked as the render's are, before any file is read, in one line
/// that names the flag and the bound. Before, a negative number was "unexpected argument
/// '-1'", `--threads-list 100000` was refused as `--threads`, and `--blocks 0` was found only
/// after both files were read and half the summary printed.
#[test]
fn the_lab_s_flags_are_refused_with_one_line_naming_the_flag() {
    let cases: [(&[&str], &[&str]); 6] = [
        (
            &["study", "S", "--time-budget", "-1"],
            &["--time-budget", "'-1' is not a positive number"],
        ),
        (
            &["study", "S", "--reference-photons", "-3"],
            &["--reference-photons", "'-3' is not a whole number"],
        ),
        (
            &["bench", "S", "--threads-list", "100000"],
            &["--threads-list: 100000 threads is outside 1 to"],
        ),
        (
            &["bench", "S", "--repeats", "-1"],
            &["--repeats", "'-1' is not a whole number"],
        ),
        (
            &[
                "compare",
                "missing-a.exr",
                "missing-b.exr",
                "--sigmas",
                "-1",
            ],
            &["--sigmas", "'-1' is not a positive number"],
        ),
        (
            &["compare", "missing-a.exr", "missing-b.exr", "--blocks", "0"],
            &["--blocks must be at least 1 pixel"],
        ),
    ];
    let scene = scene("cornell-lambert.toml");
    for (args, needles) in cases {
        let args: Vec<&std::ffi::OsStr> = args
            .iter()
            .map(|a| match *a {
                "S" => scene.as_os_str(),
                a => std::ffi::OsStr::new(a),
            })
            .collect();
        let out = run_within(bdpm().args(&args), 60);
        assert_one_line_error(&out, needles);
    }
}
