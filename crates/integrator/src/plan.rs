//! What a camera pass needs for each pixel, built in one place once per pixel
//! ([`PixelPlanner::plan`]): the pixel's weigher (its A, B and N_eff from the pixel table,
//! `corrected-balance`'s factor, its radius), its scale of the merge radius, its direct-light
//! samples and one-bounce x₁ per camera sample and its layout of samples in this pass. A preparation that
//! changes how a pixel is sampled or weighed reaches the camera side here.
use bdpm_mis::Weigher;

use crate::correction::Correction;
use crate::direct::{DirectExtra, DirectSamples};
use crate::mix::Mix;
use crate::one_bounce::OneBounceSamples;
use crate::products::Products;
use crate::sampler::{CameraSample, PixelSamples};
use crate::table::PixelTable;

/// One pixel's plan for one pass.
pub(crate) struct PixelPlan<'l> {
    /// Column, pixels from the left.
    pub(crate) x: u32,
    /// Row, pixels from the top.
    pub(crate) y: u32,
    /// The pixel's weigher (a BDPM mix's pixel; `None` for the references).
    pub(crate) weigher: Option<Weigher>,
    /// The pixel's scale of the merge radius (1 without a radius map, which keeps every bit).
    pub(crate) radius_scale: f32,
    /// Direct-light samples per camera sample (1 unless `direct_boost` gives the pixel more).
    pub(crate) direct_samples: u32,
    /// x₁ per camera sample for the one-bounce paths at a glossy x₀ (1 unless
    /// crate::one_bounce gives the pixel more).
    pub(crate) one_bounce: u32,
    /// The pixel's samples in this pass, placed on the pixel.
    layout: &'l PixelSamples,
}

impl PixelPlan<'_> {
    /// Sample `k` (< N_B) of the pixel: its stream, offset and BDF numbers at x₀.
    #[inline]
    pub(crate) fn sample(&self, k: u32) -> CameraSample {
        self.layout.sample(k)
    }

    /// The further direct-light points of sample `k`, when the pixel takes more than one
    /// direct-light sample per camera sample.
    #[inline]
    pub(crate) fn direct_extra(&self, k: u32) -> Option<DirectExtra> {
        self.layout
            .direct_extra(k, (self.x, self.y), self.direct_samples)
    }
}

/// Builds each pixel's plan from a mix (if any) and the preparations a pass reads.
pub(crate) struct PixelPlanner<'a> {
    mix: Option<&'a Mix<'a>>,
    table: Option<&'a PixelTable>,
    correction: Option<&'a Correction>,
    direct: Option<&'a DirectSamples>,
    one_bounce: Option<&'a OneBounceSamples>,
}

impl<'a> PixelPlanner<'a> {
    /// The plans of a pass without weights (`path`, `light`, the first-hit layers), with the
    /// direct-light samples `direct` if the estimator reads them.
    pub(crate) fn unweighted(direct: Option<&'a DirectSamples>) -> Self {
        PixelPlanner {
            mix: None,
            table: None,
            correction: None,
            direct,
            one_bounce: None,
        }
    }

    /// The plans of a pass of `mix` with the pixel table, the factors and the direct-light
    /// samples among `products`. A pilot of `corrected-balance` ([`Mix::pilot`]) weighs with
    /// plain `balance`: it reads neither the table nor the factors.
    pub(crate) fn weighted(mix: &'a Mix<'a>, products: &'a Products) -> Self {
        let (table, correction) = if mix.pilot {
            (None, None)
        } else {
            (products.get(), products.get())
        };
        PixelPlanner {
            mix: Some(mix),
            table,
            correction,
            direct: products.get(),
            one_bounce: products.get(),
        }
    }

    /// Pixel (x, y)'s weigher (a mix's planner only).
    pub(crate) fn weigher(&self, x: u32, y: u32) -> Weigher {
        let mix = self.mix.expect("the planner of a mix");
        let pixel = self.table.map(|t| t.get(x, y));
        let inputs = (pixel.map(|p| p.camera_samples), pixel.map(|p| &p.terms));
        let factor = self.correction.map_or(1.0, |c| c.get(x, y));
        mix.weigher(inputs, factor, mix.radius_scale(x, y))
    }

    /// Pixel (x, y)'s plan with `layout`, already placed on the pixel.
    pub(crate) fn plan<'l>(&self, x: u32, y: u32, layout: &'l PixelSamples) -> PixelPlan<'l> {
        PixelPlan {
            x,
            y,
            weigher: self.mix.map(|_| self.weigher(x, y)),
            radius_scale: self.mix.map_or(1.0, |m| m.radius_scale(x, y)),
            direct_samples: self.direct.map_or(1, |d| d.at(x, y)),
            one_bounce: self.one_bounce.map_or(1, |d| d.at(x, y)),
            layout,
        }
    }
}
