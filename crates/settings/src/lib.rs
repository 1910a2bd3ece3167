//! The render settings of bdpm: one type ([`RenderSettings`]), one validation
//! ([`RenderSettings::validate`]), one shape for settings given in part ([`PartialSettings`]:
//! a scene file's `[render]` table, command-line overrides, a mode-list entry) applied by one
//! function, and one record of them for reports and image headers ([`SettingsRecord`]),
//! shared by the scene loader, the integrator and the driver.
//!
//! Units: distances in metres.
//!
//! **Architecture invariant:** this crate depends on `bdpm-mis` (for [`Heuristic`] and
//! [`NoiseModel`]) and on nothing of geometry, scenes or photons, so the loader can build
//! settings without the integrator. Serde support (for [`RenderSettings`], whose serialised
//! form the run identity hashes, for [`PartialSettings`] and for [`SettingsRecord`]) is behind
//! the cargo feature `serde`.
//!
//! **One source for each parameter:** the mode is a [`Mode`] without parameters; the
//! threshold radius R is [`RenderSettings::threshold_radius`] and the weight clamp asked for
//! is [`RenderSettings::clamp_weights`], nowhere else. [`RenderSettings::heuristic`] builds
//! the heuristic in force from the mode and those settings, with the clamp the footprint
//! noise model needs ([`RenderSettings::weight_clamp`]); nothing is written back.
//!
//! ```
//! use bdpm_settings::{Heuristic, Mode, RenderSettings, Setting, SettingsError};
//! let mut s = RenderSettings::default();
//! s.mode = "threshold".parse().unwrap();
//! s.threshold_radius = 0.5;
//! assert!(s.validate().is_ok());
//! assert_eq!(s.heuristic(), Some(Heuristic::Threshold { radius: 0.5 }));
//! s.passes = 0;
//! let e = s.validate().unwrap_err();
//! assert_eq!(e.setting(), Setting::Passes);
//! assert!(matches!(e, SettingsError::OutOfRange { value: 0, .. }));
//! ```

use std::fmt;
use std::str::FromStr;

pub use bdpm_mis::{Heuristic, HeuristicKind, NoiseModel};

mod partial;
mod record;
#[cfg(feature = "serde")]
mod serde_names;
#[cfg(feature = "serde")]
mod serde_partial;
mod values;

pub use partial::{PartialSettings, RadiusInput};
pub use record::SettingsRecord;
pub use values::{RENDER_KEYS, ValueError, Written};

/// What a render computes: the unidirectional reference, or the BDPM mix with a weight mode.
/// A mode carries no parameters: the threshold radius and the weight clamp are settings of
/// their own ([`RenderSettings::heuristic`] combines them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Unidirectional path tracing with next-event estimation (the reference).
    Path,
    /// Exact direct light plus light tracing connected to the camera (a second, independent
    /// reference that converges fast around small bright secondary sources).
    Light,
    /// The BDD=0/BDD=1 photon-mapping mix weighted by a heuristic (method.md §4, §8).
    Bdpm(HeuristicKind),
}

impl Mode {
    /// Every mode name the parser accepts: the references (`path`, `light`), then the
    /// weighting modes of bdpm-mis's table ([`Heuristic::ALL_NAMES`]).
    pub fn names() -> Vec<&'static str> {
        ["path", "light"]
            .into_iter()
            .chain(Heuristic::ALL_NAMES.iter().copied())
            .collect()
    }

    /// Parses a mode name (`path`, `bdd0`, `bdd1`, `threshold`, …); unknown names give `None`
    /// (`str::parse` gives an error that lists the names instead).
    pub fn parse(name: &str) -> Option<Mode> {
        match name {
            "path" => Some(Mode::Path),
            "light" => Some(Mode::Light),
            _ => HeuristicKind::parse(name).map(Mode::Bdpm),
        }
    }

    /// The mode's name as [`Mode::parse`] accepts it.
    pub fn name(&self) -> &'static str {
        match self {
            Mode::Path => "path",
            Mode::Light => "light",
            Mode::Bdpm(k) => k.name(),
        }
    }

    /// The weighting mode of a BDPM mode; `None` for the references.
    pub fn kind(&self) -> Option<HeuristicKind> {
        match self {
            Mode::Bdpm(k) => Some(*k),
            Mode::Path | Mode::Light => None,
        }
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Mode {
    type Err = SettingsError;

    /// [`Mode::parse`], with an error ([`SettingsError::UnknownName`]) that lists the names.
    fn from_str(s: &str) -> Result<Mode, SettingsError> {
        parse_name(s)
    }
}

/// How the N_B camera samples of one pixel in one pass are placed: over the pixel's area and
/// over the BDF direction sampled at x₀ (the integrator's `sampler` module owns the layouts).
/// Every pass draws its own layout, independently of every other pass, so the passes stay
/// independent and identically distributed whatever the sampler.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sampler {
    /// Every sample independent and uniform (the layout of the preprint's runs).
    Independent,
    /// Stratified within the pass: the pixel cut into an n_x × n_y grid of N_B strata with one
    /// jittered sample in each, and the direction at x₀ likewise on a second grid, its strata
    /// assigned to the samples by a random permutation (pbrt's stratified sampler with padding).
    #[default]
    Stratified,
}

