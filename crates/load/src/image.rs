//! PNG and JPEG base-colour images → 8-bit sRGB RGB texels (3 bytes each), which
//! `bdpm_scene::TexelImage::srgb8` keeps and decodes to linear values when sampled, as glTF
//! specifies for base colour. PNG through `png`, JPEG through `zune-jpeg`. [`header`] reads
//! the size and the memory a decode takes before anything of that size is allocated.

use std::io::Cursor;

use crate::limits::MAX_TEXTURE_TEXELS;

/// A decoded image: width, height and row-major 8-bit sRGB R, G, B bytes from the top-left.
pub(crate) struct Decoded {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) rgb: Vec<u8>,
}

/// An image's size and what decoding it takes, read from its header alone (the decoded
/// texels kept are 3 bytes each).
pub(crate) struct Header {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// The most the decode holds at once, the kept texels included, bytes.
    pub(crate) decode_bytes: u64,
}

/// The image's [`Header`] (a PNG or JPEG recognised by its first bytes), after the checks
/// that need no decoding: a size within [`MAX_TEXTURE_TEXELS`], and for a JPEG the marker
/// walk of `jpeg_layout` (a frame, a scan, scan data enough for the size claimed).
pub(crate) fn header(bytes: &[u8]) -> Result<Header, String> {
    let (width, height, bytes_per_texel, extra) = if is_png(bytes) {
        let reader = png_reader(bytes)?;
        let info = reader.info();
        let channels = reader.output_color_type().0.samples() as u64;
        // The decoder's buffer (`channels` bytes a texel), compacted in place to RGB, or
        // expanded into a new RGB array for grey.
        let peak = if channels >= 3 {
            channels
        } else {
            channels + 3
        };
        (info.width, info.height, peak, 0)
    } else if is_jpeg(bytes) {
        let layout = jpeg_layout(bytes)?;
        check_jpeg_data(&layout, bytes.len())?;
        (layout.width, layout.height, 3, layout.coefficient_bytes())
    } else {
        let kind = if bytes.starts_with(b"RIFF") && bytes.get(8..12) == Some(b"WEBP") {
            "a WebP image"
        } else if bytes.starts_with(b"\xABKTX 20") {
            "a KTX2 (Basis) texture"
        } else if bytes.starts_with(b"GIF8") {
            "a GIF image"
        } else if bytes.starts_with(b"BM") {
            "a BMP image"
        } else {
            "neither PNG nor JPEG (no PNG or JPEG signature)"
        };
        return Err(format!(
            "image is {kind}; bdpm reads PNG and JPEG base-colour images"
        ));
    };
    check_size(u64::from(width), u64::from(height))?;
    let texels = u64::from(width) * u64::from(height);
    Ok(Header {
        width,
        height,
        decode_bytes: bytes_per_texel * texels + extra,
    })
}

/// Whether `bytes` start with the PNG signature.
pub(crate) fn is_png(bytes: &[u8]) -> bool {
    bytes.starts_with(b"\x89PNG\r\n\x1a\n")
}

/// Whether `bytes` start with a JPEG SOI marker.
pub(crate) fn is_jpeg(bytes: &[u8]) -> bool {
    bytes.starts_with(&[0xFF, 0xD8, 0xFF])
}

