//! Validation of the parsed file and assembly of the [`Scene`]: every check names the dotted
//! field it concerns.

use std::path::{Path, PathBuf};

use bdpm_bdf::Bdf;
use bdpm_geometry::{
    BOX_FACES, Geometry, GeometryError, TriangleMesh, geodesic_sphere_triangle_count,
};

use bdpm_scene::{Camera, CameraError, Material, PointLight, Scene, SceneError, SceneTextures};
// Numbers in messages as written, the same way the settings' messages write them.
use bdpm_settings::number_text as num;
use bdpm_settings::{PartialSettings, RenderSettings};
use glam::{Mat4, Vec2, Vec3};

use crate::gltf_mesh::{Assets, Origin, load_gltf};
use crate::materials::Materials;
use crate::memory::{Budget, MemoryLimit};
use crate::mesh_file::{Held, MeshFormat, MeshOrigin, load_mesh_file};
use crate::schema::{CameraDef, MaterialDef, MeshFileDef, Point, SceneFile, ShapeDef, Triple};
use crate::{LoadError, LoadReport, LoadedScene, limits};

/// The file being loaded: the source of every message's prefix.
struct Ctx<'a> {
    file: &'a Path,
}

impl Ctx<'_> {
    fn bad(&self, field: impl Into<String>, message: impl Into<String>) -> LoadError {
        LoadError::Invalid {
            path: self.file.to_path_buf(),
            field: field.into(),
            message: message.into(),
        }
    }

    fn required<T>(&self, field: &str, value: Option<T>, what: &str) -> Result<T, LoadError> {
        value.ok_or_else(|| self.bad(field, format!("missing (required: {what})")))
    }

    /// A point as written, checked in the precision it was written in (so that 1e300 is
    /// reported as 1e300, not as its f32 rounding `inf`) and converted to f32.
    fn point(&self, field: &str, p: Point) -> Result<Vec3, LoadError> {
        let text = point_text(p.0);
        for c in p.0 {
            if !c.is_finite() {
                return Err(self.bad(field, format!("{text} is not finite (NaN or infinite)")));
            }
            if c.abs() > f32::MAX as f64 {
                return Err(self.bad(
                    field,
                    format!(
                        "{text}: {} is beyond the single-precision range (±3.4e38)",
                        num(c)
                    ),
                ));
            }
        }
        Ok(Vec3::new(p.0[0] as f32, p.0[1] as f32, p.0[2] as f32))
    }

    /// A positive length as written, converted to f32 ([`bdpm_settings::metres`], the check
    /// the render settings' lengths get too).
    fn positive(&self, field: &str, v: f64) -> Result<f32, LoadError> {
        bdpm_settings::metres(v).map_err(|e| self.bad(field, e.to_string()))
    }

    /// A number as written in [lo, hi], compared in f64 (the bounds as written, not their
    /// f32 roundings), converted to f32.
    fn within(&self, field: &str, v: f64, lo: f64, hi: f64) -> Result<f32, LoadError> {
        if v >= lo && v <= hi {
            Ok(v as f32)
        } else {
            Err(self.bad(field, format!("{} is outside [{lo}, {hi}]", num(v))))
        }
    }

    fn count<T: PartialOrd + std::fmt::Display>(
        &self,
        field: &str,
        v: T,
        lo: T,
        hi: T,
    ) -> Result<T, LoadError> {
        if v >= lo && v <= hi {
            Ok(v)
        } else {
            Err(self.bad(field, format!("{v} is outside [{lo}, {hi}]")))
        }
    }

    /// Every channel of `t` finite and in [lo, hi] (checked as written, in f64).
    fn channels(
        &self,
        field: &str,
        t: Triple,
        lo: f64,
        hi: Option<f64>,
    ) -> Result<Vec3, LoadError> {
        let range = match hi {
            Some(hi) => format!("is outside [{lo}, {hi}]"),
            None => format!("must be >= {lo}"),
        };
        let channels = t.value.into_iter().zip(["red", "green", "blue"]);
        for (c, name) in channels {
            if c.is_finite() && c >= lo && hi.is_none_or(|hi| c <= hi) && c <= f32::MAX as f64 {
                continue;
            }
            let range = if c.is_finite() && c > f32::MAX as f64 {
                "is beyond the single-precision range (3.4e38)".to_string()
            } else {
                range.clone()
            };
            let message = if t.scalar {
                format!("{} {range}", num(c))
            } else if !c.is_finite() {
                format!(
                    "{name} channel {} is not finite (in {})",
                    num(c),
                    point_text(t.value)
                )
            } else {
                format!(
                    "{name} channel {} {range} (in {})",
                    num(c),
                    point_text(t.value)
                )
            };
            return Err(self.bad(field, message));
        }
        Ok(Vec3::new(
            t.value[0] as f32,
            t.value[1] as f32,
            t.value[2] as f32,
        ))
    }

    /// `scale` (non-zero finite per axis, also in f32) then `translate` as one matrix.
    fn placement(
        &self,
        prefix: &str,
        scale: Option<Triple>,
        translate: Option<Point>,
    ) -> Result<Mat4, LoadError> {
        let written = scale.map_or([1.0; 3], |s| s.value);
        let s = Vec3::new(written[0] as f32, written[1] as f32, written[2] as f32);
        if !(s.is_finite() && s.cmpne(Vec3::ZERO).all()) {
            return Err(self.bad(
                format!("{prefix}.scale"),
                format!(
                    "{} must be finite and non-zero on every axis (in single precision)",
                    point_text(written)
                ),
            ));
        }
        let t = self.point(
            &format!("{prefix}.translate"),
            translate.unwrap_or(Point([0.0; 3])),
        )?;
        Ok(Mat4::from_translation(t) * Mat4::from_scale(s))
    }
}

