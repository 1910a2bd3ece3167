//! Image and report files: EXR (mean, √V and standard-error layers, settings as header
//! attributes), a tonemapped sRGB PNG preview, and atomic writes for all of them.
use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use bdpm_integrator::Film;
use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, Layer, LayerAttributes,
    SmallVec, Text, WritableImage, read_all_flat_layers_from_file,
};
use glam::DVec3;

use crate::colormap::{Legend, compose, linear_ticks, viridis};

/// The first layer of an EXR file read back: its size, every channel as f64 (any sample
/// type) and its text attributes (`bdpm.` prefix removed). The one EXR reader of the driver.
pub(crate) struct ExrLayer {
    /// Width, pixels.
    pub(crate) width: u32,
    /// Height, pixels.
    pub(crate) height: u32,
    channels: Vec<(String, Vec<f64>)>,
    /// Text header attributes as (key without `bdpm.`, value).
    pub(crate) attributes: Vec<(String, String)>,
}

impl ExrLayer {
    /// Reads the first layer of `path`; errors name the file.
    pub(crate) fn read(path: &Path) -> Result<ExrLayer, String> {
        let image = read_all_flat_layers_from_file(path)
            .map_err(|e| format!("{}: cannot read EXR: {e}", path.display()))?;
        let layer = image
            .layer_data
            .first()
            .ok_or_else(|| format!("{}: EXR has no layer", path.display()))?;
        let channels = layer
            .channel_data
            .list
            .iter()
            .map(|c| {
                let values = match &c.sample_data {
                    FlatSamples::F16(v) => v.iter().map(|x| x.to_f64()).collect(),
                    FlatSamples::F32(v) => v.iter().map(|x| *x as f64).collect(),
                    FlatSamples::U32(v) => v.iter().map(|x| *x as f64).collect(),
                };
                (c.name.to_string(), values)
            })
            .collect();
        let attributes = layer
            .attributes
            .other
            .iter()
            .filter_map(|(k, v)| match v {
                AttributeValue::Text(t) => Some((
                    k.to_string().trim_start_matches("bdpm.").to_string(),
                    t.to_string(),
                )),
                _ => None,
            })
            .collect();
        Ok(ExrLayer {
            width: layer.size.width() as u32,
            height: layer.size.height() as u32,
            channels,
            attributes,
        })
    }

    /// The channel called `name` (e.g. `R`, `noise.G`), if present.
    pub(crate) fn channel(&self, name: &str) -> Option<&[f64]> {
        self.channels
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

/// The files of one render, with the same stem.
#[derive(Clone, Debug)]
pub(crate) struct Outputs {
    pub(crate) exr: PathBuf,
    pub(crate) png: PathBuf,
    /// OUT-noise.png: the false-colour noise map.
    pub(crate) noise_png: PathBuf,
    pub(crate) json: PathBuf,
}

impl Outputs {
    /// OUT.exr, OUT.png, OUT-noise.png and OUT.json for a requested OUT(.exr).
    pub(crate) fn beside(exr: &Path) -> Outputs {
        let exr = exr.with_extension("exr");
        let stem = exr
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        Outputs {
            png: exr.with_extension("png"),
            noise_png: exr.with_file_name(format!("{stem}-noise.png")),
            json: exr.with_extension("json"),
            exr,
        }
    }

    /// Every path, in the order the render writes them.
    pub(crate) fn all(&self) -> [&Path; 4] {
        [&self.exr, &self.png, &self.noise_png, &self.json]
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
    write_exr_with_layers(path, film, attributes, &[])
}

/// [`write_exr`] plus `extra` RGB layers (name, per-pixel values), e.g. the technique layers.
pub(crate) fn write_exr_with_layers(
    path: &Path,
    film: &Film,
    attributes: &[(String, String)],
    extra: &[(&str, Vec<DVec3>)],
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
    for (name, data) in extra {
        rgb_channels(name, data, &mut channels);
    }
    write_channels(path, (film.width, film.height), channels, attributes)
}

/// Writes a float32 EXR with one channel, e.g. the weight map's `w0`.
pub(crate) fn write_exr_single(
    path: &Path,
    size: (u32, u32),
    name: &str,
    values: &[f64],
    attributes: &[(String, String)],
) -> Result<(), String> {
    let channels = vec![channel(name, values.iter().map(|v| *v as f32))];
    write_channels(path, size, channels, attributes)
}

/// Writes a float32 EXR with several single-value channels (name, per-pixel values).
pub(crate) fn write_exr_channels(
    path: &Path,
    size: (u32, u32),
    named: &[(&str, &[f64])],
    attributes: &[(String, String)],
) -> Result<(), String> {
    let channels = named
        .iter()
        .map(|(name, values)| channel(name, values.iter().map(|v| *v as f32)))
        .collect();
    write_channels(path, size, channels, attributes)
}

/// Writes `channels` as one EXR layer with `attributes` as `bdpm.*` text header attributes.
fn write_channels(
    path: &Path,
    (width, height): (u32, u32),
    channels: Vec<AnyChannel<FlatSamples>>,
    attributes: &[(String, String)],
) -> Result<(), String> {
    let mut attrs = LayerAttributes::named("bdpm");
    for (k, v) in attributes {
        attrs.other.insert(
            Text::from(format!("bdpm.{k}").as_str()),
            AttributeValue::Text(Text::from(v.as_str())),
        );
    }
    let layer = Layer::new(
        (width as usize, height as usize),
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

/// Writes an 8-bit RGB image. It is encoded in memory first, so that an encoder error cannot
/// leave a half-written temporary file, and a write error is reported (not lost in a drop).
pub(crate) fn write_png_rgb8(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[u8],
) -> Result<(), String> {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc
            .write_header()
            .map_err(|e| format!("cannot write PNG: {e}"))?;
        w.write_image_data(rgb)
            .map_err(|e| format!("cannot write PNG: {e}"))?;
        w.finish().map_err(|e| format!("cannot write PNG: {e}"))?;
    }
    write_atomic(path, &bytes)
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

/// Rec. 709 luminance of a linear RGB value.
pub(crate) fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// The 99th percentile of the finite positive values (0 if there are none): the top of a
/// colour scale that a few hot pixels cannot stretch.
pub(crate) fn robust_max(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values
        .iter()
        .copied()
        .filter(|x| x.is_finite() && *x > 0.0)
        .collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * 0.99).round() as usize]
}

/// Writes the noise map: `noise` (√V of the pixel luminance per pass, W·m⁻²·sr⁻¹) in viridis
/// on a linear scale from 0 to its 99th percentile (brighter pixels clamp to the top colour),
/// with the colour bar and its scale drawn on the image. With fewer than two passes V is
/// unknown; the map is then flat and the legend says so.
pub(crate) fn write_noise_png(
    path: &Path,
    (width, height): (u32, u32),
    noise: &[f64],
    passes: u32,
) -> Result<(), String> {
    let max = robust_max(noise);
    let colours: Vec<[u8; 3]> = noise
        .iter()
        .map(|v| viridis(if max > 0.0 { v / max } else { 0.0 }))
        .collect();
    let mut title = vec![
        "noise sqrt V".to_string(),
        "W m-2 sr-1".into(),
        "linear, max p99".into(),
    ];
    if passes < 2 {
        title.push(format!("{passes} pass: V unknown"));
    }
    let legend = Legend {
        title,
        ticks: linear_ticks(max),
    };
    let layout = compose(width, height, &colours, &legend, viridis);
    let c = &layout.canvas;
    write_png_rgb8(path, c.width, c.height, &c.rgb)
}
