//! The figure as one PNG, for a paper: the reference and the images side by side at one
//! exposure with the crops outlined, the numbers under each image, a row per crop (enlarged,
//! nearest neighbour), then a row of relative-error maps and a row of FLIP maps, each with its
//! colour scale in the reference's column. Text in DejaVu Sans through plotters, as the
//! lab's plots.
use plotters::prelude::*;

use crate::figure::{Crop, Figure, error_ticks};
use crate::plot::colour;
use bdpm_output::colormap::ColourMap;
use bdpm_output::font::register_font;
use bdpm_output::raster::Canvas;

/// Margin around the sheet and gap between cells, pixels.
const MARGIN: u32 = 12;
const GAP: u32 = 8;
/// Line heights, pixels: the title, a cell's label, a line of numbers.
const TITLE: u32 = 68;
const LABEL: u32 = 22;
const LINE: u32 = 18;
/// Lines of numbers under each image.
const NUMBER_LINES: u32 = 4;
/// The narrowest and the widest a column may be after integer upscaling, pixels.
const MIN_COLUMN: u32 = 256;
const MAX_COLUMN: u32 = 512;
/// The narrowest sheet, pixels: room for the title's lines beside one or two columns.
const MIN_WIDTH: u32 = 600;

/// Integer upscaling of the images so that a column is about [`MIN_COLUMN`] wide.
pub(crate) fn upscale(width: u32) -> u32 {
    let want = MIN_COLUMN.div_ceil(width.max(1));
    want.min((MAX_COLUMN / width.max(1)).max(1)).max(1)
}

/// Copies the `crop` of a `width`-wide sRGB image into the canvas at (x, y), scaled (nearest
/// neighbour) to `w`×`h`.
fn blit(
    canvas: &mut Canvas,
    src: &[u8],
    width: u32,
    crop: Crop,
    (x, y, w, h): (u32, u32, u32, u32),
) {
    for dy in 0..h {
        let sy = crop.y + (dy as u64 * crop.h as u64 / h as u64) as u32;
        for dx in 0..w {
            let sx = crop.x + (dx as u64 * crop.w as u64 / w as u64) as u32;
            let i = (sy as usize * width as usize + sx as usize) * 3;
            canvas.set(
                (x + dx) as i64,
                (y + dy) as i64,
                [src[i], src[i + 1], src[i + 2]],
            );
        }
    }
}

/// Draws a `thick`-pixel frame inside the rectangle (x, y, w, h).
fn frame(canvas: &mut Canvas, (x, y, w, h): (i64, i64, i64, i64), thick: i64, c: [u8; 3]) {
    for t in 0..thick {
        for i in x..x + w {
            canvas.set(i, y + t, c);
            canvas.set(i, y + h - 1 - t, c);
        }
        for j in y..y + h {
            canvas.set(x + t, j, c);
            canvas.set(x + w - 1 - t, j, c);
        }
    }
}

/// The crop's on-screen height in a column `column` wide, capped at twice the width.
fn crop_height(c: &Crop, column: u32) -> u32 {
    ((column as u64 * c.h as u64 / c.w as u64) as u32).clamp(1, 2 * column)
}

/// One row of maps: its title (", " separates lines), colour map, scale ticks and images.
type MapRow<'a> = (
    &'a str,
    &'a dyn Fn(f64) -> [u8; 3],
    Vec<(f64, String)>,
    Vec<&'a [u8]>,
);

/// A piece of text to draw: position (top-left), size and content.
struct Text {
    at: (i32, i32),
    size: u32,
    text: String,
}

/// A horizontal colour bar (colour at t from `colour_at`) with tick labels under it.
fn colour_bar(
    canvas: &mut Canvas,
    texts: &mut Vec<Text>,
    (x, y, w): (u32, u32, u32),
    colour_at: &dyn Fn(f64) -> [u8; 3],
    ticks: &[(f64, String)],
) {
    for dx in 0..w {
        let c = colour_at(dx as f64 / (w - 1).max(1) as f64);
        for dy in 0..16 {
            canvas.set((x + dx) as i64, (y + dy) as i64, c);
        }
    }
    for (t, label) in ticks {
        let tx = x as i64 + (t * (w - 1) as f64) as i64;
        for dy in 16..21 {
            canvas.set(tx, (y + dy) as i64, [0, 0, 0]);
        }
        // Centred under the tick, kept inside the bar's span.
        let half = label.chars().count() as i64 * 4;
        let lx = (tx - half).clamp(x as i64, (x + w) as i64 - 2 * half);
        texts.push(Text {
            at: (lx as i32, (y + 22) as i32),
            size: 14,
            text: label.clone(),
        });
    }
}

