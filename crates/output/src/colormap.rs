//! False-colour images with a legend: a perceptual and a diverging colour map (plotters'
//! viridis, and ColorBrewer's RdBu through plotters' derived colour map), and the layout of a
//! map (upscaled when small, so that the legend stays legible) beside a colour bar with
//! numeric ticks and a title, drawn with plotters in DejaVu Sans. Used by the noise map of
//! `bdpm render`, the weight map of `bdpm weights` and the ratio maps of `bdpm predict`.
use std::sync::LazyLock;

use plotters::prelude::*;
use plotters::style::colors::colormaps::{DerivedColorMap, ViridisRGB};
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::font::register_font;
use crate::raster::Canvas;

/// Panel background and text colours.
const PANEL: RGBColor = RGBColor(24, 24, 24);
const TEXT: RGBColor = RGBColor(235, 235, 235);

/// ColorBrewer RdBu, reversed: blue below the midpoint, white at it, red above; for signed
/// quantities such as a log ratio.
static DIVERGING: LazyLock<DerivedColorMap<RGBColor>> = LazyLock::new(|| {
    DerivedColorMap::new(&[
        RGBColor(0x05, 0x30, 0x61),
        RGBColor(0x21, 0x66, 0xac),
        RGBColor(0x43, 0x93, 0xc3),
        RGBColor(0x92, 0xc5, 0xde),
        RGBColor(0xd1, 0xe5, 0xf0),
        RGBColor(0xf7, 0xf7, 0xf7),
        RGBColor(0xfd, 0xdb, 0xc7),
        RGBColor(0xf4, 0xa5, 0x82),
        RGBColor(0xd6, 0x60, 0x4d),
        RGBColor(0xb2, 0x18, 0x2b),
        RGBColor(0x67, 0x00, 0x1f),
    ])
});

/// A colour map from t ∈ [0, 1] to an sRGB colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColourMap {
    /// Matplotlib's viridis: perceptually uniform, monotonic in lightness, readable by
    /// colour-blind viewers and in grey print. NaN gives the bottom colour.
    Viridis,
    /// Blue–white–red, white at t = ½. NaN gives the white midpoint.
    Diverging,
}

impl ColourMap {
    /// The colour at `t` (clamped to [0, 1]).
    pub fn colour(self, t: f64) -> [u8; 3] {
        // plotters' interpolation panics on NaN (it converts the position to an index).
        let (nan, map): (f64, &dyn Fn(f64) -> RGBColor) = match self {
            ColourMap::Viridis => (0.0, &|t| ViridisRGB::get_color(t)),
            ColourMap::Diverging => (0.5, &|t| DIVERGING.get_color(t)),
        };
        let t = if t.is_nan() { nan } else { t.clamp(0.0, 1.0) };
        let RGBColor(r, g, b) = map(t);
        [r, g, b]
    }
}

/// What the colour bar shows.
pub struct Legend {
    /// Lines of text above the bar (quantity, unit, scale).
    pub title: Vec<String>,
    /// Ticks: position on the bar (0 = bottom colour, 1 = top colour) and label.
    pub ticks: Vec<(f64, String)>,
}

/// A map laid out on a canvas: where its pixels went, so that callers can draw marks on it.
pub struct Layout {
    /// The image: the map on the left, the legend panel on its right.
    pub canvas: Canvas,
    /// Image pixels per map pixel.
    pub scale: u32,
}

impl Layout {
    /// The canvas pixel at the centre of map pixel (x, y).
    pub fn centre(&self, x: u32, y: u32) -> (i64, i64) {
        let s = self.scale as i64;
        (x as i64 * s + s / 2, y as i64 * s + s / 2)
    }

    /// Marks map pixel (x, y) with a cross in `colour`, outlined in `outline` so that it stays
    /// visible on any colour of the map.
    pub fn mark(&mut self, (x, y): (u32, u32), colour: [u8; 3], outline: [u8; 3]) {
        let (cx, cy) = self.centre(x, y);
        let arm = (3 * self.scale as i64).max(6);
        let half = self.scale as i64 / 3;
        for (c, grow) in [(outline, 1), (colour, 0)] {
            for d in -arm - grow..=arm + grow {
                for t in -half - grow..=half + grow {
                    self.canvas.set(cx + d, cy + t, c);
                    self.canvas.set(cx + t, cy + d, c);
                }
            }
        }
    }
}

