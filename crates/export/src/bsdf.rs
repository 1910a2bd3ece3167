//! bdpm's materials as Mitsuba 3 BSDFs.
//!
//! Lambert → `diffuse`, mirror → `conductor`, dielectric → `dielectric` are exact; the
//! Gaussian lobe (method.md §9) has no Mitsuba counterpart and becomes a stand-in (a blend of
//! `diffuse` and a Beckmann `roughconductor` of the lobe's width), with a warning. Surfaces
//! other than dielectrics are two-sided in bdpm, so they are wrapped in `twosided`; a
//! dielectric is not (its outside is the side its normals face, in both renderers).

use bdpm_bdf::{Bdf, Material as Model};
use bdpm_scene::{Material, Texture, Wrap};
use glam::DVec3;

use crate::xml::Element;

/// A material's BSDF and what it needs beside it.
pub(crate) struct Mapped {
    /// The `<bsdf>` element, with its `id`.
    pub element: Element,
    /// The texture image to write, if textured.
    pub texture: Option<Image>,
    /// What the mapping changed, one line each.
    pub warnings: Vec<String>,
}

/// An image file to write beside the scene: its path relative to the scene file, its bytes.
pub(crate) type Image = (String, Vec<u8>);

/// The id of material `index`'s BSDF in the scene file.
pub(crate) fn id(index: u32) -> String {
    format!("mat{index}")
}

/// Mitsuba's BSDF for material `index` of the scene, `texture` its base-colour texture.
pub(crate) fn map(
    index: u32,
    material: &Material,
    texture: Option<&Texture>,
) -> Result<Mapped, String> {
    let mut warnings = Vec::new();
    let inner = match &material.delta {
        Some(Model::Mirror(m)) => {
            let mut c = Element::plugin("bsdf", "conductor");
            c = match m.conductor_index() {
                Some((eta, k)) => c.rgb("eta", eta).rgb("k", k),
                None => c.string("material", "none"),
            };
            let c = c.rgb("specular_reflectance", m.reflectance());
            return Ok(plain(index, Element::plugin("bsdf", "twosided").child(c)));
        }
        Some(Model::Dielectric(d)) => {
            let e = Element::plugin("bsdf", "dielectric")
                .float("int_ior", f64::from(d.eta()))
                .float("ext_ior", 1.0)
                .rgb("specular_reflectance", d.reflect_tint())
                .rgb("specular_transmittance", d.transmit_tint());
            return Ok(plain(index, e));
        }
        // A smooth material keeps its model in `bdf` (`Material::new`).
        Some(Model::Smooth(_)) | None => {
            smooth(index, &material.name, &material.bdf, texture, &mut warnings)?
        }
    };
    let (element, image) = inner;
    Ok(Mapped {
        element: Element::plugin("bsdf", "twosided")
            .attr("id", id(index))
            .child(element),
        texture: image,
        warnings,
    })
}

/// A delta material's element with its id. A texture is not applied: bdpm applies none to
/// mirrors and glass either.
fn plain(index: u32, element: Element) -> Mapped {
    Mapped {
        element: element.attr("id", id(index)),
        texture: None,
        warnings: Vec::new(),
    }
}

