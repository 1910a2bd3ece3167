//! What every subcommand shares: the setting overrides (the one place where command-line
//! flags change the scene file's settings, where a setting's error is named by its flag, and
//! where they are written back as arguments for the accumulation file), loading a scene with
//! them (through the loader), the flag parsers, the thread pool and the progress bar.
use std::path::{Path, PathBuf};

use bdpm_integrator::settings::{RadiusInput, SettingsError};
use bdpm_integrator::{PartialSettings, Setting};
use bdpm_load::{LoadError, LoadOptions, LoadedScene, load_scene_overridden};
use bdpm_mis::Needs;
use bdpm_settings::{Mode, Written, limits};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use crate::files::stem_of;
pub use crate::flags::flag_of;
use crate::memory::MemoryLimit;

/// `println!` that ignores a closed standard output (as in `bdpm render … | head`) instead of
/// panicking: the render's files are what matter, and they are written before any message.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// `eprintln!` that ignores a closed or failing standard error instead of panicking: the
/// message is dropped and the command's exit code still tells what happened. The one way the
/// driver, the lab and the signal handler write to standard error (a panic in the signal
/// handler's thread would leave a second interrupt without effect).
#[macro_export]
macro_rules! say_err {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

/// An error for the user: one line, no backtrace.
pub type CliResult<T> = Result<T, String>;

/// Settings that override the scene file's `[render]` table: the flags of the settings that
/// [`PartialSettings`] holds (`--no-jitter` for `pixel_jitter = false`), plus `--threads`.
/// Kept apart from [`PartialSettings`] because the flags have their own names, parsers, help
/// texts and spelling (`WxH`), and are written back as arguments for the accumulation file
/// ([`Overrides::to_args`]); they are applied through it ([`Overrides::partial`]), so every
/// check and message of a value is the scene file's.
#[derive(Args, Debug, Clone, Default)]
pub struct Overrides {
    /// Integrator and weight mode; the help lists every name of the mode table
    /// ([`bdpm_settings::Mode::names`]).
    #[arg(long, help = mode_help())]
    pub mode: Option<String>,
    /// Number of passes.
    #[arg(long, allow_negative_numbers = true, value_parser = count::<u32>(Setting::Passes))]
    pub passes: Option<u32>,
    /// Image size as WxH, e.g. 256x256.
    #[arg(long, value_parser = parse_resolution)]
    pub resolution: Option<(u32, u32)>,
    /// Photons emitted per pass (N_F).
    #[arg(long, allow_negative_numbers = true, value_parser = count::<u64>(Setting::Photons))]
    pub photons: Option<u64>,
    /// Camera samples per pixel per pass (N_B).
    #[arg(long, allow_negative_numbers = true, value_parser = count::<u32>(Setting::Spp))]
    pub spp: Option<u32>,
    /// Merge radius: metres (0.01) or pixel footprints (1.2px: the median footprint of the
    /// pixels' first hits at this resolution)
    // Taken as typed, a leading '-' included (`-1px` is a value, not flags), and checked where
    // a scene file's radius is (`PartialSettings::apply`), with its messages.
    #[arg(long, allow_hyphen_values = true)]
    pub radius: Option<String>,
    /// Master seed of all random streams.
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<u64>)]
    pub seed: Option<u64>,
    /// Send all camera samples of a pixel through its centre (the layout the preprint's noise
    /// model assumes) instead of jittering them over the pixel.
    #[arg(long)]
    pub no_jitter: bool,
    /// Noise model of the model-based weights: footprint or pinhole; the help names the modes
    /// it applies to, those whose heuristic needs N_B (`Needs::effective_samples`).
    #[arg(long, help = noise_model_help())]
    pub noise_model: Option<String>,
    /// How a pixel's camera samples are placed within a pass: stratified (default; one
    /// jittered sample per stratum of the pixel and of the direction at x0) or independent
    /// (every sample uniform, the preprint's layout).
    #[arg(long)]
    pub sampler: Option<String>,
    /// Sample BDD=0's paths by light tracing, each photon connected to the camera (true), or
    /// by merging photons at the camera's first vertex (false).
    #[arg(long)]
    pub light_tracing: Option<bool>,
    /// A merge radius per 8×8-pixel block from a 1-pass pilot's split by technique: ½× where
    /// BDD=1 carries under 30 % of the block's image, 1.4× above 60 % (true), or one radius for
    /// the image (false).
    #[arg(long)]
    pub adaptive_radius: Option<bool>,
    /// Photons traced for the radiance cache of the model-based weights (default: N_F).
    #[arg(long, allow_negative_numbers = true, value_parser = count::<u64>(Setting::CachePhotons))]
    pub cache_photons: Option<u64>,
    /// Angular bins per radiance-cache cell side of the model-based weights (default 1; one
    /// bin is used in a Lambert-only scene).
    #[arg(long, allow_negative_numbers = true, value_parser = count::<u32>(Setting::CacheBins))]
    pub cache_bins: Option<u32>,
    /// Backward rays per pixel of the weights' A/B table (default: 16 under the footprint
    /// noise model with jitter, else 64).
    #[arg(long, allow_negative_numbers = true, value_parser = count::<u32>(Setting::PixelTableRays))]
    pub pixel_table_rays: Option<u32>,
    /// The most direct-light samples per camera sample where the direct light varies steeply
    /// over a pixel (default 16; 1 turns the extra samples off).
    #[arg(long, allow_negative_numbers = true, value_parser = count::<u32>(Setting::DirectBoost))]
    pub direct_boost: Option<u32>,
    /// Worker threads (default: all cores; at most 8 per core, and at least 64 allowed).
    #[arg(long, allow_negative_numbers = true, value_parser = whole::<usize>)]
    pub threads: Option<usize>,
}

