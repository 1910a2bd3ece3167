//! The memory a render will need, estimated before anything large is allocated, so that the
//! driver can refuse a render that would run out of memory after minutes of work.
//!
//! Per-pixel and per-photon costs were measured as peak resident memory of `bdpm render` on
//! the Cornell box (docs/robustness.md, "Memory"): 171 B per pixel for the film, the pass
//! estimate and the output files being encoded (1024² and 2048², path mode), and 1.6–1.9 times
//! the finished photon map's bytes at the peak of its build (thread-local parts and the merged
//! copy, then the grid's sort arrays; `--stage-memory`, 1 and 4 million photons, docs/performance.md). The photons stored per emitted
//! photon and the bytes per stored photon depend on the scene, so a pilot of
//! [`PILOT_PHOTONS`] photons is traced to measure them.

pub use bdpm_core::human_bytes;
use bdpm_geometry::Domain;
use bdpm_mis::NoiseModel;
use bdpm_photon::{PhotonMap, TraceOptions};
use bdpm_scene::Scene;

use crate::bdpm::{Techniques, scene_default_radius};
use crate::connect::Splat;
use crate::correction::CANDIDATES;
use crate::table::PixelWeights;
use bdpm_settings::{Mode, RenderSettings};

/// Photons traced by the pilot that measures a scene's photons stored per emitted photon.
pub const PILOT_PHOTONS: u64 = 4096;
/// Peak bytes per pixel of the film, luminance film, pass estimate and output encoding
/// (measured: 171 B at 1024² and 2048²), rounded up.
const BYTES_PER_PIXEL: u64 = 180;
/// Extra peak bytes per pixel with technique layers: five RGB f64 layers per pass and their
/// sums (240 B), and their f32 EXR channels and means (180 B).
const TECHNIQUE_BYTES_PER_PIXEL: u64 = 2 * size_of::<Techniques>() as u64 + 180;
/// Peak of a photon map's build over its finished size (measured 1.61 at 10⁶ and 1.88 at
/// 4·10⁶ photons on the Lambert Cornell box), rounded up.
const PHOTON_MAP_PEAK_FACTOR: f64 = 2.0;
/// Bytes per record while the radiance cache or a light pass collects arrivals: a 12–16 B
/// record in thread-local parts and their merged copy.
const ARRIVAL_RECORD_BYTES: f64 = 32.0;
/// Name of the fixed part of the estimate.
const BASE_NAME: &str = "program";
/// Program, scene-independent buffers and thread stacks (measured ~9 MB at 8×8 pixels).
const BASE_BYTES: u64 = 16 << 20;
/// Names of the scene's items, which the scene holds already when the estimate is made.
const SCENE_ITEMS: [&str; 3] = ["geometry", "BVH", "textures"];
/// Name of the item for the scene's load, which peaks before the render's own allocations.
const LOADING_NAME: &str = "BVH build while loading, beyond the render's own";

/// One part of the estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryItem {
    /// What it is, e.g. `"photon map per pass"`.
    pub name: &'static str,
    /// Estimated peak bytes.
    pub bytes: u64,
    /// The setting that scales it, for a message that says what to lower, e.g.
    /// `"--photons"`.
    pub lower: &'static str,
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
/// render (`bdpm study`, `bench`, `predict`) adds these to its own items; [`estimate_memory`]
/// does, with [`loading_item`] for the load's peak.
pub fn scene_items(scene: &Scene) -> Vec<MemoryItem> {
    let m = scene.memory();
    vec![
        MemoryItem {
            name: SCENE_ITEMS[0],
            bytes: m.triangles,
            lower: "the scene's triangle count",
        },
        MemoryItem {
            name: SCENE_ITEMS[1],
            bytes: m.bvh,
            lower: "the scene's triangle count",
        },
        MemoryItem {
            name: SCENE_ITEMS[2],
            bytes: m.textures,
            lower: "the scene's texture sizes (texels)",
        },
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
        lower: "the scene's triangle count",
    }
}

