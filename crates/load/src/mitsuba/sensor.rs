//! The `<sensor>` (a pinhole camera and its film) and `<emitter>`s: point lights map, an area
//! emitter gives its shape's radiance, everything else is refused.

use std::sync::Arc;

use bdpm_scene::{Camera, PointLight, Texture};
use glam::{DMat4, DVec3, Vec3};
use roxmltree::Node;

use super::bitmap::Loader;
use super::bsdf::{Named, Reader};
use super::doc::{Props, Xml, elements};
use super::transform;
use crate::LoadError;

/// The camera and the film's size.
pub(crate) struct Sensor {
    pub(crate) camera: Camera,
    pub(crate) width: u32,
    pub(crate) height: u32,
}

/// Mitsuba's film size when the file gives none.
const FILM_DEFAULT: (u32, u32) = (768, 576);

/// A `perspective` (or `thinlens`, as a pinhole) `<sensor>`.
pub(crate) fn sensor(
    x: &Xml<'_>,
    node: Node<'_, '_>,
    warnings: &mut Vec<String>,
) -> Result<Sensor, LoadError> {
    let kind = x.need(node, "type")?;
    match kind.as_str() {
        "perspective" => {}
        "thinlens" => warnings.push(x.warn(
            node,
            "rendered as a pinhole (perspective): bdpm has no depth of field",
        )),
        other => return Err(x.err(
            node,
            format!(
                "sensor type \"{other}\" is not supported: bdpm has a pinhole camera (perspective)"
            ),
        )),
    }
    let p = Props::new(node);
    let (width, height) = film(x, node, warnings)?;
    let (fov, axis) = field_of_view(x, &p)?;
    let aspect = f64::from(width) / f64::from(height);
    let half = (0.5 * fov.to_radians()).tan();
    // The factor from the given axis's tan(fov/2) to the vertical one's.
    let to_vertical = match axis.as_str() {
        "y" => None,
        "x" => Some(1.0 / aspect),
        "diagonal" => Some(1.0 / (1.0 + aspect * aspect).sqrt()),
        "smaller" if width < height => Some(1.0 / aspect),
        "larger" if width > height => Some(1.0 / aspect),
        "smaller" | "larger" => None,
        other => {
            return Err(x.err(
                node,
                format!("fov_axis \"{other}\" is not x, y, diagonal, smaller or larger"),
            ));
        }
    };
    // The vertical angle as written where it is the vertical one, so that bdpm's own export
    // (fov_axis y) reads back to the same f32.
    let vfov = match to_vertical {
        None => fov,
        Some(f) => 2.0 * (half * f).atan().to_degrees(),
    };
    p.ignore(&[
        "near_clip",
        "far_clip",
        "focus_distance",
        "aperture_radius",
        "principal_point_offset_x",
        "principal_point_offset_y",
    ]);
    let (eye, target, up) = frame(x, &p, node)?;
    let camera = Camera::look_at(eye, target, up, vfov as f32, width, height)
        .map_err(|e| x.err(node, e.to_string()))?;
    p.unread(x, "<sensor>", warnings);
    Ok(Sensor {
        camera,
        width,
        height,
    })
}

/// The field of view in degrees and its axis: `fov` and `fov_axis` (default x), or a
/// `focal_length` ("50mm" when neither is given) on the 36 × 24 mm film's diagonal, as
/// Mitsuba's `parse_fov` reads them.
fn field_of_view(x: &Xml<'_>, p: &Props<'_, '_>) -> Result<(f64, String), LoadError> {
    let node = p.node();
    if let Some(fov_node) = p.get("fov") {
        let fov = x.float(p, "fov", 0.0)?;
        if !(fov > 0.0 && fov < 179.0) {
            return Err(x.err(fov_node, format!("{fov} is outside (0, 179) degrees")));
        }
        return Ok((fov, x.string(p, "fov_axis")?.unwrap_or_else(|| "x".into())));
    }
    let written = x
        .string(p, "focal_length")?
        .unwrap_or_else(|| "50mm".into());
    let mm = written
        .trim()
        .trim_end_matches("mm")
        .trim()
        .parse::<f64>()
        .ok()
        .filter(|f| f.is_finite() && *f > 0.0)
        .ok_or_else(|| {
            x.err(
                node,
                format!(
                    "focal_length \"{written}\" is not a positive length in mm such as \"50mm\""
                ),
            )
        })?;
    let fov = 2.0
        * ((36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * mm))
            .atan()
            .to_degrees();
    Ok((fov, "diagonal".into()))
}

/// Eye, target and up of the sensor's `to_world`: a lone `<lookat>` as written (in f32, as
/// bdpm's `[camera]` is read), any other transform through its matrix (Mitsuba's camera
/// looks down its local +z with +y up and +x to the image's left).
fn frame(
    x: &Xml<'_>,
    p: &Props<'_, '_>,
    node: Node<'_, '_>,
) -> Result<(Vec3, Vec3, Vec3), LoadError> {
    if let Some(t) = p.get("to_world") {
        let steps: Vec<_> = elements(t).collect();
        if let [only] = steps.as_slice()
            && only.tag_name().name() == "lookat"
        {
            // Through the matrix first, for its checks (target = origin, up parallel).
            transform::matrix(x, t)?;
            let (o, target, up) = transform::lookat(x, *only)?;
            return Ok((o.as_vec3(), target.as_vec3(), up.as_vec3()));
        }
    }
    let m = transform::to_world(x, p)?.unwrap_or(DMat4::IDENTITY);
    let eye = m.transform_point3(DVec3::ZERO);
    let dir = m.transform_vector3(DVec3::Z).normalize_or_zero();
    let up = m.transform_vector3(DVec3::Y);
    let left = m.transform_vector3(DVec3::X);
    if dir == DVec3::ZERO || dir.cross(up).length() == 0.0 {
        return Err(x.err(
            node,
            "to_world maps the camera's axes onto a line or a point",
        ));
    }
    if dir.cross(up).dot(-left) < 0.0 {
        return Err(x.err(
            node,
            "to_world mirrors the image (negative determinant); bdpm's camera cannot",
        ));
    }
    Ok((eye.as_vec3(), (eye + dir).as_vec3(), up.as_vec3()))
}

