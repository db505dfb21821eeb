//! PNG decoding into slam-core's plain images: colour or grey PNGs to 8-bit grey (ITU-R BT.601
//! weights, as OpenCV's `cvtColor(RGB2GRAY)` that ORB-SLAM2 uses), 16-bit depth PNGs to metres.

use crate::DatasetError;
use image::DynamicImage;
use slam_core::{DepthImage, GrayImage};
use std::path::Path;

fn open(path: &Path) -> Result<DynamicImage, DatasetError> {
    if !path.is_file() {
        return Err(DatasetError::Missing {
            path: path.to_path_buf(),
            what: "an image listed by the sequence".into(),
        });
    }
    let bytes = std::fs::read(path).map_err(|e| DatasetError::io(path, e))?;
    image::load_from_memory_with_format(&bytes, image::ImageFormat::Png).map_err(|e| {
        DatasetError::Decode {
            path: path.to_path_buf(),
            msg: e.to_string(),
        }
    })
}

/// BT.601 luma in 14-bit fixed point with rounding (the constants OpenCV uses), so grey values
/// match what ORB-SLAM2 sees for the same colour PNG.
#[inline]
pub fn rgb_to_gray(r: u8, g: u8, b: u8) -> u8 {
    ((r as u32 * 4899 + g as u32 * 9617 + b as u32 * 1868 + (1 << 13)) >> 14) as u8
}

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