fn point_text(p: [f64; 3]) -> String {
    format!("[{}, {}, {}]", num(p[0]), num(p[1]), num(p[2]))
}

pub(crate) fn build(
    file: SceneFile,
    base_dir: &Path,
    display_path: &Path,
    limit: Option<MemoryLimit>,
) -> Result<LoadedScene, LoadError> {
    let ctx = Ctx { file: display_path };
    let mut report = LoadReport::default();

    let render = file.render.unwrap_or_default();
    report.radius_given = render.radius.is_some();
    let (settings, output) = render_settings(&ctx, render)?;
    let mut materials = materials(&ctx, &file.material)?;
    let mut lights = point_lights(&ctx, &file.light)?;
    let mut assets = Assets::new(Budget::new(limit));
    let mut shapes = Shapes::default();
    for (i, shape) in file.shape.iter().enumerate() {
        let prefix = format!("shape[{i}]");
        let mesh = match shape {
            ShapeDef::Mesh(g) => {
                let part = gltf_shape(&ctx, &prefix, g, base_dir, &mut materials, &mut assets)?;
                report
                    .gltf_files
                    .push(base_dir.join(g.file.as_deref().unwrap_or(Path::new(""))));
                count_gltf(&mut report, &part);
                shapes.texcoords.extend_from_slice(&part.texcoords);
                lights.extend(part.lights);
                part.mesh
            }
            ShapeDef::Obj(m) | ShapeDef::Ply(m) => {
                let held = Held {
                    budget: &assets.budget,
                    bytes: assets.budget.textures() + shapes.bytes(),
                };
                let (mesh, path) =
                    mesh_file_shape(&ctx, &prefix, shape, m, base_dir, &materials, &held)?;
                // Listed with the glTF files: the scene's identity hashes their bytes.
                report.gltf_files.push(path);
                mesh
            }
            _ => builtin_shape(
                &ctx,
                &prefix,
                shape,
                &materials,
                &mut shapes.builtin_triangles,
            )?,
        };
        check_placed(&ctx, &prefix, &mesh)?;
        shapes.append(&ctx, mesh)?;
    }
    report.textures = assets.decoded();
    check_geometry_fits(&ctx, &shapes, &assets.budget)?;
    let Shapes {
        mesh, texcoords, ..
    } = shapes;
    let geometry =
        Geometry::new(mesh).map_err(|e| geometry_error(&ctx, e, report.skipped_primitives))?;

    let camera = camera(&ctx, file.camera, settings.width, settings.height)?;

    report.triangles = geometry.triangle_count();
    report.degenerate_triangles = geometry.degenerate_count();
    report.materials = materials.len();
    report.lights = lights.len();

    let light_count = lights.len();
    let (materials, base_colour) = materials.into_parts();
    let textures = SceneTextures {
        base_colour,
        texcoords,
    };
    let scene = Scene::new(geometry, materials, lights, camera)
        .and_then(|s| s.with_textures(textures))
        .map_err(|e| scene_error(&ctx, e, light_count))?;
    Ok(LoadedScene {
        scene,
        settings,
        output,
        report,
    })
}

