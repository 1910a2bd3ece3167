//! The content of a comparison figure (`bdpm figure`, and the one `bdpm study` writes): every
//! image tonemapped at the reference's exposure, its error against the reference (rel. RMSE,
//! relMSE, FLIP mean) and per-pixel maps of relative squared error and of FLIP, and the crops
//! to show enlarged (given, or the regions of largest relative squared error). Drawing it is
//! `figure_sheet` (PNG) and `figure_page` (HTML); reading and writing files is `figure_cli`.
//!
//! One exposure for all, from the reference: images tonemapped each on its own (as a render's
//! preview is) cannot be compared by eye, since a brighter outlier would darken only its own
//! image.
use glam::DVec3;

use crate::metrics::{mean, rel_epsilon, rel_mse, rmse};
use bdpm_output::colormap::{ColourMap, format_value};
use bdpm_output::preview::robust_max;
use bdpm_output::stats::luminance;

/// FLIP's viewing condition: pixels per degree of visual angle. 67 is FLIP's default (a
/// 0.7 m wide 4K monitor seen from 0.7 m).
pub(crate) const PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// Decades of relative squared error the false-colour map spans, below the shared top.
pub(crate) const ERROR_DECADES: f64 = 3.0;

/// A rectangle of the image, pixels, (x, y) its top-left corner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Crop {
    pub(crate) x: u32,
    pub(crate) y: u32,
    pub(crate) w: u32,
    pub(crate) h: u32,
}

impl Crop {
    /// Parses `x,y,w,h` (pixels, non-negative integers, w and h at least 1).
    pub(crate) fn parse(text: &str) -> Result<Crop, String> {
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        let bad = |why: &str| format!("--crop '{text}': {why}");
        if parts.len() != 4 {
            return Err(bad("expected x,y,w,h in pixels (4 integers)"));
        }
        let mut v = [0u32; 4];
        for (slot, (part, name)) in v.iter_mut().zip(parts.iter().zip(["x", "y", "w", "h"])) {
            *slot = part
                .parse()
                .map_err(|_| bad(&format!("{name} = '{part}' is not a whole number ≥ 0")))?;
        }
        if v[2] == 0 || v[3] == 0 {
            return Err(bad("w and h must be at least 1"));
        }
        Ok(Crop {
            x: v[0],
            y: v[1],
            w: v[2],
            h: v[3],
        })
    }

    /// Refuses a crop that leaves a `width`×`height` image.
    pub(crate) fn check(&self, (width, height): (u32, u32)) -> Result<(), String> {
        let inside = self.x as u64 + self.w as u64 <= width as u64
            && self.y as u64 + self.h as u64 <= height as u64;
        if inside {
            Ok(())
        } else {
            Err(format!(
                "--crop {},{},{},{}: reaches past the {width}x{height} image",
                self.x, self.y, self.w, self.h
            ))
        }
    }
}

/// One image to compare: its name in the figure, its mean radiance per pixel
/// (W·m⁻²·sr⁻¹, row-major from the top) and the time it took, s, when known.
#[derive(Clone, Debug)]
pub(crate) struct Entry {
    pub(crate) name: String,
    pub(crate) rgb: Vec<DVec3>,
    pub(crate) seconds: Option<f64>,
}

/// What a figure is made of.
pub(crate) struct Inputs {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// The reference's mean radiance per pixel, W·m⁻²·sr⁻¹.
    pub(crate) reference: Vec<DVec3>,
    /// The reference's own rel. RMSE (its standard error's, over its mean luminance), when
    /// known: the numbers under the images include it, and it says how far they can be trusted.
    pub(crate) reference_error: Option<f64>,
    pub(crate) entries: Vec<Entry>,
    /// Crops given; when empty, `auto_crops` are chosen ([`worst_regions`]).
    pub(crate) crops: Vec<Crop>,
    pub(crate) auto_crops: usize,
}

