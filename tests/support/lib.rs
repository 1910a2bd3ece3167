//! Shared helpers for the workspace integration tests: loading the repository's scenes at
//! small settings, rendering a film, the sphere-furnace analytic answer, and per-pixel
//! statistics against a reference.

use std::f32::consts::PI;
use std::path::{Path, PathBuf};

use bdpm_geometry::{Geometry, Kernel, TriangleMesh};

use bdpm_integrator::{Film, Mode, RenderSettings, Renderer};
use bdpm_load::load_scene;
use bdpm_scene::Scene;
use glam::{DVec3, Vec3};

/// Absolute path of a file in the repository's `scenes/` folder.
pub fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

/// Loads `scenes/<name>` and resizes its camera to `width` × `height`. The settings take the
/// library's default sampler (stratified): the tests' tolerances were set with it, and the
/// preprint files' independent layout is there to reproduce the preprint's figures.
pub fn load(name: &str, width: u32, height: u32) -> (Scene, RenderSettings) {
    let loaded = load_scene(&scene_path(name)).unwrap_or_else(|e| panic!("{e}"));
    let mut scene = loaded.scene;
    let mut settings = loaded.settings;
    settings.sampler = RenderSettings::default().sampler;
    scene
        .set_resolution(width, height)
        .expect("valid resolution");
    settings.width = width;
    settings.height = height;
    (scene, settings)
}

/// Renders all passes of `settings` into a film.
pub fn render(scene: &Scene, settings: &RenderSettings) -> Film {
    let renderer = Renderer::new(scene, settings).unwrap_or_else(|e| panic!("{e}"));
    render_with(&renderer)
}

/// Renders all passes with a prepared renderer.
pub fn render_with(renderer: &Renderer<'_>) -> Film {
    let s = renderer.settings();
    let mut film = Film::new(s.width, s.height);
    for pass in 0..s.passes {
        let out = renderer.render_pass(pass, &|_| {});
        film.add_pass(&out.estimates, out.dropped);
    }
    film
}

/// Settings with a mode and pass layout.
pub fn with_mode(
    settings: &RenderSettings,
    mode: &str,
    passes: u32,
    spp: u32,
    photons: u64,
) -> RenderSettings {
    // Like `--mode`: a threshold mode uses the settings' threshold radius.
    RenderSettings {
        passes,
        spp,
        photons,
        mode: Mode::parse(mode).unwrap_or_else(|| panic!("unknown mode {mode}")),
        ..settings.clone()
    }
}

/// The sphere furnace's parameters (method.md §10), read back from the loaded scene.
pub struct Furnace {
    /// Lambert albedo k of the inner surface.
    pub albedo: f64,
    /// Light flux Φ per channel, W.
    pub flux: f64,
    /// Light position, m.
    pub light: DVec3,
    /// Sphere radius R, m.
    pub radius: f64,
}

impl Furnace {
    /// Reads k, Φ, the light and R from a loaded sphere-furnace scene (the radius from its area
    /// is not used: the analytic formula is for the sphere the mesh approximates).
    pub fn of(scene: &Scene) -> Furnace {
        assert_eq!(scene.lights().len(), 1);
        let k = scene.materials()[0].bdf.kd().x as f64;
        let (lo, hi) = scene.geometry().bounds();
        Furnace {
            albedo: k,
            flux: scene.lights()[0].flux.x as f64,
            light: scene.lights()[0].position.as_dvec3(),
            radius: ((hi - lo).max_element() / 2.0) as f64,
        }
    }

    /// Uniform indirect irradiance E_ind = kΦ/((1 − k)·4πR²), W·m⁻².
    pub fn indirect_irradiance(&self) -> f64 {
        let k = self.albedo;
        k * self.flux / ((1.0 - k) * 4.0 * std::f64::consts::PI * self.radius * self.radius)
    }

