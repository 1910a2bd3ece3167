use std::sync::atomic::{AtomicU64, Ordering};

use bdpm_geometry::Domain;
use bdpm_scene::Scene;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

use bdpm_bdf::luminance;
use bdpm_cache::{CacheSettings, RadianceCache};
use bdpm_mis::{Budget, Heuristic, NoiseModel, Weigher};
use bdpm_photon::{PhotonMap, TraceOptions};

use crate::bdpm::{BATCH, Job, Mix, Slots, Techniques, WeightStats, scene_default_radius};
use crate::connect::Splats;
use crate::correction::{CandidateSums, Correction, PILOT_PASSES, pilot_seed};
use crate::direct::DirectSamples;
use crate::radius::{BLOCK, RadiusMap, SCALES, SHARE_BOUNDS, radius_pilot_seed};
use crate::sampler::PixelSamples;
use crate::stage::Stage;
use crate::table::{self, PixelTable, TableSpec};
use bdpm_settings::{
    ADAPTIVE_RADIUS_PILOT_PASSES, Mode, RadiusError, RenderSettings, SettingsError, check_radius,
};

/// Radiance-cache cells per largest scene extent: cells of ~9 cm in the 2.8 m Cornell box,
/// far larger than the merge radius, as method.md §5 asks.
const CACHE_CELLS_PER_EXTENT: f32 = 32.0;

/// Photons of the noise model's radiance cache ([`Renderer::with_model_inputs`]) at least.
/// The model reads L_d and b at x₁ as the values of a BDD=1 sample and of its photon noise:
/// the cache's noise from cell to cell reads as variation over directions (T1), and a coarse
/// cache's b as the photon noise (T2). A render's cache is chosen for its weights per second
/// (the glossy file's 2.5·10⁵ photons in one bin); the model's is for the truth
/// (docs/results.md, "The noise model's own cache").
pub const MODEL_CACHE_PHOTONS: u64 = 8_000_000;

/// Bins per cell side of the noise model's radiance cache at least (method.md's M ≈ 100;
/// a Lambert-only scene's cache keeps one, which is exact there).
pub const MODEL_CACHE_BINS: u32 = 100;

/// `settings` with the weights' radiance cache made the noise model's
/// ([`Renderer::with_model_cache`] of `photons`): at least `photons` photons and
/// [`MODEL_CACHE_BINS`] bins. A renderer with these settings weighs with the very cache the
/// model reads: `bdpm predict --headroom`'s floor, the minimiser of the model's functional,
/// is one.
pub fn model_cache_settings(settings: &RenderSettings, photons: u64) -> RenderSettings {
    let mut s = settings.clone();
    s.cache_photons = Some(
        settings
            .cache_photons
            .unwrap_or(settings.photons)
            .max(photons),
    );
    s.cache_bins = settings.cache_bins.max(MODEL_CACHE_BINS);
    s
}

/// A merge radius above this fraction of the scene's largest extent draws a warning
/// ([`Renderer::warnings`]): the density estimate then averages photons over a large part of
/// the scene.
pub const LARGE_RADIUS_FRACTION: f32 = 0.1;

/// Told by [`Renderer::render_pass`] when each stage of a pass starts and ends, e.g. to sample
/// the process's memory per stage. A probe sees stages only and cannot change the render.
pub trait StageProbe: Sync {
    /// `stage` of a pass (one of [`PassOutput::stage_seconds`]) is about to start.
    fn enter(&self, stage: Stage);
    /// `stage` has ended.
    fn leave(&self, stage: Stage);
}

/// Time and memory of one preparatory stage (photon map, radiance cache, A/B table, …).
#[derive(Clone, Debug, PartialEq)]
pub struct StageReport {
    /// The stage, e.g. [`Stage::RadianceCache`].
    pub stage: Stage,
    /// Wall time, seconds.
    pub seconds: f64,
    /// Memory held by the stage's result, bytes.
    pub bytes: u64,
    /// One line of facts (cell counts, bins, …).
    pub detail: String,
}

/// Why a render cannot start, or why a query of a renderer (weight map, noise prediction)
/// cannot be answered. `Display` keeps one line that says what is wrong; callers tell the
/// cases apart by variant, never by the message.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// A setting is out of range or inconsistent ([`RenderSettings::validate`]).
    #[error("{setting}: {0}", setting = .0.setting())]
    Settings(#[from] SettingsError),
    /// The scene's camera has another image size than the settings.
    #[error("camera is {}×{} but the settings ask for {}×{}", .camera.0, .camera.1, .settings.0, .settings.1)]
    Resolution {
        /// The camera's (width, height), pixels.
        camera: (u32, u32),
        /// The settings' (width, height), pixels.
        settings: (u32, u32),
    },
    /// The merge radius in force (the scene's default when none was given) is unusable.
    #[error("merge radius {0}")]
    Radius(RadiusError),
    /// A merge radius in pixel footprints, but no pixel's centre ray hits the scene.
    #[error(
        "merge radius {0} px: the camera sees no surface through any pixel centre, so a pixel has no footprint; give the radius in metres"
    )]
    NoFootprint(f32),
    /// The mode (`path`, `light`) has no weights, so no weight map.
    #[error("mode '{0}' has no weights")]
    NoWeights(Mode),
    /// The mode weighs each light path by its incoming direction at x₁, so no map over x₁.
    #[error(
        "mode '{0}' weighs each light path by its incoming direction at x1, so it has no map over x1 alone; a mode whose weights depend on x1 alone has one (e.g. --mode optimal)"
    )]
    PerLightPathWeights(&'static str),
    /// The mode (`path`, `light`) has no noise model.
    #[error("mode '{0}' has no noise model to predict")]
    NoNoiseModel(Mode),
    /// The render samples BDD=0 by light tracing (`light_tracing`), which the noise model and
    /// the weight maps (both of the merge at x₀) do not describe.
    #[error(
        "light_tracing = true: mode '{0}' then samples BDD=0 by light tracing, which the noise model and the weight maps (both of the merge at x0) do not describe; set light_tracing = false (--light-tracing false)"
    )]
    LightTracing(&'static str),
    /// The weights asked for read the pixel table's A and B, which the mode did not build.
    #[error(
        "the weights '{weights}' need the pixel table's A and B, which mode '{mode}' does not build"
    )]
    NoPixelTable {
        /// The weights' name.
        weights: &'static str,
        /// The renderer's mode.
        mode: Mode,
    },
    /// The weights asked for read `corrected-balance`'s per-pixel factors, which the mode did
    /// not learn.
    #[error(
        "the weights '{weights}' need corrected-balance's per-pixel factors, which mode '{mode}' does not learn"
    )]
    NoCorrection {
        /// The weights' name.
        weights: &'static str,
        /// The renderer's mode.
        mode: Mode,
    },
    /// The noise model needs the radiance cache, which was not built.
    #[error(
        "the noise model needs the radiance cache: build the renderer with with_model_inputs()"
    )]
    NoCache,
    /// The x₀ asked for cannot be used (outside the image, not visible, facing away).
    #[error("{0}")]
    Target(TargetError),
    /// The preparation was stopped ([`Renderer::new_until`]) during this stage.
    #[error("interrupted during preparation ({0})")]
    Interrupted(Stage),
}