/// The shapes so far, joined into one mesh as they are read (no second copy of every part),
/// with the texture coordinates of each triangle.
#[derive(Default)]
struct Shapes {
    mesh: TriangleMesh,
    texcoords: Vec<[Vec2; 3]>,
    /// Triangles generated by built-in spheres, against their limit.
    builtin_triangles: u64,
    /// Whether any shape so far has vertex normals (then every vertex has one, zero = flat).
    normals: bool,
}

impl Shapes {
    /// Appends a shape's mesh. Normals are kept per vertex (zero = flat) once any shape has
    /// them, so the result does not depend on the order of the shapes.
    fn append(&mut self, ctx: &Ctx<'_>, part: TriangleMesh) -> Result<(), LoadError> {
        let out = &mut self.mesh;
        let vertices = out.positions.len() + part.positions.len();
        if vertices > u32::MAX as usize {
            return Err(ctx.bad(
                "shape",
                format!("{vertices} vertices in total; at most 2^32 - 1 are supported"),
            ));
        }
        if !part.normals.is_empty() && !self.normals {
            self.normals = true;
            out.normals.resize(out.positions.len(), Vec3::ZERO);
        }
        if self.normals {
            if part.normals.is_empty() {
                out.normals
                    .extend(std::iter::repeat_n(Vec3::ZERO, part.positions.len()));
            } else {
                out.normals.extend_from_slice(&part.normals);
            }
        }
        let base = out.positions.len() as u32;
        out.positions.extend_from_slice(&part.positions);
        out.indices
            .extend(part.indices.iter().map(|t| t.map(|k| k + base)));
        out.materials.extend_from_slice(&part.materials);
        self.texcoords
            .resize(self.texcoords.len().max(out.indices.len()), [Vec2::ZERO; 3]);
        Ok(())
    }

    /// Bytes the joined mesh and texture coordinates hold.
    fn bytes(&self) -> u64 {
        let m = &self.mesh;
        (m.positions.capacity() * size_of::<Vec3>()
            + m.normals.capacity() * size_of::<Vec3>()
            + m.indices.capacity() * size_of::<[u32; 3]>()
            + m.materials.capacity() * size_of::<u32>()
            + self.texcoords.capacity() * size_of::<[Vec2; 3]>()) as u64
    }
}

/// Refuses, before the BVH is built, a geometry that with the texels and the mesh held would
/// not fit in the memory limit: what it keeps (per-triangle data and BVH) and what its build
/// allocates beside that.
fn check_geometry_fits(ctx: &Ctx<'_>, shapes: &Shapes, budget: &Budget) -> Result<(), LoadError> {
    let n = shapes.mesh.indices.len();
    let needs = Geometry::planned_bytes(n).total() + Geometry::build_transient_bytes(n);
    budget
        .check(
            budget.textures() + shapes.bytes(),
            needs,
            "per-triangle data, BVH and the BVH build",
        )
        .map_err(|m| ctx.bad("shape", format!("building the scene's {n} triangles {m}")))
}

