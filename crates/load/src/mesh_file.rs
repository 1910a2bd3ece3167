//! OBJ and PLY mesh files → triangles with optional per-vertex normals and texture
//! coordinates, one material.
//!
//! The crates parse (`tobj` for OBJ, `ply-rs-bw` for PLY); this module checks what they give:
//! finite coordinates, indices in range, at least one face. Polygons are split into fans
//! (vertex 0 with each following edge), the order the built-in quad uses, so that a quad
//! written in a file gives the very triangles of the same `type = "quad"`.

use std::io::{BufRead, BufReader, Read as _};
use std::path::Path;

use bdpm_geometry::{Geometry, TriangleMesh};
use glam::{Mat3, Mat4, Vec2, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{ElementDef, Property, PropertyAccess, PropertyType};

use crate::LoadError;
use crate::files::open_regular;
use crate::limits::MAX_MESH_FILE_BYTES;
use crate::memory::Budget;

/// The two formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MeshFormat {
    /// Wavefront OBJ.
    Obj,
    /// Stanford PLY, ASCII or binary.
    Ply,
}

impl MeshFormat {
    fn name(self) -> &'static str {
        match self {
            MeshFormat::Obj => "OBJ file",
            MeshFormat::Ply => "PLY file",
        }
    }
}

/// Where the mesh file came from, for messages.
pub(crate) struct MeshOrigin<'a> {
    /// The scene file.
    pub(crate) scene: &'a Path,
    /// The field that named the file, such as `shape[2].file`.
    pub(crate) field: &'a str,
    /// The file to open (joined to the scene file's directory).
    pub(crate) path: &'a Path,
}

