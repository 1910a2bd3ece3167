//! Round four (issue 43): textures, glTF images and the scene's memory, through the binary.
//! Every glTF, PNG and JPEG file is made by the test itself.
use crate::bdpm;
use std::path::{Path, PathBuf};
use std::process::Output;

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Exit code 1 (not a panic's 101 or an abort's 134) and exactly one line on stderr
/// containing every `needle`.
fn assert_one_line_error(out: &Output, needles: &[&str]) {
    let stderr = text(&out.stderr);
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "not one line: {stderr}");
    assert!(lines[0].starts_with("bdpm: error: "), "{stderr}");
    for n in needles {
        assert!(lines[0].contains(n), "'{n}' not in: {stderr}");
    }
}

fn assert_success(out: &Output) {
    assert!(
        out.status.success(),
        "bdpm failed ({:?}):\nstdout: {}\nstderr: {}",
        out.status,
        text(&out.stdout),
        text(&out.stderr)
    );
}

fn read_json(path: &Path) -> serde_json::Value {
    let s = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&s).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A scene of one or more `[[shape]]`s naming `files` (glTF files in the scene's folder),
/// seen by a camera at z = −2 with a light in front of them.
fn scene_text(files: &[&str]) -> String {
    let mut s = String::from(
        r#"
[render]
resolution = [8, 8]
passes = 1
photons = 1000
spp = 1
mode = "path"

[camera]
position = [0.0, 0.0, -2.0]
look_at = [0.0, 0.0, 0.0]
vfov = 40

[[light]]
position = [0.1, 0.2, -1.0]
flux = 4.0
"#,
    );
    for f in files {
        s.push_str(&format!("\n[[shape]]\ntype = \"mesh\"\nfile = \"{f}\"\n"));
    }
    s
}

/// Renders the scene file `name` (written with `text`) in `dir` with `extra` arguments.
fn render(dir: &Path, name: &str, scene: &str, extra: &[&str]) -> Output {
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, scene).expect("write scene");
    bdpm()
        .arg("render")
        .arg(&path)
        .args(extra)
        .args(["--quiet", "-o"])
        .arg(dir.join(format!("{name}.exr")))
        .output()
        .expect("run bdpm")
}

/// An 8-bit RGB PNG of `w` × `h` texels, a gradient.
fn png_rgb(w: u32, h: u32) -> Vec<u8> {
    let mut data = Vec::with_capacity((w * h * 3) as usize);
    for y in 0..h {
        for x in 0..w {
            data.extend_from_slice(&[(x * 255 / w.max(1)) as u8, (y * 255 / h.max(1)) as u8, 90]);
        }
    }
    let mut out = Vec::new();
    let mut e = png::Encoder::new(&mut out, w, h);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    let mut writer = e.write_header().expect("png header");
    writer.write_image_data(&data).expect("png data");
    writer.finish().expect("png end");
    out
}

/// The quad x, y ∈ [−0.5, 0.5] m at z = 0 facing −z: positions (48 bytes), texture
/// coordinates (32 bytes) and u16 indices (12 bytes).
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

/// Writes `name.gltf` and `name.bin` in `dir`: the quad, drawn by `materials` primitives
/// (one per material, all over the same accessors), material k using texture k, whose
/// sampler k has its own wrap modes, and every texture showing image 0, `image` (a JSON
/// object). `embedded` is appended to the buffer after the quad as bufferView 3 (when not
/// empty), for images stored in the buffer.
fn textured_quad(dir: &Path, name: &str, image: &str, embedded: &[u8], materials: usize) {
    let mut bin = quad_bin();
    let quad_len = bin.len();
    bin.extend_from_slice(embedded);
    std::fs::write(dir.join(format!("{name}.bin")), &bin).expect("write bin");
    let wraps = [33071, 33648, 10497];
    let list = |f: &dyn Fn(usize) -> String| (0..materials).map(f).collect::<Vec<_>>().join(", ");
    let samplers = list(&|k| {
        format!(
            r#"{{ "wrapS": {}, "wrapT": {} }}"#,
            wraps[k % 3],
            wraps[(k / 3) % 3]
        )
    });
    let textures = list(&|k| format!(r#"{{ "source": 0, "sampler": {k} }}"#));
    let mats = list(&|k| {
        format!(r#"{{ "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": {k} }} }} }}"#)
    });
    let prims = list(&|k| {
        format!(
            r#"{{ "attributes": {{ "POSITION": 0, "TEXCOORD_0": 1 }}, "indices": 2, "material": {k} }}"#
        )
    });
    let embedded_view = if embedded.is_empty() {
        String::new()
    } else {
        format!(
            r#", {{ "buffer": 0, "byteOffset": {quad_len}, "byteLength": {} }}"#,
            embedded.len()
        )
    };
    let gltf = format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "buffers": [ {{ "byteLength": {}, "uri": "{name}.bin" }} ],
  "bufferViews": [
    {{ "buffer": 0, "byteOffset": 0, "byteLength": 48 }},
    {{ "buffer": 0, "byteOffset": 48, "byteLength": 32 }},
    {{ "buffer": 0, "byteOffset": 80, "byteLength": 12 }}{embedded_view}
  ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-0.5, -0.5, 0], "max": [0.5, 0.5, 0] }},
    {{ "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2" }},
    {{ "bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR" }}
  ],
  "images": [ {image} ],
  "samplers": [ {samplers} ],
  "textures": [ {textures} ],
  "materials": [ {mats} ],
  "meshes": [ {{ "primitives": [ {prims} ] }} ],
  "nodes": [ {{ "mesh": 0 }} ],
  "scenes": [ {{ "nodes": [0] }} ]
}}"#,
        bin.len()
    );
    std::fs::write(dir.join(format!("{name}.gltf")), gltf).expect("write gltf");
}