/// Decodes a PNG or JPEG (recognised by its first bytes, whatever the file's mimeType says)
/// after the checks of [`header`]. Alpha is dropped; grey images become equal RGB channels.
pub(crate) fn decode(bytes: &[u8]) -> Result<Decoded, String> {
    let _ = header(bytes)?;
    if is_png(bytes) {
        decode_png(bytes)
    } else {
        decode_jpeg(bytes)
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

/// A PNG reader past the header, set to give 8-bit samples: palette and low bit depths expand
/// to 8 bits; 16-bit samples keep their top byte (texture detail below 1/255 is far below the
/// renderer's noise).
fn png_reader(bytes: &[u8]) -> Result<png::Reader<Cursor<&[u8]>>, String> {
    let bad = |e: png::DecodingError| format!("cannot decode PNG: {e}");
    let mut decoder = png::Decoder::new(Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let header = decoder.read_header_info().map_err(bad)?;
    check_size(u64::from(header.width), u64::from(header.height))?;
    decoder.read_info().map_err(bad)
}

fn decode_png(bytes: &[u8]) -> Result<Decoded, String> {
    let mut reader = png_reader(bytes)?;
    let size = reader
        .output_buffer_size()
        .ok_or("PNG image too large for memory")?;
    let mut buf = vec![0; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("cannot decode PNG: {e}"))?;
    let channels = info.color_type.samples();
    let (w, h) = (info.width as usize, info.height as usize);
    let rgb = if channels >= 3 {
        // In place: texel i moves from (row, column) of the decoder's layout to 3i, never
        // after where it was, so a forward pass overwrites only bytes already moved.
        for y in 0..h {
            for x in 0..w {
                let from = y * info.line_size + x * channels;
                buf.copy_within(from..from + 3, 3 * (y * w + x));
            }
        }
        buf.truncate(3 * w * h);
        buf.shrink_to_fit();
        buf
    } else {
        let mut rgb = Vec::with_capacity(3 * w * h);
        for y in 0..h {
            let row = &buf[y * info.line_size..][..w * channels];
            for px in row.chunks_exact(channels) {
                rgb.extend_from_slice(&[px[0]; 3]);
            }
        }
        rgb
    };
    Ok(Decoded {
        width: info.width,
        height: info.height,
        rgb,
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
    /// Bytes of the DCT coefficients a decoder holds for the whole image when it cannot turn
    /// each row of blocks into texels as it goes (progressive files, or components in separate
    /// scans): 2 bytes per sample of every component, padded to whole blocks; 0 otherwise.
    fn coefficient_bytes(&self) -> u64 {
        if !self.progressive && self.scans <= 1 {
            return 0;
        }
        2 * 64 * self.blocks()
    }

    /// 8 × 8 blocks over all components.
    fn blocks(&self) -> u64 {
        let h_max = u64::from(self.sampling.iter().map(|s| s.0).max().unwrap_or(1));
        let v_max = u64::from(self.sampling.iter().map(|s| s.1).max().unwrap_or(1));
        let (w, h) = (u64::from(self.width), u64::from(self.height));
        self.sampling
            .iter()
            .map(|&(hc, vc)| {
                let cw = (w * u64::from(hc)).div_ceil(h_max);
                let ch = (h * u64::from(vc)).div_ceil(v_max);
                cw.div_ceil(8) * ch.div_ceil(8)
            })
            .sum()
    }

    /// The fewest bytes of entropy-coded data that can describe the image: every 8 × 8 block
    /// of every component costs at least one bit in a progressive file (its DC code) and two
    /// in a sequential one (a DC code and an AC code or end-of-block), as Huffman codes are at
    /// least one bit long.
    fn least_coded_bytes(&self) -> u64 {
        let blocks = self.blocks();
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

/// A header claiming more texels than the scans can describe is forged, or the data are
/// missing, and is refused before the decoder allocates the image (a 635-byte file claiming
/// 16384 × 16384 took 3.9 GB and 15 s to decode to grey).
fn check_jpeg_data(layout: &JpegLayout, file_bytes: usize) -> Result<(), String> {
    let least = layout.least_coded_bytes();
    if layout.coded_bytes < least {
        return Err(format!(
            "JPEG header claims {}×{} texels, more than its {file_bytes} bytes can hold ({} bytes of scan data where that size needs at least {least}); the file is truncated or its header forged",
            layout.width, layout.height, layout.coded_bytes
        ));
    }
    Ok(())
}

fn decode_jpeg(bytes: &[u8]) -> Result<Decoded, String> {
    use zune_jpeg::zune_core::bytestream::ZCursor;
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    let layout = jpeg_layout(bytes)?;
    let (width, height) = (layout.width, layout.height);
    // Strict: a marker inside the entropy-coded data, or data ending without an end-of-image
    // marker, is an error (zune-jpeg otherwise fills what it could not decode with grey).
    let options = DecoderOptions::default()
        .jpeg_set_out_colorspace(ColorSpace::RGB)
        .set_strict_mode(true);
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
    let rgb = decoder.decode().map_err(|e| {
        format!("cannot decode JPEG ({width}×{height}): {e:?}; the file is truncated or damaged")
    })?;
    if rgb.len() != width as usize * height as usize * 3 {
        return Err(format!(
            "cannot decode JPEG: {} samples for a {width}×{height} RGB image",
            rgb.len()
        ));
    }
    Ok(Decoded { width, height, rgb })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 16 × 8 texels of sRGB (200, 100, 50), written by libjpeg-turbo's
    /// `cjpeg -quality 100` from a PPM (djpeg reads back exactly those bytes).
    const SOLID_JPEG: &[u8] = include_bytes!("../tests/data/solid-200-100-50.jpg");

    #[test]
    fn jpeg_decodes_to_srgb_bytes() {
        let d = decode(SOLID_JPEG).expect("decodes");
        assert_eq!((d.width, d.height, d.rgb.len()), (16, 8, 3 * 128));
        for t in d.rgb.chunks_exact(3) {
            // Baseline JPEG at quality 100 may be off by one code value.
            let off = t.iter().zip([200u8, 100, 50]).map(|(a, b)| a.abs_diff(b));
            assert!(off.max() <= Some(1), "{t:?}");
        }
        let h = header(SOLID_JPEG).expect("header");
        // Sequential, one scan: the decoder turns rows of blocks into texels as it goes.
        assert_eq!((h.width, h.height, h.decode_bytes), (16, 8, 384));
    }

    #[test]
    fn png_grey_and_rgba_decode_to_srgb_rgb() {
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
        let grey = png(png::ColorType::Grayscale, &[0, 188]);
        assert_eq!(
            decode(&grey).expect("grey").rgb,
            vec![0, 0, 0, 188, 188, 188]
        );
        let h = header(&grey).expect("header");
        // One byte a texel decoded, expanded into a new RGB array.
        assert_eq!(h.decode_bytes, 8);
        let rgba = png(png::ColorType::Rgba, &[255, 0, 10, 0, 1, 2, 3, 255]);
        assert_eq!(decode(&rgba).expect("rgba").rgb, vec![255, 0, 10, 1, 2, 3]);
        assert_eq!(header(&rgba).expect("header").decode_bytes, 8);
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
                prop_assert_eq!(d.rgb.len(), 3 * d.width as usize * d.height as usize);
            }
        });
    }

    #[test]
    fn other_bytes_are_an_error_not_a_panic() {
        let gif = decode(b"GIF89a").err().expect("GIF refused");
        assert!(
            gif.contains("is a GIF image; bdpm reads PNG and JPEG"),
            "{gif}"
        );
        let webp = decode(b"RIFF\0\0\0\0WEBPVP8 ").err().expect("WebP refused");
        assert!(webp.contains("is a WebP image"), "{webp}");
        assert!(decode(&SOLID_JPEG[..100]).is_err());
        assert!(decode(b"\x89PNG\r\n\x1a\n\0\0").is_err());
    }
}
