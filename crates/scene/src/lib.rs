//! The in-memory scene of bdpm: geometry, materials, point lights and a pinhole camera, plus
//! the shading helpers that every integrator shares (two-sided shading frames, ray spawning,
//! exact direct light from point lights).
//!
//! Units: metres, watts; radiance in W·m⁻²·sr⁻¹; a point light's flux Φ in W per RGB channel,
//! its intensity Φ/(4π) in W·sr⁻¹.
//!
//! Architecture invariant: no file IO and no format knowledge (TOML and glTF live in
//! `bdpm-load`); no photons, weights or films.
//!
//! ```
//! use bdpm_scene::{Camera, PointLight, Scene};
//! use bdpm_geometry::{Geometry, TriangleMesh};
//! use bdpm_bdf::Bdf;
//! use glam::{Vec2, Vec3};
//! // A 2 m × 2 m floor at y = 0 facing +y, lit from 1 m above.
//! let mut mesh = TriangleMesh::default();
//! mesh.push_rect(Vec3::ZERO, Vec3::Z, Vec3::X, 0);
//! let scene = Scene::one_material(
//!     Geometry::new(mesh).unwrap(),
//!     Bdf::lambert(Vec3::splat(0.5)).unwrap(),
//!     vec![PointLight { position: Vec3::new(0.0, 1.0, 0.0), flux: Vec3::ONE }],
//!     Camera::look_at(Vec3::new(0.0, 1.0, -2.0), Vec3::ZERO, Vec3::Y, 40.0, 64, 64).unwrap(),
//! ).unwrap();
//! assert_eq!(scene.total_flux(), Vec3::ONE);
//! ```

mod camera;
mod delta;
mod emission_texture;
mod emitters;
pub mod spherical;
#[cfg(test)]
mod test_stats;
mod texture;
mod traits;
mod vertex;

pub use camera::Camera;
pub use delta::{DeltaStep, DeltaWalk, MAX_DELTA_CHAIN};
pub use emission_texture::{EMISSION_PICK_FLOOR, EmissionTextures};
pub use emitters::{
    AreaLightEnd, Emitter, EmitterPhoton, EmitterSample, MASKED_EMITTERS, SPHERICAL_MAX,
    SPHERICAL_MIN, cosine_hemisphere, power_heuristic,
};
pub use texture::{
    SceneTextures, TexelImage, Texture, TextureError, Wrap, srgb_to_linear, srgb8_to_linear,
};
// The plain data the photon tracer, the cache and the weights share lives in bdpm-core.
pub use bdpm_core::{MASKED_LIGHTS, PointLight, Shading, WeightVertex};

use std::borrow::Cow;
use std::fmt;

use bdpm_bdf::{Bdf, luminance};
use bdpm_geometry::{Frame, Geometry, Hit};
use glam::{Vec2, Vec3};

/// A named scattering model.
///
/// Invariant (kept by [`Material::new`]): a smooth material has `delta: None` and its model in
/// `bdf`; a mirror or dielectric has its model in `delta` and a black `bdf` (kd = 0), so that
/// code which only knows non-delta surfaces sees it as absorbing, never as a wrong reflector.
#[derive(Clone, Debug)]
pub struct Material {
    /// Name from the scene file (for reports and overrides).
    pub name: String,
    /// The non-delta model; black for a delta material.
    pub bdf: Bdf,
    /// The delta model (a mirror or a dielectric), or `None` for a smooth material.
    pub delta: Option<bdpm_bdf::Material>,
    /// Emitted radiance Le, W·m⁻²·sr⁻¹ per channel (zero for a material that does not emit):
    /// cosine emission from the front side of its triangles (the side the winding normal
    /// points to), or from both with `two_sided_emission`.
    pub emission: Vec3,
    /// Emits from both sides of its triangles.
    pub two_sided_emission: bool,
}

impl Material {
    /// A material named `name` of the model `model`: smooth (a [`Bdf`]) or delta.
    pub fn new(name: impl Into<String>, model: impl Into<bdpm_bdf::Material>) -> Material {
        let name = name.into();
        match model.into() {
            bdpm_bdf::Material::Smooth(bdf) => Material {
                name,
                bdf,
                delta: None,
                emission: Vec3::ZERO,
                two_sided_emission: false,
            },
            delta => Material {
                name,
                bdf: Bdf::lambert(Vec3::ZERO).expect("kd = 0 is a valid Lambert albedo"),
                delta: Some(delta),
                emission: Vec3::ZERO,
                two_sided_emission: false,
            },
        }
    }

