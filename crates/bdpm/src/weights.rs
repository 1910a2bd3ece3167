//! `bdpm weights`: the weight map of the preprint's Fig. 5. For a fixed first vertex x₀, the
//! weight w₀ = 1 − w₁(x₀, x₁) of the chosen mode at every surface point x₁ the camera sees,
//! written as a float EXR and as a false-colour PNG on a log scale with x₀ marked.
use std::path::{Path, PathBuf};

use bdpm_integrator::{
    Mode, RenderError, RenderSettings, Renderer, Setting, WeightMap, WeightTarget, estimate_memory,
    human_bytes, weightmap::weight_map_heuristic,
};
use clap::{ArgGroup, Args};
use glam::Vec3;

use bdpm_output::cli::{CliResult, Overrides, flag_of, parse_bytes, prepare, thread_pool};
use bdpm_output::colormap::{ColourMap, Legend, compose};
use bdpm_output::files::stem_of;
use bdpm_output::memory::{self, MemoryLimit};
use bdpm_output::raster::Canvas;
use bdpm_output::{exr, say};

/// Bottom of the PNG's colour scale: w₀ at or below it gets the bottom colour. 2⁻⁷, the
/// smallest value the preprint's Fig. 5 scale distinguishes.
const LOG_MIN: f64 = 0.008;
/// Tick values of the colour bar: powers of two from 2⁻⁷ to 1, rounded as labels.
const TICKS: [(f64, &str); 8] = [
    (0.0078125, "0.008"),
    (0.015625, "0.015"),
    (0.03125, "0.03"),
    (0.0625, "0.06"),
    (0.125, "0.125"),
    (0.25, "0.25"),
    (0.5, "0.5"),
    (1.0, "1"),
];
/// Colour of pixels that see no surface.
const NO_SURFACE: [u8; 3] = [0, 0, 0];
/// Colour of the cross that marks x₀: red, which viridis does not contain.
const MARK: [u8; 3] = [255, 40, 40];

/// The subcommand's help: what it writes, and the modes that have a weight map (those
/// [`weight_map_heuristic`] accepts), from the mode table.
pub(crate) fn about() -> String {
    let modes: Vec<&str> = Mode::names()
        .into_iter()
        .filter(|name| {
            let settings = RenderSettings {
                mode: Mode::parse(name).unwrap_or(Mode::Path),
                light_tracing: false,
                ..RenderSettings::default()
            };
            weight_map_heuristic(&settings).is_ok()
        })
        .collect();
    format!(
        "Map the weight w₀ = 1 − w₁ over every visible x₁ for a fixed x₀ (the preprint's \
         Fig. 5): OUT.exr (channel w0) and OUT.png (log scale 0.008–1, x₀ marked). Modes whose \
         weights depend on x₁ alone: {}",
        modes.join(", ")
    )
}

// The field docs are clap's help text, printed in a terminal: `<scene>` there is a
// placeholder, not an HTML tag.
#[allow(rustdoc::invalid_html_tags)]
/// Arguments of this subcommand.
#[derive(Args, Debug)]
#[command(group(ArgGroup::new("target").required(true).args(["x0", "pixel"])))]
pub(crate) struct WeightsArgs {
    /// Scene file (TOML, or a Mitsuba 3 scene ending in .xml).
    scene: PathBuf,
    /// x₀ as a world point X,Y,Z in metres; the camera must see it (within 1 mm + 0.1% of its
    /// distance).
    #[arg(long, value_parser = parse_point, allow_negative_numbers = true)]
    x0: Option<Vec3>,
    /// x₀ as the surface point seen through the centre of pixel X,Y (row 0 at the top).
    #[arg(long, value_parser = parse_pixel)]
    pixel: Option<(u32, u32)>,
    #[command(flatten)]
    overrides: Overrides,
    /// Output EXR path (default: out/<scene>-weights-<mode>.exr); the PNG goes beside it.
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
    /// Refuse to start when the estimated peak memory of preparing the mode's renderer (its
    /// radiance cache, pixel table and pilots; no pass is rendered) exceeds this, e.g. 8G or
    /// 512M (K, M, G, T are powers of 1024). Default: the memory available on this machine
    /// (MemAvailable of /proc/meminfo), no limit where unknown.
    #[arg(long, value_parser = parse_bytes)]
    max_memory: Option<u64>,
}

