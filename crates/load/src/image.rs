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

/// What the marker segments of a JPEG say, before any decoding.
struct JpegLayout {
    width: u32,
    height: u32,
    /// Progressive (SOF2, SOF6, SOF10, SOF14) rather than sequential.
    progressive: bool,
    /// Horizontal and vertical sampling factors of each component.
    sampling: Vec<(u8, u8)>,
    /// Scans (SOS segments).
    scans: usize,
    /// Bytes of entropy-coded data over all scans.
    coded_bytes: u64,
}

impl JpegLayout {
    /// The fewest bytes of entropy-coded data that can describe the image: every 8 × 8 block
    /// of every component costs at least one bit in a progressive file (its DC code) and two
    /// in a sequential one (a DC code and an AC code or end-of-block), as Huffman codes are at
    /// least one bit long.
    fn least_coded_bytes(&self) -> u64 {
        let h_max = u64::from(self.sampling.iter().map(|s| s.0).max().unwrap_or(1));
        let v_max = u64::from(self.sampling.iter().map(|s| s.1).max().unwrap_or(1));
        let (w, h) = (u64::from(self.width), u64::from(self.height));
        let blocks: u64 = self
            .sampling
            .iter()
            .map(|&(hc, vc)| {
                let cw = (w * u64::from(hc)).div_ceil(h_max);
                let ch = (h * u64::from(vc)).div_ceil(v_max);
                cw.div_ceil(8) * ch.div_ceil(8)
            })
            .sum();
        let bits_per_block = if self.progressive { 1 } else { 2 };
        (blocks * bits_per_block).div_ceil(8)
    }
}

/// Walks the JPEG's marker segments (zune-jpeg does not report them, and it decodes a file
/// whose data stop early by filling the missing blocks with grey, even in strict mode, when an
/// end-of-image marker follows): the frame header's size and sampling, the scans and their
/// entropy-coded bytes. A file without a frame header or a scan, or one that ends inside a
/// segment or its scan data, is an error.
fn jpeg_layout(b: &[u8]) -> Result<JpegLayout, String> {
    let mut layout = JpegLayout {
        width: 0,
        height: 0,
        progressive: false,
        sampling: Vec::new(),
        scans: 0,
        coded_bytes: 0,
    };
    let cut = || "JPEG ends inside a segment (the file is truncated)".to_string();
    let mut i = 2;
    let mut frame = false;
    loop {
        // Markers may be preceded by any number of 0xFF fill bytes.
        while b.get(i) == Some(&0xFF) && b.get(i + 1) == Some(&0xFF) {
            i += 1;
        }
        let (Some(&0xFF), Some(&marker)) = (b.get(i), b.get(i + 1)) else {
            return Err("JPEG ends without an end-of-image marker (the file is truncated)".into());
        };
        i += 2;
        match marker {
            0xD9 => break,
            0xD0..=0xD7 | 0x01 => continue,
            _ => {}
        }
        let len = b.get(i..i + 2).ok_or_else(cut)?;
        let len = usize::from(u16::from_be_bytes([len[0], len[1]]));
        let seg = b.get(i + 2..i + len.max(2)).ok_or_else(cut)?;
        i += len.max(2);
        match marker {
            0xC0..=0xC3 | 0xC5..=0xC7 | 0xC9..=0xCB | 0xCD..=0xCF => {
                let comps = seg.get(5).copied().unwrap_or(0) as usize;
                let head = seg
                    .get(..6 + 3 * comps)
                    .filter(|_| comps > 0)
                    .ok_or_else(|| {
                        "JPEG frame header is too short for its components".to_string()
                    })?;
                frame = true;
                layout.height = u32::from(u16::from_be_bytes([head[1], head[2]]));
                layout.width = u32::from(u16::from_be_bytes([head[3], head[4]]));
                layout.progressive = matches!(marker, 0xC2 | 0xC6 | 0xCA | 0xCE);
                layout.sampling = head[6..]
                    .chunks_exact(3)
                    .map(|c| (c[1] >> 4, c[1] & 15))
                    .collect();
                if layout.sampling.iter().any(|&(h, v)| h == 0 || v == 0) {
                    return Err("JPEG frame header has a sampling factor of 0".into());
                }
            }
            0xDA => {
                layout.scans += 1;
                // Entropy-coded data run to the next marker that is not a stuffed 0xFF00 or
                // a restart marker.
                let start = i;
                loop {
                    match (b.get(i), b.get(i + 1)) {
                        (Some(&0xFF), Some(&next))
                            if next != 0 && !(0xD0..=0xD7).contains(&next) =>
                        {
                            break;
                        }
                        (Some(_), Some(_)) => i += 1,
                        _ => {
                            return Err(
                                "JPEG ends inside its scan data (the file is truncated)".into()
                            );
                        }
                    }
                }
                layout.coded_bytes += (i - start) as u64;
            }
            _ => {}
        }
    }
    if !frame {
        return Err("JPEG has no frame header (SOF), so no image size".into());
    }
    if layout.scans == 0 {
        return Err("JPEG has no scan (SOS): the file holds no image data".into());
    }
    Ok(layout)
}

