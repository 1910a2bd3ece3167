//! A glTF metallic-roughness material (with KHR_materials_transmission, KHR_materials_ior and
//! KHR_materials_volume) → one of bdpm's models: a perfect mirror, a smooth dielectric, or
//! Lambert (docs/scene-format.md, "glTF materials").
//!
//! bdpm has no microfacet model, so only the two ends of glTF's roughness range map exactly:
//! a smooth metal is a mirror and smooth transmission is glass; everything rougher or mixed
//! stays the Lambert material glTF files always gave, and the material is named in a warning
//! saying what was approximated.

use std::path::Path;

use bdpm_bdf::{Dielectric, ETA_MAX, ETA_MIN, Mirror};
use glam::Vec3;

use crate::material_types::IOR_RANGE;
use crate::materials::Materials;

/// Largest `roughnessFactor` taken as perfectly smooth (a mirror or glass).
pub(crate) const SMOOTH_ROUGHNESS: f32 = 0.05;

/// Smallest transmitted share (1 − metallic) · transmission that makes smooth glass.
pub(crate) const GLASS_SHARE: f32 = 0.5;

/// The index of refraction glTF assumes without KHR_materials_ior (dimensionless).
pub(crate) const DEFAULT_IOR: f32 = 1.5;

/// What the mapping reads of one glTF material: its factors (glTF's defaults where the file
/// gives none) and which textures it has.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Factors {
    /// `pbrMetallicRoughness.baseColorFactor`, RGB (alpha is not read).
    pub(crate) base_colour: Vec3,
    /// `pbrMetallicRoughness.metallicFactor` (glTF's default 1).
    pub(crate) metallic: f32,
    /// `pbrMetallicRoughness.roughnessFactor` (glTF's default 1).
    pub(crate) roughness: f32,
    /// `KHR_materials_transmission.transmissionFactor` (0 without the extension).
    pub(crate) transmission: f32,
    /// `KHR_materials_ior.ior` (1.5 without the extension).
    pub(crate) ior: f32,
    /// `KHR_materials_volume`, if the material has it.
    pub(crate) volume: Option<Volume>,
    /// Whether it has a `baseColorTexture`.
    pub(crate) base_colour_texture: bool,
    /// Whether it has a `metallicRoughnessTexture`.
    pub(crate) metallic_roughness_texture: bool,
    /// Whether it has a `transmissionTexture`.
    pub(crate) transmission_texture: bool,
    /// `emissiveFactor` × `KHR_materials_emissive_strength.emissiveStrength` (1 without the
    /// extension): the emitted radiance, W·m⁻²·sr⁻¹ per channel, before the
    /// `emissiveTexture` (which the caller applies).
    pub(crate) emission: Vec3,
    /// `doubleSided`: emission then leaves both sides.
    pub(crate) double_sided: bool,
}

/// The KHR_materials_volume factors the mapping reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Volume {
    /// `thicknessFactor` in the mesh's units; 0 means thin-walled.
    pub(crate) thickness: f32,
    /// `attenuationDistance` in metres (infinite: no absorption).
    pub(crate) attenuation_distance: f32,
    /// `attenuationColor`, RGB.
    pub(crate) attenuation_colour: Vec3,
}

impl Factors {
    /// The factors of `m` as the file gives them, glTF's defaults elsewhere.
    pub(crate) fn read(m: &gltf::json::Material) -> Factors {
        let pbr = &m.pbr_metallic_roughness;
        let [r, g, b, _] = pbr.base_color_factor.0;
        let ext = m.extensions.as_ref();
        let transmission = ext.and_then(|e| e.transmission.as_ref());
        Factors {
            base_colour: Vec3::new(r, g, b),
            metallic: pbr.metallic_factor.0,
            roughness: pbr.roughness_factor.0,
            transmission: transmission.map_or(0.0, |t| t.transmission_factor.0),
            ior: ext
                .and_then(|e| e.ior.as_ref())
                .map_or(DEFAULT_IOR, |i| i.ior.0),
            volume: ext.and_then(|e| e.volume.as_ref()).map(|v| Volume {
                thickness: v.thickness_factor.0,
                attenuation_distance: v.attenuation_distance.0,
                attenuation_colour: Vec3::from_array(v.attenuation_color.0),
            }),
            base_colour_texture: pbr.base_color_texture.is_some(),
            metallic_roughness_texture: pbr.metallic_roughness_texture.is_some(),
            transmission_texture: transmission.is_some_and(|t| t.transmission_texture.is_some()),
            emission: Vec3::from_array(m.emissive_factor.0)
                * ext
                    .and_then(|e| e.emissive_strength.as_ref())
                    .map_or(1.0, |s| s.emissive_strength.0),
            double_sided: m.double_sided,
        }
    }
}

