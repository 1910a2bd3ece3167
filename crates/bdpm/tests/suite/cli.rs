//! Tests of the `bdpm` binary as a user runs it: the files `render` and `weights` write and
//! what they contain, one-line errors (exit code 1, never a panic) for bad input, and an
//! interrupted render that keeps its work.
use crate::{TINY, bdpm, scene};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// A fresh directory under the system temp dir, removed when dropped.
struct TempDir(tempfile::TempDir);

impl TempDir {
    fn new(tag: &str) -> TempDir {
        TempDir(crate::temp_dir(&format!("cli-{tag}")))
    }

    fn path(&self, name: &str) -> PathBuf {
        self.0.path().join(name)
    }

    /// Files whose name starts with '.': the writers' temporary files, which must not survive.
    fn hidden_files(&self) -> Vec<String> {
        std::fs::read_dir(self.0.path())
            .expect("read temp dir")
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with('.'))
            .collect()
    }
}

fn run(cmd: &mut Command) -> Output {
    cmd.output().expect("run bdpm")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
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

/// An EXR read back: its channels by name and its `bdpm.*` text attributes.
struct Exr {
    width: usize,
    height: usize,
    channels: HashMap<String, Vec<f32>>,
    /// Names of the channels stored as half floats.
    halves: Vec<String>,
    attributes: HashMap<String, String>,
}

impl Exr {
    fn read(path: &Path) -> Exr {
        let image = exr::prelude::read_all_flat_layers_from_file(path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(image.layer_data.len(), 1, "one layer");
        let layer = &image.layer_data[0];
        let mut channels = HashMap::new();
        let mut halves = Vec::new();
        for c in &layer.channel_data.list {
            let v = match &c.sample_data {
                exr::prelude::FlatSamples::F32(v) => v.clone(),
                exr::prelude::FlatSamples::F16(v) => {
                    halves.push(c.name.to_string());
                    v.iter().map(|x| x.to_f32()).collect()
                }
                _ => panic!("channel {} is not float32 or half", c.name),
            };
            channels.insert(c.name.to_string(), v);
        }
        let mut attributes = HashMap::new();
        for (k, v) in &layer.attributes.other {
            if let exr::prelude::AttributeValue::Text(t) = v {
                attributes.insert(k.to_string(), t.to_string());
            }
        }
        Exr {
            width: layer.size.0,
            height: layer.size.1,
            channels,
            halves,
            attributes,
        }
    }

    fn channel(&self, name: &str) -> &[f32] {
        self.channels.get(name).unwrap_or_else(|| {
            let mut names: Vec<_> = self.channels.keys().collect();
            names.sort();
            panic!("no channel {name}; channels: {names:?}")
        })
    }
}

fn read_json(path: &Path) -> serde_json::Value {
    let s = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&s).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The number at JSON pointer `path` of a report; panics naming the path if there is none.
fn json_number(json: &serde_json::Value, path: &str) -> f64 {
    json.pointer(path)
        .and_then(|v| v.as_f64())
        .unwrap_or_else(|| panic!("{path} is not a number"))
}

fn rgb(prefix: &str) -> [String; 3] {
    ["R", "G", "B"].map(|c| {
        if prefix.is_empty() {
            c.to_string()
        } else {
            format!("{prefix}.{c}")
        }
    })
}

#[test]
fn render_writes_exr_png_noise_map_and_report() {
    let dir = TempDir::new("render");
    let out = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--mode", "path", "--resolution", "24x24", "--passes", "2"])
        .args(["--spp", "2", "--quiet", "-o"])
        .arg(dir.path("X.exr")));
    assert_success(&out);
    for f in ["X.exr", "X.png", "X-noise.png", "X.json"] {
        assert!(dir.path(f).is_file(), "{f} missing");
    }
    assert!(dir.hidden_files().is_empty(), "{:?}", dir.hidden_files());

    let exr = Exr::read(&dir.path("X.exr"));
    assert_eq!((exr.width, exr.height), (24, 24));
    for prefix in ["", "noise", "stderr"] {
        for name in rgb(prefix) {
            let c = exr.channel(&name);
            assert_eq!(c.len(), 24 * 24);
            assert!(c.iter().all(|v| v.is_finite() && *v >= 0.0), "{name}");
        }
    }
    assert!(exr.channel("R").iter().any(|v| *v > 0.0), "black image");
    let attr = |k: &str| exr.attributes.get(k).map(String::as_str);
    assert_eq!(attr("bdpm.mode"), Some("path"));
    assert_eq!(attr("bdpm.seed"), Some("1"));
    assert_eq!(attr("bdpm.passes"), Some("2"));
    assert_eq!(attr("bdpm.passes_done"), Some("2"));
    assert_eq!(attr("bdpm.spp"), Some("2"));

    let json = read_json(&dir.path("X.json"));
    let settings = &json["settings"];
    assert_eq!(settings["mode"], "path");
    assert!(settings["photons_per_pass"].as_u64().is_some());
    assert_eq!(settings["spp"], 2);
    assert!(settings["radius_m"].as_f64().is_some_and(|r| r > 0.0));
    assert_eq!(json["passes_done"], 2);
    assert_eq!(json["interrupted"], false);
    let outputs: Vec<&str> = json["outputs"]
        .as_array()
        .expect("outputs")
        .iter()
        .filter_map(|v| v.as_str())
        .collect();
    assert!(
        outputs.iter().any(|o| o.ends_with("X-noise.png")),
        "{outputs:?}"
    );

    // The noise map is the render upscaled, plus a legend panel.
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(dir.path("X-noise.png")).expect("open noise png"),
    ));
    let reader = decoder.read_info().expect("noise png header");
    let info = reader.info();
    assert!(info.width > 24 * 2 && info.height >= 24 * 2);
}

#[test]
fn technique_layers_sum_to_the_image() {
    let dir = TempDir::new("techniques");
    let out = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args([
            "--mode",
            "optimal",
            "--resolution",
            "24x24",
            "--passes",
            "2",
        ])
        .args([
            "--spp",
            "2",
            "--photons",
            "20000",
            "--techniques",
            "--quiet",
            "-o",
        ])
        .arg(dir.path("T.exr")));
    assert_success(&out);
    let exr = Exr::read(&dir.path("T.exr"));
    for layer in ["direct", "x0_raw", "x0_weighted", "x1_raw", "x1_weighted"] {
        for name in rgb(layer) {
            assert!(exr.channel(&name).iter().all(|v| v.is_finite()), "{name}");
        }
    }
    let mut worst = 0.0f64;
    for c in ["R", "G", "B"] {
        let image = exr.channel(c);
        let part = |l: &str| exr.channel(&format!("{l}.{c}"));
        let (d, x0, x1) = (part("direct"), part("x0_weighted"), part("x1_weighted"));
        for i in 0..image.len() {
            let sum = d[i] as f64 + x0[i] as f64 + x1[i] as f64;
            let want = image[i] as f64;
            let err = (sum - want).abs();
            assert!(
                err <= 1e-5 * want.abs() + 1e-9,
                "{c} pixel {i}: direct + x0_weighted + x1_weighted = {sum}, image {want}"
            );
            worst = worst.max(err / want.abs().max(1e-12));
        }
    }
    eprintln!("worst relative difference {worst:e}");
    assert!(exr.channel("x1_weighted.R").iter().any(|v| *v != 0.0));
}

#[test]
fn techniques_flag_is_refused_for_reference_modes() {
    let dir = TempDir::new("techniques-path");
    let out = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--mode", "path", "--resolution", "8x8", "--passes", "1"])
        .args(["--techniques", "--quiet", "-o"])
        .arg(dir.path("p.exr")));
    assert_one_line_error(&out, &["--techniques", "path"]);
    assert!(!dir.path("p.exr").exists());
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

/// A small valid scene (a coarse closed sphere with one light), to be broken by each case.
const BASE_SCENE: &str = r#"
[render]
resolution = [8, 8]
passes = 1
photons = 1000
spp = 1
mode = "path"