/// A `[[shape]]` of type `mesh`: its glTF file, placed, with an optional material override.
fn gltf_shape(
    ctx: &Ctx<'_>,
    prefix: &str,
    g: &crate::schema::MeshDef,
    base_dir: &Path,
    materials: &mut Materials,
    assets: &mut Assets,
) -> Result<crate::gltf_mesh::GltfPart, LoadError> {
    let override_material = match g.material.as_deref() {
        Some(name) => Some(shape_material(ctx, prefix, Some(name), materials, "mesh")?),
        None => None,
    };
    let field = format!("{prefix}.file");
    let written = ctx.required(
        &field,
        g.file.as_ref(),
        "path of a .gltf or .glb file, relative to the scene file",
    )?;
    let path = base_dir.join(written);
    let post = ctx.placement(prefix, g.scale, g.translate)?;
    let origin = Origin {
        path: &path,
        field: &field,
        written,
    };
    load_gltf(&origin, post, override_material, materials, assets)
}

/// A `[[shape]]` of type `obj` or `ply`: its file's triangles, placed, with its material;
/// and the file as opened.
fn mesh_file_shape(
    ctx: &Ctx<'_>,
    prefix: &str,
    shape: &ShapeDef,
    m: &MeshFileDef,
    base_dir: &Path,
    materials: &Materials,
    held: &Held<'_>,
) -> Result<(TriangleMesh, PathBuf), LoadError> {
    let (format, what) = match shape {
        ShapeDef::Ply(_) => (
            MeshFormat::Ply,
            "path of a .ply file, relative to the scene file",
        ),
        _ => (
            MeshFormat::Obj,
            "path of a .obj file, relative to the scene file",
        ),
    };
    let material = shape_material(
        ctx,
        prefix,
        m.material.as_deref(),
        materials,
        shape.type_name(),
    )?;
    let field = format!("{prefix}.file");
    let written = ctx.required(&field, m.file.as_ref(), what)?;
    let path = base_dir.join(written);
    let post = ctx.placement(prefix, m.scale, m.translate)?;
    let origin = MeshOrigin {
        scene: ctx.file,
        field: &field,
        path: &path,
    };
    let mesh = load_mesh_file(&origin, format, post, material, held)?;
    Ok((mesh, path))
}

/// A built-in `quad`, `box` or `sphere` shape as a mesh.
fn builtin_shape(
    ctx: &Ctx<'_>,
    prefix: &str,
    shape: &ShapeDef,
    materials: &Materials,
    builtin_triangles: &mut u64,
) -> Result<TriangleMesh, LoadError> {
    let mut mesh = TriangleMesh::default();
    let material =
        |name: Option<&str>| shape_material(ctx, prefix, name, materials, shape.type_name());
    match shape {
        ShapeDef::Quad(q) => quad(ctx, prefix, q, material(q.material.as_deref())?, &mut mesh)?,
        ShapeDef::Box(b) => cuboid(ctx, prefix, b, material(b.material.as_deref())?, &mut mesh)?,
        ShapeDef::Sphere(sp) => sphere(
            ctx,
            prefix,
            sp,
            material(sp.material.as_deref())?,
            builtin_triangles,
            &mut mesh,
        )?,
        ShapeDef::Mesh(_) | ShapeDef::Obj(_) | ShapeDef::Ply(_) => {
            unreachable!("file shapes are loaded by gltf_shape and mesh_file_shape")
        }
    }
    Ok(mesh)
}

/// A `quad` shape: its four corners, placed, as two triangles.
fn quad(
    ctx: &Ctx<'_>,
    prefix: &str,
    q: &crate::schema::QuadDef,
    material: u32,
    mesh: &mut TriangleMesh,
) -> Result<(), LoadError> {
    let field = format!("{prefix}.vertices");
    let v = ctx.required(&field, q.vertices.as_ref(), "4 points [x, y, z]")?;
    let v: [Point; 4] = v
        .as_slice()
        .try_into()
        .map_err(|_| ctx.bad(&field, format!("{} points given; a quad has 4", v.len())))?;
    let mut checked = [Vec3::ZERO; 4];
    for (k, (p, out)) in v.iter().zip(&mut checked).enumerate() {
        *out = ctx.point(&format!("{field}[{k}]"), *p)?;
    }
    let v = checked;
    let m = ctx.placement(prefix, q.scale, q.translate)?;
    mesh.push_quad(v.map(|p| m.transform_point3(p)), material);
    Ok(())
}

