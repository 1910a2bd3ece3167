//! What every preparation and pass of a renderer reads: the scene, the settings in force, the
//! heuristic and the merge radius, checked once (`Setup::new`); and the merge radius in force
//! for settings on a scene ([`resolve_radius`]).
use bdpm_bdf::luminance;
use bdpm_cache::RadianceCache;
use bdpm_mis::{Budget, Heuristic, NoiseModel};
use bdpm_scene::Scene;
use bdpm_settings::{RenderSettings, check_radius};

use crate::error::RenderError;
#[cfg(feature = "test-hooks")]
use crate::mix::Hooks;
use crate::mix::Mix;
use crate::products::Products;
use crate::radius::RadiusMap;

/// A scene and checked settings: the constants of a renderer, from which its preparations
/// decide whether they are needed and its mixes are made.
pub(crate) struct Setup<'a> {
    pub(crate) scene: &'a Scene,
    /// The caller's settings with the merge radius in force (metres; `radius_px` resolved).
    pub(crate) settings: RenderSettings,
    /// The heuristic in force (BDPM modes): the mode's, with the weight clamp in force.
    pub(crate) heuristic: Option<Heuristic>,
    /// Merge radius r, metres.
    pub(crate) radius: f32,
    /// The scene's pixel footprint at this resolution, metres (`None`: the camera sees nothing).
    pub(crate) footprint: Option<f32>,
    /// Photons of the noise model's own radiance cache, once asked for
    /// (`Renderer::with_model_cache`; crate::prepare::model_cache).
    pub(crate) model_cache_photons: Option<u64>,
    /// The test-only switches of its mixes (only with the feature `test-hooks`).
    #[cfg(feature = "test-hooks")]
    pub(crate) hooks: Hooks,
}

impl<'a> Setup<'a> {
    /// Checks `settings` against `scene` (validation, the camera's image size, the merge
    /// radius) and resolves the radius in force.
    pub(crate) fn new(scene: &'a Scene, settings: &RenderSettings) -> Result<Self, RenderError> {
        settings.validate()?;
        let camera = (scene.camera().width(), scene.camera().height());
        if camera != (settings.width, settings.height) {
            return Err(RenderError::Resolution {
                camera,
                settings: (settings.width, settings.height),
            });
        }
        if scene.has_delta() && settings.light_traced() {
            return Err(RenderError::LightTracingDelta);
        }
        let footprint = scene.pixel_footprint();
        let radius = resolve_radius(scene, settings, footprint)?;
        Ok(Self::with_radius(scene, settings, radius, footprint))
    }

    /// The setup a memory estimate reads, before any check: an unusable radius (which
    /// [`Setup::new`] refuses) is taken as the scene's default.
    pub(crate) fn unchecked(scene: &'a Scene, settings: &RenderSettings) -> Self {
        let footprint = scene.pixel_footprint();
        let radius = resolve_radius(scene, settings, footprint)
            .unwrap_or_else(|_| scene_default_radius(scene));
        Self::with_radius(scene, settings, radius, footprint)
    }

    fn with_radius(
        scene: &'a Scene,
        s: &RenderSettings,
        radius: f32,
        footprint: Option<f32>,
    ) -> Self {
        // `None` means the scene's default or a radius in pixels; the copy holds the value in
        // force, in metres. The mode stays as given: `heuristic` is the mode's with the clamp
        // in force (RenderSettings::weight_clamp).
        let mut settings = s.clone();
        settings.radius = Some(radius);
        settings.radius_px = None;
        Setup {
            scene,
            heuristic: settings.heuristic(),
            settings,
            radius,
            footprint,
            model_cache_photons: None,
            #[cfg(feature = "test-hooks")]
            hooks: Hooks::default(),
        }
    }

    /// Whether the weights use per-pixel N_eff from footprints (method.md §12): the footprint
    /// noise model with jittered samples (without jitter ρ = 1, so N_eff = N_B).
    pub(crate) fn footprint_model(&self) -> bool {
        self.settings.noise_model == NoiseModel::Footprint && self.settings.pixel_jitter
    }

    /// The budget every weight of the render shares (N_B, N_F, S = π r², Φ).
    pub(crate) fn budget(&self) -> Budget {
        Budget {
            camera_samples: self.settings.spp as f64,
            photons: self.settings.photons as f64,
            merge_area: (std::f64::consts::PI * (self.radius as f64).powi(2)),
            flux: luminance(self.scene.total_flux()) as f64,
        }
    }

    /// The mix of mode `heuristic` with this setup's constants and the radiance cache and
    /// radius map among `products`.
    pub(crate) fn mix<'p>(&'p self, heuristic: Heuristic, products: &'p Products) -> Mix<'p> {
        let mut needs = heuristic.needs();
        // `bdd1` has no BDD=0 part to sample.
        let light_tracing = self.settings.light_tracing && needs.photons_at_x0;
        // BDD=1 cannot sample a path with a mirror or glass between x₀ and x₁ or the light:
        // the merge at x₀ takes those whole (`Mix::after_delta`), in `bdd1` too.
        needs.photons_at_x0 |= self.scene.has_delta();
        Mix {
            scene: self.scene,
            heuristic,
            needs,
            fixed_w1: heuristic.fixed_w1(),
            budget: self.budget(),
            inv_area: 1.0 / (std::f32::consts::PI * self.radius * self.radius),
            radius: self.radius,
            radius_map: products.get::<RadiusMap>(),
            cache: products.get::<RadianceCache>(),
            pilot: false,
            light_tracing,
            #[cfg(feature = "test-hooks")]
            hooks: self.hooks,
        }
    }
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

/// The default merge radius for `scene`: its largest bounding-box extent / 1600, metres.
pub fn scene_default_radius(scene: &Scene) -> f32 {
    let (lo, hi) = scene.geometry().bounds();
    bdpm_settings::default_radius((hi - lo).max_element())
}