/// Why a weight map's x₀ cannot be used ([`RenderError::Target`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TargetError {
    /// The pixel is outside the image.
    #[error("pixel ({x}, {y}) is outside the {width}x{height} image")]
    OutsideImage {
        /// Column asked for.
        x: u32,
        /// Row asked for.
        y: u32,
        /// Image width, pixels.
        width: u32,
        /// Image height, pixels.
        height: u32,
    },
    /// The camera sees no surface in the direction of x₀.
    #[error("the camera sees no surface towards x0")]
    NoSurface,
    /// The point given is hidden behind another surface.
    #[error("x0 {point} is not visible from the camera (the camera sees {seen} in its direction)")]
    Hidden {
        /// The point asked for, metres.
        point: Vec3,
        /// The first surface point the camera sees in its direction, metres.
        seen: Vec3,
    },
    /// x₀ faces away from the camera.
    #[error("x0 faces away from the camera")]
    FacesAway,
}

/// A scene and settings made ready to render passes: validates the settings, builds what the
/// mode needs once (and nothing it does not need), then renders any pass on demand.
pub struct Renderer<'a> {
    scene: &'a Scene,
    settings: RenderSettings,
    /// The heuristic in force (BDPM modes): the mode's, with the weight clamp in force.
    heuristic: Option<Heuristic>,
    stages: Vec<StageReport>,
    radius: f32,
    footprint: Option<f32>,
    techniques: bool,
    #[cfg(feature = "test-hooks")]
    camera_x1_weighting: bool,
    #[cfg(feature = "test-hooks")]
    per_visit_inputs: bool,
    #[cfg(feature = "test-hooks")]
    two_way_splat_weights: bool,
    cache: Option<RadianceCache>,
    /// The noise model's own cache, where the weights' is coarser ([`Self::with_model_inputs`]).
    model_cache: Option<RadianceCache>,
    /// The noise model reads the weights' cache (as fine as its own would be).
    model_reads_weights_cache: bool,
    table: Option<PixelTable>,
    /// `corrected-balance`'s per-pixel factors.
    correction: Option<Correction>,
    /// Direct-light samples per camera sample, per pixel (BDPM modes; `None`: one everywhere).
    direct: Option<DirectSamples>,
    /// Each pixel's scale of the merge radius (`adaptive_radius`; `None`: r everywhere).
    radius_map: Option<RadiusMap>,
    probe: Option<&'a dyn StageProbe>,
}

