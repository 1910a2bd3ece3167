//! Base-colour textures: kd(u, v) = (the material's kd) × texture(u, v), linear RGB texels
//! sampled bilinearly with the glTF sampler's wrap modes.

use std::sync::{Arc, LazyLock};

use glam::{Vec2, Vec3};

/// How texture coordinates outside [0, 1] map into the image (glTF sampler `wrapS`/`wrapT`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The image repeats (glTF 10497, its default).
    #[default]
    Repeat,
    /// Coordinates are clamped to the edge texels (glTF 33071).
    ClampToEdge,
    /// The image repeats, every other copy mirrored (glTF 33648).
    MirroredRepeat,
}

impl Wrap {
    /// The texel index `i` (any integer) maps to, in 0..n.
    fn index(self, i: i64, n: u32) -> usize {
        let n = i64::from(n);
        let k = match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::ClampToEdge => i.clamp(0, n - 1),
            Wrap::MirroredRepeat => {
                let m = i.rem_euclid(2 * n);
                if m < n { m } else { 2 * n - 1 - m }
            }
        };
        k as usize
    }
}

/// Why texels cannot form a [`Texture`].
#[derive(Clone, Debug, PartialEq)]
pub enum TextureError {
    /// Width or height is zero, or the texel count is not width × height.
    Size {
        /// Width, texels.
        width: u32,
        /// Height, texels.
        height: u32,
        /// Texels given.
        texels: usize,
    },
    /// A texel is not finite or has a channel outside [0, 1].
    Texel {
        /// Index of the texel (row-major from the top-left).
        index: usize,
    },
}

impl std::fmt::Display for TextureError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Size {
                width,
                height,
                texels,
            } => write!(f, "{width}×{height} image with {texels} texels"),
            Self::Texel { index } => {
                write!(f, "texel {index} is not finite or outside [0, 1]")
            }
        }
    }
}

impl std::error::Error for TextureError {}

/// The texels of one decoded image, shared (through an `Arc`) by every [`Texture`] that
/// shows it, whatever its sampler: an image used by nine samplers is held once.
#[derive(Debug, PartialEq)]
pub struct TexelImage {
    width: u32,
    height: u32,
    texels: Texels,
}

/// How texels are stored: linear f32 (12 bytes a texel, for images made in code), or 8-bit
/// sRGB (3 bytes a texel, as PNG and JPEG images are decoded), turned into linear values
/// through a 256-entry table when read, so a read gives the same number as decoding the image
/// to linear f32 up front would.
#[derive(Debug, PartialEq)]
enum Texels {
    Linear(Vec<Vec3>),
    Srgb8(Vec<u8>),
}

/// The linear value of each 8-bit sRGB code, `srgb_to_linear(i / 255)`.
static SRGB8_TO_LINEAR: LazyLock<[f32; 256]> =
    LazyLock::new(|| std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0)));

impl TexelImage {
    /// `width` × `height` linear RGB texels in [0, 1], row-major from the top-left.
    pub fn linear(width: u32, height: u32, texels: Vec<Vec3>) -> Result<Self, TextureError> {
        check_size(width, height, texels.len())?;
        if let Some(index) = texels
            .iter()
            .position(|t| !(t.is_finite() && t.min_element() >= 0.0 && t.max_element() <= 1.0))
        {
            return Err(TextureError::Texel { index });
        }
        Ok(TexelImage {
            width,
            height,
            texels: Texels::Linear(texels),
        })
    }

    /// `width` × `height` texels given as 8-bit sRGB-encoded R, G, B bytes (3 per texel),
    /// row-major from the top-left; decoded to linear values when sampled.
    pub fn srgb8(width: u32, height: u32, rgb: Vec<u8>) -> Result<Self, TextureError> {
        if !rgb.len().is_multiple_of(3) {
            return Err(TextureError::Size {
                width,
                height,
                texels: rgb.len() / 3,
            });
        }
        check_size(width, height, rgb.len() / 3)?;
        Ok(TexelImage {
            width,
            height,
            texels: Texels::Srgb8(rgb),
        })
    }

    /// Width and height, texels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Bytes held by the texels.
    pub fn bytes(&self) -> u64 {
        match &self.texels {
            Texels::Linear(t) => (t.capacity() * size_of::<Vec3>()) as u64,
            Texels::Srgb8(t) => t.capacity() as u64,
        }
    }

