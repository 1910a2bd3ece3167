//! The named stages of a render, as timed, probed and reported.

use std::fmt;

/// Told by [`crate::Renderer::render_pass`] when each stage of a pass starts and ends, e.g. to
/// sample the process's memory per stage. A probe sees stages only and cannot change the
/// render.
pub trait StageProbe: Sync {
    /// `stage` of a pass (one of [`crate::PassOutput::stage_seconds`]) is about to start.
    fn enter(&self, stage: Stage);
    /// `stage` has ended.
    fn leave(&self, stage: Stage);
}

/// Time and memory of one preparatory stage (photon map, radiance cache, A/B table, …).
#[derive(Clone, Debug, PartialEq)]
pub struct StageReport {
    /// The stage, e.g. [`Stage::RadianceCache`].
    pub stage: Stage,
    /// Wall time, seconds.
    pub seconds: f64,
    /// Memory held by the stage's result, bytes.
    pub bytes: u64,
    /// One line of facts (cell counts, bins, …).
    pub detail: String,
}

/// `probe`'s [`StageProbe::enter`], if there is one.
pub(crate) fn enter(probe: Option<&dyn StageProbe>, stage: Stage) {
    if let Some(p) = probe {
        p.enter(stage);
    }
}

/// `probe`'s [`StageProbe::leave`], if there is one.
pub(crate) fn leave(probe: Option<&dyn StageProbe>, stage: Stage) {
    if let Some(p) = probe {
        p.leave(stage);
    }
}

/// A stage of a render: one of the preparatory stages ([`crate::Renderer::stages`]), a stage
/// of a pass ([`crate::PassOutput::stage_seconds`], [`crate::StageProbe`]), or the driver's
/// whole preparation. Code matches on the variant; [`Stage::name`] is the text that reports,
/// EXR headers and JSON files carry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Stage {
    /// Everything before the first pass (the driver's own stage around `Renderer::new`).
    Prepare,
    /// A whole pass of a reference (`path`, `light`), whose stages interleave.
    Pass,
    /// Photon tracing and the photon map of a BDPM pass.
    Photons,
    /// Camera samples of a pass.
    Camera,
    /// Light tracing connected to the camera (the `light` reference).
    LightTracing,
    /// The radiance cache (method.md §5), built once.
    RadianceCache,
    /// The per-pixel weight table (ρ, N_eff, A, B), built once.
    PixelTable,
    /// The per-pixel footprints alone (ρ, N_eff), built once.
    PixelFootprints,
    /// `corrected-balance`'s per-pixel factors, learnt once from a pilot of `balance`.
    BalanceCorrection,
    /// How many direct-light samples each pixel takes (`direct_boost`), fixed once.
    DirectSamples,
    /// How many x₁ each pixel takes for the one-bounce paths at a glossy x₀
    /// (crate::one_bounce), fixed once.
    OneBounceSamples,
    /// `adaptive_radius`'s pilot and the radius of each block of pixels (crate::radius).
    RadiusMap,
}

impl Stage {
    /// The stage's name in reports, headers and files (e.g. `"radiance cache"`).
    pub fn name(self) -> &'static str {
        match self {
            Stage::Prepare => "prepare",
            Stage::Pass => "pass",
            Stage::Photons => "photons",
            Stage::Camera => "camera",
            Stage::LightTracing => "light tracing",
            Stage::RadianceCache => "radiance cache",
            Stage::PixelTable => "pixel table",
            Stage::PixelFootprints => "pixel footprints",
            Stage::BalanceCorrection => "balance correction",
            Stage::DirectSamples => "direct samples",
            Stage::OneBounceSamples => "one-bounce samples",
            Stage::RadiusMap => "radius map",
        }
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A stop that never fires (a preparation or pass that runs to its end).
pub(crate) fn never() -> bool {
    false
}
