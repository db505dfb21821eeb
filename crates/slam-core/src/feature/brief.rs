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
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: `gaussian_blur_avx2` only enables AVX2 code generation for safe code; the
        // CPU supports AVX2, checked on the line above.
        unsafe { gaussian_blur_avx2(src, dst, tmp) };
        return;
    }
    gaussian_blur_impl(src, dst, tmp);
}

/// [`gaussian_blur_impl`] compiled with AVX2 enabled (integer arithmetic: bit-identical to the
/// baseline build). Call only on a CPU that has AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn gaussian_blur_avx2(src: &GrayImage, dst: &mut GrayImage, tmp: &mut Vec<u16>) {
    gaussian_blur_impl(src, dst, tmp);
}

/// The body of [`gaussian_blur`].
#[inline(always)]
fn gaussian_blur_impl(src: &GrayImage, dst: &mut GrayImage, tmp: &mut Vec<u16>) {
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

/// Row stride of the local copy of the descriptor window: a power of two above
/// `2 * PATTERN_RADIUS + 1`, so a window index is `(v << 5) | u` and masking it with
/// `WINDOW_LEN - 1` proves it in bounds without a check.
const WINDOW_STRIDE: usize = 32;
/// Size of the local window copy.
const WINDOW_LEN: usize = WINDOW_STRIDE * WINDOW_STRIDE;
const _: () = assert!(2 * (PATTERN_RADIUS as usize) < WINDOW_STRIDE);

/// `floor(x)` as a float for `|x| < 2^22`, in arithmetic that vectorizes. Adding `1.5 * 2^23`
/// rounds `x` to the nearest integer (ties to even); one compare turns that into the floor.
#[inline(always)]
fn floor_small(x: f32) -> f32 {
    let nearest = (x + MAGIC) - MAGIC;
    if nearest > x {
        nearest - 1.0
    } else {
        nearest
    }
}

/// `1.5 * 2^23`: its ulp is 1, so `x + MAGIC` holds the integer `x` in the low mantissa bits.
const MAGIC: f32 = 12_582_912.0;

/// The integer value of `x`, an integer-valued float with `|x| < 2^22` (a plain `as i32` cast
/// saturates, which SSE2/AVX2 code can only do one lane at a time).
#[inline(always)]
fn small_float_to_int(x: f32) -> i32 {
    (x + MAGIC).to_bits() as i32 - MAGIC.to_bits() as i32
}

/// The steered BRIEF descriptor of the keypoint at pixel (x, y) of the blurred level, with
/// orientation `angle_deg` (degrees, image coordinates): each pattern point (px, py) is rotated
/// to (px cos - py sin, px sin + py cos) and rounded to the nearest pixel. The caller keeps
/// (x, y) at least `PATTERN_RADIUS + 2` px from the border.
pub fn compute_descriptor(blurred: &GrayImage, x: usize, y: usize, angle_deg: f32) -> Descriptor {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: `descriptor_avx2` only enables AVX2 code generation for safe code; the CPU
        // supports AVX2, checked on the line above.
        return unsafe { descriptor_avx2(blurred, x, y, angle_deg) };
    }
    descriptor_impl(blurred, x, y, angle_deg)
}

/// [`descriptor_impl`] compiled with AVX2 enabled (8 pattern points per instruction instead of
/// 4; the float operations are the same IEEE operations, so the result is bit-identical). Call
/// only on a CPU that has AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn descriptor_avx2(blurred: &GrayImage, x: usize, y: usize, angle_deg: f32) -> Descriptor {
    descriptor_impl(blurred, x, y, angle_deg)
}

