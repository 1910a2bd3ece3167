//! The memory a render will need, estimated before anything large is allocated, so that the
//! driver can refuse a render that would run out of memory after minutes of work.
//!
//! Per-pixel and per-photon costs were measured as peak resident memory of `bdpm render` on
//! the Cornell box (docs/robustness.md, "Memory"): 171 B per pixel for the film, the pass
//! estimate and the output files being encoded (1024² and 2048², path mode), and 1.6–1.9 times
//! the finished photon map's bytes at the peak of its build (thread-local parts and the merged
//! copy, then the grid's sort arrays; the driver's per-stage memory probe, 1 and 4 million
//! photons, docs/performance.md). The photons stored per emitted photon and the bytes per
//! stored photon depend on the scene, so a pilot of [`PILOT_PHOTONS`] photons is traced to
//! measure them. The preparations' items are their own (crate::prepare), summed over the
//! plan's needed entries.
use bdpm_geometry::Domain;
use bdpm_photon::{MAX_DEPTH, PhotonMap, TraceOptions};
use bdpm_scene::Scene;
use bdpm_settings::{Mode, RenderSettings, Setting};

use crate::connect::Splat;
use crate::estimates::Techniques;
use crate::memory::{
    ARRIVAL_RECORD_BYTES, BASE_NAME, Lifetime, Lower, MemoryEstimate, MemoryItem, PILOT_PHOTONS,
    loading_item, scene_items,
};
use crate::prepare::{MemoryScale, PLAN};
use crate::setup::Setup;

/// Peak bytes per pixel of the film, luminance film, pass estimate and output encoding
/// (measured: 171 B at 1024² and 2048²), rounded up.
const BYTES_PER_PIXEL: u64 = 180;
/// Extra peak bytes per pixel with technique layers: five RGB f64 layers per pass and their
/// sums (240 B), and their f32 EXR channels and means (180 B).
const TECHNIQUE_BYTES_PER_PIXEL: u64 = 2 * size_of::<Techniques>() as u64 + 180;
/// Peak of a photon map's build over its finished size (measured 1.61 at 10⁶ and 1.88 at
/// 4·10⁶ photons on the Lambert Cornell box), rounded up.
const PHOTON_MAP_PEAK_FACTOR: f64 = 2.0;
/// Program, scene-independent buffers and thread stacks (measured ~9 MB at 8×8 pixels).
const BASE_BYTES: u64 = 16 << 20;

/// Estimates the peak memory of rendering `scene` with `settings` (with technique layers
/// when `techniques`): the program, the scene's own items ([`scene_items`], [`loading_item`]),
/// the passes' and the preparations' (each needed entry of the plan's). Traces a pilot of
/// [`PILOT_PHOTONS`] photons for BDPM and light modes; allocates nothing in proportion to the
/// resolution or N_F.
pub fn estimate_memory(
    scene: &Scene,
    settings: &RenderSettings,
    techniques: bool,
) -> MemoryEstimate {
    let setup = Setup::unchecked(scene, settings);
    let s = &setup.settings;
    let pixels = s.width as u64 * s.height as u64;
    let mut items = vec![
        MemoryItem {
            name: BASE_NAME,
            bytes: BASE_BYTES,
            lifetime: Lifetime::Shared,
            lower: Lower::SceneTriangles,
        },
        MemoryItem {
            name: "film and output images",
            bytes: pixels * BYTES_PER_PIXEL,
            lifetime: Lifetime::Held,
            lower: Lower::Setting(Setting::Resolution),
        },
    ];
    if techniques {
        items.push(MemoryItem {
            name: "technique layers",
            bytes: pixels * TECHNIQUE_BYTES_PER_PIXEL,
            lifetime: Lifetime::Held,
            lower: Lower::ResolutionOrTechniques,
        });
    }
    let stored_per_emitted = match s.mode {
        Mode::Path => 0.0,
        _ => pass_items(&setup, &mut items),
    };
    let scale = MemoryScale {
        pixels,
        // Arrivals include the first hit from the light, which is not stored.
        arrivals_per_emitted: stored_per_emitted + 1.0,
    };
    for entry in PLAN.iter().filter(|e| e.needed(&setup)) {
        items.extend(entry.memory(&setup, &scale));
    }
    add_scene_items(scene, &mut items);
    MemoryEstimate {
        items,
        stored_per_emitted,
    }
}

/// The items of a pass that traces photons (`light` and the BDPM modes): its photon map or
/// light-path splats, and light tracing's splats. Returns the photons stored per emitted
/// photon that a pilot of [`PILOT_PHOTONS`] photons measures.
fn pass_items(setup: &Setup<'_>, items: &mut Vec<MemoryItem>) -> f64 {
    let s = &setup.settings;
    let options = TraceOptions {
        photons: PILOT_PHOTONS,
        seed: s.seed,
        domain: Domain::Photon,
        pass: 0,
        light_visibility: false,
        max_depth: MAX_DEPTH,
    };
    let pilot = PhotonMap::trace(setup.scene, &options, setup.radius);
    let stored = pilot.photons().len() as f64;
    let stored_per_emitted = stored / PILOT_PHOTONS as f64;
    // Arrivals include the first hit from the light, which is not stored.
    let arrivals_per_emitted = stored_per_emitted + 1.0;
    let bytes_per_stored = pilot.memory_bytes() as f64 / stored.max(1.0);
    let per_pass = |name, bytes: f64| MemoryItem {
        name,
        bytes: bytes as u64,
        lifetime: Lifetime::Pass,
        lower: Lower::Setting(Setting::Photons),
    };
    let photons = s.photons as f64;
    items.push(match s.mode {
        Mode::Light => per_pass(
            "light-path splats per pass",
            photons * arrivals_per_emitted * ARRIVAL_RECORD_BYTES,
        ),
        _ => per_pass(
            "photon map per pass",
            photons * stored_per_emitted * bytes_per_stored * PHOTON_MAP_PEAK_FACTOR,
        ),
    });
    if s.light_traced() {
        // Every arrival of depth ≥ 1 that the camera sees is a splat, held until the pass
        // adds them in photon order; a growing list can hold twice its length.
        items.push(per_pass(
            "light-tracing splats per pass",
            photons * stored_per_emitted * (2 * size_of::<Splat>()) as f64,
        ));
    }
    stored_per_emitted
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