[camera]
position = [-0.5, 0.0, 0.0]
look_at = [0.5, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
vfov = 60

[[light]]
position = [0.3, -0.2, 0.1]
flux = [1.0, 1.0, 1.0]

[material.inside]
kd = 0.5

[[shape]]
type = "sphere"
center = [0.0, 0.0, 0.0]
radius = 1.0
subdivisions = 2
facing = "inside"
material = "inside"
"#;

#[test]
fn bad_input_gives_one_line_naming_file_and_field() {
    let dir = TempDir::new("errors");
    let base = BASE_SCENE;
    let mesh = |file: &str| format!("{base}\n[[shape]]\ntype = \"mesh\"\nfile = \"{file}\"\n");
    std::fs::write(dir.path("bad.gltf"), b"\x00\x9f garbage {{ not json").expect("write");
    // Faults in the scene file: (file name, text of the base scene, its replacement, what the
    // error line must contain).
    #[rustfmt::skip]
    let edits: [(&str, &str, &str, &[&str]); 6] = [
        ("no-vfov.toml",    "vfov = 60\n",     "",                  &["camera.vfov", "missing"]),
        ("negative.toml",   "kd = 0.5",        "kd = -0.1",         &["material.inside.kd", "-0.1"]),
        ("above-one.toml",  "kd = 0.5",        "kd = 1.2",          &["material.inside.kd", "1.2"]),
        ("energy.toml",     "kd = 0.5",        "kd = 0.6\ngr = 0.5\ndelta = 10", &["material.inside", "kd + gr"]),
        ("mode.toml",       "mode = \"path\"", "mode = \"fastest\"", &["render.mode", "fastest"]),
        ("typo.toml",       "spp = 1",         "sp = 1",            &["`sp`"]),
    ];
    // (file name, scene text, extra arguments, what the error line must contain)
    #[rustfmt::skip]
    let mut cases: Vec<(&str, String, &[&str], &[&str])> = vec![
        ("valid.toml",        base.into(),          &[],                 &[]),
        ("flag.toml",         base.into(),          &["--mode", "fast"], &["--mode", "fast"]),
        ("missing-mesh.toml", mesh("missing.gltf"), &[],                 &["missing.gltf", "shape[1].file"]),
        ("corrupt-mesh.toml", mesh("bad.gltf"),     &[],                 &["bad.gltf", "shape[1].file"]),
    ];
    cases.extend(
        edits.map(|(name, from, to, needles)| (name, base.replace(from, to), &[][..], needles)),
    );
    for (name, scene_text, extra, needles) in cases {
        let path = dir.path(name);
        std::fs::write(&path, scene_text).expect("write scene");
        let out_exr = dir.path(&format!("{name}.exr"));
        let out = run(bdpm()
            .arg("render")
            .arg(&path)
            .args(extra)
            .args(["--quiet", "-o"])
            .arg(&out_exr));
        if needles.is_empty() {
            // The unbroken scene renders: the other cases fail for their one fault only.
            assert_success(&out);
            continue;
        }
        let mut all = needles.to_vec();
        // A flag error names the flag; a glTF error names the glTF file and the scene field
        // that referenced it; every other error names the scene file.
        if !name.starts_with("flag") && !name.ends_with("mesh.toml") {
            all.push(name);
        }
        assert_one_line_error(&out, &all);
        assert!(!out_exr.exists(), "{name}: an output was written");
    }
    let missing = dir.path("does-not-exist.toml");
    let out = run(bdpm().arg("render").arg(&missing).arg("--quiet"));
    assert_one_line_error(&out, &["does-not-exist.toml", "cannot read"]);
    assert!(dir.hidden_files().is_empty(), "{:?}", dir.hidden_files());
}

/// A quiet render of the Cornell scene with `settings` and `more` to `out`, interrupted after
/// `wait` seconds: its exit code and its output.
fn interrupted_render(
    wait: f64,
    settings: &[&str],
    more: &[&str],
    out: &Path,
) -> (Option<i32>, Output) {
    let mut child = spawn_render(&[settings, more], out);
    std::thread::sleep(Duration::from_secs_f64(wait));
    let code = interrupt(&mut child);
    (code, child.wait_with_output().expect("output"))
}

#[test]
fn interrupted_render_writes_what_it_has() {
    let dir = TempDir::new("sigint");
    // Loading and one 32×32 pass take well under a second; if the signal still comes before
    // the first pass ends, the render (correctly) writes nothing, and the test waits longer.
    for wait in [1.5, 6.0] {
        let (code, out) = interrupted_render(
            wait,
            &["--resolution", "32x32", "--passes", "100000", "--spp", "1"],
            &["--photons", "20000", "--mode", "bdd0", "--threads", "1"],
            &dir.path("i.exr"),
        );
        let stderr = text(&out.stderr);
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert_eq!(code, Some(130), "stderr: {stderr}");
        if stderr.contains("nothing was written") {
            continue;
        }
        for f in ["i.exr", "i.png", "i-noise.png", "i.json"] {
            assert!(dir.path(f).is_file(), "{f} missing");
        }
        assert!(dir.hidden_files().is_empty(), "{:?}", dir.hidden_files());
        let json = read_json(&dir.path("i.json"));
        assert_eq!(json["interrupted"], true);
        let done = json["passes_done"].as_u64().expect("passes_done");
        assert!((1..100_000).contains(&done), "passes_done {done}");
        assert!(text(&out.stdout).contains(&format!("interrupted after {done} of 100000")));
        let exr = Exr::read(&dir.path("i.exr"));
        assert_eq!(
            exr.attributes.get("bdpm.passes_done"),
            Some(&done.to_string())
        );
        return;
    }
    panic!("the render did not finish a pass within 6 s");
}

/// Pixel (column, row) in which the Cornell camera (pinhole at (1.39, 1.365, −4) m looking
/// +z, up +y, vfov 39.3°, square `n`×`n` image, +x to the left) sees world point `p`.
fn cornell_pixel(p: [f64; 3], n: usize) -> (f64, f64) {
    let tan_half = (39.3f64.to_radians() / 2.0).tan();
    let dz = p[2] + 4.0;
    let ndc_x = (p[0] - 1.39) / dz / tan_half;
    let ndc_y = (p[1] - 1.365) / dz / tan_half;
    (
        (1.0 - ndc_x) / 2.0 * n as f64,
        (1.0 - ndc_y) / 2.0 * n as f64,
    )
}

#[test]
fn weight_map_shows_the_ceiling_spot() {
    // The preprint's Fig. 5 must-show: for x₀ on the floor, w₀ is large only in the small spot
    // on the ceiling above the light, and ≤ 0.03 almost everywhere else. The spot is about a
    // pixel wide at this resolution, so the test uses 67×67, where a pixel centre falls within
    // 0.04 pixel of the ceiling point above the light (at 64×64 the nearest centre is ~0.6 px
    // away and sees only w₀ ≈ 0.33).
    let n = 67;
    let dir = TempDir::new("weights");
    let out = run(bdpm()
        .arg("weights")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--x0", "1.05,0.4125,0.4475", "--mode", "algebraic"])
        // The preprint's figure is drawn with its own (pinhole) noise model: N_B = 30.
        .args(["--noise-model", "pinhole"])
        .args(["--resolution", &format!("{n}x{n}")])
        .args(["--photons", "1000000", "--spp", "30", "-o"])
        .arg(dir.path("w.exr")));
    assert_success(&out);
    assert!(dir.path("w.png").is_file());
    assert!(text(&out.stdout).contains("median"));
    let exr = Exr::read(&dir.path("w.exr"));
    assert_eq!((exr.width, exr.height), (n, n));
    assert_eq!(
        exr.attributes.get("bdpm.mode").map(String::as_str),
        Some("algebraic")
    );
    let w0 = exr.channel("w0");

    // The ceiling (y = 548.8 mm × 0.005) above the light at (1.39, 2.676, 1.398) m.
    let (sx, sy) = cornell_pixel([1.39, 2.744, 1.398], n);
    let (cx, cy) = (sx as usize, sy as usize);
    assert!((sx - (cx as f64 + 0.5)).abs() < 0.05 && (sy - (cy as f64 + 0.5)).abs() < 0.05);
    let spot = w0[cy * n + cx] as f64;
    eprintln!("w0 above the light: {spot:.3}");
    assert!((0.5..=0.9).contains(&spot), "w0 above the light = {spot}");

    // Everywhere else (outside a few pixels around the spot), w₀ is small.
    let mut others = 0usize;
    let mut small = 0usize;
    for y in 0..n {
        for x in 0..n {
            let w = w0[y * n + x];
            if w.is_nan() || (x.abs_diff(cx) <= 3 && y.abs_diff(cy) <= 3) {
                continue;
            }
            others += 1;
            small += usize::from(w <= 0.03);
        }
    }
    let fraction = small as f64 / others as f64;
    eprintln!("w0 <= 0.03 on {:.1}% of the other pixels", 100.0 * fraction);
    assert!(others > n * n / 2, "only {others} pixels see a surface");
    assert!(
        fraction >= 0.9,
        "w0 <= 0.03 on only {:.1}% of pixels",
        100.0 * fraction
    );
}

#[test]
fn weights_needs_a_mode_with_weights() {
    let out = run(bdpm()
        .arg("weights")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--pixel", "4,4", "--mode", "path", "--resolution", "8x8"]));
    assert_one_line_error(&out, &["--mode path", "no weights"]);
    // Refused from the settings, before the mode's pilot pass would run.
    let out = run(bdpm()
        .arg("weights")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--pixel", "4,4", "--mode", "corrected-balance"]));
    assert_one_line_error(
        &out,
        &["--mode corrected-balance", "incoming direction at x1"],
    );
    let out = run(bdpm()
        .arg("weights")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--pixel", "40,4", "--mode", "bdd1", "--resolution", "8x8"]));
    assert_one_line_error(&out, &["--pixel", "outside"]);
    let out = run(bdpm()
        .arg("weights")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--pixel", "4,4", "--mode", "optimal", "--resolution", "8x8"])
        .args(["--light-tracing", "true"]));
    assert_one_line_error(&out, &["cornell-lambert.toml", "light_tracing = true"]);
    // A radius per block is the pixel's (tests/suite/weight_map.rs checks the map itself).
    let dir = TempDir::new("weights-adaptive");
    let out = run(bdpm()
        .arg("weights")
        .arg(scene("cornell-glossy.toml"))
        .args([
            "--pixel",
            "4,4",
            "--mode",
            "optimal",
            "--resolution",
            "16x16",
            "-o",
        ])
        .arg(dir.path("w.exr")));
    assert_success(&out);
    assert!(dir.path("w.exr").is_file());
}

/// `bdpm compare`: a render and its rerun with 1 thread are bit-identical (exit 0 with
/// `--require-identical`); a render with another seed is not (exit 1), but agrees with it
/// statistically; images of different sizes are refused with one line.
#[test]
fn compare_tells_identical_from_merely_equivalent_renders() {
    let dir = TempDir::new("compare");
    let render = |name: &str, seed: &str, threads: &str, res: &str| {
        let out = run(bdpm()
            .arg("render")
            .arg(scene("preprint/cornell-lambert.toml"))
            .args(["--mode", "balance", "--resolution", res, "--passes", "3"])
            .args(["--spp", "4", "--photons", "20000", "--seed", seed])
            .args(["--threads", threads, "--quiet", "-o"])
            .arg(dir.path(name)));
        assert_success(&out);
    };
    render("a.exr", "1", "2", "16x16");
    render("b.exr", "1", "1", "16x16");
    render("c.exr", "2", "2", "16x16");
    render("d.exr", "1", "2", "8x8");
    let compare = |a: &str, b: &str| {
        run(bdpm()
            .arg("compare")
            .arg(dir.path(a))
            .arg(dir.path(b))
            .arg("--require-identical"))
    };
    let same = compare("a.exr", "b.exr");
    assert_success(&same);
    assert!(
        text(&same.stdout).contains("bit-identical"),
        "{}",
        text(&same.stdout)
    );
    let other = compare("a.exr", "c.exr");
    assert_eq!(other.status.code(), Some(1), "{}", text(&other.stdout));
    assert!(
        text(&other.stdout).contains("pixels differ"),
        "{}",
        text(&other.stdout)
    );
    let sizes = compare("a.exr", "d.exr");
    assert_one_line_error(&sizes, &["a.exr", "16x16", "8x8"]);
}

/// `bdpm predict`: render cornell-lambert with bdd0, then evaluate the noise model of method.md
/// §12 for the same settings. The files exist, the report's numbers are finite, and over 8×8
/// blocks the median predicted/measured V lies within a factor of 2. The merge radius is
/// raised to 1 cm so that each gather finds photons at 30000 per pass: with the default
/// 1.75 mm most gathers are empty and a pixel's measured V hinges on a handful of photons.
/// A render with other settings, or of another size, is refused with one line. With a radius
/// per block of pixels (`--adaptive-radius true`) the model follows each pixel's radius.
#[test]
fn predict_compares_the_noise_model_with_a_render() {
    let dir = TempDir::new("predict");
    let settings = [
        "--mode",
        "bdd0",
        "--resolution",
        "32x32",
        "--photons",
        "30000",
        "--spp",
        "8",
        "--radius",
        "0.01",
    ];
    let (rendered, out) = render_then_predict(
        &dir,
        "preprint/cornell-lambert.toml",
        (&settings, "8"),
        &["--headroom"],
        "r",
    );
    assert_success(&out);
    assert!(text(&out.stdout).contains("8x8 blocks"));
    assert!(text(&out.stdout).contains("headroom over the floor"));
    // The model's own cache (bdd0's weights read none) is reported with the other stages.
    assert!(
        text(&out.stdout).contains("radiance cache") && text(&out.stdout).contains("noise model's"),
        "{}",
        text(&out.stdout)
    );
    assert!(dir.path("p-r.png").is_file());
    assert!(dir.path("p-r-headroom.png").is_file());
    let exr = Exr::read(&dir.path("p-r.exr"));
    assert_eq!((exr.width, exr.height), (32, 32));
    for c in [
        "predicted_V",
        "measured_V",
        "ratio",
        "T0",
        "T1",
        "T2",
        "T_jitter",
        "floor_V",
        "headroom",
    ] {
        assert_eq!(exr.channel(c).len(), 32 * 32);
    }
    let json = read_json(&dir.path("p-r.json"));
    eprintln!("{json:#}");
    let number = |path: &str| json_number(&json, path);
    for path in [
        "/image_mean_predicted_v",
        "/image_mean_measured_v",
        "/measured_relative_se_per_pixel",
        "/term_shares/t0",
        "/term_shares/t1",
        "/term_shares/t2",
        "/term_shares/t_jitter",
        "/per_pixel/correlation_log",
        "/per_pixel/correlation",
        "/per_pixel/ratio_median",
        "/per_pixel/ratio_q10",
        "/per_pixel/ratio_q90",
        "/blocks/correlation_log",
        "/blocks/correlation",
        "/blocks/ratio_median",
        "/blocks/ratio_q10",
        "/blocks/ratio_q90",
    ] {
        assert!(number(path).is_finite(), "{path} = {}", number(path));
    }
    assert_eq!(number("/passes"), 8.0);
    // bdd0 has no x₁ part.
    assert_eq!(number("/term_shares/t1") + number("/term_shares/t2"), 0.0);
    assert!(number("/term_shares/t0") > 0.0);
    let median = number("/blocks/ratio_median");
    assert!((0.5..=2.0).contains(&median), "block median ratio {median}");
    // Pure BDD=0 sits well above the floor that the mixed weights reach.
    let headroom = number("/headroom/blocks/ratio_median");
    assert!(
        headroom > 1.1,
        "bdd0's predicted V over the floor {headroom}"
    );
    assert!(number("/headroom/image_mean_floor_v") > 0.0);

    // A render with other settings is refused, naming them: (setting changed, value,
    // what the error line must contain).
    for (i, value, needles) in [
        (7, "4", &["r.exr", "spp 8"][..]),
        (3, "16x16", &["r.exr", "32x32", "16x16"]),
    ] {
        let mut other = settings.to_vec();
        other[i] = value;
        let out = run(bdpm()
            .arg("predict")
            .arg(scene("preprint/cornell-lambert.toml"))
            .args(&other)
            .arg("--measured")
            .arg(&rendered)
            .arg("-o")
            .arg(dir.path("q.exr")));
        assert_one_line_error(&out, needles);
    }
    // Refused with one line naming the flag: light tracing in place of the merge at x₀, which
    // the model does not describe; a model cache beyond any machine's memory, before it is built.
    for (extra, needles) in [
        (
            ["--light-tracing", "true"],
            ["light_tracing = true", "--light-tracing false"],
        ),
        (
            ["--model-cache-photons", "1000000000000"],
            ["the prediction needs about", "lower --model-cache-photons"],
        ),
    ] {
        let out = run(bdpm()
            .arg("predict")
            .arg(scene("preprint/cornell-lambert.toml"))
            .args(settings)
            .args(extra)
            .arg("--measured")
            .arg(&rendered)
            .arg("-o")
            .arg(dir.path("q.exr")));
        assert_one_line_error(&out, &[&["cornell-lambert.toml"][..], &needles].concat());
    }

    // A radius per block of pixels: bdd0's pilot has no BDD=1 share, so every block merges at
    // ½ r (here 1 cm again). Without jitter V is T0 alone, and a model that kept r everywhere
    // would predict a quarter of the measured V.
    let mut adaptive = settings.to_vec();
    adaptive[9] = "0.02";
    adaptive.extend(["--adaptive-radius", "true", "--no-jitter"]);
    let scene_name = "preprint/cornell-lambert.toml";
    let (_, out) = render_then_predict(&dir, scene_name, (&adaptive, "8"), &[], "a");
    assert_success(&out);
    let json = read_json(&dir.path("p-a.json"));
    let median = json_number(&json, "/blocks/ratio_median");
    assert!(
        (0.5..=2.0).contains(&median),
        "block median ratio {median} with a radius per block"
    );
}

/// `bdpm predict --headroom` on the glossy file, whose radius is per block: the floor weighs
/// on the mode's own map (its own pilot, of other weights, draws another at 64², seed 2, and
/// 10 % of the pixels then sat below the floor: 0.84), with the model's cache
/// (`--model-cache-photons`), so no pixel of the mode is meaningfully below it.
#[test]
fn predict_headroom_keeps_the_modes_radius_map() {
    let dir = TempDir::new("headroom-map");
    let settings = ["--resolution", "64x64", "--seed", "2"];
    let predict = ["--headroom", "--model-cache-photons", "1000000"];
    let (_, out) =
        render_then_predict(&dir, "cornell-glossy.toml", (&settings, "2"), &predict, "g");
    assert_success(&out);
    let json = read_json(&dir.path("p-g.json"));
    let q10 = json_number(&json, "/headroom/per_pixel/ratio_q10");
    assert!(
        q10 > 0.98,
        "10 % of the pixels at {q10} of the floor or less"
    );
}

/// Renders `scene_name` with `settings` and `passes` passes to DIR/NAME.exr (asserting success),
/// then runs `bdpm predict` with the same settings and `predict_args` against it, writing
/// DIR/p-NAME.*: the render's path and predict's output.
fn render_then_predict(
    dir: &TempDir,
    scene_name: &str,
    (settings, passes): (&[&str], &str),
    predict_args: &[&str],
    name: &str,
) -> (PathBuf, std::process::Output) {
    let rendered = dir.path(&format!("{name}.exr"));
    let out = run(bdpm()
        .arg("render")
        .arg(scene(scene_name))
        .args(settings)
        .args(["--passes", passes, "--quiet", "-o"])
        .arg(&rendered));
    assert_success(&out);
    let out = run(bdpm()
        .arg("predict")
        .arg(scene(scene_name))
        .args(settings)
        .arg("--measured")
        .arg(&rendered)
        .args(predict_args)
        .arg("-o")
        .arg(dir.path(&format!("p-{name}.exr"))));
    (rendered, out)
}

/// A quiet render of the Cornell scene with the arguments `args` to `out`, its standard
/// output and error piped.
fn spawn_render(args: &[&[&str]], out: &Path) -> std::process::Child {
    crate::spawn_render(&scene("preprint/cornell-lambert.toml"), &args.concat(), out)
}

/// A render of the Cornell box that runs until interrupted (one thread, 100000 passes).
fn endless_render(out: &Path) -> std::process::Child {
    spawn_render(
        &[
            &["--resolution", "16x16", "--passes", "100000", "--spp", "1"],
            &["--mode", "path", "--threads", "1"],
        ],
        out,
    )
}

/// Sends SIGINT and waits (at most 60 s) for the exit code.
fn interrupt(child: &mut std::process::Child) -> Option<i32> {
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("run kill");
    assert!(status.success());
    let start = Instant::now();
    loop {
        if let Some(s) = child.try_wait().expect("wait") {
            return s.code();
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("bdpm did not stop within 60 s of SIGINT");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn output_location_is_checked_before_any_work() {
    let dir = TempDir::new("preflight");
    std::fs::create_dir_all(dir.path("adir")).expect("mkdir");
    std::fs::write(dir.path("afile"), b"x").expect("write");
    std::fs::create_dir_all(dir.path("clash.json")).expect("mkdir");
    let cases: Vec<(PathBuf, &str)> = vec![
        (dir.path("adir"), "is a directory"),
        (PathBuf::from("/dev/null"), "not a regular file"),
        (dir.path("afile").join("x.exr"), "not a directory"),
        (dir.path("clash.exr"), "is a directory"),
    ];
    for (out_path, needle) in cases {
        let start = Instant::now();
        // 10⁵ passes would take minutes: the error must come before the render.
        let out = run(bdpm()
            .arg("render")
            .arg(scene("preprint/cornell-lambert.toml"))
            .args([
                "--resolution",
                "64x64",
                "--passes",
                "100000",
                "--quiet",
                "-o",
            ])
            .arg(&out_path));
        assert_one_line_error(&out, &[needle]);
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "{}: refused only after {:?}",
            out_path.display(),
            start.elapsed()
        );
    }
    assert!(!Path::new("/dev/null.exr").exists());
    assert!(dir.hidden_files().is_empty(), "{:?}", dir.hidden_files());
}

#[test]
fn a_second_render_to_the_same_output_is_refused_and_temps_cannot_be_planted() {
    let dir = TempDir::new("lock");
    let out = dir.path("L.exr");
    std::fs::write(dir.path("victim"), b"precious").expect("write victim");
    let mut first = endless_render(&out);
    // The lock exists once the output has been claimed, before the first pass.
    let start = Instant::now();
    while !dir.path(".L.exr.lock").exists() {
        assert!(start.elapsed() < Duration::from_secs(30), "no lock file");
        std::thread::sleep(Duration::from_millis(20));
    }
    // Symlinks at the temporary names an older bdpm used (`.NAME.PID.tmp`): a writer that
    // followed them would overwrite the victim with its output.
    for name in ["L.exr", "L.png", "L-noise.png", "L.json"] {
        let link = dir.path(&format!(".{name}.{}.tmp", first.id()));
        std::os::unix::fs::symlink(dir.path("victim"), link).expect("plant symlink");
    }
    let second = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--resolution", "8x8", "--passes", "1", "--quiet", "-o"])
        .arg(&out));
    assert_one_line_error(&second, &["L.exr", "another bdpm render"]);
    std::thread::sleep(Duration::from_millis(300));
    let code = interrupt(&mut first);
    let stderr = text(&first.wait_with_output().expect("output").stderr);
    assert_eq!(code, Some(130), "{stderr}");
    assert_eq!(
        std::fs::read(dir.path("victim")).expect("victim"),
        b"precious"
    );
    if !stderr.contains("nothing was written") {
        // The files are one run's: the report's run_id is the EXR's.
        let json = read_json(&dir.path("L.json"));
        let exr = Exr::read(&out);
        let id = json["run_id"].as_str().expect("run_id");
        assert_eq!(
            exr.attributes.get("bdpm.run_id").map(String::as_str),
            Some(id)
        );
    }
    let mut hidden = dir.hidden_files();
    hidden.retain(|n| !n.ends_with(".tmp"));
    assert!(hidden.is_empty(), "{hidden:?}");
}

#[test]
fn stale_temporary_files_of_the_output_are_removed() {
    let dir = TempDir::new("stale");
    let an_hour_ago = std::time::SystemTime::now() - Duration::from_secs(3600);
    for name in [
        ".S.exr.Ab3dE9xQ1z.bdpm-tmp",
        ".S.json.0123456789.bdpm-tmp",
        ".S.accum.exr.Zz9yX8wV7u.bdpm-tmp",
        ".keep",
    ] {
        let f = std::fs::File::create(dir.path(name)).expect("create");
        f.set_modified(an_hour_ago).expect("set mtime");
    }
    let out = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args([
            "--mode",
            "path",
            "--resolution",
            "8x8",
            "--passes",
            "1",
            "--quiet",
            "-o",
        ])
        .arg(dir.path("S.exr")));
    assert_success(&out);
    assert_eq!(dir.hidden_files(), vec![".keep".to_string()]);
}

#[test]
fn command_line_numbers_are_checked_with_clear_messages() {
    let dir = TempDir::new("flags");
    let path = dir.path("s.toml");
    std::fs::write(&path, BASE_SCENE).expect("write scene");
    // (arguments, what the one error line must contain)
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            vec!["--radius", "-1"],
            vec!["--radius", "-1 must be a finite number > 0"],
        ),
        (
            vec!["--passes", "-1"],
            vec!["--passes", "-1 is outside [1, 4294967295]"],
        ),
        (
            vec!["--spp", "2.5"],
            vec!["--spp", "expected a whole number", "found the number 2.5"],
        ),
        (
            vec!["--radius", "1e-30"],
            vec!["--radius", "smallest usable"],
        ),
        // Checked as written, as a scene file's radius is: subnormal in f32.
        (
            vec!["--radius", "1e-39"],
            vec!["--radius", "1e-39", "smallest normal"],
        ),
        (vec!["--radius", "1e300"], vec!["--radius", "1e300"]),
        (
            vec!["--threads", "10000"],
            vec!["--threads 10000", "at most"],
        ),
        (vec!["--no-such-flag"], vec!["--no-such-flag"]),
        // Out of range for the setting: named by the flag, not the scene file's key.
        (vec!["--cache-bins", "0"], vec!["--cache-bins"]),
        (vec!["--cache-bins", "5000"], vec!["--cache-bins", "5000"]),
    ];
    for (args, needles) in cases {
        let out = run(bdpm()
            .arg("render")
            .arg(&path)
            .args(&args)
            .args(["--quiet", "-o"])
            .arg(dir.path("x.exr")));
        assert_one_line_error(&out, &needles);
    }
    assert!(!dir.path("x.exr").exists());
    let help = run(bdpm().args(["study", "--help"]));
    assert_success(&help);
    let help = text(&help.stdout);
    assert!(help.contains("--modes"), "{help}");
    assert!(
        !help.contains("--mode "),
        "study --help lists --mode:\n{help}"
    );
    let out = run(bdpm().arg("study").arg(&path).args(["--mode", "path"]));
    assert_one_line_error(&out, &["--modes"]);
}

/// A scene file without `[render]` renders with the library's defaults, the configuration
/// docs/results.md ("A scene that sets nothing") chose: `optimal-path`, half a pixel's
/// footprint, N_F = 2.5·10⁵, N_B = 10, stratified samples, one radiance-cache bin per cell side.
#[test]
fn a_scene_that_sets_nothing_renders_with_the_chosen_defaults() {
    let dir = TempDir::new("nothing");
    let path = dir.path("nothing.toml");
    let scene = BASE_SCENE
        .split_once("[camera]")
        .map(|(_, rest)| format!("[camera]{rest}"))
        .expect("the base scene has a camera");
    assert!(!scene.contains("[render]"));
    std::fs::write(&path, scene).expect("write scene");
    let out = run(bdpm()
        .arg("render")
        .arg(&path)
        .args(["--resolution", "16x16", "--passes", "1", "--quiet", "-o"])
        .arg(dir.path("nothing.exr")));
    assert_success(&out);
    let json = read_json(&dir.path("nothing.json"));
    let s = &json["settings"];
    assert_eq!(s["mode"], "optimal-path", "{s}");
    assert_eq!(s["photons_per_pass"], 250_000, "{s}");
    assert_eq!(s["spp"], 10, "{s}");
    assert_eq!(s["sampler"], "stratified", "{s}");
    assert_eq!(s["cache_bins"], 1, "{s}");
    assert_eq!(s["radius_given"], false, "{s}");
    let px = s["radius_px"].as_f64().expect("radius_px");
    assert!((px - 0.5).abs() < 1e-5, "{s}");
}

#[test]
fn warnings_reach_stdout_and_the_report() {
    let dir = TempDir::new("warnings");
    let render = |name: &str, scene_text: String, extra: &[&str]| {
        let path = dir.path(&format!("{name}.toml"));
        std::fs::write(&path, scene_text).expect("write scene");
        let out = run(bdpm()
            .arg("render")
            .arg(&path)
            .args(extra)
            .args(["--quiet", "-o"])
            .arg(dir.path(&format!("{name}.exr"))));
        assert_success(&out);
        let json = read_json(&dir.path(&format!("{name}.json")));
        (text(&out.stdout), json)
    };
    // The plain scene: no warning, radius left to the default.
    let (stdout, json) = render("plain", BASE_SCENE.into(), &[]);
    assert!(!stdout.contains("warning:"), "{stdout}");
    assert_eq!(json["warnings"].as_array().map(Vec::len), Some(0));
    assert_eq!(json["settings"]["radius_given"], false);
    // A merge radius of a quarter of the scene.
    let (stdout, json) = render(
        "wide",
        BASE_SCENE.into(),
        &["--mode", "balance", "--radius", "0.5"],
    );
    assert!(
        stdout.contains("warning: the merge radius 0.5 m is 25%"),
        "{stdout}"
    );
    assert_eq!(json["settings"]["radius_given"], true);
    let w = json["warnings"][0].as_str().expect("warning");
    assert!(w.contains("merge radius"), "{w}");
    // A radius in pixel footprints: resolved against the camera, reported in both units, and
    // twice the pixels give twice the metres.
    let (_, one) = render("px1", BASE_SCENE.into(), &["--radius", "0.5px"]);
    let (_, two) = render("px2", BASE_SCENE.into(), &["--radius", "1px"]);
    let px = |j: &serde_json::Value| j["settings"]["radius_px"].as_f64().expect("radius_px");
    let m = |j: &serde_json::Value| j["settings"]["radius_m"].as_f64().expect("radius_m");
    assert!((px(&one) - 0.5).abs() < 1e-5, "{}", one["settings"]);
    assert!(
        (m(&two) / m(&one) - 2.0).abs() < 1e-5,
        "{} {}",
        m(&one),
        m(&two)
    );
    assert_eq!(one["settings"]["radius_given"], true);
    // A glTF file with a triangle, a point primitive and a camera: the skips are reported.
    let mut tri = Vec::new();
    for c in [0.9f32, -0.1, -0.1, 0.9, 0.1, -0.1, 0.9, 0.0, 0.1] {
        tri.extend_from_slice(&c.to_le_bytes());
    }
    std::fs::write(dir.path("tri.bin"), tri).expect("write bin");
    let gltf = r#"{ "asset": { "version": "2.0" },
      "buffers": [ { "byteLength": 36, "uri": "tri.bin" } ],
      "bufferViews": [ { "buffer": 0, "byteLength": 36 } ],
      "accessors": [ { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0.9, -0.1, -0.1], "max": [0.9, 0.1, 0.1] } ],
      "cameras": [ { "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1 } } ],
      "meshes": [ { "primitives": [ { "attributes": { "POSITION": 0 } },
                                    { "attributes": { "POSITION": 0 }, "mode": 0 } ] } ],
      "nodes": [ { "mesh": 0 }, { "camera": 0 } ],
      "scenes": [ { "nodes": [0, 1] } ] }"#;
    std::fs::write(dir.path("tri.gltf"), gltf).expect("write gltf");
    let with_gltf = format!("{BASE_SCENE}\n[[shape]]\ntype = \"mesh\"\nfile = \"tri.gltf\"\n");
    let (stdout, json) = render("gltf", with_gltf, &[]);
    assert!(
        stdout.contains("warning: glTF: 1 point or line primitive(s) skipped"),
        "{stdout}"
    );
    assert!(
        stdout.contains("warning: glTF: 1 camera(s) ignored"),
        "{stdout}"
    );
    assert_eq!(json["scene"]["gltf"]["skipped_points_and_lines"], 1);
    assert_eq!(json["scene"]["gltf"]["skipped_cameras"], 1);
    assert_eq!(json["warnings"].as_array().map(Vec::len), Some(2));
    // The light sealed in a small closed sphere: a black image.
    let sealed = format!(
        "{BASE_SCENE}\n[[shape]]\ntype = \"sphere\"\ncenter = [0.3, -0.2, 0.1]\nradius = 0.01\nmaterial = \"inside\"\n"
    );
    let (stdout, json) = render("sealed", sealed, &[]);
    assert!(stdout.contains("warning: the image is black"), "{stdout}");
    assert!(
        json["warnings"][0]
            .as_str()
            .is_some_and(|w| w.contains("black")),
        "{json}"
    );
}

#[test]
fn memory_is_estimated_before_the_render_and_refused_above_the_limit() {
    let dir = TempDir::new("memory");
    // (arguments, what the error must name). 10⁹ photons need some 250 GB: refused at
    // once, as is a film beyond a tiny limit; either would otherwise abort mid-render.
    let cases: [(&[&str], &str); 4] = [
        (
            &[
                "--mode",
                "bdd0",
                "--photons",
                "1000000000",
                "--max-memory",
                "4G",
            ],
            "--photons",
        ),
        (
            &[
                "--mode",
                "path",
                "--resolution",
                "512x512",
                "--max-memory",
                "20M",
            ],
            "--resolution",
        ),
        // Light tracing holds a pass's splats as well as its photon map.
        (
            &[
                "--mode",
                "balance",
                "--light-tracing",
                "true",
                "--photons",
                "1000000000",
                "--max-memory",
                "4G",
            ],
            "light-tracing splats per pass",
        ),
        // The adaptive radius's pilot holds its technique sums and a second pixel table.
        (
            &[
                "--mode",
                "optimal-path",
                "--adaptive-radius",
                "true",
                "--resolution",
                "4096x4096",
                "--max-memory",
                "1G",
            ],
            "adaptive-radius pilot",
        ),
    ];
    for (args, knob) in cases {
        let start = Instant::now();
        let out = run(bdpm()
            .arg("render")
            .arg(scene("preprint/cornell-lambert.toml"))
            .args(args)
            .args(["--quiet", "-o"])
            .arg(dir.path("m.exr")));
        assert_one_line_error(&out, &["needs about", "--max-memory", knob]);
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "{:?}",
            start.elapsed()
        );
        assert!(!dir.path("m.exr").exists());
    }
    // Within the limit, the estimate and the measured peak are in the report.
    let out = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--mode", "bdd0", "--resolution", "16x16", "--passes", "1"])
        .args([
            "--photons",
            "100000",
            "--max-memory",
            "4G",
            "--stage-memory",
            "--quiet",
            "-o",
        ])
        .arg(dir.path("m.exr")));
    assert_success(&out);
    let json = read_json(&dir.path("m.json"));
    let memory = &json["memory"];
    assert_eq!(memory["limit_source"], "--max-memory");
    assert_eq!(memory["limit_bytes"].as_u64(), Some(4 << 30));
    let estimate = memory["estimate_bytes"].as_u64().expect("estimate");
    let names: Vec<&str> = memory["items"]
        .as_array()
        .expect("items")
        .iter()
        .filter_map(|i| i["name"].as_str())
        .collect();
    assert!(names.contains(&"photon map per pass"), "{names:?}");
    if let Some(peak) = memory["measured_peak_bytes"].as_u64() {
        eprintln!("estimate {estimate} B, measured peak {peak} B");
        assert!(
            estimate >= peak / 2,
            "estimate {estimate} far below the peak {peak}"
        );
        // Where the kernel's high-water mark can be reset (Linux), every stage has its own
        // peak, none above the run's.
        let stages = memory["stage_peaks"].as_array().expect("stage_peaks");
        if !stages.is_empty() {
            let names: Vec<&str> = stages.iter().filter_map(|s| s["stage"].as_str()).collect();
            assert_eq!(names, ["prepare", "photons", "camera"]);
            for s in stages {
                let p = s["peak_bytes"].as_u64().expect("peak_bytes");
                assert!(p > 0 && p <= peak, "{s} against the run's peak {peak}");
            }
        }
    }
}

