//! `<transform>`: Mitsuba's `translate`, `rotate`, `scale`, `matrix` and `lookat`, composed
//! in its order (each later element multiplies from the left), in double precision.

use glam::{DMat3, DMat4, DVec3, DVec4};
use roxmltree::Node;

use super::doc::{Xml, elements};
use crate::LoadError;

/// The matrix of `<transform>` element `node`: the product of its children, the last one
/// leftmost. Every number finite, the result finite.
pub(crate) fn matrix(x: &Xml<'_>, node: Node<'_, '_>) -> Result<DMat4, LoadError> {
    let mut m = DMat4::IDENTITY;
    for c in elements(node) {
        let step = match c.tag_name().name() {
            "translate" => DMat4::from_translation(x.xyz(c, 0.0)?),
            "scale" => scale(x, c)?,
            "rotate" => rotate(x, c)?,
            "matrix" => given(x, c)?,
            "lookat" => {
                let (origin, target, up) = lookat(x, c)?;
                look_at_matrix(x, c, origin, target, up)?
            }
            other => {
                return Err(x.err(
                    c,
                    format!(
                        "<{other}> is not a transform (translate, rotate, scale, matrix or lookat)"
                    ),
                ));
            }
        };
        m = step * m;
        if !m.is_finite() {
            return Err(x.err(c, "the transform is not finite after this step (overflow)"));
        }
    }
    Ok(m)
}

/// `<scale value="s"/>`, `value="x y z"` or attributes x, y, z (default 1).
fn scale(x: &Xml<'_>, c: Node<'_, '_>) -> Result<DMat4, LoadError> {
    Ok(DMat4::from_scale(x.xyz(c, 1.0)?))
}

/// `<rotate angle="deg" x=… y=… z=…/>` or `value="x y z"` for the axis.
fn rotate(x: &Xml<'_>, c: Node<'_, '_>) -> Result<DMat4, LoadError> {
    let axis = x.xyz(c, 0.0)?;
    let angle = x
        .number(c, "angle")?
        .ok_or_else(|| x.err(c, "missing attribute angle (degrees)"))?;
    let unit = axis.normalize_or_zero();
    if unit == DVec3::ZERO {
        return Err(x.err(c, "the rotation axis is zero"));
    }
    Ok(DMat4::from_axis_angle(unit, angle.to_radians()))
}

/// `<matrix value="16 numbers, row by row"/>` (or 9 for a 3 × 3 linear part).
fn given(x: &Xml<'_>, c: Node<'_, '_>) -> Result<DMat4, LoadError> {
    let v = x.numbers(c, "value")?;
    match v.len() {
        16 => {
            let rows: Vec<DVec4> = v
                .chunks(4)
                .map(|r| DVec4::new(r[0], r[1], r[2], r[3]))
                .collect();
            Ok(DMat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose())
        }
        9 => Ok(DMat4::from_mat3(DMat3::from_cols_slice(&v).transpose())),
        n => Err(x.err(c, format!("value has {n} numbers; expected 16 (or 9)"))),
    }
}

/// A `<lookat>`'s origin, target and up (default up: +y).
pub(crate) fn lookat(x: &Xml<'_>, c: Node<'_, '_>) -> Result<(DVec3, DVec3, DVec3), LoadError> {
    let origin = x.triple(c, "origin")?;
    let target = x.triple(c, "target")?;
    let up = match c.attribute("up") {
        Some(_) => x.triple(c, "up")?,
        None => DVec3::Y,
    };
    Ok((origin, target, up))
}

/// Mitsuba's look-at frame: columns left = up × dir, up′ = dir × left, dir, origin.
fn look_at_matrix(
    x: &Xml<'_>,
    c: Node<'_, '_>,
    origin: DVec3,
    target: DVec3,
    up: DVec3,
) -> Result<DMat4, LoadError> {
    let dir = (target - origin).normalize_or_zero();
    if dir == DVec3::ZERO {
        return Err(x.err(c, "target equals origin: there is no viewing direction"));
    }
    let left = up.cross(dir).normalize_or_zero();
    if left == DVec3::ZERO {
        return Err(x.err(c, "up is parallel to the viewing direction (or zero)"));
    }
    let new_up = dir.cross(left);
    Ok(DMat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    ))
}

/// The `<transform name="to_world">` child of `node`'s properties, or the identity.
pub(crate) fn to_world(
    x: &Xml<'_>,
    p: &super::doc::Props<'_, '_>,
) -> Result<Option<DMat4>, LoadError> {
    match p.get("to_world") {
        Some(t) if t.tag_name().name() == "transform" => matrix(x, t).map(Some),
        Some(t) => Err(x.err(t, "to_world must be a <transform>")),
        None => Ok(None),
    }
}