/// What the glTF materials of one file became, for the load report.
#[derive(Debug, Default)]
pub(crate) struct Tally {
    /// Materials made perfect mirrors.
    pub(crate) mirrors: usize,
    /// Materials made smooth dielectrics.
    pub(crate) dielectrics: usize,
    /// One line per approximation, naming the file and the material.
    pub(crate) warnings: Vec<String>,
}

/// A glTF material as [`make`] leaves it.
pub(crate) enum Made {
    /// A mirror or dielectric, added to the materials at this index.
    Delta(u32),
    /// Lambert with this kd (the base colour factor): the caller adds it with the
    /// base-colour texture, if any.
    Lambert(Vec3),
}

/// Maps material `index` (named `name`) of the glTF file `json`, written `written` in the
/// scene file: adds it to `materials` if it is a mirror or a dielectric, counts it and its
/// notes in `tally`; also gives its emission (Le, two-sided) for the caller to set. An error is one line naming the material, the field and what is wrong.
pub(crate) fn make(
    json: &gltf::json::Root,
    index: usize,
    name: &str,
    written: &Path,
    materials: &mut Materials,
    tally: &mut Tally,
) -> Result<(Made, (Vec3, bool)), String> {
    let what = format!("material {index} ('{name}')");
    let material = json
        .materials
        .get(index)
        .ok_or_else(|| format!("material {index} does not exist"))?;
    let factors = Factors::read(material);
    let mapping = map(&factors).map_err(|e| format!("{what}: {e}"))?;
    let emission = emission(&factors).map_err(|e| format!("{what}: {e}"))?;
    for note in mapping.notes {
        let line = format!("glTF {}: {what}: {note}", written.display());
        if !tally.warnings.contains(&line) {
            tally.warnings.push(line);
        }
    }
    let made = match mapping.model {
        Model::Lambert(kd) => Made::Lambert(kd),
        Model::Delta(model) => {
            if matches!(model, bdpm_bdf::Material::Mirror(_)) {
                tally.mirrors += 1;
            } else {
                tally.dielectrics += 1;
            }
            Made::Delta(materials.add_delta(name.to_string(), model))
        }
    };
    Ok((made, emission))
}

/// A glTF material's emission: (Le, two-sided) from its factors (the `emissiveTexture`, which
/// multiplies Le, is the caller's); an error names a factor that is negative or not finite.
fn emission(f: &Factors) -> Result<(Vec3, bool), String> {
    let e = f.emission;
    if !(e.is_finite() && e.min_element() >= 0.0) {
        return Err(format!(
            "emissiveFactor × emissiveStrength = {e} must be finite and non-negative"
        ));
    }
    Ok((e, f.double_sided))
}

/// The model a glTF material becomes.
#[derive(Clone, Debug)]
pub(crate) enum Model {
    /// Lambert with kd = the base colour factor (times the base-colour texture, which the
    /// caller applies).
    Lambert(Vec3),
    /// A mirror or a dielectric; no texture applies.
    Delta(bdpm_bdf::Material),
}

/// A glTF material's model and what the mapping approximated, one note per approximation
/// (each a phrase the caller prefixes with the file and the material).
#[derive(Clone, Debug)]
pub(crate) struct Mapping {
    pub(crate) model: Model,
    pub(crate) notes: Vec<String>,
}

/// Maps `f`: metallicFactor = 1 and roughness ≤ [`SMOOTH_ROUGHNESS`] make a perfect mirror
/// (reflectance = base colour); a transmitted share (1 − metallic) · transmission ≥
/// [`GLASS_SHARE`] with roughness ≤ [`SMOOTH_ROUGHNESS`] a smooth dielectric (ior from
/// KHR_materials_ior, transmitted light tinted by the base colour); anything else Lambert
/// (kd = base colour), with a note when it had metal or transmission. Textures other than
/// base colour are not read (the factors alone decide). An error names the field and the
/// range it is outside.
pub(crate) fn map(f: &Factors) -> Result<Mapping, String> {
    check_factors(f)?;
    let share = (1.0 - f.metallic) * f.transmission;
    let smooth = f.roughness <= SMOOTH_ROUGHNESS;
    if f.metallic == 1.0 && smooth {
        mirror(f)
    } else if share >= GLASS_SHARE && smooth {
        glass(f, share)
    } else {
        Ok(Mapping {
            model: Model::Lambert(f.base_colour),
            notes: lambert_notes(f, share),
        })
    }
}