/// A small Cornell render for the partial-render tests: 16×16, few photons, one sample.
fn small_render(out: &Path, extra: &[&str]) -> Output {
    let out = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(TINY)
        .args(["--mode", "optimal", "--quiet"])
        .args(extra)
        .arg("-o")
        .arg(out));
    assert_success(&out);
    out
}

fn merge(parts: &[PathBuf], out: &Path) -> Output {
    run(bdpm()
        .arg("merge")
        .args(parts)
        .args(["--quiet", "-o"])
        .arg(out))
}

/// The report fields that must be bit-identical between two renders of the same passes (the
/// JSON prints f64 so that it reads back exactly), and the EXR's mean, noise and stderr bits.
fn assert_same_bits(a: &Path, b: &Path) {
    let (ja, jb) = (
        read_json(&a.with_extension("json")),
        read_json(&b.with_extension("json")),
    );
    for key in [
        "passes_done",
        "mean_radiance",
        "mean_radiance_standard_error",
        "mean_noise_sqrt_v",
        "pass_image_means",
        "dropped_samples",
        "camera_samples",
    ] {
        assert_eq!(
            ja[key],
            jb[key],
            "{key}: {} vs {}",
            a.display(),
            b.display()
        );
    }
    assert_eq!(ja["plan"]["passes_held"], jb["plan"]["passes_held"]);
    let (ea, eb) = (Exr::read(a), Exr::read(b));
    for prefix in ["", "noise", "stderr"] {
        for c in rgb(prefix) {
            let bits = |e: &Exr| {
                e.channel(&c)
                    .iter()
                    .map(|v| v.to_bits())
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&ea), bits(&eb), "channel {c}");
        }
    }
    for f in [a, b] {
        let out = run(bdpm()
            .arg("compare")
            .arg("--require-identical")
            .arg(a)
            .arg(f));
        assert_success(&out);
    }
}

