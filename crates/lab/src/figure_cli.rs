//! `bdpm figure`: reads the reference and the images (EXR), computes the figure
//! ([`crate::figure::build`]) and writes DIR/figure.png, DIR/figure.html and DIR/figure.json
//! as a set (each staged under a temporary name, then all renamed into place).
use std::path::{Path, PathBuf};

use clap::Args;
use glam::DVec3;
use serde_json::json;

use crate::figure::{Crop, Entry, Figure, Inputs, build};
use crate::reference::read_exr;
use bdpm_output::cli::CliResult;
use bdpm_output::files::{commit_all, stage_bytes, stem_of};

/// Arguments of `bdpm figure`.
#[derive(Args, Debug)]
pub struct FigureArgs {
    /// Reference image (EXR with R, G, B): it sets the one exposure of every image and is
    /// what the errors are measured against.
    #[arg(long)]
    reference: PathBuf,
    /// The images to compare (EXR with R, G, B, the reference's size). The time under each is
    /// the render's preparation + render time from its run report (IMAGE.json beside it), when
    /// there is one.
    #[arg(required = true)]
    images: Vec<PathBuf>,
    /// A region to show enlarged, x,y,w,h in pixels from the top-left corner (repeatable).
    /// Default: the regions of largest relative squared error summed over the images.
    #[arg(long = "crop", value_parser = Crop::parse)]
    crops: Vec<Crop>,
    /// How many regions to choose when no --crop is given.
    #[arg(long, default_value_t = 2)]
    auto_crops: usize,
    /// Names of the images in the figure, comma-separated, in order (default: file stems).
    #[arg(long, value_delimiter = ',')]
    names: Vec<String>,
    /// Title of the figure (default: the reference's file name).
    #[arg(long)]
    title: Option<String>,
    /// Output directory: figure.png, figure.html and figure.json.
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
}