impl MeshOrigin<'_> {
    fn err(&self, message: impl Into<String>) -> LoadError {
        LoadError::MeshFile {
            scene: self.scene.to_path_buf(),
            field: self.field.to_string(),
            path: self.path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// The memory account a mesh file is read against: the budget, and the bytes the scene
/// holds already (textures and the shapes before this one).
pub(crate) struct Held<'a> {
    pub(crate) budget: &'a Budget,
    pub(crate) bytes: u64,
}

/// Vertices and polygons as read from a file, before triangulation and placement.
#[derive(Default)]
struct RawMesh {
    positions: Vec<[f32; 3]>,
    /// One per position, or empty.
    normals: Vec<[f32; 3]>,
    /// Texture coordinates as the file writes them (OBJ `vt`, PLY `u v` and its synonyms),
    /// one per position, or empty.
    texcoords: Vec<[f32; 2]>,
    /// Triangles, already split into fans.
    triangles: Vec<[u32; 3]>,
}

/// Reads the mesh file of `origin` and returns its triangles placed by `post`, all with
/// `material`. Normals (when the file has them for every vertex) are transformed by the
/// inverse transpose of `post`; without them the mesh is flat (empty `normals`).
pub(crate) fn load_mesh_file(
    origin: &MeshOrigin<'_>,
    format: MeshFormat,
    post: Mat4,
    material: u32,
    held: &Held<'_>,
) -> Result<TriangleMesh, LoadError> {
    load_mesh_file_uv(origin, format, post, material, held).map(|(mesh, _)| mesh)
}

/// [`load_mesh_file`] with the texture coordinates of each vertex of the mesh, as the file
/// writes them (no flip of v: that is the caller's convention), or empty when the file has
/// none. A file where some vertices have them and others not gives (0, 0) to the others.
pub(crate) fn load_mesh_file_uv(
    origin: &MeshOrigin<'_>,
    format: MeshFormat,
    post: Mat4,
    material: u32,
    held: &Held<'_>,
) -> Result<(TriangleMesh, Vec<Vec2>), LoadError> {
    let file = open_regular(origin.path, MAX_MESH_FILE_BYTES, format.name())
        .map_err(|e| origin.err(e.to_string()))?;
    let reader = BufReader::new(file.take(MAX_MESH_FILE_BYTES + 1));
    let raw = match format {
        MeshFormat::Obj => read_obj(origin, reader)?,
        MeshFormat::Ply => read_ply(origin, reader, held)?,
    };
    check_raw(origin, &raw)?;
    let needs = raw_mesh_bytes(
        raw.positions.len(),
        !raw.normals.is_empty(),
        raw.triangles.len(),
    ) + (raw.texcoords.len() * size_of::<Vec2>()) as u64;
    held.budget
        .check(held.bytes, needs, "its vertices and triangles")
        .map_err(|m| origin.err(format!("keeping it {m}")))?;
    let texcoords = raw.texcoords.iter().map(|&t| Vec2::from(t)).collect();
    Ok((place(raw, post, material), texcoords))
}

/// Bytes of a mesh of `vertices` (with normals or not) and `triangles` as the scene keeps it.
fn raw_mesh_bytes(vertices: usize, normals: bool, triangles: usize) -> u64 {
    let per_vertex = size_of::<Vec3>() * if normals { 2 } else { 1 };
    (vertices * per_vertex + triangles * (size_of::<[u32; 3]>() + size_of::<u32>())) as u64
}

/// Finite coordinates and normals, indices in range, at least one triangle.
fn check_raw(origin: &MeshOrigin<'_>, raw: &RawMesh) -> Result<(), LoadError> {
    if raw.triangles.is_empty() {
        return Err(origin.err("has no faces (no triangle to render)"));
    }
    if let Some((k, p)) = raw
        .positions
        .iter()
        .enumerate()
        .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
    {
        return Err(origin.err(format!(
            "vertex {k} at {p:?} is not finite (NaN or infinite)"
        )));
    }
    if let Some((k, n)) = raw
        .normals
        .iter()
        .enumerate()
        .find(|(_, n)| !n.iter().all(|c| c.is_finite()))
    {
        return Err(origin.err(format!(
            "the normal of vertex {k}, {n:?}, is not finite (NaN or infinite)"
        )));
    }
    if let Some((k, t)) = raw
        .texcoords
        .iter()
        .enumerate()
        .find(|(_, t)| !t.iter().all(|c| c.is_finite()))
    {
        return Err(origin.err(format!(
            "the texture coordinates of vertex {k}, {t:?}, are not finite (NaN or infinite)"
        )));
    }
    let count = raw.positions.len();
    for (f, t) in raw.triangles.iter().enumerate() {
        if let Some(&i) = t.iter().find(|&&i| i as usize >= count) {
            return Err(origin.err(format!(
                "triangle {f} names vertex {i}, but the file has {count} vertices"
            )));
        }
    }
    Ok(())
}

/// The checked mesh placed by `post`: positions transformed, normals by the inverse
/// transpose and renormalised (zero stays zero: flat at that vertex).
fn place(raw: RawMesh, post: Mat4, material: u32) -> TriangleMesh {
    let normal_matrix = Mat3::from_mat4(post).inverse().transpose();
    let positions = raw
        .positions
        .iter()
        .map(|&p| post.transform_point3(Vec3::from(p)))
        .collect();
    let normals = raw
        .normals
        .iter()
        .map(|&n| (normal_matrix * Vec3::from(n)).normalize_or_zero())
        .collect();
    let materials = vec![material; raw.triangles.len()];
    TriangleMesh {
        positions,
        normals,
        indices: raw.triangles,
        materials,
    }
}

/// Splits polygon `face` (vertex indices) into a fan of triangles appended to `out`.
fn fan(face: &[u32], out: &mut Vec<[u32; 3]>) {
    for k in 2..face.len() {
        out.push([face[0], face[k - 1], face[k]]);
    }
}

// ---- OBJ

/// A reader that counts the lines handed out, so that an error tobj reports without a line
/// can be given the line it stopped at.
struct LineCounter<R> {
    inner: R,
    lines: usize,
    /// Whether the last byte consumed ended a line.
    at_line_start: bool,
}

impl<R: std::io::Read> std::io::Read for LineCounter<BufReader<R>> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.count(&buf[..n]);
        Ok(n)
    }
}

impl<R: std::io::Read> BufRead for LineCounter<BufReader<R>> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        self.inner.fill_buf()
    }

    fn consume(&mut self, amt: usize) {
        let consumed = self.inner.buffer()[..amt].to_vec();
        self.count(&consumed);
        self.inner.consume(amt);
    }
}

impl<R> LineCounter<R> {
    fn count(&mut self, bytes: &[u8]) {
        if let Some(&last) = bytes.last() {
            self.lines += bytes.iter().filter(|&&b| b == b'\n').count();
            self.at_line_start = last == b'\n';
        }
    }