/// The numbers under an image, one line each.
pub(crate) fn number_lines(p: &crate::figure::Panel) -> Vec<String> {
    vec![
        format!("rel. RMSE {:.4}", p.rel_rmse),
        format!("relMSE {:.3e}", p.rel_mse),
        format!("FLIP mean {:.4}", p.flip_mean),
        p.seconds
            .map_or("time unknown".into(), |s| format!("time {s:.1} s")),
    ]
}

/// The lines under the reference: its own error, when known, which the numbers of the
/// images include.
pub(crate) fn reference_lines(fig: &Figure) -> Vec<String> {
    match fig.reference_error {
        Some(e) => vec![
            format!("own rel. RMSE {e:.4}"),
            "(from its standard error;".into(),
            "the numbers beside include it)".into(),
        ],
        None => vec!["own error unknown".into()],
    }
}

/// The two lines of the figure's title: the exposure and how the crops were chosen.
fn title(fig: &Figure) -> Vec<Text> {
    let title = [
        format!("One exposure for all: ×{:.4e} sr·m²/W, sRGB", fig.exposure),
        "(the reference's 99th-percentile luminance → 1).".to_string(),
        format!(
            "Crops: {}.",
            if fig.crops_auto {
                "the largest relative squared error summed over the images"
            } else {
                "as given"
            }
        ),
    ];
    title
        .into_iter()
        .enumerate()
        .map(|(l, text)| Text {
            at: (MARGIN as i32, (MARGIN + l as u32 * 20) as i32),
            size: 16,
            text,
        })
        .collect()
}

/// Lays the figure out on a canvas and lists the text to draw on it.
fn layout(fig: &Figure) -> (Canvas, Vec<Text>) {
    let s = upscale(fig.width);
    let (col, img_h) = (fig.width * s, fig.height * s);
    let cols = 1 + fig.panels.len() as u32;
    let crop_rows: u32 = fig.crops.iter().map(|c| crop_height(c, col) + GAP).sum();
    let width = (2 * MARGIN + cols * col + (cols - 1) * GAP).max(MIN_WIDTH);
    let height = MARGIN
        + TITLE
        + LABEL
        + img_h
        + NUMBER_LINES * LINE
        + GAP
        + crop_rows
        + 2 * (LABEL + img_h + GAP)
        + MARGIN;
    let mut canvas = Canvas {
        width,
        height,
        rgb: vec![255; width as usize * height as usize * 3],
    };
    let mut texts = title(fig);
    let x_of = |i: u32| MARGIN + i * (col + GAP);
    let full = whole(fig);
    let images: Vec<(&str, &[u8])> = std::iter::once(("reference", fig.reference.as_slice()))
        .chain(
            fig.panels
                .iter()
                .map(|p| (p.name.as_str(), p.srgb.as_slice())),
        )
        .collect();
    let mut y = MARGIN + TITLE;
    for (i, (name, img)) in images.iter().enumerate() {
        let x = x_of(i as u32);
        texts.push(Text {
            at: (x as i32, y as i32),
            size: 16,
            text: name.to_string(),
        });
        blit(
            &mut canvas,
            img,
            fig.width,
            full,
            (x, y + LABEL, col, img_h),
        );
        for (k, c) in fig.crops.iter().enumerate() {
            let r = (
                (x + c.x * s) as i64,
                (y + LABEL + c.y * s) as i64,
                (c.w * s) as i64,
                (c.h * s) as i64,
            );
            frame(&mut canvas, r, 2, colour(k).rgb().into());
        }
        let lines = if i > 0 {
            number_lines(&fig.panels[i - 1])
        } else {
            reference_lines(fig)
        };
        for (l, line) in lines.into_iter().enumerate() {
            texts.push(Text {
                at: (x as i32, (y + LABEL + img_h + 2 + l as u32 * LINE) as i32),
                size: 15,
                text: line,
            });
        }
    }
    y += LABEL + img_h + NUMBER_LINES * LINE + GAP;
    for (k, c) in fig.crops.iter().enumerate() {
        let h = crop_height(c, col);
        for (i, (_, img)) in images.iter().enumerate() {
            let x = x_of(i as u32);
            blit(&mut canvas, img, fig.width, *c, (x, y, col, h));
            frame(
                &mut canvas,
                (x as i64, y as i64, col as i64, h as i64),
                2,
                colour(k).rgb().into(),
            );
        }
        y += h + GAP;
    }
    maps(fig, &mut canvas, &mut texts, y);
    (canvas, texts)
}

