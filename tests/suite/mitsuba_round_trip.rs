//! The Mitsuba round trip (issue 47): every scene of scenes/ exported to Mitsuba 3 XML
//! (bdpm-export, in memory, written to a temporary directory) and imported again renders,
//! with the TOML file's settings, to the same image bits as the TOML file: the Gaussian
//! lobe's stand-in comes back as the same kd, gr and Δ, the camera from the look-at inputs
//! the export writes, the lights from intensities written with the digits that bring the
//! flux back, area lights from the `<emitter type="area">` in their shape, glTF textures
//! (exported as EXR bitmaps of linear texels × factor) from the bitmaps as their 8-bit sRGB
//! codes and factors (docs/scene-format.md, "Import from Mitsuba 3"); or, where the
//! export's per-material meshes reorder the triangles enough to move the last bits, to the same
//! bits as the TOML file with its shapes grouped that way ([`grouped_by_material`]).

use std::path::{Path, PathBuf};

use bdpm_integrator::Renderer;
use bdpm_load::load_scene;
use bdpm_suite::{render_with, scene_path, with_mode};

/// The mean and per-pass variance of a 16 × 12 render of `scene` with `settings`' mode and
/// seed (one pass, 2 samples per pixel, 20 000 photons), bit for bit.
fn bits(scene: &mut bdpm_scene::Scene, settings: &bdpm_integrator::RenderSettings) -> Vec<u64> {
    scene.set_resolution(16, 12).expect("resolution");
    let mode = settings.mode.name();
    let settings = bdpm_integrator::RenderSettings {
        width: 16,
        height: 12,
        cache_photons: settings.cache_photons.map(|c| c.min(50_000)),
        ..with_mode(settings, mode, 1, 2, 20_000)
    };
    let film = render_with(&Renderer::new(scene, &settings).unwrap_or_else(|e| panic!("{e}")));
    assert!(
        film.mean().iter().any(|v| v.max_element() > 0.0),
        "black image"
    );
    film.mean()
        .iter()
        .chain(film.pass_variance().iter())
        .flat_map(|v| v.to_array().map(f64::to_bits))
        .collect()
}

