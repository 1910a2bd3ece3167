//! A render you can watch and headers instead of repeated flags (issue 48, items 2 and 4):
//! `render --preview-every` rewrites OUT.png and OUT.exr with the passes so far, never torn;
//! `predict RENDER.exr`, `render --resume` and `merge` take the scene and the settings from
//! what the render recorded, and refuse a flag that contradicts it.
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output};
use std::time::{Duration, Instant};

use crate::{TINY, bdpm, scene, temp_dir};

/// The image settings of the watched renders: small, fast passes, one thread, and many more
/// passes than any test waits for.
const ENDLESS: [&str; 12] = [
    "--resolution",
    "32x32",
    "--passes",
    "100000",
    "--spp",
    "1",
    "--photons",
    "20000",
    "--mode",
    "bdd0",
    "--threads",
    "1",
];

/// The text attributes and the float channels of an EXR file, read whole (one open of the
/// file: a rename over it afterwards does not change what is read).
struct Exr {
    attributes: HashMap<String, String>,
    channels: HashMap<String, Vec<f32>>,
}

impl Exr {
    fn read(path: &Path) -> Result<Exr, String> {
        let image = exr::prelude::read_all_flat_layers_from_file(path)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        let layer = image.layer_data.first().ok_or("no layer")?;
        let mut channels = HashMap::new();
        for c in &layer.channel_data.list {
            if let exr::prelude::FlatSamples::F32(v) = &c.sample_data {
                channels.insert(c.name.to_string(), v.clone());
            }
        }
        let mut attributes = HashMap::new();
        for (k, v) in &layer.attributes.other {
            if let exr::prelude::AttributeValue::Text(t) = v {
                attributes.insert(k.to_string(), t.to_string());
            }
        }
        Ok(Exr {
            attributes,
            channels,
        })
    }

    fn attribute(&self, key: &str) -> &str {
        self.attributes
            .get(key)
            .unwrap_or_else(|| panic!("no attribute {key}"))
    }

    fn passes_done(&self) -> u64 {
        self.attribute("bdpm.passes_done").parse().expect("a count")
    }

    /// The mean radiance's bits.
    fn rgb_bits(&self) -> Vec<u32> {
        ["R", "G", "B"]
            .iter()
            .flat_map(|c| self.channels[*c].iter().map(|x| x.to_bits()))
            .collect()
    }
}

/// Decodes the PNG at `path` whole.
fn read_png(path: &Path) -> Result<(), String> {
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .map_err(|e| e.to_string())?;
    let mut buf = vec![0; reader.output_buffer_size().ok_or("no size")?];
    reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    Ok(())
}

fn json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{e}"));
    serde_json::from_str(&text).expect("JSON")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn run(cmd: &mut Command) -> Output {
    cmd.output().expect("run bdpm")
}

fn assert_success(out: &Output) {
    assert!(out.status.success(), "stderr: {}", text(&out.stderr));
}

/// A one-line error (exit 1) containing every needle.
fn assert_one_line_error(out: &Output, needles: &[&str]) {
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "not one line: {stderr}");
    for n in needles {
        assert!(stderr.contains(n), "'{n}' not in: {stderr}");
    }
}

/// The Lambert box rendered with `args` to `out`, piped, not waited for.
fn spawn_render(args: &[&str], out: &Path) -> Child {
    crate::spawn_render(&scene("preprint/cornell-lambert.toml"), args, out)
}