    /// The 1-based line of the last byte consumed.
    fn line(&self) -> usize {
        if self.at_line_start {
            self.lines
        } else {
            self.lines + 1
        }
    }
}

/// Reads an OBJ file with tobj: every object and group, polygons as fans, one index per
/// vertex (a vertex with two normals is split in two). `.mtl` libraries are not opened.
fn read_obj<R: std::io::Read>(
    origin: &MeshOrigin<'_>,
    reader: BufReader<R>,
) -> Result<RawMesh, LoadError> {
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut counted = LineCounter {
        inner: reader,
        lines: 0,
        at_line_start: true,
    };
    // Materials are the scene file's: a `mtllib` line is read past, its file never opened.
    let (models, _) = tobj::load_obj_buf(&mut counted, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| origin.err(format!("line {}: {e}", counted.line())))?;
    let mut raw = RawMesh::default();
    let smooth = !models.is_empty() && models.iter().all(|m| !m.mesh.normals.is_empty());
    let textured = models.iter().any(|m| !m.mesh.texcoords.is_empty());
    for model in &models {
        append_obj_model(origin, &model.mesh, smooth, &mut raw)?;
        if textured {
            append_obj_texcoords(&model.mesh, &mut raw);
        }
    }
    Ok(raw)
}

/// Appends one tobj model's texture coordinates (`vt`, one pair per vertex with
/// `single_index`) to `raw`, (0, 0) for each vertex of a model without them.
fn append_obj_texcoords(mesh: &tobj::Mesh, raw: &mut RawMesh) {
    let count = mesh.positions.len() / 3;
    if mesh.texcoords.len() == 2 * count {
        raw.texcoords
            .extend(mesh.texcoords.chunks_exact(2).map(|c| [c[0], c[1]]));
    } else {
        raw.texcoords.extend(std::iter::repeat_n([0.0; 2], count));
    }
}

/// Appends one tobj model's vertices and faces (split into fans) to `raw`.
fn append_obj_model(
    origin: &MeshOrigin<'_>,
    mesh: &tobj::Mesh,
    smooth: bool,
    raw: &mut RawMesh,
) -> Result<(), LoadError> {
    let base = raw.positions.len();
    let count = mesh.positions.len() / 3;
    if base + count > u32::MAX as usize {
        return Err(origin.err("more than 2^32 - 1 vertices"));
    }
    raw.positions
        .extend(mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
    if smooth {
        if mesh.normals.len() != mesh.positions.len() {
            return Err(
                origin.err("some vertices have normals (vn) and others in the same object do not")
            );
        }
        raw.normals
            .extend(mesh.normals.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
    }
    let indices: Vec<u32> = mesh.indices.iter().map(|&i| i + base as u32).collect();
    if mesh.face_arities.is_empty() {
        // tobj leaves the arities empty when every face is a triangle.
        for t in indices.chunks_exact(3) {
            raw.triangles.push([t[0], t[1], t[2]]);
        }
    } else {
        let mut start = 0;
        for &arity in &mesh.face_arities {
            let end = start + arity as usize;
            let face = indices
                .get(start..end)
                .ok_or_else(|| origin.err("a face's vertex count runs past its indices"))?;
            fan(face, &mut raw.triangles);
            start = end;
        }
    }
    Ok(())
}

// ---- PLY

/// One PLY vertex: `x`, `y`, `z`, and `nx`, `ny`, `nz` and texture coordinates when the
/// file has them.
#[derive(Default)]
struct PlyVertex {
    p: [f64; 3],
    n: [f64; 3],
    uv: [f64; 2],
}

/// The names of a PLY vertex's texture coordinates, as Mitsuba's reader takes them (u, v
/// first).
const PLY_TEXCOORDS: [[&str; 2]; 4] = [
    ["u", "v"],
    ["s", "t"],
    ["texture_u", "texture_v"],
    ["texture_s", "texture_t"],
];

/// One PLY face: its `vertex_indices` (or `vertex_index`) list. Negative indices are kept
/// as such, to be reported.
#[derive(Default)]
struct PlyFace {
    indices: Vec<i64>,
}

/// An element bdpm does not read (edges, materials): parsed to move past it.
struct PlyIgnored;

impl PropertyAccess for PlyIgnored {
    fn new() -> Self {
        PlyIgnored
    }
}

fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v.into(),
        Property::UChar(v) => v.into(),
        Property::Short(v) => v.into(),
        Property::UShort(v) => v.into(),
        Property::Int(v) => v.into(),
        Property::UInt(v) => v.into(),
        Property::Float(v) => v.into(),
        Property::Double(v) => v,
        _ => return None,
    })
}

