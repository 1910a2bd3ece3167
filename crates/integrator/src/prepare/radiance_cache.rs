//! The radiance cache of method.md §5 that the model-based weights read (L_d and b at x₁),
//! built from its own photon stream.
use bdpm_cache::{CacheSettings, RadianceCache};
use bdpm_scene::Scene;

use super::{BuildContext, MemoryScale, Preparation};
use crate::error::RenderError;
use crate::memory::{ARRIVAL_RECORD_BYTES, Lifetime, Lower, MemoryItem};
use crate::setup::Setup;
use crate::stage::Stage;

/// Radiance-cache cells per largest scene extent: cells of ~9 cm in the 2.8 m Cornell box,
/// far larger than the merge radius, as method.md §5 asks.
const CACHE_CELLS_PER_EXTENT: f32 = 32.0;

/// The weights' radiance cache: `cache_photons` photons (N_F when not given), `cache_bins`
/// bins per cell side, on the render's seed.
pub(crate) struct RadianceCachePrep;

impl Preparation for RadianceCachePrep {
    type Product = RadianceCache;

    fn stage(&self, _: &Setup<'_>) -> Stage {
        Stage::RadianceCache
    }

    fn needed(&self, setup: &Setup<'_>) -> bool {
        setup.heuristic.is_some_and(|h| h.needs().radiance_cache)
    }

    fn memory(&self, setup: &Setup<'_>, scale: &MemoryScale) -> Vec<MemoryItem> {
        let s = &setup.settings;
        let photons = s.cache_photons.unwrap_or(s.photons);
        vec![build_item(
            "radiance cache build",
            photons,
            scale,
            Lower::CachePhotons,
        )]
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Option<RadianceCache>, RenderError> {
        let s = cx.settings();
        let photons = s.cache_photons.unwrap_or(s.photons);
        build(cx.setup.scene, s.seed, (photons, s.cache_bins), cx.stop)
            .map(Some)
            .ok_or(RenderError::Interrupted(Stage::RadianceCache))
    }

    fn report(&self, cache: &RadianceCache, setup: &Setup<'_>) -> Option<(u64, String)> {
        let s = &setup.settings;
        Some(report(cache, s.cache_photons.unwrap_or(s.photons), ""))
    }
}

/// A radiance cache of `photons` photons and `bins` bins per cell side on `seed`; `None` if
/// `stop()` stopped it (asked between chunks of photons).
pub(super) fn build(
    scene: &Scene,
    seed: u64,
    (photons, bins): (u64, u32),
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<RadianceCache> {
    RadianceCache::build_until(scene, &cache_settings(scene, seed, (photons, bins)), stop)
}

/// [`build`] of the caustic light alone: what reaches a surface from a light through mirrors
/// and glass only ([`bdpm_photon::PhotonArrival::caustic`]).
pub(super) fn build_caustics(
    scene: &Scene,
    seed: u64,
    (photons, bins): (u64, u32),
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<RadianceCache> {
    let settings = cache_settings(scene, seed, (photons, bins));
    RadianceCache::build_of_until(scene, &settings, &|a| a.caustic, stop)
}

/// The cache settings of `scene`: cells from its extent.
fn cache_settings(scene: &Scene, seed: u64, (photons, bins): (u64, u32)) -> CacheSettings {
    let (lo, hi) = scene.geometry().bounds();
    CacheSettings {
        bins,
        cell_size: (hi - lo).max_element() / CACHE_CELLS_PER_EXTENT,
        photons,
        seed,
    }
}

/// A cache's report: its bytes and one line (`purpose` prefixes it) of cells, bins, where b
/// comes from, the `photons` emitted, the arrivals and the share of cell sides hit.
pub(super) fn report(cache: &RadianceCache, photons: u64, purpose: &str) -> (u64, String) {
    let st = cache.stats();
    let detail = format!(
        "{purpose}{} cells x 2 sides, {} bin(s) per side, b {}, {photons} photons emitted, {} arrivals, {:.1}% of cell sides hit",
        st.cells,
        st.bins,
        if st.stores_b {
            "stored"
        } else {
            "derived (Lambert-only scene)"
        },
        st.arrivals,
        100.0 * st.filled_fraction
    );
    (st.bytes, detail)
}

/// The memory item of a cache build of `photons` photons, which holds its arrivals until it
/// sums them.
pub(super) fn build_item(
    name: &'static str,
    photons: u64,
    scale: &MemoryScale,
    lower: Lower,
) -> MemoryItem {
    MemoryItem {
        name,
        bytes: (photons as f64 * scale.arrivals_per_emitted * ARRIVAL_RECORD_BYTES) as u64,
        lifetime: Lifetime::Preparation,
        lower,
    }
}
