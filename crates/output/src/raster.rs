//! 8-bit RGB images: the canvas the false-colour maps are drawn on, and their encoding as PNG
//! files (the preview, the noise map, the weight map and the lab's plots).
use std::path::Path;

use crate::files::write_atomic;

/// Encodes an 8-bit RGB PNG in memory, so that an encoder error cannot leave a half-written
/// temporary file, and a write error is reported (not lost in a drop).
pub fn encode_png_rgb8(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc
            .write_header()
            .map_err(|e| format!("cannot write PNG: {e}"))?;
        w.write_image_data(rgb)
            .map_err(|e| format!("cannot write PNG: {e}"))?;
        w.finish().map_err(|e| format!("cannot write PNG: {e}"))?;
    }
    Ok(bytes)
}

/// Writes an 8-bit RGB image atomically.
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), String> {
    write_atomic(path, &encode_png_rgb8(width, height, rgb)?)
}

/// An 8-bit RGB image, row-major, row 0 at the top.
pub struct Canvas {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// The pixels, 3 bytes each.
    pub rgb: Vec<u8>,
}

impl Canvas {
    /// Sets one pixel; coordinates outside the canvas are ignored (so callers may draw shapes
    /// that cross the border).
    pub fn set(&mut self, x: i64, y: i64, colour: [u8; 3]) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return;
        }
        let i = (y as usize * self.width as usize + x as usize) * 3;
        self.rgb[i..i + 3].copy_from_slice(&colour);
    }

    /// The image as PNG bytes.
    pub fn encode_png(&self) -> Result<Vec<u8>, String> {
        encode_png_rgb8(self.width, self.height, &self.rgb)
    }

    /// Writes the image as a PNG, atomically.
    pub fn write_png(&self, path: &Path) -> Result<(), String> {
        write_atomic(path, &self.encode_png()?)
    }
}
