use std::fmt;

use bdpm_mis::{Heuristic, NoiseModel};

/// What a render computes: the unidirectional reference, or the BDPM mix with a weight mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    /// Unidirectional path tracing with next-event estimation (the reference).
    Path,
    /// Exact direct light plus light tracing connected to the camera (a second, independent
    /// reference that converges fast around small bright secondary sources).
    Light,
    /// The BDD=0/BDD=1 photon-mapping mix weighted by a heuristic.
    Bdpm(Heuristic),
}

impl Mode {
    /// Every mode name the parser accepts, the references (`path`, `light`) first.
    pub fn names() -> Vec<&'static str> {
        ["path", "light"]
            .into_iter()
            .chain(Heuristic::ALL_NAMES.iter().copied())
            .collect()
    }

    /// Parses a mode name (`path`, `bdd0`, `bdd1`, `threshold`, …).
    pub fn parse(name: &str) -> Option<Mode> {
        match name {
            "path" => Some(Mode::Path),
            "light" => Some(Mode::Light),
            _ => Heuristic::parse(name).map(Mode::Bdpm),
        }
    }

    /// The mode's name as [`Mode::parse`] accepts it.
    pub fn name(&self) -> &'static str {
        match self {
            Mode::Path => "path",
            Mode::Light => "light",
            Mode::Bdpm(h) => h.name(),
        }
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Everything a render needs besides the scene. Defaults live in [`RenderSettings::default`].
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Number of passes K (each with a new photon map and new camera samples).
    pub passes: u32,
    /// Photons emitted per pass, N_F.
    pub photons: u64,
    /// Camera samples per pixel per pass, N_B.
    pub spp: u32,
    /// Merge (gather) radius r, metres; `None` = the scene's largest extent / 1600.
    pub radius: Option<f32>,
    /// Master seed of every random stream.
    pub seed: u64,
    /// Integrator and weight mode.
    pub mode: Mode,
    /// Radius R of the threshold rule (eq. 11), metres.
    pub threshold_radius: f32,
    /// Angular bins K per radiance-cache cell (one bin is used for Lambert-only scenes).
    pub cache_bins: u32,
    /// Photons traced for the radiance cache (`None` = N_F, one pass's worth). More photons
    /// with more bins make an "oracle" cache, to tell cache error from model error.
    pub cache_photons: Option<u64>,
    /// Backward rays per pixel of the A/B pre-pass, N (`None`: the default of the noise model,
    /// see [`RenderSettings::table_rays`]).
    pub pixel_table_rays: Option<u32>,
    /// Clamp the `optimal*` weights to [0, 1] (the mix stays unbiased either way). The
    /// footprint noise model with jittered samples always clamps (method-notes.md,
    /// "Clamping"); `Renderer::settings` reports the clamp in force.
    pub clamp_weights: bool,
    /// Path-tracing depth after which Russian roulette starts.
    pub roulette_depth: u32,
    /// Jitter camera samples over the pixel (box filter). When false, all N_B samples of a
    /// pixel go through its centre and share x₀, the layout the preprint's noise model (and
    /// its optimal weights) assumes.
    pub pixel_jitter: bool,
    /// How the model-based weights account for the photons that a pixel's camera samples
    /// share at x₀ (method.md §12): `Footprint` (default) uses N_eff per pixel, `Pinhole` the
    /// preprint's N_B. Without jitter both give N_eff = N_B.
    pub noise_model: NoiseModel,
}

/// A/B rays per pixel when the footprint noise model weighs jittered samples: there N_eff is
/// close to 1 and the c·G̃ term that A and B feed is small, and 16 rays give the same noise as
/// 64 (cornell-lambert 512², `optimal-path`, 10 passes: mean √V 7.6036e-4 against 7.6025e-4;
/// docs/results.md) at a quarter of the pre-pass's rays.
pub const FOOTPRINT_TABLE_RAYS: u32 = 16;

/// A/B rays per pixel otherwise (the preprint's layout, where c·G̃ matters).
pub const PINHOLE_TABLE_RAYS: u32 = 64;

impl RenderSettings {
    /// The A/B rays per pixel in force: `pixel_table_rays` if given, else
    /// [`FOOTPRINT_TABLE_RAYS`] under the footprint noise model with jittered samples and
    /// [`PINHOLE_TABLE_RAYS`] otherwise (which keeps the preprint's weights bit for bit).
    pub fn table_rays(&self) -> u32 {
        self.pixel_table_rays.unwrap_or(
            if self.noise_model == NoiseModel::Footprint && self.pixel_jitter {
                FOOTPRINT_TABLE_RAYS
            } else {
                PINHOLE_TABLE_RAYS
            },
        )
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 256,
            height: 256,
            passes: 4,
            photons: 100_000,
            spp: 4,
            radius: None,
            seed: 1,
            // `balance` wins at equal time on both preprint scenes with jittered pixels
            // (docs/results.md); `path` and `light` are references, not defaults.
            mode: Mode::Bdpm(Heuristic::Balance),
            threshold_radius: 0.2,
            cache_bins: 100,
            cache_photons: None,
            pixel_table_rays: None,
            clamp_weights: false,
            roulette_depth: 3,
            pixel_jitter: true,
            noise_model: NoiseModel::Footprint,
        }
    }
}

/// Where in the pixel a camera sample goes: the jittered offset, or the centre.
#[inline]
pub(crate) fn pixel_offset(u: [f32; 2], jitter: bool) -> [f32; 2] {
    if jitter { u } else { [0.5, 0.5] }
}

/// Smallest merge radius accepted, metres. The renderer divides by the merge disk's area in
/// f32 (1/(πr²)) and the photon grid by its cell edge 2r; below about 10⁻¹⁹ m r² is subnormal
/// or zero in f32 and the quotient infinite. At 10⁻¹⁸ m, 1/(πr²) ≈ 3·10³⁵ stays finite.
pub const MIN_RADIUS: f32 = 1e-18;

/// Checks a merge radius r (metres) in the precision the renderer uses it in: finite and at
/// least [`MIN_RADIUS`]. The error says what is wrong, without naming the field.
pub fn check_radius(r: f32) -> Result<f32, String> {
    if !(r.is_finite() && r > 0.0) {
        return Err(format!("{r:e} m must be a finite number > 0"));
    }
    if r < MIN_RADIUS {
        return Err(format!(
            "{r:e} m is below the smallest usable merge radius {MIN_RADIUS:e} m (1/(pi r^2) \
             would overflow single precision)"
        ));
    }
    Ok(r)
}

/// Default merge radius for a scene whose bounding box has largest extent `extent` (metres):
/// extent / 1600, as the preprint's Cornell box uses.
pub fn default_radius(extent: f32) -> f32 {
    extent / 1600.0
}
