//! Export of a loaded bdpm scene to Mitsuba 3, so that another renderer can render the same
//! scene: `scene.xml` (Mitsuba's scene format version 3.0.0), the triangles bdpm renders as
//! binary PLY files under `meshes/`, base-colour textures as float EXR images under
//! `textures/`, and `export.json`, the report (counts, files, and every approximation the
//! mapping made).
//!
//! The scene exported is the *loaded* one: the triangle meshes after placement, glTF node
//! transforms and sphere tessellation, with their vertex normals and texture coordinates,
//! in the frame bdpm renders in (the geometry's local frame, `Geometry::origin`, the world frame
//! unless the scene lies far from the origin); so both renderers intersect the same f32
//! triangles. The mapping (docs/scene-format.md, "Export to Mitsuba 3"):
//!
//! - camera → `perspective`, `fov` = bdpm's vertical field of view with `fov_axis` = `y`,
//!   `to_world` a `lookat`, film `hdrfilm` at the render resolution with a `box` filter (a
//!   pixel is the mean over its square, as bdpm's jittered samples make it);
//! - point light of flux Φ (W per channel) → `point` of intensity Φ/(4π) W/sr;
//! - Lambert → `twosided` `diffuse`; mirror → `twosided` `conductor`; dielectric →
//!   `dielectric`; Lambert plus Gaussian lobe → a stand-in with a warning (see `bsdf`).
//!
//! Architecture: reads a [`Scene`], writes files only through [`write()`] (staged, then
//! committed as a set by bdpm-output's `files`).

mod bsdf;
mod image;
mod mesh;
mod xml;

use std::fs;
use std::path::{Path, PathBuf};

use bdpm_scene::Scene;
use bdpm_settings::RenderSettings;
use glam::Vec3;
use serde::Serialize;

use crate::xml::{Element, named, num, triple};

/// The scene format version written into `<scene version="...">`.
pub const MITSUBA_VERSION: &str = "3.0.0";
/// The scene file's name inside the export directory.
pub const SCENE_FILE: &str = "scene.xml";
/// The report's name inside the export directory.
pub const REPORT_FILE: &str = "export.json";

/// Why an export failed: one line naming the file and what is wrong.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// A file or directory of the output cannot be made or written.
    #[error("{}: {message}", path.display())]
    Output {
        /// The file or directory.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The staged files could not all be moved into place (the message names the file and
    /// says whether the previous set is back).
    #[error("{0}")]
    Commit(String),
    /// A material's texture could not be encoded.
    #[error("{}: material '{material}': {message}", scene.display())]
    Texture {
        /// The scene file.
        scene: PathBuf,
        /// The material's name.
        material: String,
        /// What is wrong.
        message: String,
    },
}

/// One file of an export.
#[derive(Clone, Debug)]
pub struct ExportFile {
    /// Path relative to the export directory, with `/` separators.
    pub path: String,
    /// Its contents.
    pub bytes: Vec<u8>,
}

/// What an export wrote and what it changed: `export.json`.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ExportReport {
    /// The scene file exported, as given.
    pub scene: String,
    /// `"mitsuba"` and the scene format version.
    pub format: String,
    /// Film size, pixels.
    pub resolution: [u32; 2],
    /// The sampler's default `sample_count` (`$spp`): bdpm's camera samples per pixel over all
    /// passes, spp × passes.
    pub sample_count: u64,
    /// `<shape>` elements: one PLY mesh per material and kind of shading.
    pub shapes: usize,
    /// Triangles written.
    pub triangles: usize,
    /// Triangles of the scene left out as bdpm's BVH leaves them out: zero-area ones and
    /// exact duplicates.
    pub left_out_triangles: usize,
    /// `<bsdf>` elements: one per material used by a triangle.
    pub bsdfs: usize,
    /// `<emitter>` elements: one per point light.
    pub emitters: usize,
    /// Texture images written.
    pub textures: usize,
    /// The world position of the exported frame's origin, metres: every position in the
    /// export is world minus this (zero unless the scene lies far from the origin).
    pub frame_origin: [f32; 3],
    /// Every approximation of the mapping, one line each (also printed as warnings).
    pub warnings: Vec<String>,
    /// The files of the export, relative to its directory, `scene.xml` last.
    pub files: Vec<String>,
}