impl Sampler {
    /// Every name [`Sampler::parse`] accepts.
    pub const ALL_NAMES: &'static [&'static str] = &["independent", "stratified"];

    /// The sampler's name as used in settings and reports.
    pub fn name(&self) -> &'static str {
        match self {
            Sampler::Independent => "independent",
            Sampler::Stratified => "stratified",
        }
    }

    /// The inverse of [`Sampler::name`]; unknown names give `None`.
    pub fn parse(name: &str) -> Option<Sampler> {
        match name {
            "independent" => Some(Sampler::Independent),
            "stratified" => Some(Sampler::Stratified),
            _ => None,
        }
    }
}

impl fmt::Display for Sampler {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Sampler {
    type Err = SettingsError;

    /// [`Sampler::parse`], with an error ([`SettingsError::UnknownName`]) that lists the names.
    fn from_str(s: &str) -> Result<Sampler, SettingsError> {
        parse_name(s)
    }
}

/// A setting whose values are named (the mode, the noise model, the sampler): one way to
/// parse them, with one message for an unknown name, in every place that reads names.
pub(crate) trait Named: Sized + fmt::Display {
    /// The setting the names are values of.
    const SETTING: Setting;
    /// Every accepted name.
    fn names() -> Vec<&'static str>;
    /// The value of a name, if any (the inverse of its `Display`).
    fn from_name(name: &str) -> Option<Self>;
}

impl Named for Mode {
    const SETTING: Setting = Setting::Mode;
    fn names() -> Vec<&'static str> {
        Mode::names()
    }
    fn from_name(name: &str) -> Option<Self> {
        Mode::parse(name)
    }
}

impl Named for NoiseModel {
    const SETTING: Setting = Setting::NoiseModel;
    fn names() -> Vec<&'static str> {
        NoiseModel::ALL_NAMES.to_vec()
    }
    fn from_name(name: &str) -> Option<Self> {
        NoiseModel::parse(name)
    }
}

impl Named for Sampler {
    const SETTING: Setting = Setting::Sampler;
    fn names() -> Vec<&'static str> {
        Sampler::ALL_NAMES.to_vec()
    }
    fn from_name(name: &str) -> Option<Self> {
        Sampler::parse(name)
    }
}

/// The value named `name`, or [`SettingsError::UnknownName`] listing the names.
pub(crate) fn parse_name<T: Named>(name: &str) -> Result<T, SettingsError> {
    T::from_name(name).ok_or_else(|| SettingsError::UnknownName {
        setting: T::SETTING,
        name: name.to_string(),
        expected: T::names(),
    })
}

