//! The memory gates of the commands: the limit a command compares its estimate with
//! (`--max-memory`, else the memory available), how the estimates of renderers add up when a
//! command prepares several and holds them together (`study`, `predict --headroom`) or
//! prepares one and renders no pass (`merge`, `weights`), and the parts a refusal names.
//!
//! The estimate of one render is [`bdpm_integrator::estimate_memory`]'s; each of its items
//! says how long it lives ([`Lifetime`]), which decides how they add up here, and what scales
//! it ([`bdpm_integrator::memory::Lower`]), which [`lower`] names as the command line does.

pub use bdpm_integrator::memory::Lifetime;
use bdpm_integrator::memory::Lower;
use bdpm_integrator::{MemoryEstimate, MemoryItem, RenderSettings, Setting, human_bytes};

use crate::system::available_memory;

/// What to lower to shrink `item`, as the command line names it: a render setting by its
/// flag (`--photons`), an on/off one as a flag to leave out, the scene's parts in words.
pub fn lower(item: &MemoryItem) -> String {
    let flag = crate::flags::flag_of;
    match item.lower {
        Lower::Setting(s) => flag(s).to_string(),
        Lower::SettingOrOff(s, off) => format!("{} (or leave out {})", flag(s), flag(off)),
        Lower::CachePhotons => format!(
            "{} (or {})",
            flag(Setting::CachePhotons),
            flag(Setting::Photons)
        ),
        Lower::ResolutionOrTechniques => {
            format!("{} (or leave out --techniques)", flag(Setting::Resolution))
        }
        Lower::ModelCachePhotons => "--model-cache-photons".to_string(),
        Lower::SceneTriangles => "the scene's triangle count".to_string(),
        Lower::SceneTextures => "the scene's texture sizes (texels)".to_string(),
        Lower::Other(text) => text.to_string(),
        _ => "the render's settings".to_string(),
    }
}

/// The bytes of `e`'s items that live only while a renderer is prepared or a pass renders.
fn transient_bytes(e: &MemoryEstimate) -> u64 {
    e.items
        .iter()
        .filter(|i| matches!(i.lifetime, Lifetime::Preparation | Lifetime::Pass))
        .map(|i| i.bytes)
        .sum()
}

/// The peak of renderers of one scene prepared one after another, then held together while
/// they render their passes one at a time (the estimates `entries`, one per renderer): the
/// shared items once, the held items of every renderer, and the preparation and pass items
/// of the renderer with the most of them (one preparation or pass runs at a time). Held
/// items of the same name are summed into one.
pub fn held_together(entries: &[MemoryEstimate]) -> MemoryEstimate {
    let mut items: Vec<MemoryItem> = Vec::new();
    for e in entries {
        for item in &e.items {
            let kind = item.lifetime;
            if !matches!(kind, Lifetime::Shared | Lifetime::Held) {
                continue;
            }
            match items.iter_mut().find(|i| i.name == item.name) {
                Some(i) if kind == Lifetime::Held => i.bytes += item.bytes,
                Some(i) => i.bytes = i.bytes.max(item.bytes),
                None => items.push(item.clone()),
            }
        }
    }
    if let Some(e) = entries.iter().max_by_key(|e| transient_bytes(e)) {
        items.extend(
            e.items
                .iter()
                .filter(|i| matches!(i.lifetime, Lifetime::Preparation | Lifetime::Pass))
                .cloned(),
        );
    }
    items.sort_by_key(|i| std::cmp::Reverse(i.bytes));
    MemoryEstimate {
        items,
        stored_per_emitted: entries
            .iter()
            .map(|e| e.stored_per_emitted)
            .fold(0.0, f64::max),
    }
}

/// The estimate of a command that prepares a renderer with `settings` and renders no pass
/// (`merge`, `weights`): `estimate` without its pass items, unless the preparation itself
/// renders a pilot pass (an adaptive radius, the balance correction).
pub fn without_passes(mut estimate: MemoryEstimate, settings: &RenderSettings) -> MemoryEstimate {
    let pilot_pass = settings.adaptive_radius
        || settings
            .heuristic()
            .is_some_and(|h| h.needs().balance_correction);
    if !pilot_pass {
        estimate.items.retain(|i| i.lifetime != Lifetime::Pass);
    }
    estimate
}

/// The limit a command's estimate is compared with: `--max-memory`, else the memory
/// available on this machine (MemAvailable), none where that is unknown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryLimit {
    /// The limit, bytes.
    pub bytes: Option<u64>,
    /// Where it came from, as messages and reports name it.
    pub source: &'static str,
}

impl MemoryLimit {
    /// The limit for `--max-memory` (bytes) when given, else the available memory.
    pub fn of(max_memory: Option<u64>) -> MemoryLimit {
        match max_memory {
            Some(b) => MemoryLimit {
                bytes: Some(b),
                source: "--max-memory",
            },
            None => MemoryLimit {
                bytes: available_memory(),
                source: "available memory",
            },
        }
    }