/// An export held in memory: its files (the scene file last) and its report.
#[derive(Clone, Debug)]
pub struct Export {
    /// The files, `export.json` and `scene.xml` last.
    pub files: Vec<ExportFile>,
    /// The report (also the contents of `export.json`).
    pub report: ExportReport,
}

/// The Mitsuba 3 export of `scene`, rendered with `settings` (its resolution is the
/// camera's; spp × passes is the sampler's default sample count), loaded from `source` (for
/// messages and the report).
pub fn mitsuba(
    scene: &Scene,
    settings: &RenderSettings,
    source: &Path,
) -> Result<Export, ExportError> {
    let camera = scene.camera();
    let mut report = ExportReport {
        scene: source.display().to_string(),
        format: format!("mitsuba {MITSUBA_VERSION}"),
        resolution: [camera.width(), camera.height()],
        sample_count: u64::from(settings.spp) * u64::from(settings.passes),
        frame_origin: scene.geometry().origin().to_array(),
        ..ExportReport::default()
    };
    if !settings.pixel_jitter {
        report.warnings.push(
            "the scene renders without pixel jitter (every camera sample through the pixel \
             centre); Mitsuba's box filter averages over the pixel"
                .to_string(),
        );
    }
    if scene.geometry().origin() != Vec3::ZERO {
        report.warnings.push(format!(
            "the scene lies far from the origin: exported in bdpm's render frame, every position \
             shifted by -({})",
            triple(scene.geometry().origin())
        ));
    }
    let mut root = Element::new("scene")
        .attr("version", MITSUBA_VERSION)
        .child(Element::new("default").attr("name", "spp").attr(
            "value",
            report.sample_count.min(u64::from(u32::MAX)).to_string(),
        ))
        .child(Element::plugin("integrator", "path").integer("max_depth", "-1"))
        .child(sensor(scene))
        .comment("point lights: bdpm's flux (W per channel) / (4 pi) as intensity (W/sr)");
    for light in scene.lights() {
        let p = light.position;
        root = root.child(
            Element::plugin("emitter", "point")
                .child(
                    named("point", "position")
                        .attr("x", num(f64::from(p.x)))
                        .attr("y", num(f64::from(p.y)))
                        .attr("z", num(f64::from(p.z))),
                )
                .child(named("rgb", "intensity").attr(
                    "value",
                    light.flux.to_array().map(intensity_text).join(", "),
                )),
        );
        report.emitters += 1;
    }
    let mut files = Vec::new();
    root = add_shapes(scene, source, root, &mut files, &mut report)?;
    report.files = files.iter().map(|f: &ExportFile| f.path.clone()).collect();
    report.files.push(REPORT_FILE.to_string());
    report.files.push(SCENE_FILE.to_string());
    let json = serde_json::to_vec_pretty(&report).map_err(|e| ExportError::Output {
        path: PathBuf::from(REPORT_FILE),
        message: format!("cannot encode the report: {e}"),
    })?;
    files.push(ExportFile {
        path: REPORT_FILE.to_string(),
        bytes: json,
    });
    let header = format!(
        "Mitsuba 3 scene exported by `bdpm export` from {} (docs/scene-format.md, \"Export to \
         Mitsuba 3\")",
        source.display()
    );
    files.push(ExportFile {
        path: SCENE_FILE.to_string(),
        bytes: root.document(&header),
    });
    Ok(Export { files, report })
}

/// A point light's intensity Φ/(4π) for a flux channel Φ, W/sr: the shortest f32 text where
/// 4π times it, in f64, rounds back to Φ (bdpm's import reads it so), else the f64 digits of
/// the quotient, which do (Mitsuba reads either in single precision).
fn intensity_text(flux: f32) -> String {
    let four_pi = 4.0 * std::f64::consts::PI;
    let quotient = f64::from(flux) / four_pi;
    let single = quotient as f32;
    if (f64::from(single) * four_pi) as f32 == flux {
        num(f64::from(single))
    } else {
        num(quotient)
    }
}

