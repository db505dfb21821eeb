//! Keypoint orientation by intensity centroid (Rosin 1999, as in ORB): the angle of the vector
//! from the keypoint to the centroid of the intensities over a circular patch of radius
//! [`HALF_PATCH_SIZE`]. The patch is a disk so the measure does not depend on the rotation.

use super::HALF_PATCH_SIZE;
use crate::image::GrayImage;

/// Half-widths of the circular patch: row `v` (|v| <= r) spans columns `-umax[|v|]..=umax[|v|]`.
/// The disk is `u^2 + v^2 <= r^2 + r` (the pixels whose centre is nearer than r + 1/2), which is
/// symmetric under swapping u and v, so a 90 degree rotation maps the patch onto itself.
#[derive(Clone, Debug)]
pub struct CirclePatch {
    /// Radius r.
    pub radius: usize,
    /// Half-width per row offset, `umax[v]` for v in 0..=r.
    pub umax: Vec<usize>,
}

impl CirclePatch {
    /// The patch of radius `radius`.
    pub fn new(radius: usize) -> Self {
        let r2 = (radius * radius + radius) as i64;
        let umax = (0..=radius as i64)
            .map(|v| {
                let mut u = 0i64;
                while (u + 1) * (u + 1) + v * v <= r2 {
                    u += 1;
                }
                u as usize
            })
            .collect();
        CirclePatch { radius, umax }
    }
}

impl Default for CirclePatch {
    /// The ORB patch, radius [`HALF_PATCH_SIZE`] (15).
    fn default() -> Self {
        Self::new(HALF_PATCH_SIZE)
    }
}

/// Orientation in degrees in [0, 360) of the patch centred on pixel (x, y) of `img`, measured
/// in image coordinates (x right, y down). The caller keeps the patch inside the image.
pub fn ic_angle(img: &GrayImage, patch: &CirclePatch, x: usize, y: usize) -> f32 {
    let (m10, m01) = if patch.radius == HALF_PATCH_SIZE {
        moments_orb(img, patch, x, y)
    } else {
        moments(img, patch, x, y)
    };
    let mut a = (m01 as f32).atan2(m10 as f32).to_degrees();
    if a < 0.0 {
        a += 360.0;
    }
    if a >= 360.0 {
        a -= 360.0;
    }
    a
}

/// First moments `(m10, m01)` of the disk patch about its centre, any radius.
fn moments(img: &GrayImage, patch: &CirclePatch, x: usize, y: usize) -> (i64, i64) {
    let w = img.width;
    let r = patch.radius;
    debug_assert!(r <= x && r <= y);
    let mut m10: i64 = 0;
    let mut m01: i64 = 0;
    for (dv, &um) in patch.umax.iter().enumerate() {
        let rows: &[i64] = if dv == 0 { &[0] } else { &[-1, 1] };
        for &sign in rows {
            let v = sign * dv as i64;
            let row_start = (y as i64 + v) as usize * w;
            let seg = &img.data[row_start + x - um..=row_start + x + um];
            let mut sum: i32 = 0;
            let mut weighted: i32 = 0;
            for (i, &p) in seg.iter().enumerate() {
                sum += p as i32;
                weighted += (i as i32 - um as i32) * p as i32;
            }
            m10 += weighted as i64;
            m01 += v * sum as i64;
        }
    }
    (m10, m01)
}

/// Row width of [`moments_orb`]: the 31 pixels of a radius-15 patch row plus one zero.
const ORB_ROW: usize = 2 * HALF_PATCH_SIZE + 2;

/// [`moments`] for the ORB radius (15), vectorized: every row of the patch is read as the
/// same 31 pixels, masked to the disk and summed with the weights `u` in fixed-size arrays
/// (integer sums, so the moments are exactly those of [`moments`]).
#[inline]
fn moments_orb(img: &GrayImage, patch: &CirclePatch, x: usize, y: usize) -> (i64, i64) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: `moments_orb_avx2` only enables AVX2 code generation for safe code; the CPU
        // supports AVX2, checked on the line above.
        return unsafe { moments_orb_avx2(img, patch, x, y) };
    }
    moments_orb_impl(img, patch, x, y)
}

/// [`moments_orb_impl`] compiled with AVX2 enabled (integer arithmetic: bit-identical to the
/// baseline build). Call only on a CPU that has AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn moments_orb_avx2(img: &GrayImage, patch: &CirclePatch, x: usize, y: usize) -> (i64, i64) {
    moments_orb_impl(img, patch, x, y)
}

/// The body of [`moments_orb`].
#[inline(always)]
fn moments_orb_impl(img: &GrayImage, patch: &CirclePatch, x: usize, y: usize) -> (i64, i64) {
    const R: usize = HALF_PATCH_SIZE;
    let w = img.width;
    let mut weights = [0i16; ORB_ROW];
    for (k, u) in weights.iter_mut().enumerate() {
        *u = k as i16 - R as i16;
    }
    let mut m10: i64 = 0;
    let mut m01: i64 = 0;
    for yy in y - R..=y + R {
        let v = yy as i64 - y as i64;
        let um = patch.umax[v.unsigned_abs() as usize] as i16;
        let mut row = [0u8; ORB_ROW];
        row[..2 * R + 1].copy_from_slice(&img.data[yy * w + x - R..=yy * w + x + R]);
        let mut sum = 0i32;
        let mut weighted = 0i32;
        for k in 0..ORB_ROW {
            let p = if weights[k].abs() <= um {
                row[k] as i16
            } else {
                0
            };
            sum += p as i32;
            weighted += p as i32 * weights[k] as i32;
        }
        m10 += weighted as i64;
        m01 += v * sum as i64;
    }
    (m10, m01)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patch_is_symmetric_disk() {
        let p = CirclePatch::new(15);
        assert_eq!(p.umax[0], 15);
        assert_eq!(p.umax[15], p.umax.iter().filter(|&&u| u == 15).count() - 1);
        // Symmetry under swapping u and v: the column extent equals the row extent.
        for v in 0..=15 {
            for u in 0..=15 {
                assert_eq!(u <= p.umax[v], v <= p.umax[u], "({u},{v})");
            }
        }
    }

    #[test]
    fn vectorized_moments_equal_plain_ones() {
        let img = crate::feature::fast::tests::random_image(70, 50, 8);
        let p = CirclePatch::default();
        for (x, y) in [(15, 15), (54, 34), (30, 20), (40, 25)] {
            assert_eq!(
                moments_orb(&img, &p, x, y),
                moments(&img, &p, x, y),
                "({x}, {y})"
            );
            assert_eq!(moments_orb_impl(&img, &p, x, y), moments(&img, &p, x, y));
        }
    }

    #[test]
    fn angle_points_to_the_bright_side() {
        // A bright half-plane in direction theta from the centre: the centroid lies that way.
        for deg in [0.0f32, 45.0, 100.0, 200.0, 300.0] {
            let (s, c) = deg.to_radians().sin_cos();
            let mut img = GrayImage::new(41, 41);
            for y in 0..41 {
                for x in 0..41 {
                    let d = (x as f32 - 20.0) * c + (y as f32 - 20.0) * s;
                    img.data[y * 41 + x] = if d > 0.0 { 200 } else { 20 };
                }
            }
            let a = ic_angle(&img, &CirclePatch::default(), 20, 20);
            let diff = (a - deg + 540.0).rem_euclid(360.0) - 180.0;
            assert!(diff.abs() < 2.0, "{deg} -> {a}");
        }
    }
}