    /// The material emitting radiance `emission` (W·m⁻²·sr⁻¹ per channel) from the front side
    /// of its triangles, or from both with `two_sided`.
    pub fn with_emission(mut self, emission: Vec3, two_sided: bool) -> Material {
        self.emission = emission;
        self.two_sided_emission = two_sided;
        self
    }

    /// True iff the material emits light (some channel of its emission is positive).
    #[inline]
    pub fn emits(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// True iff the material is a mirror or a dielectric.
    #[inline]
    pub fn is_delta(&self) -> bool {
        self.delta.is_some()
    }
}

/// Why a set of parts cannot form a scene.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneError {
    /// A triangle names a material index that does not exist.
    MissingMaterial {
        /// The index.
        material: u32,
        /// Number of materials given.
        count: usize,
    },
    /// No light, or all lights and emitters have zero flux: every image would be black.
    NoLight,
    /// A material's emission is not finite or has a negative channel.
    BadEmission {
        /// Index of the material.
        material: usize,
    },
    /// A light's position or flux is not finite, or a flux is negative.
    BadLight {
        /// Index of the light.
        index: usize,
    },
    /// The camera's parameters do not define a view.
    BadCamera(CameraError),
    /// Textures given for more materials than exist, or texture coordinates not one triple
    /// per triangle while some material has a texture.
    BadTextures {
        /// Materials with a texture slot given.
        textures: usize,
        /// Triangles with texture coordinates given.
        texcoords: usize,
    },
}

/// Why a camera's parameters do not define a view ([`SceneError::BadCamera`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraError {
    /// Position, target or up is not finite.
    NotFinite,
    /// The target equals the position: no viewing direction.
    TargetIsPosition,
    /// The up vector is parallel to the viewing direction.
    UpParallel,
    /// The vertical field of view is outside (0, 179) degrees.
    FieldOfView,
    /// Width or height is 0.
    Resolution,
}

impl fmt::Display for CameraError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CameraError::NotFinite => "position, target and up must be finite",
            CameraError::TargetIsPosition => "target equals position",
            CameraError::UpParallel => "up is parallel to the viewing direction",
            CameraError::FieldOfView => "vertical fov must be in (0, 179) degrees",
            CameraError::Resolution => "resolution must be at least 1×1",
        })
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::MissingMaterial { material, count } => {
                write!(
                    f,
                    "a triangle uses material {material} but only {count} are defined"
                )
            }
            Self::NoLight => write!(f, "the scene has no light with positive flux"),
            Self::BadEmission { material } => write!(
                f,
                "material {material} has a negative or non-finite emission"
            ),
            Self::BadLight { index } => {
                write!(
                    f,
                    "light {index} has a non-finite position or a negative/non-finite flux"
                )
            }
            Self::BadCamera(why) => write!(f, "camera: {why}"),
            Self::BadTextures {
                textures,
                texcoords,
            } => write!(
                f,
                "{textures} texture slots or {texcoords} texture-coordinate triples do not fit the materials and triangles"
            ),
        }
    }
}

impl std::error::Error for SceneError {}

/// A point light nearer a surface than that surface's ray offset
/// ([`bdpm_geometry::Geometry::spawn_offset`]), found by [`Scene::lights_near_surfaces`].
///
/// Such a light is not lost or leaked: which side of the surface it lies on is decided once,
/// the same for its photons and its shadow rays (`Geometry::occluded`). But the light it casts
/// on that surface near it (irradiance ∝ 1/distance²) lands on hit points that are themselves
/// placed only to within an offset (held one offset inside their triangle's edges, left one
/// offset off the surface), so it depends on rounding at the scale of the distance itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightNearSurface {
    /// Index of the light in [`Scene::lights`] (the scene file's `light[i]`).
    pub light: usize,
    /// Its position in world coordinates, metres.
    pub position: Vec3,
    /// Distance to the nearest such surface, metres.
    pub distance: f32,
    /// That surface's ray offset, metres.
    pub offset: f32,
}