/// The help of `--mode`: every mode name, in the mode table's order.
fn mode_help() -> String {
    format!("Integrator and weight mode: {}", Mode::names().join(", "))
}

/// The names of the weighting modes whose heuristic needs `what` of [`Needs`], in the mode
/// table's order.
fn modes_that(what: impl Fn(&Needs) -> bool) -> Vec<&'static str> {
    Mode::names()
        .into_iter()
        .filter(|name| {
            Mode::parse(name)
                .and_then(|m| m.kind())
                .is_some_and(|k| what(&k.heuristic().needs()))
        })
        .collect()
}

/// The help of `--noise-model`, naming the modes whose weights read N_B (the modes it
/// applies to) from the mode table.
fn noise_model_help() -> String {
    format!(
        "Noise model of the model-based weights ({}): footprint (N_eff per pixel from the \
         overlap of the samples' merge disks) or pinhole (the preprint's N_B; its weights \
         assume every sample of a pixel shares x0)",
        modes_that(|n| n.effective_samples).join(", ")
    )
}

/// A whole number for a flag, with a message that says so: the parser's own ("invalid digit
/// found in string") does not tell a user that `-1` or `2.5` is the problem.
pub fn whole<T: std::str::FromStr>(s: &str) -> Result<T, String> {
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
pub fn number(s: &str) -> Result<f64, String> {
    s.trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))
}

