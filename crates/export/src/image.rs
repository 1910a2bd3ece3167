//! A base-colour texture as Mitsuba reads it: the linear texels bdpm samples, times the
//! material's factor, as a float EXR image (exact where an 8-bit sRGB copy of the original
//! file would round, and the same for textures that came from a glTF buffer or data URI).

use std::io::Cursor;

use bdpm_scene::Texture;
use exr::prelude::{SpecificChannels, Vec2, WritableImage};
use glam::Vec3;

/// The EXR bytes of `texture`'s texels times `scale`, linear RGB float32, row 0 at the top
/// (v = 0, as both renderers lay the image out).
pub(crate) fn exr(texture: &Texture, scale: Vec3) -> Result<Vec<u8>, String> {
    let (width, height) = texture.size();
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let t = texture.texel(p.0 as u32, p.1 as u32) * scale;
        (t.x, t.y, t.z)
    });
    let image = exr::prelude::Image::from_channels((width as usize, height as usize), channels);
    let mut bytes = Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| format!("cannot encode the texture as EXR: {e}"))?;
    Ok(bytes.into_inner())
}