impl fmt::Display for LightNearSurface {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.position;
        write!(
            f,
            "light[{}] at ({}, {}, {}) m is {:.2e} m from a surface, closer than the {:.2e} m by \
             which rays leave that surface: the light it casts on that surface near it depends on \
             rounding; move it at least {:.2e} m away",
            self.light, p.x, p.y, p.z, self.distance, self.offset, self.offset
        )
    }
}

/// What a [`Scene`] holds in memory ([`Scene::memory`]), bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneMemory {
    /// Per-triangle data: vertices, normals, areas, spawn offsets, the area CDF and texture
    /// coordinates, bytes.
    pub triangles: u64,
    /// The BVH, bytes.
    pub bvh: u64,
    /// Decoded texels, each image counted once, bytes.
    pub textures: u64,
    /// The most the BVH build allocated beside what the geometry keeps, while the scene was
    /// loaded (freed since), bytes ([`Geometry::build_transient_bytes`]).
    pub bvh_build: u64,
}

/// Geometry, materials, lights and camera of one render.
///
/// The parts are read through accessors and fixed at [`Scene::new`]: the light-selection
/// CDF is built from the lights, the lights and the camera are moved into the geometry's
/// frame, and every triangle's material index is checked, so changing one part alone would
/// leave the others wrong. [`Scene::set_resolution`] changes the one thing that can change.
#[derive(Debug)]
pub struct Scene {
    geometry: Geometry,
    materials: Vec<Material>,
    lights: Vec<PointLight>,
    camera: Camera,
    /// Cumulative flux luminance over the point lights, then the emitters, normalised to 1:
    /// the photons' light distribution (the point lights' part alone without emitters).
    light_cdf: Vec<f32>,
    emitters: emitters::Emitters,
    textures: SceneTextures,
    /// Per material index: its emissive texture (`emission_texture.rs`); empty without.
    emission_textures: Vec<Option<std::sync::Arc<Texture>>>,
    /// Per material index: is it a delta material ([`Material::is_delta`]).
    delta: Vec<bool>,
    /// Whether any material is a delta one: scenes without keep every path as it was.
    has_delta: bool,
}

impl Scene {
    /// A scene of one material (named `"material"`, index 0, which every triangle of
    /// `geometry` must carry) lit by `lights`: the small scenes of the examples and tests.
    pub fn one_material(
        geometry: Geometry,
        bdf: Bdf,
        lights: Vec<PointLight>,
        camera: Camera,
    ) -> Result<Scene, SceneError> {
        let material = Material::new("material", bdf);
        Scene::new(geometry, vec![material], lights, camera)
    }

    /// Assembles and checks a scene. The lights and the camera are given in world coordinates
    /// and moved into the geometry's frame (see [`Geometry::origin`]; a no-op for scenes
    /// around the origin), in which all of a `Scene`'s positions are then expressed.
    pub fn new(
        geometry: Geometry,
        materials: Vec<Material>,
        mut lights: Vec<PointLight>,
        mut camera: Camera,
    ) -> Result<Scene, SceneError> {
        for prim in 0..geometry.triangle_count() as u32 {
            let m = geometry.material(prim);
            if m as usize >= materials.len() {
                return Err(SceneError::MissingMaterial {
                    material: m,
                    count: materials.len(),
                });
            }
        }
        for (index, l) in lights.iter().enumerate() {
            if !l.position.is_finite() || !l.flux.is_finite() || l.flux.min_element() < 0.0 {
                return Err(SceneError::BadLight { index });
            }
        }
        for (material, m) in materials.iter().enumerate() {
            if !m.emission.is_finite() || m.emission.min_element() < 0.0 {
                return Err(SceneError::BadEmission { material });
            }
        }
        let emitters = emitters::Emitters::new(&geometry, &materials);
        let light_cdf = light_cdf(&lights, &emitters)?;
        let origin = geometry.origin();
        for l in &mut lights {
            l.position -= origin;
        }
        camera.position -= origin;
        camera.target -= origin;
        let delta: Vec<bool> = materials.iter().map(Material::is_delta).collect();
        Ok(Scene {
            geometry,
            has_delta: delta.contains(&true),
            delta,
            materials,
            lights,
            camera,
            light_cdf,
            emitters,
            textures: SceneTextures::default(),
            emission_textures: Vec::new(),
        })
    }