/// The TOML scenes of scenes/ and scenes/preprint/.
fn scenes() -> Vec<PathBuf> {
    let mut out = Vec::new();
    for dir in [scene_path(""), scene_path("preprint")] {
        for entry in std::fs::read_dir(&dir).expect("scenes/") {
            let path = entry.expect("entry").path();
            if path.extension().is_some_and(|e| e == "toml") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// The scene exported and imported again; `Err` with the import's message.
fn round_trip(path: &Path, dir: &Path) -> Result<bdpm_load::LoadedScene, String> {
    let loaded = load_scene(path).unwrap_or_else(|e| panic!("{e}"));
    let export = bdpm_export::mitsuba(&loaded.scene, &loaded.settings, path)
        .unwrap_or_else(|e| panic!("{e}"));
    bdpm_export::write(&export, dir).unwrap_or_else(|e| panic!("{e}"));
    load_scene(&dir.join(bdpm_export::SCENE_FILE)).map_err(|e| e.to_string())
}

/// Scenes whose export the import refuses, with the element: none since the import reads
/// `<texture type="bitmap">` (the glTF textures of textured-box.toml and emissive-room.toml
/// come back as their 8-bit codes and factors, docs/scene-format.md).
const REFUSED: [(&str, &str); 0] = [];

/// Scenes whose export is lossy by a documented mapping, rendered and reported but not
/// required to keep their bits: Mitsuba 3's area emitter has no two-sided form
/// (docs/scene-format.md, "Round trip").
const LOSSY: [(&str, &str); 1] = [(
    "many-lights.toml",
    "its two-sided emitters lamp28 and lamp29 export one-sided",
)];

/// What differs between two loaded scenes, for the report: the camera, the lights, the
/// triangle count, the number of materials some triangle uses (an area light's import adds an
/// emitting copy of the material its shape refers to, and the original may then be unused);
/// and the largest relative difference of kd, gr, Δ and emission over the used
/// Lambert-and-lobe materials matched in order of (kd, gr, Δ, emission).
fn differences(a: &bdpm_scene::Scene, b: &bdpm_scene::Scene) -> (Vec<&'static str>, f32) {
    let mut differ = Vec::new();
    if a.camera() != b.camera() {
        differ.push("camera");
    }
    if a.lights() != b.lights() {
        differ.push("lights");
    }
    if a.geometry().triangle_count() != b.geometry().triangle_count() {
        differ.push("triangle count");
    }
    let emitting = |s: &bdpm_scene::Scene| -> Vec<[glam::Vec3; 3]> {
        s.emitters()
            .iter()
            .map(|e| s.geometry().vertices(e.prim))
            .collect()
    };
    if emitting(a) != emitting(b) {
        differ.push("emitting triangles' vertices");
    }
    if textured(a, false) != textured(b, false) {
        differ.push("base-colour textures or their texture coordinates");
    }
    if textured(a, true) != textured(b, true) {
        differ.push("emissive textures or their texture coordinates");
    }
    let key = |s: &bdpm_scene::Scene| {
        let g = s.geometry();
        let used: std::collections::BTreeSet<u32> = (0..g.triangle_count() as u32)
            .map(|t| g.material(t))
            .collect();
        let mut v: Vec<[f32; 10]> = used
            .iter()
            .map(|&i| &s.materials()[i as usize])
            .filter(|m| m.delta.is_none())
            .map(|m| {
                let (kd, gr, le) = (m.bdf.kd(), m.bdf.gr(), m.emission);
                [
                    kd.x,
                    kd.y,
                    kd.z,
                    gr.x,
                    gr.y,
                    gr.z,
                    m.bdf.delta().unwrap_or(0.0),
                    le.x,
                    le.y,
                    le.z,
                ]
            })
            .collect();
        v.sort_by(|p, q| p.partial_cmp(q).expect("finite"));
        v
    };
    let (ka, kb) = (key(a), key(b));
    let worst = ka
        .iter()
        .zip(&kb)
        .flat_map(|(p, q)| {
            p.iter()
                .zip(q)
                .map(|(x, y)| (x - y).abs() / x.abs().max(1e-30))
        })
        .fold(0.0f32, f32::max);
    if ka.len() != kb.len() {
        differ.push("materials");
    }
    (differ, worst)
}

/// Every textured triangle (base colour, or `emissive`) as bits, sorted: its vertices, its
/// texture coordinates, its texture's size and the texels it samples (not the wrap modes:
/// Mitsuba has one for both axes, docs/scene-format.md)
/// (a texture-coordinate or texel that did not come back shows here, not only in a render).
fn textured(s: &bdpm_scene::Scene, emissive: bool) -> Vec<Vec<u32>> {
    let g = s.geometry();
    let mut out: Vec<Vec<u32>> = (0..g.triangle_count() as u32)
        .filter_map(|t| {
            let m = g.material(t);
            let (texture, uv) = if emissive {
                (s.emission_texture(m)?, s.emission_texcoords(t)?)
            } else {
                (s.texture(m)?, s.texcoords(t)?)
            };
            let (w, h) = texture.size();
            let mut key: Vec<u32> = g
                .vertices(t)
                .iter()
                .flat_map(|p| p.to_array())
                .map(f32::to_bits)
                .collect();
            key.extend(uv.iter().flat_map(|p| p.to_array()).map(f32::to_bits));
            key.extend([w, h]);
            for y in 0..h {
                for x in 0..w {
                    key.extend(texture.texel(x, y).to_array().map(f32::to_bits));
                }
            }
            Some(key)
        })
        .collect();
    out.sort_unstable();
    out
}

/// The largest |a − b|/max(|a|, |b|) over two renders' values (as [`bits`] gives them).
fn largest_relative_difference(a: &[u64], b: &[u64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(&x, &y)| {
            let (x, y) = (f64::from_bits(x), f64::from_bits(y));
            let scale = x.abs().max(y.abs());
            if scale == 0.0 {
                0.0
            } else {
                (x - y).abs() / scale
            }
        })
        .fold(
            if a.len() == b.len() {
                0.0
            } else {
                f64::INFINITY
            },
            f64::max,
        )
}

/// A TOML scene's text with its `[[shape]]` tables grouped by material name in ascending order
/// (bdpm's material indices: TOML tables load in name order), keeping their order within a
/// material: the triangle order of the export's per-material meshes. `None` for a scene
/// whose shapes are not all plain tables naming a material (the grouping would be a guess).
fn grouped_by_material(text: &str) -> Option<String> {
    let first = text.find("[[shape]]")?;
    let (head, body) = text.split_at(first);
    let mut shapes: Vec<(String, String)> = Vec::new();
    for block in body.split("[[shape]]").skip(1) {
        // A table ends where the next one starts; what follows the shapes stays with the last.
        if block.contains("\n[") {
            return None;
        }
        let material = block
            .lines()
            .find_map(|l| l.trim().strip_prefix("material = "))?
            .trim_matches('"')
            .to_string();
        shapes.push((material, format!("[[shape]]{block}")));
    }
    shapes.sort_by(|a, b| a.0.cmp(&b.0));
    Some(head.to_string() + &shapes.into_iter().map(|(_, b)| b).collect::<String>())
}

#[test]
fn every_scene_exports_imports_and_renders_the_same_bits() {
    let tmp = tempfile::tempdir().expect("temporary directory");
    let mut report = Vec::new();
    let mut failures = Vec::new();
    for (k, path) in scenes().iter().enumerate() {
        let name = path
            .strip_prefix(scene_path(""))
            .expect("under scenes/")
            .display()
            .to_string();
        let dir = tmp.path().join(k.to_string());
        let imported = match round_trip(path, &dir) {
            Ok(s) => s,
            Err(e) => {
                let expected = REFUSED.iter().any(|(n, el)| *n == name && e.contains(el));
                report.push(format!("{name}: refused: {e}"));
                if !expected {
                    failures.push(name);
                }
                continue;
            }
        };
        let toml = load_scene(path).unwrap_or_else(|e| panic!("{e}"));
        let (mut a, mut b) = (toml.scene, imported.scene);
        let (differ, worst) = differences(&a, &b);
        let (bits_a, bits_b) = (bits(&mut a, &toml.settings), bits(&mut b, &toml.settings));
        let same = bits_a == bits_b;
        // The export writes one mesh per material (bdpm-export's `groups`, in the order of the
        // materials), so the import's triangles come in another order than the TOML file's.
        // Where that moves the image (area-lit scenes in the default mode: a ray meets the
        // other of two triangles along their shared edge, a few pixels' last bits), the TOML
        // file with its shapes grouped the same way must render the import's bits exactly.
        let last = largest_relative_difference(&bits_a, &bits_b);
        let regrouped = (!same && differ.is_empty())
            .then(|| grouped_by_material(&std::fs::read_to_string(path).expect("scene file")))
            .flatten()
            .map(|text| {
                let (mut g, settings) = crate::specular::load(&text);
                bits(&mut g, &settings) == bits_b
            });
        let last_bits = regrouped == Some(true);
        report.push(format!(
            "{name}: {}; differ: {differ:?}; materials within {worst:e} relative",
            match (same, last_bits) {
                (true, _) => "same bits".to_string(),
                (false, true) => format!(
                    "same bits as the file with its shapes grouped by material, as the export \
                     writes them (in the file's order the largest relative difference is {last:e})"
                ),
                (false, false) => format!("bits differ (largest relative difference {last:e})"),
            },
        ));
        let lossy = LOSSY.iter().find(|(n, _)| *n == name);
        if let Some((_, why)) = lossy {
            report.push(format!("{name}: lossy by design: {why}"));
        }
        if !same && !last_bits && lossy.is_none() {
            failures.push(name);
        }
    }
    eprintln!("{}", report.join("\n"));
    assert!(failures.is_empty(), "{failures:?}\n{}", report.join("\n"));
}
