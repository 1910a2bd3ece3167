//! `<texture type="bitmap">` as a bdpm texture times a factor: a diffuse `reflectance` (kd =
//! factor × texture) or an area emitter's `radiance` (Le = factor × texture).
//!
//! bdpm keeps glTF textures as 8-bit sRGB codes and multiplies the sampled value by the
//! material's factor; bdpm-export writes each texel's linear value times the factor
//! (`srgb8_to_linear(code) × factor`, in f32) as a float EXR, since Mitsuba's bitmap has no
//! factor of its own. The import inverts that: it looks for a factor per channel (1 first,
//! then one common to the three channels, then one per channel) under which every texel of
//! the channel is an entry of the 256-entry decoding table times the factor, bit for bit,
//! and keeps the codes ([`TexelImage::srgb8`]); the texture then samples and scales to the
//! very numbers of the exported scene. An EXR whose values are not such products (any EXR
//! bdpm did not write) is kept as linear texels divided by each channel's largest value, with
//! that value as the factor: the same image up to the rounding of that division. PNG and JPEG
//! bitmaps are read as Mitsuba reads them: sRGB codes (decoded when sampled, as bdpm decodes
//! glTF images) with `raw` false, the codes / 255 as linear values with `raw` true.

use std::collections::HashMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use bdpm_scene::{TexelImage, Texture, Wrap, srgb8_to_linear};
use glam::{DMat4, DVec3, Vec3};
use roxmltree::Node;

use super::doc::{Props, Xml};
use crate::LoadError;
use crate::limits::{MAX_GLTF_BYTES, MAX_TEXTURE_TEXELS};
use crate::memory::Budget;

/// A bitmap as bdpm renders it: Mitsuba's value at a point is `factor` × `texture` there.
#[derive(Clone, Debug)]
pub(crate) struct Bitmap {
    /// The texels and the wrap mode (Mitsuba's one `wrap_mode` for both axes).
    pub(crate) texture: Arc<Texture>,
    /// The factor per channel (kd or Le when the texture is 1).
    pub(crate) factor: DVec3,
}

/// A decoded image and its factor.
type Decoded = (Arc<TexelImage>, Vec3);

/// The bitmaps read so far: decoded images by file and `raw` (one decode per image, however
/// many textures show it), and the top-level `<texture id=…>`s for `<ref id=…>`.
#[derive(Default)]
pub(crate) struct Images {
    decoded: HashMap<(PathBuf, bool), Decoded>,
    named: HashMap<String, Bitmap>,
}

impl Images {
    /// Images decoded.
    pub(crate) fn count(&self) -> usize {
        self.decoded.len()
    }

    /// Keeps a top-level texture under its id.
    pub(crate) fn name(&mut self, id: String, bitmap: Bitmap) {
        let _ = self.named.insert(id, bitmap);
    }
}

/// What reading a bitmap takes from the scene being read: where its file name is looked up
/// (the naming file's directory, then the `<path>`s), the memory account, the images so far
/// and the list of files the scene reads (for its identity).
pub(crate) struct Loader<'a> {
    /// The directory of the file that names the bitmap.
    pub(crate) dir: &'a Path,
    /// The `<path>` directories, searched after `dir`.
    pub(crate) search: &'a [PathBuf],
    /// The loader's memory account: the texels kept are added to it.
    pub(crate) budget: &'a mut Budget,
    /// The images decoded so far and the top-level textures.
    pub(crate) images: &'a mut Images,
    /// The files the scene reads; each bitmap file joins them.
    pub(crate) files: &'a mut Vec<PathBuf>,
}