/// The `<sensor>`: bdpm's pinhole as Mitsuba's `perspective`. Pixel (i, j) of bdpm covers
/// [i, i + 1) × [j, j + 1) of an image plane whose height spans the vertical field of view
/// (`Camera::ray_direction`), as Mitsuba's film with `fov_axis` = `y` does; the `box`
/// filter of radius ½ pixel weighs every sample of the pixel alike and none of its
/// neighbours', as bdpm's box pixels do. The clipping planes hold the whole scene: `far_clip`
/// twice the distance to its farthest corner, `near_clip` 10⁻⁶ of that (bdpm clips nothing).
fn sensor(scene: &Scene) -> Element {
    let camera = scene.camera();
    let (lo, hi) = scene.geometry().bounds();
    let eye = camera.position();
    let far = (0..8)
        .map(|i| {
            let corner = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            f64::from(corner.distance(eye))
        })
        .fold(0.0f64, f64::max)
        .max(1e-3)
        * 2.0;
    let film = Element::plugin("film", "hdrfilm")
        .integer("width", camera.width().to_string())
        .integer("height", camera.height().to_string())
        .string("pixel_format", "rgb")
        .string("component_format", "float32")
        .child(Element::plugin("rfilter", "box"));
    // The inputs of bdpm's look-at as given, so that Mitsuba and bdpm's import build the
    // frame from the same numbers (position + forward, renormalised, would round).
    let lookat = Element::new("lookat")
        .attr("origin", triple(eye))
        .attr("target", triple(camera.target()))
        .attr("up", triple(camera.up_given()));
    Element::plugin("sensor", "perspective")
        .float("fov", f64::from(camera.vfov_degrees()))
        .string("fov_axis", "y")
        .float("near_clip", far * 1e-6)
        .float("far_clip", far)
        .child(named("transform", "to_world").child(lookat))
        .child(Element::plugin("sampler", "independent").integer("sample_count", "$spp"))
        .child(film)
}

/// Adds a `<bsdf>` for each material a triangle uses and a `<shape>` for each group of
/// triangles ([`mesh::groups`]), and their PLY and texture files to `files`.
fn add_shapes(
    scene: &Scene,
    source: &Path,
    mut root: Element,
    files: &mut Vec<ExportFile>,
    report: &mut ExportReport,
) -> Result<Element, ExportError> {
    let groups = mesh::groups(scene);
    let mut mapped: Vec<u32> = Vec::new();
    for group in &groups {
        if mapped.contains(&group.material) {
            continue;
        }
        mapped.push(group.material);
        let material = &scene.materials()[group.material as usize];
        let m = bsdf::map(group.material, material, scene.texture(group.material)).map_err(
            |message| ExportError::Texture {
                scene: source.to_path_buf(),
                material: material.name.clone(),
                message,
            },
        )?;
        root = root.comment(&format!("material '{}'", material.name));
        root = root.child(m.element);
        report.bsdfs += 1;
        report.warnings.extend(m.warnings);
        if let Some((path, bytes)) = m.texture {
            files.push(ExportFile { path, bytes });
            report.textures += 1;
        }
    }
    for group in &groups {
        let material = &scene.materials()[group.material as usize];
        let name = format!(
            "meshes/{}-{}{}.ply",
            bsdf::id(group.material),
            file_safe(&material.name),
            if group.smooth { "-smooth" } else { "" }
        );
        let mut shape = Element::plugin("shape", "ply").string("filename", &name);
        if !group.smooth {
            shape = shape.boolean("face_normals", true);
        }
        shape = shape.child(Element::new("ref").attr("id", bsdf::id(group.material)));
        if material.emits() {
            let (emitter, image) = area_emitter(scene, source, group, report)?;
            shape = shape.child(emitter);
            // Once per material, whatever its groups (smooth and flat triangles).
            if let Some((path, bytes)) = image.filter(|(p, _)| !files.iter().any(|f| &f.path == p))
            {
                files.push(ExportFile { path, bytes });
                report.textures += 1;
            }
        }
        root = root.child(shape);
        let comment = format!("bdpm material '{}'", material.name);
        files.push(ExportFile {
            path: name,
            bytes: mesh::ply(group, &comment),
        });
        report.shapes += 1;
        report.triangles += group.positions.len();
    }
    report.left_out_triangles = scene.geometry().triangle_count() - report.triangles;
    Ok(root)
}