    /// Gives materials base-colour textures: a textured material's kd at a hit is its kd
    /// times the texture at the hit's interpolated texture coordinates ([`Scene::kd_at`]).
    pub fn with_textures(mut self, textures: SceneTextures) -> Result<Scene, SceneError> {
        let any = textures.base_colour.iter().any(Option::is_some);
        let fits = textures.base_colour.len() <= self.materials.len()
            && (!any || textures.texcoords.len() == self.geometry.triangle_count());
        if !fits {
            return Err(SceneError::BadTextures {
                textures: textures.base_colour.len(),
                texcoords: textures.texcoords.len(),
            });
        }
        self.textures = textures;
        if !any {
            // Read only where a material is textured: 24 bytes a triangle for nothing.
            self.textures.texcoords = Vec::new();
        }
        Ok(self)
    }

    /// Bytes the scene holds in its large parts, and the most its geometry's build allocated
    /// beside them: what a memory estimate of a render adds for the scene.
    pub fn memory(&self) -> SceneMemory {
        let g = self.geometry.memory();
        let texcoords = (self.textures.texcoords.capacity() * size_of::<[Vec2; 3]>()) as u64;
        // Each image once, however many textures (samplers, materials) show it.
        let mut images: Vec<&std::sync::Arc<TexelImage>> = Vec::new();
        let emissive = self.emission_textures.iter().flatten();
        for t in self.textures.base_colour.iter().flatten().chain(emissive) {
            if !images.iter().any(|i| std::sync::Arc::ptr_eq(i, t.image())) {
                images.push(t.image());
            }
        }
        let emitter_texcoords =
            (self.emitters.texcoords.capacity() * size_of::<[Vec2; 3]>()) as u64;
        SceneMemory {
            triangles: g.triangles + texcoords + emitter_texcoords,
            bvh: g.bvh,
            textures: images.iter().map(|i| i.bytes()).sum(),
            bvh_build: Geometry::build_transient_bytes(self.geometry.triangle_count()),
        }
    }

    /// The base-colour texture of a material index, if it has one.
    #[inline]
    pub fn texture(&self, material: u32) -> Option<&Texture> {
        self.textures
            .base_colour
            .get(material as usize)
            .and_then(|t| t.as_deref())
    }

    /// Number of materials with a base-colour texture.
    pub fn textured_materials(&self) -> usize {
        self.textures.base_colour.iter().flatten().count()
    }

    /// kd at barycentric point `bary` of triangle `prim` of material `material`: the
    /// material's kd, times its texture at the interpolated texture coordinates if it has one.
    #[inline]
    pub fn kd_at(&self, material: u32, prim: u32, bary: Vec2) -> Vec3 {
        let kd = self.bdf(material).kd();
        match self.texture(material) {
            Some(t) => kd * t.sample(self.texcoord(prim, bary)),
            None => kd,
        }
    }

    /// Texture coordinates of the three vertices of triangle `prim`, if the scene has any
    /// textured material (they are kept only then; zero where the triangle's material has no
    /// texture). For exporters.
    pub fn texcoords(&self, prim: u32) -> Option<[Vec2; 3]> {
        self.textures.texcoords.get(prim as usize).copied()
    }

    /// Interpolated texture coordinates at barycentric point `bary` of triangle `prim`.
    fn texcoord(&self, prim: u32, bary: Vec2) -> Vec2 {
        let [t0, t1, t2] = self.textures.texcoords[prim as usize];
        t0 * (1.0 - bary.x - bary.y) + t1 * bary.x + t2 * bary.y
    }