    /// The limit as the loader compares a scene's textures, buffers and geometry with it,
    /// with the words of this command line; `None` where there is no limit.
    pub fn for_loader(&self) -> Option<bdpm_load::MemoryLimit> {
        self.bytes.map(|bytes| bdpm_load::MemoryLimit {
            bytes,
            source: self.source.into(),
            remedy: Some("raise --max-memory if the machine has it".into()),
        })
    }

    /// The limit, when `bytes` exceed it.
    pub fn exceeded_by(&self, bytes: u64) -> Option<u64> {
        self.bytes.filter(|&limit| bytes > limit)
    }

    /// `the available memory of 1.2 GiB`, for a message.
    pub fn describe(&self) -> String {
        match self.bytes {
            Some(b) => format!("the {} of {}", self.source, human_bytes(b)),
            None => "no limit".into(),
        }
    }
}

/// The items of `e` that hold at least 1 % of it, as `name size, …`, for a message.
pub fn parts(e: &MemoryEstimate) -> String {
    let total = e.total();
    e.items
        .iter()
        .filter(|i| i.bytes.saturating_mul(100) >= total)
        .map(|i| format!("{} {}", i.name, human_bytes(i.bytes)))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use bdpm_integrator::{Mode, estimate_memory};
    use std::path::Path;

    fn item(name: &'static str, bytes: u64) -> MemoryItem {
        let lifetime = match name {
            "film and output images" | "per-pixel weight table" => Lifetime::Held,
            "photon map per pass" => Lifetime::Pass,
            "radiance cache build" => Lifetime::Preparation,
            _ => Lifetime::Shared,
        };
        MemoryItem {
            name,
            bytes,
            lifetime,
            lower: Lower::Setting(Setting::Photons),
        }
    }

    fn estimate(items: Vec<MemoryItem>) -> MemoryEstimate {
        MemoryEstimate {
            items,
            stored_per_emitted: 0.5,
        }
    }

    #[test]
    fn renderers_held_together_add_their_held_items_and_the_largest_transients() {
        let a = estimate(vec![
            item("program and scene", 16),
            item("film and output images", 100),
            item("photon map per pass", 1000),
        ]);
        let b = estimate(vec![
            item("program and scene", 16),
            item("film and output images", 100),
            item("per-pixel weight table", 10),
            item("photon map per pass", 600),
            item("radiance cache build", 500),
        ]);
        let c = held_together(&[a.clone(), b]);
        // Scene once, two films, one table, and b's transients (1100 > 1000).
        assert_eq!(c.total(), 16 + 200 + 10 + 600 + 500);
        assert_eq!(c.items[0].name, "photon map per pass");
        assert_eq!(held_together(std::slice::from_ref(&a)).total(), a.total());
        assert_eq!(held_together(&[]).total(), 0);
    }

    #[test]
    fn a_renderer_that_renders_no_pass_leaves_out_the_pass_items_unless_a_pilot_renders_one() {
        let e = estimate(vec![
            item("program and scene", 16),
            item("photon map per pass", 1000),
            item("radiance cache build", 500),
        ]);
        let mut s = RenderSettings::default();
        assert_eq!(without_passes(e.clone(), &s).total(), 516);
        s.adaptive_radius = true;
        assert_eq!(without_passes(e.clone(), &s).total(), 1516);
        s.adaptive_radius = false;
        s.mode = Mode::parse("corrected-balance").unwrap();
        assert_eq!(without_passes(e, &s).total(), 1516);
    }

    /// The items of the estimates of renders live as this module adds them up: what a
    /// renderer holds once per renderer, what its preparation or a pass allocates once at a
    /// time, the rest once.
    #[test]
    fn the_estimates_items_say_how_long_they_live() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-lambert.toml");
        let loaded = bdpm_load::load_scene(&path).unwrap();
        let mut seen: Vec<(&str, Lifetime)> = Vec::new();
        for (mode, light_tracing, adaptive) in [
            ("optimal", false, true),
            ("corrected-balance", true, false),
            ("light", false, false),
        ] {
            let mut s = loaded.settings.clone();
            s.mode = Mode::parse(mode).unwrap();
            s.light_tracing = light_tracing;
            s.adaptive_radius = adaptive;
            s.photons = 1000;
            for techniques in [false, true] {
                let e = estimate_memory(&loaded.scene, &s, techniques);
                seen.extend(e.items.iter().map(|i| (i.name, i.lifetime)));
            }
        }
        for expected in [
            ("film and output images", Lifetime::Held),
            ("technique layers", Lifetime::Held),
            ("per-pixel weight table", Lifetime::Held),
            ("radiance cache build", Lifetime::Preparation),
            ("adaptive-radius pilot", Lifetime::Preparation),
            ("balance-correction pilot", Lifetime::Preparation),
            ("photon map per pass", Lifetime::Pass),
            ("light-path splats per pass", Lifetime::Pass),
            ("light-tracing splats per pass", Lifetime::Pass),
            ("program", Lifetime::Shared),
        ] {
            assert!(seen.contains(&expected), "{expected:?} not in {seen:?}");
        }
        let model = bdpm_integrator::prepare::model_cache_item(
            &estimate_memory(&loaded.scene, &loaded.settings, false),
            1000,
        );
        assert_eq!(model.lifetime, Lifetime::Preparation);
        assert_eq!(lower(&model), "--model-cache-photons");
    }
}