    /// Radiance leaving surface point `p` with unit normal `n` (facing the inside):
    /// k/π·(E₀(p) + E_ind), W·m⁻²·sr⁻¹.
    pub fn radiance(&self, p: DVec3, n: DVec3) -> f64 {
        let to = self.light - p;
        let d2 = to.length_squared();
        let cos = (n.dot(to) / d2.sqrt()).max(0.0);
        let e0 = self.flux * cos / (4.0 * std::f64::consts::PI * d2);
        self.albedo / std::f64::consts::PI * (e0 + self.indirect_irradiance())
    }

    /// The exact pixel values: each pixel's footprint averaged over an s × s grid of rays cast
    /// against the actual mesh (so the comparison sees the same facets as the render).
    pub fn image(&self, scene: &Scene, s: u32) -> Vec<f64> {
        let cam = &scene.camera();
        let mut out = Vec::with_capacity((cam.width() * cam.height()) as usize);
        for y in 0..cam.height() {
            for x in 0..cam.width() {
                let mut sum = 0.0;
                for j in 0..s {
                    for i in 0..s {
                        let fx = x as f32 + (i as f32 + 0.5) / s as f32;
                        let fy = y as f32 + (j as f32 + 0.5) / s as f32;
                        let d = cam.ray_direction(fx, fy);
                        let h = scene
                            .geometry()
                            .intersect(cam.position(), d, f32::INFINITY)
                            .expect("closed sphere");
                        let n = if h.ng.dot(-d) < 0.0 { -h.ng } else { h.ng };
                        sum += self.radiance(h.p.as_dvec3(), n.as_dvec3());
                    }
                }
                out.push(sum / (s * s) as f64);
            }
        }
        out
    }
}

/// Comparison of a film's first channel with per-pixel exact values.
#[derive(Debug)]
pub struct Agreement {
    /// (mean of film − mean of exact) / mean of exact.
    pub mean_relative_error: f64,
    /// Fraction of pixels with |film − exact| ≤ k·(standard error).
    pub within: f64,
    /// The image mean's standard error, relative to the exact mean.
    pub mean_relative_se: f64,
}

/// Compares channel 0 of `film` with `exact` per pixel at `k` standard errors.
pub fn agreement(film: &Film, exact: &[f64], k: f64) -> Agreement {
    let mean = film.mean();
    let se = film.standard_error();
    let n = exact.len() as f64;
    let m_film: f64 = mean.iter().map(|v| v.x).sum::<f64>() / n;
    let m_exact: f64 = exact.iter().sum::<f64>() / n;
    let within = mean
        .iter()
        .zip(&se)
        .zip(exact)
        .filter(|((m, s), e)| (m.x - *e).abs() <= k * s.x)
        .count();
    let var_mean: f64 = se.iter().map(|s| s.x * s.x).sum::<f64>() / (n * n);
    Agreement {
        mean_relative_error: (m_film - m_exact) / m_exact,
        within: within as f64 / n,
        mean_relative_se: var_mean.sqrt() / m_exact,
    }
}

/// Per-pixel agreement of two films (e.g. a mode against a reference), channel by channel:
/// fraction of pixel channels with |a − b| ≤ k·√(se_a² + se_b²), and the relative difference of
/// the image means with its standard error (a pixel's channels taken as fully correlated).
pub fn films_agree(a: &Film, b: &Film, k: f64) -> (f64, f64, f64) {
    let (ma, mb) = (a.mean(), b.mean());
    let (sa, sb) = (a.standard_error(), b.standard_error());
    let mut within = 0usize;
    let mut total = 0usize;
    let (mut sum_a, mut sum_b, mut var) = (0.0f64, 0.0f64, 0.0f64);
    for i in 0..ma.len() {
        // A pixel's three channels come from the same paths: their errors add as if fully
        // correlated, (Σ_c s_c)², the bound that holds whatever their correlation. Summed as
        // independent they understated the mean's standard error up to √3-fold (a grey scene).
        let mut pixel_s = 0.0;
        for c in 0..3 {
            let s = (sa[i][c].powi(2) + sb[i][c].powi(2)).sqrt();
            if (ma[i][c] - mb[i][c]).abs() <= k * s {
                within += 1;
            }
            total += 1;
            sum_a += ma[i][c];
            sum_b += mb[i][c];
            pixel_s += s;
        }
        var += pixel_s * pixel_s;
    }
    (
        within as f64 / total as f64,
        (sum_a - sum_b) / sum_b,
        var.sqrt() / sum_b,
    )
}

