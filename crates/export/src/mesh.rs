//! The triangles bdpm renders, grouped by material and shading, and their binary PLY files.

use std::collections::HashSet;

use bdpm_scene::Scene;
use glam::{Vec2, Vec3};

/// The triangles of one material with one kind of shading: one PLY file, one Mitsuba shape.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Group {
    /// Material index in the scene.
    pub material: u32,
    /// Whether the triangles have vertex normals (smooth shading).
    pub smooth: bool,
    /// Whether the triangles carry texture coordinates (their material has a base-colour or
    /// an emissive texture).
    pub textured: bool,
    /// Vertices of each triangle, metres, in the scene's frame.
    pub positions: Vec<[Vec3; 3]>,
    /// Unit vertex normals of each triangle (empty unless `smooth`).
    pub normals: Vec<[Vec3; 3]>,
    /// Texture coordinates of each triangle's vertices (empty unless `textured`).
    pub texcoords: Vec<[Vec2; 3]>,
}

/// The scene's triangles as bdpm's BVH holds them, grouped by (material, smooth): zero-area
/// triangles and exact duplicates (the same three vertices in any order; the first in mesh
/// order kept) left out, as `Geometry` leaves them out of its BVH. Groups in order of
/// material, flat before smooth; triangles in mesh order.
pub(crate) fn groups(scene: &Scene) -> Vec<Group> {
    let geometry = scene.geometry();
    let mut seen = HashSet::new();
    let mut out: Vec<Group> = Vec::new();
    for prim in 0..geometry.triangle_count() as u32 {
        if geometry.area(prim) == 0.0 {
            continue;
        }
        let v = geometry.vertices(prim);
        let mut key = v.map(|p| p.to_array().map(f32::to_bits));
        key.sort_unstable();
        if !seen.insert(key) {
            continue;
        }
        let material = geometry.material(prim);
        let normals = geometry.vertex_normals(prim);
        let smooth = normals.is_some();
        // Base colour's texture coordinates where the material has that texture, else those of
        // its emissive texture (a PLY has one set; `area_emitter` warns where both differ).
        let base_textured = scene.texture(material).is_some();
        let textured = base_textured || scene.emission_texture(material).is_some();
        let at = match out
            .iter()
            .position(|g| g.material == material && g.smooth == smooth)
        {
            Some(i) => i,
            None => {
                out.push(Group {
                    material,
                    smooth,
                    textured,
                    ..Group::default()
                });
                out.len() - 1
            }
        };
        let group = &mut out[at];
        group.positions.push(v);
        if let Some(n) = normals {
            group.normals.push(n);
        }
        if textured {
            let uv = if base_textured {
                scene.texcoords(prim)
            } else {
                scene.emission_texcoords(prim)
            };
            group.texcoords.push(uv.unwrap_or([Vec2::ZERO; 3]));
        }
    }
    out.sort_by_key(|g| (g.material, g.smooth));
    out
}

/// The group as a binary little-endian PLY file: three vertices a triangle (not shared, so
/// that each corner keeps its own normal and texture coordinates exactly), `x y z` as
/// float32, `nx ny nz` when smooth, `u v` when textured (Mitsuba's names; row 0 of the image
/// at v = 0 in both renderers), and a `vertex_indices` list of three uint32 per face.
pub(crate) fn ply(group: &Group, comment: &str) -> Vec<u8> {
    let triangles = group.positions.len();
    let mut header = String::from("ply\nformat binary_little_endian 1.0\n");
    header += &format!("comment {}\n", comment.replace(['\n', '\r'], " "));
    header += &format!("element vertex {}\n", 3 * triangles);
    header += "property float x\nproperty float y\nproperty float z\n";
    if group.smooth {
        header += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    if group.textured {
        header += "property float u\nproperty float v\n";
    }
    header += &format!("element face {triangles}\n");
    header += "property list uchar uint vertex_indices\nend_header\n";
    let floats = 3 + 3 * usize::from(group.smooth) + 2 * usize::from(group.textured);
    let mut bytes = Vec::with_capacity(header.len() + triangles * (3 * 4 * floats + 13));
    bytes.extend_from_slice(header.as_bytes());
    let mut put = |x: f32| bytes.extend_from_slice(&x.to_le_bytes());
    for (t, tri) in group.positions.iter().enumerate() {
        for (k, p) in tri.iter().enumerate() {
            p.to_array().into_iter().for_each(&mut put);
            if group.smooth {
                group.normals[t][k]
                    .to_array()
                    .into_iter()
                    .for_each(&mut put);
            }
            if group.textured {
                group.texcoords[t][k]
                    .to_array()
                    .into_iter()
                    .for_each(&mut put);
            }
        }
    }
    for t in 0..triangles as u32 {
        bytes.push(3);
        for k in 0..3 {
            bytes.extend_from_slice(&(3 * t + k).to_le_bytes());
        }
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The file's size is what its header declares: header, 4 bytes a float, 13 a face.
    #[test]
    fn ply_payload_matches_its_header() {
        let group = Group {
            material: 0,
            smooth: true,
            textured: true,
            positions: vec![[Vec3::X, Vec3::Y, Vec3::Z]; 2],
            normals: vec![[Vec3::Z; 3]; 2],
            texcoords: vec![[Vec2::ZERO, Vec2::X, Vec2::Y]; 2],
        };
        let bytes = ply(&group, "test");
        let end = b"end_header\n";
        let at = bytes
            .windows(end.len())
            .position(|w| w == end)
            .expect("header end")
            + end.len();
        assert_eq!(bytes.len() - at, 6 * 8 * 4 + 2 * 13);
        let header = std::str::from_utf8(&bytes[..at]).unwrap();
        assert!(header.contains("element vertex 6\n") && header.contains("element face 2\n"));
        assert!(header.contains("property float nx") && header.contains("property float u"));
    }
}