/// Everything a render needs besides the scene. Defaults live in [`RenderSettings::default`];
/// [`RenderSettings::validate`] checks a value before use.
///
/// With the `serde` feature it serialises field by field under the field names (the keys of
/// a scene file's `[render]` table where the two share a setting), the mode, the noise model
/// and the sampler as their names; unknown keys are refused, and deserialising does not
/// validate. The run identity hashes this form (`bdpm_output::accum::settings_hash`).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields)
)]
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
    /// Merge (gather) radius r, metres: when set, the radius in force (and
    /// [`RenderSettings::radius_px`] is not read); `None` = `radius_px` if set, else the
    /// scene's largest extent / 1600 ([`default_radius`]).
    pub radius: Option<f32>,
    /// Merge radius in pixel footprints (`radius = "1px"`): resolved into metres against the
    /// scene's camera when a renderer is made (the median footprint of the pixels' first
    /// hits, method-notes.md "Radius in pixels"), when `radius` is `None`. The default is
    /// [`DEFAULT_RADIUS_PX`]; a radius given in a scene file or on the command line sets one
    /// of the two and clears the other.
    pub radius_px: Option<f32>,
    /// Master seed of every random stream.
    pub seed: u64,
    /// Integrator and weight mode, without parameters (they are the settings below).
    #[cfg_attr(feature = "serde", serde(with = "serde_names"))]
    pub mode: Mode,
    /// Radius R of the threshold rule (eq. 11), metres: the `threshold` mode's radius, and
    /// nowhere else.
    pub threshold_radius: f32,
    /// Angular bins K per radiance-cache cell side (one bin is used for Lambert-only scenes;
    /// [`DEFAULT_CACHE_BINS`] by default).
    pub cache_bins: u32,
    /// Photons traced for the radiance cache (`None` = N_F, one pass's worth). More photons
    /// with more bins make an "oracle" cache, to tell cache error from model error.
    pub cache_photons: Option<u64>,
    /// Backward rays per pixel of the A/B pre-pass, N (`None`: the default of the noise model,
    /// see [`RenderSettings::table_rays`]).
    pub pixel_table_rays: Option<u32>,
    /// Ask for the `optimal*` weights clamped to [0, 1] (the mix stays unbiased either way):
    /// the one place the request lives. The footprint noise model with jittered samples
    /// clamps whatever is asked: see [`RenderSettings::weight_clamp`].
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
    #[cfg_attr(feature = "serde", serde(with = "serde_names"))]
    pub noise_model: NoiseModel,
    /// How a pixel's camera samples are placed within a pass ([`Sampler`]).
    #[cfg_attr(feature = "serde", serde(with = "serde_names"))]
    pub sampler: Sampler,
    /// Sample BDD=0's paths by light tracing (each photon arrival connected to the camera,
    /// with BDD=0's weight) instead of merging photons at the camera's x₀: the same photons
    /// without the merge's hit noise, kernel bias or gathers (method-notes.md). The mixing
    /// modes only; `bdd1` has no BDD=0 part, and the `path` and `light` references ignore it.
    /// Serialised only when set, so that the settings hash of every render without it (and so
    /// its accumulation files) stays what it was.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "std::ops::Not::not")
    )]
    pub light_tracing: bool,
    /// The most direct-light samples per camera sample, M_max (1: off). Where the direct light
    /// L₀(x₀) varies steeply over a pixel (a surface close to a point light), each camera
    /// sample of the BDPM mix and of the `light` reference's direct term also evaluates L₀ at up to
    /// M_max − 1 further points of its own
    /// stratum of the pixel: the pixel-integration noise of L₀ falls there for a primary and a
    /// shadow ray each. How many a pixel gets is fixed before the passes, from the scene alone
    /// (`bdpm_integrator`'s `direct` module), so every pass stays unbiased and independent.
    /// Serialised only when not 1, so that the settings hash of every render without it (and
    /// so its accumulation files) stays what it was; absent means 1.
    #[cfg_attr(
        feature = "serde",
        serde(
            default = "direct_boost_off",
            skip_serializing_if = "is_direct_boost_off"
        )
    )]
    pub direct_boost: u32,
    /// A merge radius per 8 × 8-pixel block instead of one for the image: before the passes, a
    /// pilot of [`ADAPTIVE_RADIUS_PILOT_PASSES`] passes of the mode on streams of its own splits
    /// each block's image by technique, and the block's radius is ½ the radius where BDD=1
    /// carries under 30 % of it, the radius from 30 to 60 %, and 1.4 × the radius above
    /// (docs/results.md, "A sharper glossy reference"): where the exact direct light makes the
    /// image a larger disk buys little, where BDD=1's merges do it buys much. The mixing modes
    /// (with light tracing, a splat weighs with the radius of the pixel it lands in).
    /// Serialised only when set, so that the settings hash of every render without it (and so
    /// its accumulation files) stays what it was.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "std::ops::Not::not")
    )]
    pub adaptive_radius: bool,
}

/// Passes of [`RenderSettings::adaptive_radius`]'s pilot. One pass at the render's N_F and
/// N_B cut the glossy box's relV as much as two (0.79–0.84× against 0.79–0.81×, seeds 1–3,
/// docs/results.md, "A one-pass pilot") for half the pilot's time; a pass at N_B = 4 or
/// N_F = 10⁵ saved a little more time and kept a little less of the cut.
pub const ADAPTIVE_RADIUS_PILOT_PASSES: u32 = 1;

/// [`RenderSettings::direct_boost`] of a serialised record that does not name it.
#[cfg(feature = "serde")]
fn direct_boost_off() -> u32 {
    1
}

#[cfg(feature = "serde")]
fn is_direct_boost_off(m: &u32) -> bool {
    *m == 1
}