#[test]
fn partial_renders_merged_in_any_order_equal_one_render() {
    let dir = TempDir::new("merge");
    let full = dir.path("full.exr");
    small_render(&full, &["--passes", "10"]);
    let mut parts = Vec::new();
    for (first, n) in [(0, 4), (4, 2), (6, 4)] {
        let out = dir.path(&format!("part{first}.exr"));
        small_render(
            &out,
            &[
                "--first-pass",
                &first.to_string(),
                "--passes",
                &n.to_string(),
            ],
        );
        parts.push(dir.path(&format!("part{first}.accum.exr")));
    }
    for (i, order) in [[2, 0, 1], [1, 2, 0]].iter().enumerate() {
        let shuffled: Vec<PathBuf> = order.iter().map(|&k| parts[k].clone()).collect();
        let merged = dir.path(&format!("merged{i}.exr"));
        let out = merge(&shuffled, &merged);
        assert_success(&out);
        assert_same_bits(&full, &merged);
        let json = read_json(&merged.with_extension("json"));
        assert_eq!(json["plan"]["passes_held"], "0-9");
        assert_eq!(json["plan"]["passes_replayed"], 10);
        assert!(dir.path(&format!("merged{i}.accum.exr")).is_file());
    }
    // A merged accumulation file merges again: (0-3 + 4-5) + 6-9.
    let ab = dir.path("ab.exr");
    assert_success(&merge(&parts[..2], &ab));
    let again = dir.path("again.exr");
    assert_success(&merge(
        &[parts[2].clone(), dir.path("ab.accum.exr")],
        &again,
    ));
    assert_same_bits(&full, &again);
    assert!(dir.hidden_files().is_empty(), "{:?}", dir.hidden_files());
}