    /// The scattering model at a point of triangle `prim`: the material's, with kd from
    /// [`Scene::kd_at`] where it is textured (borrowed, at no cost, where it is not).
    #[inline]
    pub fn bdf_on(&self, material: u32, prim: u32, bary: Vec2) -> Cow<'_, Bdf> {
        let bdf = self.bdf(material);
        if self.texture(material).is_some() {
            Cow::Owned(bdf.with_kd(self.kd_at(material, prim, bary)))
        } else {
            Cow::Borrowed(bdf)
        }
    }

    /// [`Scene::bdf_on`] at a shading point.
    #[inline]
    pub fn bdf_at(&self, sh: &Shading) -> Cow<'_, Bdf> {
        self.bdf_on(sh.material, sh.prim, sh.bary)
    }

    /// Surfaces and BVH; its frame (world minus [`Geometry::origin`]) is the scene's frame.
    #[inline]
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// The geometry alone, the rest of the scene dropped (for benchmarks of the ray kernel).
    pub fn into_geometry(self) -> Geometry {
        self.geometry
    }

    /// Materials indexed by the triangles' material index.
    #[inline]
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// Point lights, positions in the geometry's frame (metres).
    #[inline]
    pub fn lights(&self) -> &[PointLight] {
        &self.lights
    }

    /// The camera, position in the geometry's frame (metres).
    #[inline]
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The pixel footprint of this camera on this scene, metres: the median, over the pixels
    /// whose centre ray hits a surface, of √(area of the pixel projected onto the surface
    /// first seen) = √(Ω_pixel·t²/|cos θ|), with Ω_pixel the pixel's solid angle, t the hit
    /// distance and θ the angle between the ray and the surface normal. At most 64 × 64
    /// pixel centres, evenly spaced, are traced; `None` when none hits. A merge radius of
    /// "1 px" is this length (method-notes.md, "Radius in pixels").
    pub fn pixel_footprint(&self) -> Option<f32> {
        let cam = &self.camera;
        let (w, h) = (cam.width(), cam.height());
        let (nx, ny) = (w.min(64), h.min(64));
        let mut sizes = Vec::with_capacity((nx * ny) as usize);
        for j in 0..ny {
            for i in 0..nx {
                // Pixel centres spread evenly over the image, the same ones at any seed.
                let px = ((i as f32 + 0.5) * w as f32 / nx as f32).floor() + 0.5;
                let py = ((j as f32 + 0.5) * h as f32 / ny as f32).floor() + 0.5;
                let d = cam.ray_direction(px, py);
                let Some(hit) = self.geometry.intersect(cam.position(), d, f32::INFINITY) else {
                    continue;
                };
                let cos_cam = d.dot(cam.forward());
                let cos_surf = d.dot(hit.ng).abs();
                if cos_surf <= 0.0 {
                    continue;
                }
                let solid_angle = cam.pixel_area() * cos_cam * cos_cam * cos_cam;
                sizes.push((solid_angle * hit.t * hit.t / cos_surf).sqrt());
            }
        }
        if sizes.is_empty() {
            return None;
        }
        let mid = sizes.len() / 2;
        let (_, m, _) = sizes.select_nth_unstable_by(mid, f32::total_cmp);
        Some(*m)
    }

    /// The lights that lie closer to some surface than that surface's ray offset, in light
    /// order (see [`LightNearSurface`]). Visits every triangle once per light.
    pub fn lights_near_surfaces(&self) -> Vec<LightNearSurface> {
        let origin = self.geometry.origin();
        self.lights
            .iter()
            .enumerate()
            .filter_map(|(light, l)| {
                let (prim, distance) = self.geometry.nearest_within_offset(l.position)?;
                Some(LightNearSurface {
                    light,
                    position: l.position + origin,
                    distance,
                    offset: self.geometry.spawn_offset(prim),
                })
            })
            .collect()
    }

    /// Gives the camera another image size (the field of view stays vertical).
    pub fn set_resolution(&mut self, width: u32, height: u32) -> Result<(), SceneError> {
        self.camera = self.camera.with_resolution(width, height)?;
        Ok(())
    }

    /// The scattering model of a material index, with the material's own kd (a texture, if
    /// it has one, is applied by [`Scene::bdf_on`] and [`Scene::bdf_at`]).
    #[inline]
    pub fn bdf(&self, material: u32) -> &Bdf {
        &self.materials[material as usize].bdf
    }

    /// Total emitted flux per channel, W: the point lights' and the emitters'.
    pub fn total_flux(&self) -> Vec3 {
        let points: Vec3 = self.lights.iter().map(|l| l.flux).sum();
        if self.has_emission() {
            points + self.emitters.total_flux()
        } else {
            points
        }
    }

    /// True when every non-delta material is pure Lambert (the radiance leaving every surface
    /// that stores photons is then isotropic per point); mirrors and dielectrics store none.
    pub fn all_lambert(&self) -> bool {
        self.materials.iter().all(|m| m.bdf.is_lambert())
    }

    /// True iff some material is a mirror or a dielectric.
    #[inline]
    pub fn has_delta(&self) -> bool {
        self.has_delta
    }

    /// True iff material index `material` is a mirror or a dielectric.
    #[inline]
    pub fn is_delta(&self, material: u32) -> bool {
        self.has_delta && self.delta[material as usize]
    }

    /// Picks a light with probability proportional to its flux luminance, among the point
    /// lights and the emitters together: (index, probability). Indices below
    /// `lights().len()` are point lights; index `lights().len() + k` is `emitters()[k]`.
    #[inline]
    pub fn pick_light(&self, u: f32) -> (usize, f32) {
        let i = self
            .light_cdf
            .partition_point(|&c| c <= u)
            .min(self.light_cdf.len() - 1);
        let lo = if i == 0 { 0.0 } else { self.light_cdf[i - 1] };
        (i, self.light_cdf[i] - lo)
    }

    /// Probability with which [`Scene::pick_light`] returns light `i` (point lights first,
    /// then emitters).
    pub fn light_probability(&self, i: usize) -> f32 {
        let lo = if i == 0 { 0.0 } else { self.light_cdf[i - 1] };
        self.light_cdf[i] - lo
    }

    /// Prepares `hit` for shading towards the unit direction `wo` (pointing away from it).
    #[inline]
    pub fn shade(&self, hit: &Hit, wo: Vec3) -> Shading {
        let flip = if hit.ng.dot(wo) < 0.0 { -1.0 } else { 1.0 };
        Shading {
            p: hit.p,
            ng: hit.ng * flip,
            frame: Frame::from_normal(hit.ns * flip),
            material: hit.material,
            prim: hit.prim,
            bary: hit.uv,
        }
    }

    /// Ray origin for leaving `sh` in direction `dir`: pushed off the surface to the side of `dir`.
    #[inline]
    pub fn spawn(&self, sh: &Shading, dir: Vec3) -> Vec3 {
        let side = if sh.ng.dot(dir) >= 0.0 { 1.0 } else { -1.0 };
        sh.p + sh.ng * (side * self.geometry.spawn_offset(sh.prim))
    }

    /// The BDF at `sh` for world directions `wo` and `wi`: zero unless both are on the side of
    /// the geometric normal that `sh` faces (no light through surfaces).
    // Always inlined: with the area lights' call site beside the point lights', LLVM stopped
    // inlining it into `direct`, which cost point-light scenes 0.5 % of a pass's instructions.
    #[inline(always)]
    pub fn eval(&self, sh: &Shading, wo: Vec3, wi: Vec3) -> Vec3 {
        if sh.ng.dot(wi) <= 0.0 || sh.ng.dot(wo) <= 0.0 {
            return Vec3::ZERO;
        }
        self.bdf_at(sh)
            .eval(sh.frame.to_local(wo), sh.frame.to_local(wi))
    }

    /// [`Scene::eval`] with the BDF at `sh` already looked up (`bdf` = [`Scene::bdf_at`]`(sh)`):
    /// for loops over many directions at one point, such as a gather's photons, which would
    /// otherwise look up the material's texture once per photon. The same numbers.
    #[inline]
    pub fn eval_with(&self, bdf: &Bdf, sh: &Shading, wo: Vec3, wi: Vec3) -> Vec3 {
        if sh.ng.dot(wi) <= 0.0 || sh.ng.dot(wo) <= 0.0 {
            return Vec3::ZERO;
        }
        bdf.eval(sh.frame.to_local(wo), sh.frame.to_local(wi))
    }

    /// Direct radiance L₀ leaving `sh` towards `wo`: Σ over lights of f·cos·I/d²·visibility,
    /// W·m⁻²·sr⁻¹ (exact; one shadow ray per light).
    pub fn direct(&self, sh: &Shading, wo: Vec3) -> Vec3 {
        let mut sum = Vec3::ZERO;
        for light in &self.lights {
            sum += self.direct_from(sh, wo, light);
        }
        sum
    }

    /// The part of [`Scene::direct`] due to one light.
    #[inline]
    pub fn direct_from(&self, sh: &Shading, wo: Vec3, light: &PointLight) -> Vec3 {
        let c = self.direct_unshadowed(sh, wo, light);
        if c == Vec3::ZERO || !self.light_visible(sh, light) {
            return Vec3::ZERO;
        }
        c
    }

    /// [`Scene::direct_from`] without the shadow ray: f·cos·I/d² for a light on the lit side.
    #[inline]
    pub fn direct_unshadowed(&self, sh: &Shading, wo: Vec3, light: &PointLight) -> Vec3 {
        let to = light.position - sh.p;
        let d2 = to.length_squared();
        if d2 <= 0.0 {
            return Vec3::ZERO;
        }
        let wi = to / d2.sqrt();
        let cos = sh.frame.n.dot(wi);
        if cos <= 0.0 || sh.ng.dot(wi) <= 0.0 {
            return Vec3::ZERO;
        }
        self.eval(sh, wo, wi) * light.intensity() * (cos / d2)
    }

    /// True if `light` is on the side of `sh` and no surface blocks the segment to it.
    #[inline]
    pub fn light_visible(&self, sh: &Shading, light: &PointLight) -> bool {
        let to = light.position - sh.p;
        sh.ng.dot(to) > 0.0 && !self.geometry.occluded(self.spawn(sh, to), light.position)
    }
}

