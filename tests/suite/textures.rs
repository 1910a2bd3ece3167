//! A textured glTF quad under a point light: the image has the texture's colours, pixel by
//! pixel, against the exact direct radiance kd(u, v)/π · I · cos θ / d² (issue 26).
//!
//! The quad is the only surface, so the radiance leaving it is its direct light alone: no
//! light returns to it. kd = baseColorFactor × sRGB-decoded texel. The 4 × 4 texture holds
//! four 2 × 2 blocks of one colour each and is clamped at its edges, so bilinear filtering is
//! constant over u, v ∈ [0, 0.375] ∪ [0.625, 1] in each quadrant (texel centres at 0.125 and
//! 0.375 share a colour); pixels that see any other part of the quad are not compared. The
//! exact pixel value is the mean over the pixel (the camera jitters uniformly over it) of the
//! formula, by a 24 × 24 midpoint rule along the camera's own ray directions.

use bdpm_integrator::Film;
use bdpm_load::load_scene;
use bdpm_scene::Scene;
use bdpm_suite::{render, with_mode};
use glam::DVec3;

const RES: u32 = 24;
/// The four quadrants' sRGB bytes: top-left, top-right, bottom-left, bottom-right.
const COLOURS: [[u8; 3]; 4] = [[230, 40, 20], [30, 200, 60], [20, 60, 240], [128, 128, 128]];
const FACTOR: [f32; 3] = [0.9, 0.8, 1.0];
const LIGHT: [f32; 3] = [0.15, 0.2, -1.0];
const FLUX: f32 = 4.0;

