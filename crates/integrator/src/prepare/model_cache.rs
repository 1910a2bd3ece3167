//! The noise model's own radiance cache (`Renderer::with_model_cache`): the model reads L_d
//! and b at x₁ as the values of a BDD=1 sample and of its photon noise, so it wants a finer
//! cache than the weights (docs/results.md, "The noise model's own cache"). Built only when a
//! caller asks for it, after the render's own preparations.
use bdpm_cache::RadianceCache;
use bdpm_settings::RenderSettings;

use super::radiance_cache::{build, build_caustics, build_item, report};
use super::{BuildContext, MemoryScale, Preparation};
use crate::error::RenderError;
use crate::memory::{Lower, MemoryEstimate, MemoryItem};
use crate::setup::Setup;
use crate::stage::Stage;

/// Photons of the noise model's radiance cache ([`crate::Renderer::with_model_inputs`]) at
/// least. The model reads L_d and b at x₁ as the values of a BDD=1 sample and of its photon
/// noise: the cache's noise from cell to cell reads as variation over directions (T1), and a
/// coarse cache's b as the photon noise (T2). A render's cache is chosen for its weights per
/// second (the glossy file's 2.5·10⁵ photons in one bin); the model's is for the truth
/// (docs/results.md, "The noise model's own cache").
pub const MODEL_CACHE_PHOTONS: u64 = 8_000_000;

/// Bins per cell side of the noise model's radiance cache at least (method.md's M ≈ 100;
/// a Lambert-only scene's cache keeps one, which is exact there).
pub const MODEL_CACHE_BINS: u32 = 100;

/// `settings` with the weights' radiance cache made the noise model's
/// ([`crate::Renderer::with_model_cache`] of `photons`): at least `photons` photons and
/// [`MODEL_CACHE_BINS`] bins. A renderer with these settings weighs with the very cache the
/// model reads: the floor of the noise model's headroom query, the minimiser of the model's
/// functional, is one.
pub fn model_cache_settings(settings: &RenderSettings, photons: u64) -> RenderSettings {
    let mut s = settings.clone();
    s.cache_photons = Some(
        settings
            .cache_photons
            .unwrap_or(settings.photons)
            .max(photons),
    );
    s.cache_bins = settings.cache_bins.max(MODEL_CACHE_BINS);
    s
}

/// The build of the noise model's radiance cache of `photons` photons
/// ([`crate::Renderer::with_model_cache`]), which holds its arrivals until it sums them: an
/// item for `estimate` (of the same scene and settings, whose pilot measured the photons
/// stored per emitted photon) of a caller that asks for the model.
pub fn model_cache_item(estimate: &MemoryEstimate, photons: u64) -> MemoryItem {
    let scale = MemoryScale {
        pixels: 0,
        // Arrivals include the first hit from the light, which is not stored.
        arrivals_per_emitted: estimate.stored_per_emitted + 1.0,
    };
    item(photons, &scale)
}

fn item(photons: u64, scale: &MemoryScale) -> MemoryItem {
    build_item(
        "noise model's radiance cache build",
        photons,
        scale,
        Lower::ModelCachePhotons,
    )
}

/// The radiance cache the noise model reads: its own, or none where it reads the weights'
/// (as fine as its own would be).
pub(crate) struct ModelCache {
    own: Option<RadianceCache>,
    /// In a scene with mirrors or glass, the caustic light alone (light → delta vertices →
    /// here): its b at x₀ is the photon noise of the merges at x₀ that no direction sampled
    /// at x₀ finds (docs/method-notes.md, "Mirrors and glass").
    caustic: Option<RadianceCache>,
}

impl ModelCache {
    /// The cache the model reads, given the weights' `weights` cache (if any).
    pub(crate) fn cache<'c>(
        &'c self,
        weights: Option<&'c RadianceCache>,
    ) -> Option<&'c RadianceCache> {
        self.own.as_ref().or(weights)
    }

    /// The caustic light's cache; `None` in a scene without mirrors or glass.
    pub(crate) fn caustic(&self) -> Option<&RadianceCache> {
        self.caustic.as_ref()
    }
}

/// The noise model's cache of [`model_cache_settings`] for the photons asked for.
pub(crate) struct ModelCachePrep;

impl Preparation for ModelCachePrep {
    type Product = ModelCache;

    fn stage(&self, _: &Setup<'_>) -> Stage {
        Stage::RadianceCache
    }

    fn needed(&self, setup: &Setup<'_>) -> bool {
        setup.model_cache_photons.is_some()
    }

    fn memory(&self, setup: &Setup<'_>, scale: &MemoryScale) -> Vec<MemoryItem> {
        setup
            .model_cache_photons
            .map(|photons| item(photons, scale))
            .into_iter()
            .collect()
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Option<ModelCache>, RenderError> {
        let s = cx.settings();
        let Some(photons) = cx.setup.model_cache_photons else {
            return Ok(None);
        };
        let model = model_cache_settings(s, photons);
        let photons = model.cache_photons.unwrap_or(model.photons);
        let weights = cx.products.get::<RadianceCache>();
        let as_fine = weights.is_some_and(|c| {
            s.cache_photons.unwrap_or(s.photons) == photons
                && (s.cache_bins == model.cache_bins || !c.stats().stores_b)
        });
        let interrupted = RenderError::Interrupted(Stage::RadianceCache);
        let scene = cx.setup.scene;
        let caustic = match scene.has_delta() {
            true => Some(
                build_caustics(scene, s.seed, (photons, model.cache_bins), cx.stop)
                    .ok_or(interrupted.clone())?,
            ),
            false => None,
        };
        if as_fine {
            return Ok(Some(ModelCache { own: None, caustic }));
        }
        let own = build(scene, s.seed, (photons, model.cache_bins), cx.stop).ok_or(interrupted)?;
        Ok(Some(ModelCache {
            own: Some(own),
            caustic,
        }))
    }

    fn report(&self, cache: &ModelCache, setup: &Setup<'_>) -> Option<(u64, String)> {
        let model = model_cache_settings(&setup.settings, setup.model_cache_photons?);
        let photons = model.cache_photons.unwrap_or(model.photons);
        Some(report(cache.own.as_ref()?, photons, "noise model's: "))
    }
}