impl Loader<'_> {
    /// The bitmap of `<texture>` element `node`, or of a `<ref id=…>` to a top-level one.
    /// Refused: other texture types, a missing `filename`, a `wrap_mode` or `filter_type`
    /// Mitsuba does not have, a `to_uv` other than the identity, an unreadable image. A
    /// `nearest` filter is warned (bdpm samples bilinearly).
    pub(crate) fn read(
        &mut self,
        x: &Xml<'_>,
        node: Node<'_, '_>,
        warnings: &mut Vec<String>,
    ) -> Result<Bitmap, LoadError> {
        if node.tag_name().name() == "ref" {
            let id = x.need(node, "id")?;
            return self.images.named.get(&id).cloned().ok_or_else(|| {
                x.err(
                    node,
                    format!("no <texture id=\"{id}\"> before this reference"),
                )
            });
        }
        let kind = x.need(node, "type")?;
        if kind != "bitmap" {
            return Err(x.err(node, format!("texture type \"{kind}\" is not supported: bdpm reads bitmap textures (give a constant colour as <rgb>)")));
        }
        let p = Props::new(node);
        let name = x.string(&p, "filename")?.ok_or_else(|| {
            x.err(
                node,
                "missing <string name=\"filename\">: bdpm reads bitmaps from files",
            )
        })?;
        let wrap = wrap_mode(x, &p)?;
        filter(x, &p, warnings)?;
        let raw = x.boolean(&p, "raw", false)?;
        if let Some(t) = p.get("to_uv") {
            let m = match t.tag_name().name() {
                "transform" => super::transform::matrix(x, t)?,
                _ => return Err(x.err(t, "to_uv must be a <transform>")),
            };
            if m != DMat4::IDENTITY {
                return Err(x.err(t, "a to_uv other than the identity is not supported: bake the transform into the mesh's texture coordinates"));
            }
        }
        // Mitsuba's storage format and lookup acceleration change nothing bdpm renders.
        p.ignore(&["format", "accel"]);
        p.unread(x, "<texture type=\"bitmap\">", warnings);
        let path = super::shape::resolve(self.dir, self.search, &name);
        let key = (
            std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone()),
            raw,
        );
        let (image, factor) = match self.images.decoded.get(&key) {
            Some(d) => d.clone(),
            None => {
                let d = self
                    .decode(&path, raw)
                    .map_err(|m| x.err(node, format!("{}: {m}", path.display())))?;
                self.budget.keep_texels(d.0.bytes());
                self.files.push(path);
                let _ = self.images.decoded.insert(key, d.clone());
                d
            }
        };
        Ok(Bitmap {
            texture: Arc::new(Texture::with_image(image, wrap, wrap)),
            factor: factor.as_dvec3(),
        })
    }

    /// The image at `path` and its factor: an OpenEXR, PNG or JPEG file (recognised by its
    /// first bytes), each step checked against the memory budget before it allocates.
    fn decode(&self, path: &Path, raw: bool) -> Result<Decoded, String> {
        let len = std::fs::metadata(path)
            .map_err(|e| format!("cannot open the bitmap: {e}"))?
            .len();
        let held = self.budget.textures();
        self.budget
            .check(held, len, "the bitmap file's bytes")
            .map_err(|m| format!("reading it {m}"))?;
        // The loader's bound for one binary file (a glTF file's), 2 GiB.
        let bytes = crate::files::read_regular(path, MAX_GLTF_BYTES, "bitmap")
            .map_err(|e| e.to_string())?;
        let held = held + bytes.len() as u64;
        if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
            return decode_exr(&bytes, self.budget, held);
        }
        if !(crate::image::is_png(&bytes) || crate::image::is_jpeg(&bytes)) {
            return Err(
                "not an OpenEXR, PNG or JPEG image (bdpm reads those bitmaps; convert the image)"
                    .into(),
            );
        }
        let header = crate::image::header(&bytes)?;
        let texels = u64::from(header.width) * u64::from(header.height);
        let linear = if raw { 12 * texels } else { 0 };
        self.budget
            .check(
                held,
                header.decode_bytes + linear,
                "3 bytes a texel, and the decoder's buffers",
            )
            .map_err(|m| format!("decoding its {}×{} texels {m}", header.width, header.height))?;
        let d = crate::image::decode(&bytes)?;
        let image = if raw {
            // Mitsuba reads the codes of a raw bitmap as linear values, code / 255.
            let t = d
                .rgb
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0].into(), c[1].into(), c[2].into()) / 255.0)
                .collect();
            TexelImage::linear(d.width, d.height, t)
        } else {
            TexelImage::srgb8(d.width, d.height, d.rgb)
        };
        Ok((Arc::new(image.map_err(|e| e.to_string())?), Vec3::ONE))
    }
}

/// `wrap_mode`: Mitsuba's `repeat` (its default), `mirror` and `clamp` are bdpm's three
/// wrap modes, for both axes.
fn wrap_mode(x: &Xml<'_>, p: &Props<'_, '_>) -> Result<Wrap, LoadError> {
    match x.string(p, "wrap_mode")?.as_deref() {
        None | Some("repeat") => Ok(Wrap::Repeat),
        Some("mirror") => Ok(Wrap::MirroredRepeat),
        Some("clamp") => Ok(Wrap::ClampToEdge),
        Some(other) => Err(x.err(
            p.get("wrap_mode").unwrap_or(p.node()),
            format!(
                "wrap_mode \"{other}\" is not supported: bdpm wraps by repeat, mirror or clamp"
            ),
        )),
    }
}

