//! How many direct-light samples each pixel's camera samples take (crate::direct), fixed
//! from the scene alone before the passes.
use super::{BuildContext, Preparation};
use crate::direct::DirectSamples;
use crate::error::RenderError;
use crate::setup::Setup;
use crate::stage::Stage;
use bdpm_settings::Mode;

/// M per pixel from L₀'s spread over four fixed points of the pixel. The mix's and the
/// `light` reference's camera samples read it; `path` takes its direct light by next-event
/// estimation at every vertex and does not. Reported only when some pixel takes more than
/// one.
pub(crate) struct DirectSamplesPrep;

impl Preparation for DirectSamplesPrep {
    type Product = DirectSamples;

    fn stage(&self, _: &Setup<'_>) -> Stage {
        Stage::DirectSamples
    }

    fn needed(&self, setup: &Setup<'_>) -> bool {
        setup.settings.mode != Mode::Path
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Option<DirectSamples>, RenderError> {
        Ok(DirectSamples::allocate(cx.setup.scene, cx.settings()))
    }

    fn report(&self, d: &DirectSamples, setup: &Setup<'_>) -> Option<(u64, String)> {
        let detail = format!(
            "{} pixels take up to {} direct-light samples per camera sample (at most {}): \
             {:.4} more per camera sample over the image",
            d.boosted(),
            d.largest(),
            setup.settings.direct_boost,
            d.extra_per_sample()
        );
        Some((d.bytes(), detail))
    }
}