#[test]
fn overlapping_or_mismatched_parts_are_refused() {
    let dir = TempDir::new("merge-bad");
    small_render(&dir.path("a.exr"), &["--first-pass", "0", "--passes", "3"]);
    small_render(&dir.path("b.exr"), &["--first-pass", "2", "--passes", "2"]);
    small_render(
        &dir.path("s.exr"),
        &["--first-pass", "3", "--passes", "1", "--seed", "9"],
    );
    small_render(
        &dir.path("m.exr"),
        &["--first-pass", "3", "--passes", "1", "--no-jitter"],
    );
    let (a, b) = (dir.path("a.accum.exr"), dir.path("b.accum.exr"));
    let out = merge(&[a.clone(), b.clone()], &dir.path("x.exr"));
    assert_one_line_error(&out, &["b.accum.exr", "passes 2", "a.accum.exr"]);
    let out = merge(&[a.clone(), dir.path("s.accum.exr")], &dir.path("x.exr"));
    assert_one_line_error(&out, &["s.accum.exr", "seed"]);
    let out = merge(&[dir.path("m.accum.exr"), a.clone()], &dir.path("x.exr"));
    assert_one_line_error(&out, &["m.accum.exr", "settings"]);
    // A plain render's EXR is not an accumulation file.
    let out = merge(&[a.clone(), dir.path("b.exr")], &dir.path("x.exr"));
    assert_one_line_error(&out, &["b.exr", "not a bdpm accumulation file"]);
    // Resuming with other settings is refused the same way.
    let out = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--resolution", "16x16", "--photons", "3000", "--spp", "1"])
        .args(["--mode", "optimal", "--quiet", "--passes", "1", "--resume"])
        .arg(&a)
        .arg("-o")
        .arg(dir.path("r.exr")));
    assert_one_line_error(&out, &["a.accum.exr", "settings"]);
    assert!(!dir.path("x.exr").exists() && !dir.path("r.exr").exists());
}

