//! The renderer: a scene and settings made ready to render passes. It checks the settings,
//! runs the preparations the mode needs (crate::prepare's plan) and renders any pass on demand.
use bdpm_cache::RadianceCache;
use bdpm_mis::Heuristic;
use bdpm_scene::Scene;

use crate::camera::render_path_pass;
use crate::correction::Correction;
use crate::direct::DirectSamples;
use crate::error::RenderError;
use crate::estimates::PassOutput;
use crate::mix::Mix;
use crate::one_bounce::OneBounceSamples;
use crate::pass::{PassContext, TechniqueSplit, bdpm_pass};
use crate::prepare::{
    BuildContext, MODEL_CACHE_PHOTONS, ModelCache, PLAN, PixelTablePrep, Planned, unless_stopped,
};
use crate::products::Products;
use crate::radius::RadiusMap;
use crate::setup::Setup;
use crate::stage::{self, Stage, StageProbe, StageReport, never};
use crate::table::PixelTable;
use bdpm_settings::{Mode, RenderSettings};

/// A merge radius above this fraction of the scene's largest extent draws a warning
/// ([`Renderer::warnings`]): the density estimate then averages photons over a large part of
/// the scene.
pub const LARGE_RADIUS_FRACTION: f32 = 0.1;

/// A scene and settings made ready to render passes: validates the settings, builds what the
/// mode needs once (and nothing it does not need), then renders any pass on demand.
pub struct Renderer<'a> {
    setup: Setup<'a>,
    /// What the preparations built, by type.
    products: Products,
    /// Which entries of the plan have run.
    ran: [bool; PLAN.len()],
    stages: Vec<StageReport>,
    techniques: bool,
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
        let mut renderer = Renderer {
            setup: Setup::new(scene, settings)?,
            products: Products::default(),
            ran: [false; PLAN.len()],
            stages: Vec::new(),
            techniques: false,
            probe: None,
        };
        renderer.run_plan(stop)?;
        Ok(renderer)
    }

    /// Runs, in order, every entry of the plan that the setup needs and that has not run.
    fn run_plan(&mut self, stop: &(dyn Fn() -> bool + Sync)) -> Result<(), RenderError> {
        for (i, entry) in PLAN.iter().enumerate() {
            if !self.ran[i] && entry.needed(&self.setup) {
                self.run(*entry, stop)?;
                self.ran[i] = true;
            }
        }
        Ok(())
    }

    /// Builds `entry` (asking `stop` first), keeps its product and reports its stage.
    fn run(
        &mut self,
        entry: &dyn Planned,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<(), RenderError> {
        let stage = entry.stage(&self.setup);
        unless_stopped(stop, stage)?;
        let start = std::time::Instant::now();
        let cx = BuildContext {
            setup: &self.setup,
            products: &self.products,
            stop,
            probe: self.probe,
        };
        let Some(built) = entry.run(&cx)? else {
            return Ok(());
        };
        if let Some((bytes, detail)) = built.report {
            self.stages.push(StageReport {
                stage,
                seconds: start.elapsed().as_secs_f64(),
                bytes,
                detail,
            });
        }
        self.products.put(built.product);
        Ok(())
    }

    /// Each pixel's scale of the merge radius, with `adaptive_radius`.
    pub fn radius_map(&self) -> Option<&RadiusMap> {
        self.products.get()
    }

    /// The direct-light samples per camera sample of each pixel, when some pixel takes more
    /// than one.
    pub fn direct_samples(&self) -> Option<&DirectSamples> {
        self.products.get()
    }

    /// The x₁ per camera sample of each pixel for the one-bounce paths at a glossy x₀
    /// (crate::one_bounce), when some pixel takes more than one.
    pub fn one_bounce_samples(&self) -> Option<&OneBounceSamples> {
        self.products.get()
    }

    /// `corrected-balance`'s per-pixel factors, when the mode uses them.
    pub fn correction(&self) -> Option<&Correction> {
        self.products.get()
    }

    /// The per-pixel weight inputs (ρ, N_eff, A, B), when the mode uses them.
    pub fn pixel_table(&self) -> Option<&PixelTable> {
        self.products.get()
    }

    /// Builds the noise model's radiance cache for [`Renderer::predict_variance`], which reads
    /// L_d and b for every mode: [`Self::with_model_cache`] of [`MODEL_CACHE_PHOTONS`].
    pub fn with_model_inputs(self) -> Self {
        self.with_model_cache(MODEL_CACHE_PHOTONS)
    }

    /// [`Self::with_model_inputs`] with a cache of at least `photons` photons (and
    /// [`crate::prepare::MODEL_CACHE_BINS`] bins), or the weights' own cache where that is as fine. The
    /// weights keep reading theirs, so rendering is unchanged and the model weighs exactly as
    /// the render does; the cache is that of [`crate::prepare::model_cache_settings`] with the same
    /// `photons`. Built once: a later call keeps the first cache.
    pub fn with_model_cache(mut self, photons: u64) -> Self {
        self.setup.model_cache_photons.get_or_insert(photons);
        // Never stopped, so never an error.
        let built = self.run_plan(&never);
        debug_assert!(built.is_ok());
        self
    }

    /// The radiance cache the noise model reads: its own, or the weights' where that is as
    /// fine ([`Self::with_model_inputs`]); None before that.
    pub(crate) fn model_cache(&self) -> Option<&RadianceCache> {
        let model: &ModelCache = self.products.get()?;
        model.cache(self.products.get())
    }

    /// The noise model's cache of the caustic light alone (a scene with mirrors or glass,
    /// after [`Self::with_model_inputs`]); None otherwise.
    pub(crate) fn caustic_cache(&self) -> Option<&RadianceCache> {
        let model: &ModelCache = self.products.get()?;
        model.caustic()
    }

    /// Whether the weights use per-pixel N_eff from footprints (method.md §12).
    pub(crate) fn footprint_model(&self) -> bool {
        self.setup.footprint_model()
    }

    /// The mix of mode `h` with this renderer's constants.
    pub(crate) fn mix(&self, heuristic: Heuristic) -> Mix<'_> {
        self.setup.mix(heuristic, &self.products)
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
        self.setup.hooks.camera_x1_weighting = on;
        self
    }

    /// Test-only: compute the weight inputs of a photon's previous vertex at each visit of a
    /// merge at x₀ instead of once per photon per pass; the image bits must not change. Only
    /// with the feature `test-hooks`.
    #[cfg(feature = "test-hooks")]
    #[doc(hidden)]
    pub fn with_per_visit_inputs(mut self, on: bool) -> Self {
        self.setup.hooks.per_visit_inputs = on;
        self
    }

    /// Test-only: with light tracing, weigh the splats with the merge's two-way w₁ (without
    /// light tracing's density ratio) while the camera side uses the light-traced one: the two
    /// sides of a path then disagree, and a test must see the bias. Only with the feature
    /// `test-hooks`.
    #[cfg(feature = "test-hooks")]
    #[doc(hidden)]
    pub fn with_two_way_splat_weights(mut self, on: bool) -> Self {
        self.setup.hooks.two_way_splat_weights = on;
        self
    }

    /// Merges with `map`'s radius per pixel instead of the pilot's (or of one radius), the
    /// pixel table built again for it: e.g. other weights on a render's own map (the noise
    /// model's headroom floor, whose own pilot, of other weights, would draw another), or
    /// blocks at every scale where the pilot would not put them (tests). `map` must be of this
    /// renderer's image size.
    pub fn with_radius_map(mut self, map: RadiusMap) -> Self {
        let (w, h) = (self.setup.settings.width, self.setup.settings.height);
        assert!(
            map.fits(w, h),
            "a radius map of another image size than {w}x{h}"
        );
        self.products.put(Box::new(map));
        if self.pixel_table().is_some() {
            // Never stopped, so never an error.
            let built = self.run(&PixelTablePrep::AT_PIXEL_RADII, &never);
            debug_assert!(built.is_ok());
        }
        self
    }

    /// The scene this renderer draws.
    pub fn scene(&self) -> &Scene {
        self.setup.scene
    }

    /// The merge radius r in use, metres.
    pub fn radius(&self) -> f32 {
        self.setup.radius
    }

    /// The scene's pixel footprint at this resolution, metres (`Scene::pixel_footprint`):
    /// what a radius of "1px" is. `None` when the camera sees nothing.
    pub fn pixel_footprint(&self) -> Option<f32> {
        self.setup.footprint
    }

    /// The settings this renderer uses: the caller's, with the merge radius in force.
    pub fn settings(&self) -> &RenderSettings {
        &self.setup.settings
    }

    /// The heuristic the BDPM modes weigh with: the mode's, with the weight clamp in force
    /// ([`RenderSettings::heuristic`]); `None` for `path` and `light`.
    pub fn heuristic(&self) -> Option<Heuristic> {
        self.setup.heuristic
    }

    /// Whether BDD=0's paths are sampled by light tracing: `light_tracing` set and a mode
    /// with a BDD=0 part (not `bdd1`, `path` or `light`).
    pub fn light_traced(&self) -> bool {
        self.setup.settings.light_traced()
    }

    /// The preparatory stages that ran, with their cost.
    pub fn stages(&self) -> &[StageReport] {
        &self.stages
    }

    /// Renders pass number `pass` (0-based). `progress` is called with units of work done
    /// (one per image row); a pass has [`Renderer::work_per_pass`] units.
    pub fn render_pass(&self, pass: u32, progress: &(dyn Fn(u64) + Sync)) -> PassOutput {
        let (scene, settings) = (self.setup.scene, &self.setup.settings);
        match settings.mode {
            // The references' stages interleave; the probe sees the pass as one stage.
            Mode::Path | Mode::Light => {
                stage::enter(self.probe, Stage::Pass);
                let out = if settings.mode == Mode::Path {
                    render_path_pass(scene, settings, pass, progress)
                } else {
                    let direct = self.direct_samples();
                    crate::light::render_light_pass(scene, settings, direct, pass, progress)
                };
                stage::leave(self.probe, Stage::Pass);
                out
            }
            Mode::Bdpm(_) => self.render_bdpm_pass(pass, progress),
        }
    }

    /// Pass `pass` of the mix, with the technique split when asked for.
    fn render_bdpm_pass(&self, pass: u32, progress: &(dyn Fn(u64) + Sync)) -> PassOutput {
        let h = self.setup.heuristic.expect("a BDPM mode has a heuristic");
        let mix = self.mix(h);
        let cx = PassContext {
            setup: &self.setup,
            products: &self.products,
            probe: self.probe,
        };
        let s = &self.setup.settings;
        let complete = "a pass that is never stopped is complete";
        if self.techniques {
            let (mut out, split) =
                bdpm_pass::<TechniqueSplit>(&cx, &mix, s, pass, progress, &never).expect(complete);
            out.techniques = Some(split);
            out
        } else {
            bdpm_pass::<()>(&cx, &mix, s, pass, progress, &never)
                .expect(complete)
                .0
        }
    }

    /// Reports each pass stage's start and end to `probe` from now on (see [`StageProbe`]).
    pub fn set_stage_probe(&mut self, probe: &'a dyn StageProbe) {
        self.probe = Some(probe);
    }

    /// Warnings known before the first pass, one line each: a light within the ray offset of
    /// a surface ([`Scene::lights_near_surfaces`]), a merge radius that is a large part of the
    /// scene (above [`LARGE_RADIUS_FRACTION`] of its largest extent).
    pub fn warnings(&self) -> Vec<String> {
        let scene = self.setup.scene;
        let mut warnings: Vec<String> = (scene.lights_near_surfaces().iter())
            .map(ToString::to_string)
            .collect();
        let (lo, hi) = scene.geometry().bounds();
        let extent = (hi - lo).max_element();
        let r = self.setup.radius;
        if matches!(self.setup.settings.mode, Mode::Bdpm(_)) && r > LARGE_RADIUS_FRACTION * extent {
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
        self.setup.settings.height as u64
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicU32, Ordering};

    use bdpm_settings::{Mode, RenderSettings};

    use super::Renderer;
    use crate::error::RenderError;
    use crate::stage::Stage;

    /// The stages a preparation of `mode` is interrupted in, stopped at each ask of its stop
    /// flag in turn, until one that is never stopped completes.
    fn interrupted_stages(mode: &str, adaptive_radius: bool) -> Vec<Stage> {
        let scene = crate::inputs::tests::open_box(false);
        let settings = RenderSettings {
            width: 8,
            height: 8,
            photons: 3000,
            cache_photons: Some(10_000),
            pixel_table_rays: Some(4),
            radius: Some(0.05),
            mode: Mode::parse(mode).expect("a mode"),
            adaptive_radius,
            ..RenderSettings::default()
        };
        let mut stages = Vec::new();
        for after in 0.. {
            let asked = AtomicU32::new(0);
            let stop = || asked.fetch_add(1, Ordering::SeqCst) >= after;
            match Renderer::new_until(&scene, &settings, &stop) {
                Ok(_) => break,
                Err(RenderError::Interrupted(stage)) if stages.last() != Some(&stage) => {
                    stages.push(stage)
                }
                Err(RenderError::Interrupted(_)) => {}
                Err(e) => panic!("{mode}: {e}"),
            }
            assert!(after < 100_000, "{mode}: still stopped after {after} asks");
        }
        stages
    }

    #[test]
    fn a_set_stop_flag_interrupts_each_preparation_in_its_stage() {
        // A flag set from the start stops the first stage before any work.
        let scene = crate::inputs::tests::open_box(false);
        let settings = RenderSettings {
            width: 8,
            height: 8,
            mode: Mode::parse("optimal").expect("a mode"),
            ..RenderSettings::default()
        };
        let stopped = Renderer::new_until(&scene, &settings, &|| true).err();
        assert_eq!(
            stopped,
            Some(RenderError::Interrupted(Stage::RadianceCache))
        );
        // Stopped later, the plan's stages in order.
        assert_eq!(
            interrupted_stages("optimal", true),
            [
                Stage::RadianceCache,
                Stage::PixelTable,
                Stage::RadiusMap,
                Stage::PixelTable,
                Stage::DirectSamples
            ]
        );
        assert_eq!(
            interrupted_stages("corrected-balance", false),
            [Stage::BalanceCorrection, Stage::DirectSamples]
        );
        assert_eq!(interrupted_stages("path", false), []);
    }
}
