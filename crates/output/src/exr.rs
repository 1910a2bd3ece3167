//! EXR files: the render's EXR (mean, √V and standard-error layers, settings as header
//! attributes), single-value channel files, arbitrary channels (the accumulation file), and
//! the one EXR reader of the driver.
use std::fs;
use std::io::{self, Write as _};
use std::path::Path;

use bdpm_integrator::{Film, Techniques};
use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, Layer, LayerAttributes,
    SmallVec, Text, WritableImage, read_all_flat_layers_from_file,
};
use glam::DVec3;

use crate::files::{Staged, stage, write_via_temp};

/// The text attributes of the first layer of the EXR at `path` (`bdpm.` prefix removed, as
/// [`ExrLayer::attributes`]), read from its header alone, without the pixels.
pub fn read_attributes(path: &Path) -> Result<Vec<(String, String)>, String> {
    Ok(text_attributes(&first_header(path)?.own_attributes))
}

/// The header of the first layer of the EXR at `path`, read without the pixels; errors name
/// the file.
pub(crate) fn first_header(path: &Path) -> Result<exr::meta::header::Header, String> {
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| format!("{}: cannot read EXR: {e}", path.display()))?;
    meta.headers
        .into_iter()
        .next()
        .ok_or_else(|| format!("{}: EXR has no layer", path.display()))
}

/// The text attributes among `attributes`, keys without the `bdpm.` prefix.
fn text_attributes(attributes: &LayerAttributes) -> Vec<(String, String)> {
    attributes
        .other
        .iter()
        .filter_map(|(k, v)| match v {
            AttributeValue::Text(t) => Some((
                k.to_string().trim_start_matches("bdpm.").to_string(),
                t.to_string(),
            )),
            _ => None,
        })
        .collect()
}

/// The first layer of an EXR file read back: its size, every channel as f64 (any sample
/// type) and its text attributes (`bdpm.` prefix removed). The one EXR reader of the driver.
pub struct ExrLayer {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    channels: Vec<(String, Vec<f64>)>,
    /// Text header attributes as (key without `bdpm.`, value).
    pub attributes: Vec<(String, String)>,
}

impl ExrLayer {
    /// Reads the first layer of `path`; errors name the file.
    pub fn read(path: &Path) -> Result<ExrLayer, String> {
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
        let attributes = text_attributes(&layer.attributes);
        Ok(ExrLayer {
            width: layer.size.width() as u32,
            height: layer.size.height() as u32,
            channels,
            attributes,
        })
    }