/// A `box` shape: its faces but the open ones, placed, facing out or in.
fn cuboid(
    ctx: &Ctx<'_>,
    prefix: &str,
    b: &crate::schema::BoxDef,
    material: u32,
    mesh: &mut TriangleMesh,
) -> Result<(), LoadError> {
    let lo = ctx.point(
        &format!("{prefix}.min"),
        ctx.required(&format!("{prefix}.min"), b.min, "[x, y, z] in metres")?,
    )?;
    let hi = ctx.point(
        &format!("{prefix}.max"),
        ctx.required(&format!("{prefix}.max"), b.max, "[x, y, z] in metres")?,
    )?;
    if !hi.cmpgt(lo).all() {
        return Err(ctx.bad(
            format!("{prefix}.max"),
            format!("{hi} must exceed min = {lo} on every axis"),
        ));
    }
    let mut keep = [true; 6];
    for (k, face) in b.open.iter().enumerate() {
        let j = BOX_FACES
            .iter()
            .position(|f| f.name == face)
            .ok_or_else(|| {
                ctx.bad(
                    format!("{prefix}.open[{k}]"),
                    format!("unknown face '{face}'; expected one of +x, -x, +y, -y, +z, -z"),
                )
            })?;
        keep[j] = false;
    }
    let inward = facing(ctx, prefix, b.facing.as_deref())?;
    let m = ctx.placement(prefix, b.scale, b.translate)?;
    let (a, c) = (m.transform_point3(lo), m.transform_point3(hi));
    // A negative scale swaps min and max; the box stays the same set of points.
    mesh.push_box(a.min(c), a.max(c), keep, inward, material);
    Ok(())
}

/// A `sphere` shape, counted against the built-in shapes' triangle limit in `total_triangles`.
fn sphere(
    ctx: &Ctx<'_>,
    prefix: &str,
    s: &crate::schema::SphereDef,
    material: u32,
    total_triangles: &mut u64,
    mesh: &mut TriangleMesh,
) -> Result<(), LoadError> {
    let center = ctx.point(
        &format!("{prefix}.center"),
        s.center.unwrap_or(Point([0.0; 3])),
    )?;
    let radius = ctx.required(&format!("{prefix}.radius"), s.radius, "metres")?;
    let radius = ctx.positive(&format!("{prefix}.radius"), radius)?;
    let freq = ctx.count(
        &format!("{prefix}.subdivisions"),
        s.subdivisions
            .unwrap_or(limits::SPHERE_SUBDIVISIONS_DEFAULT),
        1,
        limits::SPHERE_SUBDIVISIONS_MAX,
    )?;
    *total_triangles += geodesic_sphere_triangle_count(freq);
    if *total_triangles > limits::MAX_BUILTIN_TRIANGLES {
        return Err(ctx.bad(
            format!("{prefix}.subdivisions"),
            format!(
                "the built-in shapes would exceed {} triangles",
                limits::MAX_BUILTIN_TRIANGLES
            ),
        ));
    }
    let inward = facing(ctx, prefix, s.facing.as_deref())?;
    mesh.push_geodesic_sphere(center, radius, freq, inward, material);
    Ok(())
}

/// The `[[light]]` tables as point lights.
fn point_lights(
    ctx: &Ctx<'_>,
    defs: &[crate::schema::LightDef],
) -> Result<Vec<PointLight>, LoadError> {
    let mut lights = Vec::with_capacity(defs.len());
    for (i, l) in defs.iter().enumerate() {
        let field = format!("light[{i}]");
        let position = ctx.required(
            &format!("{field}.position"),
            l.position,
            "[x, y, z] in metres",
        )?;
        let position = ctx.point(&format!("{field}.position"), position)?;
        let flux = ctx.required(
            &format!("{field}.flux"),
            l.flux,
            "watts per RGB channel, a number or [r, g, b]",
        )?;
        let flux = ctx.channels(&format!("{field}.flux"), flux, 0.0, None)?;
        lights.push(PointLight { position, flux });
    }
    Ok(lights)
}

