//! The command line's name for each render setting, shared by the messages of the settings'
//! errors (`cli`) and of the memory gates (`memory`).

use bdpm_integrator::Setting;

/// The flag that sets `setting` (a typed error's or memory item's setting, named as the
/// command line names it).
pub fn flag_of(setting: Setting) -> &'static str {
    match setting {
        Setting::Width | Setting::Height | Setting::Resolution => "--resolution",
        Setting::Passes => "--passes",
        Setting::Photons => "--photons",
        Setting::Spp => "--spp",
        Setting::Radius => "--radius",
        Setting::Mode => "--mode",
        Setting::NoiseModel => "--noise-model",
        Setting::Sampler => "--sampler",
        Setting::CachePhotons => "--cache-photons",
        Setting::CacheBins => "--cache-bins",
        Setting::PixelTableRays => "--pixel-table-rays",
        Setting::DirectBoost => "--direct-boost",
        Setting::AdaptiveRadius => "--adaptive-radius",
        Setting::LightTracing => "--light-tracing",
        // No flag sets it; only a scene file's value reaches here.
        Setting::ThresholdRadius => "render.threshold_radius",
    }
}
