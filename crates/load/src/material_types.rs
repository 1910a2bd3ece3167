//! A scene file's `[material.NAME]` by its `type`: `"smooth"` (Lambert + Gaussian lobe, the
//! default), `"mirror"` and `"dielectric"` (docs/scene-format.md, "Materials").

use bdpm_bdf::{Bdf, Dielectric, Material, Mirror};
use glam::Vec3;

use crate::LoadError;
use crate::ctx::Ctx;
use crate::limits;
use crate::schema::MaterialDef;

/// The range of `ior`: bdpm_bdf's [`bdpm_bdf::ETA_MIN`] and [`bdpm_bdf::ETA_MAX`] as written
/// (their f32 values print as 0.009999…).
pub(crate) const IOR_RANGE: (f64, f64) = (0.01, 100.0);
const _: () =
    assert!(IOR_RANGE.0 as f32 == bdpm_bdf::ETA_MIN && IOR_RANGE.1 as f32 == bdpm_bdf::ETA_MAX);

/// The material types and the keys each reads (besides `type`).
const TYPES: [(&str, &[&str]); 3] = [
    ("smooth", &["kd", "gr", "delta"]),
    ("mirror", &["reflectance", "eta", "k"]),
    ("dielectric", &["ior", "reflect_tint", "transmit_tint"]),
];

/// The model of the material `def` written at `prefix` (`material.NAME`), every key checked:
/// a key that its type does not read is refused, naming the type's keys.
pub(crate) fn model(ctx: &Ctx<'_>, prefix: &str, def: &MaterialDef) -> Result<Material, LoadError> {
    let kind = def.kind.as_deref().unwrap_or("smooth");
    let Some((_, keys)) = TYPES.iter().find(|(name, _)| *name == kind) else {
        let known: Vec<&str> = TYPES.iter().map(|(name, _)| *name).collect();
        return Err(ctx.bad(
            format!("{prefix}.type"),
            format!(
                "\"{kind}\" is not a material type (one of: {})",
                known.join(", ")
            ),
        ));
    };
    if let Some((key, _)) = def
        .keys()
        .into_iter()
        .find(|(k, given)| *given && !keys.contains(k))
    {
        return Err(ctx.bad(
            format!("{prefix}.{key}"),
            format!(
                "a {kind} material has no key {key} (its keys: {})",
                keys.join(", ")
            ),
        ));
    }
    match kind {
        "mirror" => mirror(ctx, prefix, def).map(Material::from),
        "dielectric" => dielectric(ctx, prefix, def).map(Material::from),
        _ => smooth_bdf(ctx, prefix, def).map(Material::from),
    }
}

/// `type = "mirror"`: `reflectance` (default 1), and a conductor's complex index `eta` + i·`k`
/// (both or neither) for its Fresnel term.
fn mirror(ctx: &Ctx<'_>, prefix: &str, def: &MaterialDef) -> Result<Mirror, LoadError> {
    let reflectance = match def.reflectance {
        Some(r) => ctx.channels(&format!("{prefix}.reflectance"), r, 0.0, Some(1.0))?,
        None => Vec3::ONE,
    };
    let mirror = match (def.eta, def.k) {
        (None, None) => Mirror::new(reflectance),
        (Some(eta), Some(k)) => {
            let eta = ctx.channels(&format!("{prefix}.eta"), eta, 0.0, None)?;
            let k = ctx.channels(&format!("{prefix}.k"), k, 0.0, None)?;
            Mirror::conductor(reflectance, eta, k)
        }
        (Some(_), None) | (None, Some(_)) => {
            let missing = if def.eta.is_none() { "eta" } else { "k" };
            return Err(ctx.bad(
                format!("{prefix}.{missing}"),
                "missing (a conductor's index needs both eta and k, e.g. gold: \
                 eta = [0.143, 0.374, 1.442], k = [3.983, 2.385, 1.603])",
            ));
        }
    };
    mirror.map_err(|e| ctx.bad(prefix, e.to_string()))
}

/// `type = "dielectric"`: `ior` = η_interior/η_exterior (the interior is behind the surface's
/// normal, inside for the closed shapes), optional tints of reflected and transmitted light.
fn dielectric(ctx: &Ctx<'_>, prefix: &str, def: &MaterialDef) -> Result<Dielectric, LoadError> {
    let field = format!("{prefix}.ior");
    let ior = ctx.required(
        &field,
        def.ior,
        "index of refraction, interior over exterior, e.g. 1.5 for glass in air",
    )?;
    let ior = ctx.within(&field, ior, IOR_RANGE.0, IOR_RANGE.1)?;
    let tint = |name: &str, t: Option<crate::schema::Triple>| match t {
        Some(t) => ctx.channels(&format!("{prefix}.{name}"), t, 0.0, Some(1.0)),
        None => Ok(Vec3::ONE),
    };
    let reflect = tint("reflect_tint", def.reflect_tint)?;
    let transmit = tint("transmit_tint", def.transmit_tint)?;
    Dielectric::tinted(ior, reflect, transmit).map_err(|e| ctx.bad(prefix, e.to_string()))
}

/// A `type = "smooth"` material (the default): Lambert kd plus a Gaussian lobe gr of width
/// delta.
fn smooth_bdf(ctx: &Ctx<'_>, prefix: &str, def: &MaterialDef) -> Result<Bdf, LoadError> {
    let kd = ctx.required(
        &format!("{prefix}.kd"),
        def.kd,
        "Lambert albedo, a number or [r, g, b] in [0, 1]",
    )?;
    let kd = ctx.channels(&format!("{prefix}.kd"), kd, 0.0, Some(1.0))?;
    let gr = match def.gr {
        Some(gr) => ctx.channels(&format!("{prefix}.gr"), gr, 0.0, Some(1.0))?,
        None => Vec3::ZERO,
    };
    let sum = kd + gr;
    if sum.max_element() > 1.0 + 1e-6 {
        return Err(ctx.bad(
            prefix,
            format!(
                "kd + gr = {sum} exceeds 1 (kd = {kd}, gr = {gr}); the surface would create energy"
            ),
        ));
    }
    let delta = |d: Option<f64>| -> Result<Option<f32>, LoadError> {
        d.map(|d| {
            let field = format!("{prefix}.delta");
            ctx.within(
                &field,
                d,
                limits::DELTA_MIN_DEGREES,
                limits::DELTA_MAX_DEGREES,
            )
        })
        .transpose()
    };
    let bdf = if gr == Vec3::ZERO {
        // A lobe width without a lobe is harmless but still must be a number.
        let _ = delta(def.delta)?;
        Bdf::lambert(kd)
    } else {
        let d = ctx.required(
            &format!("{prefix}.delta"),
            def.delta,
            "lobe width in degrees, needed because gr > 0",
        )?;
        let d = delta(Some(d))?.expect("given");
        Bdf::new(kd, gr, d.to_radians())
    };
    bdf.map_err(|e| ctx.bad(prefix, e.to_string()))
}