/// Refuses factors outside the ranges glTF gives them (a file may hold anything a JSON number
/// can, and an f32 overflows to infinity).
fn check_factors(f: &Factors) -> Result<(), String> {
    let b = f.base_colour;
    if !(b.is_finite() && b.min_element() >= 0.0 && b.max_element() <= 1.0) {
        return Err(format!("baseColorFactor {b} has a channel outside [0, 1]"));
    }
    for (field, v) in [
        ("pbrMetallicRoughness.metallicFactor", f.metallic),
        ("pbrMetallicRoughness.roughnessFactor", f.roughness),
        (
            "KHR_materials_transmission.transmissionFactor",
            f.transmission,
        ),
    ] {
        // NaN fails the range test.
        if !(0.0..=1.0).contains(&v) {
            return Err(format!("{field} {v} is outside [0, 1]"));
        }
    }
    Ok(())
}

/// A perfect mirror reflecting the base colour factor at every angle.
fn mirror(f: &Factors) -> Result<Mapping, String> {
    let mut notes = Vec::new();
    if f.base_colour_texture {
        notes.push(format!(
            "a smooth metal, rendered as a perfect mirror: its baseColorTexture is not applied \
             (reflectance = baseColorFactor {})",
            f.base_colour
        ));
    }
    if f.metallic_roughness_texture {
        notes.push(
            "a smooth metal by its factors, rendered as a perfect mirror: its \
             metallicRoughnessTexture is not read"
                .to_string(),
        );
    }
    let mirror = Mirror::new(f.base_colour).map_err(|e| e.to_string())?;
    Ok(Mapping {
        model: Model::Delta(mirror.into()),
        notes,
    })
}

/// Smooth glass: a dielectric boundary of index `ior`, transmitted light tinted by the base
/// colour factor.
fn glass(f: &Factors, share: f32) -> Result<Mapping, String> {
    // NaN fails the range test.
    if !(ETA_MIN..=ETA_MAX).contains(&f.ior) {
        return Err(format!(
            "KHR_materials_ior.ior {} is outside [{}, {}], the index of refraction a \
             dielectric accepts",
            f.ior, IOR_RANGE.0, IOR_RANGE.1
        ));
    }
    let mut notes = Vec::new();
    if share < 1.0 {
        notes.push(format!(
            "smooth transmission of share (1 - metallic) * transmission = {share}, rendered \
             as clear glass: the rest (diffuse or metal) is dropped"
        ));
    }
    if f.base_colour_texture {
        notes.push(format!(
            "smooth transmission, rendered as glass: its baseColorTexture is not applied \
             (transmitted light tinted by baseColorFactor {})",
            f.base_colour
        ));
    }
    if f.transmission_texture || f.metallic_roughness_texture {
        notes.push(
            "smooth transmission by its factors, rendered as glass: its transmission and \
             metallic-roughness textures are not read"
                .to_string(),
        );
    }
    match f.volume {
        Some(v) if !(v.thickness >= 0.0 && v.thickness.is_finite()) => {
            return Err(format!(
                "KHR_materials_volume.thicknessFactor {} is not a finite number >= 0",
                v.thickness
            ));
        }
        Some(v) if v.thickness > 0.0 => {
            if v.attenuation_distance.is_finite() {
                notes.push(format!(
                    "KHR_materials_volume attenuation (distance {} m, colour {}) is ignored: \
                     the glass absorbs nothing inside",
                    v.attenuation_distance, v.attenuation_colour
                ));
            }
        }
        _ => notes.push(format!(
            "thin-walled transmission (no KHR_materials_volume thicknessFactor > 0), rendered \
             as the boundary of a solid of ior {}: right for a closed mesh, not for a single \
             sheet",
            f.ior
        )),
    }
    let glass = Dielectric::tinted(f.ior, Vec3::ONE, f.base_colour).map_err(|e| e.to_string())?;
    Ok(Mapping {
        model: Model::Delta(glass.into()),
        notes,
    })
}

