//! The image pyramid: per-level scale tables ([`ScaleInfo`]) and the resized levels
//! ([`Pyramid`]), each level resized bilinearly from the previous one as ORB-SLAM2 does.

use crate::image::GrayImage;

/// Scale tables of an `n_levels` pyramid with ratio `scale_factor` between consecutive levels.
/// Level `l` is `scale_factor^l` times smaller than the input; a keypoint found on it has a
/// position uncertainty `sigma^2 = scale_factor^(2l)` px^2 (in level-0 pixels), which the
/// optimizers use as the inverse weight of its reprojection error.
#[derive(Clone, Debug, PartialEq)]
pub struct ScaleInfo {
    /// Number of pyramid levels (ORB-SLAM2: 8).
    pub n_levels: usize,
    /// Ratio between the sizes of consecutive levels (ORB-SLAM2: 1.2).
    pub scale_factor: f64,
    /// `ln(scale_factor)`, used to predict the level a map point is seen at.
    pub log_scale_factor: f64,
    /// `scale_factor^l` per level.
    pub scale_factors: Vec<f64>,
    /// `1 / scale_factor^l` per level.
    pub inv_scale_factors: Vec<f64>,
    /// `scale_factor^(2l)` per level: the variance of a keypoint position, px^2.
    pub level_sigma2: Vec<f64>,
    /// `1 / scale_factor^(2l)` per level: the information weight of a keypoint position.
    pub inv_level_sigma2: Vec<f64>,
}

impl ScaleInfo {
    /// Tables for `n_levels` levels (at least 1) with ratio `scale_factor` (> 1).
    pub fn new(n_levels: usize, scale_factor: f64) -> Self {
        let n_levels = n_levels.max(1);
        let mut scale_factors = Vec::with_capacity(n_levels);
        let mut s = 1.0;
        for _ in 0..n_levels {
            scale_factors.push(s);
            s *= scale_factor;
        }
        let inv_scale_factors = scale_factors.iter().map(|s| 1.0 / s).collect();
        let level_sigma2: Vec<f64> = scale_factors.iter().map(|s| s * s).collect();
        let inv_level_sigma2 = level_sigma2.iter().map(|s| 1.0 / s).collect();
        ScaleInfo {
            n_levels,
            scale_factor,
            log_scale_factor: scale_factor.ln(),
            scale_factors,
            inv_scale_factors,
            level_sigma2,
            inv_level_sigma2,
        }
    }

    /// Size of level `l` for a `width x height` input: each side divided by the level's scale
    /// factor and rounded (ORB-SLAM2 `cvRound`).
    pub fn level_size(&self, width: usize, height: usize, l: usize) -> (usize, usize) {
        let inv = self.inv_scale_factors[l];
        (
            (width as f64 * inv).round() as usize,
            (height as f64 * inv).round() as usize,
        )
    }
}

/// The resized levels of one image. Buffers are kept between calls to [`Pyramid::build`] so a
/// running extractor allocates nothing per frame once the image size is stable.
#[derive(Clone, Debug, Default)]
pub struct Pyramid {
    /// Level `l` is the input resized by `1 / scale_factor^l`; level 0 is a copy of the input.
    pub levels: Vec<GrayImage>,
    /// Scratch: the vertically interpolated source row of one destination row (fixed point,
    /// weights of 128; at most 255 * 128, so 16 bits suffice and the products vectorize as
    /// 16-bit multiplies), plus one zero so that the right neighbour of the last column exists.
    vrow: Vec<u16>,
    /// Scratch: per destination column, the left source column and the right one's weight.
    col_x0: Vec<u32>,
    col_w: Vec<u16>,
}

/// Fixed-point precision of the bilinear weights: weights sum to `1 << RESIZE_BITS`.
const RESIZE_BITS: u32 = 7;
const RESIZE_ONE: u32 = 1 << RESIZE_BITS;

impl Pyramid {
    /// An empty pyramid; [`Pyramid::build`] fills it.
    pub fn new() -> Self {
        Self::default()
    }

