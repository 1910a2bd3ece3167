//! Which kinds of light path a render samples where mirrors and glass are involved, for the
//! run report: a scene without them leaves the delta walks out altogether.
use bdpm_settings::Mode;

use crate::render::Renderer;

/// The path kinds through mirrors and glass (delta vertices) that a render samples
/// (docs/method-notes.md, "Mirrors and glass").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathsRan {
    /// Materials that are perfect mirrors or smooth dielectrics; 0 when there are none, and
    /// then every walk through delta vertices is left out (camera rays stop at their first
    /// hit, photons never take a delta step).
    pub delta_materials: usize,
    /// Camera rays follow mirrors and glass to their first non-delta vertex x₀ (…–x₀–S…–E).
    pub camera_through_delta: bool,
    /// BDD=1 follows mirrors and glass from x₀ to a non-delta x₁ (…–x₁–S…–x₀), where the
    /// weights give it a share (`path` follows every chain).
    pub x1_through_delta: bool,
    /// Photons that reached x₀ through mirrors and glass are merged there; those that came
    /// from the light through them alone (caustics, L–S…–x₀) by the merge at x₀ only.
    pub caustics_merged_at_x0: bool,
    /// Photons cross mirrors and glass and are stored at non-delta vertices only.
    pub photons_through_delta: bool,
    /// Light tracing connects photons to the camera from non-delta vertices only (the `light`
    /// reference; a mode's `light_tracing` is refused with delta materials).
    pub light_connections: bool,
}

impl PathsRan {
    /// One line for the console, `None` in a scene without mirrors or glass.
    pub fn summary(&self) -> Option<String> {
        if self.delta_materials == 0 {
            return None;
        }
        let yes = |b: bool| if b { "yes" } else { "no" };
        Some(format!(
            "mirrors and glass ({} delta material{}): camera to x0 through them {}, x0 to x1 through them {}, photons through them {}, caustics merged at x0 {}, light-tracing connections {}",
            self.delta_materials,
            if self.delta_materials == 1 { "" } else { "s" },
            yes(self.camera_through_delta),
            yes(self.x1_through_delta),
            yes(self.photons_through_delta),
            yes(self.caustics_merged_at_x0),
            yes(self.light_connections),
        ))
    }
}

impl Renderer<'_> {
    /// The path kinds through mirrors and glass this renderer samples.
    pub fn paths_ran(&self) -> PathsRan {
        let scene = self.scene();
        let delta_materials = scene
            .materials()
            .iter()
            .filter(|m| m.delta.is_some())
            .count();
        if delta_materials == 0 {
            return PathsRan::default();
        }
        let mode = self.settings().mode;
        let needs = self.heuristic().map(|h| h.needs()).unwrap_or_default();
        let bdpm = self.heuristic().is_some();
        // A chain x₀–S…–x₁ gets w₁ > 0 in bdd1 and where x₀ has a lobe (Mix::chain_w1).
        let lobes = scene
            .materials()
            .iter()
            .any(|m| m.delta.is_none() && !m.bdf.is_lambert());
        let fixed = self.heuristic().and_then(|h| h.fixed_w1());
        let x1 = match mode {
            Mode::Path => true,
            _ => bdpm && needs.second_vertex && (fixed == Some(1.0) || (fixed.is_none() && lobes)),
        };
        let photons = mode != Mode::Path;
        PathsRan {
            delta_materials,
            camera_through_delta: true,
            x1_through_delta: x1,
            caustics_merged_at_x0: bdpm && needs.photons_at_x0,
            photons_through_delta: photons,
            light_connections: mode == Mode::Light,
        }
    }
}
