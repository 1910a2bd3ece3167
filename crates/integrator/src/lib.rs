//! Integrators of bdpm: the unidirectional `path` reference and the BDPM mix, the film that
//! accumulates per-pass estimates, and the render settings.
//!
//! Units: radiance in W·m⁻²·sr⁻¹, distances in metres.

mod settings;

pub use settings::{Mode, RenderSettings, default_radius};