impl<'a> Renderer<'a> {
    /// Checks `settings` against `scene` and prepares the mode's pre-passes.
    pub fn new(scene: &'a Scene, settings: &RenderSettings) -> Result<Renderer<'a>, RenderError> {
        Self::new_until(scene, settings, &never)
    }

    /// [`Renderer::new`] whose preparation gives up when `stop()` returns true: it is asked
    /// before each preparatory stage and within each between chunks of its work (4096 photons
    /// of the radiance cache or of a pilot pass, a pixel of the pixel table, an image row of a
    /// pilot's camera samples), so that an interrupt ends a long preparation within a chunk's
    /// time, with [`RenderError::Interrupted`] naming the stage. A `stop` that never fires
    /// prepares the same renderer as [`Renderer::new`].
    pub fn new_until(
        scene: &'a Scene,
        settings: &RenderSettings,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<Renderer<'a>, RenderError> {
        let s = settings;
        s.validate()?;
        if (scene.camera().width(), scene.camera().height()) != (s.width, s.height) {
            return Err(RenderError::Resolution {
                camera: (scene.camera().width(), scene.camera().height()),
                settings: (s.width, s.height),
            });
        }
        let footprint = scene.pixel_footprint();
        let radius = resolve_radius(scene, s, footprint)?;
        // `None` means the scene's default or a radius in pixels; the renderer's copy holds
        // the value in force, in metres. The mode stays as given: `heuristic` is the mode's
        // with the clamp in force (RenderSettings::weight_clamp).
        let mut settings = s.clone();
        settings.radius = Some(radius);
        settings.radius_px = None;
        let heuristic = settings.heuristic();
        let mut renderer = Renderer {
            scene,
            settings,
            heuristic,
            stages: Vec::new(),
            radius,
            footprint,
            techniques: false,
            #[cfg(feature = "test-hooks")]
            camera_x1_weighting: false,
            #[cfg(feature = "test-hooks")]
            per_visit_inputs: false,
            #[cfg(feature = "test-hooks")]
            two_way_splat_weights: false,
            cache: None,
            model_cache: None,
            model_reads_weights_cache: false,
            table: None,
            correction: None,
            direct: None,
            radius_map: None,
            probe: None,
        };
        if let Some(h) = renderer.heuristic {
            renderer.prepare(h, stop)?;
        }
        // The mix's camera samples and the `light` reference's direct term read it; `path`
        // takes its direct light by next-event estimation at every vertex and does not.
        if renderer.settings.mode != Mode::Path {
            unless_stopped(stop, Stage::DirectSamples)?;
            renderer.allocate_direct();
        }
        Ok(renderer)
    }

    /// Builds the radiance cache and the A/B table when (and only when) `h` needs them;
    /// gives up when `stop()` says so ([`Renderer::new_until`]).
    fn prepare(
        &mut self,
        h: Heuristic,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<(), RenderError> {
        let needs = h.needs();
        if needs.radiance_cache {
            self.build_cache(stop)?;
        }
        self.prepare_table(h, stop)?;
        if needs.balance_correction {
            self.build_correction(stop)?;
        }
        if self.settings.adaptive_radius {
            self.build_radius_map(h, stop)?;
        }
        Ok(())
    }

    /// Builds the pixel table (ρ, N_eff, and A, B) when `h` needs it, with each pixel's radius;
    /// gives up when `stop()` says so.
    fn prepare_table(
        &mut self,
        h: Heuristic,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<(), RenderError> {
        let needs = h.needs();
        let s = &self.settings;
        let footprint = self.footprint_model() && needs.effective_samples;
        let stage = if needs.pixel_table {
            Stage::PixelTable
        } else {
            Stage::PixelFootprints
        };
        if needs.pixel_table || footprint {
            let start = std::time::Instant::now();
            let spec = TableSpec {
                rays: needs.pixel_table.then_some(s.table_rays()),
                footprint,
                strata: crate::sampler::pixel_strata(s),
                radius: self.radius,
                seed: s.seed,
            };
            let table = table::build(&self.mix(h), s.width, s.height, &spec, stop)
                .ok_or(RenderError::Interrupted(stage))?;
            let budget = self.budget();
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
            let (rho, n_eff) = table::mean_overlap(&table);
            let overlap = if footprint {
                format!(
                    "footprint noise model: mean rho {rho:.4}, mean N_eff {n_eff:.2} of N_B {}",
                    s.spp
                )
            } else {
                format!("pinhole noise model (N_eff = N_B = {})", s.spp)
            };
            let detail = if needs.pixel_table {
                format!(
                    "A, B for {}x{} pixels, {} rays each; {} pixels with c*B clamped; {overlap}",
                    s.width,
                    s.height,
                    s.table_rays(),
                    clamped
                )
            } else {
                format!("rho, N_eff for {}x{} pixels; {overlap}", s.width, s.height)
            };
            self.stages.push(StageReport {
                stage,
                seconds: start.elapsed().as_secs_f64(),
                bytes: table.bytes(),
                detail,
            });
            self.table = Some(table);
        }
        Ok(())
    }

    /// `adaptive_radius`: [`ADAPTIVE_RADIUS_PILOT_PASSES`] passes of the mode at r on the
    /// pilot's own streams, split by technique, give each block its radius (crate::radius);
    /// then the pixel table, whose N_eff, A and B depend on the radius, is built again with
    /// each pixel's.
    fn build_radius_map(
        &mut self,
        h: Heuristic,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<(), RenderError> {
        unless_stopped(stop, Stage::RadiusMap)?;
        let start = std::time::Instant::now();
        let mut pilot = self.settings.clone();
        pilot.seed = radius_pilot_seed(self.settings.seed);
        let record = std::mem::replace(&mut self.techniques, true);
        let (w, hgt) = (self.settings.width, self.settings.height);
        let mut sums = vec![Techniques::default(); w as usize * hgt as usize];
        {
            let mix = self.mix(h);
            for pass in 0..ADAPTIVE_RADIUS_PILOT_PASSES {
                let Some((out, _)) = self.bdpm_pass(&mix, &pilot, pass, &|_| {}, stop) else {
                    self.techniques = record;
                    return Err(RenderError::Interrupted(Stage::RadiusMap));
                };
                for (s, t) in sums.iter_mut().zip(out.techniques.iter().flatten()) {
                    s.direct += t.direct;
                    s.x0_weighted += t.x0_weighted;
                    s.x1_weighted += t.x1_weighted;
                }
            }
        }
        self.techniques = record;
        let map = RadiusMap::from_techniques(w, hgt, &sums);
        let [small, same, large] = map.blocks();
        self.stages.push(StageReport {
            stage: Stage::RadiusMap,
            seconds: start.elapsed().as_secs_f64(),
            bytes: map.bytes(),
            detail: format!(
                "{ADAPTIVE_RADIUS_PILOT_PASSES} pilot pass(es): of {} blocks of {BLOCK}x{BLOCK} pixels, \
                 {small} at {:.2} r (BDD=1 under {:.0}% of the block), {same} at r, {large} at \
                 {:.2} r (over {:.0}%); r = {} m",
                small + same + large,
                SCALES[0],
                100.0 * SHARE_BOUNDS[0],
                SCALES[2],
                100.0 * SHARE_BOUNDS[1],
                self.radius
            ),
        });
        self.radius_map = Some(map);
        // The first table (at r, for the pilot) stays in the report: it was paid for.
        if self.table.is_some() {
            self.prepare_table(h, stop)?;
        }
        Ok(())
    }

    /// Fixes each pixel's direct-light samples per camera sample (crate::direct) when the
    /// settings allow more than one; reported as a stage only when some pixel takes more.
    fn allocate_direct(&mut self) {
        let start = std::time::Instant::now();
        self.direct = DirectSamples::allocate(self.scene, &self.settings);
        if let Some(d) = &self.direct {
            self.stages.push(StageReport {
                stage: Stage::DirectSamples,
                seconds: start.elapsed().as_secs_f64(),
                bytes: d.bytes(),
                detail: format!(
                    "{} pixels take up to {} direct-light samples per camera sample (at most {}): \
                     {:.4} more per camera sample over the image",
                    d.boosted(),
                    d.largest(),
                    self.settings.direct_boost,
                    d.extra_per_sample()
                ),
            });
        }
    }

    /// Each pixel's scale of the merge radius, with `adaptive_radius`.
    pub fn radius_map(&self) -> Option<&RadiusMap> {
        self.radius_map.as_ref()
    }

    /// The direct-light samples per camera sample of each pixel, when some pixel takes more
    /// than one.
    pub fn direct_samples(&self) -> Option<&DirectSamples> {
        self.direct.as_ref()
    }

    /// Learns `corrected-balance`'s per-pixel factors from [`PILOT_PASSES`] passes of
    /// `balance` on the pilot's own streams (crate::correction).
    fn build_correction(&mut self, stop: &(dyn Fn() -> bool + Sync)) -> Result<(), RenderError> {
        unless_stopped(stop, Stage::BalanceCorrection)?;
        let start = std::time::Instant::now();
        let mut pilot = self.settings.clone();
        pilot.seed = pilot_seed(self.settings.seed);
        let mix = Mix {
            pilot: true,
            ..self.mix(Heuristic::Balance)
        };
        let pixels = self.settings.width as usize * self.settings.height as usize;
        let mut second = vec![CandidateSums::default(); pixels];
        for pass in 0..PILOT_PASSES {
            let (_, estimates) = self
                .bdpm_pass(&mix, &pilot, pass, &|_| {}, stop)
                .ok_or(RenderError::Interrupted(Stage::BalanceCorrection))?;
            for (m, f) in second.iter_mut().zip(&estimates) {
                m.add_squares(f, 1.0 / f64::from(PILOT_PASSES));
            }
        }
        let correction = Correction::from_moments(self.settings.width, &second);
        self.stages.push(StageReport {
            stage: Stage::BalanceCorrection,
            seconds: start.elapsed().as_secs_f64(),
            bytes: correction.bytes(),
            detail: correction.summary(),
        });
        self.correction = Some(correction);
        Ok(())
    }

    /// `corrected-balance`'s per-pixel factors, when the mode uses them.
    pub fn correction(&self) -> Option<&Correction> {
        self.correction.as_ref()
    }

    /// Builds the radiance cache of method.md §5 from its own photon stream.
    fn build_cache(&mut self, stop: &(dyn Fn() -> bool + Sync)) -> Result<(), RenderError> {
        unless_stopped(stop, Stage::RadianceCache)?;
        let s = &self.settings;
        let photons = s.cache_photons.unwrap_or(s.photons);
        let cache = self.radiance_cache(photons, s.cache_bins, "", stop);
        self.cache = Some(cache.ok_or(RenderError::Interrupted(Stage::RadianceCache))?);
        Ok(())
    }

    /// A radiance cache of `photons` photons and `bins` bins per cell side on the render's
    /// seed, reported as a stage (`purpose` prefixes its detail); `None` if `stop()` stopped
    /// it.
    fn radiance_cache(
        &mut self,
        photons: u64,
        bins: u32,
        purpose: &str,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Option<RadianceCache> {
        let start = std::time::Instant::now();
        let (lo, hi) = self.scene.geometry().bounds();
        let settings = CacheSettings {
            bins,
            cell_size: (hi - lo).max_element() / CACHE_CELLS_PER_EXTENT,
            photons,
            seed: self.settings.seed,
        };
        let cache = RadianceCache::build_until(self.scene, &settings, stop)?;
        let st = cache.stats();
        self.stages.push(StageReport {
            stage: Stage::RadianceCache,
            seconds: start.elapsed().as_secs_f64(),
            bytes: st.bytes,
            detail: format!(
                "{purpose}{} cells x 2 sides, {} bin(s) per side, b {}, {} photons emitted, {} arrivals, {:.1}% of cell sides hit",
                st.cells,
                st.bins,
                if st.stores_b { "stored" } else { "derived (Lambert-only scene)" },
                settings.photons,
                st.arrivals,
                100.0 * st.filled_fraction
            ),
        });
        Some(cache)
    }

    /// Builds the noise model's radiance cache for [`Renderer::predict_variance`], which reads
    /// L_d and b for every mode: [`Self::with_model_cache`] of [`MODEL_CACHE_PHOTONS`].
    pub fn with_model_inputs(self) -> Self {
        self.with_model_cache(MODEL_CACHE_PHOTONS)
    }

    /// [`Self::with_model_inputs`] with a cache of at least `photons` photons (and
    /// [`MODEL_CACHE_BINS`] bins), or the weights' own cache where that is as fine. The weights
    /// keep reading theirs, so rendering is unchanged and the model weighs exactly as the
    /// render does; the cache is that of [`model_cache_settings`] with the same `photons`.
    pub fn with_model_cache(mut self, photons: u64) -> Self {
        let s = &self.settings;
        let model = model_cache_settings(s, photons);
        let own = self.cache.as_ref().is_some_and(|c| {
            s.cache_photons.unwrap_or(s.photons) == model.cache_photons.unwrap_or(model.photons)
                && (s.cache_bins == model.cache_bins || !c.stats().stores_b)
        });
        self.model_reads_weights_cache = own;
        if !own && self.model_cache.is_none() {
            let photons = model.cache_photons.unwrap_or(model.photons);
            self.model_cache =
                self.radiance_cache(photons, model.cache_bins, "noise model's: ", &never);
        }
        self
    }

    /// The radiance cache the noise model reads: its own, or the weights' where that is as
    /// fine ([`Self::with_model_inputs`]); None before that.
    pub(crate) fn model_cache(&self) -> Option<&RadianceCache> {
        self.model_cache.as_ref().or(self
            .cache
            .as_ref()
            .filter(|_| self.model_reads_weights_cache))
    }

    /// Whether the weights use per-pixel N_eff from footprints (method.md §12): the footprint
    /// noise model with jittered samples (without jitter ρ = 1, so N_eff = N_B).
    pub(crate) fn footprint_model(&self) -> bool {
        self.settings.noise_model == NoiseModel::Footprint && self.settings.pixel_jitter
    }

    /// The per-pixel weight inputs (ρ, N_eff, A, B), when the mode uses them.
    pub fn pixel_table(&self) -> Option<&PixelTable> {
        self.table.as_ref()
    }

    /// The mix of mode `h` with this renderer's constants.
    pub(crate) fn mix(&self, heuristic: Heuristic) -> Mix<'_> {
        Mix {
            scene: self.scene,
            heuristic,
            needs: heuristic.needs(),
            fixed_w1: heuristic.fixed_w1(),
            budget: self.budget(),
            inv_area: 1.0 / (std::f32::consts::PI * self.radius * self.radius),
            radius: self.radius,
            radius_map: self.radius_map.as_ref(),
            cache: self.cache.as_ref(),
            pilot: false,
            // `bdd1` has no BDD=0 part to sample.
            light_tracing: self.settings.light_tracing && heuristic.needs().photons_at_x0,
            #[cfg(feature = "test-hooks")]
            camera_x1_weighting: self.camera_x1_weighting,
            #[cfg(feature = "test-hooks")]
            per_visit_inputs: self.per_visit_inputs,
            #[cfg(feature = "test-hooks")]
            two_way_splat_weights: self.two_way_splat_weights,
        }
    }

    /// Also return each sample's contributions split by technique ([`PassOutput::techniques`]).
    pub fn with_technique_layers(mut self, on: bool) -> Self {
        self.techniques = on;
        self
    }

    /// Test-only: weight the photon sum at x₀ with the camera's w₁(x₀, x₁ᶜ) as the preprint's
    /// eq. 2–3 read literally. This estimator is biased (method.md §2); it exists so that a test
    /// can show the bias. Only with the feature `test-hooks`.
    #[cfg(feature = "test-hooks")]
    #[doc(hidden)]
    pub fn with_camera_x1_weighting(mut self, on: bool) -> Self {
        self.camera_x1_weighting = on;
        self
    }

    /// Test-only: compute the weight inputs of a photon's previous vertex at each visit of a
    /// merge at x₀ instead of once per photon per pass; the image bits must not change. Only
    /// with the feature `test-hooks`.
    #[cfg(feature = "test-hooks")]
    #[doc(hidden)]
    pub fn with_per_visit_inputs(mut self, on: bool) -> Self {
        self.per_visit_inputs = on;
        self
    }

    /// Test-only: with light tracing, weigh the splats with the merge's two-way w₁ (without
    /// light tracing's density ratio) while the camera side uses the light-traced one: the two
    /// sides of a path then disagree, and a test must see the bias. Only with the feature
    /// `test-hooks`.
    #[cfg(feature = "test-hooks")]
    #[doc(hidden)]
    pub fn with_two_way_splat_weights(mut self, on: bool) -> Self {
        self.two_way_splat_weights = on;
        self
    }

    /// Merges with `map`'s radius per pixel instead of the pilot's (or of one radius), the
    /// pixel table built again for it: e.g. other weights on a render's own map (`bdpm predict
    /// --headroom`'s floor, whose own pilot, of other weights, would draw another), or blocks
    /// at every scale where the pilot would not put them (tests). `map` must be of this
    /// renderer's image size.
    pub fn with_radius_map(mut self, map: RadiusMap) -> Self {
        let (w, h) = (self.settings.width, self.settings.height);
        assert!(
            map.fits(w, h),
            "a radius map of another image size than {w}x{h}"
        );
        self.radius_map = Some(map);
        if let (Some(h), Some(_)) = (self.heuristic, &self.table) {
            // Never stopped, so never an error.
            let built = self.prepare_table(h, &never);
            debug_assert!(built.is_ok());
        }
        self
    }

    /// The scene this renderer draws.
    pub fn scene(&self) -> &Scene {
        self.scene
    }

    /// The merge radius r in use, metres.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// The scene's pixel footprint at this resolution, metres (`Scene::pixel_footprint`):
    /// what a radius of "1px" is. `None` when the camera sees nothing.
    pub fn pixel_footprint(&self) -> Option<f32> {
        self.footprint
    }

    /// The settings this renderer uses: the caller's, with the merge radius in force.
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// The heuristic the BDPM modes weigh with: the mode's, with the weight clamp in force
    /// ([`RenderSettings::heuristic`]); `None` for `path` and `light`.
    pub fn heuristic(&self) -> Option<Heuristic> {
        self.heuristic
    }

    /// Whether BDD=0's paths are sampled by light tracing: `light_tracing` set and a mode
    /// with a BDD=0 part (not `bdd1`, `path` or `light`).
    pub fn light_traced(&self) -> bool {
        self.settings.light_traced()
    }

    /// The preparatory stages that ran, with their cost.
    pub fn stages(&self) -> &[StageReport] {
        &self.stages
    }

    /// Renders pass number `pass` (0-based). `progress` is called with units of work done
    /// (one per image row); a pass has [`Renderer::work_per_pass`] units.
    pub fn render_pass(&self, pass: u32, progress: &(dyn Fn(u64) + Sync)) -> PassOutput {
        match self.settings.mode {
            // The references' stages interleave; the probe sees the pass as one stage.
            Mode::Path | Mode::Light => {
                self.enter(Stage::Pass);
                let out = if self.settings.mode == Mode::Path {
                    render_path_pass(self.scene, &self.settings, pass, progress)
                } else {
                    crate::light::render_light_pass(
                        self.scene,
                        &self.settings,
                        self.direct.as_ref(),
                        pass,
                        progress,
                    )
                };
                self.leave(Stage::Pass);
                out
            }
            Mode::Bdpm(_) => {
                let h = self.heuristic.expect("a BDPM mode has a heuristic");
                self.render_bdpm_pass(h, pass, progress)
            }
        }
    }

    /// Reports each pass stage's start and end to `probe` from now on (see [`StageProbe`]).
    pub fn set_stage_probe(&mut self, probe: &'a dyn StageProbe) {
        self.probe = Some(probe);
    }

    fn enter(&self, stage: Stage) {
        if let Some(p) = self.probe {
            p.enter(stage);
        }
    }

    fn leave(&self, stage: Stage) {
        if let Some(p) = self.probe {
            p.leave(stage);
        }
    }

    /// Warnings known before the first pass, one line each: a light within the ray offset of
    /// a surface ([`Scene::lights_near_surfaces`]), a merge radius that is a large part of the
    /// scene (above [`LARGE_RADIUS_FRACTION`] of its largest extent).
    pub fn warnings(&self) -> Vec<String> {
        let mut warnings: Vec<String> = (self.scene.lights_near_surfaces().iter())
            .map(ToString::to_string)
            .collect();
        let (lo, hi) = self.scene.geometry().bounds();
        let extent = (hi - lo).max_element();
        let r = self.radius;
        if matches!(self.settings.mode, Mode::Bdpm(_)) && r > LARGE_RADIUS_FRACTION * extent {
            warnings.push(format!(
                "the merge radius {r} m is {:.0}% of the scene's largest extent ({extent} m): photons \
                 are merged across large parts of the scene, so the image is strongly blurred and biased",
                100.0 * r / extent
            ));
        }
        warnings
    }

    /// Units of progress one pass reports.
    pub fn work_per_pass(&self) -> u64 {
        self.settings.height as u64
    }
}

// The test hooks are read through these, so that without the feature `test-hooks` the mix
// has no fields for them and its branches on them are constant.
impl Mix<'_> {
    /// Test hook: weight the photon sum at x₀ with the camera's w₁.
    #[cfg(feature = "test-hooks")]
    #[inline]
    pub(crate) fn camera_x1_weighting(&self) -> bool {
        self.camera_x1_weighting
    }

    /// Test hook: compute a photon's y_p inputs at every visit.
    #[cfg(feature = "test-hooks")]
    #[inline]
    pub(crate) fn per_visit_inputs(&self) -> bool {
        self.per_visit_inputs
    }

    /// Without the feature `test-hooks`: never.
    #[cfg(not(feature = "test-hooks"))]
    #[inline]
    pub(crate) fn camera_x1_weighting(&self) -> bool {
        false
    }

    /// Without the feature `test-hooks`: never.
    #[cfg(not(feature = "test-hooks"))]
    #[inline]
    pub(crate) fn per_visit_inputs(&self) -> bool {
        false
    }

    /// Test hook: the splats' weights without light tracing's density ratio.
    #[cfg(feature = "test-hooks")]
    #[inline]
    pub(crate) fn two_way_splat_weights(&self) -> bool {
        self.two_way_splat_weights
    }

    /// Without the feature `test-hooks`: never.
    #[cfg(not(feature = "test-hooks"))]
    #[inline]
    pub(crate) fn two_way_splat_weights(&self) -> bool {
        false
    }
}

impl Renderer<'_> {
    fn budget(&self) -> Budget {
        Budget {
            camera_samples: self.settings.spp as f64,
            photons: self.settings.photons as f64,
            merge_area: (std::f64::consts::PI * (self.radius as f64).powi(2)),
            flux: luminance(self.scene.total_flux()) as f64,
        }
    }

    fn render_bdpm_pass(
        &self,
        heuristic: Heuristic,
        pass: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> PassOutput {
        self.bdpm_pass(&self.mix(heuristic), &self.settings, pass, progress, &never)
            .expect("a pass that is never stopped is complete")
            .0
    }

    /// Pass `pass` of the mix `mix` under `s` (the render's settings, or the pilot's with
    /// their own seed). With [`Mix::pilot`] it also returns each pixel's pass estimate under
    /// every candidate factor of `corrected-balance` (luminance), and reads neither the pixel
    /// table nor the factors (the pilot weighs with `balance`); otherwise that list is empty.
    /// `None` when `stop()` stopped it (asked before each chunk of photons and each row).
    fn bdpm_pass(
        &self,
        mix: &Mix<'_>,
        s: &RenderSettings,
        pass: u32,
        progress: &(dyn Fn(u64) + Sync),
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Option<(PassOutput, Vec<CandidateSums>)> {
        self.enter(Stage::Photons);
        let t_photons = std::time::Instant::now();
        let (table, correction) = if mix.pilot {
            (None, None)
        } else {
            (self.table.as_ref(), self.correction.as_ref())
        };
        let weigher_at = |x: u32, y: u32| {
            let factor = correction.map_or(1.0, |c| c.get(x, y));
            mix.weigher(table.map(|t| t.get(x, y)), factor, mix.radius_scale(x, y))
        };
        let (map, splats) = self.pass_photons(mix, s, pass, &weigher_at, stop)?;
        let prev_inputs = mix.prev_inputs(&map);
        let photon_seconds = t_photons.elapsed().as_secs_f64();
        self.leave(Stage::Photons);
        self.enter(Stage::Camera);
        let t_camera = std::time::Instant::now();
        let camera = CameraPass {
            mix,
            s,
            pass,
            map: &map,
            prev_inputs: &prev_inputs,
            weigher_at: &weigher_at,
            direct: self.direct.as_ref(),
            record: self.techniques,
        };
        let rows: Vec<Row> = (0..s.height as usize)
            .into_par_iter()
            .map(|y| {
                if stop() {
                    return None;
                }
                let row = camera.row(y);
                progress(1);
                Some(row)
            })
            .collect::<Option<_>>()?;
        self.leave(Stage::Camera);
        let pixels = s.width as usize * s.height as usize;
        let sums = Gathered::new(rows, &splats, self.techniques, mix.pilot, pixels);
        let out = PassOutput {
            estimates: sums.estimates,
            dropped: sums.dropped,
            samples: pixels as u64 * s.spp as u64,
            stage_seconds: vec![
                (Stage::Photons, photon_seconds),
                (Stage::Camera, t_camera.elapsed().as_secs_f64()),
            ],
            techniques: self.techniques.then_some(sums.techniques),
            photons_stored: map.photons().len() as u64,
            photon_map_bytes: map.memory_bytes(),
            weights: sums.weights,
        };
        Some((out, sums.candidates))
    }

    /// The photon map of pass `pass` under `s`, and with light tracing the splats of its
    /// arrivals (weighed with `weigher_at`); `None` when `stop()` stopped the tracing.
    fn pass_photons<F: Fn(u32, u32) -> Weigher + Sync>(
        &self,
        mix: &Mix<'_>,
        s: &RenderSettings,
        pass: u32,
        weigher_at: &F,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Option<(PhotonMap, Vec<Splats>)> {
        let options = TraceOptions {
            photons: s.photons,
            seed: s.seed,
            domain: Domain::Photon,
            pass,
            light_visibility: mix.needs.direct_at_x1,
            max_depth: 1024,
        };
        // Built for the largest pixel radius, which every gather's query may reach.
        let grid_radius = self.radius * mix.largest_radius_scale();
        if mix.light_tracing {
            PhotonMap::trace_visiting_until(
                self.scene,
                &options,
                grid_radius,
                |_| Splats::default(),
                |acc, a, vertices| mix.splat(a, vertices, weigher_at, acc),
                stop,
            )
        } else {
            // `PhotonMap::trace` is this with nothing visited.
            let no_visit = |_: &mut (), _: &_, _: &[_]| {};
            let traced = PhotonMap::trace_visiting_until(
                self.scene,
                &options,
                grid_radius,
                |_| (),
                no_visit,
                stop,
            )?;
            Some((traced.0, Vec::new()))
        }
    }
}

/// The camera samples of one BDPM pass, row by row ([`CameraPass::row`]).
struct CameraPass<'p, F> {
    mix: &'p Mix<'p>,
    s: &'p RenderSettings,
    pass: u32,
    map: &'p PhotonMap,
    prev_inputs: &'p [[f32; 3]],
    /// Each pixel's weigher.
    weigher_at: &'p F,
    direct: Option<&'p DirectSamples>,
    /// Keep each pixel's estimate split by technique.
    record: bool,
}

impl<F: Fn(u32, u32) -> Weigher + Sync> CameraPass<'_, F> {
    /// Image row `y`: each pixel's N_B camera samples, in batches of [`BATCH`].
    fn row(&self, y: usize) -> Row {
        let (mix, s, pass, record) = (self.mix, self.s, self.pass, self.record);
        let w = s.width as usize;
        let mut row = Row::default();
        let mut slots = Slots::default();
        let mut layout = PixelSamples::new(s);
        for x in 0..w {
            let pixel = (y * w + x) as u64;
            let mut sum = DVec3::ZERO;
            let mut tsum = Techniques::default();
            let mut csum = CandidateSums::default();
            let weigher = (self.weigher_at)(x as u32, y as u32);
            let direct_m = self.direct.map_or(1, |d| d.at(x as u32, y as u32));
            layout.start(pass, pixel);
            for first in (0..s.spp).step_by(BATCH) {
                let count = (s.spp - first).min(BATCH as u32);
                let mut jobs: [Job; BATCH] = std::array::from_fn(|i| {
                    // Past N_B the slot is unused; sample 0's numbers fill it.
                    let k = (first + i as u32).min(s.spp - 1);
                    let c = layout.sample(k);
                    let direct_extra = layout.direct_extra(k, (x as u32, y as u32), direct_m);
                    Job {
                        x: x as f32 + c.offset[0],
                        y: y as f32 + c.offset[1],
                        rng: c.rng,
                        bdf: c.bdf,
                        out: Techniques::default(),
                        pilot: CandidateSums::default(),
                        direct_extra,
                        scale: mix.radius_scale(x as u32, y as u32),
                    }
                });
                let jobs = &mut jobs[..count as usize];
                mix.sample_batch(
                    self.map,
                    self.prev_inputs,
                    jobs,
                    &mut slots,
                    &weigher,
                    &mut row.stats,
                );
                // Summed in sample order, so the pixel does not depend on the batching.
                for job in jobs.iter() {
                    let t = &job.out;
                    let value = t.total();
                    if value.is_finite() {
                        sum += value;
                        if record {
                            tsum.direct += t.direct;
                            tsum.x0_raw += t.x0_raw;
                            tsum.x0_weighted += t.x0_weighted;
                            tsum.x1_raw += t.x1_raw;
                            tsum.x1_weighted += t.x1_weighted;
                        }
                        if mix.pilot {
                            csum.add_sums(&job.pilot);
                            csum.add_to_all(f64::from(luminance(t.direct.as_vec3())));
                        }
                    } else {
                        row.dropped += 1;
                    }
                }
            }
            let n = s.spp as f64;
            row.estimates.push(sum / n);
            if record {
                row.techniques.push(Techniques {
                    direct: tsum.direct / n,
                    x0_raw: tsum.x0_raw / n,
                    x0_weighted: tsum.x0_weighted / n,
                    x1_raw: tsum.x1_raw / n,
                    x1_weighted: tsum.x1_weighted / n,
                });
            }
            if mix.pilot {
                row.candidates.push(csum.scaled(1.0 / n));
            }
        }
        row
    }
}

/// A pass's rows put together, with light tracing's splats added.
struct Gathered {
    estimates: Vec<DVec3>,
    techniques: Vec<Techniques>,
    candidates: Vec<CandidateSums>,
    dropped: u64,
    weights: WeightStats,
}

impl Gathered {
    /// The rows in row order, then the splats in photon order (so the sums do not depend on
    /// the threads); `record` keeps the technique split, `pilot` the candidates.
    fn new(rows: Vec<Row>, splats: &[Splats], record: bool, pilot: bool, pixels: usize) -> Self {
        let mut estimates = Vec::with_capacity(pixels);
        let mut techniques = Vec::with_capacity(if record { pixels } else { 0 });
        let mut candidates = Vec::new();
        let mut dropped = 0;
        let mut weights = WeightStats::default();
        for row in rows {
            estimates.extend(row.estimates);
            techniques.extend(row.techniques);
            candidates.extend(row.candidates);
            dropped += row.dropped;
            // Integer sums: the total does not depend on the order rows finish in.
            weights.add(&row.stats);
        }
        for chunk in splats {
            weights.add(&chunk.stats);
            for s in &chunk.list {
                let p = s.pixel as usize;
                let weighted = s.raw * (1.0 - s.w1) as f32;
                if !(s.raw.is_finite() && weighted.is_finite()) {
                    dropped += 1;
                    continue;
                }
                estimates[p] += weighted.as_dvec3();
                if record {
                    techniques[p].x0_raw += s.raw.as_dvec3();
                    techniques[p].x0_weighted += weighted.as_dvec3();
                }
                if pilot {
                    candidates[p].add(f64::from(luminance(s.raw)), s.w1, false);
                }
            }
        }
        Gathered {
            estimates,
            techniques,
            candidates,
            dropped,
            weights,
        }
    }
}

/// A stop that never fires ([`Renderer::new`]).
fn never() -> bool {
    false
}

/// `Err(Interrupted(stage))` when `stop()` says so.
fn unless_stopped(stop: &(dyn Fn() -> bool + Sync), stage: Stage) -> Result<(), RenderError> {
    if stop() {
        Err(RenderError::Interrupted(stage))
    } else {
        Ok(())
    }
}

/// One image row of a BDPM pass, gathered in row order.
#[derive(Default)]
struct Row {
    estimates: Vec<DVec3>,
    techniques: Vec<Techniques>,
    candidates: Vec<CandidateSums>,
    dropped: u64,
    stats: WeightStats,
}

/// What one pass produced: the per-pixel estimates and counters.
#[derive(Clone, Debug)]
pub struct PassOutput {
    /// Per-pixel pass estimate (mean of the pass's camera samples), row-major, W·m⁻²·sr⁻¹.
    pub estimates: Vec<DVec3>,
    /// Camera samples whose value was NaN or infinite (dropped: they contribute zero).
    pub dropped: u64,
    /// Camera samples taken.
    pub samples: u64,
    /// Wall time of the pass's stages (e.g. photon tracing, camera samples), seconds.
    pub stage_seconds: Vec<(Stage, f64)>,
    /// Per-pixel pass estimates split by technique, when asked for
    /// ([`Renderer::with_technique_layers`]; BDPM modes only).
    pub techniques: Option<Vec<Techniques>>,
    /// Photons stored in this pass's map (0 for `path`).
    pub photons_stored: u64,
    /// Memory of this pass's photon map, bytes (0 without one).
    pub photon_map_bytes: u64,
    /// Weight evaluations and their anomalies (BDPM modes).
    pub weights: WeightStats,
}

/// Adds a sample to a pixel sum unless it is non-finite, in which case it is counted.
#[inline]
pub(crate) fn accumulate(sum: &mut DVec3, sample: Vec3, dropped: &mut u64) {
    if sample.is_finite() {
        *sum += sample.as_dvec3();
    } else {
        *dropped += 1;
    }
}

/// Renders pass `pass` of the `path` reference: N_B jittered samples per pixel, each a pure
/// function of (seed, pass, pixel, sample). `progress` is called with the number of rows done.
pub fn render_path_pass(
    scene: &Scene,
    settings: &RenderSettings,
    pass: u32,
    progress: &(dyn Fn(u64) + Sync),
) -> PassOutput {
    debug_assert_eq!(settings.mode, Mode::Path);
    let (w, h) = (settings.width, settings.height);
    let cam = &scene.camera();
    let start = std::time::Instant::now();
    let dropped = AtomicU64::new(0);
    let mut estimates = vec![DVec3::ZERO; w as usize * h as usize];
    estimates
        .par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            let mut row_dropped = 0;
            let mut layout = PixelSamples::new(settings);
            for (x, px) in row.iter_mut().enumerate() {
                let pixel = (y * w as usize + x) as u64;
                let mut sum = DVec3::ZERO;
                layout.start(pass, pixel);
                for s in 0..settings.spp {
                    let mut c = layout.sample(s);
                    let dir = cam.ray_direction(x as f32 + c.offset[0], y as f32 + c.offset[1]);
                    let l = crate::path::trace_path_with_first(
                        scene,
                        (cam.position(), dir),
                        &mut c.rng,
                        settings.roulette_depth,
                        c.bdf,
                    );
                    accumulate(&mut sum, l, &mut row_dropped);
                }
                *px = sum / settings.spp as f64;
            }
            dropped.fetch_add(row_dropped, Ordering::Relaxed);
            progress(1);
        });
    PassOutput {
        estimates,
        dropped: dropped.into_inner(),
        samples: w as u64 * h as u64 * settings.spp as u64,
        stage_seconds: vec![(Stage::Camera, start.elapsed().as_secs_f64())],
        techniques: None,
        photons_stored: 0,
        photon_map_bytes: 0,
        weights: WeightStats::default(),
    }
}

/// Per-pixel first-hit layers for denoisers (Open Image Denoise and the like), see
/// [`first_hit_layers`].
#[derive(Clone, Debug)]
pub struct FirstHitLayers {
    /// Directional albedo µ(wo) of the surface first seen, averaged over the pixel's samples,
    /// each channel in [0, 1]; 0 where nothing is seen. Row-major.
    pub albedo: Vec<DVec3>,
    /// World-space unit shading normal at the first hit (facing the camera), averaged over the
    /// pixel's samples and renormalised; 0 where nothing is seen. Row-major.
    pub normal: Vec<DVec3>,
}

/// Traces one primary ray per camera sample of pass 0 (the same jittered positions: the
/// camera stream of (seed, 0, pixel, sample)) and records the first hit's directional albedo
/// and shading normal. Costs `spp` ray casts per pixel, independent of the radiance passes,
/// whose bits it does not touch.
pub fn first_hit_layers(scene: &Scene, settings: &RenderSettings) -> FirstHitLayers {
    let (w, h) = (settings.width as usize, settings.height as usize);
    let cam = &scene.camera();
    let spp = settings.spp.max(1);
    let mut pixels = vec![(DVec3::ZERO, DVec3::ZERO); w * h];
    pixels.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let mut layout = PixelSamples::new(settings);
        for (x, px) in row.iter_mut().enumerate() {
            let pixel = (y * w + x) as u64;
            let (mut albedo, mut normal) = (DVec3::ZERO, DVec3::ZERO);
            layout.start(0, pixel);
            for s in 0..spp {
                let [jx, jy] = layout.sample(s).offset;
                let dir = cam.ray_direction(x as f32 + jx, y as f32 + jy);
                let Some(hit) = scene
                    .geometry()
                    .intersect(cam.position(), dir, f32::INFINITY)
                else {
                    continue;
                };
                let wo = -dir;
                let sh = scene.shade(&hit, wo);
                let a = scene.bdf_at(&sh).albedo(sh.frame.to_local(wo));
                albedo += a.clamp(Vec3::ZERO, Vec3::ONE).as_dvec3();
                normal += sh.frame.n.as_dvec3();
            }
            *px = (albedo / spp as f64, normal.normalize_or_zero());
        }
    });
    let (albedo, normal) = pixels.into_iter().unzip();
    FirstHitLayers { albedo, normal }
}

/// The merge radius in force for `settings` on `scene`, metres: `radius` if given, else
/// `radius_px` times the pixel footprint `footprint` (`Scene::pixel_footprint`, passed in so
/// that a caller who has it does not trace it twice), else [`scene_default_radius`]. Checked
/// with `check_radius`.
pub fn resolve_radius(
    scene: &Scene,
    settings: &RenderSettings,
    footprint: Option<f32>,
) -> Result<f32, RenderError> {
    let r = match (settings.radius, settings.radius_px) {
        (Some(r), _) => r,
        (None, Some(k)) => k * footprint.ok_or(RenderError::NoFootprint(k))?,
        (None, None) => scene_default_radius(scene),
    };
    check_radius(r).map_err(RenderError::Radius)
}
