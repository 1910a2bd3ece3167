//! Built-in shapes as triangles: boxes and geodesic spheres (quads go straight to
//! [`TriangleMesh::push_quad`]). Pure geometry; validation happens in `build.rs`.

use bdpm_geometry::TriangleMesh;
use glam::Vec3;

/// The six faces of an axis-aligned box as (name, outward normal, u, v) with `u × v = normal`,
/// so that the corners (−u−v, +u−v, +u+v, −u+v) wind counter-clockwise seen from outside.
pub(crate) const BOX_FACES: [(&str, Vec3, Vec3, Vec3); 6] = [
    ("+x", Vec3::X, Vec3::Y, Vec3::Z),
    ("-x", Vec3::NEG_X, Vec3::Z, Vec3::Y),
    ("+y", Vec3::Y, Vec3::Z, Vec3::X),
    ("-y", Vec3::NEG_Y, Vec3::X, Vec3::Z),
    ("+z", Vec3::Z, Vec3::X, Vec3::Y),
    ("-z", Vec3::NEG_Z, Vec3::Y, Vec3::X),
];

/// Appends the faces of the box [lo, hi] whose `keep` flag is set (in [`BOX_FACES`] order),
/// front faces outward or, with `inward`, inward.
pub(crate) fn push_box(
    mesh: &mut TriangleMesh,
    lo: Vec3,
    hi: Vec3,
    keep: [bool; 6],
    inward: bool,
    material: u32,
) {
    let center = 0.5 * (lo + hi);
    let half = 0.5 * (hi - lo);
    for (&(_, n, u, v), keep) in BOX_FACES.iter().zip(keep) {
        if !keep {
            continue;
        }
        let c = center + n * half;
        let (u, v) = (u * half, v * half);
        let quad = [c - u - v, c + u - v, c + u + v, c - u + v];
        let quad = if inward {
            [quad[0], quad[3], quad[2], quad[1]]
        } else {
            quad
        };
        mesh.push_quad(quad, material);
    }
}

/// Number of triangles of a geodesic sphere with `frequency` subdivisions per icosahedron edge.
pub(crate) fn sphere_triangle_count(frequency: u32) -> u64 {
    20 * u64::from(frequency) * u64::from(frequency)
}

/// Appends a geodesic sphere: each icosahedron face cut into `frequency²` triangles whose
/// vertices are projected onto the sphere. Flat facets (no vertex normals); front faces point
/// outward, or inward with `inward`.
pub(crate) fn push_sphere(
    mesh: &mut TriangleMesh,
    center: Vec3,
    radius: f32,
    frequency: u32,
    inward: bool,
    material: u32,
) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let ico = [
        Vec3::new(-1.0, t, 0.0),
        Vec3::new(1.0, t, 0.0),
        Vec3::new(-1.0, -t, 0.0),
        Vec3::new(1.0, -t, 0.0),
        Vec3::new(0.0, -1.0, t),
        Vec3::new(0.0, 1.0, t),
        Vec3::new(0.0, -1.0, -t),
        Vec3::new(0.0, 1.0, -t),
        Vec3::new(t, 0.0, -1.0),
        Vec3::new(t, 0.0, 1.0),
        Vec3::new(-t, 0.0, -1.0),
        Vec3::new(-t, 0.0, 1.0),
    ];
    const FACES: [[usize; 3]; 20] = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let n = frequency.max(1);
    let nf = n as f32;
    for face in FACES {
        let [a, b, c] = face.map(|k| ico[k]);
        let base = mesh.positions.len() as u32;
        // Grid point (i, j) is a·(n−i−j)/n + b·i/n + c·j/n. A point on an edge shared with
        // the neighbouring face has one zero weight, and the remaining two products are
        // added in either order, which f32 addition gives bit-identically: the faces meet
        // without cracks even though their edge vertices are stored twice.
        for i in 0..=n {
            for j in 0..=(n - i) {
                let (wa, wb, wc) = ((n - i - j) as f32 / nf, i as f32 / nf, j as f32 / nf);
                let p = (a * wa + b * wb + c * wc).normalize();
                mesh.positions.push(center + radius * p);
            }
        }
        // Row i holds n + 1 − i points, starting at offset(i).
        let row_start = |i: u32| base + i * (2 * n + 3 - i) / 2;
        for i in 0..n {
            for j in 0..(n - i) {
                let p00 = row_start(i) + j;
                let p10 = row_start(i + 1) + j;
                let p01 = p00 + 1;
                push_oriented(mesh, center, [p00, p10, p01], inward, material);
                if i + j + 1 < n {
                    let p11 = p10 + 1;
                    push_oriented(mesh, center, [p10, p11, p01], inward, material);
                }
            }
        }
    }
}

/// Appends a sphere triangle wound so that its front faces away from (or, with `inward`,
/// towards) the centre, whatever the winding of the icosahedron table.
fn push_oriented(
    mesh: &mut TriangleMesh,
    center: Vec3,
    tri: [u32; 3],
    inward: bool,
    material: u32,
) {
    let [p0, p1, p2] = tri.map(|k| mesh.positions[k as usize]);
    let outward = (p1 - p0).cross(p2 - p0).dot(p0 + p1 + p2 - 3.0 * center) > 0.0;
    let tri = if outward != inward {
        tri
    } else {
        [tri[0], tri[2], tri[1]]
    };
    mesh.indices.push(tri);
    mesh.materials.push(material);
}