/// A/B rays per pixel when the footprint noise model weighs jittered samples: there N_eff is
/// close to 1 and the c·G̃ term that A and B feed is small, and 16 rays give the same noise as
/// 64 (cornell-lambert 512², `optimal-path`, 10 passes: mean √V 7.6036e-4 against 7.6025e-4;
/// docs/results.md) at a quarter of the pre-pass's rays.
pub const FOOTPRINT_TABLE_RAYS: u32 = 16;

/// A/B rays per pixel otherwise (the preprint's layout, where c·G̃ matters).
pub const PINHOLE_TABLE_RAYS: u32 = 64;

/// The ranges [`RenderSettings::validate`] accepts beyond "at least 1".
pub mod limits {
    /// Largest image side, pixels.
    pub const MAX_RESOLUTION: u32 = 16384;
    /// Most photons per pass (also for the radiance cache).
    pub const MAX_PHOTONS: u64 = 1_000_000_000;
    /// Most angular bins per radiance-cache cell.
    pub const MAX_CACHE_BINS: u32 = 4096;
    /// Most backward rays per pixel of the A/B pre-pass (256 times the default of 64). The
    /// pre-pass shows no progress, and 4·10⁹ rays per pixel would run for days.
    pub const MAX_PIXEL_TABLE_RAYS: u32 = 16384;
    /// Most direct-light samples per camera sample ([`crate::RenderSettings::direct_boost`]).
    pub const MAX_DIRECT_BOOST: u32 = 64;
}

/// Whether the `optimal*` weights are clamped to [0, 1], and why.
///
/// Under the footprint model with jittered samples the weights are clamped
/// (method-notes.md, "Clamping"): unclamped, the correlation term pushes many of them
/// outside, and the two techniques' contributions then cancel with a heavy-tailed sum. The
/// pinhole model and centred samples keep the preprint's unclamped weights unless asked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WeightClamp {
    /// The caller asked for it ([`RenderSettings::clamp_weights`]).
    pub requested: bool,
    /// The footprint noise model with jittered samples needs it.
    pub footprint: bool,
}

impl WeightClamp {
    /// The clamp in force: asked for or needed.
    pub fn effective(&self) -> bool {
        self.requested || self.footprint
    }
}

/// One setting, as named in the scene file's `[render]` table (see [`Setting::key`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Setting {
    /// [`RenderSettings::width`].
    Width,
    /// [`RenderSettings::height`].
    Height,
    /// [`RenderSettings::passes`].
    Passes,
    /// [`RenderSettings::photons`].
    Photons,
    /// [`RenderSettings::spp`].
    Spp,
    /// [`RenderSettings::width`] and [`RenderSettings::height`] given together (a
    /// `resolution` of the wrong length).
    Resolution,
    /// [`RenderSettings::radius`] (or [`RenderSettings::radius_px`]).
    Radius,
    /// [`RenderSettings::mode`].
    Mode,
    /// [`RenderSettings::noise_model`].
    NoiseModel,
    /// [`RenderSettings::sampler`].
    Sampler,
    /// [`RenderSettings::threshold_radius`].
    ThresholdRadius,
    /// [`RenderSettings::cache_bins`].
    CacheBins,
    /// [`RenderSettings::cache_photons`].
    CachePhotons,
    /// [`RenderSettings::pixel_table_rays`].
    PixelTableRays,
    /// [`RenderSettings::light_tracing`].
    LightTracing,
    /// [`RenderSettings::direct_boost`].
    DirectBoost,
    /// [`RenderSettings::adaptive_radius`].
    AdaptiveRadius,
}

impl Setting {
    /// The key in the scene file's `[render]` table (`resolution[0]` for the width).
    pub fn key(&self) -> &'static str {
        match self {
            Setting::Width => "resolution[0]",
            Setting::Height => "resolution[1]",
            Setting::Passes => "passes",
            Setting::Photons => "photons",
            Setting::Spp => "spp",
            Setting::Resolution => "resolution",
            Setting::Radius => "radius",
            Setting::Mode => "mode",
            Setting::NoiseModel => "noise_model",
            Setting::Sampler => "sampler",
            Setting::ThresholdRadius => "threshold_radius",
            Setting::CacheBins => "cache_bins",
            Setting::CachePhotons => "cache_photons",
            Setting::PixelTableRays => "pixel_table_rays",
            Setting::LightTracing => "light_tracing",
            Setting::DirectBoost => "direct_boost",
            Setting::AdaptiveRadius => "adaptive_radius",
        }
    }

    /// What a value of this setting is called in messages (`unknown noise model 'x'`).
    fn noun(&self) -> &'static str {
        match self {
            Setting::NoiseModel => "noise model",
            other => other.key(),
        }
    }

    /// The noun with its article (`a mode`, `a noise model`).
    pub(crate) fn article_noun(&self) -> String {
        format!("a {}", self.noun())
    }

    /// The accepted range of a count, both ends included; `None` for a setting that is not
    /// a count. [`RenderSettings::validate`] checks these, and a value as written is checked
    /// against the same range before it is converted ([`PartialSettings::set`]).
    pub fn range(&self) -> Option<(u64, u64)> {
        use limits::*;
        let most = |max: u32| Some((1, u64::from(max)));
        match self {
            Setting::Width | Setting::Height => most(MAX_RESOLUTION),
            Setting::Passes | Setting::Spp => most(u32::MAX),
            Setting::Photons | Setting::CachePhotons => Some((1, MAX_PHOTONS)),
            Setting::CacheBins => most(MAX_CACHE_BINS),
            Setting::PixelTableRays => most(MAX_PIXEL_TABLE_RAYS),
            Setting::DirectBoost => most(MAX_DIRECT_BOOST),
            _ => None,
        }
    }
}