    /// Builds all levels of `img` for the tables in `scale`, reusing the buffers.
    pub fn build(&mut self, img: &GrayImage, scale: &ScaleInfo) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: `build_avx2` only enables AVX2 code generation for safe code; the CPU
            // supports AVX2, checked on the line above.
            unsafe { self.build_avx2(img, scale) };
            return;
        }
        self.build_impl(img, scale);
    }

    /// [`Pyramid::build_impl`] compiled with AVX2 enabled (integer arithmetic: bit-identical to
    /// the baseline build). Call only on a CPU that has AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn build_avx2(&mut self, img: &GrayImage, scale: &ScaleInfo) {
        self.build_impl(img, scale);
    }

    /// The body of [`Pyramid::build`].
    #[inline(always)]
    fn build_impl(&mut self, img: &GrayImage, scale: &ScaleInfo) {
        self.levels
            .resize_with(scale.n_levels, || GrayImage::new(0, 0));
        let (first, rest) = self.levels.split_first_mut().expect("at least one level");
        first.width = img.width;
        first.height = img.height;
        first.data.clear();
        first.data.extend_from_slice(&img.data);
        let mut prev: &GrayImage = first;
        for (i, level) in rest.iter_mut().enumerate() {
            let (w, h) = scale.level_size(img.width, img.height, i + 1);
            resize_bilinear(
                prev,
                level,
                w.max(1),
                h.max(1),
                &mut self.vrow,
                &mut self.col_x0,
                &mut self.col_w,
            );
            prev = level;
        }
    }
}

/// Bilinear resize of `src` into `dst` (`w x h`), sampling at pixel centres like OpenCV's
/// `INTER_LINEAR`: destination pixel `x` reads source position `(x + 0.5) * sw / w - 0.5`.
/// Fixed-point weights of 1/128, rounded to nearest; the four weighted pixels are summed
/// exactly and rounded once, so the order of the two passes does not change the result. The
/// vertical pass runs first, over contiguous source rows (vectorized), and leaves a single
/// gather per destination pixel for the horizontal one.
#[inline(always)]
fn resize_bilinear(
    src: &GrayImage,
    dst: &mut GrayImage,
    w: usize,
    h: usize,
    vrow: &mut Vec<u16>,
    col_x0: &mut Vec<u32>,
    col_w: &mut Vec<u16>,
) {
    dst.width = w;
    dst.height = h;
    dst.data.resize(w * h, 0);
    let (sw, sh) = (src.width, src.height);
    // Column table: left source column and right weight (0 on the last source column, whose
    // right neighbour is the zero padding of `vrow`).
    col_x0.clear();
    col_w.clear();
    let sx = sw as f64 / w as f64;
    for x in 0..w {
        let (x0, f) = sample_pos(x, sx, sw);
        col_x0.push(x0 as u32);
        col_w.push(f as u16);
    }
    vrow.clear();
    vrow.resize(sw + 1, 0);
    let sy = sh as f64 / h as f64;
    let one = RESIZE_ONE as u16;
    let half = 1u32 << (2 * RESIZE_BITS - 1);
    for y in 0..h {
        let (y0, fy) = sample_pos(y, sy, sh);
        let y1 = (y0 + 1).min(sh - 1);
        let (gy0, gy1) = (one - fy as u16, fy as u16);
        let (ra, rb) = (src.row(y0), src.row(y1));
        for ((v, &a), &b) in vrow[..sw].iter_mut().zip(ra).zip(rb) {
            *v = a as u16 * gy0 + b as u16 * gy1;
        }
        // Plain slices, so the compiler keeps their bounds in registers across the stores.
        let (vr, xs, fs): (&[u16], &[u32], &[u16]) = (vrow, col_x0, col_w);
        let out = &mut dst.data[y * w..(y + 1) * w];
        for ((o, &x0), &f) in out.iter_mut().zip(xs).zip(fs) {
            let pair = &vr[x0 as usize..x0 as usize + 2];
            let v = pair[0] as u32 * (one - f) as u32 + pair[1] as u32 * f as u32 + half;
            *o = (v >> (2 * RESIZE_BITS)) as u8;
        }
    }
}

/// Source sample of destination index `i` for a scale `s = src / dst`: the left (or upper)
/// source index and the fixed-point weight of the next one.
#[inline]
fn sample_pos(i: usize, s: f64, n: usize) -> (usize, u32) {
    let pos = ((i as f64 + 0.5) * s - 0.5).max(0.0);
    let i0 = (pos.floor() as usize).min(n - 1);
    let f = if i0 + 1 >= n {
        0
    } else {
        ((pos - i0 as f64) * RESIZE_ONE as f64).round() as u32
    };
    (i0, f.min(RESIZE_ONE))
}