fn temp() -> (tempfile::TempDir, PathBuf) {
    let t = crate::temp_dir("round4-textures");
    let p = t.path().to_path_buf();
    (t, p)
}

/// Finding 1: an image in a bufferView without a mimeType, and an image with neither a uri
/// nor a bufferView, made the `gltf` crate panic (exit 101). The first is decoded (images are
/// recognised by their bytes), the second refused in one line naming the file and the image.
#[test]
fn gltf_images_without_mime_type_or_source_do_not_panic() {
    let (_t, dir) = temp();
    textured_quad(&dir, "nomime", r#"{ "bufferView": 3 }"#, &png_rgb(4, 4), 1);
    let out = render(&dir, "nomime", &scene_text(&["nomime.gltf"]), &[]);
    assert_success(&out);
    let json = read_json(&dir.join("nomime.json"));
    assert_eq!(json["scene"]["gltf"]["textures"], 1, "{}", json["scene"]);

    textured_quad(&dir, "nosource", r#"{ "name": "lost" }"#, &[], 1);
    let out = render(&dir, "nosource", &scene_text(&["nosource.gltf"]), &[]);
    assert_one_line_error(
        &out,
        &[
            "nosource.gltf",
            "shape[0].file",
            "image 0",
            "neither a uri nor a bufferView",
        ],
    );
}

/// 16 × 8 texels of sRGB (200, 100, 50), baseline JPEG (the loader's own test image); the
/// damaged versions below are made from it.
const JPEG: &[u8] = include_bytes!("../../../load/tests/data/solid-200-100-50.jpg");

/// The JPEG's segments: (marker byte, start of the 0xFF, end), the scan's entropy-coded data
/// included in the SOS segment.
fn jpeg_segments(b: &[u8]) -> Vec<(u8, usize, usize)> {
    let mut out = Vec::new();
    let mut i = 2;
    while i + 1 < b.len() {
        assert_eq!(b[i], 0xFF, "marker expected at {i}");
        let marker = b[i + 1];
        if marker == 0xD9 {
            out.push((marker, i, i + 2));
            break;
        }
        let mut end = i + 2 + usize::from(u16::from_be_bytes([b[i + 2], b[i + 3]]));
        if marker == 0xDA {
            // Entropy-coded data runs to the next marker that is not a stuffed 0xFF00 or RSTn.
            while !(b[end] == 0xFF && b[end + 1] != 0 && !(0xD0..=0xD7).contains(&b[end + 1])) {
                end += 1;
            }
        }
        out.push((marker, i, end));
        i = end;
    }
    out
}

/// Finding 2: a JPEG whose header claims 16384² texels decoded to 3.9 GB of filler (exit 0, or
/// 134 under a memory limit); truncated and scan-less JPEGs decoded silently with grey rows.
/// Each is now refused in one line naming the file and the image; the intact file renders.
#[test]
fn forged_truncated_and_scanless_jpegs_are_refused() {
    let (_t, dir) = temp();
    let segments = jpeg_segments(JPEG);
    let (_, sof, _) = *segments.iter().find(|s| s.0 == 0xC0).expect("SOF0");
    let (_, sos, sos_end) = *segments.iter().find(|s| s.0 == 0xDA).expect("SOS");
    let forged = |w: u16, h: u16| {
        let mut b = JPEG.to_vec();
        b[sof + 5..sof + 7].copy_from_slice(&h.to_be_bytes());
        b[sof + 7..sof + 9].copy_from_slice(&w.to_be_bytes());
        b
    };
    // Cut within the entropy-coded data, as a download that stopped early.
    let scan_data = sos + 2 + usize::from(u16::from_be_bytes([JPEG[sos + 2], JPEG[sos + 3]]));
    let truncated = JPEG[..scan_data + (sos_end - scan_data) / 2].to_vec();
    let mut scanless = JPEG[..sos].to_vec();
    scanless.extend_from_slice(&JPEG[sos_end..]);
    #[rustfmt::skip]
    let cases: [(&str, Vec<u8>, &[&str]); 4] = [
        ("huge", forged(16384, 16384), &["16384×16384", "more than its 635 bytes can hold"]),
        ("tall", forged(16, 4096), &["16×4096", "more than its 635 bytes can hold"]),
        ("truncated", truncated, &["ends inside its scan data"]),
        ("scanless", scanless, &["has no scan"]),
    ];
    for (name, bytes, needles) in cases {
        std::fs::write(dir.join(format!("{name}.jpg")), bytes).expect("write jpeg");
        let image = format!(r#"{{ "uri": "{name}.jpg" }}"#);
        textured_quad(&dir, name, &image, &[], 1);
        let out = render(&dir, name, &scene_text(&[&format!("{name}.gltf")]), &[]);
        let mut all = vec![format!("{name}.gltf"), "image 0".to_string()];
        all.extend(needles.iter().map(|n| n.to_string()));
        let all: Vec<&str> = all.iter().map(String::as_str).collect();
        assert_one_line_error(&out, &all);
    }
    std::fs::write(dir.join("intact.jpg"), JPEG).expect("write jpeg");
    textured_quad(&dir, "intact", r#"{ "uri": "intact.jpg" }"#, &[], 1);
    assert_success(&render(&dir, "intact", &scene_text(&["intact.gltf"]), &[]));
}

/// The report's memory item `name`, bytes (0 when the report does not list it).
fn memory_item(json: &serde_json::Value, name: &str) -> u64 {
    json["memory"]["items"]
        .as_array()
        .expect("memory items")
        .iter()
        .find(|i| i["name"] == name)
        .map_or(0, |i| i["bytes"].as_u64().expect("bytes"))
}

/// Estimated over measured peak memory of a report.
fn estimate_over_peak(json: &serde_json::Value) -> f64 {
    let m = &json["memory"];
    m["estimate_bytes"].as_f64().expect("estimate")
        / m["measured_peak_bytes"].as_f64().expect("peak")
}

/// Finding 4: an image was decoded again for every sampler and every `[[shape]]` naming its
/// glTF file (9 samplers on one 4096² image: 1.9 GB), and the estimate left textures out.
/// Now it is decoded once (the report counts 1 image), held as 3 bytes a texel, and counted
/// in the estimate, which is within 1.5× of the measured peak.
#[test]
fn an_image_shown_by_nine_samplers_and_two_shapes_is_decoded_once_and_counted() {
    let (_t, dir) = temp();
    std::fs::write(dir.join("small.png"), png_rgb(64, 32)).expect("write png");
    textured_quad(&dir, "nine", r#"{ "uri": "small.png" }"#, &[], 9);
    let out = render(&dir, "nine", &scene_text(&["nine.gltf", "nine.gltf"]), &[]);
    assert_success(&out);
    let json = read_json(&dir.join("nine.json"));
    assert_eq!(
        json["scene"]["gltf"]["textured_materials"], 18,
        "{}",
        json["scene"]
    );
    assert_eq!(json["scene"]["gltf"]["textures"], 1, "{}", json["scene"]);
    assert_eq!(memory_item(&json, "textures"), 3 * 64 * 32);

    // 4096² texels through 9 samplers: 48 MiB kept, where 18 decodes of 12 bytes a texel
    // would hold 3.4 GiB.
    std::fs::write(dir.join("big.png"), png_rgb(4096, 4096)).expect("write png");
    textured_quad(&dir, "big", r#"{ "uri": "big.png" }"#, &[], 9);
    let out = render(&dir, "big", &scene_text(&["big.gltf"]), &[]);
    assert_success(&out);
    let json = read_json(&dir.join("big.json"));
    assert_eq!(memory_item(&json, "textures"), 3 * 4096 * 4096);
    let ratio = estimate_over_peak(&json);
    assert!(
        (1.0 / 1.5..=1.5).contains(&ratio),
        "estimate / peak = {ratio}: {}",
        json["memory"]
    );
}

/// CRC-32 (ISO 3309, as PNG chunks use), bitwise.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// A PNG whose header claims `size` × `size` texels over the data of a 1 × 1 image.
fn forged_png(size: u32) -> Vec<u8> {
    let mut b = png_rgb(1, 1);
    // Signature (8), IHDR length and type (8), then width and height; the CRC covers the
    // chunk type and data (bytes 12..29) and follows them.
    b[16..20].copy_from_slice(&size.to_be_bytes());
    b[20..24].copy_from_slice(&size.to_be_bytes());
    let crc = crc32(&b[12..29]);
    b[29..33].copy_from_slice(&crc.to_be_bytes());
    b
}

/// Writes `name.gltf` and `name.bin`: an `n` × `n` grid of quads (2n² triangles, f32
/// positions, u32 indices) over x, y ∈ [−0.5, 0.5] at z = 0.
fn grid_mesh(dir: &Path, name: &str, n: u32) {
    let mut bin = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            for c in [i as f32 / n as f32 - 0.5, j as f32 / n as f32 - 0.5, 0.0] {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    let positions = bin.len();
    let w = n + 1;
    for j in 0..n {
        for i in 0..n {
            let a = j * w + i;
            for k in [a, a + w, a + 1, a + 1, a + w, a + w + 1] {
                bin.extend_from_slice(&k.to_le_bytes());
            }
        }
    }
    std::fs::write(dir.join(format!("{name}.bin")), &bin).expect("write bin");
    let gltf = format!(
        r#"{{ "asset": {{ "version": "2.0" }},
  "buffers": [ {{ "byteLength": {}, "uri": "{name}.bin" }} ],
  "bufferViews": [ {{ "buffer": 0, "byteLength": {positions} }},
                   {{ "buffer": 0, "byteOffset": {positions}, "byteLength": {} }} ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": {}, "type": "VEC3", "min": [-0.5, -0.5, 0], "max": [0.5, 0.5, 0] }},
    {{ "bufferView": 1, "componentType": 5125, "count": {}, "type": "SCALAR" }} ],
  "meshes": [ {{ "primitives": [ {{ "attributes": {{ "POSITION": 0 }}, "indices": 1 }} ] }} ],
  "nodes": [ {{ "mesh": 0 }} ], "scenes": [ {{ "nodes": [0] }} ] }}"#,
        bin.len(),
        bin.len() - positions,
        w * w,
        6 * n * n
    );
    std::fs::write(dir.join(format!("{name}.gltf")), gltf).expect("write gltf");
}

/// Finding 4: a 16384² texture was decoded under `--max-memory 200M` (3.8 GB), and 10⁶
/// triangles were estimated at 46 MB and accepted under `--max-memory 100M` (465 MB). Both are
/// refused by the loader before the allocation, in one line naming the item and the bound;
/// a 10⁶-triangle render's estimate counts geometry, BVH and its build, within 1.5× of the
/// measured peak.
#[test]
fn a_huge_texture_or_mesh_is_refused_before_it_is_decoded_or_built() {
    let (_t, dir) = temp();
    std::fs::write(dir.join("huge.png"), forged_png(16384)).expect("write png");
    textured_quad(&dir, "huge", r#"{ "uri": "huge.png" }"#, &[], 1);
    let scene = scene_text(&["huge.gltf"]);
    let out = render(&dir, "huge", &scene, &["--max-memory", "200M"]);
    assert_one_line_error(
        &out,
        &[
            "huge.gltf",
            "image 0",
            "16384×16384",
            "768.0 MiB",
            "--max-memory of 200.0 MiB",
        ],
    );

    // 707² quads: 999 698 triangles.
    grid_mesh(&dir, "grid", 707);
    let scene = scene_text(&["grid.gltf"]);
    let out = render(&dir, "grid", &scene, &["--max-memory", "100M"]);
    assert_one_line_error(
        &out,
        &[
            "grid.toml",
            "shape",
            "999698 triangles",
            "BVH",
            "--max-memory of 100.0 MiB",
        ],
    );
    let out = render(&dir, "grid", &scene, &[]);
    assert_success(&out);
    let json = read_json(&dir.join("grid.json"));
    for item in ["geometry", "BVH"] {
        assert!(
            memory_item(&json, item) > 50 << 20,
            "{item}: {}",
            json["memory"]
        );
    }
    let ratio = estimate_over_peak(&json);
    assert!(
        (1.0 / 1.5..=1.5).contains(&ratio),
        "estimate / peak = {ratio}: {}",
        json["memory"]
    );
}

/// The glTF messages of the review: a Draco file's cause was the last of 103 clauses; a
/// glTF 1.0 file said `invalid type: map, expected a sequence`; zero-area triangles were only
/// counted in the report. Each is one line naming the file and the cause now, and the
/// degenerate triangles get a warning line.
#[test]
fn gltf_messages_name_the_cause_in_one_line() {
    let (_t, dir) = temp();
    // Draco: the accessors have no bufferView (the extension holds the data).
    let accessors: Vec<String> = (0..6)
        .map(|_| r#"{ "componentType": 5126, "count": 3, "type": "VEC3" }"#.to_string())
        .collect();
    let draco = format!(
        r#"{{ "asset": {{ "version": "2.0" }},
  "extensionsUsed": ["KHR_draco_mesh_compression"],
  "extensionsRequired": ["KHR_draco_mesh_compression"],
  "accessors": [ {} ],
  "meshes": [ {{ "primitives": [ {{ "attributes": {{ "POSITION": 0 }} }} ] }} ],
  "nodes": [ {{ "mesh": 0 }} ], "scenes": [ {{ "nodes": [0] }} ] }}"#,
        accessors.join(", ")
    );
    std::fs::write(dir.join("draco.gltf"), &draco).expect("write");
    let out = render(&dir, "draco", &scene_text(&["draco.gltf"]), &[]);
    assert_one_line_error(
        &out,
        &[
            "draco.gltf",
            "uses KHR_draco_mesh_compression, which bdpm does not decode; export without Draco",
        ],
    );
    // The same accessors without the extension: eight validation errors (six accessors
    // without data, the POSITION accessor without min and max), three shown.
    let plain = draco.replace(
        r#""extensionsRequired": ["KHR_draco_mesh_compression"],"#,
        "",
    );
    std::fs::write(dir.join("nodata.gltf"), plain).expect("write");
    let out = render(&dir, "nodata", &scene_text(&["nodata.gltf"]), &[]);
    assert_one_line_error(
        &out,
        &["nodata.gltf", "accessors[0].bufferView", "; and 5 more"],
    );
    assert!(
        !text(&out.stderr).contains("accessors[3]"),
        "{}",
        text(&out.stderr)
    );
    // glTF 1.0: objects where 2.0 has arrays.
    let v1 = r#"{ "asset": { "version": "1.0" }, "buffers": { "b": { "uri": "x.bin" } }, "meshes": {} }"#;
    std::fs::write(dir.join("v1.gltf"), v1).expect("write");
    let out = render(&dir, "v1", &scene_text(&["v1.gltf"]), &[]);
    assert_one_line_error(
        &out,
        &["v1.gltf", "is a glTF 1.0 file; bdpm reads glTF 2.0"],
    );

    // Two zero-area triangles (repeated vertices) beside the textured quad.
    let mut bin = Vec::new();
    for c in [0.0f32, 0.0, 0.1, 0.1, 0.0, 0.1, 0.0, 0.0, 0.1] {
        bin.extend_from_slice(&c.to_le_bytes());
    }
    std::fs::write(dir.join("flat.bin"), &bin).expect("write");
    let flat = r#"{ "asset": { "version": "2.0" },
  "buffers": [ { "byteLength": 36, "uri": "flat.bin" } ],
  "bufferViews": [ { "buffer": 0, "byteLength": 36 } ],
  "accessors": [ { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0.1], "max": [0.1, 0, 0.1] } ],
  "meshes": [ { "primitives": [ { "attributes": { "POSITION": 0 } } ] } ],
  "nodes": [ { "mesh": 0 }, { "mesh": 0 } ], "scenes": [ { "nodes": [0, 1] } ] }"#;
    std::fs::write(dir.join("flat.gltf"), flat).expect("write");
    std::fs::write(dir.join("quad.png"), png_rgb(2, 2)).expect("write png");
    textured_quad(&dir, "quad", r#"{ "uri": "quad.png" }"#, &[], 1);
    let out = render(&dir, "flat", &scene_text(&["quad.gltf", "flat.gltf"]), &[]);
    assert_success(&out);
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("warning: 2 of the scene's 4 triangles have zero area and are left out"),
        "{stdout}"
    );
}