impl fmt::Display for Setting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.key())
    }
}

/// Why a merge radius cannot be used. `Display` says what is wrong without naming the field.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum RadiusError {
    /// Not finite, or not > 0 (metres).
    #[error("{0:e} m must be a finite number > 0")]
    NotPositive(f32),
    /// Below [`MIN_RADIUS`] (metres).
    #[error(
        "{0:e} m is below the smallest usable merge radius {MIN_RADIUS:e} m (1/(pi r^2) would overflow single precision)"
    )]
    BelowMinimum(f32),
}

/// Why settings are not acceptable. `Display` says what is wrong; [`SettingsError::setting`]
/// says which setting, so that the loader can name the scene-file key and the driver its flag.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SettingsError {
    /// A count outside its range.
    #[error("{value} is outside [{min}, {max}]")]
    OutOfRange {
        /// Which setting.
        setting: Setting,
        /// The value given.
        value: u64,
        /// Smallest accepted.
        min: u64,
        /// Largest accepted.
        max: u64,
    },
    /// A merge radius that cannot be used.
    #[error("{0}")]
    Radius(RadiusError),
    /// A merge radius in pixel footprints that is not finite or not in (0, [`MAX_RADIUS_PX`]]
    /// (the number as written).
    #[error(
        "{} px: the radius must be positive, a number of pixel footprints in (0, {MAX_RADIUS_PX}]",
        number_text(*.0)
    )]
    RadiusPx(f64),
    /// A merge radius in pixel footprints too small for single precision (the number as
    /// written; it would be zero or subnormal).
    #[error(
        "{} px is below the smallest normal single-precision number (1.2e-38)",
        number_text(*.0)
    )]
    RadiusPxBelowNormal(f64),
    /// A merge radius in metres, as written, below [`MIN_RADIUS`].
    #[error(
        "{} m is below the smallest usable merge radius {MIN_RADIUS:e} m (1/(pi r^2) would overflow single precision)",
        number_text(*.0)
    )]
    RadiusBelowMinimum(f64),
    /// A threshold radius R that is not finite, not > 0 or not a normal f32 (metres).
    #[error("{0:e} must be a finite number > 0 (metres)")]
    ThresholdRadius(f32),
    /// A length as written that single precision cannot hold ([`metres`]).
    #[error("{error}")]
    Length {
        /// Which setting.
        setting: Setting,
        /// What is wrong with the number.
        error: LengthError,
    },
    /// A radius written as text that [`RadiusSpec::parse`] does not read; the message says why.
    #[error("{0}")]
    RadiusText(String),
    /// A `resolution` of other than two values.
    #[error("{0} values given; expected [width, height] in pixels")]
    ResolutionCount(usize),
    /// A name that is none of the setting's values (a mode, noise model or sampler).
    #[error("unknown {} '{name}'; expected one of {}", setting.noun(), expected.join(", "))]
    UnknownName {
        /// Which setting.
        setting: Setting,
        /// The name given.
        name: String,
        /// Every accepted name.
        expected: Vec<&'static str>,
    },
    /// Light tracing with pixel jitter off: a connection lands anywhere in its pixel and so
    /// estimates the pixel's area average, while unjittered camera samples estimate the
    /// radiance through the pixel's centre; a mix of the two converges to neither.
    #[error(
        "light tracing estimates a pixel's average over its area, which a render without pixel jitter (pixel_jitter = false) does not: turn one of them off"
    )]
    LightTracingWithoutJitter,
}