/// A count setting's flag (`--passes`, `--photons`, …): a whole number in the setting's range
/// ([`Setting::range`]), with the scene file's message for a value of the wrong kind or out
/// of range (`-1 is outside [1, 4294967295]`).
pub fn count<T: TryFrom<i128>>(
    setting: Setting,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static {
    move |s| {
        let mut p = PartialSettings::default();
        p.set(setting.key(), &Written::from_text(s))
            .map_err(|e| e.message)?;
        let value = match setting {
            Setting::Passes => p.passes.map(u64::from),
            Setting::Photons => p.photons,
            Setting::Spp => p.spp.map(u64::from),
            Setting::CachePhotons => p.cache_photons,
            Setting::CacheBins => p.cache_bins.map(u64::from),
            Setting::PixelTableRays => p.pixel_table_rays.map(u64::from),
            Setting::DirectBoost => p.direct_boost.map(u64::from),
            _ => None,
        };
        value
            .and_then(|v| T::try_from(i128::from(v)).ok())
            .ok_or_else(|| format!("'{s}' is not a value of {setting}"))
    }
}

/// Image size `WxH` for a flag, each side 1 to [`limits::MAX_RESOLUTION`] pixels.
pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let max = limits::MAX_RESOLUTION;
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WxH (e.g. 256x256)"))?;
    let side = |v: &str, which: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|v| (1..=max).contains(v))
            .ok_or_else(|| format!("the {which} in '{s}' is not a whole number in [1, {max}]"))
    };
    Ok((side(w, "width")?, side(h, "height")?))
}

/// The message for an error in the settings the flags `o` put over the scene file `scene`
/// (or in the final combination of the two): the setting named by its flag, and a
/// combination by where each of its settings came from (`--light-tracing true and
/// --no-jitter: …`, or the scene file's keys when no flag set them).
fn override_message(o: &Overrides, scene: &Path, e: &SettingsError) -> String {
    match e {
        SettingsError::LightTracingWithoutJitter => {
            let from = |flag: Option<&str>, key: &str| match flag {
                Some(f) => f.to_string(),
                None => format!("{} sets {key}", scene.display()),
            };
            let tracing = from(
                o.light_tracing.map(|_| "--light-tracing true"),
                "light_tracing = true",
            );
            let jitter = from(o.no_jitter.then_some("--no-jitter"), "pixel_jitter = false");
            if o.light_tracing.is_none() && !o.no_jitter {
                format!("{}: render.light_tracing: {e}", scene.display())
            } else {
                format!("{tracing} and {jitter}: {e}")
            }
        }
        other => format!("{}: {other}", flag_of(other.setting())),
    }
}