fn decode_jpeg(bytes: &[u8]) -> Result<Decoded, String> {
    use zune_jpeg::zune_core::bytestream::ZCursor;
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    // Strict: a truncated scan, a missing scan or a marker inside the entropy-coded data is an
    // error; zune-jpeg otherwise fills the rows it could not decode with grey and succeeds.
    let options = DecoderOptions::default()
        .jpeg_set_out_colorspace(ColorSpace::RGB)
        .set_strict_mode(true);
    let layout = jpeg_layout(bytes)?;
    let (width, height) = (layout.width, layout.height);
    check_size(u64::from(width), u64::from(height))?;
    // Before the decoder allocates the image: a header claiming more texels than the scans can
    // describe (a 635-byte file claiming 16384 × 16384 took 3.9 GB and 15 s to decode to grey).
    let least = layout.least_coded_bytes();
    if layout.coded_bytes < least {
        return Err(format!(
            "JPEG header claims {width}×{height} texels, more than its {} bytes can hold ({} bytes of scan data where that size needs at least {least}); the file is truncated or its header forged",
            bytes.len(),
            layout.coded_bytes
        ));
    }
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), options);
    decoder
        .decode_headers()
        .map_err(|e| format!("cannot decode JPEG: {e:?}"))?;
    let info = decoder.info().ok_or("cannot decode JPEG: no header")?;
    if (u32::from(info.width), u32::from(info.height)) != (width, height) {
        return Err(format!(
            "cannot decode JPEG: the decoder reads {}×{} where the frame header says {width}×{height}",
            info.width, info.height
        ));
    }
    let samples = decoder.decode().map_err(|e| {
        format!("cannot decode JPEG ({width}×{height}): {e:?}; the file is truncated or damaged")
    })?;
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

    /// Random byte edits and cuts of the JPEG (its marker walk and the decoder) and of a PNG:
    /// `Ok` or an error, never a panic, and an image that decodes has width × height texels.
    /// `PROPTEST_CASES=100000` runs it longer.
    #[test]
    fn damaged_images_decode_or_fail_without_panic() {
        use proptest::prelude::*;
        let mut png = Vec::new();
        {
            let mut e = png::Encoder::new(&mut png, 4, 3);
            e.set_color(png::ColorType::Rgb);
            e.set_depth(png::BitDepth::Eight);
            let mut w = e.write_header().expect("header");
            w.write_image_data(&[7; 36]).expect("data");
        }
        let edit = (any::<usize>(), any::<u8>());
        proptest!(|(which in 0..2usize, edits in proptest::collection::vec(edit, 1..6), cut in any::<usize>())| {
            let mut bytes = if which == 0 { SOLID_JPEG.to_vec() } else { png.clone() };
            for (i, b) in edits {
                let n = bytes.len();
                bytes[i % n] = b;
            }
            if cut % 3 == 0 {
                bytes.truncate(cut % (bytes.len() + 1));
            }
            if let Ok(d) = decode(&bytes) {
                prop_assert_eq!(d.texels.len(), d.width as usize * d.height as usize);
            }
        });
    }

    #[test]
    fn other_bytes_are_an_error_not_a_panic() {
        assert!(decode(b"GIF89a").is_err());
        assert!(decode(&SOLID_JPEG[..100]).is_err());
        assert!(decode(b"\x89PNG\r\n\x1a\n\0\0").is_err());
    }
}
