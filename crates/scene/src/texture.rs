//! Base-colour textures: kd(u, v) = (the material's kd) × texture(u, v), linear RGB texels
//! sampled bilinearly with the glTF sampler's wrap modes.

use std::sync::Arc;

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

/// An RGB image of linear reflectances in [0, 1] (already decoded from sRGB), row 0 at
/// texture coordinate v = 0, as glTF lays images out.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    width: u32,
    height: u32,
    texels: Vec<Vec3>,
    wrap_u: Wrap,
    wrap_v: Wrap,
}

impl Texture {
    /// A texture of `width` × `height` texels, row-major from the top-left (v = 0).
    pub fn new(
        width: u32,
        height: u32,
        texels: Vec<Vec3>,
        wrap_u: Wrap,
        wrap_v: Wrap,
    ) -> Result<Self, TextureError> {
        if width == 0 || height == 0 || texels.len() as u64 != u64::from(width) * u64::from(height)
        {
            return Err(TextureError::Size {
                width,
                height,
                texels: texels.len(),
            });
        }
        if let Some(index) = texels
            .iter()
            .position(|t| !(t.is_finite() && t.min_element() >= 0.0 && t.max_element() <= 1.0))
        {
            return Err(TextureError::Texel { index });
        }
        Ok(Texture {
            width,
            height,
            texels,
            wrap_u,
            wrap_v,
        })
    }

    /// Width and height, texels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The texel at column `x`, row `y` (unwrapped).
    pub fn texel(&self, x: u32, y: u32) -> Vec3 {
        self.texels[y as usize * self.width as usize + x as usize]
    }

    /// Bilinear value at texture coordinates `uv` (texel centres at ((i + ½)/w, (j + ½)/h)),
    /// each of the four texels wrapped by the sampler's mode. A non-finite coordinate reads
    /// as 0. The result is in [0, 1] per channel.
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        let axis = |c: f32, n: u32| -> (i64, f32) {
            let x = if c.is_finite() { c } else { 0.0 } as f64 * f64::from(n) - 0.5;
            let i = x.floor();
            (i as i64, (x - i) as f32)
        };
        let (x0, fx) = axis(uv.x, self.width);
        let (y0, fy) = axis(uv.y, self.height);
        let xs = [
            self.wrap_u.index(x0, self.width),
            self.wrap_u.index(x0.saturating_add(1), self.width),
        ];
        let ys = [
            self.wrap_v.index(y0, self.height),
            self.wrap_v.index(y0.saturating_add(1), self.height),
        ];
        let at = |x: usize, y: usize| self.texels[y * self.width as usize + x];
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
    fn srgb_decoding_matches_the_standard() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        // sRGB 0.5 is linear 0.2140.
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
    }
}
