//! `<shape>`s as triangle meshes: `obj` and `ply` files through the loader's mesh reader,
//! Mitsuba's built-in `rectangle`, `cube`, `sphere` and `disk` tessellated, `shapegroup`
//! and `instance`; `flip_normals` and `face_normals`; a nested `<emitter type="area">` makes
//! the shape's material emit. Mesh files keep their texture coordinates, in Mitsuba's
//! convention (row 0 of an image at v = 0, as in bdpm; an OBJ's `vt` flipped to 1 − v, a
//! PLY's kept, unless `flip_tex_coords` says otherwise).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use bdpm_geometry::TriangleMesh;
use bdpm_scene::Texture;
use glam::{DMat3, DMat4, DVec3, Vec2, Vec3};
use roxmltree::Node;

use super::doc::{Props, Xml, elements};
use super::{State, sensor, transform};
use crate::LoadError;
use crate::mesh_file::{Held, MeshFormat, MeshOrigin, load_mesh_file_uv};

/// A shape's triangles and the texture coordinates of each of its vertices (empty where the
/// shape has none: built-in shapes, instances, mesh files without them).
pub(crate) struct Part {
    pub(crate) mesh: TriangleMesh,
    pub(crate) uv: Vec<Vec2>,
}

/// An area emitter's radiance and its bitmap texture, if it has one (Le = radiance × texture).
pub(crate) type Emission = (Vec3, Option<Arc<Texture>>);

/// Geodesic frequency of a `sphere`: 20·16² = 5120 triangles, the scene file's default.
pub(crate) const SPHERE_FREQUENCY: u32 = crate::limits::SPHERE_SUBDIVISIONS_DEFAULT;
/// Segments of a tessellated `disk`: its area falls short of π by (2π/256)²/6 ≈ 10⁻⁴.
pub(crate) const DISK_SEGMENTS: u32 = 256;

/// The mesh of `<shape>` element `node`, or `None` for a `shapegroup` (kept by its id for
/// the instances that follow).
pub(crate) fn shape(
    st: &mut State,
    x: &Xml<'_>,
    dir: &Path,
    node: Node<'_, '_>,
) -> Result<Option<Part>, LoadError> {
    let kind = x.need(node, "type")?;
    let emission = attached_emitter(st, x, dir, node, &kind)?;
    if kind == "shapegroup" {
        let id = x.need(node, "id")?;
        let mut group = TriangleMesh::default();
        for c in elements(node).filter(|c| c.tag_name().name() == "shape") {
            if let Some(e) = emitter_of(c) {
                return Err(x.err(e, "an emitter in a shapegroup is not supported: Mitsuba's instances cannot replicate emitters; attach it to a shape outside the group"));
            }
            if let Some(part) = shape(st, x, dir, c)? {
                append(&mut group, part.mesh);
            }
        }
        st.groups.insert(id, group);
        return Ok(None);
    }
    let p = Props::new(node);
    let to_world = transform::to_world(x, &p)?;
    let mut uv = Vec::new();
    let mut mesh = match kind.as_str() {
        "instance" => instance(st, x, node, to_world)?,
        "obj" | "ply" => {
            let material = st.shape_material(x, dir, node, emission)?;
            let (mesh, texcoords) = file_mesh(st, x, dir, &p, &kind, to_world, material)?;
            uv = texcoords;
            mesh
        }
        "rectangle" | "cube" | "sphere" | "disk" => {
            let material = st.shape_material(x, dir, node, emission)?;
            builtin(x, &p, &kind, to_world.unwrap_or(DMat4::IDENTITY), material, &mut st.builtin_triangles)?
        }
        "serialized" => return Err(x.err(node, "Mitsuba's serialized meshes are not supported: convert the mesh to PLY (e.g. load it in Mitsuba and write it with Mesh.write_ply)")),
        other => return Err(x.err(node, format!("shape type \"{other}\" is not supported: bdpm reads obj, ply, rectangle, cube, sphere, disk, shapegroup and instance"))),
    };
    if x.boolean(&p, "face_normals", false)? {
        mesh.normals.clear();
    }
    if x.boolean(&p, "flip_normals", false)? {
        flip(&mut mesh);
    }
    p.unread(x, &format!("<shape type=\"{kind}\">"), &mut st.warnings);
    check(x, node, &mesh)?;
    Ok(Some(Part { mesh, uv }))
}

/// The `<emitter>` element nested in `node`, if any.
fn emitter_of<'a, 'i>(node: Node<'a, 'i>) -> Option<Node<'a, 'i>> {
    elements(node).find(|c| c.tag_name().name() == "emitter")
}

