//! The figure's HTML page in a real browser: headless Chromium screenshots the page, the
//! image view must show the reference's tonemapped pixels, and after a key press (ArrowRight,
//! dispatched by the page's `?keys=` to its own handler) the first image's, while the page
//! around the view stays the same.
//!
//! Without Chromium the test says so and passes, unless `BDPM_REQUIRE_CHROMIUM` is set (CI's
//! `.ci/run` installs Chromium and sets it), where a missing browser fails it.
use std::path::{Path, PathBuf};
use std::process::Command;

use glam::DVec3;

use crate::figure::{Entry, Figure, Inputs, build};
use crate::figure_page::{VIEW_TOP, page};

/// The browser to use: `BDPM_CHROMIUM`, else /usr/bin/chromium, else `chromium` on the PATH.
fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("BDPM_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let debian = PathBuf::from("/usr/bin/chromium");
    if debian.exists() {
        return Some(debian);
    }
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join("chromium"))
            .find(|p| p.exists())
    })
}

/// Window size of the screenshots, CSS pixels (device scale factor 1).
const WINDOW: (u32, u32) = (800, 600);

/// A decoded screenshot: width and RGB bytes.
struct Shot {
    width: u32,
    rgb: Vec<u8>,
}

impl Shot {
    fn at(&self, x: u32, y: u32) -> [u8; 3] {
        let i = (y as usize * self.width as usize + x as usize) * 3;
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }
}

/// Screenshots `url` with `browser` into `out` and decodes it (RGB or RGBA PNG).
fn screenshot(browser: &Path, url: &str, out: &Path) -> Shot {
    let profile = tempfile::tempdir().expect("a temporary profile directory");
    let status = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
            "--force-device-scale-factor=1",
            "--force-color-profile=srgb",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg(format!("--screenshot={}", out.display()))
        .arg(format!("--window-size={},{}", WINDOW.0, WINDOW.1))
        .arg(url)
        .output()
        .expect("chromium starts");
    assert!(
        status.status.success() && out.exists(),
        "chromium failed on {url}: {}",
        String::from_utf8_lossy(&status.stderr)
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(out).expect("the screenshot opens"),
    ));
    let mut reader = decoder.read_info().expect("a PNG screenshot");
    let mut buf = vec![0; reader.output_buffer_size().expect("a sized PNG")];
    let info = reader.next_frame(&mut buf).expect("a decodable screenshot");
    let channels = info.color_type.samples();
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let rgb = buf[..info.buffer_size()]
        .chunks(channels)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    Shot {
        width: info.width,
        rgb,
    }
}

/// A figure of a colour gradient (the reference) and a checkerboard of it at 2× and 0.2×
/// (the image): the two differ in every pixel.
fn figure() -> Figure {
    let (w, h) = (48u32, 32u32);
    let reference: Vec<DVec3> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64, (i / w) as f64);
            DVec3::new(0.1 + x / w as f64, 0.1 + y / h as f64, 0.3)
        })
        .collect();
    let image = reference
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let (x, y) = (i as u32 % w, i as u32 / w);
            *c * if (x / 4 + y / 4) % 2 == 0 { 2.0 } else { 0.2 }
        })
        .collect();
    build(Inputs {
        width: w,
        height: h,
        reference,
        reference_error: None,
        entries: vec![Entry {
            name: "checkers".into(),
            rgb: image,
            seconds: Some(1.5),
        }],
        crops: Vec::new(),
        auto_crops: 2,
    })
}

/// The share of the figure's pixels whose block centre in `shot` (view at zoom `zoom`) is
/// within 6 levels of `srgb` in every channel.
fn share_matching(shot: &Shot, fig: &Figure, srgb: &[u8], zoom: u32) -> f64 {
    let mut good = 0;
    for y in 0..fig.height {
        for x in 0..fig.width {
            let s = shot.at(x * zoom + zoom / 2, VIEW_TOP + y * zoom + zoom / 2);
            let i = (y * fig.width + x) as usize * 3;
            if (0..3).all(|c| s[c].abs_diff(srgb[i + c]) <= 6) {
                good += 1;
            }
        }
    }
    good as f64 / (fig.width * fig.height) as f64
}

#[test]
fn the_page_shows_the_images_and_a_key_press_switches_them() {
    let Some(browser) = chromium() else {
        let required =
            std::env::var("BDPM_REQUIRE_CHROMIUM").is_ok_and(|v| !v.is_empty() && v != "0");
        assert!(
            !required,
            "BDPM_REQUIRE_CHROMIUM is set but no chromium was found (BDPM_CHROMIUM, /usr/bin/chromium, PATH)"
        );
        eprintln!(
            "SKIPPED: no chromium (install it: apt-get install chromium) for the figure's browser test"
        );
        return;
    };
    let fig = figure();
    let dir = tempfile::tempdir().unwrap();
    let html = dir.path().join("figure.html");
    std::fs::write(&html, page(&fig, "browser test").unwrap()).unwrap();
    let zoom = 4;
    let url = format!("file://{}?zoom={zoom}", html.display());
    let first = screenshot(&browser, &url, &dir.path().join("first.png"));
    let second = screenshot(
        &browser,
        &format!("{url}&keys=ArrowRight"),
        &dir.path().join("second.png"),
    );
    // The view shows the reference, then (after the key) the image, each at its tonemapped
    // pixels; and not the other one.
    let checkers = &fig.panels[0].srgb;
    let matches = [
        share_matching(&first, &fig, &fig.reference, zoom),
        share_matching(&first, &fig, checkers, zoom),
        share_matching(&second, &fig, checkers, zoom),
        share_matching(&second, &fig, &fig.reference, zoom),
    ];
    assert!(matches[0] > 0.95 && matches[2] > 0.95, "{matches:?}");
    assert!(matches[1] < 0.2 && matches[3] < 0.2, "{matches:?}");
    // Outside the view (to its right, and the header's first line) the screenshots agree.
    let right = fig.width * zoom + 16;
    let mut outside = 0;
    for y in (0..16).chain(VIEW_TOP..VIEW_TOP + fig.height * zoom) {
        for x in right..WINDOW.0 {
            assert_eq!(first.at(x, y), second.at(x, y), "pixel ({x}, {y}) changed");
            outside += 1;
        }
    }
    assert!(outside > 10_000, "{outside}");
}
