//! The reference image of `bdpm study`: read from a given EXR, or rendered once with the
//! `light` mode (unbiased, and far faster to converge than `path` on the Cornell scenes,
//! method.md §10) and cached in the study's output directory by a hash of everything that
//! determines it.
use std::path::{Path, PathBuf};
use std::time::Instant;

use bdpm_integrator::{Film, Mode, RenderSettings, Renderer};
use bdpm_load::fnv1a;
use bdpm_output::cli::progress_bar;
use bdpm_output::exr::{ExrLayer, write_exr};
use bdpm_output::files::stem_of;
use bdpm_scene::Scene;
use glam::DVec3;

/// Seed offset of the reference render, so that its random streams are independent of the
/// study's (the streams are keyed by the seed).
pub(crate) const SEED_OFFSET: u64 = 12345;

/// A reference image and what is known about its own error.
#[derive(Clone, Debug)]
pub(crate) struct Reference {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// Mean radiance per pixel, W·m⁻²·sr⁻¹.
    pub(crate) mean: Vec<DVec3>,
    /// Standard error of the mean per pixel, when the file has it (`stderr.R/G/B`).
    pub(crate) stderr: Option<Vec<DVec3>>,
    /// Where it came from, for the report.
    pub(crate) path: PathBuf,
    /// How it was made ("read from …", "rendered …", "cached …").
    pub(crate) origin: String,
    /// The file's `bdpm.*` text attributes (empty for a fresh render).
    pub(crate) attributes: Vec<(String, String)>,
}

/// The settings of the reference render for a study with `study` settings.
pub(crate) fn reference_settings(
    study: &RenderSettings,
    passes: u32,
    photons: u64,
) -> RenderSettings {
    let mut s = study.clone();
    s.mode = Mode::Light;
    s.passes = passes;
    s.photons = photons;
    s.seed = study.seed.wrapping_add(SEED_OFFSET);
    // `light` merges nothing: the radius does not change it, so studies at several radii share
    // one cached reference.
    s.radius = None;
    s.radius_px = None;
    s
}

/// The cache path of a reference in the study's directory `dir`:
/// `dir/reference-<stem>-<W>x<H>-<hash>.exr`, the hash over the scene hash (the scene file and
/// the meshes, buffers and images it references, [`bdpm_output::accum::scene_hash`]) and
/// every reference setting.
pub(crate) fn cache_path(
    dir: &Path,
    scene_path: &Path,
    scene_hash: &str,
    settings: &RenderSettings,
) -> PathBuf {
    let mut key = scene_hash.as_bytes().to_vec();
    key.extend_from_slice(format!("{settings:?}").as_bytes());
    let stem = stem_of(scene_path, "scene");
    dir.join(format!(
        "reference-{stem}-{}x{}-{:016x}.exr",
        settings.width,
        settings.height,
        fnv1a(&key)
    ))
}

/// Reads the RGB mean (channels `R`, `G`, `B`) and, when present, the `stderr.R/G/B` layer of
/// an EXR file.
pub(crate) fn read_exr(path: &Path) -> Result<Reference, String> {
    let layer = ExrLayer::read(path)?;
    let (w, h) = (layer.width as usize, layer.height as usize);
    let find = |name: &str| layer.channel(name).map(<[f64]>::to_vec);
    let rgb = |prefix: &str| -> Option<Vec<DVec3>> {
        let [r, g, b] = ["R", "G", "B"].map(|c| find(&format!("{prefix}{c}")));
        let (r, g, b) = (r?, g?, b?);
        Some(
            r.iter()
                .zip(&g)
                .zip(&b)
                .map(|((r, g), b)| DVec3::new(*r, *g, *b))
                .collect(),
        )
    };
    let mean = rgb("").ok_or_else(|| {
        format!(
            "{}: EXR has no R, G, B channels in its first layer",
            path.display()
        )
    })?;
    if mean.len() != w * h {
        return Err(format!(
            "{}: channel size does not match the image",
            path.display()
        ));
    }
    Ok(Reference {
        width: w as u32,
        height: h as u32,
        mean,
        stderr: rgb("stderr."),
        path: path.to_path_buf(),
        origin: String::new(),
        attributes: layer.attributes.clone(),
    })
}

/// The cached reference at `path` if it exists, else a fresh `light` render of `settings`
/// written there.
pub(crate) fn cached_or_render(
    scene: &Scene,
    scene_hash: &str,
    settings: &RenderSettings,
    path: &Path,
    pool: &rayon::ThreadPool,
    quiet: bool,
) -> Result<Reference, String> {
    if path.exists() {
        let mut r = read_exr(path)?;
        r.origin = format!("cached {}", path.display());
        return Ok(r);
    }
    let renderer = pool
        .install(|| Renderer::new(scene, settings))
        .map_err(|e| format!("reference: {e}"))?;
    let bar = progress_bar(
        quiet,
        Some(settings.passes as u64 * renderer.work_per_pass()),
        "{prefix:>16} [{elapsed_precise}] {bar:32} {percent:>3}% (eta {eta})",
    );
    bar.set_prefix("reference");
    if !quiet {
        bdpm_output::say_err!(
            "reference: rendering {} passes of `light` (N_F = {}, N_B = {}) to cache as {}",
            settings.passes,
            settings.photons,
            settings.spp,
            path.display()
        );
    }
    let start = Instant::now();
    let mut film = Film::new(settings.width, settings.height);
    for pass in 0..settings.passes {
        let out = pool.install(|| renderer.render_pass(pass, &|n| bar.inc(n)));
        film.add_pass(&out.estimates, out.dropped);
        if pass == 0 && settings.passes > 1 && !quiet {
            let first = start.elapsed().as_secs_f64();
            bar.suspend(|| {
                bdpm_output::say_err!(
                    "reference: its first pass took {first:.2} s: about {:.1} s for all {} \
                     (give --reference FILE, or fewer --reference-passes, to skip or shorten it)",
                    first * settings.passes as f64,
                    settings.passes
                )
            });
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let attrs = vec![
        ("mode".to_string(), "light".to_string()),
        ("passes".to_string(), settings.passes.to_string()),
        ("photons".to_string(), settings.photons.to_string()),
        ("spp".to_string(), settings.spp.to_string()),
        ("seed".to_string(), settings.seed.to_string()),
        ("seconds".to_string(), format!("{seconds:.1}")),
        ("scene_hash".to_string(), scene_hash.to_string()),
    ];
    write_exr(path, &film, &attrs).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(Reference {
        width: settings.width,
        height: settings.height,
        // Rounded to f32 as in the file, so a cached and a fresh reference give the same numbers.
        mean: film.mean().iter().map(|v| v.as_vec3().as_dvec3()).collect(),
        stderr: Some(
            film.standard_error()
                .iter()
                .map(|v| v.as_vec3().as_dvec3())
                .collect(),
        ),
        path: path.to_path_buf(),
        origin: format!(
            "rendered in {seconds:.0} s and cached as {}",
            path.display()
        ),
        attributes: attrs,
    })
}