/// `filter_type`: `bilinear` (Mitsuba's default) is bdpm's lookup; `nearest` is warned.
fn filter(x: &Xml<'_>, p: &Props<'_, '_>, warnings: &mut Vec<String>) -> Result<(), LoadError> {
    let node = p.get("filter_type").unwrap_or(p.node());
    match x.string(p, "filter_type")?.as_deref() {
        None | Some("bilinear") => Ok(()),
        Some("nearest") => {
            warnings.push(x.warn(node, "bdpm samples every texture bilinearly: nearest-neighbour lookup is not applied (the image differs within a texel of each texel edge)"));
            Ok(())
        }
        Some(other) => Err(x.err(
            node,
            format!("filter_type \"{other}\" is not supported: bdpm samples bilinearly (bilinear, or nearest with a warning)"),
        )),
    }
}

/// An OpenEXR's first layer with R, G and B channels (alpha ignored) as sRGB codes and a
/// factor ([`factorise`]), else as linear texels scaled to at most 1 per channel.
fn decode_exr(bytes: &[u8], budget: &Budget, held: u64) -> Result<Decoded, String> {
    let bad = |e: exr::error::Error| format!("cannot decode OpenEXR: {e}");
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(bad)?;
    let size = meta
        .headers
        .first()
        .ok_or("OpenEXR has no layer")?
        .layer_size;
    let (width, height) = (size.0 as u64, size.1 as u64);
    if width == 0 || height == 0 || width * height > MAX_TEXTURE_TEXELS {
        return Err(format!(
            "image is {width}×{height}, more than {MAX_TEXTURE_TEXELS} texels or empty"
        ));
    }
    // f32 RGB as decoded, one channel's values sorted beside them, and the codes kept.
    budget
        .check(
            held,
            (12 + 4 + 3) * width * height,
            "19 bytes a texel while it is decoded",
        )
        .map_err(|m| format!("decoding its {width}×{height} texels {m}"))?;
    use exr::prelude::{ReadChannels as _, ReadLayers as _};
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size, _| (size.0, vec![Vec3::ZERO; size.0 * size.1]),
            |(w, px): &mut (usize, Vec<Vec3>),
             at: exr::math::Vec2<usize>,
             (r, g, b, _): (f32, f32, f32, f32)| {
                px[at.1 * *w + at.0] = Vec3::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .from_buffered(Cursor::new(bytes))
        .map_err(bad)?;
    let texels = image.layer_data.channel_data.pixels.1;
    let (w, h) = (width as u32, height as u32);
    if let Some(i) = texels
        .iter()
        .position(|t| !(t.is_finite() && t.min_element() >= 0.0))
    {
        return Err(format!(
            "texel ({}, {}) is {}: bdpm's textures are finite and not negative",
            i % w as usize,
            i / w as usize,
            texels[i]
        ));
    }
    if let Some((codes, factor)) = factorise(&texels) {
        let image = TexelImage::srgb8(w, h, codes).map_err(|e| e.to_string())?;
        return Ok((Arc::new(image), factor));
    }
    let factor = texels.iter().fold(Vec3::ZERO, |m, t| m.max(*t));
    let scale = Vec3::select(factor.cmpgt(Vec3::ZERO), factor, Vec3::ONE);
    let linear = texels.iter().map(|t| (*t / scale).min(Vec3::ONE)).collect();
    let image = TexelImage::linear(w, h, linear).map_err(|e| e.to_string())?;
    Ok((Arc::new(image), factor))
}

/// The 8-bit sRGB codes (3 a texel) and the factor per channel such that every texel
/// channel is `srgb8_to_linear(code) × factor` in f32, bit for bit, if there are: the factor 1
/// (glTF's default) if it fits, else one factor for the three channels, else one per channel
/// (a channel that is 0 everywhere takes the largest of the others').
fn factorise(texels: &[Vec3]) -> Option<(Vec<u8>, Vec3)> {
    // A channel of more than 256 distinct values is no set of codes; one channel's values
    // at a time, so that the scratch is 4 bytes a texel.
    let channel = |k: usize| {
        let mut v: Vec<f32> = texels.iter().map(|t| t[k]).collect();
        v.sort_unstable_by(f32::total_cmp);
        v.dedup();
        if v.len() > 256 {
            return None;
        }
        v.shrink_to_fit();
        Some(v)
    };
    let values = [channel(0)?, channel(1)?, channel(2)?];
    let mut all: Vec<f32> = values.concat();
    all.sort_unstable_by(f32::total_cmp);
    all.dedup();
    let factor = match factor_of(&all) {
        Some(s) => Vec3::splat(s),
        None => {
            let per: Vec<Option<f32>> = values.iter().map(|v| factor_of(v)).collect();
            let zero = |v: &[f32]| v.iter().all(|&c| c == 0.0);
            let others = per
                .iter()
                .flatten()
                .copied()
                .reduce(f32::max)
                .unwrap_or(1.0);
            let mut f = [0.0; 3];
            for k in 0..3 {
                f[k] = match per[k] {
                    Some(s) => s,
                    None if zero(&values[k]) => others,
                    None => return None,
                };
            }
            Vec3::from(f)
        }
    };
    let mut codes = Vec::with_capacity(3 * texels.len());
    for t in texels {
        for k in 0..3 {
            codes.push(code_of(t[k], factor[k])?);
        }
    }
    Some((codes, factor))
}

/// The code whose table value times `s` is `v` (the smallest, where several are).
fn code_of(v: f32, s: f32) -> Option<u8> {
    // The products grow with the code (the table increases, s ≥ 0): a binary search.
    let (mut lo, mut hi) = (0usize, 256usize);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if srgb8_to_linear(mid as u8) * s < v {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    (lo < 256 && srgb8_to_linear(lo as u8) * s == v).then_some(lo as u8)
}

/// The codes on the linear segment of the sRGB curve (c/255 ≤ 0.04045): their values are
/// multiples of one step, so that decimal data (0.3, 0.7, …) would factorise with a large
/// factor and small codes. The largest value of a channel is not taken as one of them.
const LINEAR_CODES: u8 = 10;

/// A factor s > 0 under which every one of `values` (distinct, ascending) is a table entry
/// times s: 1 if it is one; else, for the largest value taken as each code above
/// [`LINEAR_CODES`] in turn, the f32
/// numbers within 4 ulps of value / entry whose product gives the value back and that fit
/// every value; of all these the one with the shortest decimal form (the number a person or a
/// glTF file writes, such as 6 or 0.8: a channel with one value besides 0 fits under every
/// code, and only this choice brings its factor back), then the highest code. `None` when the
/// values are all 0 or nothing fits.
fn factor_of(values: &[f32]) -> Option<f32> {
    let &top = values.last()?;
    if top <= 0.0 {
        return None;
    }
    let fits = |s: f32| values.iter().all(|&v| code_of(v, s).is_some());
    if fits(1.0) {
        return Some(1.0);
    }
    let mut best: Option<((usize, u8, u32), f32)> = None;
    for code in (LINEAR_CODES + 1..=255u8).rev() {
        let entry = srgb8_to_linear(code);
        let guess = top / entry;
        if !guess.is_finite() {
            continue;
        }
        for k in -4i32..=4 {
            let s = f32::from_bits(guess.to_bits().saturating_add_signed(k));
            if !(s > 0.0 && s.is_finite() && entry * s == top && fits(s)) {
                continue;
            }
            let key = (s.to_string().len(), 255 - code, k.unsigned_abs());
            if best.is_none_or(|(b, _)| key < b) {
                best = Some((key, s));
            }
        }
    }
    best.map(|(_, s)| s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Texels written as bdpm-export writes them (table value × factor, in f32) factorise
    /// back to their codes and factor, for the factors of the scenes and a few others.
    #[test]
    fn exported_texels_come_back_as_codes_and_factor() {
        let codes: Vec<[u8; 3]> = vec![[255, 128, 0], [10, 20, 140], [0, 0, 0], [200, 7, 90]];
        // Two texels, one value besides 0 in green and blue (as the emissive-room sign's).
        let sign: Vec<[u8; 3]> = vec![[255, 128, 0], [0, 0, 90]];
        for (codes, factor) in [
            (&sign, Vec3::new(10.0, 9.0, 7.5)),
            (&sign, Vec3::splat(6.0)),
        ]
        .into_iter()
        .chain(
            [
                Vec3::ONE,
                Vec3::splat(6.0),
                Vec3::new(1.0, 0.9, 0.75) * 10.0,
                Vec3::new(0.6, 0.1, 0.1),
            ]
            .map(|f| (&codes, f)),
        ) {
            let texels: Vec<Vec3> = codes
                .iter()
                .map(|c| {
                    Vec3::new(
                        srgb8_to_linear(c[0]),
                        srgb8_to_linear(c[1]),
                        srgb8_to_linear(c[2]),
                    ) * factor
                })
                .collect();
            let (back, f) = factorise(&texels).expect("factorises");
            assert_eq!(f, factor);
            assert_eq!(back, codes.concat());
        }
    }

    /// Values that are no table entry times one factor are not factorised, decimal data
    /// included (which would fit the linear segment's codes under a large factor).
    #[test]
    fn other_values_are_not_factorised() {
        let texels = vec![Vec3::splat(0.3), Vec3::splat(0.30001), Vec3::splat(0.7)];
        assert_eq!(factorise(&texels), None);
        let decimal = vec![Vec3::new(0.3, 2.0, 0.0), Vec3::new(0.7, 1.0, 0.0)];
        assert_eq!(factorise(&decimal), None);
        assert_eq!(code_of(srgb8_to_linear(77), 1.0), Some(77));
        assert_eq!(code_of(0.5, 1.0), None);
    }
}
