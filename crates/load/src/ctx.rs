//! The file being loaded, as every message of the scene file's build names it, and the
//! checks of single values that those messages come from.

use std::path::Path;

use bdpm_settings::number_text as num;
use glam::{Mat4, Vec3};

use crate::LoadError;
use crate::schema::{Point, Triple};

/// The file being loaded: the source of every message's prefix.
pub(crate) struct Ctx<'a> {
    pub(crate) file: &'a Path,
}

impl Ctx<'_> {
    pub(crate) fn bad(&self, field: impl Into<String>, message: impl Into<String>) -> LoadError {
        LoadError::Invalid {
            path: self.file.to_path_buf(),
            field: field.into(),
            message: message.into(),
        }
    }

    pub(crate) fn required<T>(
        &self,
        field: &str,
        value: Option<T>,
        what: &str,
    ) -> Result<T, LoadError> {
        value.ok_or_else(|| self.bad(field, format!("missing (required: {what})")))
    }

    /// A point as written, checked in the precision it was written in (so that 1e300 is
    /// reported as 1e300, not as its f32 rounding `inf`) and converted to f32.
    pub(crate) fn point(&self, field: &str, p: Point) -> Result<Vec3, LoadError> {
        let text = point_text(p.0);
        for c in p.0 {
            if !c.is_finite() {
                return Err(self.bad(field, format!("{text} is not finite (NaN or infinite)")));
            }
            if c.abs() > f32::MAX as f64 {
                return Err(self.bad(
                    field,
                    format!(
                        "{text}: {} is beyond the single-precision range (±3.4e38)",
                        num(c)
                    ),
                ));
            }
        }
        Ok(Vec3::new(p.0[0] as f32, p.0[1] as f32, p.0[2] as f32))
    }

    /// A positive length as written, converted to f32 ([`bdpm_settings::metres`], the check
    /// the render settings' lengths get too).
    pub(crate) fn positive(&self, field: &str, v: f64) -> Result<f32, LoadError> {
        bdpm_settings::metres(v).map_err(|e| self.bad(field, e.to_string()))
    }

    /// A number as written in [lo, hi], compared in f64 (the bounds as written, not their
    /// f32 roundings), converted to f32.
    pub(crate) fn within(&self, field: &str, v: f64, lo: f64, hi: f64) -> Result<f32, LoadError> {
        if v >= lo && v <= hi {
            Ok(v as f32)
        } else {
            Err(self.bad(field, format!("{} is outside [{lo}, {hi}]", num(v))))
        }
    }

    pub(crate) fn count<T: PartialOrd + std::fmt::Display>(
        &self,
        field: &str,
        v: T,
        lo: T,
        hi: T,
    ) -> Result<T, LoadError> {
        if v >= lo && v <= hi {
            Ok(v)
        } else {
            Err(self.bad(field, format!("{v} is outside [{lo}, {hi}]")))
        }
    }

    /// Every channel of `t` finite and in [lo, hi] (checked as written, in f64).
    pub(crate) fn channels(
        &self,
        field: &str,
        t: Triple,
        lo: f64,
        hi: Option<f64>,
    ) -> Result<Vec3, LoadError> {
        let range = match hi {
            Some(hi) => format!("is outside [{lo}, {hi}]"),
            None => format!("must be >= {lo}"),
        };
        let channels = t.value.into_iter().zip(["red", "green", "blue"]);
        for (c, name) in channels {
            if c.is_finite() && c >= lo && hi.is_none_or(|hi| c <= hi) && c <= f32::MAX as f64 {
                continue;
            }
            let range = if c.is_finite() && c > f32::MAX as f64 {
                "is beyond the single-precision range (3.4e38)".to_string()
            } else {
                range.clone()
            };
            let message = if t.scalar {
                format!("{} {range}", num(c))
            } else if !c.is_finite() {
                format!(
                    "{name} channel {} is not finite (in {})",
                    num(c),
                    point_text(t.value)
                )
            } else {
                format!(
                    "{name} channel {} {range} (in {})",
                    num(c),
                    point_text(t.value)
                )
            };
            return Err(self.bad(field, message));
        }
        Ok(Vec3::new(
            t.value[0] as f32,
            t.value[1] as f32,
            t.value[2] as f32,
        ))
    }

    /// `scale` (non-zero finite per axis, also in f32) then `translate` as one matrix.
    pub(crate) fn placement(
        &self,
        prefix: &str,
        scale: Option<Triple>,
        translate: Option<Point>,
    ) -> Result<Mat4, LoadError> {
        let written = scale.map_or([1.0; 3], |s| s.value);
        let s = Vec3::new(written[0] as f32, written[1] as f32, written[2] as f32);
        if !(s.is_finite() && s.cmpne(Vec3::ZERO).all()) {
            return Err(self.bad(
                format!("{prefix}.scale"),
                format!(
                    "{} must be finite and non-zero on every axis (in single precision)",
                    point_text(written)
                ),
            ));
        }
        let t = self.point(
            &format!("{prefix}.translate"),
            translate.unwrap_or(Point([0.0; 3])),
        )?;
        Ok(Mat4::from_translation(t) * Mat4::from_scale(s))
    }
}

fn point_text(p: [f64; 3]) -> String {
    format!("[{}, {}, {}]", num(p[0]), num(p[1]), num(p[2]))
}