/// Cumulative flux luminance over the point lights, then the emitters, normalised to 1: the
/// photons' light distribution. [`SceneError::NoLight`] if the total is not positive.
pub(crate) fn light_cdf(
    lights: &[PointLight],
    emitters: &emitters::Emitters,
) -> Result<Vec<f32>, SceneError> {
    let mut acc = 0.0;
    let mut light_cdf: Vec<f32> = lights
        .iter()
        .map(|l| l.flux)
        .chain(emitters.list.iter().map(Emitter::flux))
        .map(|flux| {
            acc += luminance(flux);
            acc
        })
        .collect();
    if acc <= 0.0 {
        return Err(SceneError::NoLight);
    }
    light_cdf.iter_mut().for_each(|c| *c /= acc);
    Ok(light_cdf)
}

#[cfg(test)]
mod tests {
    use super::*;
    use bdpm_geometry::TriangleMesh;
    use glam::Vec3;

    /// A camera at the origin looking at `look` and a wall z = `d` (wider than the view), 64 × 48
    /// pixels, vertical field of view 40°.
    fn wall_scene(d: f32, look: Vec3) -> Scene {
        let mut mesh = TriangleMesh::default();
        let s = 100.0;
        mesh.push_rect(Vec3::new(0.0, 0.0, d), Vec3::X * s, Vec3::Y * s, 0);
        Scene::one_material(
            Geometry::new(mesh).unwrap(),
            Bdf::lambert(Vec3::splat(0.5)).unwrap(),
            vec![PointLight {
                position: Vec3::new(0.0, 0.0, 1.0),
                flux: Vec3::ONE,
            }],
            Camera::look_at(Vec3::ZERO, look, Vec3::Y, 40.0, 64, 48).unwrap(),
        )
        .unwrap()
    }

    #[test]
    fn footprint_on_a_facing_wall_is_distance_times_pixel_pitch() {
        // On a plane facing the camera every pixel covers (pitch·d)², whatever its angle
        // off the axis: t = d/cos α, Ω = pitch²·cos³α and the slant 1/cos α cancel.
        for d in [0.5_f32, 3.0] {
            let scene = wall_scene(d, Vec3::Z);
            let pitch = 2.0 * (20.0_f32.to_radians()).tan() / 48.0;
            let f = scene.pixel_footprint().expect("the wall fills the view");
            assert!(
                (f / (pitch * d) - 1.0).abs() < 1e-4,
                "footprint {f} m, expected {} m",
                pitch * d
            );
        }
    }

    #[test]
    fn no_footprint_when_nothing_is_seen() {
        // The camera turned away from the wall.
        assert_eq!(wall_scene(2.0, -Vec3::Z).pixel_footprint(), None);
    }
}

// The README (the crate's page on crates.io) as a hidden item, so that `cargo test --doc`
// compiles and runs its example; the crate documentation above stays as it is.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