/// The body of [`compute_descriptor`]: the window around the keypoint is copied into a
/// fixed-size array, the rotated pattern turned into window indices in float arithmetic (no
/// branches, no saturating casts, no libm: all of it vectorizes), then the 256 tests read.
#[inline(always)]
fn descriptor_impl(blurred: &GrayImage, x: usize, y: usize, angle_deg: f32) -> Descriptor {
    const R: usize = PATTERN_RADIUS as usize;
    let (s, c) = angle_deg.to_radians().sin_cos();
    let w = blurred.width;
    // The square window of radius R around the keypoint; slicing panics (instead of reading
    // elsewhere) if the caller breaks the border contract.
    let mut window = [0u8; WINDOW_LEN];
    for (dy, dst) in window
        .chunks_exact_mut(WINDOW_STRIDE)
        .take(2 * R + 1)
        .enumerate()
    {
        let start = (y + dy).wrapping_sub(R).wrapping_mul(w) + x.wrapping_sub(R);
        dst[..2 * R + 1].copy_from_slice(&blurred.data[start..start + 2 * R + 1]);
    }
    // Window index of every rotated point: the pixel is floor(p + 64.5) - 64 as in the plain
    // `(p + 64.5) as i32 - 64`, clamped to the window (every pattern point lies within radius
    // R, so the rounded rotated point does too and the clamp never changes a value; it only
    // keeps the index provably inside the window). All values are small integers, exact in f32.
    let mut idx = [0u32; 512];
    let (px, py) = (&PATTERN_SOA.x, &PATTERN_SOA.y);
    let (lo, hi) = (64.0 - R as f32, 64.0 + R as f32);
    for k in 0..512 {
        let u = floor_small(px[k] * c - py[k] * s + 64.5).clamp(lo, hi) - lo;
        let v = floor_small(px[k] * s + py[k] * c + 64.5).clamp(lo, hi) - lo;
        idx[k] = small_float_to_int(v * WINDOW_STRIDE as f32 + u) as u32;
    }
    let at = |i: u32| window[i as usize & (WINDOW_LEN - 1)];
    let mut desc = [0u64; 4];
    for (word, pairs) in desc.iter_mut().zip(idx.chunks_exact(128)) {
        let mut bits = 0u64;
        for (b, pair) in pairs.chunks_exact(2).enumerate() {
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
    fn float_floor_and_conversion_are_exact() {
        let mut x = -300.0f32;
        while x < 300.0 {
            for v in [x, x + 0.5, x - 0.5, x.next_up(), x.next_down()] {
                assert_eq!(floor_small(v), v.floor(), "{v}");
                assert_eq!(small_float_to_int(v.floor()), v.floor() as i32, "{v}");
            }
            x += 0.37;
        }
        for v in [
            0.0,
            -0.0,
            0.5,
            1.5,
            2.5,
            -0.5,
            -1.5,
            64.5,
            63.999_996,
            4_194_303.5,
        ] {
            assert_eq!(floor_small(v), v.floor(), "{v}");
            assert_eq!(small_float_to_int(v.floor()), v.floor() as i32, "{v}");
        }
    }

    #[test]
    fn blur_equals_direct_convolution() {
        let img = crate::feature::fast::tests::random_image(67, 41, 9);
        let (w, h) = (67usize, 41usize);
        let at = |x: i64, y: i64| {
            img.get(
                x.clamp(0, w as i64 - 1) as usize,
                y.clamp(0, h as i64 - 1) as usize,
            ) as u32
        };
        let (mut out, mut tmp) = (GrayImage::new(0, 0), Vec::new());
        gaussian_blur(&img, &mut out, &mut tmp);
        let (mut portable, mut tmp2) = (GrayImage::new(0, 0), Vec::new());
        gaussian_blur_impl(&img, &mut portable, &mut tmp2);
        assert_eq!(out, portable);
        for y in 0..h as i64 {
            for x in 0..w as i64 {
                let mut v = 0u32;
                for (j, &gy) in GAUSS7.iter().enumerate() {
                    let row: u32 = GAUSS7
                        .iter()
                        .enumerate()
                        .map(|(i, &gx)| gx * at(x + i as i64 - 3, y + j as i64 - 3))
                        .sum();
                    v += gy * row;
                }
                assert_eq!(
                    out.get(x as usize, y as usize) as u32,
                    (v + (1 << 15)) >> 16
                );
            }
        }
    }

    /// The descriptor as first written: integer casts and offsets into the whole level.
    fn reference_descriptor(img: &GrayImage, x: usize, y: usize, angle_deg: f32) -> Descriptor {
        let (s, c) = angle_deg.to_radians().sin_cos();
        let mut desc = [0u64; 4];
        for (i, p) in PATTERN.iter().enumerate() {
            let pt = |px: i8, py: i8| {
                let (px, py) = (px as f32, py as f32);
                let u = (px * c - py * s + 64.5) as i32 - 64;
                let v = (px * s + py * c + 64.5) as i32 - 64;
                img.get((x as i32 + u) as usize, (y as i32 + v) as usize)
            };
            if pt(p[0], p[1]) < pt(p[2], p[3]) {
                desc[i / 64] |= 1 << (i % 64);
            }
        }
        desc
    }

    #[test]
    fn descriptor_equals_reference_at_every_angle() {
        let img = crate::feature::fast::tests::random_image(61, 61, 5);
        let mut angle = 0.0f32;
        while angle < 360.0 {
            assert_eq!(
                compute_descriptor(&img, 30, 30, angle),
                reference_descriptor(&img, 30, 30, angle),
                "{angle}"
            );
            // Also the portable build when the dispatcher picks AVX2.
            assert_eq!(
                descriptor_impl(&img, 30, 30, angle),
                reference_descriptor(&img, 30, 30, angle)
            );
            angle += 0.7;
        }
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