/// A shape's vertices after scale and translate: finite, and within the coordinates the BVH
/// builder takes.
fn check_placed(ctx: &Ctx<'_>, prefix: &str, mesh: &TriangleMesh) -> Result<(), LoadError> {
    if let Some(k) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(ctx.bad(
            prefix,
            format!("vertex {k} is not finite after scale and translate (overflow?)"),
        ));
    }
    // The BVH builder (obvhs 0.4) panics when squared extents overflow f32, which happens
    // near 1e19 m; a far smaller bound costs no real scene anything.
    if let Some((k, p)) = mesh
        .positions
        .iter()
        .enumerate()
        .find(|(_, p)| p.abs().max_element() > limits::MAX_COORDINATE)
    {
        return Err(ctx.bad(
            prefix,
            format!(
                "vertex {k} at {p} m is beyond ±{:e} m on some axis",
                limits::MAX_COORDINATE
            ),
        ));
    }
    Ok(())
}

/// Adds a glTF file's counts to the load report.
fn count_gltf(report: &mut LoadReport, part: &crate::gltf_mesh::GltfPart) {
    report.skipped_primitives += part.skipped_primitives;
    report.strips_and_fans += part.strips_and_fans;
    report.skipped_lights += part.skipped_lights;
    report.skipped_cameras += part.skipped_cameras;
    report.textured_materials += part.textured_materials;
    report.other_textures += part.other_textures;
    report.flat_primitives += part.flat_primitives;
}

/// The loader's message for a geometry that cannot be built (`skipped`: glTF point or line
/// primitives left out).
fn geometry_error(ctx: &Ctx<'_>, e: GeometryError, skipped: usize) -> LoadError {
    match e {
        GeometryError::Empty if skipped > 0 => ctx.bad(
            "shape",
            format!(
                "the scene has no triangle with positive area ({skipped} glTF point or line primitive(s) were skipped)"
            ),
        ),
        GeometryError::Empty => ctx.bad("shape", "the scene has no triangle with positive area"),
        other => ctx.bad("shape", other.to_string()),
    }
}

/// The loader's message for a scene that cannot be assembled (`light_count`: lights given).
fn scene_error(ctx: &Ctx<'_>, e: SceneError, light_count: usize) -> LoadError {
    match e {
        SceneError::NoLight if light_count == 0 => ctx.bad(
            "light",
            "the scene has no light; add a [[light]] with position and flux",
        ),
        SceneError::NoLight => ctx.bad(
            "light",
            "every light has zero flux; the image would be black",
        ),
        SceneError::BadLight { index } => ctx.bad(format!("light[{index}]"), e.to_string()),
        SceneError::BadCamera(why) => ctx.bad("camera", why.to_string()),
        SceneError::MissingMaterial { .. } | SceneError::BadTextures { .. } => {
            ctx.bad("shape", e.to_string())
        }
    }
}

/// `facing = "outside" | "inside"`: true for inside.
fn facing(ctx: &Ctx<'_>, prefix: &str, v: Option<&str>) -> Result<bool, LoadError> {
    match v {
        None | Some("outside") => Ok(false),
        Some("inside") => Ok(true),
        Some(other) => Err(ctx.bad(
            format!("{prefix}.facing"),
            format!("unknown value '{other}'; expected \"outside\" or \"inside\""),
        )),
    }
}

fn shape_material(
    ctx: &Ctx<'_>,
    prefix: &str,
    name: Option<&str>,
    materials: &Materials,
    kind: &str,
) -> Result<u32, LoadError> {
    let field = format!("{prefix}.material");
    let name = ctx.required(
        &field,
        name,
        &format!("the name of a [material.NAME] for this {kind}"),
    )?;
    materials.lookup(name).ok_or_else(|| {
        let known = materials.names();
        let known = if known.is_empty() {
            "none are defined".to_string()
        } else {
            format!("defined: {}", known.join(", "))
        };
        ctx.bad(field, format!("unknown material '{name}' ({known})"))
    })
}