/// The radiance (W·m⁻²·sr⁻¹ per channel, with its texture) of the area emitter nested in
/// shape `node` of type `kind`, if it has one; another emitter type, or an emitter on a
/// `shapegroup` or an `instance` (which Mitsuba refuses too), is an error.
fn attached_emitter(
    st: &mut State,
    x: &Xml<'_>,
    dir: &Path,
    node: Node<'_, '_>,
    kind: &str,
) -> Result<Option<Emission>, LoadError> {
    let Some(e) = emitter_of(node) else {
        return Ok(None);
    };
    if matches!(kind, "shapegroup" | "instance") {
        return Err(x.err(e, format!("an emitter on a {kind} is not supported: Mitsuba's instances cannot replicate emitters; attach it to each shape")));
    }
    match x.attr(e, "type")?.as_deref() {
        Some("area") => {
            let mut loader = st.loader(dir);
            let (le, texture) = sensor::area_radiance(x, e, loader.warnings, &mut loader.bitmaps)?;
            Ok(Some((le.as_vec3(), texture)))
        }
        _ => Err(x.err(
            e,
            "only an area emitter can be attached to a shape (bdpm's emitting surfaces are Lambert emitters)",
        )),
    }
}

/// An `obj` or `ply` file, placed by `to_world`, and its vertices' texture coordinates:
/// v flipped to 1 − v where `flip_tex_coords` is true (Mitsuba's default for OBJ files, whose
/// `vt` has v up, not for PLY files), so that row 0 of an image is at v = 0 as in bdpm.
fn file_mesh(
    st: &mut State,
    x: &Xml<'_>,
    dir: &Path,
    p: &Props<'_, '_>,
    kind: &str,
    to_world: Option<DMat4>,
    material: u32,
) -> Result<(TriangleMesh, Vec<Vec2>), LoadError> {
    let node = p.node();
    let name = x
        .string(p, "filename")?
        .ok_or_else(|| x.err(node, "missing <string name=\"filename\">"))?;
    let path = st.resolve(dir, &name);
    let format = if kind == "ply" {
        MeshFormat::Ply
    } else {
        MeshFormat::Obj
    };
    let field = format!(
        "line {}: {}",
        super::doc::line(node),
        super::doc::what(node)
    );
    let origin = MeshOrigin {
        scene: x.file,
        field: &field,
        path: &path,
    };
    let held = Held {
        budget: &st.budget,
        bytes: st.budget.textures() + st.shapes.bytes(),
    };
    let post = to_world.unwrap_or(DMat4::IDENTITY).as_mat4();
    let (mesh, mut uv) = load_mesh_file_uv(&origin, format, post, material, &held)?;
    st.files.push(path);
    if x.boolean(p, "flip_tex_coords", format == MeshFormat::Obj)? {
        // In f32, as Mitsuba flips them.
        uv.iter_mut().for_each(|t| t.y = 1.0 - t.y);
    }
    // Mitsuba's limits and counts of OBJ groups change nothing bdpm renders.
    p.ignore(&["maximum_area_lights", "vertex_count", "face_count"]);
    Ok((mesh, uv))
}

/// A `shapegroup`'s triangles placed by an `instance`'s `to_world`.
fn instance(
    st: &State,
    x: &Xml<'_>,
    node: Node<'_, '_>,
    to_world: Option<DMat4>,
) -> Result<TriangleMesh, LoadError> {
    let r = elements(node)
        .find(|c| c.tag_name().name() == "ref")
        .ok_or_else(|| x.err(node, "missing <ref id=…> to a shapegroup"))?;
    let id = x.need(r, "id")?;
    let group = st.groups.get(&id).ok_or_else(|| {
        x.err(
            r,
            format!("no <shape type=\"shapegroup\" id=\"{id}\"> before this reference"),
        )
    })?;
    Ok(place(group.clone(), to_world.unwrap_or(DMat4::IDENTITY)))
}