/// The film's width and height (Mitsuba's defaults when not given); a filter other than
/// `box` is noted: bdpm's pixels are boxes.
fn film(
    x: &Xml<'_>,
    sensor: Node<'_, '_>,
    warnings: &mut Vec<String>,
) -> Result<(u32, u32), LoadError> {
    if let Some(sampler) = elements(sensor).find(|c| c.tag_name().name() == "sampler")
        && let Some(n) = Props::new(sampler).get("sample_count")
    {
        warnings.push(x.warn(
            n,
            "ignored: bdpm's camera samples come from --spp and --passes",
        ));
    }
    if let Some(c) = elements(sensor).find(|c| c.tag_name().name() == "film") {
        let p = Props::new(c);
        let size = |name: &str, default: u32| -> Result<u32, LoadError> {
            let v = x.float(&p, name, f64::from(default))?;
            if (1.0..=f64::from(crate::limits::MAX_RESOLUTION)).contains(&v) && v.fract() == 0.0 {
                Ok(v as u32)
            } else {
                Err(x.err(
                    p.get(name).unwrap_or(c),
                    format!(
                        "{v} pixels is outside [1, {}]",
                        crate::limits::MAX_RESOLUTION
                    ),
                ))
            }
        };
        let (w, h) = (
            size("width", FILM_DEFAULT.0)?,
            size("height", FILM_DEFAULT.1)?,
        );
        if let Some(f) = elements(c).find(|f| f.tag_name().name() == "rfilter")
            && f.attribute("type") != Some("box")
        {
            warnings.push(x.warn(f, "bdpm's pixels are box filtered (each pixel the mean over its square); this filter is not applied"));
        }
        return Ok((w, h));
    }
    Ok(FILM_DEFAULT)
}

/// A `point` emitter as a point light of flux 4πI; every other emitter is refused.
pub(crate) fn emitter(
    x: &Xml<'_>,
    node: Node<'_, '_>,
    warnings: &mut Vec<String>,
) -> Result<PointLight, LoadError> {
    let kind = x.need(node, "type")?;
    match kind.as_str() {
        "point" => {}
        "area" => return Err(x.err(node, "an area emitter must be nested in the <shape> that emits (Mitsuba takes its surface from there)")),
        other => return Err(x.err(node, format!("emitter type \"{other}\" is not supported: bdpm imports isotropic point lights only (use <emitter type=\"point\">)"))),
    }
    let p = Props::new(node);
    let position = match p.get("position") {
        Some(n) => x.xyz(n, 0.0)?,
        None => transform::to_world(x, &p)?
            .unwrap_or(DMat4::IDENTITY)
            .transform_point3(DVec3::ZERO),
    };
    let intensity = emitted(x, &p, "intensity", warnings)?;
    // In f64: bdpm's export writes Φ/(4π) with the digits that bring Φ back.
    let flux = (intensity * (4.0 * std::f64::consts::PI)).as_vec3();
    let position = position.as_vec3();
    if !(flux.is_finite() && position.is_finite()) {
        return Err(x.err(
            node,
            "position or flux is beyond the single-precision range",
        ));
    }
    p.unread(x, "<emitter type=\"point\">", warnings);
    Ok(PointLight { position, flux })
}

/// The radiance Le (W·m⁻²·sr⁻¹ per channel) of an `<emitter type="area">` nested in a
/// shape: `radiance` as `<rgb>`, `<float>` or a `<spectrum>` (Mitsuba's default 1), or a
/// bitmap (then Le is its factor, and the texture is returned beside it: Le × texture); a
/// spectrum from a file is refused.
pub(crate) fn area_radiance(
    x: &Xml<'_>,
    node: Node<'_, '_>,
    warnings: &mut Vec<String>,
    bitmaps: &mut Loader<'_>,
) -> Result<(DVec3, Option<Arc<Texture>>), LoadError> {
    let p = Props::new(node);
    if let Some(n) = p
        .get("radiance")
        .filter(|n| matches!(n.tag_name().name(), "texture" | "ref"))
    {
        let named = Named::new();
        let b = Reader {
            x,
            named: &named,
            warnings,
            bitmaps: Some(bitmaps),
        }
        .bitmap(n)?;
        p.unread(x, "<emitter type=\"area\">", warnings);
        return Ok((b.factor, Some(b.texture)));
    }
    let radiance = emitted(x, &p, "radiance", warnings)?;
    if !radiance.as_vec3().is_finite() {
        return Err(x.err(
            node,
            format!("radiance {radiance} is beyond the single-precision range"),
        ));
    }
    p.unread(x, "<emitter type=\"area\">", warnings);
    Ok((radiance, None))
}

/// An emitter's colour property `name` (Mitsuba's default 1 in every channel), refused where
/// negative.
fn emitted(
    x: &Xml<'_>,
    p: &Props<'_, '_>,
    name: &str,
    warnings: &mut Vec<String>,
) -> Result<DVec3, LoadError> {
    let named = Named::new();
    let c = Reader {
        x,
        named: &named,
        warnings,
        bitmaps: None,
    }
    .colour(p, name, DVec3::ONE)?;
    if c.min_element() < 0.0 {
        return Err(x.err(p.node(), format!("{name} {c} is negative")));
    }
    Ok(c)
}