/// Row access used by the pyramid and the detectors.
pub(crate) trait RowAccess {
    /// The pixels of row `y`.
    fn row(&self, y: usize) -> &[u8];
}

impl RowAccess for GrayImage {
    #[inline]
    fn row(&self, y: usize) -> &[u8] {
        &self.data[y * self.width..(y + 1) * self.width]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_tables_match_orbslam2() {
        let s = ScaleInfo::new(8, 1.2);
        let expected_sigma2 = [
            1.0, 1.44, 2.0736, 2.98598, 4.29982, 6.19174, 8.91610, 12.83918,
        ];
        for (l, e) in expected_sigma2.iter().enumerate() {
            assert!((s.level_sigma2[l] - e).abs() < 1e-4, "level {l}");
            assert!((s.scale_factors[l] * s.inv_scale_factors[l] - 1.0).abs() < 1e-12);
            assert!((s.level_sigma2[l] * s.inv_level_sigma2[l] - 1.0).abs() < 1e-12);
        }
        assert!((s.log_scale_factor - 1.2f64.ln()).abs() < 1e-15);
        assert_eq!(s.level_size(640, 480, 1), (533, 400));
        assert_eq!(s.level_size(640, 480, 7), (179, 134));
    }

    #[test]
    fn resize_equals_direct_bilinear_formula() {
        // Odd sizes, a 1-pixel-wide level and an upscale exercise the clamped borders.
        let img = crate::feature::fast::tests::random_image(67, 41, 4);
        for (w, h) in [(56usize, 34usize), (1, 3), (67, 41), (80, 50), (2, 1)] {
            let mut out = GrayImage::new(0, 0);
            let (mut v, mut x0s, mut fs) = (Vec::new(), Vec::new(), Vec::new());
            resize_bilinear(&img, &mut out, w, h, &mut v, &mut x0s, &mut fs);
            assert_eq!((out.width, out.height), (w, h));
            for y in 0..h {
                let (y0, fy) = sample_pos(y, 41.0 / h as f64, 41);
                let y1 = (y0 + 1).min(40);
                for x in 0..w {
                    let (x0, fx) = sample_pos(x, 67.0 / w as f64, 67);
                    let x1 = (x0 + 1).min(66);
                    let p = |xx: usize, yy: usize| img.get(xx, yy) as u32;
                    let sum = (p(x0, y0) * (128 - fx) + p(x1, y0) * fx) * (128 - fy)
                        + (p(x0, y1) * (128 - fx) + p(x1, y1) * fx) * fy;
                    assert_eq!(
                        out.get(x, y) as u32,
                        (sum + 8192) >> 14,
                        "{w}x{h} ({x},{y})"
                    );
                }
            }
        }
        // The dispatched build of the whole pyramid agrees with the portable one.
        let scale = ScaleInfo::new(8, 1.2);
        let (mut a, mut b) = (Pyramid::new(), Pyramid::new());
        a.build(&img, &scale);
        b.build_impl(&img, &scale);
        assert_eq!(a.levels, b.levels);
    }

    #[test]
    fn resize_keeps_constant_and_linear_images() {
        let (w, h) = (60, 40);
        let mut img = GrayImage::new(w, h);
        for y in 0..h {
            for x in 0..w {
                img.data[y * w + x] = (2 * x + y) as u8;
            }
        }
        let scale = ScaleInfo::new(3, 1.2);
        let mut pyr = Pyramid::new();
        pyr.build(&img, &scale);
        assert_eq!(pyr.levels[0], img);
        let l1 = &pyr.levels[1];
        assert_eq!((l1.width, l1.height), (50, 33));
        // A linear ramp stays linear under bilinear sampling (away from the clamped border).
        for y in 2..l1.height - 2 {
            for x in 2..l1.width - 2 {
                let sx = (x as f64 + 0.5) * 1.2 - 0.5;
                let sy = (y as f64 + 0.5) * (40.0 / 33.0) - 0.5;
                let expect = 2.0 * sx + sy;
                let got = l1.get(x, y) as f64;
                assert!((got - expect).abs() <= 1.0, "({x},{y}) {got} vs {expect}");
            }
        }
        // Rebuilding a different image reuses buffers and gives a fresh result.
        let flat = GrayImage {
            width: w,
            height: h,
            data: vec![77; w * h],
        };
        pyr.build(&flat, &scale);
        assert!(pyr.levels[2].data.iter().all(|&v| v == 77));
    }
}