/// The `<emitter type="area">` of an emitting material's shape (`group`): Mitsuba's area
/// emitter sends its radiance from the front side (the triangles' winding normals, which the
/// PLY keeps), as bdpm's one-sided emission does; a two-sided emitter is exported one-sided
/// with a warning. An emissive texture becomes the radiance's `bitmap` (`textures/matK-
/// emission.exr`: bdpm's linear texels times the emission factor, returned to be written),
/// read through the PLY's texture coordinates.
fn area_emitter(
    scene: &Scene,
    source: &Path,
    group: &mesh::Group,
    report: &mut ExportReport,
) -> Result<(Element, Option<bsdf::Image>), ExportError> {
    let material = &scene.materials()[group.material as usize];
    if material.two_sided_emission {
        report.warnings.push(format!(
            "material '{}' emits from both sides; Mitsuba's area emitter emits from the front \
             side only (exported one-sided)",
            material.name
        ));
    }
    report.emitters += 1;
    let emitter = Element::plugin("emitter", "area");
    let Some(texture) = scene.emission_texture(group.material) else {
        return Ok((emitter.rgb("radiance", material.emission), None));
    };
    let path = format!("textures/{}-emission.exr", bsdf::id(group.material));
    let bitmap = bsdf::bitmap(
        texture,
        "radiance",
        &path,
        &material.name,
        &mut report.warnings,
    );
    let bytes = image::exr(texture, material.emission).map_err(|message| ExportError::Texture {
        scene: source.to_path_buf(),
        material: material.name.clone(),
        message,
    })?;
    if scene.texture(group.material).is_some() {
        report.warnings.push(format!(
            "material '{}' has a base-colour and an emissive texture; the PLY carries one set \
             of texture coordinates, the base colour's, which the emission is read through \
             (exact where both textures use the same coordinates)",
            material.name
        ));
    }
    Ok((emitter.child(bitmap), Some((path, bytes))))
}

/// A material name as a short file-name part: ASCII letters, digits, `-` and `_` kept,
/// everything else `_`, at most 40 characters.
fn file_safe(name: &str) -> String {
    name.chars()
        .take(40)
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Writes `export`'s files into `dir` (created if missing) as a set: each staged under a
/// temporary name beside its target, then all renamed into place, `scene.xml` last, the
/// previous files kept until every rename has succeeded (bdpm-output's `commit_all`).
pub fn write(export: &Export, dir: &Path) -> Result<(), ExportError> {
    let error = |path: &Path, message: String| ExportError::Output {
        path: path.to_path_buf(),
        message,
    };
    if let Ok(meta) = fs::metadata(dir)
        && !meta.is_dir()
    {
        return Err(error(
            dir,
            "is a file, not a directory: the export writes a directory (scene.xml, meshes/, \
             textures/, export.json)"
                .to_string(),
        ));
    }
    let mut staged = Vec::with_capacity(export.files.len());
    for file in &export.files {
        let target = dir.join(&file.path);
        if let Some(parent) = target.parent() {
            fs::create_dir_all(parent)
                .map_err(|e| error(parent, format!("cannot create the directory: {e}")))?;
        }
        if target.is_dir() {
            return Err(error(&target, "is a directory".to_string()));
        }
        staged.push(
            bdpm_output::files::stage_bytes(&target, &file.bytes)
                .map_err(|message| error(&target, message))?,
        );
    }
    bdpm_output::files::commit_all(staged).map_err(ExportError::Commit)
}

// The README (the crate's page on crates.io) as a hidden item, so that `cargo test --doc`
// compiles and runs its example; the crate documentation above stays as it is.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
