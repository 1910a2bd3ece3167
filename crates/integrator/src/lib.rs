//! Integrators of bdpm: the unidirectional `path` reference and the BDPM mix, the film that
//! accumulates per-pass estimates, and the render settings.
//!
//! Units: radiance in W·m⁻²·sr⁻¹, distances in metres.
//!
//! Determinism: every random number of a pass is drawn from a stream keyed by
//! (seed, domain, pass, pixel or photon index, sample), and per-pixel results are written to
//! their own slot, so the image bits do not depend on the number of threads.
//!
//! Architecture invariant: no file IO; the driver writes images and reports.

mod bdpm;
pub mod camera;
mod connect;
pub mod correction;
pub mod direct;
pub mod error;
mod estimate;
pub mod estimates;
pub mod film;
mod inputs;
mod light;
pub mod memory;
mod mix;
pub mod one_bounce;
mod pass;
pub mod path;
mod paths;
pub mod photon_spread;
mod plan;
pub mod predict;
pub mod prepare;
mod products;
pub mod radius;
pub mod render;
mod sampler;
pub mod setup;
pub mod stage;
pub mod table;
pub mod weightmap;

// The crate root names what most users need; the rest is in the modules above (e.g.
// `memory::Lower`, `radius::RadiusMap`, `prepare::model_cache_settings`).
pub use error::RenderError;
pub use estimate::estimate_memory;
pub use estimates::{PassOutput, Techniques, WeightStats};
pub use film::Film;
pub use memory::{MemoryEstimate, MemoryItem, human_bytes};
pub use paths::PathsRan;
pub use predict::Prediction;
pub use render::Renderer;
pub use stage::{Stage, StageProbe, StageReport};
pub use weightmap::{WeightMap, WeightTarget};
// The settings are `bdpm-settings`' (all of them as `settings`); re-exported so that a user
// of the integrator needs one dependency.
pub use bdpm_settings as settings;
pub use bdpm_settings::{Mode, NoiseModel, PartialSettings, RenderSettings, Sampler, Setting};

// The README (the crate's page on crates.io) as a hidden item, so that `cargo test --doc`
// compiles and runs its example; the crate documentation above stays as it is.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
