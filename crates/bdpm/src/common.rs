//! What every subcommand shares: the setting overrides, loading a scene with them, the thread
//! pool and the user-facing error type.
use std::path::{Path, PathBuf};

use bdpm_integrator::{Mode, NoiseModel, RenderSettings, Setting};
use bdpm_load::{LoadReport, load_scene};
use bdpm_scene::Scene;
use clap::Args;

/// `println!` that ignores a closed standard output (as in `bdpm render … | head`) instead of
/// panicking: the render's files are what matter, and they are written before any message.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}
pub(crate) use say;

/// An error for the user: one line, no backtrace.
pub(crate) type CliResult<T> = Result<T, String>;

/// Settings that override the scene file's `[render]` table.
#[derive(Args, Debug, Clone, Default)]
pub(crate) struct Overrides {
    /// Integrator and weight mode: path, light, bdd0, bdd1, threshold, algebraic-direct, algebraic,
    /// optimal, optimal-split, optimal-path, balance, power, camis.
    #[arg(long)]
    pub(crate) mode: Option<String>,
    /// Number of passes.
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<u32>)]
    pub(crate) passes: Option<u32>,
    /// Image size as WxH, e.g. 256x256.
    #[arg(long, value_parser = parse_resolution)]
    pub(crate) resolution: Option<(u32, u32)>,
    /// Photons emitted per pass (N_F).
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<u64>)]
    pub(crate) photons: Option<u64>,
    /// Camera samples per pixel per pass (N_B).
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<u32>)]
    pub(crate) spp: Option<u32>,
    /// Merge radius, metres.
    #[arg(long, allow_negative_numbers = true, value_parser = number)]
    pub(crate) radius: Option<f64>,
    /// Master seed of all random streams.
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<u64>)]
    pub(crate) seed: Option<u64>,
    /// Send all camera samples of a pixel through its centre (the layout the preprint's noise
    /// model assumes) instead of jittering them over the pixel.
    #[arg(long)]
    pub(crate) no_jitter: bool,
    /// Noise model of the model-based weights (algebraic-direct, algebraic, optimal,
    /// optimal-split, optimal-path): footprint
    /// (N_eff per pixel from the overlap of the samples' merge disks) or pinhole (the preprint's
    /// N_B; its weights assume every sample of a pixel shares x0).
    #[arg(long)]
    pub(crate) noise_model: Option<String>,
    /// Worker threads (default: all cores; at most 8 per core, and at least 64 allowed).
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<usize>)]
    pub(crate) threads: Option<usize>,
}

/// A whole number for a flag, with a message that says so: the parser's own ("invalid digit
/// found in string") does not tell a user that `-1` or `2.5` is the problem.
pub(crate) fn whole<T: std::str::FromStr>(s: &str) -> Result<T, String> {
    s.trim().parse().map_err(|_| {
        format!(
            "'{s}' is not a whole number in range (0 to {})",
            if size_of::<T>() == 4 {
                u32::MAX as u64
            } else {
                u64::MAX
            }
        )
    })
}

/// A real number for a flag, kept in f64 so that messages quote it as typed.
pub(crate) fn number(s: &str) -> Result<f64, String> {
    s.trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))
}

pub(crate) fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WxH"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in '{s}'"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in '{s}'"))?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!(
            "resolution '{s}' must be between 1x1 and 16384x16384"
        ));
    }
    Ok((w, h))
}

