//! The parts of a memory estimate ([`MemoryItem`]: what it is, its bytes, how long it lives,
//! what scales it), and the scene's own; `crate::estimate` sums a render's
//! ([`crate::estimate_memory`]), so that the driver can refuse a render that would run out of
//! memory after minutes of work.

pub use bdpm_core::human_bytes;
use bdpm_scene::Scene;
use bdpm_settings::Setting;

/// Photons traced by the pilot of [`crate::estimate_memory`] that measures a scene's photons
/// stored per emitted photon.
pub const PILOT_PHOTONS: u64 = 4096;
/// Bytes per record while the radiance cache or a light pass collects arrivals: a 12–16 B
/// record in thread-local parts and their merged copy.
pub(crate) const ARRIVAL_RECORD_BYTES: f64 = 32.0;
/// Name of the fixed part of the estimate.
pub(crate) const BASE_NAME: &str = "program";
/// Names of the scene's items, which the scene holds already when the estimate is made.
const SCENE_ITEMS: [&str; 3] = ["geometry", "BVH", "textures"];
/// Name of the item for the scene's load, which peaks before the render's own allocations.
const LOADING_NAME: &str = "BVH build while loading, beyond the render's own";

/// How long an item of a render's estimate lives, which decides how the items of several
/// renderers of one scene add up (a caller that holds several renderers sums them by it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lifetime {
    /// The program and the scene: one copy however many renderers there are.
    Shared,
    /// Held by a renderer, or by the film and statistics of its image, for as long as it
    /// lives: one copy per renderer held.
    Held,
    /// Allocated while a renderer is prepared and freed before its first pass (a cache
    /// build's arrivals, a pilot's images).
    Preparation,
    /// Allocated while a pass renders and freed after it (the photon map).
    Pass,
}

/// What scales an item, i.e. what to lower (or leave out) to shrink it. Typed, so that each
/// caller names it in its own words (a command-line flag, a scene file's key).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Lower {
    /// A render setting, e.g. [`Setting::Photons`] or [`Setting::Resolution`].
    Setting(Setting),
    /// The first setting, or else leave out the second, an on/off setting that adds the item
    /// (the resolution, or `adaptive_radius`).
    SettingOrOff(Setting, Setting),
    /// The radiance cache's photons: [`Setting::CachePhotons`], or [`Setting::Photons`],
    /// which it follows when not given.
    CachePhotons,
    /// The resolution, or leave out the technique layers
    /// ([`crate::Renderer::with_technique_layers`]).
    ResolutionOrTechniques,
    /// The photons of the noise model's own radiance cache
    /// ([`crate::Renderer::with_model_cache`]).
    ModelCachePhotons,
    /// The scene's triangle count.
    SceneTriangles,
    /// The scene's texture sizes (texels).
    SceneTextures,
    /// In the words of the caller that adds the item (for what it holds itself).
    Other(&'static str),
}

/// One part of the estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryItem {
    /// What it is, e.g. `"photon map per pass"`.
    pub name: &'static str,
    /// Estimated peak bytes.
    pub bytes: u64,
    /// How long it lives.
    pub lifetime: Lifetime,
    /// What scales it, for a message that says what to lower.
    pub lower: Lower,
}

/// The estimated peak memory of a render: the sum of its items (each at its own peak, which
/// over-estimates a little because not all peaks coincide).
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryEstimate {
    /// The parts, largest first.
    pub items: Vec<MemoryItem>,
    /// Photons stored per photon emitted, as measured by the pilot.
    pub stored_per_emitted: f64,
}

impl MemoryEstimate {
    /// The estimated peak, bytes.
    pub fn total(&self) -> u64 {
        self.items.iter().map(|i| i.bytes).sum()
    }

    /// The largest item that a render setting or the scene scales (not the fixed program
    /// part): the one to name when the estimate is too large.
    pub fn scalable_largest(&self) -> &MemoryItem {
        self.items
            .iter()
            .find(|i| i.name != BASE_NAME)
            .unwrap_or(&self.items[0])
    }
}

/// The items of `scene` itself: its per-triangle data, its BVH and its decoded textures
/// ([`Scene::memory`]), bytes held. A caller that sizes work on a loaded scene other than a
/// render (`bdpm study`, `bench`, `predict`) adds these to its own items;
/// [`crate::estimate_memory`] does, with [`loading_item`] for the load's peak.
pub fn scene_items(scene: &Scene) -> Vec<MemoryItem> {
    let m = scene.memory();
    let item = |name, bytes, lower| MemoryItem {
        name,
        bytes,
        lifetime: Lifetime::Shared,
        lower,
    };
    vec![
        item(SCENE_ITEMS[0], m.triangles, Lower::SceneTriangles),
        item(SCENE_ITEMS[1], m.bvh, Lower::SceneTriangles),
        item(SCENE_ITEMS[2], m.textures, Lower::SceneTextures),
    ]
}

/// The part of the scene's load that the render's items do not cover: loading peaks while
/// the BVH is built (its temporaries, [`bdpm_scene::SceneMemory::bvh_build`], beside the kept
/// scene), before any of the render's allocations, so the estimate's peak is the kept scene
/// plus the larger of the two; this item is the build's excess over `render` bytes of the
/// other items (0 when the render needs more).
pub fn loading_item(scene: &Scene, render: u64) -> MemoryItem {
    MemoryItem {
        name: LOADING_NAME,
        bytes: scene.memory().bvh_build.saturating_sub(render),
        lifetime: Lifetime::Shared,
        lower: Lower::SceneTriangles,
    }
}