/// The worker threads of a command: `threads` of them (`--threads`), or one per core.
pub fn thread_pool(threads: Option<usize>) -> CliResult<rayon::ThreadPool> {
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

/// The render's EXR when neither `-o` nor the scene file names one: `out/<scene>.exr`.
pub fn default_output(scene: &Path) -> PathBuf {
    PathBuf::from("out").join(format!("{}.exr", stem_of(scene, "render")))
}

/// Loads a scene file with the overrides put over its `[render]` table
/// ([`bdpm_load::load_scene_overridden`]: the scene file's checks, then the final settings
/// checked together once, the camera at the final resolution), refusing a scene whose
/// textures, glTF buffers or geometry would not fit in the available memory before
/// allocating them. An error in an override names its flag.
pub fn prepare(path: &Path, overrides: &Overrides) -> CliResult<LoadedScene> {
    prepare_within(path, overrides, MemoryLimit::of(None))
}

/// [`prepare`] with the loader's memory check against `limit`.
pub fn prepare_within(
    path: &Path,
    overrides: &Overrides,
    limit: MemoryLimit,
) -> CliResult<LoadedScene> {
    let options = LoadOptions {
        memory_limit: limit.for_loader(),
    };
    load_scene_overridden(path, &options, &overrides.partial()).map_err(|e| match e {
        LoadError::Override { path, source } => override_message(overrides, &path, &source),
        LoadError::Resolution { source, .. } => format!("--resolution: {source}"),
        other => other.to_string(),
    })
}

impl Overrides {
    /// The settings these flags give, in the shape of a scene file's `[render]` table.
    pub fn partial(&self) -> PartialSettings {
        PartialSettings {
            mode: self.mode.clone(),
            passes: self.passes,
            resolution: self.resolution.map(|(w, h)| vec![w, h]),
            photons: self.photons,
            spp: self.spp,
            radius: self.radius.clone().map(RadiusInput::Text),
            seed: self.seed,
            pixel_jitter: self.no_jitter.then_some(false),
            noise_model: self.noise_model.clone(),
            sampler: self.sampler.clone(),
            light_tracing: self.light_tracing,
            adaptive_radius: self.adaptive_radius,
            cache_photons: self.cache_photons,
            cache_bins: self.cache_bins,
            pixel_table_rays: self.pixel_table_rays,
            direct_boost: self.direct_boost,
            ..PartialSettings::default()
        }
    }

    /// The overrides that shape the image as command-line arguments (`--threads` does not).
    pub fn to_args(&self) -> Vec<String> {
        let o = self;
        let mut v = Vec::new();
        let mut push = |k: &str, val: String| {
            v.push(k.to_string());
            v.push(val);
        };
        if let Some(m) = &o.mode {
            push("--mode", m.clone());
        }
        if let Some((w, h)) = o.resolution {
            push("--resolution", format!("{w}x{h}"));
        }
        if let Some(n) = o.photons {
            push("--photons", n.to_string());
        }
        if let Some(n) = o.spp {
            push("--spp", n.to_string());
        }
        if let Some(r) = &o.radius {
            push("--radius", r.clone());
        }
        if let Some(s) = o.seed {
            push("--seed", s.to_string());
        }
        if let Some(m) = &o.noise_model {
            push("--noise-model", m.clone());
        }
        if let Some(m) = &o.sampler {
            push("--sampler", m.clone());
        }
        if let Some(b) = o.light_tracing {
            push("--light-tracing", b.to_string());
        }
        if let Some(b) = o.adaptive_radius {
            push("--adaptive-radius", b.to_string());
        }
        if let Some(n) = o.cache_photons {
            push("--cache-photons", n.to_string());
        }
        if let Some(n) = o.cache_bins {
            push("--cache-bins", n.to_string());
        }
        if let Some(n) = o.pixel_table_rays {
            push("--pixel-table-rays", n.to_string());
        }
        if let Some(n) = o.direct_boost {
            push("--direct-boost", n.to_string());
        }
        if o.no_jitter {
            v.push("--no-jitter".into());
        }
        v
    }

    /// Parses arguments made by [`Overrides::to_args`] back into overrides.
    pub fn from_args(args: &[String]) -> Result<Overrides, String> {
        use clap::Parser;
        #[derive(Parser)]
        struct Only {
            #[command(flatten)]
            o: Overrides,
        }
        Only::try_parse_from(std::iter::once("bdpm".to_string()).chain(args.iter().cloned()))
            .map(|p| p.o)
            .map_err(|e| format!("bad stored overrides {args:?}: {}", e.kind()))
    }
}

/// A positive finite number for a flag.
pub fn positive(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("'{s}' is not a positive number"))
    }
}

/// A byte count with an optional binary suffix (K, M, G, T; `B` or `iB` may follow).
pub fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let t = t
        .strip_suffix("iB")
        .or_else(|| t.strip_suffix('B'))
        .unwrap_or(t);
    let (digits, shift) = match t.chars().last().map(|c| c.to_ascii_uppercase()) {
        Some('K') => (&t[..t.len() - 1], 10),
        Some('M') => (&t[..t.len() - 1], 20),
        Some('G') => (&t[..t.len() - 1], 30),
        Some('T') => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    let bad = || format!("'{s}' is not a size such as 8G, 512M or 1000000");
    let value: f64 = digits.trim().parse().map_err(|_| bad())?;
    let bytes = value * (1u64 << shift) as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(bad());
    }
    Ok(bytes as u64)
}