/// The smallest map side after upscaling: small renders (e.g. 24×24 test images) are enlarged
/// by an integer factor so that the map is not dwarfed by its legend.
const MIN_MAP_SIDE: u32 = 160;
/// The longest map side that upscaling may produce.
const MAX_UPSCALED_SIDE: u32 = 2048;
/// Height of the colour bar, in text-scale units, at least.
const MIN_BAR_HEIGHT: u32 = 96;
/// Text height at text scale 1, pixels.
const FONT_PX: u32 = 12;

fn draw_err<E: std::fmt::Display>(e: E) -> String {
    format!("cannot draw the legend: {e}")
}

/// Lays out `colours` (a `width`×`height` map of sRGB colours) upscaled by an integer factor
/// when small, with `legend` drawn in a panel on its right: the colour bar (drawn with `cmap`
/// from 0 at the bottom to 1 at the top) and tick labels beside it.
pub fn compose(
    width: u32,
    height: u32,
    colours: &[[u8; 3]],
    legend: &Legend,
    cmap: ColourMap,
) -> Result<Layout, String> {
    register_font();
    // Capped so that a long thin render does not become a huge image.
    let scale = MIN_MAP_SIDE
        .div_ceil(width.min(height).max(1))
        .min(MAX_UPSCALED_SIDE / width.max(height).max(1))
        .clamp(1, 8);
    let (map_w, map_h) = (width * scale, height * scale);
    // Larger images get larger text, so that labels keep a similar size relative to the map.
    let ts = (1 + map_h / 600).min(4);
    let font = ("sans-serif", (FONT_PX * ts) as f64).into_font();
    let text_w = |s: &String| font.box_size(s).map_or(0, |(w, _)| w);
    let line = (FONT_PX + 4) * ts;
    let pad = 6 * ts;
    let bar_w = 10 * ts;
    let tick_w = 3 * ts;
    let label_w = legend
        .ticks
        .iter()
        .map(|(_, l)| text_w(l))
        .max()
        .unwrap_or(0);
    let title_w = legend.title.iter().map(text_w).max().unwrap_or(0);
    let panel_w = (bar_w + tick_w + label_w).max(title_w) + 2 * pad;
    let title_h = legend.title.len() as u32 * line;
    let min_h = pad + title_h + pad + MIN_BAR_HEIGHT * ts + pad + line / 2;
    let (canvas_w, canvas_h) = (map_w + panel_w, map_h.max(min_h));
    let mut rgb = vec![0u8; canvas_w as usize * canvas_h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (canvas_w, canvas_h)).into_drawing_area();
        root.fill(&PANEL).map_err(draw_err)?;
        let (map, panel) = root.split_horizontally(map_w);
        for (x, y) in (0..map_h).flat_map(|y| (0..map_w).map(move |x| (x, y))) {
            let [r, g, b] = colours[(y / scale * width + x / scale) as usize];
            map.draw_pixel((x as i32, y as i32), &RGBColor(r, g, b))
                .map_err(draw_err)?;
        }
        let (px, pad) = (pad as i32, pad as i32);
        let style = font.color(&TEXT);
        for (i, l) in legend.title.iter().enumerate() {
            panel
                .draw_text(l, &style, (px, pad + (i as u32 * line) as i32))
                .map_err(draw_err)?;
        }
        // The bar leaves half a text line below and above, so the end labels fit.
        let bar_top = pad + title_h as i32 + pad;
        let bar_bottom = canvas_h as i32 - pad - (line / 2) as i32;
        let bar_h = (bar_bottom - bar_top).max(1);
        let (bar_w, tick_w) = (bar_w as i32, tick_w as i32);
        for y in bar_top..=bar_bottom {
            let [r, g, b] = cmap.colour((bar_bottom - y) as f64 / bar_h as f64);
            let row = Rectangle::new([(px, y), (px + bar_w, y + 1)], RGBColor(r, g, b).filled());
            panel.draw(&row).map_err(draw_err)?;
        }
        let label = style.pos(Pos::new(HPos::Left, VPos::Center));
        for (t, text) in &legend.ticks {
            let y = bar_bottom - (t.clamp(0.0, 1.0) * bar_h as f64).round() as i32;
            // The tick is a notch cut into the bar's right edge rather than a dash beside it,
            // which would read as a minus sign in front of the label.
            panel
                .draw(&Rectangle::new(
                    [(px + bar_w - tick_w, y), (px + bar_w, y + ts as i32)],
                    PANEL.filled(),
                ))
                .map_err(draw_err)?;
            panel
                .draw_text(text, &label, (px + bar_w + tick_w, y))
                .map_err(draw_err)?;
        }
        root.present().map_err(draw_err)?;
    }
    Ok(Layout {
        canvas: Canvas {
            width: canvas_w,
            height: canvas_h,
            rgb,
        },
        scale,
    })
}