#[test]
fn resumed_render_equals_an_uninterrupted_one() {
    let dir = TempDir::new("resume");
    let full = dir.path("full.exr");
    small_render(&full, &["--passes", "5"]);
    small_render(&dir.path("r.exr"), &["--passes", "2", "--accumulate"]);
    // Resume in place: the file read is replaced by the one written.
    let resumed = dir.path("r.exr");
    small_render(
        &resumed,
        &[
            "--passes",
            "3",
            "--resume",
            dir.path("r.accum.exr").to_str().unwrap(),
        ],
    );
    assert_same_bits(&full, &resumed);
    let json = read_json(&resumed.with_extension("json"));
    assert_eq!(json["plan"]["first_pass_rendered"], 2);
    assert_eq!(json["plan"]["passes_replayed"], 2);
}

#[test]
fn interrupted_render_resumes_after_the_passes_it_holds() {
    let dir = TempDir::new("resume-int");
    for wait in [1.5, 6.0] {
        let (code, _) = interrupted_render(
            wait,
            &TINY,
            &[
                "--mode",
                "optimal",
                "--threads",
                "1",
                "--passes",
                "100000",
                "--accumulate",
            ],
            &dir.path("i.exr"),
        );
        assert_eq!(code, Some(130));
        if !dir.path("i.accum.exr").is_file() {
            continue;
        }
        let done = read_json(&dir.path("i.json"))["passes_done"]
            .as_u64()
            .expect("passes_done");
        assert!(done >= 1);
        let accum = dir.path("i.accum.exr");
        small_render(
            &dir.path("i2.exr"),
            &["--passes", "2", "--resume", accum.to_str().unwrap()],
        );
        let json = read_json(&dir.path("i2.json"));
        assert_eq!(json["plan"]["first_pass_rendered"], done);
        let full = dir.path("full.exr");
        small_render(&full, &["--passes", &(done + 2).to_string()]);
        assert_same_bits(&full, &dir.path("i2.exr"));
        return;
    }
    panic!("the render did not finish a pass within 6 s");
}

#[test]
fn budgets_stop_after_the_pass_that_crosses_them() {
    let dir = TempDir::new("budget");
    // Any pass takes longer than a microsecond: the first one crosses the budget.
    let t = dir.path("t.exr");
    small_render(&t, &["--passes", "50", "--time-budget", "0.000001"]);
    let json = read_json(&t.with_extension("json"));
    assert_eq!(json["passes_done"], 1);
    assert_eq!(json["plan"]["stop_reason"], "time_budget");
    assert_eq!(json["plan"]["time_budget_seconds"], 0.000001);

    let x = 0.5;
    let n = dir.path("n.exr");
    small_render(&n, &["--passes", "200", "--target-noise", &x.to_string()]);
    let json = read_json(&n.with_extension("json"));
    assert_eq!(json["plan"]["stop_reason"], "target_noise");
    let done = json["passes_done"].as_u64().expect("passes_done");
    let reached = json["plan"]["mean_relative_standard_error"]
        .as_f64()
        .expect("mean_relative_standard_error");
    assert!(
        reached < x && (2..200).contains(&done),
        "{reached} after {done}"
    );
    // One pass fewer had not reached it.
    let before = dir.path("before.exr");
    small_render(&before, &["--passes", &(done - 1).to_string()]);
    let prior =
        read_json(&before.with_extension("json"))["plan"]["mean_relative_standard_error"].as_f64();
    assert!(
        prior.is_none_or(|p| p >= x),
        "{prior:?} after {} passes",
        done - 1
    );
}

/// Renders cornell-lambert at 24×24 with `extra` flags into `dir/name`.
fn render_small(dir: &TempDir, name: &str, extra: &[&str]) -> Exr {
    let out = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--resolution", "24x24", "--passes", "1", "--spp", "2"])
        .args(["--photons", "5000", "--quiet"])
        .args(extra)
        .arg("-o")
        .arg(dir.path(name)));
    assert_success(&out);
    Exr::read(&dir.path(name))
}

#[test]
fn aov_layers_hold_first_hit_albedo_and_normal_without_changing_the_image() {
    let dir = TempDir::new("aov");
    let plain = render_small(&dir, "plain.exr", &[]);
    let with = render_small(&dir, "aov.exr", &["--aov"]);
    for c in rgb("") {
        let (a, b) = (plain.channel(&c), with.channel(&c));
        assert!(
            a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()),
            "{c}: --aov changed the image bits"
        );
    }
    assert!(plain.channels.keys().all(|k| !k.starts_with("albedo")));
    let albedo = rgb("albedo").map(|c| with.channel(&c).to_vec());
    let normal = ["X", "Y", "Z"].map(|c| with.channel(&format!("normal.{c}")).to_vec());
    let pixels = with.width * with.height;
    let mut seen = 0;
    for i in 0..pixels {
        for a in &albedo {
            assert!((0.0..=1.0).contains(&a[i]), "albedo {} at pixel {i}", a[i]);
        }
        let len = (normal.iter().map(|n| (n[i] as f64).powi(2)).sum::<f64>()).sqrt();
        if albedo.iter().any(|a| a[i] > 0.0) {
            seen += 1;
            assert!((len - 1.0).abs() < 1e-5, "normal length {len} at pixel {i}");
        } else {
            assert!(
                len == 0.0 || (len - 1.0).abs() < 1e-5,
                "normal length {len}"
            );
        }
    }
    assert!(seen > pixels / 2, "{seen} of {pixels} pixels see a surface");
    // The floor (y = 0) in front of the blocks: its normal is +y.
    let (x, y) = cornell_pixel([2.2, 0.0, 0.5], with.width);
    let i = y as usize * with.width + x as usize;
    let n = [normal[0][i], normal[1][i], normal[2][i]];
    assert!(n[1] > 0.99, "floor normal {n:?} at ({x}, {y})");
    assert!(albedo[0][i] > 0.1, "floor albedo {}", albedo[0][i]);
}

#[test]
fn half_precision_exr_is_readable_and_close_to_float() {
    let dir = TempDir::new("half");
    let float = render_small(&dir, "f.exr", &["--aov"]);
    let half = render_small(&dir, "h.exr", &["--aov", "--exr-precision", "half"]);
    assert!(float.halves.is_empty());
    for name in float.channels.keys() {
        assert!(half.halves.contains(name), "{name} is not half");
        let (f, h) = (float.channel(name), half.channel(name));
        for (a, b) in f.iter().zip(h) {
            assert!(
                (a - b).abs() <= 1e-3 * a.abs() + 1e-6,
                "{name}: float {a} vs half {b}"
            );
        }
    }
    let same_layers = {
        let mut a: Vec<_> = float.channels.keys().collect();
        let mut b: Vec<_> = half.channels.keys().collect();
        a.sort();
        b.sort();
        a == b
    };
    assert!(same_layers);
}

#[test]
fn bad_exr_precision_is_refused() {
    let dir = TempDir::new("precision-bad");
    let out = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--resolution", "8x8", "--exr-precision", "double", "-o"])
        .arg(dir.path("p.exr")));
    assert_one_line_error(&out, &["--exr-precision", "double"]);
    assert!(!dir.path("p.exr").exists());
}

/// Runs `cmd` with its standard output and/or error a pipe whose reader has already gone
/// (as `bdpm … | true` or a closed terminal): every write to it fails with EPIPE. Returns
/// the exit code and what reached the stream left open.
fn run_with_closed(
    cmd: &mut Command,
    close_stdout: bool,
    close_stderr: bool,
) -> (Option<i32>, String) {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start bdpm");
    if close_stdout {
        drop(child.stdout.take());
    }
    if close_stderr {
        drop(child.stderr.take());
    }
    let out = child.wait_with_output().expect("wait");
    let open = if close_stdout {
        &out.stderr
    } else {
        &out.stdout
    };
    (out.status.code(), text(open))
}

