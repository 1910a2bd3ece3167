//! Serde for [`RenderSettings`]: modes and noise models as their names, the other fields as
//! they are. Deserialising does not validate; call [`RenderSettings::validate`].

use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::{Mode, NoiseModel, RenderSettings, Sampler};

/// The serialised form: the fields of [`RenderSettings`], names for the enums.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Repr {
    width: u32,
    height: u32,
    passes: u32,
    photons: u64,
    spp: u32,
    radius: Option<f32>,
    #[serde(default)]
    radius_px: Option<f32>,
    seed: u64,
    mode: String,
    threshold_radius: f32,
    cache_bins: u32,
    cache_photons: Option<u64>,
    pixel_table_rays: Option<u32>,
    clamp_weights: bool,
    roulette_depth: u32,
    pixel_jitter: bool,
    noise_model: String,
    sampler: String,
}

impl Serialize for RenderSettings {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        Repr {
            width: self.width,
            height: self.height,
            passes: self.passes,
            photons: self.photons,
            spp: self.spp,
            radius: self.radius,
            radius_px: self.radius_px,
            seed: self.seed,
            mode: self.mode.name().into(),
            threshold_radius: self.threshold_radius,
            cache_bins: self.cache_bins,
            cache_photons: self.cache_photons,
            pixel_table_rays: self.pixel_table_rays,
            clamp_weights: self.clamp_weights,
            roulette_depth: self.roulette_depth,
            pixel_jitter: self.pixel_jitter,
            noise_model: self.noise_model.name().into(),
            sampler: self.sampler.name().into(),
        }
        .serialize(s)
    }
}

impl<'de> Deserialize<'de> for RenderSettings {
    /// The mode gets the serialised `threshold_radius` ([`RenderSettings::select`]), the
    /// `optimal*` clamp comes from `clamp_weights` alone.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let r = Repr::deserialize(d)?;
        let mode = Mode::parse(&r.mode)
            .ok_or_else(|| D::Error::custom(format!("unknown mode '{}'", r.mode)))?;
        let noise_model = NoiseModel::parse(&r.noise_model)
            .ok_or_else(|| D::Error::custom(format!("unknown noise model '{}'", r.noise_model)))?;
        let sampler = Sampler::parse(&r.sampler)
            .ok_or_else(|| D::Error::custom(format!("unknown sampler '{}'", r.sampler)))?;
        let mut s = RenderSettings {
            width: r.width,
            height: r.height,
            passes: r.passes,
            photons: r.photons,
            spp: r.spp,
            radius: r.radius,
            radius_px: r.radius_px,
            seed: r.seed,
            mode: Mode::Path,
            threshold_radius: r.threshold_radius,
            cache_bins: r.cache_bins,
            cache_photons: r.cache_photons,
            pixel_table_rays: r.pixel_table_rays,
            clamp_weights: r.clamp_weights,
            roulette_depth: r.roulette_depth,
            pixel_jitter: r.pixel_jitter,
            noise_model,
            sampler,
        };
        s.select(mode);
        Ok(s)
    }
}