/// One compared image, ready to draw.
pub(crate) struct Panel {
    pub(crate) name: String,
    pub(crate) seconds: Option<f64>,
    /// Tonemapped, 8-bit sRGB, 3 bytes a pixel.
    pub(crate) srgb: Vec<u8>,
    /// Relative squared error in false colour (viridis, log scale, [`Figure::error_top`]).
    pub(crate) error_map: Vec<u8>,
    /// FLIP per pixel in FLIP's magma map (0 black … 1 light yellow).
    pub(crate) flip_map: Vec<u8>,
    /// rel. RMSE of luminance: the RMSE over the reference's mean luminance.
    pub(crate) rel_rmse: f64,
    /// relMSE of luminance ([`rel_mse`]).
    pub(crate) rel_mse: f64,
    /// The mean of FLIP's per-pixel error, in [0, 1].
    pub(crate) flip_mean: f64,
}

/// A figure: the reference and the panels at one exposure, the crops and the maps' scales.
pub(crate) struct Figure {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// The factor every radiance is multiplied by before the sRGB curve, sr·m²·W⁻¹.
    pub(crate) exposure: f64,
    pub(crate) reference: Vec<u8>,
    /// The reference's own rel. RMSE, when known ([`Inputs::reference_error`]).
    pub(crate) reference_error: Option<f64>,
    pub(crate) panels: Vec<Panel>,
    pub(crate) crops: Vec<Crop>,
    /// Whether the crops were chosen automatically.
    pub(crate) crops_auto: bool,
    /// The top of the relative-squared-error colour scale: the largest 99th percentile over
    /// the images; the scale spans [`ERROR_DECADES`] decades below it.
    pub(crate) error_top: f64,
}

/// Linear → sRGB transfer function, in [0, 1].
fn srgb(x: f64) -> f64 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// The exposure that maps the reference's 99th-percentile luminance to 1, as a render's
/// preview does for its own image (1 for a black reference).
pub(crate) fn exposure(reference: &[DVec3]) -> f64 {
    let top = robust_max(&reference.iter().map(|c| luminance(*c)).collect::<Vec<_>>());
    if top > 0.0 { 1.0 / top } else { 1.0 }
}

/// `rgb` × `exposure`, clamped and sRGB-encoded, 8 bits per channel.
pub(crate) fn tonemap(rgb: &[DVec3], exposure: f64) -> Vec<u8> {
    rgb.iter()
        .flat_map(|c| [c.x, c.y, c.z])
        .map(|v| (srgb(v * exposure) * 255.0 + 0.5) as u8)
        .collect()
}

/// Per-pixel relative squared error of luminance, (I − R)²/(R² + ε), ε = 0.01·mean(R)²: the
/// terms whose mean is relMSE.
pub(crate) fn relative_squared_errors(image: &[f64], reference: &[f64]) -> Vec<f64> {
    let eps = rel_epsilon(reference);
    image
        .iter()
        .zip(reference)
        .map(|(i, r)| (i - r).powi(2) / (r * r + eps))
        .collect()
}

/// The colour of relative squared error `e` on the log scale from `top`·10^−decades to `top`.
pub(crate) fn error_colour(e: f64, top: f64) -> [u8; 3] {
    let t = if e > 0.0 && top > 0.0 {
        1.0 + (e / top).log10() / ERROR_DECADES
    } else {
        0.0
    };
    ColourMap::Viridis.colour(t)
}

/// The ticks of the error scale: (position in [0, 1], label) at every decade.
pub(crate) fn error_ticks(top: f64) -> Vec<(f64, String)> {
    (0..=ERROR_DECADES as i32)
        .map(|k| {
            let v = top * 10f64.powi(-k);
            (1.0 - k as f64 / ERROR_DECADES, format_value(v))
        })
        .collect()
}

/// FLIP between two 8-bit sRGB images: the per-pixel error in [0, 1] and its mean (FLIP's
/// pooled mean, the single number its authors recommend).
pub(crate) fn flip(reference: &[u8], test: &[u8], (width, height): (u32, u32)) -> (Vec<f32>, f64) {
    let r = nv_flip::FlipImageRgb8::with_data(width, height, reference);
    let t = nv_flip::FlipImageRgb8::with_data(width, height, test);
    let map = nv_flip::flip(r, t, PIXELS_PER_DEGREE);
    let mean = nv_flip::FlipPool::from_image(&map).mean() as f64;
    (map.to_vec(), mean)
}

/// FLIP's own magma colour map applied to a per-pixel FLIP error.
pub(crate) fn flip_colours(map: &[f32], (width, height): (u32, u32)) -> Vec<u8> {
    nv_flip::FlipImageFloat::with_data(width, height, map)
        .apply_color_lut(&nv_flip::magma_lut())
        .to_vec()
}