/// The rows of relative-error and FLIP maps from height `y` down, their scales in the first
/// column.
fn maps(fig: &Figure, canvas: &mut Canvas, texts: &mut Vec<Text>, mut y: u32) {
    let s = upscale(fig.width);
    let (col, img_h) = (fig.width * s, fig.height * s);
    let x_of = |i: u32| MARGIN + i * (col + GAP);
    let full = whole(fig);
    let top = fig.error_top;
    let error_colour = move |t: f64| ColourMap::Viridis.colour(t);
    let magma = |t: f64| {
        let m = crate::figure::flip_colours(&[t as f32], (1, 1));
        [m[0], m[1], m[2]]
    };
    let flip_ticks: Vec<(f64, String)> = (0..=4)
        .map(|k| (k as f64 / 4.0, format!("{}", k as f64 / 4.0)))
        .collect();
    let rows: [MapRow<'_>; 2] = [
        (
            "relative squared error (I−R)²/(R²+ε), luminance, log scale",
            &error_colour,
            error_ticks(top),
            fig.panels.iter().map(|p| p.error_map.as_slice()).collect(),
        ),
        (
            "FLIP (on the sRGB images at 67 px/°), 0 = no visible difference",
            &magma,
            flip_ticks,
            fig.panels.iter().map(|p| p.flip_map.as_slice()).collect(),
        ),
    ];
    for (title, colour_at, ticks, images) in rows {
        let mut lines = title.split(", ");
        texts.push(Text {
            at: (MARGIN as i32, (y + LABEL) as i32),
            size: 15,
            text: lines.next().unwrap_or_default().to_string(),
        });
        for (l, line) in lines.enumerate() {
            texts.push(Text {
                at: (MARGIN as i32, (y + LABEL + (l as u32 + 1) * LINE) as i32),
                size: 15,
                text: line.to_string(),
            });
        }
        let bar = (MARGIN, y + LABEL + 4 * LINE, col - 16);
        colour_bar(canvas, texts, bar, colour_at, &ticks);
        for (i, img) in images.iter().enumerate() {
            let x = x_of(i as u32 + 1);
            texts.push(Text {
                at: (x as i32, y as i32),
                size: 16,
                text: fig.panels[i].name.clone(),
            });
            blit(canvas, img, fig.width, full, (x, y + LABEL, col, img_h));
        }
        y += LABEL + img_h + GAP;
    }
}

/// The figure as PNG bytes.
pub(crate) fn encode(fig: &Figure) -> Result<Vec<u8>, String> {
    let (mut canvas, texts) = layout(fig);
    register_font();
    {
        let err = |e: &dyn std::fmt::Display| format!("cannot draw the figure's text: {e}");
        let root = BitMapBackend::with_buffer(&mut canvas.rgb, (canvas.width, canvas.height))
            .into_drawing_area();
        for t in &texts {
            let style = ("sans-serif", t.size).into_font().color(&BLACK);
            root.draw_text(&t.text, &style, t.at).map_err(|e| err(&e))?;
        }
        root.present().map_err(|e| err(&e))?;
    }
    canvas.encode_png()
}

/// The crop that is the whole image.
fn whole(fig: &Figure) -> Crop {
    Crop {
        x: 0,
        y: 0,
        w: fig.width,
        h: fig.height,
    }
}
