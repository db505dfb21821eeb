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
    /// Scratch: horizontally interpolated source rows (fixed point, weights of 128; at most
    /// 255 * 128, so 16 bits suffice and the vertical products vectorize as 16-bit multiplies).
    row_a: Vec<u16>,
    row_b: Vec<u16>,
    /// Scratch: per destination column, the left source column, the right one (clamped) and
    /// the right one's weight.
    col_x0: Vec<u32>,
    col_x1: Vec<u32>,
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
                &mut self.row_a,
                &mut self.row_b,
                &mut self.col_x0,
                &mut self.col_x1,
                &mut self.col_w,
            );
            prev = level;
        }
    }
}

/// Bilinear resize of `src` into `dst` (`w x h`), sampling at pixel centres like OpenCV's
/// `INTER_LINEAR`: destination pixel `x` reads source position `(x + 0.5) * sw / w - 0.5`.
/// Fixed-point weights of 1/128, rounded to nearest.
#[allow(clippy::too_many_arguments)]
fn resize_bilinear(
    src: &GrayImage,
    dst: &mut GrayImage,
    w: usize,
    h: usize,
    row_a: &mut Vec<u16>,
    row_b: &mut Vec<u16>,
    col_x0: &mut Vec<u32>,
    col_x1: &mut Vec<u32>,
    col_w: &mut Vec<u16>,
) {
    dst.width = w;
    dst.height = h;
    dst.data.resize(w * h, 0);
    let (sw, sh) = (src.width, src.height);
    // Column table: left source column (clamped so x0 + 1 stays inside) and right weight.
    col_x0.clear();
    col_x1.clear();
    col_w.clear();
    let sx = sw as f64 / w as f64;
    for x in 0..w {
        let (x0, f) = sample_pos(x, sx, sw);
        col_x0.push(x0 as u32);
        col_x1.push((x0 + 1).min(sw - 1) as u32);
        col_w.push(f as u16);
    }
    row_a.resize(w, 0);
    row_b.resize(w, 0);
    let sy = sh as f64 / h as f64;
    let (mut have_a, mut have_b) = (usize::MAX, usize::MAX);
    for y in 0..h {
        let (y0, fy) = sample_pos(y, sy, sh);
        let y1 = (y0 + 1).min(sh - 1);
        // Reuse the interpolated rows of the previous destination row when possible.
        if have_a != y0 {
            if have_b == y0 {
                std::mem::swap(row_a, row_b);
                std::mem::swap(&mut have_a, &mut have_b);
            } else {
                hinterp(src.row(y0), col_x0, col_x1, col_w, row_a);
                have_a = y0;
            }
        }
        if have_b != y1 {
            hinterp(src.row(y1), col_x0, col_x1, col_w, row_b);
            have_b = y1;
        }
        let gy1 = fy as u16;
        let gy0 = (RESIZE_ONE - fy) as u16;
        let out = &mut dst.data[y * w..(y + 1) * w];
        let half = 1u32 << (2 * RESIZE_BITS - 1);
        for ((o, &a), &b) in out.iter_mut().zip(row_a.iter()).zip(row_b.iter()) {
            let v = a as u32 * gy0 as u32 + b as u32 * gy1 as u32 + half;
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

/// Horizontal interpolation of one source row into `out` (fixed point, times 128).
#[inline]
fn hinterp(row: &[u8], col_x0: &[u32], col_x1: &[u32], col_w: &[u16], out: &mut [u16]) {
    let one = RESIZE_ONE as u16;
    for (((o, &x0), &x1), &f) in out.iter_mut().zip(col_x0).zip(col_x1).zip(col_w) {
        let a = row[x0 as usize] as u16;
        let b = row[x1 as usize] as u16;
        *o = a * (one - f) + b * f;
    }
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