/// The `count` non-overlapping `side`×`side` windows with the largest sum of `score`
/// (a `width`-wide row-major map), largest first; a summed-area table makes each window
/// sum O(1).
pub(crate) fn worst_regions(score: &[f64], width: u32, count: usize, side: u32) -> Vec<Crop> {
    let (w, h) = (width as usize, score.len() / width.max(1) as usize);
    let side = (side as usize).min(w).min(h).max(1);
    let mut sat = vec![0.0f64; (w + 1) * (h + 1)];
    for y in 0..h {
        for x in 0..w {
            let s = if score[y * w + x].is_finite() {
                score[y * w + x]
            } else {
                0.0
            };
            sat[(y + 1) * (w + 1) + x + 1] =
                s + sat[y * (w + 1) + x + 1] + sat[(y + 1) * (w + 1) + x] - sat[y * (w + 1) + x];
        }
    }
    let sum = |x: usize, y: usize| {
        let (x1, y1) = (x + side, y + side);
        sat[y1 * (w + 1) + x1] - sat[y * (w + 1) + x1] - sat[y1 * (w + 1) + x]
            + sat[y * (w + 1) + x]
    };
    let mut chosen: Vec<Crop> = Vec::new();
    for _ in 0..count {
        let overlaps = |x: usize, y: usize| {
            chosen.iter().any(|c| {
                x < (c.x + c.w) as usize
                    && (c.x as usize) < x + side
                    && y < (c.y + c.h) as usize
                    && (c.y as usize) < y + side
            })
        };
        let mut best: Option<(f64, usize, usize)> = None;
        for y in 0..=h - side {
            for x in 0..=w - side {
                let s = sum(x, y);
                if best.is_none_or(|b| s > b.0) && !overlaps(x, y) {
                    best = Some((s, x, y));
                }
            }
        }
        let Some((_, x, y)) = best else { break };
        let side = side as u32;
        chosen.push(Crop {
            x: x as u32,
            y: y as u32,
            w: side,
            h: side,
        });
    }
    chosen
}

/// The own rel. RMSE of a reference with standard errors `stderr` (W·m⁻²·sr⁻¹ per pixel):
/// √(mean over pixels of the luminance of the standard error, squared) over the mean luminance
/// of `reference` (an upper bound for coloured pixels, as `study`'s floor).
pub(crate) fn reference_error(reference: &[DVec3], stderr: &[DVec3]) -> f64 {
    let var: Vec<f64> = stderr.iter().map(|c| luminance(*c).powi(2)).collect();
    let lum: Vec<f64> = reference.iter().map(|c| luminance(*c)).collect();
    mean(&var).sqrt() / mean(&lum)
}