fn srgb_to_linear(byte: u8) -> f64 {
    let c = f64::from(byte) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// 4 × 4 RGB texels: quadrant q = 2·(row ≥ 2) + (column ≥ 2).
fn texture_png() -> Vec<u8> {
    let mut rgb = Vec::new();
    for row in 0..4 {
        for col in 0..4 {
            rgb.extend_from_slice(&COLOURS[2 * (row / 2) + col / 2]);
        }
    }
    let mut out = Vec::new();
    let mut e = png::Encoder::new(&mut out, 4, 4);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    let mut w = e.write_header().expect("png header");
    w.write_image_data(&rgb).expect("png data");
    w.finish().expect("png end");
    out
}

/// The quad x, y ∈ [−0.5, 0.5] m at z = 0 facing −z (towards the camera), uv = (x + ½, ½ − y):
/// positions (48 bytes), texture coordinates (32 bytes), u16 indices (12 bytes).
fn quad_bin() -> Vec<u8> {
    let corners = [[-0.5f32, 0.5], [-0.5, -0.5], [0.5, -0.5], [0.5, 0.5]];
    let mut b = Vec::new();
    for [x, y] in corners {
        for c in [x, y, 0.0] {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    for [x, y] in corners {
        for c in [x + 0.5, 0.5 - y] {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    b
}

const GLTF: &str = r#"{
  "asset": { "version": "2.0" },
  "buffers": [ { "byteLength": 92, "uri": "quad.bin" } ],
  "bufferViews": [
    { "buffer": 0, "byteOffset": 0, "byteLength": 48 },
    { "buffer": 0, "byteOffset": 48, "byteLength": 32 },
    { "buffer": 0, "byteOffset": 80, "byteLength": 12 }
  ],
  "accessors": [
    { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-0.5, -0.5, 0], "max": [0.5, 0.5, 0] },
    { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2" },
    { "bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR" }
  ],
  "images": [ { "uri": "blocks.png" } ],
  "samplers": [ { "wrapS": 33071, "wrapT": 33071 } ],
  "textures": [ { "source": 0, "sampler": 0 } ],
  "materials": [ { "pbrMetallicRoughness": {
    "baseColorFactor": [0.9, 0.8, 1.0, 1.0], "baseColorTexture": { "index": 0 },
    "metallicFactor": 0.0 } } ],
  "meshes": [ { "primitives": [ { "attributes": { "POSITION": 0, "TEXCOORD_0": 1 },
    "indices": 2, "material": 0 } ] } ],
  "nodes": [ { "mesh": 0 } ],
  "scenes": [ { "nodes": [0] } ]
}"#;

fn scene_toml() -> String {
    format!(
        r#"
[render]
resolution = [{RES}, {RES}]

[camera]
position = [0.0, 0.0, -2.0]
look_at = [0.0, 0.0, 0.0]
vfov = 30

[[light]]
position = [{}, {}, {}]
flux = {FLUX}

[[shape]]
type = "gltf"
file = "quad.gltf"
"#,
        LIGHT[0], LIGHT[1], LIGHT[2]
    )
}

fn load() -> (Scene, bdpm_integrator::RenderSettings) {
    let tmp = tempfile::Builder::new()
        .prefix("bdpm-texture-test-")
        .tempdir()
        .expect("temp dir");
    let dir = tmp.path();
    std::fs::write(dir.join("quad.bin"), quad_bin()).expect("write bin");
    std::fs::write(dir.join("blocks.png"), texture_png()).expect("write png");
    std::fs::write(dir.join("quad.gltf"), GLTF).expect("write gltf");
    std::fs::write(dir.join("scene.toml"), scene_toml()).expect("write toml");
    let loaded = load_scene(&dir.join("scene.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(loaded.report.textured_materials, 1);
    assert_eq!(loaded.report.textures, 1);
    assert!(
        loaded.report.warnings().is_empty(),
        "{:?}",
        loaded.report.warnings()
    );
    (loaded.scene, loaded.settings)
}

/// The exact mean radiance over pixel (x, y), or None if part of the pixel sees a blend of
/// quadrants, an edge of the quad, or nothing.
fn exact_pixel(scene: &Scene, x: u32, y: u32) -> Option<DVec3> {
    const N: u32 = 24;
    let cam = scene.camera();
    // Scene positions are relative to the geometry's origin; the quad's plane is world z = 0.
    let origin = scene.geometry().origin().as_dvec3();
    let eye = cam.position().as_dvec3() + origin;
    let light = DVec3::from_array(LIGHT.map(f64::from));
    let intensity = f64::from(FLUX) / (4.0 * std::f64::consts::PI);
    let mut quadrant = None;
    let mut sum = DVec3::ZERO;
    for j in 0..N {
        for i in 0..N {
            let (px, py) = (
                x as f32 + (i as f32 + 0.5) / N as f32,
                y as f32 + (j as f32 + 0.5) / N as f32,
            );
            let d = cam.ray_direction(px, py).as_dvec3();
            let t = -eye.z / d.z;
            let p = eye + d * t;
            let (u, v) = (p.x + 0.5, 0.5 - p.y);
            let inside = |c: f64| (0.01..=0.37).contains(&c) || (0.63..=0.99).contains(&c);
            if !(inside(u) && inside(v)) {
                return None;
            }
            let q = 2 * usize::from(v > 0.5) + usize::from(u > 0.5);
            if *quadrant.get_or_insert(q) != q {
                return None;
            }
            let to = light - p;
            let d2 = to.length_squared();
            let cos = -to.z / d2.sqrt();
            let texel = DVec3::from_array(COLOURS[q].map(srgb_to_linear));
            let kd = DVec3::from_array(FACTOR.map(f64::from)) * texel;
            sum += kd / std::f64::consts::PI * intensity * cos / d2;
        }
    }
    Some(sum / f64::from(N * N))
}

/// Per-pixel agreement at 4 standard errors and the relative error of the compared pixels'
/// mean per channel, with that mean's relative standard error.
fn compare(scene: &Scene, film: &Film) -> (usize, usize, DVec3, DVec3) {
    let (mean, se) = (film.mean(), film.standard_error());
    let (mut compared, mut within) = (0, 0);
    let (mut sum_f, mut sum_e, mut var) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    for y in 0..RES {
        for x in 0..RES {
            let Some(exact) = exact_pixel(scene, x, y) else {
                continue;
            };
            let i = (y * RES + x) as usize;
            compared += 1;
            let ok = (mean[i] - exact)
                .abs()
                .cmple(se[i] * 4.0 + exact * 1e-5)
                .all();
            within += usize::from(ok);
            sum_f += mean[i];
            sum_e += exact;
            var += se[i] * se[i];
        }
    }
    (
        compared,
        within,
        (sum_f - sum_e) / sum_e,
        var.sqrt() / sum_e,
    )
}

/// Every kind of integrator reads the textured kd: the path tracer (next-event estimation),
/// the light tracer, and BDPM's x₀ with its merges and weights.
#[test]
fn textured_quad_matches_the_exact_direct_light_per_texel() {
    let (scene, settings) = load();
    let mut failures = Vec::new();
    for mode in ["path", "light", "balance", "optimal"] {
        let mut s = with_mode(&settings, mode, 16, 16, 20_000);
        s.radius = Some(0.01);
        let film = render(&scene, &s);
        let (compared, within, rel, rel_se) = compare(&scene, &film);
        eprintln!(
            "{mode:>8}: {within}/{compared} pixels within 4σ, mean error {rel:.5} (SE {rel_se:.5})"
        );
        // 4 quadrants' worth of pixels, away from the blends, or the test checks nothing.
        assert!(compared >= 100, "{compared} pixels compared");
        let fraction = within as f64 / compared as f64;
        if !(fraction >= 0.99 && rel.abs().max_element() < 0.002 && rel_se.max_element() < 5e-4) {
            failures.push(format!(
                "{mode}: {within}/{compared}, mean {rel}, SE {rel_se}"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
    // The compared pixels see different colours: a texture read as its factor alone, or at
    // the wrong coordinates, fails above. (The camera sees the quad's back, so the image is
    // the texture mirrored: the top-left pixel sees the green top-right block.)
    let tl = exact_pixel(&scene, 3, 3).expect("top-left pixel sees one quadrant");
    let br = exact_pixel(&scene, RES - 4, RES - 4).expect("bottom-right pixel sees one quadrant");
    assert!(
        tl.y > 3.0 * tl.x.max(tl.z) && br.z > 3.0 * br.x.max(br.y),
        "{tl} {br}"
    );
}
