//! False-colour images with a legend: a perceptual and a diverging colour map, an RGB canvas,
//! and the layout of a map (upscaled when small, so that the legend text stays legible) beside a
//! colour bar with numeric ticks. Used by the noise map of `bdpm render`, the weight map of
//! `bdpm weights` and the ratio map of `bdpm predict`.
use crate::font;

/// Matplotlib's viridis at t = 0, 0.1, …, 1 (sRGB): perceptually uniform, monotonic in
/// lightness, readable by colour-blind viewers and in grey print.
const VIRIDIS: [[u8; 3]; 11] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x24, 0x75],
    [0x41, 0x44, 0x87],
    [0x35, 0x5f, 0x8d],
    [0x2a, 0x78, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x22, 0xa8, 0x84],
    [0x44, 0xbf, 0x70],
    [0x7a, 0xd1, 0x51],
    [0xbd, 0xdf, 0x26],
    [0xfd, 0xe7, 0x25],
];

/// Panel background and text colours.
const PANEL: [u8; 3] = [24, 24, 24];
const TEXT: [u8; 3] = [235, 235, 235];

/// The viridis colour at `t` ∈ [0, 1] (clamped; NaN gives the bottom colour), by linear
/// interpolation between the control points.
pub(crate) fn viridis(t: f64) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    interpolate(&VIRIDIS, t)
}

/// A diverging blue–white–red map (ColorBrewer RdBu, reversed) at t = 0, 0.1, …, 1: blue
/// below the midpoint, white at it, red above; for signed quantities such as a log ratio.
const DIVERGING: [[u8; 3]; 11] = [
    [0x05, 0x30, 0x61],
    [0x21, 0x66, 0xac],
    [0x43, 0x93, 0xc3],
    [0x92, 0xc5, 0xde],
    [0xd1, 0xe5, 0xf0],
    [0xf7, 0xf7, 0xf7],
    [0xfd, 0xdb, 0xc7],
    [0xf4, 0xa5, 0x82],
    [0xd6, 0x60, 0x4d],
    [0xb2, 0x18, 0x2b],
    [0x67, 0x00, 0x1f],
];

/// The diverging colour at `t` ∈ [0, 1] (clamped; NaN gives the white midpoint): t = ½ is
/// white, 0 dark blue, 1 dark red.
pub(crate) fn diverging(t: f64) -> [u8; 3] {
    let t = if t.is_nan() { 0.5 } else { t.clamp(0.0, 1.0) };
    interpolate(&DIVERGING, t)
}

/// Linear interpolation between 11 equally spaced control colours.
fn interpolate(points: &[[u8; 3]; 11], t: f64) -> [u8; 3] {
    let x = t * (points.len() - 1) as f64;
    let i = (x.floor() as usize).min(points.len() - 2);
    let f = x - i as f64;
    let (a, b) = (points[i], points[i + 1]);
    std::array::from_fn(|c| (a[c] as f64 + f * (b[c] as f64 - a[c] as f64)).round() as u8)
}

/// An 8-bit RGB image, row-major, row 0 at the top.
pub(crate) struct Canvas {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) rgb: Vec<u8>,
}

impl Canvas {
    /// A canvas filled with `colour`.
    pub(crate) fn new(width: u32, height: u32, colour: [u8; 3]) -> Canvas {
        let rgb = colour
            .iter()
            .copied()
            .cycle()
            .take(width as usize * height as usize * 3)
            .collect();
        Canvas { width, height, rgb }
    }

    /// Sets one pixel; coordinates outside the canvas are ignored (so callers may draw shapes
    /// that cross the border).
    pub(crate) fn set(&mut self, x: i64, y: i64, colour: [u8; 3]) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return;
        }
        let i = (y as usize * self.width as usize + x as usize) * 3;
        self.rgb[i..i + 3].copy_from_slice(&colour);
    }

    /// Fills the rectangle [x, x + w) × [y, y + h).
    pub(crate) fn fill(&mut self, x: i64, y: i64, w: u32, h: u32, colour: [u8; 3]) {
        for yy in y..y + h as i64 {
            for xx in x..x + w as i64 {
                self.set(xx, yy, colour);
            }
        }
    }

    /// Draws `text` with its top-left corner at (x, y).
    pub(crate) fn text(&mut self, text: &str, x: i64, y: i64, scale: u32, colour: [u8; 3]) {
        font::draw_text(text, x, y, scale, |px, py| self.set(px, py, colour));
    }
}

/// What the colour bar shows.
pub(crate) struct Legend {
    /// Lines of text above the bar (quantity, unit, scale).
    pub(crate) title: Vec<String>,
    /// Ticks: position on the bar (0 = bottom colour, 1 = top colour) and label.
    pub(crate) ticks: Vec<(f64, String)>,
}

/// A map laid out on a canvas: where its pixels went, so that callers can draw marks on it.
pub(crate) struct Layout {
    pub(crate) canvas: Canvas,
    /// Image pixels per map pixel.
    pub(crate) scale: u32,
}

impl Layout {
    /// The canvas pixel at the centre of map pixel (x, y).
    pub(crate) fn centre(&self, x: u32, y: u32) -> (i64, i64) {
        let s = self.scale as i64;
        (x as i64 * s + s / 2, y as i64 * s + s / 2)
    }
}