    /// The channel called `name` (e.g. `R`, `noise.G`), if present.
    pub fn channel(&self, name: &str) -> Option<&[f64]> {
        self.channels
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

fn channel(name: &str, values: impl Iterator<Item = f32>) -> AnyChannel<FlatSamples> {
    AnyChannel::new(name, FlatSamples::F32(values.collect()))
}

/// Sample type of an EXR's colour and layer channels (`--exr-precision`); the accumulation
/// file is always exact and does not use this.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Precision {
    /// 32-bit float (the default).
    #[default]
    Float,
    /// 16-bit half float: half the size, about 3 significant digits, overflows above 65504.
    Half,
}

/// An extra EXR layer: name, its three channel names and per-pixel values.
pub type ExtraLayer<'a> = (&'a str, [&'a str; 3], Vec<DVec3>);

/// Channel names of an RGB layer.
pub const RGB: [&str; 3] = ["R", "G", "B"];

fn rgb_channels(
    prefix: &str,
    names: [&str; 3],
    data: &[DVec3],
    precision: Precision,
    out: &mut Vec<AnyChannel<FlatSamples>>,
) {
    for (c, name) in names.iter().enumerate() {
        let full = if prefix.is_empty() {
            name.to_string()
        } else {
            format!("{prefix}.{name}")
        };
        let values = data.iter().map(|v| v[c]);
        let samples = match precision {
            Precision::Float => FlatSamples::F32(values.map(|x| x as f32).collect()),
            Precision::Half => FlatSamples::F16(values.map(exr::prelude::f16::from_f64).collect()),
        };
        out.push(AnyChannel::new(full.as_str(), samples));
    }
}

/// Writes the film as a float32 EXR: default R, G, B = mean radiance (W·m⁻²·sr⁻¹); layer
/// `noise` = √(per-pass variance) (the preprint's √V); layer `stderr` = standard error of the
/// mean. `attributes` go into the header as text.
pub fn write_exr(path: &Path, film: &Film, attributes: &[(String, String)]) -> Result<(), String> {
    let channels = film_channels(film, &[], Precision::Float);
    write_channels(path, (film.width(), film.height()), channels, attributes)
}

/// The film's mean, `noise` and `stderr` RGB layers, then `extra`, at `precision`.
fn film_channels(
    film: &Film,
    extra: &[ExtraLayer<'_>],
    precision: Precision,
) -> Vec<AnyChannel<FlatSamples>> {
    let mean = film.mean();
    let noise: Vec<DVec3> = film
        .pass_variance()
        .into_iter()
        .map(|v| v.map(f64::sqrt))
        .collect();
    let stderr = film.standard_error();
    let mut channels = Vec::new();
    rgb_channels("", RGB, &mean, precision, &mut channels);
    rgb_channels("noise", RGB, &noise, precision, &mut channels);
    rgb_channels("stderr", RGB, &stderr, precision, &mut channels);
    for (name, names, data) in extra {
        rgb_channels(name, *names, data, precision, &mut channels);
    }
    channels
}

/// Stages the film's EXR (see [`write_exr`]) plus `extra` layers (e.g. the technique or
/// first-hit layers) at `precision`, as a temporary file beside `path` (see [`stage`]).
pub fn stage_exr_with_layers(
    path: &Path,
    film: &Film,
    attributes: &[(String, String)],
    extra: &[ExtraLayer<'_>],
    precision: Precision,
) -> Result<Staged, String> {
    let channels = film_channels(film, extra, precision);
    stage(path, |f| {
        encode_channels(f, (film.width(), film.height()), channels, attributes)
    })
}

/// Stages an EXR of arbitrary `channels` (any sample type) beside `path`, e.g. the
/// accumulation file's u32 channels (see [`crate::accum`]).
pub fn stage_exr_channels(
    path: &Path,
    size: (u32, u32),
    channels: Vec<AnyChannel<FlatSamples>>,
    attributes: &[(String, String)],
) -> Result<Staged, String> {
    stage(path, |f| encode_channels(f, size, channels, attributes))
}

/// Writes a float32 EXR with one channel, e.g. the weight map's `w0`.
pub fn write_exr_single(
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
pub fn write_exr_channels(
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
    size: (u32, u32),
    channels: Vec<AnyChannel<FlatSamples>>,
    attributes: &[(String, String)],
) -> Result<(), String> {
    write_via_temp(path, |f| encode_channels(f, size, channels, attributes))
}

/// Encodes `channels` as one EXR layer into `file` (through the open handle: the file is
/// never reopened by name).
fn encode_channels(
    file: &mut fs::File,
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
    let mut writer = io::BufWriter::new(file);
    image
        .write()
        .to_buffered(&mut writer)
        .map_err(|e| format!("cannot write EXR: {e}"))?;
    writer.flush().map_err(|e| format!("cannot write EXR: {e}"))
}

/// Sums of the technique layers over passes.
pub struct TechniqueSums {
    sums: Vec<Techniques>,
}

impl TechniqueSums {
    /// Zero sums for an image of `pixels` pixels.
    pub fn new(pixels: usize) -> TechniqueSums {
        TechniqueSums {
            sums: vec![Techniques::default(); pixels],
        }
    }

    /// Adds one pass's per-pixel technique split.
    pub fn add_pass(&mut self, pass: &[Techniques]) {
        for (s, t) in self.sums.iter_mut().zip(pass) {
            s.direct += t.direct;
            s.x0_raw += t.x0_raw;
            s.x0_weighted += t.x0_weighted;
            s.x1_raw += t.x1_raw;
            s.x1_weighted += t.x1_weighted;
        }
    }

    /// The named layers: means over `passes`.
    pub fn layers(&self, passes: u32) -> Vec<ExtraLayer<'static>> {
        let k = passes.max(1) as f64;
        let layer = |f: fn(&Techniques) -> DVec3| self.sums.iter().map(|t| f(t) / k).collect();
        vec![
            ("direct", RGB, layer(|t| t.direct)),
            ("x0_raw", RGB, layer(|t| t.x0_raw)),
            ("x0_weighted", RGB, layer(|t| t.x0_weighted)),
            ("x1_raw", RGB, layer(|t| t.x1_raw)),
            ("x1_weighted", RGB, layer(|t| t.x1_weighted)),
        ]
    }
}