    /// Texel `i` (row-major), linear RGB.
    #[inline]
    fn at(&self, i: usize) -> Vec3 {
        match &self.texels {
            Texels::Linear(t) => t[i],
            Texels::Srgb8(t) => {
                let lut = &*SRGB8_TO_LINEAR;
                let p = &t[3 * i..3 * i + 3];
                Vec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize])
            }
        }
    }
}

fn check_size(width: u32, height: u32, texels: usize) -> Result<(), TextureError> {
    if width == 0 || height == 0 || texels as u64 != u64::from(width) * u64::from(height) {
        return Err(TextureError::Size {
            width,
            height,
            texels,
        });
    }
    Ok(())
}

/// An RGB image of linear reflectances in [0, 1] (already decoded from sRGB), row 0 at
/// texture coordinate v = 0, as glTF lays images out, with a sampler's wrap modes. The texels
/// are shared with every other texture of the same image ([`Texture::with_image`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    image: Arc<TexelImage>,
    wrap_u: Wrap,
    wrap_v: Wrap,
}

impl Texture {
    /// A texture of `width` × `height` linear texels, row-major from the top-left (v = 0).
    pub fn new(
        width: u32,
        height: u32,
        texels: Vec<Vec3>,
        wrap_u: Wrap,
        wrap_v: Wrap,
    ) -> Result<Self, TextureError> {
        let image = Arc::new(TexelImage::linear(width, height, texels)?);
        Ok(Texture::with_image(image, wrap_u, wrap_v))
    }

    /// A texture showing `image` with a sampler's wrap modes; the texels are not copied.
    pub fn with_image(image: Arc<TexelImage>, wrap_u: Wrap, wrap_v: Wrap) -> Self {
        Texture {
            image,
            wrap_u,
            wrap_v,
        }
    }

    /// The image this texture shows (shared with the other textures of the same image).
    pub fn image(&self) -> &Arc<TexelImage> {
        &self.image
    }

    /// Width and height, texels.
    pub fn size(&self) -> (u32, u32) {
        self.image.size()
    }

    /// The sampler's wrap modes along u and v.
    pub fn wraps(&self) -> (Wrap, Wrap) {
        (self.wrap_u, self.wrap_v)
    }

    /// The texel at column `x`, row `y` (unwrapped).
    pub fn texel(&self, x: u32, y: u32) -> Vec3 {
        self.image
            .at(y as usize * self.image.width as usize + x as usize)
    }

    /// Bilinear value at texture coordinates `uv` (texel centres at ((i + ½)/w, (j + ½)/h)),
    /// each of the four texels wrapped by the sampler's mode. A non-finite coordinate reads
    /// as 0. The result is in [0, 1] per channel.
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        let (width, height) = self.image.size();
        let axis = |c: f32, n: u32| -> (i64, f32) {
            let x = if c.is_finite() { c } else { 0.0 } as f64 * f64::from(n) - 0.5;
            let i = x.floor();
            (i as i64, (x - i) as f32)
        };
        let (x0, fx) = axis(uv.x, width);
        let (y0, fy) = axis(uv.y, height);
        let xs = [
            self.wrap_u.index(x0, width),
            self.wrap_u.index(x0.saturating_add(1), width),
        ];
        let ys = [
            self.wrap_v.index(y0, height),
            self.wrap_v.index(y0.saturating_add(1), height),
        ];
        let at = |x: usize, y: usize| self.image.at(y * width as usize + x);
        let top = at(xs[0], ys[0]).lerp(at(xs[1], ys[0]), fx);
        let bottom = at(xs[0], ys[1]).lerp(at(xs[1], ys[1]), fx);
        top.lerp(bottom, fy).clamp(Vec3::ZERO, Vec3::ONE)
    }
}

/// The textures of a scene: one optional base-colour texture per material, and the texture
/// coordinates of every triangle's three corners (needed only where a textured material is).
#[derive(Clone, Debug, Default)]
pub struct SceneTextures {
    /// Per material index: its base-colour texture, or `None`. Shorter than the material
    /// list means `None` for the rest.
    pub base_colour: Vec<Option<Arc<Texture>>>,
    /// Per triangle index: texture coordinates of its vertices 0, 1, 2 (zero where unused).
    pub texcoords: Vec<[Vec2; 3]>,
}

/// The linear value bdpm reads for the 8-bit sRGB code `code`: the very number an
/// [`TexelImage::srgb8`] texel of that code samples to (one entry of the decoding table), so
/// that importers can find the codes behind linear values written out from it.
pub fn srgb8_to_linear(code: u8) -> f32 {
    SRGB8_TO_LINEAR[code as usize]
}

