//! Mitsuba BSDFs as bdpm materials (docs/scene-format.md, "Import from Mitsuba 3"): the exact
//! ones (`diffuse`, `conductor`, `dielectric`, `twosided`, `blendbsdf` of those), the
//! approximated ones with a warning saying how (`roughconductor`, `roughplastic`, `plastic`,
//! the maps of `bumpmap` and `normalmap`), and refusals for the rest. A diffuse reflectance
//! may be a bitmap texture (`bitmap`): kd = its factor × the texture, as for glTF.

use std::collections::HashMap;
use std::sync::Arc;

use bdpm_bdf::{Bdf, Dielectric, Material, Mirror};
use bdpm_scene::Texture;
use glam::DVec3;
use roxmltree::Node;

use super::bitmap::{Bitmap, Loader};
use super::doc::{Props, Xml, elements, property};
use crate::LoadError;
use crate::limits::{DELTA_MAX_DEGREES, DELTA_MIN_DEGREES};
use crate::material_types::IOR_RANGE;

/// A BSDF as bdpm can render it, before it becomes a [`Material`].
#[derive(Clone, Debug)]
pub(crate) enum Bsdf {
    /// Lambert `kd` (times `texture`, if any) plus a Gaussian lobe `gr` of width `delta`
    /// (radians).
    Smooth {
        kd: DVec3,
        gr: DVec3,
        delta: Option<f64>,
        texture: Option<Arc<Texture>>,
    },
    /// A mirror or a smooth dielectric.
    Delta(Material),
}

/// The BSDFs defined so far with an `id`, and where they went among the scene's materials.
pub(crate) type Named = HashMap<String, (u32, Bsdf)>;

/// Mitsuba's named indices of refraction (its `int_ior`/`ext_ior` strings).
const IOR_NAMES: [(&str, f64); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// Reads BSDF elements: the file, the named BSDFs so far, where warnings go, and what
/// reading a bitmap takes (`None` where no texture is read: a point light's intensity).
pub(crate) struct Reader<'r, 'x, 'l> {
    pub(crate) x: &'r Xml<'x>,
    pub(crate) named: &'r Named,
    pub(crate) warnings: &'r mut Vec<String>,
    pub(crate) bitmaps: Option<&'r mut Loader<'l>>,
}

