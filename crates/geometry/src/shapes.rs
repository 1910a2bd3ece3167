//! Built-in shapes as triangles: rectangles, axis-aligned boxes and geodesic spheres. The one
//! place their vertex tables are written, for the scene loader, the tests and the examples.

use glam::Vec3;

use crate::TriangleMesh;

/// A face of an axis-aligned box: its name in scene files, outward unit normal, and the unit
/// edge directions `u`, `v` with `u × v = normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxFace {
    /// The face's name in scene files (`"+x"`, `"-x"`, … `"-z"`).
    pub name: &'static str,
    /// Outward unit normal.
    pub normal: Vec3,
    /// First unit edge direction.
    pub u: Vec3,
    /// Second unit edge direction; `u × v = normal`.
    pub v: Vec3,
}

/// The six faces of an axis-aligned box, in the order of the `keep` flags of
/// [`TriangleMesh::push_box`].
pub const BOX_FACES: [BoxFace; 6] = [
    face("+x", Vec3::X, Vec3::Y, Vec3::Z),
    face("-x", Vec3::NEG_X, Vec3::Z, Vec3::Y),
    face("+y", Vec3::Y, Vec3::Z, Vec3::X),
    face("-y", Vec3::NEG_Y, Vec3::X, Vec3::Z),
    face("+z", Vec3::Z, Vec3::X, Vec3::Y),
    face("-z", Vec3::NEG_Z, Vec3::Y, Vec3::X),
];

const fn face(name: &'static str, normal: Vec3, u: Vec3, v: Vec3) -> BoxFace {
    BoxFace { name, normal, u, v }
}

/// The corners (c−u−v, c+u−v, c+u+v, c−u+v) of the rectangle with centre `c` and half-edge
/// vectors `u`, `v` (m): counter-clockwise seen from the side `u × v` points to.
pub fn rect_corners(c: Vec3, u: Vec3, v: Vec3) -> [Vec3; 4] {
    [c - u - v, c + u - v, c + u + v, c - u + v]
}