impl SettingsError {
    /// The setting the error is about.
    pub fn setting(&self) -> Setting {
        match self {
            SettingsError::OutOfRange { setting, .. } => *setting,
            SettingsError::Radius(_)
            | SettingsError::RadiusPx(_)
            | SettingsError::RadiusPxBelowNormal(_)
            | SettingsError::RadiusBelowMinimum(_)
            | SettingsError::RadiusText(_) => Setting::Radius,
            SettingsError::ThresholdRadius(_) => Setting::ThresholdRadius,
            SettingsError::ResolutionCount(_) => Setting::Resolution,
            SettingsError::LightTracingWithoutJitter => Setting::LightTracing,
            SettingsError::Length { setting, .. } | SettingsError::UnknownName { setting, .. } => {
                *setting
            }
        }
    }
}

impl RenderSettings {
    /// The A/B rays per pixel in force: `pixel_table_rays` if given, else
    /// [`FOOTPRINT_TABLE_RAYS`] under the footprint noise model with jittered samples and
    /// [`PINHOLE_TABLE_RAYS`] otherwise (which keeps the preprint's weights bit for bit).
    pub fn table_rays(&self) -> u32 {
        self.pixel_table_rays.unwrap_or(if self.footprint_jitter() {
            FOOTPRINT_TABLE_RAYS
        } else {
            PINHOLE_TABLE_RAYS
        })
    }

    /// True under the footprint noise model with jittered samples.
    fn footprint_jitter(&self) -> bool {
        self.noise_model == NoiseModel::Footprint && self.pixel_jitter
    }

    /// Whether the `optimal*` weights are clamped, and why (see [`WeightClamp`]). The same for
    /// every mode; only the `optimal*` weights can leave [0, 1].
    pub fn weight_clamp(&self) -> WeightClamp {
        WeightClamp {
            requested: self.clamp_weights,
            footprint: self.footprint_jitter(),
        }
    }

    /// The heuristic a BDPM render uses, built from the mode and the settings that hold its
    /// parameters: a `threshold` mode with [`RenderSettings::threshold_radius`], an
    /// `optimal*` mode with the clamp in force ([`RenderSettings::weight_clamp`]). `None` for
    /// the references.
    pub fn heuristic(&self) -> Option<Heuristic> {
        let clamp = self.weight_clamp().effective();
        self.mode.kind().map(|kind| match kind.heuristic() {
            Heuristic::Threshold { .. } => Heuristic::Threshold {
                radius: self.threshold_radius.into(),
            },
            other => other.with_weight_clamp(clamp),
        })
    }

    /// Whether BDD=0's paths are sampled by light tracing: `light_tracing` set and a mode with
    /// a BDD=0 part (a mixing mode other than `bdd1`; `path` and `light` ignore the setting).
    pub fn light_traced(&self) -> bool {
        self.light_tracing && self.mode.kind().is_some_and(|k| k != HeuristicKind::Bdd1)
    }

    /// Checks every setting ([`RenderSettings::validate_values`]) and then the combinations of
    /// settings (light tracing needs pixel jitter). The first problem found is returned. Run
    /// it once, on the final settings: a combination that a scene file gets wrong can be put
    /// right by a command-line override.
    pub fn validate(&self) -> Result<(), SettingsError> {
        self.validate_values()?;
        if self.light_tracing && !self.pixel_jitter {
            return Err(SettingsError::LightTracingWithoutJitter);
        }
        Ok(())
    }

    /// Checks each setting on its own: counts within their [`Setting::range`], a given merge
    /// radius usable ([`check_radius`]), a radius in pixels in (0, [`MAX_RADIUS_PX`]] and the
    /// threshold radius finite, > 0 and normal; not the combinations
    /// ([`RenderSettings::validate`]). The first problem found is returned.
    pub fn validate_values(&self) -> Result<(), SettingsError> {
        let range = |setting: Setting, value: u64| {
            let (min, max) = setting.range().unwrap_or((0, u64::MAX));
            if (min..=max).contains(&value) {
                Ok(())
            } else {
                Err(SettingsError::OutOfRange {
                    setting,
                    value,
                    min,
                    max,
                })
            }
        };
        range(Setting::Width, self.width.into())?;
        range(Setting::Height, self.height.into())?;
        range(Setting::Passes, self.passes.into())?;
        range(Setting::Photons, self.photons)?;
        range(Setting::Spp, self.spp.into())?;
        if let Some(r) = self.radius {
            check_radius(r).map_err(SettingsError::Radius)?;
        }
        if let Some(k) = self.radius_px
            && !(k > 0.0 && k <= MAX_RADIUS_PX)
        {
            return Err(SettingsError::RadiusPx(k.into()));
        }
        let t = self.threshold_radius;
        if !(t.is_finite() && t > 0.0 && t.is_normal()) {
            return Err(SettingsError::ThresholdRadius(t));
        }
        range(Setting::CacheBins, self.cache_bins.into())?;
        if let Some(n) = self.cache_photons {
            range(Setting::CachePhotons, n)?;
        }
        if let Some(n) = self.pixel_table_rays {
            range(Setting::PixelTableRays, n.into())?;
        }
        range(Setting::DirectBoost, self.direct_boost.into())
    }

