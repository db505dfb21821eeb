//! PNG decoding into slam-core's plain images: colour or grey PNGs to 8-bit grey (ITU-R BT.601
//! weights, as OpenCV's `cvtColor(RGB2GRAY)` that ORB-SLAM2 uses), 16-bit depth PNGs to metres;
//! and any PNG or JPEG for `noisefree features`.
//!
//! An image's header is checked before its pixels are allocated: a header claiming more pixel
//! bytes than the file's compressed data can expand to ([`MAX_DECODED_BYTES_PER_BYTE`]) is
//! refused, so a corrupt or hostile 100-byte file cannot make the reader allocate gigabytes.

use crate::DatasetError;
use image::{DynamicImage, ImageDecoder, ImageFormat, ImageReader};
use slam_core::{ColourImage, DepthImage, GrayImage};
use std::io::Cursor;
use std::path::Path;

/// Most bytes of decoded pixels a compressed image can hold per byte of its file: deflate
/// (PNG) expands at most 1032:1, and a 1-bit PNG's samples are decoded to a byte each, 8 from a
/// byte of expanded data. (JPEG's baseline needs at least two bits per 8x8 block; its
/// progressive mode's runs of empty blocks are held to the same bound as PNG.)
pub const MAX_DECODED_BYTES_PER_BYTE: u64 = 8 * 1032;

/// Bytes of decoded pixels any image may claim whatever its size (a small file may be a plain
/// 128x128 RGBA image).
const MIN_DECODED_ALLOWANCE: u64 = 1 << 16;

/// A defect of a PNG's chunks that its decoder (the `png` crate, 0.18) panics on instead of
/// refusing: a palette (PLTE) whose length is not a whole number of RGB entries (the decoder
/// checks 3..=768 bytes, then copies the last entry as three bytes). Found by fuzzing
/// (png-gray, png-depth, seed 50, from the palette seeds). `None` for other content.
fn png_chunk_defect(bytes: &[u8]) -> Option<String> {
    const SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
    if !bytes.starts_with(SIGNATURE) {
        return None;
    }
    // Chunks as the decoder frames them: length, type, data, CRC.
    let mut at = SIGNATURE.len();
    while let Some(head) = bytes.get(at..at + 8) {
        let len = u32::from_be_bytes([head[0], head[1], head[2], head[3]]) as usize;
        match &head[4..8] {
            b"PLTE" if !len.is_multiple_of(3) => {
                return Some(format!(
                    "its palette (the PLTE chunk at byte {at}) is {len} bytes long, not a whole \
                     number of 3-byte RGB entries"
                ))
            }
            b"IEND" => break,
            _ => {}
        }
        at = at.checked_add(12)?.checked_add(len)?;
    }
    None
}

/// Decodes `bytes` (the file `path`) as `format`, or as the format its content shows when
/// `None`, after checking that the header's size is one its data can hold.
fn decode(
    path: &Path,
    bytes: &[u8],
    format: Option<ImageFormat>,
) -> Result<DynamicImage, DatasetError> {
    let fail = |msg: String| DatasetError::Decode {
        path: path.to_path_buf(),
        msg,
    };
    let reader = |b: &[u8]| -> Result<ImageReader<Cursor<Vec<u8>>>, DatasetError> {
        let r = ImageReader::new(Cursor::new(b.to_vec()));
        match format {
            Some(f) => {
                let mut r = r;
                r.set_format(f);
                Ok(r)
            }
            None => r.with_guessed_format().map_err(|e| fail(e.to_string())),
        }
    };
    if let Some(defect) = png_chunk_defect(bytes) {
        return Err(fail(defect));
    }
    let decoder = reader(bytes)?
        .into_decoder()
        .map_err(|e| fail(e.to_string()))?;
    let (w, h) = decoder.dimensions();
    let pixel_bytes = u64::from(decoder.color_type().bytes_per_pixel());
    let decoded = u64::from(w) * u64::from(h) * pixel_bytes;
    let allowed = MIN_DECODED_ALLOWANCE + MAX_DECODED_BYTES_PER_BYTE * bytes.len() as u64;
    if decoded > allowed {
        return Err(fail(format!(
            "the header says {w}x{h} pixels of {pixel_bytes} bytes, more than its {} bytes can \
             hold (at most {allowed} bytes of pixels); the file is corrupt or truncated",
            bytes.len()
        )));
    }
    drop(decoder);
    reader(bytes)?.decode().map_err(|e| fail(e.to_string()))
}

fn open(path: &Path) -> Result<DynamicImage, DatasetError> {
    if !path.is_file() {
        return Err(DatasetError::Missing {
            path: path.to_path_buf(),
            what: "an image listed by the sequence".into(),
        });
    }
    let bytes = std::fs::read(path).map_err(|e| DatasetError::io(path, e))?;
    decode(path, &bytes, Some(ImageFormat::Png))
}

/// Reads an image of any format the build decodes (PNG, JPEG), told by its content, with the
/// same header check as the sequence readers.
pub fn read_image(path: &Path) -> Result<DynamicImage, DatasetError> {
    let bytes = std::fs::read(path).map_err(|e| DatasetError::io(path, e))?;
    decode(path, &bytes, None)
}