fn list(p: Property) -> Option<Vec<i64>> {
    Some(match p {
        Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
        Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
        Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
        Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
        Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
        Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
        _ => return None,
    })
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        PlyVertex::default()
    }

    fn set_property(
        &mut self,
        name: &str,
        property: Property,
    ) -> ply_rs_bw::ply::PropertyAccessResult {
        let slot = match name {
            "x" => &mut self.p[0],
            "y" => &mut self.p[1],
            "z" => &mut self.p[2],
            "nx" => &mut self.n[0],
            "ny" => &mut self.n[1],
            "nz" => &mut self.n[2],
            "u" | "s" | "texture_u" | "texture_s" => &mut self.uv[0],
            "v" | "t" | "texture_v" | "texture_t" => &mut self.uv[1],
            _ => return ply_rs_bw::ply::PropertyAccessResult::Ignored,
        };
        // The header check has made sure these are scalars.
        *slot = scalar(&property).unwrap_or(f64::NAN);
        ply_rs_bw::ply::PropertyAccessResult::Set
    }
}

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        PlyFace::default()
    }

    fn set_property(
        &mut self,
        name: &str,
        property: Property,
    ) -> ply_rs_bw::ply::PropertyAccessResult {
        if name == "vertex_indices" || name == "vertex_index" {
            self.indices = list(property).unwrap_or_default();
            ply_rs_bw::ply::PropertyAccessResult::Set
        } else {
            ply_rs_bw::ply::PropertyAccessResult::Ignored
        }
    }
}

/// What the header says of the two elements bdpm reads.
struct PlyLayout {
    vertices: usize,
    faces: usize,
    normals: bool,
    texcoords: bool,
}

/// The vertex and face elements' counts and properties, refused when a needed property is
/// missing or of the wrong kind.
fn ply_layout(
    origin: &MeshOrigin<'_>,
    elements: &[(&String, &ElementDef)],
) -> Result<PlyLayout, LoadError> {
    let find = |name: &str| elements.iter().find(|(k, _)| *k == name).map(|(_, e)| *e);
    let vertex = find("vertex").ok_or_else(|| origin.err("the header has no 'vertex' element"))?;
    let has_scalar = |name: &str| {
        vertex
            .properties
            .get(name)
            .is_some_and(|p| matches!(p.data_type, PropertyType::Scalar(_)))
    };
    if let Some(missing) = ["x", "y", "z"].into_iter().find(|c| !has_scalar(c)) {
        return Err(origin.err(format!(
            "the 'vertex' element has no scalar property '{missing}'"
        )));
    }
    let normals = ["nx", "ny", "nz"].into_iter().all(has_scalar);
    let texcoords = PLY_TEXCOORDS
        .iter()
        .any(|pair| pair.iter().all(|n| has_scalar(n)));
    let faces = match find("face") {
        None => 0,
        Some(face) => {
            let listed = ["vertex_indices", "vertex_index"].iter().any(|n| {
                face.properties
                    .get(*n)
                    .is_some_and(|p| matches!(p.data_type, PropertyType::List(_, _)))
            });
            if !listed {
                return Err(origin.err(
                    "the 'face' element has no list property 'vertex_indices' or 'vertex_index'",
                ));
            }
            face.count
        }
    };
    Ok(PlyLayout {
        vertices: vertex.count,
        faces,
        normals,
        texcoords,
    })
}

/// A PLY parse error on one line (the crate's messages span several).
fn ply_error(
    origin: &MeshOrigin<'_>,
    element: &str,
    e: &ply_rs_bw::parser::ParseError,
) -> LoadError {
    let text = e
        .to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    origin.err(format!("reading the '{element}' element: {text}"))
}

