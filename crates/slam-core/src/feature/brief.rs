//! Steered BRIEF (Calonder et al. 2010; rotated as in ORB): the level is smoothed with a 7x7
//! Gaussian (sigma 2) to make the binary tests robust to noise, then the 256 point pairs of
//! [`PATTERN`] are rotated by the keypoint angle, rounded to whole pixels (no interpolation, as
//! ORB-SLAM2) and compared.

use super::pattern::{PATTERN, PATTERN_RADIUS};
use super::Descriptor;
use crate::image::GrayImage;

/// Integer taps of the 7-tap Gaussian with sigma 2, summing to 256 (the exact weights are
/// 0.0702, 0.1311, 0.1907, 0.2161, ...).
pub const GAUSS7: [u32; 7] = [18, 33, 49, 56, 49, 33, 18];

/// Separable 7x7 Gaussian blur (sigma 2) of `src` into `dst`, replicating the border pixels.
/// `tmp` holds the horizontal pass and is reused between calls.
pub fn gaussian_blur(src: &GrayImage, dst: &mut GrayImage, tmp: &mut Vec<u16>) {
    let (w, h) = (src.width, src.height);
    dst.width = w;
    dst.height = h;
    dst.data.resize(w * h, 0);
    tmp.resize(w * h, 0);
    if w == 0 || h == 0 {
        return;
    }
    // Horizontal pass: u8 -> u16 (at most 255 * 256).
    for y in 0..h {
        let row = &src.data[y * w..(y + 1) * w];
        let out = &mut tmp[y * w..(y + 1) * w];
        if w > 6 {
            let n = w - 6;
            let (s0, s1, s2, s3) = (&row[0..n], &row[1..n + 1], &row[2..n + 2], &row[3..n + 3]);
            let (s4, s5, s6) = (&row[4..n + 4], &row[5..n + 5], &row[6..n + 6]);
            let o = &mut out[3..n + 3];
            for i in 0..n {
                let v = GAUSS7[0] as u16 * (s0[i] as u16 + s6[i] as u16)
                    + GAUSS7[1] as u16 * (s1[i] as u16 + s5[i] as u16)
                    + GAUSS7[2] as u16 * (s2[i] as u16 + s4[i] as u16)
                    + GAUSS7[3] as u16 * s3[i] as u16;
                o[i] = v;
            }
        }
        // Border columns (and whole rows narrower than the kernel) with clamped indices.
        let left = 3.min(w);
        for x in (0..left).chain(w.saturating_sub(3).max(left)..w) {
            let mut v = 0u32;
            for (k, &g) in GAUSS7.iter().enumerate() {
                let xx = (x as i64 + k as i64 - 3).clamp(0, w as i64 - 1) as usize;
                v += g * row[xx] as u32;
            }
            out[x] = v as u16;
        }
    }
    // Vertical pass: u16 -> u32 -> u8 with rounding.
    for y in 0..h {
        let r = |k: usize| {
            let yy = (y as i64 + k as i64 - 3).clamp(0, h as i64 - 1) as usize;
            &tmp[yy * w..(yy + 1) * w]
        };
        let (r0, r1, r2, r3) = (&r(0)[..w], &r(1)[..w], &r(2)[..w], &r(3)[..w]);
        let (r4, r5, r6) = (&r(4)[..w], &r(5)[..w], &r(6)[..w]);
        let out = &mut dst.data[y * w..(y + 1) * w];
        for i in 0..w {
            // Products of 16-bit values (pmullw / pmulhuw on any x86-64), summed in 32 bits.
            let v = GAUSS7[0] * r0[i] as u32
                + GAUSS7[0] * r6[i] as u32
                + GAUSS7[1] * r1[i] as u32
                + GAUSS7[1] * r5[i] as u32
                + GAUSS7[2] * r2[i] as u32
                + GAUSS7[2] * r4[i] as u32
                + GAUSS7[3] * r3[i] as u32;
            out[i] = ((v + (1 << 15)) >> 16) as u8;
        }
    }
}

/// The pattern as x and y coordinate arrays (point `2i` and `2i + 1` are the two points of
/// test `i`), laid out so rotating all of them vectorizes.
struct PatternSoa {
    x: [f32; 512],
    y: [f32; 512],
}

const PATTERN_SOA: PatternSoa = {
    let mut x = [0f32; 512];
    let mut y = [0f32; 512];
    let mut i = 0;
    while i < 256 {
        x[2 * i] = PATTERN[i][0] as f32;
        y[2 * i] = PATTERN[i][1] as f32;
        x[2 * i + 1] = PATTERN[i][2] as f32;
        y[2 * i + 1] = PATTERN[i][3] as f32;
        i += 1;
    }
    PatternSoa { x, y }
};