pub use slam_core::rgb_to_gray;

/// Decodes a PNG (grey, grey+alpha, RGB or RGBA; 8 or 16 bit) into an 8-bit grey image.
pub fn read_gray(path: &Path) -> Result<GrayImage, DatasetError> {
    let img = open(path)?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let data = match img {
        DynamicImage::ImageLuma8(b) => b.into_raw(),
        DynamicImage::ImageRgb8(b) => b
            .into_raw()
            .chunks_exact(3)
            .map(|p| rgb_to_gray(p[0], p[1], p[2]))
            .collect(),
        DynamicImage::ImageRgba8(b) => b
            .into_raw()
            .chunks_exact(4)
            .map(|p| rgb_to_gray(p[0], p[1], p[2]))
            .collect(),
        other => {
            // 16-bit or grey+alpha: go through 8-bit RGB first.
            let rgb = other.to_rgb8();
            rgb.into_raw()
                .chunks_exact(3)
                .map(|p| rgb_to_gray(p[0], p[1], p[2]))
                .collect()
        }
    };
    Ok(GrayImage {
        width: w,
        height: h,
        data,
    })
}

/// Decodes a PNG into its 8-bit grey image (as [`read_gray`]) and, when it has colour
/// channels, its 8-bit RGB image (alpha dropped; 16-bit channels to 8 as `image` converts them):
/// the grey is the colour's luma, bit for bit what [`read_gray`] gives.
pub fn read_gray_and_colour(path: &Path) -> Result<(GrayImage, Option<ColourImage>), DatasetError> {
    let img = open(path)?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let rgb = match img {
        DynamicImage::ImageLuma8(b) => {
            let grey = GrayImage {
                width: w,
                height: h,
                data: b.into_raw(),
            };
            return Ok((grey, None));
        }
        DynamicImage::ImageRgb8(b) => b.into_raw(),
        other if other.color().has_color() => other.to_rgb8().into_raw(),
        other => {
            // Grey with alpha or 16-bit grey: no colour to keep.
            let data = other
                .to_rgb8()
                .into_raw()
                .chunks_exact(3)
                .map(|p| rgb_to_gray(p[0], p[1], p[2]))
                .collect();
            return Ok((
                GrayImage {
                    width: w,
                    height: h,
                    data,
                },
                None,
            ));
        }
    };
    let colour = ColourImage {
        width: w,
        height: h,
        data: rgb,
    };
    Ok((colour.to_gray(), Some(colour)))
}

/// Decodes a 16-bit single-channel depth PNG; value / `depth_factor` is metres, 0 is no depth.
/// Any other pixel format (e.g. 8-bit) is an error: scaling it would silently give wrong depth.
pub fn read_depth(path: &Path, depth_factor: f64) -> Result<DepthImage, DatasetError> {
    let img = open(path)?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let DynamicImage::ImageLuma16(buf) = img else {
        return Err(DatasetError::DepthFormat {
            path: path.to_path_buf(),
            found: describe(&img),
        });
    };
    // Divide in f64 and round once to f32: the correctly rounded metre value of each PNG step.
    let data = buf
        .into_raw()
        .into_iter()
        .map(|v| (v as f64 / depth_factor) as f32)
        .collect();
    Ok(DepthImage {
        width: w,
        height: h,
        data,
    })
}

fn describe(img: &DynamicImage) -> String {
    match img {
        DynamicImage::ImageLuma8(_) => "8-bit grey".into(),
        DynamicImage::ImageLumaA8(_) => "8-bit grey+alpha".into(),
        DynamicImage::ImageRgb8(_) => "8-bit RGB".into(),
        DynamicImage::ImageRgba8(_) => "8-bit RGBA".into(),
        DynamicImage::ImageLumaA16(_) => "16-bit grey+alpha".into(),
        DynamicImage::ImageRgb16(_) => "16-bit RGB".into(),
        DynamicImage::ImageRgba16(_) => "16-bit RGBA".into(),
        other => format!("{:?}", other.color()),
    }
}

