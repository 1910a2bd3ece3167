//! Triangle geometry and ray queries for bdpm.
//!
//! This crate owns what every higher layer needs of space and chance:
//! - [`TriangleMesh`]: an indexed triangle soup with optional vertex normals and one opaque
//!   material index per triangle;
//! - [`Geometry`]: the mesh with a BVH for closest-hit and occlusion queries (a 4-wide BVH with
//!   f32 boxes by default, obvhs's compressed CWBVH as the [`Kernel`] it replaced), per-triangle
//!   areas and area-weighted surface sampling;
//! - [`Frame`] and the [`sampling`] warps (concentric disk, uniform sphere, uniform triangle);
//! - mesh builders for rectangles, boxes and geodesic spheres ([`TriangleMesh::push_rect`],
//!   [`TriangleMesh::cuboid`], [`TriangleMesh::geodesic_sphere`]), used by the scene loader,
//!   the tests and the examples;
//! - [`Rng`]: deterministic random streams keyed by (seed, domain, indices), so that every
//!   sample is a pure function of its keys whatever the thread count.
//!
//! Units: positions and distances in metres, areas in m², solid angles in sr.
//!
//! Architecture invariant: this crate knows nothing of materials (a material is an opaque
//! `u32`), lights, photons, weights or files.
//!
//! ```
//! use bdpm_geometry::{Geometry, TriangleMesh};
//! use glam::Vec3;
//! let mut mesh = TriangleMesh::default();
//! mesh.push_quad([Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0),
//!                 Vec3::new(1.0, 0.0, 1.0), Vec3::new(-1.0, 0.0, 1.0)], 0);
//! let geometry = Geometry::new(mesh).unwrap();
//! let hit = geometry.intersect(Vec3::new(0.2, 1.0, 0.3), Vec3::NEG_Y, f32::INFINITY).unwrap();
//! assert!((hit.t - 1.0).abs() < 1e-6);
//! assert!((geometry.total_area() - 4.0).abs() < 1e-6);
//! ```

mod build;
mod mesh;
mod shapes;
mod wide;

// Frames, warps, random streams and prefetch live in bdpm-core (crates below the BVH use
// them); re-exported so that a user of the geometry needs one dependency.
pub use bdpm_core::{Domain, Frame, Rng, prefetch, sampling};
pub use mesh::{
    BVH_BYTES_PER_TRIANGLE, Geometry, GeometryBytes, GeometryError, Hit, Kernel, MAX_COORDINATE,
    SurfaceSample, TriangleMesh,
};
pub use shapes::{BOX_FACES, BoxFace, geodesic_sphere_triangle_count, rect_corners};

// The README (the crate's page on crates.io) as a hidden item, so that `cargo test --doc`
// compiles and runs its example; the crate documentation above stays as it is.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