/// Parses `X,Y,Z` (metres).
fn parse_point(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|c| c.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("'{s}' is not X,Y,Z (three numbers in metres)"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(x, y, z)),
        _ => Err(format!(
            "'{s}' is not X,Y,Z (three finite numbers in metres)"
        )),
    }
}

/// Parses `X,Y` (pixel column and row).
fn parse_pixel(s: &str) -> Result<(u32, u32), String> {
    let (x, y) = s
        .split_once(',')
        .ok_or_else(|| format!("'{s}' is not X,Y"))?;
    let p = |c: &str| {
        c.trim()
            .parse::<u32>()
            .map_err(|_| format!("'{s}' is not X,Y (two pixel indices)"))
    };
    Ok((p(x)?, p(y)?))
}

/// `out/<scene>-weights-<mode>.exr`.
fn default_output(scene: &Path, mode: Mode) -> PathBuf {
    let stem = stem_of(scene, "scene");
    PathBuf::from("out").join(format!("{stem}-weights-{}.exr", mode.name()))
}

/// Position of `w0` on the PNG's log colour scale, in [0, 1].
fn log_position(w0: f64) -> f64 {
    ((w0.max(LOG_MIN) / LOG_MIN).ln() / (1.0 / LOG_MIN).ln()).clamp(0.0, 1.0)
}

/// Runs the subcommand.
pub(crate) fn run(args: WeightsArgs) -> CliResult<()> {
    let loaded = prepare(&args.scene, &args.overrides)?;
    let (scene, settings) = (loaded.scene, loaded.settings);
    let mode = settings.mode;
    // Where a mode error comes from: the flag if one was given, else the scene file.
    let mode_source = if args.overrides.mode.is_some() {
        format!("--mode {mode}")
    } else {
        format!("{}: render.mode = \"{mode}\"", args.scene.display())
    };
    // Checked before building anything (a mode's preparation can take a pass), and the
    // message says where the mode, or light tracing, came from.
    let refused = |e: RenderError| match e {
        RenderError::LightTracing(_) => {
            let flag = flag_of(Setting::LightTracing);
            format!("{}: {e} ({flag} false)", args.scene.display())
        }
        _ => format!("{mode_source}: {e}"),
    };
    weight_map_heuristic(&settings).map_err(refused)?;
    let (target, target_flag) = match (args.x0, args.pixel) {
        (Some(p), _) => (WeightTarget::Point(p), "--x0"),
        (None, Some((x, y))) => (WeightTarget::Pixel(x, y), "--pixel"),
        (None, None) => return Err("give x0 as --x0 X,Y,Z or --pixel X,Y".into()),
    };
    let exr_path = args
        .output
        .unwrap_or_else(|| default_output(&args.scene, mode))
        .with_extension("exr");
    let png_path = exr_path.with_extension("png");
    let pool = thread_pool(args.overrides.threads)?;
    memory_gate(&args.scene, &scene, &settings, &pool, args.max_memory)?;

    let renderer = pool
        .install(|| Renderer::new(&scene, &settings))
        .map_err(|e| format!("{}: {e}", args.scene.display()))?;
    let map = pool
        .install(|| renderer.weight_map(target))
        .map_err(|e| format!("{target_flag}: {e}"))?;

    let attributes = vec![
        ("version".to_string(), env!("CARGO_PKG_VERSION").to_string()),
        ("scene".into(), args.scene.display().to_string()),
        ("mode".into(), mode.name().into()),
        (
            "x0".into(),
            format!("{} {} {}", map.x0.x, map.x0.y, map.x0.z),
        ),
        (
            "x0_pixel".into(),
            format!("{} {}", map.x0_pixel.0, map.x0_pixel.1),
        ),
        ("photons_per_pass".into(), settings.photons.to_string()),
        ("spp".into(), settings.spp.to_string()),
        ("radius_m".into(), renderer.radius().to_string()),
        ("seed".into(), settings.seed.to_string()),
    ];
    exr::write_exr_single(
        &exr_path,
        (map.width, map.height),
        "w0",
        &map.w0,
        &attributes,
    )
    .map_err(|e| format!("{}: {e}", exr_path.display()))?;
    weight_png(&map)
        .and_then(|c| c.write_png(&png_path))
        .map_err(|e| format!("{}: {e}", png_path.display()))?;

    say!(
        "x0 = ({:.4}, {:.4}, {:.4}) m, seen in pixel ({}, {}); mode {}",
        map.x0.x,
        map.x0.y,
        map.x0.z,
        map.x0_pixel.0,
        map.x0_pixel.1,
        mode
    );
    let mut w: Vec<f64> = map.w0.iter().copied().filter(|v| v.is_finite()).collect();
    if w.is_empty() {
        say!("no pixel sees a surface");
    } else {
        w.sort_by(f64::total_cmp);
        let small = w.iter().filter(|v| **v <= 0.03).count();
        say!(
            "w0 over {} pixels with a surface: min {:.4}, median {:.4}, max {:.4}; {:.1}% at or below 0.03",
            w.len(),
            w[0],
            w[w.len() / 2],
            w[w.len() - 1],
            100.0 * small as f64 / w.len() as f64
        );
    }
    say!("wrote {}, {}", exr_path.display(), png_path.display());
    Ok(())
}

