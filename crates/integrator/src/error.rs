//! Why a render cannot start, or a query of a renderer cannot be answered.
use glam::Vec3;

use crate::stage::Stage;
use bdpm_settings::{Mode, RadiusError, SettingsError};

/// Why a render cannot start, or why a query of a renderer (weight map, noise prediction)
/// cannot be answered. `Display` keeps one line that says what is wrong; callers tell the
/// cases apart by variant, never by the message.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// A setting is out of range or inconsistent ([`bdpm_settings::RenderSettings::validate`]).
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
        "mode '{0}' weighs each light path by its incoming direction at x1, so it has no map over x1 alone; a mode whose weights depend on x1 alone has one (e.g. optimal)"
    )]
    PerLightPathWeights(&'static str),
    /// The mode (`path`, `light`) has no noise model.
    #[error("mode '{0}' has no noise model to predict")]
    NoNoiseModel(Mode),
    /// The render samples BDD=0 by light tracing (`light_tracing`), which the noise model and
    /// the weight maps (both of the merge at x₀) do not describe.
    #[error(
        "light_tracing = true: mode '{0}' then samples BDD=0 by light tracing, which the noise model and the weight maps (both of the merge at x0) do not describe; set light_tracing = false"
    )]
    LightTracing(&'static str),
    /// Light tracing in BDD=0's place with mirrors or glass in the scene: it cannot sample the
    /// paths seen through them (its connections end at the camera), which the merge at x₀ does.
    #[error(
        "light_tracing = true with mirror or dielectric materials: light tracing cannot sample what is seen through them (the merge at x0 can); set light_tracing = false"
    )]
    LightTracingDelta,
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
    /// The preparation was stopped ([`crate::Renderer::new_until`]) during this stage.
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
