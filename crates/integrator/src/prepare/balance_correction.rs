//! `corrected-balance`'s per-pixel factors (crate::correction), learnt from a pilot of
//! `balance` on its own streams.
use bdpm_mis::Heuristic;

use super::{BuildContext, MemoryScale, Preparation, pilot_settings};
use crate::correction::{CANDIDATES, CandidateSums, Correction, PILOT_PASSES, pilot_seed};
use crate::error::RenderError;
use crate::memory::{Lifetime, Lower, MemoryItem};
use crate::mix::Mix;
use crate::pass::{CandidateLayer, bdpm_pass};
use crate::setup::Setup;
use crate::stage::Stage;
use bdpm_settings::Setting;

/// [`PILOT_PASSES`] passes of `balance` on the pilot's own streams score every candidate
/// factor per pixel; the factors come from their box-filtered second moments.
pub(crate) struct BalanceCorrectionPrep;

impl Preparation for BalanceCorrectionPrep {
    type Product = Correction;

    fn stage(&self, _: &Setup<'_>) -> Stage {
        Stage::BalanceCorrection
    }

    fn needed(&self, setup: &Setup<'_>) -> bool {
        setup
            .heuristic
            .is_some_and(|h| h.needs().balance_correction)
    }

    fn memory(&self, _: &Setup<'_>, scale: &MemoryScale) -> Vec<MemoryItem> {
        // Per pixel and candidate, at the pilot's peak: the pass's per-row sums, their
        // concatenation, and the second moments.
        vec![MemoryItem {
            name: "balance-correction pilot",
            bytes: scale.pixels * (3 * CANDIDATES.len() * size_of::<f64>()) as u64,
            lifetime: Lifetime::Preparation,
            lower: Lower::Setting(Setting::Resolution),
        }]
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Option<Correction>, RenderError> {
        let s = cx.settings();
        let pilot = pilot_settings(s, pilot_seed(s.seed));
        let mix = Mix {
            pilot: true,
            ..cx.mix(Heuristic::Balance)
        };
        let pass_cx = cx.pass_context();
        let pixels = s.width as usize * s.height as usize;
        let mut second = vec![CandidateSums::default(); pixels];
        for pass in 0..PILOT_PASSES {
            let (_, estimates) =
                bdpm_pass::<CandidateLayer>(&pass_cx, &mix, &pilot, pass, &|_| {}, cx.stop)
                    .ok_or(RenderError::Interrupted(Stage::BalanceCorrection))?;
            for (m, f) in second.iter_mut().zip(&estimates) {
                m.add_squares(f, 1.0 / f64::from(PILOT_PASSES));
            }
        }
        Ok(Some(Correction::from_moments(s.width, &second)))
    }

    fn report(&self, correction: &Correction, _: &Setup<'_>) -> Option<(u64, String)> {
        Some((correction.bytes(), correction.summary()))
    }
}