/// Applies command-line overrides to the settings loaded from the scene file.
pub(crate) fn apply_overrides(settings: &mut RenderSettings, o: &Overrides) -> CliResult<()> {
    if let Some(name) = &o.mode {
        let mode = Mode::parse(name).ok_or_else(|| {
            format!(
                "--mode: unknown mode '{name}'; expected one of {}",
                Mode::names().join(", ")
            )
        })?;
        // A scene file's `threshold_radius` stays the threshold mode's radius.
        settings.select(mode);
    }
    if let Some(p) = o.passes {
        settings.passes = p;
    }
    if let Some((w, h)) = o.resolution {
        settings.width = w;
        settings.height = h;
    }
    if let Some(n) = o.photons {
        settings.photons = n;
    }
    if let Some(n) = o.spp {
        settings.spp = n;
    }
    if let Some(r) = o.radius {
        if !(r.is_finite() && r > 0.0 && r <= f32::MAX as f64) {
            let r = if (1e-4..1e7).contains(&r.abs()) {
                format!("{r}")
            } else {
                format!("{r:e}")
            };
            return Err(format!(
                "--radius must be a positive number of metres below 3.4e38, not {r}"
            ));
        }
        settings.radius = Some(r as f32);
    }
    if o.no_jitter {
        settings.pixel_jitter = false;
    }
    if let Some(name) = &o.noise_model {
        settings.noise_model = NoiseModel::parse(name).ok_or_else(|| {
            format!(
                "--noise-model: unknown model '{name}'; expected one of {}",
                NoiseModel::ALL_NAMES.join(", ")
            )
        })?;
    }
    if let Some(s) = o.seed {
        settings.seed = s;
    }
    // The scene file's values were validated by the loader, so an error here is a flag's.
    settings.validate().map_err(|e| {
        let flag = match e.setting() {
            Setting::Width | Setting::Height => "--resolution".to_string(),
            Setting::Passes => "--passes".into(),
            Setting::Photons => "--photons".into(),
            Setting::Spp => "--spp".into(),
            Setting::Radius => "--radius".into(),
            other => format!("render.{}", other.key()),
        };
        format!("{flag}: {e}")
    })
}

pub(crate) fn thread_pool(threads: Option<usize>) -> CliResult<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        if t == 0 {
            return Err("--threads must be at least 1".into());
        }
        // Thousands of threads on a few cores only queue for them (10000 spent minutes
        // starting up); the cap leaves room to oversubscribe for tests of determinism.
        let cores = std::thread::available_parallelism().map_or(1, usize::from);
        let max = (8 * cores).max(64);
        if t > max {
            return Err(format!(
                "--threads {t} is more than this machine can use: at most {max} (8 per core, {cores} cores)"
            ));
        }
        b = b.num_threads(t);
    }
    b.build()
        .map_err(|e| format!("cannot start worker threads: {e}"))
}

/// Mean over pixels of one pass's estimates, per channel.
pub(crate) fn image_mean(estimates: &[glam::DVec3]) -> [f64; 3] {
    let sum: glam::DVec3 = estimates.iter().copied().sum();
    (sum / estimates.len().max(1) as f64).to_array()
}

pub(crate) fn default_output(scene: &Path) -> PathBuf {
    let stem = scene.file_stem().map(|s| s.to_string_lossy().into_owned());
    PathBuf::from("out").join(format!("{}.exr", stem.unwrap_or_else(|| "render".into())))
}

/// A scene loaded from `path` with `overrides` applied (the camera resized to match).
pub(crate) struct Prepared {
    /// The scene, camera at the final resolution.
    pub(crate) scene: Scene,
    /// The final settings.
    pub(crate) settings: RenderSettings,
    /// The scene file's `output`, if any.
    pub(crate) output: Option<PathBuf>,
    /// Facts from loading.
    pub(crate) report: LoadReport,
}

/// Loads a scene file and applies the overrides.
pub(crate) fn prepare(path: &Path, overrides: &Overrides) -> CliResult<Prepared> {
    let loaded = load_scene(path).map_err(|e| e.to_string())?;
    let mut scene = loaded.scene;
    let mut settings = loaded.settings;
    apply_overrides(&mut settings, overrides)?;
    if (scene.camera().width(), scene.camera().height()) != (settings.width, settings.height) {
        scene
            .set_resolution(settings.width, settings.height)
            .map_err(|e| format!("--resolution: {e}"))?;
    }
    Ok(Prepared {
        scene,
        settings,
        output: loaded.output,
        report: loaded.report,
    })
}
