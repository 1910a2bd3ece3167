//! The scene's materials as the loader assembles them: the scene file's, by name, then those
//! made from glTF files, with their base-colour and emissive textures. Shared by the scene file's build
//! and the glTF reader.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

use bdpm_bdf::Bdf;
use bdpm_scene::{Material, Texture};
use glam::Vec3;

use crate::LoadError;

/// The scene's materials: TOML ones first (sorted by name), then those made from glTF files.
pub(crate) struct Materials {
    list: Vec<Material>,
    by_name: HashMap<String, u32>,
    gltf_default: Option<u32>,
    /// Base-colour textures by material index (shorter than `list` where the rest have none).
    textures: Vec<Option<Arc<Texture>>>,
    /// Emissive textures by material index (shorter than `list` where the rest have none).
    emission_textures: Vec<Option<Arc<Texture>>>,
}

impl Materials {
    /// No materials yet, room for `n` from the scene file.
    pub(crate) fn with_capacity(n: usize) -> Materials {
        Materials {
            list: Vec::with_capacity(n),
            by_name: HashMap::new(),
            gltf_default: None,
            textures: Vec::new(),
            emission_textures: Vec::new(),
        }
    }

    /// Adds a scene file's material, reachable by its name.
    pub(crate) fn add_named(&mut self, material: Material) {
        let _ = self
            .by_name
            .insert(material.name.clone(), self.list.len() as u32);
        self.list.push(material);
    }

    /// The names of the scene file's materials, sorted.
    pub(crate) fn names(&self) -> Vec<&str> {
        let mut known: Vec<&str> = self.by_name.keys().map(String::as_str).collect();
        known.sort_unstable();
        known
    }

    /// How many materials there are.
    pub(crate) fn len(&self) -> usize {
        self.list.len()
    }

    /// The materials in index order and their base-colour textures.
    pub(crate) fn into_parts(self) -> (Vec<Material>, Vec<Option<Arc<Texture>>>) {
        (self.list, self.textures)
    }

    /// Index of the TOML material `name`.
    pub(crate) fn lookup(&self, name: &str) -> Option<u32> {
        self.by_name.get(name).copied()
    }

    /// Adds a Lambert material made from a glTF file (not reachable by name from shapes).
    pub(crate) fn add_lambert(&mut self, name: String, kd: Vec3) -> Result<u32, String> {
        let bdf = Bdf::lambert(kd).map_err(|e| e.to_string())?;
        self.list.push(Material::new(name, bdf));
        Ok(self.list.len() as u32 - 1)
    }

    /// Adds a mirror or dielectric made from a glTF file (not reachable by name from shapes).
    pub(crate) fn add_delta(&mut self, name: String, model: bdpm_bdf::Material) -> u32 {
        self.list.push(Material::new(name, model));
        self.list.len() as u32 - 1
    }

    /// Gives material `m` the emitted radiance `emission` (W·m⁻²·sr⁻¹ per channel), from
    /// both sides of its triangles if `two_sided`.
    pub(crate) fn set_emission(&mut self, m: u32, emission: Vec3, two_sided: bool) {
        let material = &mut self.list[m as usize];
        material.emission = emission;
        material.two_sided_emission = two_sided;
    }

    /// Adds a copy of material `m` (with its texture) that emits radiance `emission`
    /// (W·m⁻²·sr⁻¹ per channel) from the front side of its triangles; returns its index.
    pub(crate) fn add_emitting_copy(&mut self, m: u32, emission: Vec3) -> u32 {
        let original = &self.list[m as usize];
        let copy = original.clone().with_emission(emission, false);
        let copy = Material {
            name: format!("{} (emitting)", original.name),
            ..copy
        };
        self.list.push(copy);
        let index = self.list.len() as u32 - 1;
        if let Some(Some(t)) = self.textures.get(m as usize) {
            let t = Arc::clone(t);
            self.set_texture(index, t);
        }
        index
    }

    /// Whether material `m` emits (some channel of its emission is positive).
    pub(crate) fn emits(&self, m: u32) -> bool {
        self.list[m as usize].emits()
    }

    /// Whether material `m` has a base-colour texture and whether it has an emissive one.
    pub(crate) fn textured(&self, m: u32) -> (bool, bool) {
        let has = |list: &[Option<Arc<Texture>>]| list.get(m as usize).is_some_and(Option::is_some);
        (has(&self.textures), has(&self.emission_textures))
    }

    /// Gives material `m` a base-colour texture.
    pub(crate) fn set_texture(&mut self, m: u32, texture: Arc<Texture>) {
        let m = m as usize;
        if self.textures.len() <= m {
            self.textures.resize(m + 1, None);
        }
        self.textures[m] = Some(texture);
    }

    /// Gives material `m` an emissive texture: its Le is its emission × the texture.
    pub(crate) fn set_emission_texture(&mut self, m: u32, texture: Arc<Texture>) {
        let m = m as usize;
        if self.emission_textures.len() <= m {
            self.emission_textures.resize(m + 1, None);
        }
        self.emission_textures[m] = Some(texture);
    }

    /// The emissive textures by material index, taken out (empty without any).
    pub(crate) fn take_emission_textures(&mut self) -> Vec<Option<Arc<Texture>>> {
        std::mem::take(&mut self.emission_textures)
    }

    /// The material of glTF primitives without one: Lambert, kd = 0.8 in every channel.
    pub(crate) fn gltf_default(&mut self) -> Result<u32, LoadError> {
        if let Some(m) = self.gltf_default {
            return Ok(m);
        }
        let m = self
            .add_lambert("gltf:default".into(), Vec3::splat(crate::GLTF_DEFAULT_KD))
            .map_err(|e| LoadError::Invalid {
                path: PathBuf::new(),
                field: "gltf:default".into(),
                message: e,
            })?;
        self.gltf_default = Some(m);
        Ok(m)
    }
}