/// A progress bar on stderr drawn with `template` (indicatif's syntax), `len` units long
/// (`None`: a spinner with no end), or a hidden one when `quiet`.
pub fn progress_bar(quiet: bool, len: Option<u64>, template: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = match len {
        Some(n) => ProgressBar::new(n),
        None => ProgressBar::no_length(),
    };
    bar.set_style(
        ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}

#[cfg(test)]
mod tests {
    use super::*;
    use bdpm_integrator::RenderSettings;

    /// The flags put over `settings` as the loader puts them over a scene file's, with the
    /// command line's messages.
    fn apply_overrides(
        settings: &mut RenderSettings,
        o: &Overrides,
        scene: &Path,
    ) -> CliResult<()> {
        o.partial()
            .apply(settings)
            .and_then(|()| settings.validate())
            .map_err(|e| override_message(o, scene, &e))
    }

    #[test]
    fn overrides_round_trip() {
        let o = Overrides {
            mode: Some("optimal".into()),
            resolution: Some((16, 8)),
            photons: Some(100),
            radius: Some("0.1".into()),
            seed: Some(7),
            no_jitter: true,
            sampler: Some("independent".into()),
            cache_photons: Some(500_000),
            cache_bins: Some(9),
            pixel_table_rays: Some(8),
            ..Default::default()
        };
        let back = Overrides::from_args(&o.to_args()).unwrap();
        assert_eq!(back.to_args(), o.to_args());
        assert_eq!(
            (back.cache_photons, back.cache_bins, back.pixel_table_rays),
            (Some(500_000), Some(9), Some(8))
        );
        let mut s = RenderSettings::default();
        apply_overrides(&mut s, &o, Path::new("s.toml")).unwrap();
        assert_eq!(
            (s.cache_photons, s.cache_bins, s.pixel_table_rays),
            (Some(500_000), 9, Some(8))
        );
        assert_eq!(back.radius.as_deref(), Some("0.1"));
        let px = Overrides {
            radius: Some("1.25px".into()),
            ..Default::default()
        };
        let back = Overrides::from_args(&px.to_args()).unwrap();
        assert_eq!(back.radius.as_deref(), Some("1.25px"));
    }

    /// The flags go through the scene file's checks, and an error names the flag.
    #[test]
    fn overrides_apply_as_partial_settings() {
        let o = Overrides {
            mode: Some("threshold".into()),
            resolution: Some((16, 8)),
            radius: Some("2px".into()),
            no_jitter: true,
            ..Default::default()
        };
        let mut s = RenderSettings::default();
        apply_overrides(&mut s, &o, Path::new("s.toml")).unwrap();
        assert_eq!((s.width, s.height, s.radius_px), (16, 8, Some(2.0)));
        assert!(!s.pixel_jitter);
        assert_eq!(s.mode.name(), "threshold");
        let error = |o: Overrides| {
            apply_overrides(&mut RenderSettings::default(), &o, Path::new("s.toml")).unwrap_err()
        };
        let e = error(Overrides {
            noise_model: Some("wide".into()),
            ..Default::default()
        });
        assert!(
            e.starts_with("--noise-model: unknown noise model 'wide'; expected one of"),
            "{e}"
        );
        let e = error(Overrides {
            radius: Some("1e300".into()),
            ..Default::default()
        });
        assert!(e.starts_with("--radius: 1e300 is beyond"), "{e}");
        let e = error(Overrides {
            mode: Some("fast".into()),
            ..Default::default()
        });
        assert!(e.starts_with("--mode: unknown mode 'fast'; expected one of path, light"));
        let e = error(Overrides {
            light_tracing: Some(true),
            no_jitter: true,
            ..Default::default()
        });
        assert!(
            e.starts_with("--light-tracing true and --no-jitter: light tracing"),
            "{e}"
        );
        let e = error(Overrides {
            direct_boost: Some(0),
            ..Default::default()
        });
        assert!(e.starts_with("--direct-boost: 0 is outside [1, 64]"), "{e}");
    }

    #[test]
    fn byte_counts_parse() {
        assert_eq!(parse_bytes("8G"), Ok(8 << 30));
        assert_eq!(parse_bytes("512MiB"), Ok(512 << 20));
        assert_eq!(parse_bytes("1000"), Ok(1000));
        assert!(parse_bytes("-1").is_err());
        assert!(positive("0").is_err());
    }
}