/// What a Lambert stand-in leaves out: the metal and the transmission glTF gave.
fn lambert_notes(f: &Factors, share: f32) -> Vec<String> {
    let mut notes = Vec::new();
    let rough = f.roughness > SMOOTH_ROUGHNESS;
    if f.metallic == 1.0 {
        notes.push(format!(
            "rough metal (metallicFactor 1, glTF's default when not given; roughnessFactor \
             {} > {SMOOTH_ROUGHNESS}), rendered as Lambert with kd = baseColorFactor",
            f.roughness
        ));
    } else if f.metallic > 0.0 {
        notes.push(format!(
            "partly metallic (metallicFactor {}), rendered as Lambert with kd = \
             baseColorFactor",
            f.metallic
        ));
    }
    if share >= GLASS_SHARE && rough {
        notes.push(format!(
            "rough transmission (share {share}, roughnessFactor {} > {SMOOTH_ROUGHNESS}), \
             rendered as opaque Lambert with kd = baseColorFactor",
            f.roughness
        ));
    } else if share > 0.0 {
        notes.push(format!(
            "partial transmission (share (1 - metallic) * transmission = {share} < \
             {GLASS_SHARE}), rendered as opaque Lambert with kd = baseColorFactor"
        ));
    }
    notes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plain() -> Factors {
        Factors {
            base_colour: Vec3::new(0.9, 0.8, 0.7),
            metallic: 0.0,
            roughness: 0.5,
            transmission: 0.0,
            ior: DEFAULT_IOR,
            volume: None,
            base_colour_texture: false,
            metallic_roughness_texture: false,
            transmission_texture: false,
            emission: Vec3::ZERO,
            double_sided: false,
        }
    }

    #[test]
    fn emission_is_checked() {
        let lit = Factors {
            emission: Vec3::new(2.0, 1.0, 0.0),
            double_sided: true,
            ..plain()
        };
        assert_eq!(emission(&lit), Ok((lit.emission, true)));
        let bad = Factors {
            emission: Vec3::new(1.0, -1.0, 0.0),
            ..plain()
        };
        let e = emission(&bad).unwrap_err();
        assert!(
            e.contains("emissiveFactor") && e.contains("non-negative"),
            "{e}"
        );
        assert_eq!(emission(&plain()), Ok((Vec3::ZERO, false)));
    }

    fn solid() -> Option<Volume> {
        Some(Volume {
            thickness: 0.1,
            attenuation_distance: f32::INFINITY,
            attenuation_colour: Vec3::ONE,
        })
    }

    #[test]
    fn thresholds_are_inclusive_at_their_edges() {
        let metal = Factors {
            metallic: 1.0,
            roughness: SMOOTH_ROUGHNESS,
            ..plain()
        };
        assert!(matches!(map(&metal).unwrap().model, Model::Delta(_)));
        let rough = Factors {
            roughness: f32::from_bits(SMOOTH_ROUGHNESS.to_bits() + 1),
            ..metal.clone()
        };
        assert!(matches!(map(&rough).unwrap().model, Model::Lambert(_)));
        let glass = Factors {
            metallic: 0.5,
            transmission: 1.0,
            roughness: 0.0,
            volume: solid(),
            ..plain()
        };
        let m = map(&glass).unwrap();
        assert!(matches!(m.model, Model::Delta(_)), "{m:?}");
        let less = Factors {
            transmission: 0.99,
            ..glass
        };
        assert!(matches!(map(&less).unwrap().model, Model::Lambert(_)));
    }

    #[test]
    fn a_plain_dielectric_is_lambert_without_a_note() {
        let m = map(&plain()).unwrap();
        assert!(matches!(m.model, Model::Lambert(kd) if kd == plain().base_colour));
        assert!(m.notes.is_empty(), "{:?}", m.notes);
    }

    #[test]
    fn nan_factors_are_refused() {
        for f in [
            Factors {
                metallic: f32::NAN,
                ..plain()
            },
            Factors {
                roughness: f32::INFINITY,
                ..plain()
            },
            Factors {
                transmission: -0.1,
                ..plain()
            },
        ] {
            assert!(map(&f).is_err(), "{f:?}");
        }
        let glass = Factors {
            transmission: 1.0,
            roughness: 0.0,
            ior: f32::NAN,
            ..plain()
        };
        assert!(map(&glass).unwrap_err().contains("ior NaN"));
    }
}
