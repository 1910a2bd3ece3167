//! The per-pixel weight inputs (crate::table): ρ and N_eff from each pixel's footprint under
//! the footprint noise model (method.md §12), and A and B for the weights that read them
//! (method.md §6). Built at r, and with `adaptive_radius` again at each pixel's radius once
//! the radius map is known (N_eff, A and B depend on the radius).
use bdpm_mis::{Budget, Heuristic};

use super::{BuildContext, MemoryScale, Preparation};
use crate::error::RenderError;
use crate::memory::{Lifetime, Lower, MemoryItem};
use crate::setup::Setup;
use crate::stage::Stage;
use crate::table::{self, PixelTable, PixelWeights, TableSpec};
use bdpm_settings::Setting;

/// The pixel table, at r or (`after_radius_map`) again at each pixel's radius.
pub(crate) struct PixelTablePrep {
    after_radius_map: bool,
}

impl PixelTablePrep {
    /// The table at the radius map in force (r everywhere before there is one).
    pub(crate) const AT_R: PixelTablePrep = PixelTablePrep {
        after_radius_map: false,
    };
    /// The table built again after `adaptive_radius`'s map; the first one, at r, served its
    /// pilot and stays in the report (it was paid for).
    pub(crate) const AT_PIXEL_RADII: PixelTablePrep = PixelTablePrep {
        after_radius_map: true,
    };
}

/// Whether the weights of `h` read a pixel table: A and B, or each pixel's N_eff under the
/// footprint noise model.
fn table_needed(setup: &Setup<'_>, h: Heuristic) -> bool {
    let needs = h.needs();
    needs.pixel_table || footprints(setup, h)
}

/// Whether the table holds each pixel's ρ and N_eff from its footprint.
fn footprints(setup: &Setup<'_>, h: Heuristic) -> bool {
    setup.footprint_model() && h.needs().effective_samples
}

impl Preparation for PixelTablePrep {
    type Product = PixelTable;

    fn stage(&self, setup: &Setup<'_>) -> Stage {
        if setup.heuristic.is_some_and(|h| h.needs().pixel_table) {
            Stage::PixelTable
        } else {
            Stage::PixelFootprints
        }
    }

    fn needed(&self, setup: &Setup<'_>) -> bool {
        setup.heuristic.is_some_and(|h| table_needed(setup, h))
            && (!self.after_radius_map || setup.settings.adaptive_radius)
    }

    fn memory(&self, _: &Setup<'_>, scale: &MemoryScale) -> Vec<MemoryItem> {
        // The second table replaces the first; the radius map's pilot item counts the two
        // side by side.
        if self.after_radius_map {
            return Vec::new();
        }
        vec![MemoryItem {
            name: "per-pixel weight table",
            bytes: scale.pixels * size_of::<PixelWeights>() as u64,
            lifetime: Lifetime::Held,
            lower: Lower::Setting(Setting::Resolution),
        }]
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Option<PixelTable>, RenderError> {
        let setup = cx.setup;
        let Some(h) = setup.heuristic else {
            return Ok(None);
        };
        let s = &setup.settings;
        let spec = TableSpec {
            rays: h.needs().pixel_table.then_some(s.table_rays()),
            footprint: footprints(setup, h),
            strata: crate::sampler::pixel_strata(s),
            radius: setup.radius,
            seed: s.seed,
        };
        table::build(&cx.mix(h), s.width, s.height, &spec, cx.stop)
            .map(Some)
            .ok_or(RenderError::Interrupted(self.stage(setup)))
    }

    fn report(&self, table: &PixelTable, setup: &Setup<'_>) -> Option<(u64, String)> {
        let h = setup.heuristic?;
        let s = &setup.settings;
        let budget = setup.budget();
        // c·B with each pixel's own c = (N_F − 1)·S/(Φ·N_eff).
        let clamped = table
            .pixels()
            .iter()
            .filter(|p| {
                Budget {
                    camera_samples: p.camera_samples,
                    ..budget
                }
                .one_minus_cb(p.terms.b)
                .1
            })
            .count();
        let (rho, n_eff) = table::mean_overlap(table);
        let overlap = if footprints(setup, h) {
            format!(
                "footprint noise model: mean rho {rho:.4}, mean N_eff {n_eff:.2} of N_B {}",
                s.spp
            )
        } else {
            format!("pinhole noise model (N_eff = N_B = {})", s.spp)
        };
        let detail = if h.needs().pixel_table {
            format!(
                "A, B for {}x{} pixels, {} rays each; {clamped} pixels with c*B clamped; {overlap}",
                s.width,
                s.height,
                s.table_rays(),
            )
        } else {
            format!("rho, N_eff for {}x{} pixels; {overlap}", s.width, s.height)
        };
        Some((table.bytes(), detail))
    }
}
