//! The figure as one self-contained HTML page: a flip-book over the reference and the images
//! (keys 1…9 or ←/→ switch, `c`/`e`/`f` show the image, its relative-error map or its FLIP
//! map, `+`/`-` or the mouse wheel zoom, `0` resets), the crops of the image shown, and the
//! numbers. Everything is inline: the images as PNG data URIs, the style and the script, so
//! the page opens without a network and can be mailed as one file.
//!
//! The query `?keys=ArrowRight,e` dispatches those keys as `KeyboardEvent`s to the page's
//! own handler once it has loaded, and `?zoom=K` sets the starting zoom: the browser test
//! screenshots the page without and with a key press through them (a URL fragment that
//! selected an image directly would not exercise the handler).
use base64::Engine as _;
use serde_json::json;

use crate::figure::{Crop, Figure, error_ticks};
use crate::figure_sheet::{number_lines, reference_lines};
use bdpm_output::colormap::ColourMap;
use bdpm_output::raster::encode_png_rgb8;

/// Height of the page's header (title, buttons, the shown image's numbers), CSS pixels: the
/// image view starts this far from the top, at the left edge.
pub(crate) const VIEW_TOP: u32 = 96;

/// The longest side of the image view at the starting zoom, CSS pixels.
const VIEW_SIDE: u32 = 640;

/// The starting zoom: the largest whole factor that keeps the image within [`VIEW_SIDE`].
pub(crate) fn start_zoom(width: u32, height: u32) -> u32 {
    (VIEW_SIDE / width.max(height).max(1)).max(1)
}

fn data_uri(width: u32, height: u32, rgb: &[u8]) -> Result<String, String> {
    let png = encode_png_rgb8(width, height, rgb)?;
    Ok(format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(png)
    ))
}

/// A 256×1 strip of a colour map, for the page's colour scales.
fn strip(colour_at: impl Fn(f64) -> [u8; 3]) -> Result<String, String> {
    let rgb: Vec<u8> = (0..256).flat_map(|i| colour_at(i as f64 / 255.0)).collect();
    data_uri(256, 1, &rgb)
}

/// HTML-escapes text for element content and attribute values.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The page's data: one entry per image (the reference first) with its three views and its
/// numbers, the crops and the colour scales.
fn data(fig: &Figure) -> Result<serde_json::Value, String> {
    let (w, h) = (fig.width, fig.height);
    let mut images = vec![json!({
        "name": "reference",
        "views": { "c": data_uri(w, h, &fig.reference)? },
        "numbers": reference_lines(fig),
    })];
    for p in &fig.panels {
        images.push(json!({
            "name": p.name,
            "views": {
                "c": data_uri(w, h, &p.srgb)?,
                "e": data_uri(w, h, &p.error_map)?,
                "f": data_uri(w, h, &p.flip_map)?,
            },
            "numbers": number_lines(p),
        }));
    }
    let crops: Vec<_> = fig
        .crops
        .iter()
        .map(|Crop { x, y, w, h }| json!({ "x": x, "y": y, "w": w, "h": h }))
        .collect();
    let palette: Vec<String> = (0..fig.crops.len())
        .map(|k| {
            let (r, g, b) = plotters::style::Color::rgb(&crate::plot::colour(k));
            format!("rgb({r},{g},{b})")
        })
        .collect();
    let error_labels: Vec<String> = error_ticks(fig.error_top)
        .into_iter()
        .rev()
        .map(|t| t.1)
        .collect();
    Ok(json!({
        "width": w,
        "height": h,
        "zoom": start_zoom(w, h),
        "images": images,
        "crops": crops,
        "palette": palette,
        "scales": {
            "e": { "strip": strip(|t| ColourMap::Viridis.colour(t))?,
                   "title": "relative squared error (I−R)²/(R²+ε) of luminance, log scale",
                   "labels": error_labels },
            "f": { "strip": strip(|t| {
                       let m = crate::figure::flip_colours(&[t as f32], (1, 1));
                       [m[0], m[1], m[2]]
                   })?,
                   "title": "FLIP on the sRGB images at 67 px/° (0: no visible difference)",
                   "labels": ["0", "0.25", "0.5", "0.75", "1"] },
        },
    }))
}

const STYLE: &str = r#"
body { margin: 0; background: #1e1e1e; color: #eee; font: 14px sans-serif; }
#head { position: absolute; left: 0; top: 0; right: 0; height: VIEW_TOPpx; overflow: hidden;
        padding: 4px 8px; box-sizing: border-box; }
#head button { background: #333; color: #eee; border: 1px solid #555; margin-right: 4px; }
#head button.on { background: #eee; color: #111; }
#view { position: absolute; left: 0; top: VIEW_TOPpx; overflow: auto; background: #000; }
#view img { display: block; image-rendering: pixelated; }
.box { position: absolute; border: 2px solid; box-sizing: border-box; pointer-events: none; }
#below { position: absolute; left: 0; padding: 8px; }
.crop { display: inline-block; overflow: hidden; margin: 0 8px 8px 0; border: 2px solid;
        position: relative; }
.crop img { position: absolute; image-rendering: pixelated; }
#scale img { width: 256px; height: 12px; image-rendering: pixelated; vertical-align: middle; }
td, th { padding: 2px 10px; text-align: right; }
"#;

