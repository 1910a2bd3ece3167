//! The scene file as written: serde types that mirror the TOML one to one. The `[render]`
//! table is bdpm-settings' [`PartialSettings`], the one shape of settings given in part.
//!
//! Everything is optional at this level, so that a missing value is reported by the
//! validation in `build.rs` with its full dotted path (serde would only name the key).
//! Every table denies unknown keys, so that a typo is an error rather than a silent default.

use std::collections::BTreeMap;
use std::fmt;
use std::path::PathBuf;

use bdpm_settings::PartialSettings;
use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};

/// The whole file.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SceneFile {
    /// `[render]`: the settings given, in the shape the command line's overrides share.
    pub(crate) render: Option<PartialSettings>,
    pub(crate) camera: Option<CameraDef>,
    #[serde(default)]
    pub(crate) light: Vec<LightDef>,
    /// Sorted by name, which fixes the material indices independently of the file's order.
    #[serde(default)]
    pub(crate) material: BTreeMap<String, MaterialDef>,
    #[serde(default)]
    pub(crate) shape: Vec<ShapeDef>,
}

/// `[camera]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CameraDef {
    pub(crate) position: Option<Point>,
    pub(crate) look_at: Option<Point>,
    pub(crate) up: Option<Point>,
    pub(crate) vfov: Option<f64>,
}

/// One `[[light]]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LightDef {
    pub(crate) position: Option<Point>,
    pub(crate) flux: Option<Triple>,
}

/// One `[material.NAME]`: `type` is `"smooth"` (the default: `kd`, `gr`, `delta`),
/// `"mirror"` (`reflectance`, `eta` and `k`) or `"dielectric"` (`ior`, `reflect_tint`,
/// `transmit_tint`); any type may add `emission` and `two_sided_emission`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MaterialDef {
    #[serde(rename = "type")]
    pub(crate) kind: Option<String>,
    pub(crate) kd: Option<Triple>,
    pub(crate) gr: Option<Triple>,
    pub(crate) delta: Option<f64>,
    pub(crate) reflectance: Option<Triple>,
    pub(crate) eta: Option<Triple>,
    pub(crate) k: Option<Triple>,
    pub(crate) ior: Option<f64>,
    pub(crate) reflect_tint: Option<Triple>,
    pub(crate) transmit_tint: Option<Triple>,
    /// Emitted radiance Le, W·m⁻²·sr⁻¹ (any type of material may emit).
    pub(crate) emission: Option<Triple>,
    /// Emission from both sides of the triangles.
    pub(crate) two_sided_emission: Option<bool>,
}

impl MaterialDef {
    /// The keys given, by name, each with whether it is given.
    pub(crate) fn keys(&self) -> [(&'static str, bool); 9] {
        [
            ("kd", self.kd.is_some()),
            ("gr", self.gr.is_some()),
            ("delta", self.delta.is_some()),
            ("reflectance", self.reflectance.is_some()),
            ("eta", self.eta.is_some()),
            ("k", self.k.is_some()),
            ("ior", self.ior.is_some()),
            ("reflect_tint", self.reflect_tint.is_some()),
            ("transmit_tint", self.transmit_tint.is_some()),
        ]
    }
}

/// One `[[shape]]`, told apart by its `type` key.
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub(crate) enum ShapeDef {
    Quad(QuadDef),
    Box(BoxDef),
    Sphere(SphereDef),
    #[serde(alias = "gltf")]
    Mesh(MeshDef),
    Obj(MeshFileDef),
    Ply(MeshFileDef),
}

impl ShapeDef {
    pub(crate) fn type_name(&self) -> &'static str {
        match self {
            ShapeDef::Quad(_) => "quad",
            ShapeDef::Box(_) => "box",
            ShapeDef::Sphere(_) => "sphere",
            ShapeDef::Mesh(_) => "mesh",
            ShapeDef::Obj(_) => "obj",
            ShapeDef::Ply(_) => "ply",
        }
    }
}

