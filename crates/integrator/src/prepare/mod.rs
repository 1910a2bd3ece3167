//! The renderer's preparations: everything built once, before the first pass, because the
//! settings and the scene need it (method.md §7: nothing a mode does not need). Each is one
//! type in its own file that implements `Preparation`: when it is needed, what it costs in
//! memory, what it builds and how it reports itself. `PLAN` lists them in the order they
//! run; the renderer runs the plan (`Renderer::new`), keeps their products by type
//! (crate::products) and reports one stage each, and the memory estimate
//! (crate::estimate) sums the items of the plan's needed entries.
use std::any::Any;

use bdpm_mis::Heuristic;
use bdpm_settings::RenderSettings;

use crate::error::RenderError;
use crate::memory::MemoryItem;
use crate::mix::Mix;
use crate::pass::PassContext;
use crate::products::Products;
use crate::setup::Setup;
use crate::stage::{Stage, StageProbe};

mod balance_correction;
mod direct_samples;
mod model_cache;
mod one_bounce_samples;
mod pixel_table;
mod radiance_cache;
mod radius_map;

pub(crate) use model_cache::ModelCache;
pub use model_cache::{
    MODEL_CACHE_BINS, MODEL_CACHE_PHOTONS, model_cache_item, model_cache_settings,
};
pub(crate) use pixel_table::PixelTablePrep;

/// The preparations in the order they run (a later one may read an earlier one's product):
/// the radiance cache, the pixel table at r, `corrected-balance`'s pilot, `adaptive_radius`'s
/// pilot and the pixel table again at each pixel's radius, the direct-light samples, the x₁ of
/// the one-bounce paths at a glossy x₀, the noise
/// model's own cache (only once asked for, `Renderer::with_model_cache`).
pub(crate) static PLAN: [&dyn Planned; 8] = [
    &radiance_cache::RadianceCachePrep,
    &PixelTablePrep::AT_R,
    &balance_correction::BalanceCorrectionPrep,
    &radius_map::RadiusMapPrep,
    &PixelTablePrep::AT_PIXEL_RADII,
    &direct_samples::DirectSamplesPrep,
    &one_bounce_samples::OneBounceSamplesPrep,
    &model_cache::ModelCachePrep,
];

/// What the memory estimate knows before anything is built, for a preparation's items.
pub(crate) struct MemoryScale {
    /// Pixels of the image.
    pub(crate) pixels: u64,
    /// Photon arrivals per photon emitted (stored photons and first hits), as the estimate's
    /// pilot measured them (0 for `path`, which traces no photons).
    pub(crate) arrivals_per_emitted: f64,
}

/// What a preparation's build reads: the setup, the products of the preparations before it,
/// when to give up, and the probe of the stages of any pass it renders.
pub(crate) struct BuildContext<'c> {
    pub(crate) setup: &'c Setup<'c>,
    pub(crate) products: &'c Products,
    /// Asked between chunks of the work (a chunk of photons, a pixel of a table, a row of a
    /// pilot's camera samples): true gives up with [`RenderError::Interrupted`].
    pub(crate) stop: &'c (dyn Fn() -> bool + Sync),
    pub(crate) probe: Option<&'c dyn StageProbe>,
}

impl BuildContext<'_> {
    /// The settings in force.
    pub(crate) fn settings(&self) -> &RenderSettings {
        &self.setup.settings
    }

    /// The mix of `heuristic` with the products built so far (the cache, the radius map).
    pub(crate) fn mix(&self, heuristic: Heuristic) -> Mix<'_> {
        self.setup.mix(heuristic, self.products)
    }

    /// A pilot pass's context: the products built so far.
    pub(crate) fn pass_context(&self) -> PassContext<'_> {
        PassContext {
            setup: self.setup,
            products: self.products,
            probe: self.probe,
        }
    }
}

/// One pre-pass of a render, typed by what it builds. Implemented once per file of this
/// module; [`Planned`] is its face in the [`PLAN`].
pub(crate) trait Preparation: Sync {
    /// What it builds, kept in the renderer's products.
    type Product: Any + Send + Sync;

    /// The stage it runs and reports as.
    fn stage(&self, setup: &Setup<'_>) -> Stage;

    /// Whether the settings and the scene need it.
    fn needed(&self, setup: &Setup<'_>) -> bool;

    /// Its items of the memory estimate, when it is needed (none by default).
    fn memory(&self, _setup: &Setup<'_>, _scale: &MemoryScale) -> Vec<MemoryItem> {
        Vec::new()
    }

    /// Builds it; `Ok(None)` when there is nothing to keep (e.g. every pixel takes one
    /// direct-light sample). Gives up with [`RenderError::Interrupted`] when `cx.stop` says so.
    fn build(&self, cx: &BuildContext<'_>) -> Result<Option<Self::Product>, RenderError>;

    /// Its report: the bytes it holds and one line of facts, or `None` for no stage line.
    fn report(&self, product: &Self::Product, setup: &Setup<'_>) -> Option<(u64, String)>;
}

/// A built preparation: its product, and its report (bytes, one line) if it makes one.
pub(crate) struct Built {
    pub(crate) product: Box<dyn Any + Send + Sync>,
    pub(crate) report: Option<(u64, String)>,
}

/// A [`Preparation`] with its product's type erased, as the [`PLAN`] lists it.
pub(crate) trait Planned: Sync {
    /// [`Preparation::stage`].
    fn stage(&self, setup: &Setup<'_>) -> Stage;
    /// [`Preparation::needed`].
    fn needed(&self, setup: &Setup<'_>) -> bool;
    /// [`Preparation::memory`].
    fn memory(&self, setup: &Setup<'_>, scale: &MemoryScale) -> Vec<MemoryItem>;
    /// [`Preparation::build`] and [`Preparation::report`].
    fn run(&self, cx: &BuildContext<'_>) -> Result<Option<Built>, RenderError>;
}

impl<P: Preparation> Planned for P {
    fn stage(&self, setup: &Setup<'_>) -> Stage {
        Preparation::stage(self, setup)
    }

    fn needed(&self, setup: &Setup<'_>) -> bool {
        Preparation::needed(self, setup)
    }

    fn memory(&self, setup: &Setup<'_>, scale: &MemoryScale) -> Vec<MemoryItem> {
        Preparation::memory(self, setup, scale)
    }

    fn run(&self, cx: &BuildContext<'_>) -> Result<Option<Built>, RenderError> {
        Ok(self.build(cx)?.map(|product| Built {
            report: self.report(&product, cx.setup),
            product: Box::new(product),
        }))
    }
}

/// `Err(Interrupted(stage))` when `stop()` says so.
pub(crate) fn unless_stopped(
    stop: &(dyn Fn() -> bool + Sync),
    stage: Stage,
) -> Result<(), RenderError> {
    if stop() {
        Err(RenderError::Interrupted(stage))
    } else {
        Ok(())
    }
}

/// A pilot's settings: the render's, on the pilot's own seed.
pub(crate) fn pilot_settings(settings: &RenderSettings, seed: u64) -> RenderSettings {
    RenderSettings {
        seed,
        ..settings.clone()
    }
}