    /// The settings as reports and image headers give them, with the merge radius in force
    /// (`radius`, metres: the scene's default when none was given), whether it was given, and
    /// the scene's pixel footprint (metres) when known, to give the radius in pixels too.
    pub fn record(
        &self,
        radius: f32,
        radius_given: bool,
        footprint: Option<f32>,
    ) -> SettingsRecord {
        SettingsRecord {
            mode: self.mode.name(),
            width: self.width,
            height: self.height,
            passes: self.passes,
            photons_per_pass: self.photons,
            spp: self.spp,
            radius_m: radius,
            radius_px: footprint.map(|f| radius / f),
            radius_given,
            seed: self.seed,
            threshold_radius_m: self.threshold_radius,
            cache_bins: self.cache_bins,
            cache_photons: self.cache_photons.unwrap_or(self.photons),
            pixel_table_rays: self.table_rays(),
            clamp_weights: self.weight_clamp().effective(),
            clamp_weights_requested: self.weight_clamp().requested,
            pixel_jitter: self.pixel_jitter,
            noise_model: self.noise_model.name(),
            sampler: self.sampler.name(),
            light_tracing: self.light_tracing,
            direct_boost: self.direct_boost,
            adaptive_radius: self.adaptive_radius,
        }
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 256,
            height: 256,
            passes: 4,
            // What a scene that sets nothing renders with: the configuration that had the
            // lowest error at equal CPU time on both Cornell boxes among those measured
            // (docs/results.md, "A scene that sets nothing"): within 6 % of the best relMSE on
            // the Lambert box and the best on the glossy one.
            photons: DEFAULT_PHOTONS,
            spp: DEFAULT_SPP,
            radius: None,
            radius_px: Some(DEFAULT_RADIUS_PX),
            seed: 1,
            mode: Mode::Bdpm(HeuristicKind::OptimalPath),
            threshold_radius: bdpm_mis::DEFAULT_THRESHOLD_RADIUS as f32,
            // One bin per cell side, not method.md's M ≈ 100: from N_F cache photons the
            // 100-bin estimates gave the weights nothing more on the glossy Cornell box and
            // cost 11 % a pass (docs/results.md, "One radiance-cache bin on the glossy box").
            cache_bins: DEFAULT_CACHE_BINS,
            cache_photons: None,
            pixel_table_rays: None,
            clamp_weights: false,
            roulette_depth: 3,
            pixel_jitter: true,
            noise_model: NoiseModel::Footprint,
            sampler: Sampler::Stratified,
            light_tracing: false,
            // Only pixels close to a point light take more than one: on the Lambert box the
            // ceiling above the light (docs/results.md, "Direct light near a light").
            direct_boost: DEFAULT_DIRECT_BOOST,
            adaptive_radius: false,
        }
    }
}

/// [`RenderSettings::direct_boost`] of [`RenderSettings::default`].
pub const DEFAULT_DIRECT_BOOST: u32 = 16;

/// Photons per pass N_F of [`RenderSettings::default`].
pub const DEFAULT_PHOTONS: u64 = 250_000;

/// Camera samples per pixel per pass N_B of [`RenderSettings::default`].
pub const DEFAULT_SPP: u32 = 10;

/// Radiance-cache bins per cell side of [`RenderSettings::default`] (a Lambert-only scene
/// uses one whatever this says).
pub const DEFAULT_CACHE_BINS: u32 = 1;

/// Merge radius of [`RenderSettings::default`], pixel footprints.
pub const DEFAULT_RADIUS_PX: f32 = 0.5;

/// Largest merge radius in pixel footprints accepted ([`RenderSettings::radius_px`]).
pub const MAX_RADIUS_PX: f32 = 1000.0;

/// A merge radius as a user writes it: metres (`0.01`) or pixel footprints (`1.2px`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RadiusSpec {
    /// Metres.
    Metres(f64),
    /// Pixel footprints ([`RenderSettings::radius_px`]).
    Pixels(f64),
}