/// `type = "quad"`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct QuadDef {
    pub(crate) vertices: Option<Vec<Point>>,
    pub(crate) material: Option<String>,
    pub(crate) scale: Option<Triple>,
    pub(crate) translate: Option<Point>,
}

/// `type = "box"`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct BoxDef {
    pub(crate) min: Option<Point>,
    pub(crate) max: Option<Point>,
    pub(crate) material: Option<String>,
    #[serde(default)]
    pub(crate) open: Vec<String>,
    pub(crate) facing: Option<String>,
    pub(crate) scale: Option<Triple>,
    pub(crate) translate: Option<Point>,
}

/// `type = "sphere"`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SphereDef {
    pub(crate) center: Option<Point>,
    pub(crate) radius: Option<f64>,
    pub(crate) subdivisions: Option<u32>,
    pub(crate) smooth: Option<bool>,
    pub(crate) material: Option<String>,
    pub(crate) facing: Option<String>,
}

/// `type = "mesh"` (alias `"gltf"`).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MeshDef {
    pub(crate) file: Option<PathBuf>,
    pub(crate) material: Option<String>,
    pub(crate) scale: Option<Triple>,
    pub(crate) translate: Option<Point>,
}

/// `type = "obj"` and `type = "ply"`: a mesh file with one material (required: the file's
/// own materials are not read).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MeshFileDef {
    pub(crate) file: Option<PathBuf>,
    pub(crate) material: Option<String>,
    pub(crate) scale: Option<Triple>,
    pub(crate) translate: Option<Point>,
}

/// A point or vector written as exactly three numbers `[x, y, z]`. Kept in f64 as written,
/// so that validation sees the value the user typed (1e300, not its f32 rounding `inf`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Point(pub(crate) [f64; 3]);

impl<'de> Deserialize<'de> for Point {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct PointVisitor;

        impl<'de> Visitor<'de> for PointVisitor {
            type Value = Point;

            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an array of exactly 3 numbers [x, y, z]")
            }

            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Point, A::Error> {
                exactly_three(seq, &self).map(Point)
            }
        }

        d.deserialize_seq(PointVisitor)
    }
}

/// Reads exactly three numbers from `seq`: fewer or more is an error naming the count.
fn exactly_three<'de, A: SeqAccess<'de>>(
    mut seq: A,
    expected: &dyn de::Expected,
) -> Result<[f64; 3], A::Error> {
    let mut c = [0.0f64; 3];
    for (k, slot) in c.iter_mut().enumerate() {
        *slot = seq
            .next_element::<f64>()?
            .ok_or_else(|| de::Error::invalid_length(k, expected))?;
    }
    let mut n = 3;
    while seq.next_element::<de::IgnoredAny>()?.is_some() {
        n += 1;
    }
    if n > 3 {
        return Err(de::Error::invalid_length(n, expected));
    }
    Ok(c)
}

/// Three numbers written either as `[a, b, c]` or as one number `a` meaning `[a, a, a]`
/// (colours, fluxes, scale factors), kept in f64 as written.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Triple {
    pub(crate) value: [f64; 3],
    /// True when written as one number, so that messages can quote it as written.
    pub(crate) scalar: bool,
}

impl<'de> Deserialize<'de> for Triple {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct TripleVisitor;

        impl<'de> Visitor<'de> for TripleVisitor {
            type Value = Triple;

            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number or an array of 3 numbers")
            }

            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Triple, E> {
                Ok(Triple {
                    value: [v; 3],
                    scalar: true,
                })
            }

            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Triple, E> {
                self.visit_f64(v as f64)
            }

            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Triple, E> {
                self.visit_f64(v as f64)
            }

            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Triple, A::Error> {
                Ok(Triple {
                    value: exactly_three(seq, &self)?,
                    scalar: false,
                })
            }
        }

        d.deserialize_any(TripleVisitor)
    }
}