/// sRGB-encoded value in [0, 1] → linear (IEC 61966-2-1), as glTF asks of base-colour images.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_by_one(wrap: Wrap) -> Texture {
        Texture::new(2, 1, vec![Vec3::ZERO, Vec3::ONE], wrap, wrap).unwrap()
    }

    #[test]
    fn texel_centres_read_their_texel_and_midpoints_interpolate() {
        let t = two_by_one(Wrap::ClampToEdge);
        assert_eq!(t.sample(Vec2::new(0.25, 0.5)), Vec3::ZERO);
        assert_eq!(t.sample(Vec2::new(0.75, 0.5)), Vec3::ONE);
        assert!((t.sample(Vec2::new(0.5, 0.5)).x - 0.5).abs() < 1e-6);
        // Clamp: beyond the edge texel's centre the value stays.
        assert_eq!(t.sample(Vec2::new(-3.0, 0.5)), Vec3::ZERO);
        assert_eq!(t.sample(Vec2::new(7.0, 0.5)), Vec3::ONE);
    }

    #[test]
    fn wrap_modes_follow_the_gltf_sampler() {
        // u = 1.0 is halfway between texel 1 (centre 0.75) and texel 2 = texel 0 (repeat)
        // or texel 1 again (mirror, clamp).
        let mid = |w| two_by_one(w).sample(Vec2::new(1.0, 0.5)).x;
        assert!((mid(Wrap::Repeat) - 0.5).abs() < 1e-6);
        assert_eq!(mid(Wrap::MirroredRepeat), 1.0);
        assert_eq!(mid(Wrap::ClampToEdge), 1.0);
        // Repeat is periodic, mirror has period 2.
        let r = two_by_one(Wrap::Repeat);
        assert_eq!(
            r.sample(Vec2::new(0.25, 0.5)),
            r.sample(Vec2::new(5.25, 0.5))
        );
        let m = two_by_one(Wrap::MirroredRepeat);
        assert_eq!(m.sample(Vec2::new(1.25, 0.5)), Vec3::ONE);
        assert_eq!(m.sample(Vec2::new(1.75, 0.5)), Vec3::ZERO);
        assert_eq!(
            m.sample(Vec2::new(f32::NAN, 0.5)),
            m.sample(Vec2::new(0.0, 0.5))
        );
    }

    #[test]
    fn bad_texels_are_rejected() {
        assert!(Texture::new(2, 2, vec![Vec3::ZERO; 3], Wrap::Repeat, Wrap::Repeat).is_err());
        assert!(Texture::new(0, 0, vec![], Wrap::Repeat, Wrap::Repeat).is_err());
        let bad = vec![Vec3::new(0.0, 1.5, 0.0)];
        assert_eq!(
            Texture::new(1, 1, bad, Wrap::Repeat, Wrap::Repeat),
            Err(TextureError::Texel { index: 0 })
        );
    }

    #[test]
    fn srgb8_texels_read_as_their_linear_values_and_share_the_image() {
        let image = Arc::new(TexelImage::srgb8(2, 1, vec![0, 128, 255, 10, 20, 30]).unwrap());
        assert_eq!(image.bytes(), 6);
        let a = Texture::with_image(Arc::clone(&image), Wrap::Repeat, Wrap::Repeat);
        let b = Texture::with_image(Arc::clone(&image), Wrap::ClampToEdge, Wrap::Repeat);
        assert!(Arc::ptr_eq(a.image(), b.image()));
        let lin = |c: u8| srgb_to_linear(f32::from(c) / 255.0);
        assert_eq!(a.texel(0, 0), Vec3::new(0.0, lin(128), 1.0));
        assert_eq!(b.texel(1, 0), Vec3::new(lin(10), lin(20), lin(30)));
        // The same texels given as linear values sample to the same bits.
        let linear = Texture::new(
            2,
            1,
            vec![a.texel(0, 0), a.texel(1, 0)],
            Wrap::Repeat,
            Wrap::Repeat,
        )
        .unwrap();
        for u in [0.1, 0.4, 0.75, 1.3] {
            let uv = Vec2::new(u, 0.5);
            assert_eq!(a.sample(uv), linear.sample(uv));
        }
        assert!(TexelImage::srgb8(2, 2, vec![0; 9]).is_err());
    }

    #[test]
    fn srgb_decoding_matches_the_standard() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        // sRGB 0.5 is linear 0.2140.
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
    }
}