impl RadiusSpec {
    /// Parses `0.01` (metres), `0.01m` or `1.2px`. Says what is wrong otherwise; the number
    /// is not checked here (`-1px` parses), the ranges are: as written by
    /// [`RadiusInput::spec`], in single precision by [`RenderSettings::validate`].
    pub fn parse(text: &str) -> Result<RadiusSpec, String> {
        let t = text.trim();
        let (number, px) = match t.strip_suffix("px") {
            Some(n) => (n, true),
            None => (t.strip_suffix('m').unwrap_or(t), false),
        };
        let v: f64 = number.trim().parse().map_err(|_| {
            format!("'{text}' is not a radius: write metres (0.01) or pixel footprints (1.2px)")
        })?;
        Ok(if px {
            RadiusSpec::Pixels(v)
        } else {
            RadiusSpec::Metres(v)
        })
    }

    /// Puts this radius into `settings`, clearing the other unit.
    pub fn apply(self, settings: &mut RenderSettings) {
        match self {
            RadiusSpec::Metres(m) => {
                settings.radius = Some(m as f32);
                settings.radius_px = None;
            }
            RadiusSpec::Pixels(k) => {
                settings.radius = None;
                settings.radius_px = Some(k as f32);
            }
        }
    }
}

impl fmt::Display for RadiusSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RadiusSpec::Metres(m) => write!(f, "{m}"),
            RadiusSpec::Pixels(k) => write!(f, "{k}px"),
        }
    }
}

/// Smallest merge radius accepted, metres. The renderer divides by the merge disk's area in
/// f32 (1/(πr²)) and the photon grid by its cell edge 2r; below about 10⁻¹⁹ m r² is subnormal
/// or zero in f32 and the quotient infinite. At 10⁻¹⁸ m, 1/(πr²) ≈ 3·10³⁵ stays finite.
pub const MIN_RADIUS: f32 = MIN_RADIUS_AS_WRITTEN as f32;

/// [`MIN_RADIUS`] as a decimal, for a radius checked as the user wrote it (in f64): the f32
/// constant widened to f64 is not 10⁻¹⁸, so a user's `1e-18` would be refused against it, and
/// a number just below the bound would round onto it in f32.
pub(crate) const MIN_RADIUS_AS_WRITTEN: f64 = 1e-18;

/// Checks a merge radius r (metres) in the precision the renderer uses it in: finite and at
/// least [`MIN_RADIUS`].
pub fn check_radius(r: f32) -> Result<f32, RadiusError> {
    if !(r.is_finite() && r > 0.0) {
        return Err(RadiusError::NotPositive(r));
    }
    if r < MIN_RADIUS {
        return Err(RadiusError::BelowMinimum(r));
    }
    Ok(r)
}

/// Why a length as written (metres, in f64 as the user typed it) cannot be used in single
/// precision. The number is quoted as written ([`number_text`]): 1e300, not its f32 rounding.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum LengthError {
    /// Not finite, or not > 0.
    #[error("{} must be a finite number > 0 (metres)", number_text(*.0))]
    NotPositive(f64),
    /// Beyond the f32 range (it would become infinite).
    #[error("{} is beyond the single-precision range (3.4e38 metres)", number_text(*.0))]
    BeyondSingle(f64),
    /// Below the smallest normal f32 (it would be zero or subnormal, and its reciprocal
    /// infinite).
    #[error(
        "{} is below the smallest normal single-precision number (1.2e-38 metres)",
        number_text(*.0)
    )]
    BelowNormal(f64),
}

/// A length as written, metres, converted to f32: finite and > 0 as written, and finite and
/// normal in f32 (a subnormal length is zero for every computation that uses it). The one
/// check of lengths typed by a user: scene-file lengths, radii on the command line.
pub fn metres(v: f64) -> Result<f32, LengthError> {
    if !(v.is_finite() && v > 0.0) {
        return Err(LengthError::NotPositive(v));
    }
    let f = v as f32;
    if !f.is_finite() {
        return Err(LengthError::BeyondSingle(v));
    }
    if !f.is_normal() {
        return Err(LengthError::BelowNormal(v));
    }
    Ok(f)
}

/// A number for messages: as written when of ordinary size, in scientific notation when huge
/// or tiny (f64's `Display` would spell 1e300 with 301 digits).
pub fn number_text(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e7).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Default merge radius for a scene whose bounding box has largest extent `extent` (metres):
/// extent / 1600, as the preprint's Cornell box uses.
pub fn default_radius(extent: f32) -> f32 {
    extent / 1600.0
}

#[cfg(test)]
mod tests;

// The README (the crate's page on crates.io) as a hidden item, so that `cargo test --doc`
// compiles and runs its example; the crate documentation above stays as it is.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