/// A closed standard output or error drops the messages and never panics (exit code 101):
/// an error still exits with 1, a report printed by the lab with 0, and the interrupt
/// handler, whose message also fails, still quits on a second interrupt.
#[test]
fn closed_standard_streams_never_panic() {
    let dir = TempDir::new("closed");
    let (code, _) = run_with_closed(bdpm().args(["render", "missing.toml"]), true, true);
    assert_eq!(code, Some(1));
    let (code, stderr) = run_with_closed(
        bdpm()
            .arg("bench")
            .arg(scene("preprint/cornell-lambert.toml"))
            .args(["--modes", "path", "--resolution", "8x8", "--photons", "500"])
            .args(["--spp", "1", "--passes", "1", "--repeats", "1"])
            .args(["--threads-list", "1", "-o"])
            .arg(dir.path("b.md")),
        true,
        false,
    );
    assert_eq!(code, Some(0), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(dir.path("b.md").is_file());
    let (code, _) = run_with_closed(
        bdpm()
            .arg("render")
            .arg(scene("preprint/cornell-lambert.toml"))
            .args([
                "--resolution",
                "8x8",
                "--passes",
                "1",
                "--mode",
                "path",
                "-o",
            ])
            .arg(dir.path("r.exr")),
        true,
        true,
    );
    assert_eq!(code, Some(0));
    assert!(dir.path("r.exr").is_file());
    // Two interrupts during a long pass: the handler's message goes nowhere, and the second
    // one quits at once without writing.
    let out = dir.path("long.exr");
    let mut child = bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--resolution", "64x64", "--spp", "100000", "--passes", "2"])
        .args(["--mode", "path", "--threads", "1", "--quiet", "-o"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start bdpm");
    drop(child.stderr.take());
    let start = Instant::now();
    while !dir.path(".long.exr.lock").exists() {
        assert!(start.elapsed() < Duration::from_secs(30), "no lock file");
        std::thread::sleep(Duration::from_millis(20));
    }
    let kill = |c: &std::process::Child| {
        let status = Command::new("kill")
            .args(["-INT", &c.id().to_string()])
            .status()
            .expect("run kill");
        assert!(status.success());
    };
    kill(&child);
    std::thread::sleep(Duration::from_millis(300));
    let code = interrupt(&mut child);
    assert_eq!(code, Some(130));
    assert!(!out.exists(), "the second interrupt wrote the outputs");
}

/// An output set never replaces a file the command reads or a member of another render's
/// set, and every member's name (the accumulation file and the longest temporary name
/// included) is checked before any work.
#[test]
fn output_sets_refuse_inputs_other_sets_and_bad_members_before_any_work() {
    let dir = TempDir::new("sets");
    let flags = ["--mode", "optimal", "--passes", "2"];
    small_render(&dir.path("a.exr"), &["--passes", "2", "--accumulate"]);
    let files = ["a.exr", "a.png", "a-noise.png", "a.json", "a.accum.exr"];
    let before: Vec<Vec<u8>> = files
        .iter()
        .map(|f| std::fs::read(dir.path(f)).expect("read"))
        .collect();
    let render_to = |name: &str, extra: &[&str]| {
        run(bdpm()
            .arg("render")
            .arg(scene("preprint/cornell-lambert.toml"))
            .args(TINY)
            .args(flags)
            .args(extra)
            .args(["--quiet", "-o"])
            .arg(dir.path(name)))
    };
    assert_one_line_error(
        &render_to("a.accum.exr", &[]),
        &["a.accum.exr", "accumulation"],
    );
    assert_one_line_error(
        &render_to("a-noise.exr", &[]),
        &["a-noise.png", "noise map"],
    );
    std::fs::write(dir.path("b-noise.exr"), b"another render").expect("write");
    assert_one_line_error(&render_to("b.exr", &[]), &["b-noise.png", "b-noise.exr"]);
    let accum = dir.path("a.accum.exr");
    assert_one_line_error(
        &merge(std::slice::from_ref(&accum), &accum),
        &["a.accum.exr", "accumulation"],
    );
    let out = run(bdpm()
        .arg("predict")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(TINY)
        .args(["--mode", "optimal"])
        .arg("--measured")
        .arg(dir.path("a.exr"))
        .arg("-o")
        .arg(dir.path("a.exr")));
    assert_one_line_error(&out, &["a.exr", "reads"]);
    for (f, old) in files.iter().zip(&before) {
        assert_eq!(
            &std::fs::read(dir.path(f)).expect("read"),
            old,
            "{f} changed"
        );
    }
    // A merge into one of its parts (the parts' accumulation file replaced by one holding all
    // of its passes) stays allowed, as resuming in place does.
    assert_success(&merge(std::slice::from_ref(&accum), &dir.path("a.exr")));

    // A directory at the accumulation file's name, and a stem whose noise map's temporary
    // name is too long for the file system (the EXR's fits): refused before the 10⁵ passes.
    std::fs::create_dir_all(dir.path("c.accum.exr")).expect("mkdir");
    let long = "n".repeat(228);
    for (name, extra, needle) in [
        ("c.exr", &["--accumulate"][..], "c.accum.exr"),
        (&format!("{long}.exr") as &str, &[][..], "-noise.png"),
    ] {
        let start = Instant::now();
        let out = run(bdpm()
            .arg("render")
            .arg(scene("preprint/cornell-lambert.toml"))
            .args(["--resolution", "64x64", "--passes", "100000", "--quiet"])
            .args(extra)
            .arg("-o")
            .arg(dir.path(name)));
        assert_one_line_error(&out, &[needle]);
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "{:?}",
            start.elapsed()
        );
    }
    assert!(!dir.path("c.png").exists() && !dir.path(&format!("{long}.exr")).exists());
    assert!(dir.hidden_files().is_empty(), "{:?}", dir.hidden_files());
}

/// Rewrites the accumulation file `from` to `to` after `change` edits its channels.
fn edit_accumulation(
    from: &Path,
    to: &Path,
    change: impl FnOnce(&mut Vec<exr::prelude::AnyChannel<exr::prelude::FlatSamples>>),
) {
    use exr::prelude::WritableImage as _;
    let mut image = exr::prelude::read_all_flat_layers_from_file(from).expect("read accum");
    let mut list = image.layer_data[0].channel_data.list.to_vec();
    change(&mut list);
    list.sort_by(|a, b| a.name.cmp(&b.name));
    image.layer_data[0].channel_data.list = list.into_iter().collect();
    image.write().to_file(to).expect("write edited accum");
}

/// The accumulation reader takes u32 channels only, exactly six per pass, and finite
/// estimates: a file re-saved as float, with a NaN, or with a stray channel is refused with
/// one line naming what is wrong (the pass and the pixel for a bad value).
#[test]
fn damaged_accumulation_files_are_refused() {
    use exr::prelude::{AnyChannel, FlatSamples, f16};
    let dir = TempDir::new("accum-read");
    small_render(&dir.path("p.exr"), &["--passes", "2", "--accumulate"]);
    let good = dir.path("p.accum.exr");
    type Edit = Box<dyn FnOnce(&mut Vec<AnyChannel<FlatSamples>>)>;
    let find = |list: &mut Vec<AnyChannel<FlatSamples>>, name: &str| {
        list.iter()
            .position(|c| c.name.to_string() == name)
            .expect("channel")
    };
    let cases: Vec<(&str, Edit, Vec<&str>)> = vec![
        (
            "float",
            Box::new(move |l| {
                let i = find(l, "p000000.G.lo");
                if let FlatSamples::U32(v) = &l[i].sample_data {
                    l[i].sample_data = FlatSamples::F32(v.iter().map(|x| *x as f32).collect());
                }
            }),
            vec!["p000000.G.lo", "floating-point"],
        ),
        (
            "half",
            Box::new(move |l| {
                let i = find(l, "p000001.R.hi");
                if let FlatSamples::U32(v) = &l[i].sample_data {
                    l[i].sample_data =
                        FlatSamples::F16(v.iter().map(|x| f16::from_f32(*x as f32)).collect());
                }
            }),
            vec!["p000001.R.hi", "floating-point"],
        ),
        (
            "nan",
            Box::new(move |l| {
                // Pixel (3, 2) of pass 1, red: the high word of a quiet NaN.
                let i = find(l, "p000001.R.hi");
                if let FlatSamples::U32(v) = &mut l[i].sample_data {
                    v[2 * 16 + 3] = 0x7ff8_0000;
                }
            }),
            vec!["pass 1", "pixel (3, 2)", "non-finite"],
        ),
        (
            "extra",
            Box::new(|l| {
                let n = l[0].sample_data.len();
                l.push(AnyChannel::new("zzz", FlatSamples::U32(vec![0; n])));
            }),
            vec!["13 channels", "2 passes"],
        ),
    ];
    for (tag, edit, needles) in cases {
        let bad = dir.path(&format!("{tag}.accum.exr"));
        edit_accumulation(&good, &bad, edit);
        let out = merge(
            std::slice::from_ref(&bad),
            &dir.path(&format!("m-{tag}.exr")),
        );
        let mut all = vec![bad.file_name().unwrap().to_str().unwrap()];
        all.extend(needles);
        assert_one_line_error(&out, &all);
        assert!(!dir.path(&format!("m-{tag}.exr")).exists(), "{tag}");
    }
}

/// `predict` reads the passes the render did (not the ones asked for) and, like `study
/// --reference`, refuses a render of another scene, told by the scene hash in its header.
#[test]
fn predict_and_study_check_passes_done_and_the_scene() {
    let dir = TempDir::new("predict-scene");
    let settings = [
        "--mode",
        "optimal",
        "--resolution",
        "16x16",
        "--photons",
        "2000",
        "--spp",
        "1",
        "--radius",
        "0.02",
    ];
    let render = |scene_file: &str, out: &str, extra: &[&str]| {
        let o = run(bdpm()
            .arg("render")
            .arg(scene(scene_file))
            .args(settings)
            .args(extra)
            .args(["--quiet", "-o"])
            .arg(dir.path(out)));
        assert_success(&o);
    };
    let predict = |measured: &str| {
        run(bdpm()
            .arg("predict")
            .arg(scene("preprint/cornell-lambert.toml"))
            .args(settings)
            .arg("--measured")
            .arg(dir.path(measured))
            .arg("-o")
            .arg(dir.path("p.exr")))
    };
    // Stopped by its budget after one pass of 1000: V was not measured.
    render(
        "preprint/cornell-lambert.toml",
        "budget.exr",
        &["--passes", "1000", "--time-budget", "1e-9"],
    );
    assert_one_line_error(&predict("budget.exr"), &["budget.exr", "1 pass done"]);
    // Three passes: the report says 3, not the scene file's pass count.
    render(
        "preprint/cornell-lambert.toml",
        "three.exr",
        &["--passes", "3"],
    );
    assert_success(&predict("three.exr"));
    assert_eq!(read_json(&dir.path("p.json"))["passes"], 3);
    // Without the scene hash or the estimator hash (an older bdpm's render): not checkable.
    for (key, needle) in [
        ("bdpm.scene_hash", "no bdpm.scene_hash"),
        ("bdpm.estimator_hash", "estimator hash missing"),
    ] {
        use exr::prelude::WritableImage as _;
        let mut image = exr::prelude::read_all_flat_layers_from_file(dir.path("three.exr"))
            .expect("read render");
        let attrs = &mut image.layer_data[0].attributes.other;
        assert!(
            attrs.remove(&exr::prelude::Text::from(key)).is_some(),
            "{key}"
        );
        image
            .write()
            .to_file(dir.path("stripped.exr"))
            .expect("write stripped render");
        assert_one_line_error(&predict("stripped.exr"), &["stripped.exr", needle]);
    }
    // The glossy box with the same settings: another scene.
    render(
        "preprint/cornell-glossy.toml",
        "glossy.exr",
        &["--passes", "3"],
    );
    assert_one_line_error(&predict("glossy.exr"), &["glossy.exr", "another scene"]);
    let out = run(bdpm()
        .arg("study")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args([
            "--modes",
            "optimal",
            "--passes",
            "2",
            "--resolution",
            "16x16",
        ])
        .args(["--photons", "2000", "--spp", "1", "--quiet", "--reference"])
        .arg(dir.path("glossy.exr"))
        .arg("-o")
        .arg(dir.path("study")));
    assert_one_line_error(&out, &["glossy.exr", "another scene"]);
}

/// A merge (and a resume) refuses parts rendered while a mesh the scene references was
/// different: the scene file alone is unchanged, the glTF buffer is not.
#[test]
fn merge_refuses_parts_of_a_changed_mesh() {
    let dir = TempDir::new("mesh-change");
    let vertices = |order: [usize; 3]| {
        let v = [[0.9f32, -0.1, -0.1], [0.9, 0.1, -0.1], [0.9, 0.0, 0.1]];
        order
            .iter()
            .flat_map(|&i| v[i].iter().flat_map(|c| c.to_le_bytes()))
            .collect::<Vec<u8>>()
    };
    std::fs::write(dir.path("tri.bin"), vertices([0, 1, 2])).expect("write bin");
    let gltf = r#"{ "asset": { "version": "2.0" },
      "buffers": [ { "byteLength": 36, "uri": "tri.bin" } ],
      "bufferViews": [ { "buffer": 0, "byteLength": 36 } ],
      "accessors": [ { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0.9, -0.1, -0.1], "max": [0.9, 0.1, 0.1] } ],
      "meshes": [ { "primitives": [ { "attributes": { "POSITION": 0 } } ] } ],
      "nodes": [ { "mesh": 0 } ], "scenes": [ { "nodes": [0] } ] }"#;
    std::fs::write(dir.path("tri.gltf"), gltf).expect("write gltf");
    let toml = dir.path("s.toml");
    std::fs::write(
        &toml,
        format!("{BASE_SCENE}\n[[shape]]\ntype = \"mesh\"\nfile = \"tri.gltf\"\n"),
    )
    .expect("write scene");
    let part = |k: &str, out: &str| {
        let o = run(bdpm()
            .arg("render")
            .arg(&toml)
            .args(["--first-pass", k, "--passes", "1", "--quiet", "-o"])
            .arg(dir.path(out)));
        assert_success(&o);
        Exr::read(&dir.path(out)).attributes["bdpm.scene_hash"].clone()
    };
    let h0 = part("0", "p0.exr");
    // The same triangle, its vertices in another order: another mesh.
    std::fs::write(dir.path("tri.bin"), vertices([0, 2, 1])).expect("write bin");
    let h1 = part("1", "p1.exr");
    assert_ne!(h0, h1, "the scene hash ignores the glTF buffer");
    let out = merge(
        &[dir.path("p0.accum.exr"), dir.path("p1.accum.exr")],
        &dir.path("m.exr"),
    );
    assert_one_line_error(&out, &["p1.accum.exr", "mesh, buffer or image"]);
    assert!(!dir.path("m.exr").exists());
    let out = run(bdpm()
        .arg("render")
        .arg(&toml)
        .args(["--passes", "1", "--quiet", "--resume"])
        .arg(dir.path("p0.accum.exr"))
        .arg("-o")
        .arg(dir.path("r.exr")));
    assert_one_line_error(&out, &["p0.accum.exr", "mesh, buffer or image"]);
}

