//! What a pass produces: each pixel's estimate, optionally split by technique, and the
//! counters of its samples and weights.
use glam::{DVec3, Vec3};

use crate::stage::Stage;

/// The contributions of one camera sample, split by technique (for the debug layers).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Techniques {
    /// L₀(x₀): direct light at the first vertex (never weighted).
    pub direct: DVec3,
    /// Photons merged at x₀, unweighted (the pure BDD=0 estimate of indirect light).
    pub x0_raw: DVec3,
    /// Photons merged at x₀, each weighted by 1 − w₁(x₀, y_p).
    pub x0_weighted: DVec3,
    /// E·(L₀(x₁→x₀) + Ph(x₁)), unweighted (the pure BDD=1 estimate of indirect light).
    pub x1_raw: DVec3,
    /// The same with weights w₁.
    pub x1_weighted: DVec3,
}

impl Techniques {
    /// The sample value: direct + weighted x₀ merge + weighted x₁ part.
    pub fn total(&self) -> DVec3 {
        self.direct + self.x0_weighted + self.x1_weighted
    }

    /// Multiplies the merges' parts by `beta`: the throughput of the mirrors and glass between
    /// the camera and x₀ (the direct part has it already).
    pub(crate) fn scale_merges(&mut self, beta: DVec3) {
        self.x0_raw *= beta;
        self.x0_weighted *= beta;
        self.x1_raw *= beta;
        self.x1_weighted *= beta;
    }
}

/// Counts of weight evaluations, for the run report (method.md §4 asks that clamped c·B and
/// weights outside [0, 1] be reported).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WeightStats {
    /// Weights evaluated.
    pub evaluations: u64,
    /// Weights whose w₁ fell outside [0, 1] (before any optional clamp).
    pub outside_unit: u64,
    /// Optimal weights whose c·B was clamped to 1 − ε.
    pub clamped_cb: u64,
}

impl WeightStats {
    /// Adds another set of counts.
    pub fn add(&mut self, o: &WeightStats) {
        self.evaluations += o.evaluations;
        self.outside_unit += o.outside_unit;
        self.clamped_cb += o.clamped_cb;
    }
}

/// What one pass produced: the per-pixel estimates and counters.
#[derive(Clone, Debug)]
pub struct PassOutput {
    /// Per-pixel pass estimate (mean of the pass's camera samples), row-major, W·m⁻²·sr⁻¹.
    pub estimates: Vec<DVec3>,
    /// Camera samples whose value was NaN or infinite (dropped: they contribute zero).
    pub dropped: u64,
    /// Camera samples taken.
    pub samples: u64,
    /// Wall time of the pass's stages (e.g. photon tracing, camera samples), seconds.
    pub stage_seconds: Vec<(Stage, f64)>,
    /// Per-pixel pass estimates split by technique, when asked for
    /// ([`crate::Renderer::with_technique_layers`]; BDPM modes only).
    pub techniques: Option<Vec<Techniques>>,
    /// Photons stored in this pass's map (0 for `path`).
    pub photons_stored: u64,
    /// Memory of this pass's photon map, bytes (0 without one).
    pub photon_map_bytes: u64,
    /// Weight evaluations and their anomalies (BDPM modes).
    pub weights: WeightStats,
}

/// Adds a sample to a pixel sum unless it is non-finite, in which case it is counted.
#[inline]
pub(crate) fn accumulate(sum: &mut DVec3, sample: Vec3, dropped: &mut u64) {
    if sample.is_finite() {
        *sum += sample.as_dvec3();
    } else {
        *dropped += 1;
    }
}