/// Estimates the peak memory of rendering `scene` with `settings` (with technique layers
/// when `techniques`): the program, the scene's own items ([`scene_items`], [`loading_item`])
/// and the render's. Traces a pilot of [`PILOT_PHOTONS`] photons for BDPM and light modes;
/// allocates nothing in proportion to the resolution or N_F.
pub fn estimate_memory(
    scene: &Scene,
    settings: &RenderSettings,
    techniques: bool,
) -> MemoryEstimate {
    let s = settings;
    let pixels = s.width as u64 * s.height as u64;
    // An unusable radius fails in `Renderer::new`; the estimate goes on with the default.
    let radius = crate::render::resolve_radius(scene, s, scene.pixel_footprint())
        .unwrap_or_else(|_| scene_default_radius(scene));
    let mut items = vec![
        MemoryItem {
            name: BASE_NAME,
            bytes: BASE_BYTES,
            lower: "the scene's triangle count",
        },
        MemoryItem {
            name: "film and output images",
            bytes: pixels * BYTES_PER_PIXEL,
            lower: "--resolution",
        },
    ];
    if techniques {
        items.push(MemoryItem {
            name: "technique layers",
            bytes: pixels * TECHNIQUE_BYTES_PER_PIXEL,
            lower: "--resolution (or leave out --techniques)",
        });
    }
    let mut stored_per_emitted = 0.0;
    let heuristic = match s.mode {
        Mode::Path => None,
        Mode::Light | Mode::Bdpm(_) => {
            let pilot = PhotonMap::trace(
                scene,
                &TraceOptions {
                    photons: PILOT_PHOTONS,
                    seed: s.seed,
                    domain: Domain::Photon,
                    pass: 0,
                    light_visibility: false,
                    max_depth: 1024,
                },
                radius,
            );
            let stored = pilot.photons().len() as f64;
            stored_per_emitted = stored / PILOT_PHOTONS as f64;
            // Arrivals include the first hit from the light, which is not stored.
            let arrivals_per_emitted = stored_per_emitted + 1.0;
            let bytes_per_stored = pilot.memory_bytes() as f64 / stored.max(1.0);
            match s.mode {
                Mode::Light => items.push(MemoryItem {
                    name: "light-path splats per pass",
                    bytes: (s.photons as f64 * arrivals_per_emitted * ARRIVAL_RECORD_BYTES) as u64,
                    lower: "--photons",
                }),
                _ => items.push(MemoryItem {
                    name: "photon map per pass",
                    bytes: (s.photons as f64
                        * stored_per_emitted
                        * bytes_per_stored
                        * PHOTON_MAP_PEAK_FACTOR) as u64,
                    lower: "--photons",
                }),
            }
            if s.light_traced() {
                // Every arrival of depth ≥ 1 that the camera sees is a splat, held until the
                // pass adds them in photon order; a growing list can hold twice its length.
                items.push(MemoryItem {
                    name: "light-tracing splats per pass",
                    bytes: (s.photons as f64 * stored_per_emitted * (2 * size_of::<Splat>()) as f64)
                        as u64,
                    lower: "--photons",
                });
            }
            if let Some(h) = s.heuristic()
                && h.needs().radiance_cache
            {
                let photons = s.cache_photons.unwrap_or(s.photons) as f64;
                items.push(MemoryItem {
                    name: "radiance cache build",
                    bytes: (photons * arrivals_per_emitted * ARRIVAL_RECORD_BYTES) as u64,
                    lower: "render.cache_photons (or --photons)",
                });
            }
            s.heuristic()
        }
    };
    if let Some(h) = heuristic {
        items.extend(pixel_items(s, h, pixels));
    }
    add_scene_items(scene, &mut items);
    MemoryEstimate {
        items,
        stored_per_emitted,
    }
}

/// Adds the scene's items and its load's to the program's and the render's `items` (the
/// program first), drops empty ones and sorts them, largest first.
fn add_scene_items(scene: &Scene, items: &mut Vec<MemoryItem>) {
    let render: u64 = items.iter().skip(1).map(|i| i.bytes).sum();
    items.push(loading_item(scene, render));
    items.extend(scene_items(scene));
    items.retain(|i| i.bytes > 0 || i.name == BASE_NAME);
    items.sort_by_key(|i| std::cmp::Reverse(i.bytes));
}

/// The per-pixel items of a mode with weights `h`: its weight table, adaptive-radius pilot
/// and balance-correction pilot, as it needs them.
fn pixel_items(s: &RenderSettings, h: bdpm_mis::Heuristic, pixels: u64) -> Vec<MemoryItem> {
    let mut items = Vec::new();
    let footprint = s.noise_model == NoiseModel::Footprint && s.pixel_jitter;
    let needs = h.needs();
    if needs.pixel_table || (footprint && needs.effective_samples) {
        items.push(MemoryItem {
            name: "per-pixel weight table",
            bytes: pixels * size_of::<PixelWeights>() as u64,
            lower: "--resolution",
        });
    }
    if s.adaptive_radius {
        // At the pilot's peak: its technique sums and one pass's layers and estimates;
        // then the table at each pixel's radius is built beside the one at r.
        items.push(MemoryItem {
            name: "adaptive-radius pilot",
            bytes: pixels
                * (2 * size_of::<Techniques>() + size_of::<[f64; 3]>() + size_of::<PixelWeights>())
                    as u64,
            lower: "--resolution (or leave out --adaptive-radius)",
        });
    }
    if needs.balance_correction {
        // Per pixel and candidate, at the pilot's peak: the pass's per-row sums, their
        // concatenation, and the second moments.
        items.push(MemoryItem {
            name: "balance-correction pilot",
            bytes: pixels * (3 * CANDIDATES.len() * size_of::<f64>()) as u64,
            lower: "--resolution",
        });
    }
    items
}

/// The build of the noise model's radiance cache of `photons` photons
/// ([`crate::Renderer::with_model_cache`]), which holds its arrivals until it sums them: an item
/// for `estimate` (of the same scene and settings, whose pilot measured the photons stored per
/// emitted photon) of `bdpm predict`.
pub fn model_cache_item(estimate: &MemoryEstimate, photons: u64) -> MemoryItem {
    // Arrivals include the first hit from the light, which is not stored.
    let arrivals_per_emitted = estimate.stored_per_emitted + 1.0;
    MemoryItem {
        name: "noise model's radiance cache build",
        bytes: (photons as f64 * arrivals_per_emitted * ARRIVAL_RECORD_BYTES) as u64,
        lower: "--model-cache-photons",
    }
}