/// The unit icosahedron's 12 vertices (unnormalised: (0, ±1, ±t) and its cyclic
/// permutations, t the golden ratio) and its 20 faces.
fn icosahedron() -> ([Vec3; 12], [[usize; 3]; 20]) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let vertices = [
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
    let faces = [
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
    (vertices, faces)
}

/// Number of triangles of a geodesic sphere with `frequency` subdivisions per icosahedron
/// edge (a frequency of 0 counts as 1, as in [`TriangleMesh::push_geodesic_sphere`]).
pub fn geodesic_sphere_triangle_count(frequency: u32) -> u64 {
    let n = u64::from(frequency.max(1));
    20 * n * n
}

impl TriangleMesh {
    /// Appends the rectangle with centre `c` and half-edge vectors `u`, `v` (m), its front
    /// facing `u × v` ([`rect_corners`]).
    pub fn push_rect(&mut self, c: Vec3, u: Vec3, v: Vec3, material: u32) {
        self.push_quad(rect_corners(c, u, v), material);
    }

    /// Appends the faces of the box [lo, hi] (m) whose `keep` flag is set (in [`BOX_FACES`]
    /// order), front faces outward or, with `inward`, inward.
    pub fn push_box(&mut self, lo: Vec3, hi: Vec3, keep: [bool; 6], inward: bool, material: u32) {
        let center = 0.5 * (lo + hi);
        let half = 0.5 * (hi - lo);
        for (f, keep) in BOX_FACES.iter().zip(keep) {
            if !keep {
                continue;
            }
            let quad = rect_corners(center + f.normal * half, f.u * half, f.v * half);
            let quad = if inward {
                [quad[0], quad[3], quad[2], quad[1]]
            } else {
                quad
            };
            self.push_quad(quad, material);
        }
    }

    /// A closed box [lo, hi] (m) of one material, front faces outward or, with `inward`,
    /// inward: 12 triangles.
    pub fn cuboid(lo: Vec3, hi: Vec3, inward: bool, material: u32) -> TriangleMesh {
        let mut mesh = TriangleMesh::default();
        mesh.push_box(lo, hi, [true; 6], inward, material);
        mesh
    }

    /// Appends a geodesic sphere of `radius` (m) around `center`: each icosahedron face cut
    /// into `frequency²` triangles whose vertices are projected onto the sphere
    /// ([`geodesic_sphere_triangle_count`]). Front faces point outward, or inward with
    /// `inward`. With `smooth`, each vertex carries the sphere's own normal there, so that the
    /// interpolated shading normal follows the sphere rather than the facet (what a mirror or
    /// glass sphere needs to focus like a sphere); without, the facets are flat.
    pub fn push_geodesic_sphere(
        &mut self,
        center: Vec3,
        radius: f32,
        frequency: u32,
        inward: bool,
        smooth: bool,
        material: u32,
    ) {
        let with_normals = smooth || !self.normals.is_empty();
        if with_normals && self.normals.is_empty() {
            self.normals = vec![Vec3::ZERO; self.positions.len()];
        }
        let (ico, faces) = icosahedron();
        let n = frequency.max(1);
        let nf = n as f32;
        for face in faces {
            let [a, b, c] = face.map(|k| ico[k]);
            let base = self.positions.len() as u32;
            // Grid point (i, j) is a·(n−i−j)/n + b·i/n + c·j/n. A point on an edge shared with
            // the neighbouring face has one zero weight, and the remaining two products are
            // added in either order, which f32 addition gives bit-identically: the faces meet
            // without cracks even though their edge vertices are stored twice.
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (wa, wb, wc) = ((n - i - j) as f32 / nf, i as f32 / nf, j as f32 / nf);
                    let p = (a * wa + b * wb + c * wc).normalize();
                    self.positions.push(center + radius * p);
                    // Zero marks a flat vertex in a mesh that has normals elsewhere.
                    if with_normals {
                        self.normals.push(if smooth { p } else { Vec3::ZERO });
                    }
                }
            }
            // Row i holds n + 1 − i points, starting at offset(i).
            let row_start = |i: u32| base + i * (2 * n + 3 - i) / 2;
            for i in 0..n {
                for j in 0..(n - i) {
                    let p00 = row_start(i) + j;
                    let p10 = row_start(i + 1) + j;
                    let p01 = p00 + 1;
                    self.push_oriented(center, [p00, p10, p01], inward, material);
                    if i + j + 1 < n {
                        let p11 = p10 + 1;
                        self.push_oriented(center, [p10, p11, p01], inward, material);
                    }
                }
            }
        }
    }

    /// A geodesic sphere of `radius` (m) around `center`, front faces outward or, with
    /// `inward`, inward, flat or `smooth` ([`TriangleMesh::push_geodesic_sphere`]).
    pub fn geodesic_sphere(
        center: Vec3,
        radius: f32,
        frequency: u32,
        inward: bool,
        smooth: bool,
        material: u32,
    ) -> TriangleMesh {
        let mut mesh = TriangleMesh::default();
        mesh.push_geodesic_sphere(center, radius, frequency, inward, smooth, material);
        mesh
    }

    /// Appends a sphere triangle wound so that its front faces away from (or, with `inward`,
    /// towards) the centre, whatever the winding of the icosahedron table.
    fn push_oriented(&mut self, center: Vec3, tri: [u32; 3], inward: bool, material: u32) {
        let [p0, p1, p2] = tri.map(|k| self.positions[k as usize]);
        let outward = (p1 - p0).cross(p2 - p0).dot(p0 + p1 + p2 - 3.0 * center) > 0.0;
        let tri = if outward != inward {
            tri
        } else {
            [tri[0], tri[2], tri[1]]
        };
        self.indices.push(tri);
        self.materials.push(material);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_faces_are_right_handed() {
        for f in BOX_FACES {
            assert_eq!(f.u.cross(f.v), f.normal, "{}", f.name);
        }
    }

    #[test]
    fn a_cuboid_winds_its_faces_as_asked() {
        let (lo, hi) = (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 2.5));
        let center = 0.5 * (lo + hi);
        for inward in [false, true] {
            let mesh = TriangleMesh::cuboid(lo, hi, inward, 4);
            assert_eq!((mesh.indices.len(), mesh.materials), (12, vec![4; 12]));
            for t in &mesh.indices {
                let [a, b, c] = t.map(|k| mesh.positions[k as usize]);
                let out = (b - a).cross(c - a).dot(a + b + c - 3.0 * center) > 0.0;
                assert_eq!(out, !inward);
            }
        }
    }

    #[test]
    fn a_geodesic_sphere_lies_on_its_sphere() {
        let center = Vec3::new(1.0, 2.0, 3.0);
        for frequency in [0, 1, 3] {
            let mesh = TriangleMesh::geodesic_sphere(center, 0.5, frequency, false, false, 0);
            assert_eq!(
                mesh.indices.len() as u64,
                geodesic_sphere_triangle_count(frequency)
            );
            for p in &mesh.positions {
                assert!(((*p - center).length() - 0.5).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn a_smooth_sphere_shades_with_the_sphere_normal() {
        // Rays from the centre hit the facets; the sphere's normal there is the ray direction.
        // Flat facets are off by up to half a facet's angle (≈ 1° at frequency 16); the
        // interpolated vertex normals by the much smaller error of normalised interpolation.
        let center = Vec3::new(0.3, -0.2, 0.1);
        let (mut flat_err, mut smooth_err) = (0.0f32, 0.0f32);
        for (smooth, err) in [(false, &mut flat_err), (true, &mut smooth_err)] {
            for inward in [false, true] {
                let mesh = TriangleMesh::geodesic_sphere(center, 0.5, 16, inward, smooth, 0);
                assert_eq!(
                    mesh.normals.len(),
                    if smooth { mesh.positions.len() } else { 0 }
                );
                let geometry = crate::Geometry::new(mesh.clone()).unwrap();
                let mut rng = crate::Rng::new(7, crate::Domain::Other, [0; 3]);
                for _ in 0..2000 {
                    let d = crate::sampling::uniform_sphere(rng.uniform2());
                    let hit = geometry.intersect(center, d, f32::INFINITY).unwrap();
                    // ns lies on the side of ng (outward or inward as wound).
                    assert!(hit.ns.dot(hit.ng) > 0.0);
                    let exact = if inward { -d } else { d };
                    *err = err.max(hit.ns.angle_between(exact));
                }
            }
        }
        assert!(flat_err > 0.01, "flat facets: {flat_err} rad");
        assert!(smooth_err < 1e-3, "smooth: {smooth_err} rad");
    }
}