/// Waits (at most 120 s) until `path` exists, failing with the render's stderr if it ends
/// first.
fn wait_for(path: &Path, child: &mut Child) {
    let start = Instant::now();
    while !path.exists() {
        if let Some(status) = child.try_wait().expect("wait") {
            let out = child.stderr.take().map(std::io::read_to_string);
            panic!(
                "the render ended ({status}) before {}: {out:?}",
                path.display()
            );
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no {} after 120 s",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Sends SIGINT (as an interactive Ctrl-C) and returns the exit code and the output.
fn interrupt(mut child: Child) -> (Option<i32>, Output) {
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("run kill");
    assert!(status.success());
    let start = Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("bdpm did not stop within 60 s of SIGINT");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().expect("output");
    (out.status.code(), out)
}

/// A preview holds exactly the passes so far: its mean radiance has the bits of a complete
/// render of as many passes. The interrupt then writes the final set, which holds at least
/// those passes and says how many previews were written.
#[test]
fn a_preview_holds_the_passes_so_far_and_an_interrupt_completes_the_set() {
    let dir = temp_dir("preview");
    let out = dir.path().join("w.exr");
    let mut child = spawn_render(&[&ENDLESS[..], &["--preview-every", "0.3"]].concat(), &out);
    wait_for(&out, &mut child);
    let preview = Exr::read(&out).expect("the preview parses");
    read_png(&out.with_extension("png")).expect("the preview PNG decodes");
    let (code, output) = interrupt(child);
    assert_eq!(code, Some(130), "stderr: {}", text(&output.stderr));

    assert_eq!(preview.attribute("bdpm.preview"), "true");
    assert_eq!(preview.attribute("bdpm.stop_reason"), "running");
    assert_eq!(preview.attribute("bdpm.interrupted"), "false");
    let k = preview.passes_done();
    assert!(k >= 1, "a preview of {k} passes");
    assert_eq!(preview.attribute("bdpm.pass_list"), format!("0-{}", k - 1));
    assert!(preview.channels.contains_key("noise.R"));

    let last = Exr::read(&out).expect("the final EXR parses");
    let report = json(&out.with_extension("json"));
    assert!(!last.attributes.contains_key("bdpm.preview"));
    assert_eq!(last.attribute("bdpm.interrupted"), "true");
    assert_eq!(last.attribute("bdpm.run_id"), report["run_id"]);
    assert!(last.passes_done() >= k);
    assert_eq!(report["passes_done"], last.passes_done());
    assert_eq!(report["plan"]["preview_every_seconds"], 0.3);
    let previews = report["plan"]["previews_written"].as_u64().expect("count");
    assert!(previews >= 1, "{previews} previews");
    assert!(
        dir.path().read_dir().unwrap().all(|e| {
            let name = e.unwrap().file_name();
            !name.to_string_lossy().ends_with(".bdpm-tmp")
        }),
        "a temporary file was left"
    );

    // The same passes rendered in one go: the preview's bits.
    let mut settings = ENDLESS.to_vec();
    let passes = k.to_string();
    settings[3] = passes.as_str();
    let whole = dir.path().join("k.exr");
    let done = spawn_render(&settings, &whole)
        .wait_with_output()
        .expect("output");
    assert_success(&done);
    let whole = Exr::read(&whole).expect("parses");
    assert_eq!(whole.passes_done(), k);
    assert!(
        whole.rgb_bits() == preview.rgb_bits(),
        "the preview of {k} passes is not the render of {k} passes"
    );
}

/// A reader polling OUT.exr and OUT.png while previews are rewritten after nearly every pass
/// always reads a whole file: every read parses, and it sees several previews go by.
#[test]
fn a_reader_never_sees_a_torn_preview() {
    let dir = temp_dir("preview-torn");
    let out = dir.path().join("t.exr");
    let mut child = spawn_render(
        &[&ENDLESS[..], &["--preview-every", "0.001"]].concat(),
        &out,
    );
    wait_for(&out, &mut child);
    let (exr_path, png_path) = (out.clone(), out.with_extension("png"));
    let reader = std::thread::spawn(move || {
        let start = Instant::now();
        let mut seen = std::collections::BTreeSet::new();
        let mut reads = 0;
        while start.elapsed() < Duration::from_secs(4) {
            let exr = Exr::read(&exr_path).unwrap_or_else(|e| panic!("read {reads}: {e}"));
            let _ = seen.insert(exr.passes_done());
            read_png(&png_path).unwrap_or_else(|e| panic!("PNG read {reads}: {e}"));
            reads += 1;
        }
        (reads, seen)
    });
    let (reads, seen) = reader.join().expect("every read parses");
    let (code, output) = interrupt(child);
    assert_eq!(code, Some(130), "stderr: {}", text(&output.stderr));
    eprintln!("{reads} reads of both files, {} previews seen", seen.len());
    assert!(reads >= 20, "{reads} reads");
    assert!(
        seen.len() >= 3,
        "{} previews seen in {reads} reads",
        seen.len()
    );
    let report = json(&out.with_extension("json"));
    assert!(report["plan"]["previews_written"].as_u64().expect("count") >= seen.len() as u64);
}

/// `--preview-every` takes a positive finite number of seconds, else one line naming it,
/// before any work.
#[test]
fn preview_every_takes_positive_seconds() {
    let dir = temp_dir("preview-flag");
    for (bad, why) in [
        ("0", "is not a positive number"),
        ("-1", "is not a positive number"),
        ("nan", "is not a positive number"),
        ("inf", "is not a positive number"),
        ("soon", "is not a number"),
    ] {
        let out = run(bdpm()
            .arg("render")
            .arg(scene("preprint/cornell-lambert.toml"))
            .args(["--quiet", "--preview-every", bad, "-o"])
            .arg(dir.path().join("f.exr")));
        assert_one_line_error(&out, &["--preview-every", bad, why]);
        assert!(!dir.path().join("f.exr").exists());
    }
}

/// A small Lambert-box render with `settings` and `more` to `out`.
fn small(out: &Path, settings: &[&str], more: &[&str]) {
    let out = run(bdpm()
        .arg("render")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(settings)
        .args(more)
        .args(["--quiet", "-o"])
        .arg(out));
    assert_success(&out);
}

/// The small render of these tests: [`TINY`] in `optimal` mode with seed 5.
fn small_settings() -> Vec<&'static str> {
    [&TINY[..], &["--mode", "optimal", "--seed", "5"]].concat()
}

/// `render --resume` and `merge` need neither the scene nor the flags again: their results
/// have the bits of one render of all the passes; a resume with a flag that contradicts the
/// record is refused, naming both values.
#[test]
fn resume_and_merge_take_the_recorded_settings() {
    let dir = temp_dir("headers-resume");
    let path = |name: &str| dir.path().join(name);
    small(&path("full.exr"), &small_settings(), &["--passes", "4"]);
    small(
        &path("a.exr"),
        &small_settings(),
        &["--passes", "2", "--accumulate"],
    );
    let out = run(bdpm()
        .args(["render", "--quiet", "--passes", "2", "--resume"])
        .arg(path("a.accum.exr"))
        .arg("-o")
        .arg(path("b.exr")));
    assert_success(&out);
    let full = Exr::read(&path("full.exr")).expect("parses");
    assert!(Exr::read(&path("b.exr")).expect("parses").rgb_bits() == full.rgb_bits());

    small(
        &path("p0.exr"),
        &small_settings(),
        &["--first-pass", "0", "--passes", "3"],
    );
    small(
        &path("p1.exr"),
        &small_settings(),
        &["--first-pass", "3", "--passes", "1"],
    );
    let out = run(bdpm()
        .args(["merge", "--quiet"])
        .arg(path("p1.accum.exr"))
        .arg(path("p0.accum.exr"))
        .arg("-o")
        .arg(path("m.exr")));
    assert_success(&out);
    assert!(Exr::read(&path("m.exr")).expect("parses").rgb_bits() == full.rgb_bits());

    let out = run(bdpm()
        .args([
            "render", "--quiet", "--passes", "1", "--mode", "balance", "--resume",
        ])
        .arg(path("a.accum.exr"))
        .arg("-o")
        .arg(path("c.exr")));
    assert_one_line_error(&out, &["a.accum.exr", "--mode balance", "(--mode optimal)"]);
    assert!(!path("c.exr").exists());
}

/// `predict RENDER.exr` reads the scene and the flags from the render's header: the same
/// prediction, bit for bit, as with the scene and every flag repeated; a contradicting flag
/// is refused, naming both values.
#[test]
fn predict_takes_the_scene_and_flags_from_the_header() {
    let dir = temp_dir("headers-predict");
    let path = |name: &str| dir.path().join(name);
    let settings = [
        "--mode",
        "bdd0",
        "--resolution",
        "16x16",
        "--photons",
        "30000",
        "--spp",
        "4",
        "--radius",
        "0.01",
    ];
    let rendered: PathBuf = path("r.exr");
    small(&rendered, &settings, &["--passes", "4"]);
    let cache = ["--model-cache-photons", "200000"];
    let out = run(bdpm()
        .arg("predict")
        .arg(&rendered)
        .args(cache)
        .arg("-o")
        .arg(path("h.exr")));
    assert_success(&out);
    let out = run(bdpm()
        .arg("predict")
        .arg(scene("preprint/cornell-lambert.toml"))
        .args(settings)
        .args(cache)
        .arg("--measured")
        .arg(&rendered)
        .arg("-o")
        .arg(path("f.exr")));
    assert_success(&out);
    let (h, f) = (json(&path("h.json")), json(&path("f.json")));
    for key in ["mode", "radius_m", "per_pixel", "blocks", "term_shares"] {
        assert_eq!(h[key], f[key], "{key}");
    }
    let predicted = |name: &str| {
        let exr = Exr::read(&path(name)).expect("parses");
        exr.channels["predicted_V"]
            .iter()
            .map(|x| x.to_bits())
            .collect::<Vec<_>>()
    };
    assert!(predicted("h.exr") == predicted("f.exr"));

    let out = run(bdpm()
        .arg("predict")
        .arg(&rendered)
        .args(["--spp", "8"])
        .arg("-o")
        .arg(path("x.exr")));
    assert_one_line_error(&out, &["r.exr", "--spp 8", "(--spp 4)"]);
    let out = run(bdpm()
        .arg("predict")
        .arg(scene("preprint/cornell-lambert.toml")));
    assert_one_line_error(&out, &["cornell-lambert.toml", "--measured"]);
}
