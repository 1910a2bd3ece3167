//! The named stages of a render, as timed, probed and reported.

use std::fmt;

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
            Stage::RadiusMap => "radius map",
        }
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
