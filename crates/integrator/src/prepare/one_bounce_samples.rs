//! How many x₁ each pixel's camera samples take for the one-bounce paths at a glossy x₀
//! (crate::one_bounce), fixed from the scene alone before the passes.
use super::{BuildContext, Preparation};
use crate::error::RenderError;
use crate::one_bounce::OneBounceSamples;
use crate::setup::Setup;
use crate::stage::Stage;

/// N per pixel from the spread of its one-bounce estimates. Only a BDPM mix that traces x₁
/// reads it (not `bdd0`), and only a scene with area lights and glossy surfaces builds one; reported only
/// when some pixel takes more than one.
pub(crate) struct OneBounceSamplesPrep;

impl Preparation for OneBounceSamplesPrep {
    type Product = OneBounceSamples;

    fn stage(&self, _: &Setup<'_>) -> Stage {
        Stage::OneBounceSamples
    }

    fn needed(&self, setup: &Setup<'_>) -> bool {
        setup.scene.has_emission() && setup.heuristic.is_some_and(|h| h.needs().second_vertex)
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Option<OneBounceSamples>, RenderError> {
        Ok(OneBounceSamples::allocate(cx.setup.scene, cx.settings()))
    }

    fn report(&self, n: &OneBounceSamples, _: &Setup<'_>) -> Option<(u64, String)> {
        let detail = format!(
            "{} pixels take up to {} x1 per camera sample for the one-bounce paths at a glossy \
             x0: {:.4} more per camera sample over the image",
            n.boosted(),
            n.largest(),
            n.extra_per_sample()
        );
        Some((n.bytes(), detail))
    }
}