fn materials(
    ctx: &Ctx<'_>,
    defs: &std::collections::BTreeMap<String, MaterialDef>,
) -> Result<Materials, LoadError> {
    let mut out = Materials::with_capacity(defs.len());
    for (name, def) in defs {
        let prefix = format!("material.{name}");
        let kd = ctx.required(
            &format!("{prefix}.kd"),
            def.kd,
            "Lambert albedo, a number or [r, g, b] in [0, 1]",
        )?;
        let kd = ctx.channels(&format!("{prefix}.kd"), kd, 0.0, Some(1.0))?;
        let gr = match def.gr {
            Some(gr) => ctx.channels(&format!("{prefix}.gr"), gr, 0.0, Some(1.0))?,
            None => Vec3::ZERO,
        };
        let sum = kd + gr;
        if sum.max_element() > 1.0 + 1e-6 {
            return Err(ctx.bad(&prefix, format!("kd + gr = {sum} exceeds 1 (kd = {kd}, gr = {gr}); the surface would create energy")));
        }
        let bdf = if gr == Vec3::ZERO {
            if let Some(d) = def.delta {
                // A lobe width without a lobe is harmless but still must be a number.
                let _ = ctx.within(
                    &format!("{prefix}.delta"),
                    d,
                    limits::DELTA_MIN_DEGREES,
                    limits::DELTA_MAX_DEGREES,
                )?;
            }
            Bdf::lambert(kd)
        } else {
            let delta = ctx.required(
                &format!("{prefix}.delta"),
                def.delta,
                "lobe width in degrees, needed because gr > 0",
            )?;
            let delta = ctx.within(
                &format!("{prefix}.delta"),
                delta,
                limits::DELTA_MIN_DEGREES,
                limits::DELTA_MAX_DEGREES,
            )?;
            Bdf::new(kd, gr, delta.to_radians())
        }
        .map_err(|e| ctx.bad(&prefix, e.to_string()))?;
        out.add_named(Material {
            name: name.clone(),
            bdf,
        });
    }
    Ok(out)
}

/// The `[render]` table applied onto the defaults ([`PartialSettings::apply`]: the checks
/// the command line's overrides get too), each error named `render.<key>`; and the default
/// output file.
fn render_settings(
    ctx: &Ctx<'_>,
    r: PartialSettings,
) -> Result<(RenderSettings, Option<PathBuf>), LoadError> {
    let mut settings = RenderSettings::default();
    r.apply(&mut settings)
        .map_err(|e| ctx.bad(format!("render.{}", e.setting().key()), e.to_string()))?;
    if let Some(out) = &r.output
        && out.as_os_str().is_empty()
    {
        return Err(ctx.bad(
            "render.output",
            "empty path; leave the key out for no default output",
        ));
    }
    Ok((settings, r.output))
}

fn camera(
    ctx: &Ctx<'_>,
    def: Option<CameraDef>,
    width: u32,
    height: u32,
) -> Result<Camera, LoadError> {
    let def =
        def.ok_or_else(|| ctx.bad("camera", "missing [camera] table (position, look_at, vfov)"))?;
    let position = ctx.point(
        "camera.position",
        ctx.required("camera.position", def.position, "[x, y, z] in metres")?,
    )?;
    let look_at = ctx.point(
        "camera.look_at",
        ctx.required("camera.look_at", def.look_at, "[x, y, z] in metres")?,
    )?;
    let up = ctx.point("camera.up", def.up.unwrap_or(Point([0.0, 1.0, 0.0])))?;
    let vfov = ctx.required("camera.vfov", def.vfov, "vertical field of view in degrees")?;
    if !(vfov.is_finite() && vfov > 0.0 && vfov < 179.0) {
        return Err(ctx.bad(
            "camera.vfov",
            format!("{} is outside (0, 179) degrees", num(vfov)),
        ));
    }
    let vfov = vfov as f32;
    if position == look_at {
        return Err(ctx.bad(
            "camera.look_at",
            "equals camera.position, so there is no viewing direction",
        ));
    }
    Camera::look_at(position, look_at, up, vfov, width, height).map_err(|e| match e {
        SceneError::BadCamera(why @ CameraError::UpParallel) => {
            ctx.bad("camera.up", why.to_string())
        }
        other => ctx.bad("camera", other.to_string()),
    })
}