/// A short label for `v`: plain decimals with three significant digits for 0.01 ≤ |v| < 10⁴,
/// otherwise scientific notation (`1.5e-4`), without trailing zeros.
pub fn format_value(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if (0.01..1e4).contains(&a) {
        let decimals = (2 - a.log10().floor() as i32).clamp(0, 4) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let s = format!("{v:.1e}");
        match s.split_once('e') {
            Some((m, e)) if m.contains('.') => {
                let m = m.trim_end_matches('0').trim_end_matches('.');
                format!("{m}e{e}")
            }
            _ => s,
        }
    }
}

/// Ticks at round values (1, 2 or 5 × 10ᵏ apart) on a linear bar from 0 to `max`, plus `max`
/// itself at the top; round ticks too close to the top label are left out.
pub fn linear_ticks(max: f64) -> Vec<(f64, String)> {
    if !(max.is_finite() && max > 0.0) {
        return vec![(0.0, "0".into())];
    }
    let raw = max / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let mut ticks = Vec::new();
    let mut k = 0.0;
    while k * step < max * 0.88 {
        ticks.push(((k * step) / max, format_value(k * step)));
        k += 1.0;
    }
    ticks.push((1.0, format_value(max)));
    ticks
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_maps_end_and_clamp() {
        let v = ColourMap::Viridis;
        assert_eq!(v.colour(0.0), [68, 1, 84]);
        assert_eq!(v.colour(1.0), [254, 232, 37]);
        assert_eq!(v.colour(-3.0), v.colour(0.0));
        assert_eq!(v.colour(f64::NAN), v.colour(0.0));
        let d = ColourMap::Diverging;
        assert_eq!(d.colour(0.5), [0xf7, 0xf7, 0xf7]);
        assert_eq!(d.colour(f64::NAN), [0xf7, 0xf7, 0xf7]);
        assert_eq!(d.colour(-1.0), [0x05, 0x30, 0x61]);
        assert_eq!(d.colour(2.0), [0x67, 0x00, 0x1f]);
    }

    #[test]
    fn values_format_compactly() {
        assert_eq!(format_value(0.0), "0");
        assert_eq!(format_value(0.125), "0.125");
        assert_eq!(format_value(0.015), "0.015");
        assert_eq!(format_value(0.5), "0.5");
        assert_eq!(format_value(12.345), "12.3");
        assert_eq!(format_value(0.00012), "1.2e-4");
        assert_eq!(format_value(0.001), "1e-3");
        assert_eq!(format_value(25000.0), "2.5e4");
    }

    #[test]
    fn linear_ticks_are_round_and_end_at_max() {
        let t = linear_ticks(0.93);
        let labels: Vec<&str> = t.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["0", "0.2", "0.4", "0.6", "0.8", "0.93"]);
        assert_eq!(t.last().map(|x| x.0), Some(1.0));
        assert_eq!(linear_ticks(0.0).len(), 1);
    }

    #[test]
    fn small_maps_are_upscaled_and_legend_fits() {
        let colours = vec![[1, 2, 3]; 24 * 24];
        let legend = Legend {
            title: vec!["sqrt V".into()],
            ticks: linear_ticks(1.0),
        };
        let l = compose(24, 24, &colours, &legend, ColourMap::Viridis).expect("drawn");
        assert_eq!(l.scale, 7);
        assert!(l.canvas.width > 24 * 7 && l.canvas.height >= 24 * 7);
        assert_eq!(&l.canvas.rgb[0..3], &[1, 2, 3]);
        assert_eq!(l.centre(1, 0), (10, 3));
        // The legend's text is drawn: the panel holds colours other than its own and the bar's.
        let thin = compose(
            1024,
            8,
            &vec![[0; 3]; 1024 * 8],
            &legend,
            ColourMap::Viridis,
        );
        assert_eq!(thin.expect("drawn").scale, 2);
        let text_like = l
            .canvas
            .rgb
            .chunks(3)
            .filter(|p| p[0] > 200 && p[1] > 200 && p[2] > 200);
        assert!(text_like.count() > 20);
    }
}
