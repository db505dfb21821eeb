//! The image families on one 8-bit grey image: sensor noise (synth's CMOS shot + read noise
//! model), motion blur, exposure flicker and JPEG compression; and on a colour image, as a
//! colour camera would: noise, blur and gain on each channel, JPEG on the colour image (its
//! YCbCr with subsampled chroma), the grey image then the colour's luma.

use rayon::prelude::*;
use slam_core::{ColourImage, GrayImage};
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
/// centred on it at angle `angle` (radians), sampled every half pixel or finer, bilinearly
/// (edges clamped). Every sample's offset is the same for all pixels, so its bilinear weights
/// are computed once and a pixel costs four loads per sample.
pub fn motion_blur(img: &GrayImage, length: f64, angle: f64) -> GrayImage {
    let n = (2.0 * length).ceil().max(1.0) as usize + 1;
    let (dx, dy) = (angle.cos() * length, angle.sin() * length);
    // Per sample: integer offset and the bilinear weights of its fractional part.
    let taps: Vec<(i64, i64, [f32; 4])> = (0..n)
        .map(|k| {
            let t = k as f64 / (n - 1).max(1) as f64 - 0.5;
            let (ox, oy) = (t * dx, t * dy);
            let (fx, fy) = (ox.floor(), oy.floor());
            let (ax, ay) = ((ox - fx) as f32, (oy - fy) as f32);
            (
                fx as i64,
                fy as i64,
                [
                    (1.0 - ax) * (1.0 - ay),
                    ax * (1.0 - ay),
                    (1.0 - ax) * ay,
                    ax * ay,
                ],
            )
        })
        .collect();
    let (w, h) = (img.width as i64, img.height as i64);
    let src = &img.data;
    let inv = 1.0 / n as f32;
    let mut data = vec![0u8; img.data.len()];
    data.par_chunks_mut(img.width)
        .enumerate()
        .for_each(|(y, row)| {
            let mut acc = vec![0f32; img.width];
            for &(ox, oy, wt) in &taps {
                let r0 = ((y as i64 + oy).clamp(0, h - 1) * w) as usize;
                let r1 = ((y as i64 + oy + 1).clamp(0, h - 1) * w) as usize;
                // Columns whose x + ox and x + ox + 1 are both inside: no clamping.
                let lo = (-ox).clamp(0, w) as usize;
                let hi = (w - 1 - ox).clamp(0, w) as usize;
                let at = |x: i64| x.clamp(0, w - 1) as usize;
                for (x, a) in acc.iter_mut().enumerate() {
                    let (c0, c1) = if x >= lo && x < hi {
                        let c = (x as i64 + ox) as usize;
                        (c, c + 1)
                    } else {
                        (at(x as i64 + ox), at(x as i64 + ox + 1))
                    };
                    *a += wt[0] * src[r0 + c0] as f32
                        + wt[1] * src[r0 + c1] as f32
                        + wt[2] * src[r1 + c0] as f32
                        + wt[3] * src[r1 + c1] as f32;
                }
            }
            for (o, a) in row.iter_mut().zip(&acc) {
                *o = (a * inv + 0.5).clamp(0.0, 255.0) as u8;
            }
        });
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
    let (w, h) = (img.width, img.height);
    match jpeg_round_trip(&img.data, w, h, quality, false) {
        Some(data) => GrayImage {
            width: w,
            height: h,
            data,
        },
        // An in-memory encoder of an in-memory image does not fail; keep the frame if it does.
        None => img.clone(),
    }
}

/// `data` (grey, or RGB when `colour`) of `w x h` through a baseline JPEG of `quality` and back;
/// `None` if the encoder or decoder fails or the size changes.
fn jpeg_round_trip(data: &[u8], w: usize, h: usize, quality: u8, colour: bool) -> Option<Vec<u8>> {
    use ::image::codecs::jpeg::JpegEncoder;
    use ::image::ExtendedColorType;
    let mut bytes = Vec::new();
    let ty = if colour {
        ExtendedColorType::Rgb8
    } else {
        ExtendedColorType::L8
    };
    JpegEncoder::new_with_quality(&mut bytes, quality.clamp(1, 100))
        .encode(data, w as u32, h as u32, ty)
        .ok()?;
    let d = ::image::load_from_memory(&bytes).ok()?;
    if d.width() as usize != w || d.height() as usize != h {
        return None;
    }
    Some(if colour {
        d.into_rgb8().into_raw()
    } else {
        d.into_luma8().into_raw()
    })
}

/// The three channels of a colour image as grey planes (R, G, B).
pub fn planes(c: &ColourImage) -> [GrayImage; 3] {
    std::array::from_fn(|k| GrayImage {
        width: c.width,
        height: c.height,
        data: c.data.iter().skip(k).step_by(3).copied().collect(),
    })
}

/// The colour image of three grey planes (R, G, B) of one size.
pub fn interleave(p: &[GrayImage; 3]) -> ColourImage {
    let mut data = Vec::with_capacity(p[0].data.len() * 3);
    for i in 0..p[0].data.len() {
        data.extend([p[0].data[i], p[1].data[i], p[2].data[i]]);
    }
    ColourImage {
        width: p[0].width,
        height: p[0].height,
        data,
    }
}

/// Encodes a colour image as a baseline JPEG of `quality` (1-100) and decodes it again.
pub fn jpeg_colour(img: &ColourImage, quality: u8) -> ColourImage {
    let (w, h) = (img.width, img.height);
    match jpeg_round_trip(&img.data, w, h, quality, true) {
        Some(data) => ColourImage {
            width: w,
            height: h,
            data,
        },
        None => img.clone(),
    }
}