/// The passes a resume or a merge holds are in the memory estimate (48 bytes per pixel per
/// pass), so a limit that a plain render of the same settings fits is refused when the
/// held passes do not fit; `merge` takes `--max-memory`.
#[test]
fn held_passes_count_in_the_memory_estimate() {
    let dir = TempDir::new("held-memory");
    let flags = [
        "--mode",
        "path",
        "--resolution",
        "64x64",
        "--spp",
        "1",
        "--quiet",
    ];
    let render = |extra: &[&str], out: &str| {
        run(bdpm()
            .arg("render")
            .arg(scene("preprint/cornell-lambert.toml"))
            .args(flags)
            .args(extra)
            .arg("-o")
            .arg(dir.path(out)))
    };
    assert_success(&render(&["--passes", "40", "--accumulate"], "h.exr"));
    assert_success(&render(&["--passes", "1"], "plain.exr"));
    let plain = read_json(&dir.path("plain.json"))["memory"]["estimate_bytes"]
        .as_u64()
        .expect("estimate");
    // 40 held passes + 1 rendered: 41 × 4096 pixels × 48 B ≈ 8.1 MB, over a 4 MB margin.
    let limit = (plain + (4 << 20)).to_string();
    let accum = dir.path("h.accum.exr");
    let out = render(
        &[
            "--passes",
            "1",
            "--resume",
            accum.to_str().unwrap(),
            "--max-memory",
            &limit,
        ],
        "r.exr",
    );
    assert_one_line_error(
        &out,
        &["passes kept for the accumulation file", "--max-memory"],
    );
    assert!(!dir.path("r.exr").exists());
    let out = run(bdpm()
        .arg("merge")
        .arg(&accum)
        .args(["--quiet", "--max-memory", &limit, "-o"])
        .arg(dir.path("m.exr")));
    assert_one_line_error(
        &out,
        &["passes kept for the accumulation file", "merge fewer parts"],
    );
    // Below what the passes alone need (7.9 MB): refused from the header, before reading.
    let out = run(bdpm()
        .arg("merge")
        .arg(&accum)
        .args(["--quiet", "--max-memory", "4M", "-o"])
        .arg(dir.path("m.exr")));
    assert_one_line_error(
        &out,
        &["h.accum.exr", "passes to read", "merge fewer parts"],
    );
    let out = run(bdpm()
        .arg("merge")
        .arg(&accum)
        .args(["--quiet", "--max-memory", "4G", "-o"])
        .arg(dir.path("m.exr")));
    assert_success(&out);
    let items = read_json(&dir.path("m.json"))["memory"]["items"].clone();
    let kept = items
        .as_array()
        .expect("items")
        .iter()
        .find(|i| i["name"] == "passes kept for the accumulation file")
        .and_then(|i| i["bytes"].as_u64());
    assert_eq!(kept, Some(40 * 64 * 64 * 48));
}

/// An interrupt during a merge either stops it with nothing written (exit 130) or, once the
/// files are being written, lets it complete as a merge that was not interrupted (exit 0,
/// `interrupted: false`): never a complete merge reported as interrupted.
#[test]
fn an_interrupted_merge_reports_what_it_did() {
    let dir = TempDir::new("merge-int");
    let flags = [
        "--mode",
        "path",
        "--resolution",
        "64x64",
        "--spp",
        "1",
        "--quiet",
    ];
    let o = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(flags)
        .args(["--passes", "200", "--accumulate", "-o"])
        .arg(dir.path("h.exr")));
    assert_success(&o);
    for delay in [50, 400] {
        let out = dir.path(&format!("m{delay}.exr"));
        let mut child = bdpm()
            .arg("merge")
            .arg(dir.path("h.accum.exr"))
            .args(["--quiet", "-o"])
            .arg(&out)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start merge");
        std::thread::sleep(Duration::from_millis(delay));
        let code = interrupt(&mut child);
        match code {
            Some(130) => assert!(
                !out.exists(),
                "an interrupted merge wrote {}",
                out.display()
            ),
            Some(0) => {
                let json = read_json(&out.with_extension("json"));
                assert_eq!(json["interrupted"], false);
                assert_eq!(json["passes_done"], 200);
            }
            other => panic!("merge exit code {other:?}"),
        }
    }
}

/// Messages of `merge` and `--resume` that name the problem: a missing part list, an image
/// given instead of its accumulation file, a part given twice, and settings that differ
/// (named as the flags that differ, not only as hashes).
#[test]
fn merge_and_resume_messages_name_the_problem() {
    let dir = TempDir::new("merge-messages");
    small_render(&dir.path("a.exr"), &["--passes", "2", "--accumulate"]);
    let accum = dir.path("a.accum.exr");
    let out = run(bdpm().args(["merge", "-o"]).arg(dir.path("m.exr")));
    assert_one_line_error(&out, &["not provided: <PART.accum.exr>"]);
    assert_one_line_error(
        &merge(&[dir.path("a.exr")], &dir.path("m.exr")),
        &[
            "a.exr",
            "not a bdpm accumulation file",
            "render --accumulate",
        ],
    );
    let again = dir.path(".").join("a.accum.exr");
    assert_one_line_error(
        &merge(&[accum.clone(), again], &dir.path("m.exr")),
        &["a.accum.exr", "given twice"],
    );
    let out = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(["--resolution", "8x8", "--photons", "2000", "--spp", "1"])
        .args(["--mode", "optimal", "--quiet", "--resume"])
        .arg(&accum)
        .arg("-o")
        .arg(dir.path("r.exr")));
    assert_one_line_error(
        &out,
        // The header's flag against the one given (docs/distributed.md, "Commands").
        &[
            "a.accum.exr",
            "--resolution 8x8 contradicts",
            "(--resolution 16x16)",
        ],
    );
}
