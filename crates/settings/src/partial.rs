//! Settings given in part: the one shape of a scene file's `[render]` table, the command
//! line's overrides and a mode-list entry's own settings, and the one function that puts any
//! of them onto [`RenderSettings`].

use std::path::PathBuf;

use crate::{
    MAX_RADIUS_PX, MIN_RADIUS_AS_WRITTEN, RadiusSpec, RenderSettings, Setting, SettingsError,
    metres, parse_name,
};

/// Render settings given in part, as written: every field optional, named as the scene
/// file's `[render]` keys. Names (mode, noise model, sampler) and radii stay as the user
/// wrote them, so that [`PartialSettings::apply`] can check them and quote them; each caller
/// names the field its way (`render.mode` in a scene file, its own option on a command line).
///
/// With the `serde` feature it deserialises from a `[render]` table, refusing unknown keys,
/// each value read as written and set by [`PartialSettings::set`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PartialSettings {
    /// `[width, height]`, pixels; a list so that a wrong count is reported rather than
    /// truncated.
    pub resolution: Option<Vec<u32>>,
    /// [`RenderSettings::passes`].
    pub passes: Option<u32>,
    /// [`RenderSettings::photons`].
    pub photons: Option<u64>,
    /// [`RenderSettings::spp`].
    pub spp: Option<u32>,
    /// The merge radius, metres or pixel footprints ([`RadiusInput`]).
    pub radius: Option<RadiusInput>,
    /// [`RenderSettings::seed`].
    pub seed: Option<u64>,
    /// A mode name ([`crate::Mode::parse`]).
    pub mode: Option<String>,
    /// [`RenderSettings::threshold_radius`], metres as written.
    pub threshold_radius: Option<f64>,
    /// [`RenderSettings::cache_bins`].
    pub cache_bins: Option<u32>,
    /// [`RenderSettings::cache_photons`].
    pub cache_photons: Option<u64>,
    /// [`RenderSettings::pixel_table_rays`].
    pub pixel_table_rays: Option<u32>,
    /// [`RenderSettings::clamp_weights`].
    pub clamp_weights: Option<bool>,
    /// [`RenderSettings::pixel_jitter`].
    pub pixel_jitter: Option<bool>,
    /// A noise model name ([`crate::NoiseModel::parse`]).
    pub noise_model: Option<String>,
    /// A sampler name ([`crate::Sampler::parse`]).
    pub sampler: Option<String>,
    /// [`RenderSettings::roulette_depth`].
    pub roulette_depth: Option<u32>,
    /// [`RenderSettings::light_tracing`].
    pub light_tracing: Option<bool>,
    /// [`RenderSettings::direct_boost`].
    pub direct_boost: Option<u32>,
    /// [`RenderSettings::adaptive_radius`].
    pub adaptive_radius: Option<bool>,
    /// The render's default output file (a scene file's `output`). Not a render setting:
    /// [`PartialSettings::apply`] leaves it to the caller.
    pub output: Option<PathBuf>,
}

/// A merge radius as written: a number of metres (a scene file's `radius = 0.01`) or text
/// as [`RadiusSpec::parse`] reads it (`"0.01"`, `"0.01m"`, `"1.2px"`; scene files, command
/// lines, mode-list entries).
#[derive(Clone, Debug, PartialEq)]
pub enum RadiusInput {
    /// Metres.
    Metres(f64),
    /// Metres or pixel footprints, as text.
    Text(String),
}

impl RadiusInput {
    /// The radius given: text parsed, and the number checked as written, in f64, against
    /// the documented bounds (metres: [`metres`] and at least [`crate::MIN_RADIUS`]; pixel
    /// footprints: in (0, [`MAX_RADIUS_PX`]] and normal in f32), so that 1e300 is refused
    /// as 1e300 and 1e-50px as 1e-50, not as their f32 roundings, and a number just outside
    /// a bound does not round onto it.
    pub fn spec(&self) -> Result<RadiusSpec, SettingsError> {
        let spec = match self {
            RadiusInput::Metres(v) => RadiusSpec::Metres(*v),
            RadiusInput::Text(t) => RadiusSpec::parse(t).map_err(SettingsError::RadiusText)?,
        };
        match spec {
            RadiusSpec::Metres(v) => {
                let m = metres(v).map_err(|error| SettingsError::Length {
                    setting: Setting::Radius,
                    error,
                })?;
                if v < MIN_RADIUS_AS_WRITTEN {
                    return Err(SettingsError::RadiusBelowMinimum(v));
                }
                Ok(RadiusSpec::Metres(m.into()))
            }
            RadiusSpec::Pixels(k) => {
                if !(k > 0.0 && k <= f64::from(MAX_RADIUS_PX)) {
                    return Err(SettingsError::RadiusPx(k));
                }
                if !(k as f32).is_normal() {
                    return Err(SettingsError::RadiusPxBelowNormal(k));
                }
                Ok(RadiusSpec::Pixels(k))
            }
        }
    }
}

impl PartialSettings {
    /// Puts the settings given onto `settings` and checks each value of the result
    /// ([`RenderSettings::validate_values`]). Names are parsed, a resolution must have two
    /// values, lengths are checked as written; the error's [`SettingsError::setting`] says
    /// which setting, for the caller to name as its user wrote it. On error `settings` may be
    /// partly changed.
    ///
    /// The combinations of settings are not checked here: a later override (a command-line
    /// value over a scene file, a mode-list entry over both) may still put one right, so the
    /// caller checks them once, on the final settings ([`RenderSettings::validate`]).
    pub fn apply(&self, settings: &mut RenderSettings) -> Result<(), SettingsError> {
        let s = settings;
        if let Some(r) = &self.resolution {
            let &[w, h] = r.as_slice() else {
                return Err(SettingsError::ResolutionCount(r.len()));
            };
            (s.width, s.height) = (w, h);
        }
        if let Some(name) = &self.mode {
            s.mode = parse_name(name)?;
        }
        if let Some(name) = &self.noise_model {
            s.noise_model = parse_name(name)?;
        }
        if let Some(name) = &self.sampler {
            s.sampler = parse_name(name)?;
        }
        if let Some(r) = &self.radius {
            r.spec()?.apply(s);
        }
        if let Some(v) = self.threshold_radius {
            s.threshold_radius = metres(v).map_err(|error| SettingsError::Length {
                setting: Setting::ThresholdRadius,
                error,
            })?;
        }
        let set = |field: &mut u32, v: Option<u32>| *field = v.unwrap_or(*field);
        set(&mut s.passes, self.passes);
        set(&mut s.spp, self.spp);
        set(&mut s.cache_bins, self.cache_bins);
        set(&mut s.roulette_depth, self.roulette_depth);
        set(&mut s.direct_boost, self.direct_boost);
        s.adaptive_radius = self.adaptive_radius.unwrap_or(s.adaptive_radius);
        s.photons = self.photons.unwrap_or(s.photons);
        s.seed = self.seed.unwrap_or(s.seed);
        s.cache_photons = self.cache_photons.or(s.cache_photons);
        s.pixel_table_rays = self.pixel_table_rays.or(s.pixel_table_rays);
        s.clamp_weights = self.clamp_weights.unwrap_or(s.clamp_weights);
        s.pixel_jitter = self.pixel_jitter.unwrap_or(s.pixel_jitter);
        s.light_tracing = self.light_tracing.unwrap_or(s.light_tracing);
        s.validate_values()
    }
}
