//! Plots for `bdpm study`: error against time (log-log, one line per mode) and a bar chart of
//! one number per mode. Each plot is written twice from the same drawing code: a PNG through
//! plotters' bitmap backend, in the DejaVu Sans font that bdpm-output embeds and registers
//! (`bdpm_output::font`), so that no system font is needed; and an SVG, whose text the viewer
//! renders.
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use bdpm_output::files::write_atomic;
use bdpm_output::font::register_font;
use bdpm_output::raster::write_png_rgb8;

/// Pixel size of every plot.
const SIZE: (u32, u32) = (960, 640);

/// Tableau-10 colours: distinguishable, and readable on white.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The colour of series number `i`.
pub(crate) fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// One line of a plot: a name for the legend and its (x, y) points.
#[derive(Clone, Debug)]
pub(crate) struct Series {
    /// The name in the legend.
    pub name: String,
    /// The points, (x, y) in the plot's units; non-positive ones are left out on log axes.
    pub points: Vec<(f64, f64)>,
}

/// A log-log line plot.
#[derive(Clone, Debug)]
pub(crate) struct LogLogPlot {
    /// The caption above the plot.
    pub title: String,
    /// The x axis's description, unit included.
    pub x_label: String,
    /// The y axis's description, unit included.
    pub y_label: String,
    /// The lines, coloured in order.
    pub series: Vec<Series>,
    /// A labelled horizontal dashed line (e.g. the reference's own error).
    pub floor: Option<(String, f64)>,
}

/// A bar chart with one bar per named value.
#[derive(Clone, Debug)]
pub(crate) struct BarPlot {
    /// The caption above the chart.
    pub title: String,
    /// The y axis's description, unit included.
    pub y_label: String,
    /// The bars: name under the bar and its height.
    pub bars: Vec<(String, f64)>,
}

type Bitmap<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
type Svg<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// Writes `stem.png` (drawn by `png`) and `stem.svg` (drawn by `svg`): the same drawing code
/// instantiated for the two backends, which are different types.
fn write_both(
    stem: &Path,
    png: impl FnOnce(&Bitmap<'_>) -> Result<(), String>,
    svg: impl FnOnce(&Svg<'_>) -> Result<(), String>,
) -> Result<(), String> {
    register_font();
    let (w, h) = SIZE;
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        png(&root)?;
        root.present().map_err(err)?;
    }
    let png_path = stem.with_extension("png");
    write_png_rgb8(&png_path, w, h, &rgb).map_err(|e| format!("{}: {e}", png_path.display()))?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, (w, h)).into_drawing_area();
        svg(&root)?;
        root.present().map_err(err)?;
    }
    let svg_path = stem.with_extension("svg");
    write_atomic(&svg_path, text.as_bytes()).map_err(|e| format!("{}: {e}", svg_path.display()))
}

/// Writes `stem.png` and `stem.svg` of a log-log line plot.
pub(crate) fn write_loglog(stem: &Path, plot: &LogLogPlot) -> Result<(), String> {
    write_both(stem, |r| draw_loglog(r, plot), |r| draw_loglog(r, plot))
}

/// Writes `stem.png` and `stem.svg` of a bar chart.
pub(crate) fn write_bars(stem: &Path, plot: &BarPlot) -> Result<(), String> {
    write_both(stem, |r| draw_bars(r, plot), |r| draw_bars(r, plot))
}

fn err<E: std::fmt::Display>(e: E) -> String {
    format!("cannot draw the plot: {e}")
}

/// A log axis range that covers `values` (positive ones) with a little room on both sides.
fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() || hi <= 0.0 {
        return 0.1..10.0;
    }
    let (lo, hi) = if hi / lo < 1.5 {
        (lo / 1.5, hi * 1.5)
    } else {
        (lo, hi)
    };
    lo / 1.15..hi * 1.15
}