/// The smallest map side after upscaling: small renders (e.g. 24×24 test images) are enlarged
/// by an integer factor so that the map is not dwarfed by its legend.
const MIN_MAP_SIDE: u32 = 160;
/// The longest map side that upscaling may produce.
const MAX_UPSCALED_SIDE: u32 = 2048;
/// Height of the colour bar, in text-scale units, at least.
const MIN_BAR_HEIGHT: u32 = 96;

/// Lays out `colours` (a `width`×`height` map of sRGB colours) upscaled by an integer factor
/// when small, with `legend` drawn in a panel on its right: the colour bar (drawn with `cmap`
/// from 0 at the bottom to 1 at the top) and tick labels beside it.
pub(crate) fn compose(
    width: u32,
    height: u32,
    colours: &[[u8; 3]],
    legend: &Legend,
    cmap: impl Fn(f64) -> [u8; 3],
) -> Layout {
    // Capped so that a long thin render does not become a huge image.
    let scale = MIN_MAP_SIDE
        .div_ceil(width.min(height).max(1))
        .min(MAX_UPSCALED_SIDE / width.max(height).max(1))
        .clamp(1, 8);
    let (map_w, map_h) = (width * scale, height * scale);
    // Larger images get larger text, so that labels keep a similar size relative to the map.
    let ts = (1 + map_h / 600).min(4);
    let line = (font::GLYPH_H + 3) * ts;
    let pad = 6 * ts;
    let bar_w = 10 * ts;
    let tick_w = 3 * ts;
    let label_w = legend
        .ticks
        .iter()
        .map(|(_, l)| font::text_width(l, ts))
        .max()
        .unwrap_or(0);
    let title_w = legend
        .title
        .iter()
        .map(|l| font::text_width(l, ts))
        .max()
        .unwrap_or(0);
    let panel_w = (bar_w + tick_w + label_w).max(title_w) + 2 * pad;
    let title_h = legend.title.len() as u32 * line;
    let min_h = pad + title_h + pad + MIN_BAR_HEIGHT * ts + pad + line / 2;
    let canvas_h = map_h.max(min_h);
    let mut canvas = Canvas::new(map_w + panel_w, canvas_h, PANEL);

    for y in 0..map_h {
        for x in 0..map_w {
            let c = colours[(y / scale * width + x / scale) as usize];
            canvas.set(x as i64, y as i64, c);
        }
    }

    let px = map_w as i64 + pad as i64;
    for (i, l) in legend.title.iter().enumerate() {
        canvas.text(l, px, (pad + i as u32 * line) as i64, ts, TEXT);
    }
    // The bar leaves half a text line below and above, so the end labels fit on the canvas.
    let bar_top = (pad + title_h + pad) as i64;
    let bar_bottom = (canvas_h - pad - line / 2) as i64;
    let bar_h = (bar_bottom - bar_top).max(1);
    for y in bar_top..=bar_bottom {
        let t = (bar_bottom - y) as f64 / bar_h as f64;
        canvas.fill(px, y, bar_w, 1, cmap(t));
    }
    let glyph_h = (font::GLYPH_H * ts) as i64;
    for (t, label) in &legend.ticks {
        let y = bar_bottom - (t.clamp(0.0, 1.0) * bar_h as f64).round() as i64;
        // The tick is a notch cut into the bar's right edge rather than a dash beside it, which
        // would read as a minus sign in front of the label.
        canvas.fill(px + (bar_w - tick_w) as i64, y, tick_w, ts, PANEL);
        let lx = px + (bar_w + tick_w) as i64;
        canvas.text(label, lx, y - glyph_h / 2, ts, TEXT);
    }
    Layout { canvas, scale }
}

/// A short label for `v`: plain decimals with three significant digits for 0.01 ≤ |v| < 10⁴,
/// otherwise scientific notation (`1.5e-4`), without trailing zeros.
pub(crate) fn format_value(v: f64) -> String {
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
pub(crate) fn linear_ticks(max: f64) -> Vec<(f64, String)> {
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
    fn viridis_ends_and_clamps() {
        assert_eq!(viridis(0.0), VIRIDIS[0]);
        assert_eq!(viridis(1.0), VIRIDIS[10]);
        assert_eq!(viridis(-3.0), VIRIDIS[0]);
        assert_eq!(viridis(f64::NAN), VIRIDIS[0]);
        assert_eq!(viridis(0.05), [0x46, 0x13, 0x65]);
    }

    #[test]
    fn diverging_is_white_in_the_middle() {
        assert_eq!(diverging(0.5), [0xf7, 0xf7, 0xf7]);
        assert_eq!(diverging(f64::NAN), [0xf7, 0xf7, 0xf7]);
        assert_eq!(diverging(-1.0), DIVERGING[0]);
        assert_eq!(diverging(2.0), DIVERGING[10]);
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
        let l = compose(24, 24, &colours, &legend, viridis);
        assert_eq!(l.scale, 7);
        assert!(l.canvas.width > 24 * 7 && l.canvas.height >= 24 * 7);
        assert_eq!(&l.canvas.rgb[0..3], &[1, 2, 3]);
        assert_eq!(l.centre(1, 0), (10, 3));
        let thin = compose(1024, 8, &vec![[0; 3]; 1024 * 8], &legend, viridis);
        assert_eq!(thin.scale, 2);
    }
}