/// The steered BRIEF descriptor of the keypoint at pixel (x, y) of the blurred level, with
/// orientation `angle_deg` (degrees, image coordinates): each pattern point (px, py) is rotated
/// to (px cos - py sin, px sin + py cos) and rounded to the nearest pixel. The caller keeps
/// (x, y) at least `PATTERN_RADIUS + 2` px from the border.
pub fn compute_descriptor(blurred: &GrayImage, x: usize, y: usize, angle_deg: f32) -> Descriptor {
    const R: i32 = PATTERN_RADIUS;
    let (s, c) = angle_deg.to_radians().sin_cos();
    let w = blurred.width;
    // The square window of radius R around the keypoint; slicing panics (instead of reading
    // elsewhere) if the caller breaks the border contract.
    let r = R as usize;
    let first = (y.wrapping_sub(r))
        .wrapping_mul(w)
        .wrapping_add(x.wrapping_sub(r));
    let last = (y + r) * w + x + r;
    let window = &blurred.data[first..=last];
    let base = (R * w as i32 + R) as u32;
    // Window offsets of the rotated points (vectorized: no branches, no libm). Every pattern
    // point lies within radius R, so the rounded rotated point does too and the clamp never
    // changes a value; it only lets the reads below skip their bounds checks.
    let mut off = [0u32; 512];
    let (px, py) = (&PATTERN_SOA.x, &PATTERN_SOA.y);
    let wi = w as i32;
    for k in 0..512 {
        let u = ((px[k] * c - py[k] * s + 64.5) as i32 - 64).clamp(-R, R);
        let v = ((px[k] * s + py[k] * c + 64.5) as i32 - 64).clamp(-R, R);
        off[k] = (base as i32 + v * wi + u) as u32;
    }
    // o = (R + v) * w + (R + u) with u, v clamped to [-R, R], so 0 <= o < window.len(); the
    // bounds check stays (unchecked reads measured no faster).
    let at = |o: u32| window[o as usize];
    let mut desc = [0u64; 4];
    for (word, offs) in desc.iter_mut().zip(off.chunks_exact(128)) {
        let mut bits = 0u64;
        for (b, pair) in offs.chunks_exact(2).enumerate() {
            bits |= ((at(pair[0]) < at(pair[1])) as u64) << b;
        }
        *word = bits;
    }
    desc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blur_keeps_constants_and_smooths_an_impulse() {
        let mut img = GrayImage {
            width: 20,
            height: 15,
            data: vec![100; 300],
        };
        let (mut out, mut tmp) = (GrayImage::new(0, 0), Vec::new());
        gaussian_blur(&img, &mut out, &mut tmp);
        assert!(out.data.iter().all(|&v| v == 100));
        img.data.fill(0);
        img.data[7 * 20 + 10] = 255;
        gaussian_blur(&img, &mut out, &mut tmp);
        let sum: u32 = out.data.iter().map(|&v| v as u32).sum();
        assert!((sum as i32 - 255).abs() < 20, "mass {sum}");
        let centre = out.get(10, 7);
        assert_eq!(centre, ((56u32 * 56 * 255 + (1 << 15)) >> 16) as u8);
        assert_eq!(out.get(9, 7), out.get(11, 7));
        assert_eq!(out.get(10, 6), out.get(10, 8));
        assert_eq!(out.get(10, 3), out.get(14, 7));
        assert_eq!(out.get(10, 2), 0);
    }

    #[test]
    fn descriptor_of_rotated_patch_matches_steered_one() {
        // Rotating the image by 90 degrees and the angle by 90 degrees gives the same tests
        // (rotation by 90 degrees is exact on the pixel grid).
        let img = crate::feature::fast::tests::random_image(61, 61, 3);
        let mut rot = GrayImage::new(61, 61);
        for y in 0..61 {
            for x in 0..61 {
                // (x, y) -> (60 - y, x): a +90 degree turn in image coordinates.
                rot.data[x * 61 + (60 - y)] = img.get(x, y);
            }
        }
        let a = compute_descriptor(&img, 30, 30, 10.0);
        let b = compute_descriptor(&rot, 30, 30, 100.0);
        assert_eq!(a, b);
        assert_ne!(a, compute_descriptor(&img, 30, 30, 100.0));
    }
}