/// The labelled ticks of a log axis over `range`: every decade when the range spans four or
/// more, else 1, 2 and 5 times each power of ten, else 1…9 times; at least two, so that a
/// narrow range still has numbers on its axis (its ends, to two significant digits, when no
/// round value falls inside). Explicit ticks, because plotters' own on a log axis leave a
/// range within one decade unlabelled and crowd their light lines into bands.
pub(crate) fn log_ticks(range: &std::ops::Range<f64>) -> Vec<f64> {
    let (lo, hi) = (range.start, range.end);
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let (k0, k1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let within = |mantissas: &[f64]| -> Vec<f64> {
        (k0..=k1)
            .flat_map(|k| mantissas.iter().map(move |m| m * 10f64.powi(k)))
            .filter(|v| *v >= lo * (1.0 - 1e-9) && *v <= hi * (1.0 + 1e-9))
            .collect()
    };
    let decades = within(&[1.0]);
    let ticks = if decades.len() >= 4 {
        let step = decades.len().div_ceil(10);
        decades.into_iter().step_by(step).collect()
    } else {
        let coarse = within(&[1.0, 2.0, 5.0]);
        if coarse.len() >= 3 {
            coarse
        } else {
            within(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
        }
    };
    if ticks.len() >= 2 {
        return ticks;
    }
    let round2 = |v: f64| {
        let p = 10f64.powi(v.log10().floor() as i32 - 1);
        (v / p).round() * p
    };
    let mut ends = vec![round2(lo * 1.02), round2(hi / 1.02)];
    ends.extend(ticks);
    ends.sort_by(f64::total_cmp);
    ends.dedup();
    ends
}

/// Tick label of a log axis: short, no trailing zeros.
fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e4).contains(&a) {
        format!("{v:.0e}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

fn draw_loglog<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    plot: &LogLogPlot,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    let xs = log_range(
        plot.series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0)),
    );
    let ys = log_range(
        plot.series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .chain(plot.floor.iter().map(|f| f.1)),
    );
    let mut chart = ChartBuilder::on(root)
        .caption(&plot.title, ("sans-serif", 24))
        .margin(16)
        .x_label_area_size(56)
        .y_label_area_size(84)
        .build_cartesian_2d(
            xs.clone().log_scale().with_key_points(log_ticks(&xs)),
            ys.clone().log_scale().with_key_points(log_ticks(&ys)),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(&plot.x_label)
        .y_desc(&plot.y_label)
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 15))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(200, 200, 200))
        .draw()
        .map_err(err)?;
    for (i, s) in plot.series.iter().enumerate() {
        let c = colour(i);
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
            .map_err(err)?
            .label(&s.name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(3)));
        chart
            .draw_series(pts.iter().map(|p| Circle::new(*p, 3, c.filled())))
            .map_err(err)?;
    }
    if let Some((name, y)) = &plot.floor {
        let y = *y;
        if y > 0.0 && y.is_finite() {
            // A dashed line from short segments (plotters' DashedLineSeries needs more features).
            let (lo, hi) = (xs.start.ln(), xs.end.ln());
            let n = 60;
            let segs: Vec<Vec<(f64, f64)>> = (0..n)
                .step_by(2)
                .map(|k| {
                    let a = (lo + (hi - lo) * k as f64 / n as f64).exp();
                    let b = (lo + (hi - lo) * (k + 1) as f64 / n as f64).exp();
                    vec![(a, y), (b, y)]
                })
                .collect();
            chart
                .draw_series(
                    segs.into_iter()
                        .map(|s| PathElement::new(s, BLACK.stroke_width(1))),
                )
                .map_err(err)?
                .label(name)
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 8, y)], BLACK.stroke_width(1)));
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    Ok(())
}

fn draw_bars<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    plot: &BarPlot,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(err)?;
    let n = plot.bars.len().max(1) as i32;
    let top = plot
        .bars
        .iter()
        .map(|b| b.1)
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let top = if top > 0.0 { top * 1.15 } else { 1.0 };
    let names: Vec<String> = plot.bars.iter().map(|b| b.0.clone()).collect();
    let mut chart = ChartBuilder::on(root)
        .caption(&plot.title, ("sans-serif", 24))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(84)
        .build_cartesian_2d((0..n).into_segmented(), 0.0..top)
        .map_err(err)?;
    let label = |v: &SegmentValue<i32>| match v {
        SegmentValue::CenterOf(i) | SegmentValue::Exact(i) => {
            names.get(*i as usize).cloned().unwrap_or_default()
        }
        SegmentValue::Last => String::new(),
    };
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n as usize)
        .x_label_formatter(&label)
        .y_desc(&plot.y_label)
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 15))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(200, 200, 200))
        .draw()
        .map_err(err)?;
    chart
        .draw_series(
            Histogram::vertical(&chart)
                .margin(12)
                .style_func(|x, _| match x {
                    SegmentValue::CenterOf(i) | SegmentValue::Exact(i) => {
                        colour(*i as usize).filled()
                    }
                    SegmentValue::Last => BLACK.filled(),
                })
                .data(plot.bars.iter().enumerate().map(|(i, b)| (i as i32, b.1))),
        )
        .map_err(err)?;
    chart
        .draw_series(plot.bars.iter().enumerate().map(|(i, b)| {
            Text::new(
                format!("{:.3e}", b.1),
                (SegmentValue::CenterOf(i as i32), b.1),
                ("sans-serif", 14).into_font().color(&BLACK).pos(
                    plotters::style::text_anchor::Pos::new(
                        plotters::style::text_anchor::HPos::Center,
                        plotters::style::text_anchor::VPos::Bottom,
                    ),
                ),
            )
        }))
        .map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_label_every_range() {
        // Six decades: one tick per decade.
        assert_eq!(
            log_ticks(&(0.5..2e5)),
            vec![1.0, 10.0, 100.0, 1e3, 1e4, 1e5]
        );
        // Within two decades: 1, 2, 5 times each power of ten.
        let t = log_ticks(&(0.015..0.6));
        assert_eq!(t.len(), 5, "{t:?}");
        for (a, b) in t.iter().zip([0.02, 0.05, 0.1, 0.2, 0.5]) {
            assert!((a / b - 1.0).abs() < 1e-12, "{t:?}");
        }
        // Within a decade: every digit that falls inside.
        let t = log_ticks(&(0.031..0.068));
        assert_eq!(t.len(), 3, "{t:?}");
        // No round value inside: the ends, to two significant digits.
        let t = log_ticks(&(0.0312..0.0338));
        assert_eq!(t.len(), 2, "{t:?}");
        assert!(t.iter().all(|v| (0.0312..0.0338).contains(v)), "{t:?}");
        // Thirty decades: at most ten labels.
        assert!(log_ticks(&(1e-15..1e15)).len() <= 11);
        assert!(log_ticks(&(0.0..1.0)).is_empty());
    }
}