/// Lambert (`diffuse`), or Lambert plus the Gaussian lobe as the stand-in: a `blendbsdf` of
/// `diffuse` and a Beckmann `roughconductor` without Fresnel term (`material = none`) of
/// roughness α = Δ/√2. Under the lobe's exp(−(1 − cos ϑ)/Δ²) ≈ exp(−ϑ²/(2Δ²)), ϑ the angle
/// to the mirror direction; Beckmann's exp(−tan²θ_h/α²) with the half-vector angle θ_h ≈ ϑ/2
/// is exp(−ϑ²/(4α²)): the same width for α = Δ/√2. The blend weight w puts kd/(1 − w) on
/// the diffuse part and gr/w on the lobe, so both albedo factors are bdpm's.
fn smooth(
    index: u32,
    name: &str,
    bdf: &Bdf,
    texture: Option<&Texture>,
    warnings: &mut Vec<String>,
) -> Result<(Element, Option<Image>), String> {
    let (kd, gr) = (bdf.kd().as_dvec3(), bdf.gr().as_dvec3());
    let lobe = bdf.delta().filter(|_| gr.max_element() > 0.0);
    // In f64, so that kd/(1 − w) and gr/w round to kd and gr's own f32 values where they can.
    let weight = match lobe {
        Some(_) => gr.max_element() / (gr.max_element() + kd.max_element()),
        None => 0.0,
    };
    // Kept in f64 and written with f64's digits where it is no f32: the import's kd·(1 − w)
    // then rounds to kd's own f32 (an f32 here lost its last bit on one of
    // scenes/cornell-box-glossy.toml's walls).
    let diffuse_scale = if weight < 1.0 {
        kd / (1.0 - weight)
    } else {
        DVec3::ZERO
    };
    let (diffuse, image) = diffuse(index, name, diffuse_scale, texture, warnings)?;
    let Some(delta) = lobe else {
        return Ok((diffuse, image));
    };
    let alpha = f64::from(delta) / std::f64::consts::SQRT_2;
    let rough = Element::plugin("bsdf", "roughconductor")
        .string("distribution", "beckmann")
        .float("alpha", alpha)
        .string("material", "none")
        .rgb("specular_reflectance", gr / weight);
    warnings.push(format!(
        "material '{name}': Mitsuba has no Gaussian lobe; written as a stand-in, blendbsdf \
         (weight {weight:.4}) of diffuse and a Beckmann roughconductor of alpha {alpha:.5} \
         (the lobe's width delta = {:.3} deg, in radians / sqrt 2) without Fresnel term: the \
         same kd, gr and lobe width, not the same lobe shape or albedo \
         (docs/scene-format.md, \"Export to Mitsuba 3\")",
        f64::from(delta).to_degrees()
    ));
    let blend = Element::plugin("bsdf", "blendbsdf")
        .float("weight", weight)
        .child(diffuse)
        .child(rough);
    Ok((blend, image))
}

/// `diffuse` of reflectance `kd` (times the texture, baked into a float EXR image of
/// `textures/`).
fn diffuse(
    index: u32,
    name: &str,
    kd: DVec3,
    texture: Option<&Texture>,
    warnings: &mut Vec<String>,
) -> Result<(Element, Option<Image>), String> {
    let element = Element::plugin("bsdf", "diffuse");
    let Some(texture) = texture else {
        return Ok((element.rgb("reflectance", kd), None));
    };
    let path = format!("textures/{}.exr", id(index));
    let bitmap = bitmap(texture, "reflectance", &path, name, warnings);
    let bytes = crate::image::exr(texture, kd.as_vec3())?;
    Ok((element.child(bitmap), Some((path, bytes))))
}

/// A `bitmap` texture named `parameter` reading the EXR at `path` as bdpm samples `texture`:
/// bilinear, raw (linear) values, the sampler's wrap mode (u's for both axes, with a warning
/// naming material `name` where v's differs).
pub(crate) fn bitmap(
    texture: &Texture,
    parameter: &str,
    path: &str,
    name: &str,
    warnings: &mut Vec<String>,
) -> Element {
    let wrap = |w: Wrap| match w {
        Wrap::Repeat => "repeat",
        Wrap::ClampToEdge => "clamp",
        Wrap::MirroredRepeat => "mirror",
    };
    let (wrap_u, wrap_v) = texture.wraps();
    if wrap_u != wrap_v {
        warnings.push(format!(
            "material '{name}': its texture wraps u by {} and v by {}; Mitsuba's bitmap has one \
             wrap_mode, written as {} for both (the image can differ where v leaves [0, 1] \
             or comes within half a texel of its ends; mirror and clamp agree inside it)",
            wrap(wrap_u),
            wrap(wrap_v),
            wrap(wrap_u)
        ));
    }
    Element::plugin("texture", "bitmap")
        .attr("name", parameter)
        .string("filename", path)
        .string("filter_type", "bilinear")
        .string("wrap_mode", wrap(wrap_u))
        .boolean("raw", true)
}
