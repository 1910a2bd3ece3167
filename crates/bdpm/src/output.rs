//! Image and report files: EXR (mean, √V and standard-error layers, settings as header
//! attributes), a tonemapped sRGB PNG preview, and atomic writes for all of them.
use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use bdpm_integrator::Film;
use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, Layer, LayerAttributes,
    SmallVec, Text, WritableImage,
};
use glam::DVec3;

/// The three files of one render, with the same stem.
#[derive(Clone, Debug)]
pub(crate) struct Outputs {
    pub(crate) exr: PathBuf,
    pub(crate) png: PathBuf,
    pub(crate) json: PathBuf,
}

impl Outputs {
    /// OUT.exr, OUT.png and OUT.json for a requested OUT(.exr).
    pub(crate) fn beside(exr: &Path) -> Outputs {
        Outputs {
            exr: exr.with_extension("exr"),
            png: exr.with_extension("png"),
            json: exr.with_extension("json"),
        }
    }
}

/// A temporary path beside `path`, so the final rename stays on one file system.
fn temp_beside(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

fn ensure_parent(path: &Path) -> io::Result<()> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => fs::create_dir_all(dir),
        _ => Ok(()),
    }
}

/// Runs `write` on a temporary file beside `path`, then renames it over `path`: an existing
/// file is either left whole or replaced whole, never half-written.
pub(crate) fn write_via_temp(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), String> {
    ensure_parent(path).map_err(|e| format!("cannot create the directory: {e}"))?;
    let tmp = temp_beside(path);
    if let Err(e) = write(&tmp) {
        let _ = fs::remove_file(&tmp);
        return Err(e);
    }
    fs::rename(&tmp, path).map_err(|e| {
        let _ = fs::remove_file(&tmp);
        format!("cannot move the finished file into place: {e}")
    })
}

/// Writes bytes atomically (temporary file, then rename).
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), String> {
    write_via_temp(path, |tmp| {
        fs::write(tmp, bytes).map_err(|e| format!("cannot write: {e}"))
    })
}

fn channel(name: &str, values: impl Iterator<Item = f32>) -> AnyChannel<FlatSamples> {
    AnyChannel::new(name, FlatSamples::F32(values.collect()))
}

fn rgb_channels(prefix: &str, data: &[DVec3], out: &mut Vec<AnyChannel<FlatSamples>>) {
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let full = if prefix.is_empty() {
            name.to_string()
        } else {
            format!("{prefix}.{name}")
        };
        out.push(channel(&full, data.iter().map(|v| v[c] as f32)));
    }
}

/// Writes the film as a float32 EXR: default R, G, B = mean radiance (W·m⁻²·sr⁻¹); layer
/// `noise` = √(per-pass variance) (the preprint's √V); layer `stderr` = standard error of the
/// mean. `attributes` go into the header as text.
pub(crate) fn write_exr(
    path: &Path,
    film: &Film,
    attributes: &[(String, String)],
) -> Result<(), String> {
    let mean = film.mean();
    let noise: Vec<DVec3> = film
        .pass_variance()
        .into_iter()
        .map(|v| v.map(f64::sqrt))
        .collect();
    let stderr = film.standard_error();
    let mut channels = Vec::new();
    rgb_channels("", &mean, &mut channels);
    rgb_channels("noise", &noise, &mut channels);
    rgb_channels("stderr", &stderr, &mut channels);
    let mut attrs = LayerAttributes::named("bdpm");
    for (k, v) in attributes {
        attrs.other.insert(
            Text::from(format!("bdpm.{k}").as_str()),
            AttributeValue::Text(Text::from(v.as_str())),
        );
    }
    let size = (film.width as usize, film.height as usize);
    let layer = Layer::new(
        size,
        attrs,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(channels)),
    );
    let image = Image::from_layer(layer);
    write_via_temp(path, |tmp| {
        image
            .write()
            .to_file(tmp)
            .map_err(|e| format!("cannot write EXR: {e}"))
    })
}

/// Linear → sRGB transfer function, in [0, 1].
fn srgb(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Exposure that maps the 99th-percentile luminance to 1: robust to a few hot pixels such as
/// the Cornell ceiling spot, and deterministic.
fn auto_exposure(mean: &[DVec3]) -> f64 {
    let mut lum: Vec<f64> = mean
        .iter()
        .map(|c| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z)
        .filter(|l| l.is_finite() && *l > 0.0)
        .collect();
    if lum.is_empty() {
        return 1.0;
    }
    lum.sort_by(f64::total_cmp);
    let p = lum[((lum.len() - 1) as f64 * 0.99) as usize];
    if p > 0.0 { 1.0 / p } else { 1.0 }
}

/// Writes an 8-bit RGB image.
pub(crate) fn write_png_rgb8(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[u8],
) -> Result<(), String> {
    write_via_temp(path, |tmp| {
        let file = fs::File::create(tmp).map_err(|e| format!("cannot create: {e}"))?;
        let mut enc = png::Encoder::new(io::BufWriter::new(file), width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc
            .write_header()
            .map_err(|e| format!("cannot write PNG: {e}"))?;
        w.write_image_data(rgb)
            .map_err(|e| format!("cannot write PNG: {e}"))?;
        w.finish().map_err(|e| format!("cannot write PNG: {e}"))
    })
}

/// Writes the tonemapped preview of the mean: auto exposure, clamp, sRGB.
pub(crate) fn write_png(path: &Path, film: &Film) -> Result<(), String> {
    let mean = film.mean();
    let k = auto_exposure(&mean);
    let rgb: Vec<u8> = mean
        .iter()
        .flat_map(|c| [c.x, c.y, c.z])
        .map(|v| (srgb(v * k) * 255.0 + 0.5) as u8)
        .collect();
    write_png_rgb8(path, film.width, film.height, &rgb)
}