/// Mitsuba's built-in shapes in their own frame, placed by `m`: `rectangle` [−1, 1]² at
/// z = 0 facing +z, `cube` [−1, 1]³ facing out, `sphere` of `center` and `radius` (smooth,
/// [`SPHERE_FREQUENCY`]), `disk` of radius 1 at z = 0 facing +z ([`DISK_SEGMENTS`]).
fn builtin(
    x: &Xml<'_>,
    p: &Props<'_, '_>,
    kind: &str,
    mut m: DMat4,
    material: u32,
    total: &mut u64,
) -> Result<TriangleMesh, LoadError> {
    let mut mesh = TriangleMesh::default();
    match kind {
        "rectangle" => mesh.push_quad(
            [
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
            ],
            material,
        ),
        "cube" => mesh.push_box(Vec3::splat(-1.0), Vec3::ONE, [true; 6], false, material),
        "disk" => {
            mesh.positions.push(Vec3::ZERO);
            for k in 0..DISK_SEGMENTS {
                let a = std::f64::consts::TAU * f64::from(k) / f64::from(DISK_SEGMENTS);
                mesh.positions
                    .push(Vec3::new(a.cos() as f32, a.sin() as f32, 0.0));
                mesh.indices.push([0, k + 1, (k + 1) % DISK_SEGMENTS + 1]);
                mesh.materials.push(material);
            }
        }
        _ => {
            let center = match p.get("center") {
                Some(n) => x.xyz(n, 0.0)?,
                None => DVec3::ZERO,
            };
            let radius = x.float(p, "radius", 1.0)?;
            if radius <= 0.0 {
                return Err(x.err(p.node(), format!("radius {radius} is not positive")));
            }
            *total += bdpm_geometry::geodesic_sphere_triangle_count(SPHERE_FREQUENCY);
            if *total > crate::limits::MAX_BUILTIN_TRIANGLES {
                return Err(x.err(
                    p.node(),
                    format!(
                        "the built-in shapes would exceed {} triangles",
                        crate::limits::MAX_BUILTIN_TRIANGLES
                    ),
                ));
            }
            mesh.push_geodesic_sphere(Vec3::ZERO, 1.0, SPHERE_FREQUENCY, false, true, material);
            m = m * DMat4::from_translation(center) * DMat4::from_scale(DVec3::splat(radius));
        }
    }
    Ok(place(mesh, m))
}

/// `mesh` transformed by `m`: positions, normals by the inverse transpose (renormalised),
/// and the winding reversed where `m` mirrors, so that each triangle faces where its
/// transformed normal points, as in Mitsuba.
fn place(mut mesh: TriangleMesh, m: DMat4) -> TriangleMesh {
    if m == DMat4::IDENTITY {
        return mesh;
    }
    let normal_matrix = DMat3::from_mat4(m).inverse().transpose();
    for p in &mut mesh.positions {
        *p = m.transform_point3(p.as_dvec3()).as_vec3();
    }
    for n in &mut mesh.normals {
        *n = (normal_matrix * n.as_dvec3()).normalize_or_zero().as_vec3();
    }
    if m.determinant() < 0.0 {
        flip_winding(&mut mesh);
    }
    mesh
}

fn flip_winding(mesh: &mut TriangleMesh) {
    for t in &mut mesh.indices {
        t.swap(1, 2);
    }
}

/// `flip_normals`: the other side is the front (it matters to glass).
fn flip(mesh: &mut TriangleMesh) {
    flip_winding(mesh);
    for n in &mut mesh.normals {
        *n = -*n;
    }
}

/// Appends `part` to `out` (flat parts get zero normals where `out` has normals: flat).
fn append(out: &mut TriangleMesh, part: TriangleMesh) {
    let smooth = !out.normals.is_empty() || !part.normals.is_empty();
    if smooth {
        out.normals.resize(out.positions.len(), Vec3::ZERO);
    }
    let base = out.positions.len() as u32;
    out.positions.extend_from_slice(&part.positions);
    if smooth {
        if part.normals.is_empty() {
            out.normals.resize(out.positions.len(), Vec3::ZERO);
        } else {
            out.normals.extend_from_slice(&part.normals);
        }
    }
    out.indices
        .extend(part.indices.iter().map(|t| t.map(|k| k + base)));
    out.materials.extend_from_slice(&part.materials);
}

/// Finite vertices within the coordinates the BVH takes, and at least one triangle with area.
fn check(x: &Xml<'_>, node: Node<'_, '_>, mesh: &TriangleMesh) -> Result<(), LoadError> {
    let max = crate::limits::MAX_COORDINATE;
    if let Some((k, p)) = mesh
        .positions
        .iter()
        .enumerate()
        .find(|(_, p)| !p.is_finite() || p.abs().max_element() > max)
    {
        return Err(x.err(
            node,
            format!("vertex {k} at {p} m is not finite or beyond ±{max:e} m after to_world"),
        ));
    }
    let area = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        (b - a).cross(c - a).length()
    };
    if !mesh.indices.iter().any(|t| area(t) > 0.0) {
        return Err(x.err(
            node,
            format!(
                "all {} triangles have zero area (a degenerate mesh, or a zero scale in to_world)",
                mesh.indices.len()
            ),
        ));
    }
    Ok(())
}

/// The search list for a file name: the directory of the file that names it, then the
/// `<path>` directories in order; the first that holds it (else the first, for the message).
pub(crate) fn resolve(dir: &Path, search: &[PathBuf], name: &str) -> PathBuf {
    let first = dir.join(name);
    if first.exists() {
        return first;
    }
    search
        .iter()
        .map(|d| d.join(name))
        .find(|p| p.exists())
        .unwrap_or(first)
}