impl Reader<'_, '_, '_> {
    /// The BSDF of `<bsdf>` element `node`, or of `<ref id=…>` to one.
    pub(crate) fn read(&mut self, node: Node<'_, '_>) -> Result<Bsdf, LoadError> {
        if node.tag_name().name() == "ref" {
            let id = self.x.need(node, "id")?;
            return match self.named.get(&id) {
                Some((_, b)) => Ok(b.clone()),
                None => Err(self
                    .x
                    .err(node, format!("no <bsdf id=\"{id}\"> before this reference"))),
            };
        }
        let kind = self.x.need(node, "type")?;
        let p = Props::new(node);
        let out = match kind.as_str() {
            "diffuse" => {
                let (kd, texture) = self.albedo(&p, "reflectance", DVec3::splat(0.5))?;
                Bsdf::Smooth {
                    kd,
                    gr: DVec3::ZERO,
                    delta: None,
                    texture,
                }
            }
            "twosided" => self.twosided(node)?,
            "conductor" => self.conductor(&p)?,
            "dielectric" => self.dielectric(&p)?,
            "roughconductor" => self.rough_conductor(&p)?,
            "plastic" | "roughplastic" => self.plastic(&p, kind == "roughplastic")?,
            "blendbsdf" => self.blend(&p)?,
            "bumpmap" | "normalmap" => {
                self.warnings.push(self.x.warn(node, "the map is ignored: bdpm shades with the mesh's normals; the nested BSDF is used as it is"));
                p.ignore(&["normalmap", "scale", "arg"]);
                self.nested(node)?
            }
            "thindielectric" => {
                return Err(self.x.err(node, "not supported: bdpm has no thin dielectric (a sheet of glass without refraction); model the sheet as a closed mesh with a dielectric, or use a conductor"));
            }
            other => {
                return Err(self.x.err(node, format!("BSDF type \"{other}\" is not supported: bdpm maps diffuse, twosided, conductor, dielectric, roughconductor, plastic, roughplastic, blendbsdf, bumpmap and normalmap (docs/scene-format.md, \"Import from Mitsuba 3\")")));
            }
        };
        p.unread(self.x, &format!("<bsdf type=\"{kind}\">"), self.warnings);
        Ok(out)
    }

    /// The one BSDF nested in `node` (an element or a reference).
    fn nested(&mut self, node: Node<'_, '_>) -> Result<Bsdf, LoadError> {
        let inner: Vec<_> = elements(node)
            .filter(|c| matches!(c.tag_name().name(), "bsdf" | "ref"))
            .collect();
        match inner.first() {
            Some(&first) => self.read(first),
            None => Err(self.x.err(node, "has no nested <bsdf> (or <ref id=…>)")),
        }
    }

    /// bdpm's surfaces (but glass) are two-sided: the front BSDF serves both sides.
    fn twosided(&mut self, node: Node<'_, '_>) -> Result<Bsdf, LoadError> {
        let count = elements(node)
            .filter(|c| matches!(c.tag_name().name(), "bsdf" | "ref"))
            .count();
        if count > 1 {
            self.warnings.push(self.x.warn(node, "its second (back-side) BSDF is ignored: a bdpm surface has one material on both sides"));
        }
        self.nested(node)
    }

    /// A colour property: `<rgb>`, `<spectrum>` (one value: uniform; wavelength:value pairs:
    /// their means over 600–700, 500–600 and 400–500 nm as red, green, blue, with a warning)
    /// or `<float>`; `default` when absent.
    pub(crate) fn colour(
        &mut self,
        p: &Props<'_, '_>,
        name: &str,
        default: DVec3,
    ) -> Result<DVec3, LoadError> {
        let Some(n) = p.get(name) else {
            return Ok(default);
        };
        let x = self.x;
        match n.tag_name().name() {
            "rgb" | "float" | "integer" => {
                let v = x.numbers(n, "value")?;
                match v.as_slice() {
                    [a] => Ok(DVec3::splat(*a)),
                    [r, g, b] => Ok(DVec3::new(*r, *g, *b)),
                    _ => Err(x.err(n, format!("value has {} numbers; expected 1 or 3", v.len()))),
                }
            }
            "spectrum" => self.spectrum(n),
            "texture" | "ref" => Err(x.err(
                n,
                "a texture is not supported here: bdpm reads bitmap textures as a diffuse \
                 reflectance and as an area emitter's radiance; give the colour as <rgb>",
            )),
            other => Err(x.err(
                n,
                format!("<{other}> is not a colour (rgb, spectrum or float)"),
            )),
        }
    }

    /// A colour that may be a bitmap (a diffuse reflectance): the colour, or the bitmap's
    /// factor and its texture.
    fn albedo(
        &mut self,
        p: &Props<'_, '_>,
        name: &str,
        default: DVec3,
    ) -> Result<(DVec3, Option<Arc<Texture>>), LoadError> {
        match p.get(name) {
            Some(n) if matches!(n.tag_name().name(), "texture" | "ref") => {
                let b = self.bitmap(n)?;
                Ok((b.factor, Some(b.texture)))
            }
            _ => Ok((self.colour(p, name, default)?, None)),
        }
    }

    /// The bitmap of a `<texture>` (or a `<ref>` to one) element `n`.
    pub(crate) fn bitmap(&mut self, n: Node<'_, '_>) -> Result<Bitmap, LoadError> {
        match &mut self.bitmaps {
            Some(loader) => loader.read(self.x, n, self.warnings),
            None => Err(self.x.err(
                n,
                "a texture is not supported here: give the colour as <rgb>",
            )),
        }
    }

    fn spectrum(&mut self, n: Node<'_, '_>) -> Result<DVec3, LoadError> {
        let x = self.x;
        if n.attribute("filename").is_some() {
            return Err(x.err(
                n,
                "spectra from files are not supported: give the colour as <rgb>",
            ));
        }
        let text = x.need(n, "value")?;
        if !text.contains(':') {
            let v = x.numbers(n, "value")?;
            return match v.as_slice() {
                [a] => Ok(DVec3::splat(*a)),
                _ => Err(x.err(n, "a spectrum without wavelengths takes one value")),
            };
        }
        let mut samples = Vec::new();
        for pair in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let parsed = pair.split_once(':').and_then(|(l, v)| {
                Some((l.trim().parse::<f64>().ok()?, v.trim().parse::<f64>().ok()?))
            });
            match parsed {
                Some((l, v)) if l.is_finite() && v.is_finite() => samples.push((l, v)),
                _ => {
                    return Err(x.err(
                        n,
                        format!("\"{pair}\" is not wavelength:value with finite numbers"),
                    ));
                }
            }
        }
        let band = |lo: f64, hi: f64| {
            let inside: Vec<f64> = samples
                .iter()
                .filter(|(l, _)| *l >= lo && *l <= hi)
                .map(|s| s.1)
                .collect();
            if inside.is_empty() {
                // No sample in the band: the nearest one.
                let mid = 0.5 * (lo + hi);
                samples
                    .iter()
                    .min_by(|a, b| (a.0 - mid).abs().total_cmp(&(b.0 - mid).abs()))
                    .map_or(0.0, |s| s.1)
            } else {
                inside.iter().sum::<f64>() / inside.len() as f64
            }
        };
        let rgb = DVec3::new(band(600.0, 700.0), band(500.0, 600.0), band(400.0, 500.0));
        self.warnings.push(x.warn(n, format!("a spectrum of {} samples taken as rgb {:.4} {:.4} {:.4}: the mean over 600–700, 500–600 and 400–500 nm (a rough stand-in for Mitsuba's spectral rendering)", samples.len(), rgb.x, rgb.y, rgb.z)));
        Ok(rgb)
    }

    /// An index of refraction: a number or one of Mitsuba's names.
    fn ior(&mut self, p: &Props<'_, '_>, name: &str, default: f64) -> Result<f64, LoadError> {
        let x = self.x;
        property(p, name, default, |n| match n.tag_name().name() {
            "float" | "integer" => x.scalar(n),
            "string" => {
                let s = x.need(n, "value")?;
                IOR_NAMES.iter().find(|(k, _)| k.eq_ignore_ascii_case(s.trim())).map(|&(_, v)| v).ok_or_else(|| x.err(n, format!("\"{s}\" is not one of Mitsuba's named indices of refraction; give a number")))
            }
            other => Err(x.err(n, format!("expected <float> or <string>, found <{other}>"))),
        })
    }

    /// `conductor`: a perfect mirror of `specular_reflectance`, with the conductor's Fresnel
    /// term when `eta` and `k` are given; a named `material` other than `none` is not known
    /// here and becomes a perfect mirror with a warning.
    fn conductor(&mut self, p: &Props<'_, '_>) -> Result<Bsdf, LoadError> {
        let reflectance = self.colour(p, "specular_reflectance", DVec3::ONE)?;
        let node = p.node();
        let bad = |e: bdpm_bdf::SpecularError| self.x.err(node, e.to_string());
        let has_index = p.get("eta").is_some() || p.get("k").is_some();
        let mirror = if has_index {
            let eta = self.colour(p, "eta", DVec3::ZERO)?;
            let k = self.colour(p, "k", DVec3::ZERO)?;
            Mirror::conductor(reflectance.as_vec3(), eta.as_vec3(), k.as_vec3()).map_err(bad)?
        } else {
            let material = self
                .x
                .string(p, "material")?
                .unwrap_or_else(|| "none".into());
            if material != "none" {
                self.warnings.push(self.x.warn(node, format!("material \"{material}\": bdpm has no table of conductors; rendered as a perfect mirror of specular_reflectance without Fresnel term (give eta and k as <rgb> for the conductor's Fresnel term)")));
            }
            Mirror::new(reflectance.as_vec3()).map_err(bad)?
        };
        p.ignore(&["ext_eta"]);
        Ok(Bsdf::Delta(Material::Mirror(mirror)))
    }

    /// `dielectric`: bdpm's smooth dielectric of index int_ior / ext_ior.
    fn dielectric(&mut self, p: &Props<'_, '_>) -> Result<Bsdf, LoadError> {
        let int = self.ior(p, "int_ior", 1.5046)?;
        let ext = self.ior(p, "ext_ior", 1.000277)?;
        let node = p.node();
        let ior = int / ext;
        if !(IOR_RANGE.0..=IOR_RANGE.1).contains(&ior) {
            return Err(self.x.err(
                node,
                format!(
                    "int_ior / ext_ior = {ior} is outside [{}, {}]",
                    IOR_RANGE.0, IOR_RANGE.1
                ),
            ));
        }
        let reflect = self.colour(p, "specular_reflectance", DVec3::ONE)?;
        let transmit = self.colour(p, "specular_transmittance", DVec3::ONE)?;
        let d = Dielectric::tinted(ior as f32, reflect.as_vec3(), transmit.as_vec3())
            .map_err(|e| self.x.err(node, e.to_string()))?;
        Ok(Bsdf::Delta(Material::Dielectric(d)))
    }

    /// The lobe width Δ of a microfacet roughness α: Δ = α√2 (the inverse of the export's
    /// stand-in, docs/scene-format.md), anisotropic α the mean of α_u and α_v.
    fn lobe_width(&mut self, p: &Props<'_, '_>) -> Result<f64, LoadError> {
        let node = p.node();
        let alpha = match (p.get("alpha_u").is_some(), p.get("alpha_v").is_some()) {
            (true, _) | (_, true) => {
                let (u, v) = (
                    self.x.float(p, "alpha_u", 0.1)?,
                    self.x.float(p, "alpha_v", 0.1)?,
                );
                self.warnings.push(self.x.warn(node, format!("anisotropic roughness alpha_u {u}, alpha_v {v}: bdpm's lobe is isotropic, their mean is used")));
                0.5 * (u + v)
            }
            _ => self.x.float(p, "alpha", 0.1)?,
        };
        p.ignore(&["distribution", "sample_visible"]);
        let delta = alpha * std::f64::consts::SQRT_2;
        let (lo, hi) = (
            DELTA_MIN_DEGREES.to_radians(),
            DELTA_MAX_DEGREES.to_radians(),
        );
        if !(lo..=hi).contains(&delta) {
            let clamped = delta.clamp(lo, hi);
            self.warnings.push(self.x.warn(node, format!("alpha {alpha} gives a lobe width of {:.4} deg, outside bdpm's [{DELTA_MIN_DEGREES}, {DELTA_MAX_DEGREES}] deg; {:.4} deg is used", delta.to_degrees(), clamped.to_degrees())));
            return Ok(clamped);
        }
        Ok(delta)
    }

    /// `roughconductor` → bdpm's Gaussian lobe of gr = specular_reflectance and width
    /// Δ = α√2, without the conductor's Fresnel term.
    fn rough_conductor(&mut self, p: &Props<'_, '_>) -> Result<Bsdf, LoadError> {
        let gr = self.colour(p, "specular_reflectance", DVec3::ONE)?;
        let delta = self.lobe_width(p)?;
        p.ignore(&["material", "eta", "k", "ext_eta"]);
        self.warnings.push(self.x.warn(p.node(), format!("a microfacet lobe: rendered as bdpm's Gaussian lobe (method.md §9) of gr = specular_reflectance and width delta = alpha·√2 = {:.4} deg, without Fresnel term; not the same lobe shape", delta.to_degrees())));
        Ok(Bsdf::Smooth {
            kd: DVec3::ZERO,
            gr,
            delta: Some(delta),
            texture: None,
        })
    }

    /// `plastic` → Lambert of diffuse_reflectance (the smooth coating's reflection dropped);
    /// `roughplastic` → that plus a Gaussian lobe of gr = F₀ · specular_reflectance, F₀ the
    /// coating's normal-incidence Fresnel reflectance, width α√2; kd lowered where kd + gr
    /// would exceed 1.
    fn plastic(&mut self, p: &Props<'_, '_>, rough: bool) -> Result<Bsdf, LoadError> {
        let (kd, texture) = self.albedo(p, "diffuse_reflectance", DVec3::splat(0.5))?;
        let spec = self.colour(p, "specular_reflectance", DVec3::ONE)?;
        let n = self.ior(p, "int_ior", 1.49)? / self.ior(p, "ext_ior", 1.000277)?;
        let f0 = ((n - 1.0) / (n + 1.0)).powi(2);
        p.ignore(&["nonlinear"]);
        let node = p.node();
        if !rough {
            self.warnings.push(self.x.warn(node, format!("rendered as Lambert of diffuse_reflectance: the smooth coating's mirror reflection (F0 = {f0:.4}) is dropped, bdpm has no layered material")));
            return Ok(Bsdf::Smooth {
                kd,
                gr: DVec3::ZERO,
                delta: None,
                texture,
            });
        }
        let delta = self.lobe_width(p)?;
        let gr = spec * f0;
        let kd = kd.min(DVec3::ONE - gr);
        self.warnings.push(self.x.warn(node, format!("rendered as Lambert of diffuse_reflectance plus bdpm's Gaussian lobe of gr = F0·specular_reflectance (F0 = {f0:.4}) and width delta = alpha·√2 = {:.4} deg: not Mitsuba's layered model", delta.to_degrees())));
        Ok(Bsdf::Smooth {
            kd,
            gr,
            delta: Some(delta),
            texture,
        })
    }

    /// `blendbsdf` of two Lambert-plus-lobe BSDFs: their mix, exact for bdpm's model (the
    /// export's stand-in for the lobe comes back as it was written).
    fn blend(&mut self, p: &Props<'_, '_>) -> Result<Bsdf, LoadError> {
        let node = p.node();
        let w = match p.get("weight") {
            Some(n) if n.tag_name().name() == "float" => self.x.float(p, "weight", 0.5)?,
            Some(n) => {
                return Err(self.x.err(
                    n,
                    "a textured blend weight is not supported: give a <float>",
                ));
            }
            None => 0.5,
        };
        if !(0.0..=1.0).contains(&w) {
            return Err(self.x.err(node, format!("weight {w} is outside [0, 1]")));
        }
        let inner: Vec<_> = elements(node)
            .filter(|c| matches!(c.tag_name().name(), "bsdf" | "ref"))
            .collect();
        let [a, b] = inner.as_slice() else {
            return Err(self.x.err(
                node,
                format!("has {} nested BSDFs; a blend takes 2", inner.len()),
            ));
        };
        let (a, b) = (self.read(*a)?, self.read(*b)?);
        let (
            Bsdf::Smooth {
                kd: kd_a,
                gr: gr_a,
                delta: d_a,
                texture: t_a,
            },
            Bsdf::Smooth {
                kd: kd_b,
                gr: gr_b,
                delta: d_b,
                texture: t_b,
            },
        ) = (a, b)
        else {
            return Err(self.x.err(
                node,
                "a blend with a mirror or glass is not supported (bdpm has no such mix)",
            ));
        };
        let lobe_a = gr_a.max_element() > 0.0 && w < 1.0;
        let lobe_b = gr_b.max_element() > 0.0 && w > 0.0;
        let delta = match (lobe_a, lobe_b) {
            (true, true) if d_a != d_b => {
                return Err(self.x.err(
                    node,
                    "blends two lobes of different widths; bdpm's material has one lobe",
                ));
            }
            (true, _) => d_a,
            (_, true) => d_b,
            _ => None,
        };
        // Where a side is textured, the other side's diffuse part must be zero (or weigh
        // nothing): bdpm's kd is one factor times one texture.
        let texture = blend_texture((&kd_a, t_a, 1.0 - w), (&kd_b, t_b, w))
            .ok_or_else(|| self.x.err(node, "blends a textured diffuse part with another (untextured, or of another texture): bdpm's material has one reflectance texture"))?;
        Ok(Bsdf::Smooth {
            kd: kd_a * (1.0 - w) + kd_b * w,
            gr: gr_a * (1.0 - w) + gr_b * w,
            delta,
            texture,
        })
    }
}

