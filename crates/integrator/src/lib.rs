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
mod camera;
mod connect;
mod correction;
mod direct;
mod error;
mod estimate;
mod estimates;
mod film;
mod inputs;
mod light;
mod memory;
mod mix;
mod pass;
pub mod path;
mod plan;
mod predict;
mod prepare;
mod products;
mod radius;
mod render;
mod sampler;
mod setup;
mod stage;
mod table;
mod weightmap;

pub use bdpm_mis::NoiseModel;
pub use camera::{FirstHitLayers, first_hit_layers, render_path_pass};
pub use correction::{CANDIDATES, Correction, PILOT_PASSES, pilot_seed};
pub use direct::DirectSamples;
pub use error::{RenderError, TargetError};
pub use estimate::{PILOT_PHOTONS, estimate_memory};
pub use estimates::{PassOutput, Techniques, WeightStats};
pub use film::{Film, PassSums, PassValue};
pub use memory::{
    Lifetime, Lower, MemoryEstimate, MemoryItem, human_bytes, loading_item, scene_items,
};
pub use predict::{JITTER_RAYS, Prediction};
pub use prepare::{MODEL_CACHE_BINS, MODEL_CACHE_PHOTONS, model_cache_item, model_cache_settings};
pub use radius::RadiusMap;
pub use render::{LARGE_RADIUS_FRACTION, Renderer};
pub use setup::{resolve_radius, scene_default_radius};
// The settings are `bdpm-settings`'; re-exported so that a user of the integrator needs one
// dependency.
pub use bdpm_settings::{
    FOOTPRINT_TABLE_RAYS, HeuristicKind, MIN_RADIUS, Mode, PINHOLE_TABLE_RAYS, PartialSettings,
    RadiusError, RadiusInput, RadiusSpec, RenderSettings, Sampler, Setting, SettingsError,
    SettingsRecord, WeightClamp, Written, check_radius, default_radius,
};
pub use sampler::strata;
pub use stage::{Stage, StageProbe, StageReport};
pub use table::{PixelTable, PixelWeights};
pub use weightmap::{WeightMap, WeightTarget, weight_map_heuristic};
