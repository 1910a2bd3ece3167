//! The settings as a run report and an image header give them: one record, so the two cannot
//! drift apart.

/// The settings as reported, with the values in force: the merge radius the render uses, the
/// A/B rays per pixel and the weight clamp ([`crate::RenderSettings::record`]). With the
/// `serde` feature it serialises to the JSON report's `settings` object.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct SettingsRecord {
    /// Mode name (`path`, `balance`, …).
    pub mode: &'static str,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Passes K.
    pub passes: u32,
    /// Photons emitted per pass, N_F.
    pub photons_per_pass: u64,
    /// Camera samples per pixel per pass, N_B.
    pub spp: u32,
    /// The merge radius in use (the default, `DEFAULT_RADIUS_PX`, when none was given), metres.
    pub radius_m: f32,
    /// The same radius in pixel footprints (`Scene::pixel_footprint`), when the camera sees
    /// the scene.
    pub radius_px: Option<f32>,
    /// Whether the radius was given (scene file or command line) or is the default.
    pub radius_given: bool,
    /// Master seed.
    pub seed: u64,
    /// Radius R of the threshold rule, metres.
    pub threshold_radius_m: f32,
    /// Angular bins per radiance-cache cell.
    pub cache_bins: u32,
    /// Photons traced for the radiance cache (N_F unless set).
    pub cache_photons: u64,
    /// A/B rays per pixel in force.
    pub pixel_table_rays: u32,
    /// Whether the `optimal*` weights are clamped to [0, 1] (asked for, or needed by the
    /// footprint noise model with jittered samples).
    pub clamp_weights: bool,
    /// Whether the clamp was asked for (scene file or the mode's own flag).
    pub clamp_weights_requested: bool,
    /// Camera samples jittered over the pixel.
    pub pixel_jitter: bool,
    /// `pinhole` or `footprint` (method.md §12).
    pub noise_model: &'static str,
    /// `independent` or `stratified` ([`crate::Sampler`]).
    pub sampler: &'static str,
    /// BDD=0's paths by light tracing instead of the merge at x₀.
    pub light_tracing: bool,
    /// The most direct-light samples per camera sample (1: off).
    pub direct_boost: u32,
    /// A merge radius per block of pixels from a pilot (`adaptive_radius`).
    pub adaptive_radius: bool,
}

impl SettingsRecord {
    /// The record as image-header attributes, names without a prefix (`mode`, `seed`, …,
    /// `radius_m`, `radius_source`).
    pub fn header_attributes(&self) -> Vec<(&'static str, String)> {
        vec![
            ("mode", self.mode.into()),
            ("seed", self.seed.to_string()),
            ("passes", self.passes.to_string()),
            ("photons_per_pass", self.photons_per_pass.to_string()),
            ("spp", self.spp.to_string()),
            ("pixel_jitter", self.pixel_jitter.to_string()),
            ("noise_model", self.noise_model.into()),
            ("sampler", self.sampler.into()),
            ("light_tracing", self.light_tracing.to_string()),
            ("direct_boost", self.direct_boost.to_string()),
            ("adaptive_radius", self.adaptive_radius.to_string()),
            ("radius_m", self.radius_m.to_string()),
            (
                "radius_px",
                self.radius_px.map_or("unknown".into(), |k| k.to_string()),
            ),
            (
                "radius_source",
                if self.radius_given {
                    "given"
                } else {
                    "default"
                }
                .into(),
            ),
        ]
    }
}