/// Reads a PLY file: the header first, whose counts are checked against the memory budget
/// before any vertex is read; then the elements in order up to the last one bdpm needs.
fn read_ply<R: std::io::Read>(
    origin: &MeshOrigin<'_>,
    reader: BufReader<R>,
    held: &Held<'_>,
) -> Result<RawMesh, LoadError> {
    let mut reader = Reader::new(reader);
    let header = Parser::<PlyIgnored>::new()
        .read_header(&mut reader)
        .map_err(|e| ply_error(origin, "header", &e))?;
    let elements: Vec<(&String, &ElementDef)> = header.elements.iter().collect();
    let layout = ply_layout(origin, &elements)?;
    if layout.faces == 0 {
        return Err(origin.err("has no faces (the header declares no 'face' element or 0 faces)"));
    }
    // At least one triangle per face, and the per-triangle data and BVH they will take.
    let needs = raw_mesh_bytes(layout.vertices, layout.normals, layout.faces)
        + if layout.texcoords {
            (layout.vertices * size_of::<Vec2>()) as u64
        } else {
            0
        }
        + Geometry::planned_bytes(layout.faces).total()
        + Geometry::build_transient_bytes(layout.faces);
    held.budget
        .check(
            held.bytes,
            needs,
            &format!(
                "{} vertices and {} faces as its header declares, their BVH and its build",
                layout.vertices, layout.faces
            ),
        )
        .map_err(|m| origin.err(format!("reading it {m}")))?;
    let mut raw = RawMesh::default();
    for (name, def) in elements {
        match name.as_str() {
            "vertex" => read_ply_vertices(origin, &mut reader, def, &header, &layout, &mut raw)?,
            "face" => read_ply_faces(origin, &mut reader, def, &header, &mut raw)?,
            _ if raw.triangles.is_empty() || raw.positions.is_empty() => {
                let _ = Parser::<PlyIgnored>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| ply_error(origin, name, &e))?;
            }
            // Everything bdpm reads is in: the rest of the file is not parsed.
            _ => break,
        }
    }
    Ok(raw)
}

fn read_ply_vertices<R: BufRead>(
    origin: &MeshOrigin<'_>,
    reader: &mut Reader<R>,
    def: &ElementDef,
    header: &ply_rs_bw::ply::Header,
    layout: &PlyLayout,
    raw: &mut RawMesh,
) -> Result<(), LoadError> {
    if def.count > u32::MAX as usize {
        return Err(origin.err("more than 2^32 - 1 vertices"));
    }
    let vertices = Parser::<PlyVertex>::new()
        .read_payload_for_element(reader, def, header)
        .map_err(|e| ply_error(origin, "vertex", &e))?;
    // f64 values beyond the f32 range become infinite here, and are refused as such.
    raw.positions = vertices.iter().map(|v| v.p.map(|c| c as f32)).collect();
    if layout.normals {
        raw.normals = vertices.iter().map(|v| v.n.map(|c| c as f32)).collect();
    }
    if layout.texcoords {
        raw.texcoords = vertices.iter().map(|v| v.uv.map(|c| c as f32)).collect();
    }
    Ok(())
}

fn read_ply_faces<R: BufRead>(
    origin: &MeshOrigin<'_>,
    reader: &mut Reader<R>,
    def: &ElementDef,
    header: &ply_rs_bw::ply::Header,
    raw: &mut RawMesh,
) -> Result<(), LoadError> {
    let faces = Parser::<PlyFace>::new()
        .read_payload_for_element(reader, def, header)
        .map_err(|e| ply_error(origin, "face", &e))?;
    let mut face = Vec::new();
    for (f, PlyFace { indices }) in faces.iter().enumerate() {
        if indices.len() < 3 {
            return Err(origin.err(format!(
                "face {f} has {} vertices; a face needs at least 3",
                indices.len()
            )));
        }
        face.clear();
        let count = raw.positions.len();
        for &i in indices {
            let i = u32::try_from(i)
                .ok()
                .filter(|&i| count == 0 || (i as usize) < count)
                .ok_or_else(|| {
                    origin.err(format!(
                        "face {f} names vertex {i}, but the file has {count} vertices"
                    ))
                })?;
            face.push(i);
        }
        fan(&face, &mut raw.triangles);
    }
    Ok(())
}
