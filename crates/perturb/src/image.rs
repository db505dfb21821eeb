//! The image families on one 8-bit grey image: sensor noise (synth's CMOS shot + read noise
//! model), motion blur, exposure flicker and JPEG compression.

use rayon::prelude::*;
use slam_core::GrayImage;
use synth::hash::NoiseKey;
use synth::sensor::imaging::SensorNoise;

/// Sensor noise whose standard deviation at grey level 128 is `sigma_128` grey levels, a
/// quarter of its variance read noise and the rest shot noise (so dark pixels are less noisy,
/// as on a real sensor): `read = sigma/2`, `electrons_per_dn = 128 / (0.75 sigma^2)`.
pub fn sensor_noise(sigma_128: f64) -> SensorNoise {
    SensorNoise {
        read_dn: sigma_128 / 2.0,
        electrons_per_dn: 128.0 / (0.75 * sigma_128 * sigma_128),
    }
}

/// Adds [`sensor_noise`] of `sigma_128`.
pub fn noise(img: &GrayImage, sigma_128: f64, key: NoiseKey) -> GrayImage {
    GrayImage {
        width: img.width,
        height: img.height,
        data: sensor_noise(sigma_128).apply_gray8(&img.data, key),
    }
}

/// Bilinear sample of `img` at (x, y) (pixel centres at integers), edges clamped.
#[inline]
pub fn bilinear(img: &GrayImage, x: f64, y: f64) -> f64 {
    let (w, h) = (img.width as i64, img.height as i64);
    let (xf, yf) = (x.floor(), y.floor());
    let (ax, ay) = (x - xf, y - yf);
    let px = |x: i64, y: i64| img.data[(y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize] as f64;
    let (x0, y0) = (xf as i64, yf as i64);
    let top = px(x0, y0) * (1.0 - ax) + px(x0 + 1, y0) * ax;
    let bottom = px(x0, y0 + 1) * (1.0 - ax) + px(x0 + 1, y0 + 1) * ax;
    top * (1.0 - ay) + bottom * ay
}

/// Linear motion blur: each pixel the mean of the image along a segment of `length` pixels
/// centred on it at angle `angle` (radians), sampled every half pixel or finer.
pub fn motion_blur(img: &GrayImage, length: f64, angle: f64) -> GrayImage {
    let n = (2.0 * length).ceil().max(1.0) as usize + 1;
    let (dx, dy) = (angle.cos() * length, angle.sin() * length);
    let offsets: Vec<(f64, f64)> = (0..n)
        .map(|k| {
            let t = k as f64 / (n - 1) as f64 - 0.5;
            (t * dx, t * dy)
        })
        .collect();
    let w = img.width;
    let data = (0..img.width * img.height)
        .into_par_iter()
        .map(|i| {
            let (x, y) = ((i % w) as f64, (i / w) as f64);
            let s: f64 = offsets
                .iter()
                .map(|&(ox, oy)| bilinear(img, x + ox, y + oy))
                .sum();
            (s / n as f64 + 0.5).clamp(0.0, 255.0) as u8
        })
        .collect();
    GrayImage {
        width: img.width,
        height: img.height,
        data,
    }
}

/// Scales every grey level by `gain` (an exposure or gain change), rounded and clipped.
pub fn exposure(img: &GrayImage, gain: f64) -> GrayImage {
    GrayImage {
        width: img.width,
        height: img.height,
        data: img
            .data
            .iter()
            .map(|&g| (g as f64 * gain + 0.5).clamp(0.0, 255.0) as u8)
            .collect(),
    }
}

/// The per-frame gain of `exposure:sigma_percent`: 1 + sigma N(0, 1), at least 0.05.
pub fn flicker_gain(sigma_percent: f64, key: NoiseKey) -> f64 {
    (1.0 + sigma_percent / 100.0 * key.normal(0)).max(0.05)
}

/// Encodes as a baseline JPEG of `quality` (1-100) and decodes it again.
pub fn jpeg(img: &GrayImage, quality: u8) -> GrayImage {
    use ::image::codecs::jpeg::JpegEncoder;
    use ::image::ExtendedColorType;
    let mut bytes = Vec::new();
    let encoded = JpegEncoder::new_with_quality(&mut bytes, quality.clamp(1, 100)).encode(
        &img.data,
        img.width as u32,
        img.height as u32,
        ExtendedColorType::L8,
    );
    let decoded = encoded
        .ok()
        .and_then(|_| ::image::load_from_memory(&bytes).ok())
        .map(|d| d.into_luma8());
    match decoded {
        Some(d) if d.width() as usize == img.width && d.height() as usize == img.height => {
            GrayImage {
                width: img.width,
                height: img.height,
                data: d.into_raw(),
            }
        }
        // An in-memory encoder of an in-memory image does not fail; keep the frame if it does.
        _ => img.clone(),
    }
}
