//! PNG files: the tonemapped sRGB preview of a render and its false-colour noise map.
use std::path::Path;

use bdpm_integrator::Film;
use glam::DVec3;

use crate::colormap::{ColourMap, Legend, compose, linear_ticks};
use crate::files::write_atomic;
use crate::raster::encode_png_rgb8;
use crate::stats::luminance;

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
        .map(|c| luminance(*c))
        .filter(|l| l.is_finite() && *l > 0.0)
        .collect();
    if lum.is_empty() {
        return 1.0;
    }
    lum.sort_by(f64::total_cmp);
    let p = lum[((lum.len() - 1) as f64 * 0.99) as usize];
    if p > 0.0 { 1.0 / p } else { 1.0 }
}

/// The tonemapped preview of the mean as PNG bytes: auto exposure, clamp, sRGB.
pub fn encode_png(film: &Film) -> Result<Vec<u8>, String> {
    let mean = film.mean();
    let k = auto_exposure(&mean);
    let rgb: Vec<u8> = mean
        .iter()
        .flat_map(|c| [c.x, c.y, c.z])
        .map(|v| (srgb(v * k) * 255.0 + 0.5) as u8)
        .collect();
    encode_png_rgb8(film.width(), film.height(), &rgb)
}

/// Writes the tonemapped preview of the mean atomically (see [`encode_png`]).
pub fn write_png(path: &Path, film: &Film) -> Result<(), String> {
    write_atomic(path, &encode_png(film)?)
}

/// The 99th percentile of the finite positive values (0 if there are none): the top of a
/// colour scale that a few hot pixels cannot stretch.
pub fn robust_max(values: &[f64]) -> f64 {
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

/// The noise map as PNG bytes: `noise` (√V of the pixel luminance per pass, W·m⁻²·sr⁻¹) in viridis
/// on a linear scale from 0 to its 99th percentile (brighter pixels clamp to the top colour),
/// with the colour bar and its scale drawn on the image. With fewer than two passes V is
/// unknown; the map is then flat and the legend says so.
pub fn encode_noise_png(
    (width, height): (u32, u32),
    noise: &[f64],
    passes: u32,
) -> Result<Vec<u8>, String> {
    let max = robust_max(noise);
    let colours: Vec<[u8; 3]> = noise
        .iter()
        .map(|v| ColourMap::Viridis.colour(if max > 0.0 { v / max } else { 0.0 }))
        .collect();
    let mut title = vec![
        "noise √V".to_string(),
        "W·m⁻²·sr⁻¹".into(),
        "linear, max p99".into(),
    ];
    if passes < 2 {
        title.push(format!("{passes} pass: V unknown"));
    }
    let legend = Legend {
        title,
        ticks: linear_ticks(max),
    };
    compose(width, height, &colours, &legend, ColourMap::Viridis)?
        .canvas
        .encode_png()
}