/// One side of a blend: its diffuse reflectance, texture and weight.
type Side<'a> = (&'a DVec3, Option<Arc<Texture>>, f64);

/// The texture of a blend of sides `a` and `b`: `Some(None)` without one, `Some(t)` where one
/// texture shows in the weighted diffuse part (the other side's diffuse part zero, or both
/// sides the same image and wrap modes), `None` where two diffuse parts cannot share one.
fn blend_texture(a: Side<'_>, b: Side<'_>) -> Option<Option<Arc<Texture>>> {
    let shows = |s: &Side<'_>| s.2 > 0.0 && s.0.max_element() > 0.0;
    let (sa, sb) = (shows(&a), shows(&b));
    match (a.1.filter(|_| sa), b.1.filter(|_| sb)) {
        (None, None) => Some(None),
        (Some(t), None) if !sb => Some(Some(t)),
        (None, Some(t)) if !sa => Some(Some(t)),
        (Some(t), Some(u)) if Arc::ptr_eq(t.image(), u.image()) && t.wraps() == u.wraps() => {
            Some(Some(t))
        }
        _ => None,
    }
}

/// The bdpm material of `bsdf`, checked as the scene file's are (albedos in [0, 1], kd + gr
/// at most 1); an error names `node`.
pub(crate) fn material(
    x: &Xml<'_>,
    node: Node<'_, '_>,
    bsdf: &Bsdf,
) -> Result<Material, LoadError> {
    let (kd, gr, delta) = match bsdf {
        Bsdf::Delta(m) => return Ok(m.clone()),
        Bsdf::Smooth { kd, gr, delta, .. } => (*kd, *gr, *delta),
    };
    for (name, c) in [("reflectance", kd), ("lobe albedo", gr)] {
        if !(c.min_element() >= 0.0 && c.max_element() <= 1.0) {
            return Err(x.err(
                node,
                format!("{name} {c} is outside [0, 1] (bdpm's albedos conserve energy)"),
            ));
        }
    }
    if (kd + gr).max_element() > 1.0 + 1e-6 {
        return Err(x.err(
            node,
            format!("diffuse {kd} plus lobe {gr} exceeds 1: the surface would create energy"),
        ));
    }
    let bdf = match delta {
        Some(d) if gr.max_element() > 0.0 => Bdf::new(kd.as_vec3(), gr.as_vec3(), d as f32),
        _ => Bdf::lambert(kd.as_vec3()),
    };
    bdf.map(Material::from)
        .map_err(|e| x.err(node, e.to_string()))
}
