//! PNG and JPEG base-colour images → linear RGB texels (sRGB decoded, as glTF specifies for
//! base colour). PNG through `png`, JPEG through `zune-jpeg`.

use std::io::Cursor;

use bdpm_scene::srgb_to_linear;
use glam::Vec3;

use crate::limits::MAX_TEXTURE_TEXELS;

/// A decoded image: width, height and row-major linear RGB texels from the top-left.
pub(crate) struct Decoded {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) texels: Vec<Vec3>,
}

/// Decodes a PNG or JPEG (recognised by its first bytes, whatever the file's mimeType says).
/// Alpha is dropped; grey images become equal RGB channels.
pub(crate) fn decode(bytes: &[u8]) -> Result<Decoded, String> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        decode_png(bytes)
    } else if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
        decode_jpeg(bytes)
    } else {
        Err("image is neither PNG nor JPEG (no PNG or JPEG signature)".into())
    }
}

fn check_size(width: u64, height: u64) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("image is {width}×{height}"));
    }
    if width * height > MAX_TEXTURE_TEXELS {
        return Err(format!(
            "image is {width}×{height}, more than {MAX_TEXTURE_TEXELS} texels"
        ));
    }
    Ok(())
}

/// 256-entry table of sRGB-decoded 8-bit values.
fn srgb_table() -> [f32; 256] {
    std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0))
}

/// Texels from 8-bit samples with `channels` per pixel (1 grey, 2 grey+alpha, 3 RGB, 4 RGBA).
fn texels(samples: &[u8], channels: usize) -> Vec<Vec3> {
    let lut = srgb_table();
    samples
        .chunks_exact(channels)
        .map(|px| match channels {
            1 | 2 => Vec3::splat(lut[px[0] as usize]),
            _ => Vec3::new(
                lut[px[0] as usize],
                lut[px[1] as usize],
                lut[px[2] as usize],
            ),
        })
        .collect()
}

fn decode_png(bytes: &[u8]) -> Result<Decoded, String> {
    let bad = |e: png::DecodingError| format!("cannot decode PNG: {e}");
    let mut decoder = png::Decoder::new(Cursor::new(bytes));
    // Palette and low bit depths expand to 8 bits; 16-bit samples keep their top byte
    // (texture detail below 1/255 is far below the renderer's noise).
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let header = decoder.read_header_info().map_err(bad)?;
    check_size(u64::from(header.width), u64::from(header.height))?;
    let mut reader = decoder.read_info().map_err(bad)?;
    let size = reader
        .output_buffer_size()
        .ok_or("PNG image too large for memory")?;
    let mut buf = vec![0; size];
    let info = reader.next_frame(&mut buf).map_err(bad)?;
    let channels = info.color_type.samples();
    let row = info.width as usize * channels;
    let mut packed = Vec::with_capacity(row * info.height as usize);
    for y in 0..info.height as usize {
        packed.extend_from_slice(&buf[y * info.line_size..][..row]);
    }
    Ok(Decoded {
        width: info.width,
        height: info.height,
        texels: texels(&packed, channels),
    })
}

fn decode_jpeg(bytes: &[u8]) -> Result<Decoded, String> {
    use zune_jpeg::zune_core::bytestream::ZCursor;
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    let options = DecoderOptions::default().jpeg_set_out_colorspace(ColorSpace::RGB);
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), options);
    decoder
        .decode_headers()
        .map_err(|e| format!("cannot decode JPEG: {e:?}"))?;
    let info = decoder.info().ok_or("cannot decode JPEG: no header")?;
    check_size(u64::from(info.width), u64::from(info.height))?;
    let samples = decoder
        .decode()
        .map_err(|e| format!("cannot decode JPEG: {e:?}"))?;
    let (width, height) = (u32::from(info.width), u32::from(info.height));
    if samples.len() != width as usize * height as usize * 3 {
        return Err(format!(
            "cannot decode JPEG: {} samples for a {width}×{height} RGB image",
            samples.len()
        ));
    }
    Ok(Decoded {
        width,
        height,
        texels: texels(&samples, 3),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 16 × 8 texels of sRGB (200, 100, 50), written by libjpeg-turbo's
    /// `cjpeg -quality 100` from a PPM (djpeg reads back exactly those bytes).
    const SOLID_JPEG: &[u8] = include_bytes!("../tests/data/solid-200-100-50.jpg");

    fn srgb(byte: u8) -> f32 {
        srgb_to_linear(f32::from(byte) / 255.0)
    }

    #[test]
    fn jpeg_decodes_to_linear_rgb() {
        let d = decode(SOLID_JPEG).expect("decodes");
        assert_eq!((d.width, d.height, d.texels.len()), (16, 8, 128));
        let want = Vec3::new(srgb(200), srgb(100), srgb(50));
        for t in &d.texels {
            // Baseline JPEG at quality 100 may be off by one code value.
            assert!((*t - want).abs().max_element() < 0.01, "{t} vs {want}");
        }
    }

    #[test]
    fn png_grey_and_rgba_decode_to_linear_rgb() {
        let png = |color, bytes: &[u8]| {
            let mut out = Vec::new();
            let mut e = png::Encoder::new(&mut out, 2, 1);
            e.set_color(color);
            e.set_depth(png::BitDepth::Eight);
            let mut w = e.write_header().expect("header");
            w.write_image_data(bytes).expect("data");
            w.finish().expect("end");
            out
        };
        let grey = decode(&png(png::ColorType::Grayscale, &[0, 188])).expect("grey");
        assert_eq!(grey.texels, vec![Vec3::ZERO, Vec3::splat(srgb(188))]);
        let rgba =
            decode(&png(png::ColorType::Rgba, &[255, 0, 10, 0, 1, 2, 3, 255])).expect("rgba");
        assert_eq!(
            rgba.texels,
            vec![
                Vec3::new(1.0, 0.0, srgb(10)),
                Vec3::new(srgb(1), srgb(2), srgb(3))
            ]
        );
    }

    #[test]
    fn other_bytes_are_an_error_not_a_panic() {
        assert!(decode(b"GIF89a").is_err());
        assert!(decode(&SOLID_JPEG[..100]).is_err());
        assert!(decode(b"\x89PNG\r\n\x1a\n\0\0").is_err());
    }
}