/// Refuses a weight map whose renderer would not fit in memory (`max_memory`, default the
/// available memory), before it is prepared: the render's estimate without the items of a
/// pass, which the weight map does not render.
fn memory_gate(
    path: &Path,
    scene: &bdpm_scene::Scene,
    settings: &RenderSettings,
    pool: &rayon::ThreadPool,
    max_memory: Option<u64>,
) -> CliResult<()> {
    let estimate = memory::without_passes(
        pool.install(|| estimate_memory(scene, settings, false)),
        settings,
    );
    let limit = MemoryLimit::of(max_memory);
    match limit.exceeded_by(estimate.total()) {
        Some(_) => Err(format!(
            "{}: the weight map needs about {} ({}), more than {}; lower {} (or raise \
             --max-memory)",
            path.display(),
            human_bytes(estimate.total()),
            memory::parts(&estimate),
            limit.describe(),
            memory::lower(estimate.scalable_largest())
        )),
        None => Ok(()),
    }
}

/// The PNG: w₀ on a log scale from 0.008 to 1 (viridis), black where no surface is seen, a red
/// cross on x₀'s pixel, and the colour bar with its ticks.
fn weight_png(map: &WeightMap) -> CliResult<Canvas> {
    let colours: Vec<[u8; 3]> = map
        .w0
        .iter()
        .map(|&w| {
            if w.is_nan() {
                NO_SURFACE
            } else {
                ColourMap::Viridis.colour(log_position(w))
            }
        })
        .collect();
    let legend = Legend {
        title: vec![
            "w₀ = 1 − w₁".into(),
            "log scale".into(),
            "+ marks x₀".into(),
        ],
        ticks: TICKS
            .iter()
            .map(|(v, l)| (log_position(*v), (*l).to_string()))
            .collect(),
    };
    let mut layout = compose(map.width, map.height, &colours, &legend, ColourMap::Viridis)?;
    // Outlined in black, so the red cross stays visible on the bright w₀ ≈ 1 pixels that
    // surround x₀.
    layout.mark(map.x0_pixel, MARK, NO_SURFACE);
    Ok(layout.canvas)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arguments_parse() {
        assert_eq!(
            parse_point("1.05, 0.4125,-0.5"),
            Ok(Vec3::new(1.05, 0.4125, -0.5))
        );
        assert!(parse_point("1,2").is_err());
        assert!(parse_point("1,2,nan").is_err());
        assert_eq!(parse_pixel("3,40"), Ok((3, 40)));
        assert!(parse_pixel("3;40").is_err());
    }

    #[test]
    fn log_scale_spans_the_ticks() {
        assert_eq!(log_position(0.0), 0.0);
        assert_eq!(log_position(0.008), 0.0);
        assert!((log_position(1.0) - 1.0).abs() < 1e-12);
        assert_eq!(log_position(7.0), 1.0);
        assert!((log_position(0.0894427191) - 0.5).abs() < 1e-9);
    }
}
