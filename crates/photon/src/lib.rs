//! Photon tracing from point lights and a fixed-radius photon map (method.md §1, §7, §8).
//!
//! This crate owns:
//! - emission (the start of [`trace_photons`]): N_F photons per pass shared between the point
//!   lights in proportion to flux luminance, isotropic directions, power Φ_l/(p_l·N_F);
//! - the random walk ([`trace_photons`]): BDF sampling with Russian roulette of survival q
//!   given by the scene (bdpm's: `bdpm_bdf::survival_probability`, which depends only on the
//!   vertex and the
//!   arrival direction, as the balance heuristic of §8 needs), recording every surface
//!   vertex ([`PathVertex`]) with its depth, arrival direction, q and optionally which
//!   lights it sees;
//! - the [`PhotonMap`]: the stored [`Photon`]s (arrivals after ≥ 1 scattering, each with
//!   the index of its previous vertex y_p) in a hashed uniform grid of cell 2r, for
//!   allocation-free range queries ([`PhotonMap::for_each_near`]);
//! - the hashed grid itself ([`grid`]), which needs only plain positions: a renderer with
//!   its own points can use [`grid::PointGrid`] alone.
//!
//! Units: positions and radii in m, powers in W per RGB channel (Φ/N_F already included),
//! directions unit vectors pointing away from the surface, pdfs per steradian.
//!
//! **Determinism:** photon `i` of pass `pass` draws only from
//! `Rng::new(seed, domain, [pass, i, 0])`; work is split into fixed chunks of photon indices
//! and the chunks' outputs are concatenated in chunk order, so the map (every photon, vertex
//! and the grid order) is bit-identical whatever the thread count.
//!
//! **Approximation:** scattering uses the BDF in the shading frame and the plain sample weight
//! f·cos/pdf, without the adjoint shading-normal correction; for flat-shaded meshes (shading
//! normal = geometric normal, as in the scenes of method.md §10) this is exact.
//!
//! Architecture invariant: this crate knows nothing of MIS weights, radiance caches, cameras
//! or films. It records what the weights need (previous vertices, q, light visibility) but
//! never evaluates a weight or a density estimate. It sees a scene only through the
//! [`PhotonScene`] trait (pick and read a light, intersect and shade, scatter, spawn, light
//! visibility), which `bdpm_scene::Scene` implements; another renderer implements it for its
//! own scene type, or uses [`grid::PointGrid`] over its own points with no scene at all.
//!
//! ```
//! use bdpm_bdf::Bdf;
//! use bdpm_geometry::{Geometry, TriangleMesh};
//! use bdpm_photon::{PhotonMap, TraceOptions};
//! use bdpm_scene::{Camera, Material, PointLight, Scene};
//! use glam::Vec3;
//!
//! // A closed unit cube, Lambert albedo 0.5, with a 1 W light in the middle.
//! let mesh = TriangleMesh::cuboid(Vec3::ZERO, Vec3::ONE, true, 0);
//! let scene = Scene::new(
//!     Geometry::new(mesh).unwrap(),
//!     vec![Material::new("white", Bdf::lambert(Vec3::splat(0.5)).unwrap())],
//!     vec![PointLight { position: Vec3::splat(0.5), flux: Vec3::ONE }],
//!     Camera::look_at(Vec3::new(0.5, 0.5, 0.1), Vec3::new(0.5, 0.5, 1.0), Vec3::Y, 60.0, 8, 8).unwrap(),
//! ).unwrap();
//!
//! let map = PhotonMap::trace(&scene, &TraceOptions::new(10_000, 1, 0), 0.05);
//! assert_eq!(map.emitted(), 10_000);
//! for p in map.photons() {
//!     // Stored photons have been scattered at least once, last at y_p; the vertices before
//!     // y_p are the rest of its light path, back to the first hit (depth 0).
//!     let y = map.vertex(p.prev);
//!     let first = map.vertex(p.prev - u32::from(y.depth));
//!     assert_eq!((first.depth, first.light), (0, y.light));
//! }
//! // Density estimate of the indirect irradiance at the floor's centre, W/m².
//! let mut sum = Vec3::ZERO;
//! map.for_each_near(Vec3::new(0.5, 0.0, 0.5), |p| sum += p.power);
//! let irradiance = sum / (std::f32::consts::PI * map.radius() * map.radius());
//! assert!(irradiance.is_finite());
//! ```

/// The hashed grid of the map's gathers, its own crate (it needs only plain points).
pub use bdpm_grid as grid;
mod map;
mod scene;
mod trace;

pub use map::{Photon, PhotonMap, PhotonQuery};
pub use scene::{AREA_LIGHT, AreaEmission, PhotonScene, Scatter};
pub use trace::{
    MAX_DEPTH, PathVertex, PhotonArrival, TraceOptions, trace_photons, trace_photons_until,
};

// The README (the crate's page on crates.io) as a hidden item, so that `cargo test --doc`
// compiles and runs its example; the crate documentation above stays as it is.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