/// The render time of the image at `path` from its run report (`path` with `.json`):
/// `timing.prepare_s + timing.render_s`, s; `None` without a readable report.
fn report_seconds(path: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(path.with_extension("json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    let t = v.get("timing")?;
    let s = t.get("prepare_s")?.as_f64()? + t.get("render_s")?.as_f64()?;
    s.is_finite().then_some(s)
}

/// Refuses an image with a pixel that is not a finite radiance, naming the file and pixel.
fn check_finite(path: &Path, rgb: &[DVec3], width: u32) -> CliResult<()> {
    match rgb.iter().position(|c| !c.is_finite()) {
        None => Ok(()),
        Some(i) => Err(format!(
            "{}: pixel ({}, {}) is not a finite radiance ({})",
            path.display(),
            i as u32 % width,
            i as u32 / width,
            rgb[i]
        )),
    }
}

/// Reads the inputs; errors name the file (or flag) and what is wrong.
fn read_inputs(args: &FigureArgs) -> CliResult<Inputs> {
    let reference = read_exr(&args.reference)?;
    let (w, h) = (reference.width, reference.height);
    check_finite(&args.reference, &reference.mean, w)?;
    if !args.names.is_empty() && args.names.len() != args.images.len() {
        return Err(format!(
            "--names: {} names for {} images",
            args.names.len(),
            args.images.len()
        ));
    }
    for c in &args.crops {
        c.check((w, h))?;
    }
    let mut entries = Vec::new();
    for (i, path) in args.images.iter().enumerate() {
        let img = read_exr(path)?;
        if (img.width, img.height) != (w, h) {
            return Err(format!(
                "{}: the image is {}x{} but the reference {} is {w}x{h}",
                path.display(),
                img.width,
                img.height,
                args.reference.display()
            ));
        }
        check_finite(path, &img.mean, w)?;
        entries.push(Entry {
            name: args
                .names
                .get(i)
                .cloned()
                .unwrap_or_else(|| stem_of(path, "image")),
            rgb: img.mean,
            seconds: report_seconds(path),
        });
    }
    Ok(Inputs {
        width: w,
        height: h,
        reference_error: reference
            .stderr
            .as_ref()
            .map(|se| crate::figure::reference_error(&reference.mean, se)),
        reference: reference.mean,
        entries,
        crops: args.crops.clone(),
        auto_crops: args.auto_crops,
    })
}

/// The figure's numbers as JSON.
fn numbers(fig: &Figure, title: &str) -> String {
    let images: Vec<_> = fig
        .panels
        .iter()
        .map(|p| {
            json!({
                "name": p.name,
                "rel_rmse": p.rel_rmse,
                "rel_mse": p.rel_mse,
                "flip_mean": p.flip_mean,
                "seconds": p.seconds,
            })
        })
        .collect();
    let crops: Vec<_> = fig.crops.iter().map(|c| [c.x, c.y, c.w, c.h]).collect();
    let v = json!({
        "title": title,
        "width": fig.width,
        "height": fig.height,
        "exposure": fig.exposure,
        "reference_rel_rmse": fig.reference_error,
        "crops": crops,
        "crops_auto": fig.crops_auto,
        "error_scale_top": fig.error_top,
        "flip_pixels_per_degree": crate::figure::PIXELS_PER_DEGREE,
        "images": images,
    });
    serde_json::to_string_pretty(&v).unwrap_or_default() + "\n"
}

/// The files of a figure in `dir`.
pub(crate) fn members(dir: &Path) -> [PathBuf; 3] {
    ["figure.png", "figure.html", "figure.json"].map(|n| dir.join(n))
}

/// Writes the figure's PNG, HTML page and JSON numbers into `dir` as a set; returns the paths.
pub(crate) fn write_set(dir: &Path, fig: &Figure, title: &str) -> CliResult<Vec<PathBuf>> {
    let [png, html, json] = members(dir);
    let named = |p: &Path, e: String| format!("{}: {e}", p.display());
    let contents = [
        (
            &png,
            crate::figure_sheet::encode(fig).map_err(|e| named(&png, e))?,
        ),
        (
            &html,
            crate::figure_page::page(fig, title)
                .map_err(|e| named(&html, e))?
                .into_bytes(),
        ),
        (&json, numbers(fig, title).into_bytes()),
    ];
    let mut staged = Vec::new();
    for (path, bytes) in &contents {
        staged.push(stage_bytes(path, bytes).map_err(|e| named(path, e))?);
    }
    commit_all(staged)?;
    Ok(vec![png, html, json])
}

/// Runs `bdpm figure`.
pub(crate) fn run(args: FigureArgs) -> CliResult<()> {
    if std::fs::metadata(&args.output).is_ok_and(|m| !m.is_dir()) {
        return Err(format!(
            "-o {}: it is a file; figure writes a directory (figure.png, figure.html, figure.json)",
            args.output.display()
        ));
    }
    let inputs = read_inputs(&args)?;
    std::fs::create_dir_all(&args.output).map_err(|e| {
        format!(
            "-o {}: cannot create the directory: {e}",
            args.output.display()
        )
    })?;
    let title = args.title.clone().unwrap_or_else(|| {
        format!(
            "against {}",
            args.reference
                .file_name()
                .map_or("the reference".into(), |n| n.to_string_lossy().into_owned())
        )
    });
    let fig = build(inputs);
    for p in &fig.panels {
        bdpm_output::say!(
            "{:>20}: rel. RMSE {:.4}, relMSE {:.3e}, FLIP mean {:.4}{}",
            p.name,
            p.rel_rmse,
            p.rel_mse,
            p.flip_mean,
            p.seconds.map_or(String::new(), |s| format!(", {s:.1} s"))
        );
    }
    for path in write_set(&args.output, &fig, &title)? {
        bdpm_output::say!("wrote {}", path.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use bdpm_output::exr::write_exr_channels;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: FigureArgs,
    }

    fn args(list: &[&str]) -> FigureArgs {
        Cli::try_parse_from(std::iter::once("figure").chain(list.iter().copied()))
            .expect("valid arguments")
            .args
    }

    /// Writes a grey `w`×`h` EXR whose pixel i has radiance `f(i)`.
    fn exr(path: &Path, (w, h): (u32, u32), f: impl Fn(usize) -> f64) {
        let v: Vec<f64> = (0..(w * h) as usize).map(f).collect();
        write_exr_channels(path, (w, h), &[("R", &v), ("G", &v), ("B", &v)], &[]).unwrap();
    }

    #[test]
    fn figure_writes_its_set_and_reads_the_time_from_the_report() {
        let dir = tempfile::tempdir().unwrap();
        let p = |n: &str| dir.path().join(n).display().to_string();
        exr(Path::new(&p("ref.exr")), (16, 12), |i| {
            1.0 + (i % 16) as f64
        });
        exr(Path::new(&p("a.exr")), (16, 12), |i| {
            1.0 + (i % 16) as f64 * 1.1
        });
        std::fs::write(
            p("a.json"),
            r#"{"timing": {"prepare_s": 1.5, "render_s": 8.25}}"#,
        )
        .unwrap();
        let out = p("fig");
        run(args(&[
            "--reference",
            &p("ref.exr"),
            &p("a.exr"),
            "-o",
            &out,
        ]))
        .unwrap();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(p("fig/figure.json")).unwrap()).unwrap();
        let image = &json["images"][0];
        assert_eq!(image["name"], "a");
        assert_eq!(image["seconds"], 9.75);
        // Luminance differs by 10 % of (x) in column x: rel. RMSE = 0.1 · rms(x) / mean(1 + x).
        let xs: Vec<f64> = (0..16).map(f64::from).collect();
        let rms = (xs.iter().map(|x| x * x).sum::<f64>() / 16.0).sqrt();
        let expected = 0.1 * rms / (1.0 + 7.5);
        let got = image["rel_rmse"].as_f64().unwrap();
        // The EXR stores f32: agreement to single precision.
        assert!((got / expected - 1.0).abs() < 1e-5, "{got} vs {expected}");
        assert_eq!(json["crops"].as_array().unwrap().len(), 2);
        let html = std::fs::read_to_string(p("fig/figure.html")).unwrap();
        assert!(html.contains("data:image/png;base64,") && !html.contains("http"));
        assert!(
            std::fs::read(p("fig/figure.png"))
                .unwrap()
                .starts_with(b"\x89PNG")
        );
    }

    #[test]
    fn figure_refuses_bad_input_naming_the_file_and_what_is_wrong() {
        let dir = tempfile::tempdir().unwrap();
        let p = |n: &str| dir.path().join(n).display().to_string();
        exr(Path::new(&p("ref.exr")), (16, 12), |_| 1.0);
        exr(Path::new(&p("small.exr")), (8, 12), |_| 1.0);
        exr(Path::new(&p("nan.exr")), (16, 12), |i| {
            if i == 17 { f64::NAN } else { 1.0 }
        });
        std::fs::write(p("fake.exr"), "not an EXR").unwrap();
        let out = p("fig");
        let fail = |list: &[&str]| run(args(list)).unwrap_err();
        let e = fail(&["--reference", &p("ref.exr"), &p("small.exr"), "-o", &out]);
        assert!(
            e.contains("small.exr") && e.contains("8x12") && e.contains("16x12"),
            "{e}"
        );
        let e = fail(&["--reference", &p("ref.exr"), &p("nan.exr"), "-o", &out]);
        assert!(e.contains("nan.exr") && e.contains("pixel (1, 1)"), "{e}");
        let e = fail(&["--reference", &p("fake.exr"), &p("ref.exr"), "-o", &out]);
        assert!(e.contains("fake.exr"), "{e}");
        let e = fail(&[
            "--reference",
            &p("ref.exr"),
            &p("ref.exr"),
            "--crop",
            "10,0,8,4",
            "-o",
            &out,
        ]);
        assert!(e.contains("--crop 10,0,8,4") && e.contains("16x12"), "{e}");
        let e = fail(&[
            "--reference",
            &p("ref.exr"),
            &p("ref.exr"),
            "--names",
            "a,b",
            "-o",
            &out,
        ]);
        assert!(e.contains("--names"), "{e}");
        let e = fail(&[
            "--reference",
            &p("ref.exr"),
            &p("ref.exr"),
            "-o",
            &p("ref.exr"),
        ]);
        assert!(e.contains("it is a file"), "{e}");
        assert!(!Path::new(&out).exists(), "nothing written on refusal");
    }
}