/// The CRC-32 a PNG chunk carries over its type and data (IEEE 802.3, as the PNG
/// specification computes it): for the tests and fuzzers that build or repair PNG files.
pub fn png_crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &x in bytes {
        c ^= u32::from(x);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_crc_of_the_iend_chunk_every_png_ends_with() {
        assert_eq!(png_crc32(b"IEND"), 0xae42_6082);
        assert_eq!(png_crc32(b""), 0);
    }

    #[test]
    fn bt601_weights() {
        assert_eq!(rgb_to_gray(255, 255, 255), 255);
        assert_eq!(rgb_to_gray(0, 0, 0), 0);
        assert_eq!(rgb_to_gray(255, 0, 0), 76); // 0.299 * 255 = 76.2
        assert_eq!(rgb_to_gray(0, 255, 0), 150); // 0.587 * 255 = 149.7
        assert_eq!(rgb_to_gray(0, 0, 255), 29); // 0.114 * 255 = 29.1
    }

    #[test]
    fn reads_depth_in_metres_and_rejects_8_bit() {
        let dir = tempfile::tempdir().unwrap();
        let p16 = dir.path().join("d16.png");
        image::ImageBuffer::<image::Luma<u16>, _>::from_raw(2, 1, vec![5000u16, 0])
            .unwrap()
            .save(&p16)
            .unwrap();
        let d = read_depth(&p16, 5000.0).unwrap();
        assert_eq!(d.data, vec![1.0, 0.0]);
        let p8 = dir.path().join("d8.png");
        image::GrayImage::from_raw(2, 1, vec![1, 2])
            .unwrap()
            .save(&p8)
            .unwrap();
        let err = read_depth(&p8, 5000.0).unwrap_err();
        assert!(matches!(err, DatasetError::DepthFormat { .. }), "{err}");
        assert!(err.to_string().contains("8-bit grey"));
    }

    #[test]
    fn a_header_claiming_more_pixels_than_the_file_holds_is_refused_unallocated() {
        // A real 1x1 PNG whose IHDR is rewritten to 65535 x 65535 (CRC repaired): 4.3 G
        // pixels in 70 bytes. Decoding would allocate 4 GB before finding the data short.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("liar.png");
        image::GrayImage::from_raw(1, 1, vec![7])
            .unwrap()
            .save(&p)
            .unwrap();
        let mut b = std::fs::read(&p).unwrap();
        b[16..24].copy_from_slice(&[0, 0, 0xff, 0xff, 0, 0, 0xff, 0xff]);
        let crc = png_crc32(&b[12..29]);
        b[29..33].copy_from_slice(&crc.to_be_bytes());
        std::fs::write(&p, &b).unwrap();
        let e = read_gray(&p).unwrap_err().to_string();
        assert!(e.contains("liar.png") && e.contains("65535x65535"), "{e}");
        let e = read_image(&p).unwrap_err().to_string();
        assert!(e.contains("more than its"), "{e}");
    }

    #[test]
    fn the_header_check_counts_bytes_of_pixels_not_pixels() {
        // Found by fuzzing (png-depth, 1.96 M inputs): a 5 kB 16-bit RGB PNG whose header
        // says 2359320 x 16 passed a check of pixels per byte and took 227 MB (6 bytes a pixel).
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("rgb16.png");
        let img =
            image::ImageBuffer::<image::Rgb<u16>, _>::from_raw(24, 16, vec![9u16; 24 * 16 * 3])
                .unwrap();
        img.save(&p).unwrap();
        let mut b = std::fs::read(&p).unwrap();
        // As many pixels as the old check let through (90 % of 8256 a byte), 6 bytes each.
        let width = (0.9 * (MAX_DECODED_BYTES_PER_BYTE * b.len() as u64) as f64 / 16.0) as u32;
        b[16..20].copy_from_slice(&width.to_be_bytes());
        let crc = png_crc32(&b[12..29]);
        b[29..33].copy_from_slice(&crc.to_be_bytes());
        std::fs::write(&p, &b).unwrap();
        let e = read_depth(&p, 5000.0).unwrap_err().to_string();
        assert!(e.contains("rgb16.png") && e.contains("of 6 bytes"), "{e}");
    }

    #[test]
    fn a_palette_of_part_entries_is_refused_not_panicked_on() {
        // Found by fuzzing (png-gray and png-depth, seed 50, 2 M inputs each, from the palette
        // seeds), shrunk: a 1-bit palette PNG whose PLTE chunk holds 7 bytes made the png
        // crate's palette expansion panic (range end index 3 out of range for slice of length
        // 1), in every reader of PNGs.
        let png: &[u8] =
            b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00\x00\r\x00\x00\x00\x07\x01\x03\
            \x00\x00\x00\xe9\xbeUY\x00\x00\x00\x07PLTE\x00\x00\xff%UY\xca\xfeK\xee}\x00\x00\x00 \
            IDATx\x01\x01\x15\x00\xea\xff\x00U\xef";
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("palette.png");
        std::fs::write(&p, png).unwrap();
        let errors = [
            read_gray(&p).map(|_| ()).unwrap_err(),
            read_depth(&p, 5000.0).map(|_| ()).unwrap_err(),
            read_image(&p).map(|_| ()).unwrap_err(),
        ];
        for e in errors {
            let e = e.to_string();
            assert!(
                e.contains("palette.png")
                    && e.contains("(the PLTE chunk at byte 33) is 7 bytes long"),
                "{e}"
            );
        }
        // Whole entries (6 bytes) are decoded as before.
        let mut whole = png.to_vec();
        whole[36] = 6;
        whole.remove(47);
        let crc = png_crc32(&whole[37..47]);
        whole[47..51].copy_from_slice(&crc.to_be_bytes());
        std::fs::write(&p, &whole).unwrap();
        let e = read_gray(&p).map(|_| ()).unwrap_err().to_string();
        assert!(!e.contains("PLTE"), "{e}");
    }
}