/// Computes the figure: exposure, tonemapped images, metrics, maps and crops.
pub(crate) fn build(inputs: Inputs) -> Figure {
    let size = (inputs.width, inputs.height);
    let exposure = exposure(&inputs.reference);
    let reference = tonemap(&inputs.reference, exposure);
    let ref_lum: Vec<f64> = inputs.reference.iter().map(|c| luminance(*c)).collect();
    let ref_mean = mean(&ref_lum);
    let errors: Vec<Vec<f64>> = inputs
        .entries
        .iter()
        .map(|e| {
            let lum: Vec<f64> = e.rgb.iter().map(|c| luminance(*c)).collect();
            relative_squared_errors(&lum, &ref_lum)
        })
        .collect();
    let error_top = errors.iter().map(|e| robust_max(e)).fold(0.0, f64::max);
    let panels = inputs
        .entries
        .iter()
        .zip(&errors)
        .map(|(e, err)| {
            let lum: Vec<f64> = e.rgb.iter().map(|c| luminance(*c)).collect();
            let srgb = tonemap(&e.rgb, exposure);
            let (flip_map, flip_mean) = flip(&reference, &srgb, size);
            Panel {
                name: e.name.clone(),
                seconds: e.seconds,
                error_map: err
                    .iter()
                    .flat_map(|v| error_colour(*v, error_top))
                    .collect(),
                flip_map: flip_colours(&flip_map, size),
                srgb,
                rel_rmse: rmse(&lum, &ref_lum) / ref_mean,
                rel_mse: rel_mse(&lum, &ref_lum),
                flip_mean,
            }
        })
        .collect();
    let crops_auto = inputs.crops.is_empty();
    let crops = if crops_auto {
        let total: Vec<f64> = (0..ref_lum.len())
            .map(|i| errors.iter().map(|e| e[i]).sum())
            .collect();
        let side = (inputs.width.min(inputs.height) / 6).max(4);
        worst_regions(&total, inputs.width, inputs.auto_crops, side)
    } else {
        inputs.crops
    };
    Figure {
        width: inputs.width,
        height: inputs.height,
        exposure,
        reference,
        reference_error: inputs.reference_error,
        panels,
        crops,
        crops_auto,
        error_top,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crops_parse_and_are_checked_against_the_image() {
        let c = Crop::parse("1, 2,3,4").unwrap();
        assert_eq!((c.x, c.y, c.w, c.h), (1, 2, 3, 4));
        for bad in ["1,2,3", "1,2,3,x", "1,2,0,4", "-1,2,3,4", "1,2,3,4,5"] {
            let e = Crop::parse(bad).unwrap_err();
            assert!(e.starts_with(&format!("--crop '{bad}'")), "{e}");
        }
        assert!(c.check((4, 6)).is_ok());
        assert!(c.check((3, 6)).unwrap_err().contains("3x6"));
        assert!(c.check((4, 5)).is_err());
    }

    #[test]
    fn one_exposure_from_the_reference_and_srgb() {
        // 100 pixels of luminance 0..99 (grey): the 99th percentile is 98.
        let r: Vec<DVec3> = (0..100).map(|i| DVec3::splat(i as f64)).collect();
        assert!((exposure(&r) - 1.0 / 98.0).abs() < 1e-12);
        assert_eq!(
            tonemap(&[DVec3::new(0.0, 0.5, 2.0)], 1.0),
            vec![0, 188, 255]
        );
        assert_eq!(exposure(&[DVec3::ZERO]), 1.0);
        // Standard errors (0.1, 0.3) of grey pixels 1 and 3: √((0.01 + 0.09)/2) / 2.
        let own = reference_error(
            &[DVec3::ONE, DVec3::splat(3.0)],
            &[DVec3::splat(0.1), DVec3::splat(0.3)],
        );
        assert!((own - 0.05f64.sqrt() / 2.0).abs() < 1e-12, "{own}");
    }

    #[test]
    fn worst_regions_find_the_planted_blocks_without_overlap() {
        let w = 20;
        let mut score = vec![0.01; w * 16];
        for (x0, y0, v) in [(12, 3, 5.0), (2, 10, 2.0)] {
            for y in y0..y0 + 4 {
                for x in x0..x0 + 4 {
                    score[y * w + x] = v;
                }
            }
        }
        let c = worst_regions(&score, w as u32, 3, 4);
        assert_eq!(c.len(), 3);
        assert_eq!((c[0].x, c[0].y), (12, 3));
        assert_eq!((c[1].x, c[1].y), (2, 10));
        for (i, a) in c.iter().enumerate() {
            for b in &c[..i] {
                let apart =
                    a.x >= b.x + b.w || b.x >= a.x + a.w || a.y >= b.y + b.h || b.y >= a.y + a.h;
                assert!(apart, "{a:?} overlaps {b:?}");
            }
        }
    }

    #[test]
    fn relative_errors_and_flip_of_known_images() {
        // Reference luminance (0, 2): ε = 0.01; errors 1 and 1.
        let e = relative_squared_errors(&[1.0, 3.0], &[0.0, 2.0]);
        assert!((e[0] - 100.0).abs() < 1e-9 && (e[1] - 1.0 / 4.01).abs() < 1e-12);
        assert_eq!(error_colour(10.0, 10.0), ColourMap::Viridis.colour(1.0));
        assert_eq!(error_colour(0.01, 10.0), ColourMap::Viridis.colour(0.0));
        // FLIP of an image against itself is 0; against its negative, large.
        let img: Vec<u8> = (0..16 * 16 * 3).map(|i| (i * 7 % 256) as u8).collect();
        let (map, m) = flip(&img, &img, (16, 16));
        assert_eq!(map.len(), 256);
        assert!(m.abs() < 1e-6, "{m}");
        let neg: Vec<u8> = img.iter().map(|v| 255 - v).collect();
        assert!(flip(&img, &neg, (16, 16)).1 > 0.3);
    }
}