/// Luminance helper for tests.
pub fn lum(v: Vec3) -> f32 {
    0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z
}

/// A rayon pool of exactly `threads` workers, for the benchmarks' 1- and 2-thread runs.
pub fn thread_pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("cannot start the benchmark's worker threads")
}

/// Latitude bands of the benchmarks' UV sphere.
pub const SPHERE_STACKS: u32 = 256;
/// Longitude segments of the benchmarks' UV sphere; 2·STACKS·SLICES − 2·SLICES = 130,560
/// triangles.
pub const SPHERE_SLICES: u32 = 256;

/// A UV sphere (radius 1 m, centre 1.05 m above the floor, smooth vertex normals, material 0)
/// on a 4 m × 4 m floor quad (flat, material 1). Triangles that collapse at the poles are left
/// out, so none is degenerate.
pub fn sphere_on_floor() -> TriangleMesh {
    let centre = Vec3::new(0.0, 1.05, 0.0);
    let mut sphere = TriangleMesh::default();
    for i in 0..=SPHERE_STACKS {
        let theta = PI * i as f32 / SPHERE_STACKS as f32;
        for j in 0..=SPHERE_SLICES {
            let phi = 2.0 * PI * j as f32 / SPHERE_SLICES as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            sphere.positions.push(centre + n);
            sphere.normals.push(n);
        }
    }
    let vertex = |i: u32, j: u32| i * (SPHERE_SLICES + 1) + j;
    for i in 0..SPHERE_STACKS {
        for j in 0..SPHERE_SLICES {
            // Counter-clockwise seen from outside: along the longitude, then down the latitude.
            let (a, b) = (vertex(i, j), vertex(i, j + 1));
            let (c, d) = (vertex(i + 1, j + 1), vertex(i + 1, j));
            if i > 0 {
                sphere.indices.push([a, b, c]);
            }
            if i + 1 < SPHERE_STACKS {
                sphere.indices.push([a, c, d]);
            }
        }
    }
    sphere.materials = vec![0; sphere.indices.len()];
    let mut mesh = TriangleMesh::default();
    mesh.push_rect(Vec3::ZERO, 2.0 * Vec3::Z, 2.0 * Vec3::X, 1);
    mesh.append(&sphere);
    mesh
}

/// The same triangles (flat, with their materials) as `geometry`, built for `kernel`. Surface
/// sampling does not depend on the kernel, so the benchmarks draw the same queries on it.
pub fn with_kernel(geometry: &Geometry, kernel: Kernel) -> Geometry {
    let mut mesh = TriangleMesh::default();
    for prim in 0..geometry.triangle_count() as u32 {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(geometry.vertices(prim));
        mesh.indices.push([base, base + 1, base + 2]);
        mesh.materials.push(geometry.material(prim));
    }
    Geometry::with_kernel(mesh, kernel).expect("valid mesh")
}

/// The radius map of a `side` × `side` image whose 8 × 8 blocks, in row order, have BDD=1
/// carrying `shares` of their image (`RadiusMap::from_techniques`' rule picks each block's
/// scale: under 0.3 → ½ r, up to 0.6 → r, above → 1.4 r).
pub fn block_map(side: u32, shares: &[f64]) -> bdpm_integrator::radius::RadiusMap {
    let blocks_per_row = side.div_ceil(8);
    let techniques: Vec<bdpm_integrator::Techniques> = (0..side * side)
        .map(|i| {
            let (x, y) = (i % side, i / side);
            let share = shares[((y / 8) * blocks_per_row + x / 8) as usize];
            bdpm_integrator::Techniques {
                direct: DVec3::splat(1.0 - share),
                x1_weighted: DVec3::splat(share),
                ..bdpm_integrator::Techniques::default()
            }
        })
        .collect();
    bdpm_integrator::radius::RadiusMap::from_techniques(side, side, &techniques)
}
