//! `adaptive_radius`'s merge radius per block of pixels (crate::radius), from a pilot of the
//! mode split by technique.
use super::{BuildContext, MemoryScale, Preparation, pilot_settings};
use crate::error::RenderError;
use crate::estimates::Techniques;
use crate::memory::{Lifetime, Lower, MemoryItem};
use crate::pass::{TechniqueSplit, bdpm_pass};
use crate::radius::{BLOCK, RadiusMap, SCALES, SHARE_BOUNDS, radius_pilot_seed};
use crate::setup::Setup;
use crate::stage::Stage;
use crate::table::PixelWeights;
use bdpm_settings::{ADAPTIVE_RADIUS_PILOT_PASSES, Setting};

/// [`ADAPTIVE_RADIUS_PILOT_PASSES`] passes of the mode at r on the pilot's own streams, split
/// by technique, give each block its radius; the pixel table, whose N_eff, A and B depend on
/// the radius, is then built again (`PixelTablePrep::AT_PIXEL_RADII`).
pub(crate) struct RadiusMapPrep;

impl Preparation for RadiusMapPrep {
    type Product = RadiusMap;

    fn stage(&self, _: &Setup<'_>) -> Stage {
        Stage::RadiusMap
    }

    fn needed(&self, setup: &Setup<'_>) -> bool {
        setup.heuristic.is_some() && setup.settings.adaptive_radius
    }

    fn memory(&self, _: &Setup<'_>, scale: &MemoryScale) -> Vec<MemoryItem> {
        // At the pilot's peak: its technique sums and one pass's layers and estimates; then
        // the table at each pixel's radius is built beside the one at r.
        let per_pixel =
            2 * size_of::<Techniques>() + size_of::<[f64; 3]>() + size_of::<PixelWeights>();
        vec![MemoryItem {
            name: "adaptive-radius pilot",
            bytes: scale.pixels * per_pixel as u64,
            lifetime: Lifetime::Preparation,
            lower: Lower::SettingOrOff(Setting::Resolution, Setting::AdaptiveRadius),
        }]
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Option<RadiusMap>, RenderError> {
        let Some(h) = cx.setup.heuristic else {
            return Ok(None);
        };
        let s = cx.settings();
        let pilot = pilot_settings(s, radius_pilot_seed(s.seed));
        let mix = cx.mix(h);
        let pass_cx = cx.pass_context();
        let mut sums = vec![Techniques::default(); s.width as usize * s.height as usize];
        for pass in 0..ADAPTIVE_RADIUS_PILOT_PASSES {
            let (_, techniques) =
                bdpm_pass::<TechniqueSplit>(&pass_cx, &mix, &pilot, pass, &|_| {}, cx.stop)
                    .ok_or(RenderError::Interrupted(Stage::RadiusMap))?;
            for (sum, t) in sums.iter_mut().zip(&techniques) {
                sum.direct += t.direct;
                sum.x0_weighted += t.x0_weighted;
                sum.x1_weighted += t.x1_weighted;
            }
        }
        Ok(Some(RadiusMap::from_techniques(s.width, s.height, &sums)))
    }

    fn report(&self, map: &RadiusMap, setup: &Setup<'_>) -> Option<(u64, String)> {
        let [small, same, large] = map.blocks();
        let detail = format!(
            "{ADAPTIVE_RADIUS_PILOT_PASSES} pilot pass(es): of {} blocks of {BLOCK}x{BLOCK} pixels, \
             {small} at {:.2} r (BDD=1 under {:.0}% of the block), {same} at r, {large} at \
             {:.2} r (over {:.0}%); r = {} m",
            small + same + large,
            SCALES[0],
            100.0 * SHARE_BOUNDS[0],
            SCALES[2],
            100.0 * SHARE_BOUNDS[1],
            setup.radius
        );
        Some((map.bytes(), detail))
    }
}