const SCRIPT: &str = r#"
const view = document.getElementById('view');
const img = document.getElementById('main');
let current = 0, mode = 'c', zoom = FIG.zoom;
const params = new URLSearchParams(location.search);
if (params.get('zoom')) zoom = Math.max(1, parseInt(params.get('zoom'), 10) || zoom);
view.style.width = (FIG.width * zoom) + 'px';
view.style.height = (FIG.height * zoom) + 'px';
document.getElementById('below').style.top = (VIEW_TOP + FIG.height * zoom + 8) + 'px';
const buttons = FIG.images.map((im, i) => {
  const b = document.createElement('button');
  b.textContent = (i + 1) + ' ' + im.name;
  b.onclick = () => show(i, mode);
  document.getElementById('buttons').appendChild(b);
  return b;
});
const boxes = FIG.crops.map((c, k) => {
  const d = document.createElement('div');
  d.className = 'box'; d.style.borderColor = FIG.palette[k];
  view.appendChild(d); return d;
});
const crops = FIG.crops.map((c, k) => {
  const d = document.createElement('div');
  d.className = 'crop'; d.style.borderColor = FIG.palette[k];
  const s = Math.max(1, Math.floor(192 / Math.max(c.w, c.h)));
  d.style.width = (c.w * s) + 'px'; d.style.height = (c.h * s) + 'px';
  const i = document.createElement('img');
  i.style.width = (FIG.width * s) + 'px';
  i.style.left = (-c.x * s) + 'px'; i.style.top = (-c.y * s) + 'px';
  d.appendChild(i); document.getElementById('crops').appendChild(d);
  return i;
});
function layout() {
  img.style.width = (FIG.width * zoom) + 'px';
  img.style.height = (FIG.height * zoom) + 'px';
  FIG.crops.forEach((c, k) => {
    const s = boxes[k].style;
    s.left = (c.x * zoom) + 'px'; s.top = (c.y * zoom) + 'px';
    s.width = (c.w * zoom) + 'px'; s.height = (c.h * zoom) + 'px';
  });
  document.getElementById('zoom').textContent = 'zoom ' + zoom + '×';
}
function show(i, m) {
  current = (i + FIG.images.length) % FIG.images.length;
  const views = FIG.images[current].views;
  mode = views[m] ? m : 'c';
  img.src = views[mode];
  crops.forEach(c => { c.src = views[mode]; });
  buttons.forEach((b, k) => b.className = k === current ? 'on' : '');
  document.getElementById('numbers').textContent =
    FIG.images[current].name + ': ' + FIG.images[current].numbers.join(', ');
  const sc = FIG.scales[mode];
  document.getElementById('scale').innerHTML = sc
    ? sc.title + ': ' + sc.labels[0] + ' <img src="' + sc.strip + '"> ' + sc.labels[sc.labels.length - 1]
    : 'image (c), relative error (e), FLIP (f)';
}
function onKey(e) {
  const k = e.key;
  if (k >= '1' && k <= '9' && (k.charCodeAt(0) - 49) < FIG.images.length) show(k.charCodeAt(0) - 49, mode);
  else if (k === 'ArrowRight') show(current + 1, mode);
  else if (k === 'ArrowLeft') show(current - 1, mode);
  else if (k === 'c' || k === 'e' || k === 'f') show(current, k);
  else if (k === '+' || k === '=') { zoom = Math.min(64, zoom * 2); layout(); }
  else if (k === '-') { zoom = Math.max(1, Math.floor(zoom / 2)); layout(); }
  else if (k === '0') { zoom = FIG.zoom; layout(); }
  else return;
  e.preventDefault();
}
document.addEventListener('keydown', onKey);
view.addEventListener('wheel', e => {
  e.preventDefault();
  zoom = e.deltaY < 0 ? Math.min(64, zoom * 2) : Math.max(1, Math.floor(zoom / 2));
  layout();
}, { passive: false });
layout();
show(0, 'c');
for (const k of (params.get('keys') || '').split(',').filter(k => k)) {
  document.dispatchEvent(new KeyboardEvent('keydown', { key: k, bubbles: true }));
}
"#;

/// The table of every image's numbers, for the page's foot.
fn table(fig: &Figure) -> String {
    let mut rows = String::from(
        "<table><tr><th>image</th><th>rel. RMSE</th><th>relMSE</th><th>FLIP mean</th><th>time, s</th></tr>",
    );
    for p in &fig.panels {
        rows.push_str(&format!(
            "<tr><td>{}</td><td>{:.4}</td><td>{:.3e}</td><td>{:.4}</td><td>{}</td></tr>",
            escape(&p.name),
            p.rel_rmse,
            p.rel_mse,
            p.flip_mean,
            p.seconds.map_or("–".into(), |s| format!("{s:.1}"))
        ));
    }
    rows + "</table>"
}

/// The page, `title` in its head and header.
pub(crate) fn page(fig: &Figure, title: &str) -> Result<String, String> {
    // `</` cannot end the script early: JSON escapes no slash, so it is escaped here.
    let data = serde_json::to_string(&data(fig)?)
        .map_err(|e| format!("cannot write the page's data: {e}"))?
        .replace("</", "<\\/");
    let top = VIEW_TOP.to_string();
    Ok(format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{t}</title>\
         <style>{style}</style></head><body>\
         <div id=\"head\"><div><b>{t}</b> · one exposure for all (×{exp:.4e}) · keys 1–9 or ←/→: image, \
         c/e/f: colour/relative error/FLIP, +/− or wheel: zoom, 0: reset · <span id=\"zoom\"></span></div>\
         <div id=\"buttons\"></div><div id=\"numbers\"></div><div id=\"scale\"></div></div>\
         <div id=\"view\"><img id=\"main\" alt=\"image\"></div>\
         <div id=\"below\"><div>crops (the image shown)</div><div id=\"crops\"></div>{table}</div>\
         <script>const FIG = {data}; const VIEW_TOP = {top};\n{script}</script></body></html>\n",
        t = escape(title),
        style = STYLE.replace("VIEW_TOP", &top),
        exp = fig.exposure,
        table = table(fig),
        script = SCRIPT,
    ))
}
