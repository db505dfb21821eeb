//! Stereo rectification after Bouguet (the method of OpenCV's `stereoRectify`): each camera is
//! rotated by half of the relative rotation, then both by the rotation that brings the baseline
//! onto the x axis; the two share new pinhole intrinsics chosen so that the rectified images
//! hold only valid pixels (OpenCV's `alpha = 0`), with equal principal points (zero disparity at
//! infinity). Remap maps (rectified pixel -> raw pixel, bilinear) are computed once per sequence.
//!
//! Conventions: `X_right = R * X_left + T` (raw camera frames); rectified frames are
//! `X_rect_k = R_k * X_k`. After rectification a point at depth Z lies at the same row in both
//! images and `u_left - u_right = fx * baseline / Z`.

use crate::DatasetError;
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector2, Vector3};
use slam_core::camera::distort_normalized;
use slam_core::{Camera, Distortion, GrayImage, SensorKind};

/// Fixed-point undistortion steps used when choosing the rectified intrinsics: OpenCV's
/// `undistortPoints` default (5), not converged at EuRoC's image corners, but it is what
/// ORB-SLAM2's EuRoC.yaml was computed with; with it we reproduce that file's rectified camera
/// (fx 435.2047, cx 367.4517, cy 252.2009, bf 47.9064) to 1e-4 px. Converged undistortion would
/// give fx 435.215. The remap maps themselves are exact (they only distort, never undistort).
pub const OPENCV_UNDISTORT_ITERS: usize = 5;

/// A raw (unrectified) camera as its calibration file describes it.
#[derive(Clone, Debug, PartialEq)]
pub struct RawCamera {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Focal length x, pixels.
    pub fx: f64,
    /// Focal length y, pixels.
    pub fy: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// Radial-tangential distortion (k3 = 0 for EuRoC's four coefficients).
    pub distortion: Distortion,
    /// T_body_sensor: pose of this camera in the body (IMU) frame.
    pub t_bs: Isometry3<f64>,
    /// Frame rate, Hz.
    pub rate_hz: f64,
}

impl RawCamera {
    /// Raw pixel of a point in normalised coordinates of this camera (applies distortion).
    pub fn distort_project(&self, x: f64, y: f64) -> (f64, f64) {
        let (xd, yd) = distort_normalized(&self.distortion, x, y);
        (self.fx * xd + self.cx, self.fy * yd + self.cy)
    }

    /// Normalised undistorted coordinates of a raw pixel (fixed-point iteration as OpenCV's
    /// `undistortPoints`, run to convergence instead of its default 5 steps).
    pub fn undistort_normalize(&self, u: f64, v: f64) -> (f64, f64) {
        self.undistort_normalize_iters(u, v, 100)
    }

    /// [`RawCamera::undistort_normalize`] with at most `iters` fixed-point steps.
    pub fn undistort_normalize_iters(&self, u: f64, v: f64, iters: usize) -> (f64, f64) {
        let xd = (u - self.cx) / self.fx;
        let yd = (v - self.cy) / self.fy;
        let d = &self.distortion;
        let (mut x, mut y) = (xd, yd);
        for _ in 0..iters {
            let r2 = x * x + y * y;
            let radial = 1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
            let dx = 2.0 * d.p1 * x * y + d.p2 * (r2 + 2.0 * x * x);
            let dy = d.p1 * (r2 + 2.0 * y * y) + 2.0 * d.p2 * x * y;
            let (nx, ny) = ((xd - dx) / radial, (yd - dy) / radial);
            let done = (nx - x).abs() < 1e-14 && (ny - y).abs() < 1e-14;
            (x, y) = (nx, ny);
            if done {
                break;
            }
        }
        (x, y)
    }
}

/// Rectified-pixel -> raw-pixel lookup table of one camera, for bilinear resampling.
#[derive(Clone, Debug)]
pub struct RemapMap {
    width: usize,
    height: usize,
    /// Raw x of each rectified pixel, row-major.
    map_x: Vec<f32>,
    /// Raw y of each rectified pixel, row-major.
    map_y: Vec<f32>,
    /// Each rectified pixel's bilinear taps, worked out once: a sequence rectifies every frame
    /// with the same map, and deriving the taps per frame (floor, bounds, weights) cost more
    /// than the interpolation itself.
    taps: Taps,
}

/// The bilinear taps of every rectified pixel into a raw image of the map's size framed by a
/// one-pixel black border (so taps that leave the image by a pixel read black without a
/// bounds check, as [`RemapMap::remap`]'s checked path reads them): the framed index of the
/// top-left tap and the weights of the right and lower taps, exactly as the checked path
/// derives them. A pixel that maps wholly outside reads the black corner with zero weights.
#[derive(Clone, Debug)]
struct Taps {
    /// Framed index of each pixel's top-left tap.
    index: Vec<u32>,
    /// Weight of the right-hand taps.
    ax: Vec<f32>,
    /// Weight of the lower taps.
    ay: Vec<f32>,
    /// The largest of `index`: the gathers' reach.
    last: usize,
}

impl RemapMap {
    /// The map of rectified pixels to raw pixels `map_x`, `map_y` (row-major, `width` x
    /// `height`, raw images of the same size), with its taps worked out.
    fn new(width: usize, height: usize, map_x: Vec<f32>, map_y: Vec<f32>) -> RemapMap {
        let taps = {
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: `Taps::of_avx2` only enables AVX2 code generation for safe code
                // (floor inlined as one instruction); the CPU has AVX2 (checked above).
                unsafe { Taps::of_avx2(width, height, &map_x, &map_y) }
            } else {
                Taps::of(width, height, &map_x, &map_y)
            }
            #[cfg(not(target_arch = "x86_64"))]
            Taps::of(width, height, &map_x, &map_y)
        };
        RemapMap {
            width,
            height,
            map_x,
            map_y,
            taps,
        }
    }

    /// Raw pixel sampled for rectified pixel (x, y).
    pub fn lookup(&self, x: usize, y: usize) -> (f32, f32) {
        let i = y * self.width + x;
        (self.map_x[i], self.map_y[i])
    }

    /// Resamples `src` (the raw image) into the rectified image with bilinear interpolation;
    /// pixels that map outside `src` are black (none with the default `alpha = 0` intrinsics,
    /// except sub-pixel slivers at the border).
    pub fn remap(&self, src: &GrayImage) -> GrayImage {
        let (w, h) = (self.width, self.height);
        let fits = src.width == w && src.height == h && src.data.len() == w * h;
        // Framed indices must fit the taps' u32.
        if !fits || (w + 2) * (h + 2) > u32::MAX as usize {
            return self.remap_checked(src);
        }
        let (fw, framed) = (w + 2, framed(src));
        let mut out = GrayImage::new(w, h);
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: `resample_avx2` only enables AVX2 code generation for safe code; the CPU
            // has AVX2 (checked above).
            unsafe { resample_avx2(&self.taps, &framed, fw, &mut out.data) };
            return out;
        }
        let t = &self.taps;
        resample((&t.index, &t.ax, &t.ay), &framed, fw, &mut out.data);
        out
    }

    /// [`RemapMap::remap`] of a raw image of any size, every tap's bounds checked (the
    /// reference the precomputed taps reproduce bit for bit).
    fn remap_checked(&self, src: &GrayImage) -> GrayImage {
        let mut out = GrayImage::new(self.width, self.height);
        let (sw, sh) = (src.width as i64, src.height as i64);
        for (o, (&mx, &my)) in out
            .data
            .iter_mut()
            .zip(self.map_x.iter().zip(self.map_y.iter()))
        {
            if let Some(origin) = bilinear_origin(mx, my, sw, sh) {
                *o = resample_checked(src, origin);
            }
        }
        out
    }
}

impl Taps {
    /// The taps of the map `map_x`, `map_y` of a `width` x `height` raw image.
    #[inline(always)]
    fn of(width: usize, height: usize, map_x: &[f32], map_y: &[f32]) -> Taps {
        let (sw, sh) = (width as i64, height as i64);
        let n = map_x.len();
        let mut taps = Taps {
            index: Vec::with_capacity(n),
            ax: Vec::with_capacity(n),
            ay: Vec::with_capacity(n),
            last: 0,
        };
        for (&mx, &my) in map_x.iter().zip(map_y) {
            let (index, ax, ay) = match bilinear_origin(mx, my, sw, sh) {
                None => (0, 0.0, 0.0),
                Some((x0, y0, ax, ay)) => {
                    // The framed image is (width + 2) wide, raw (0, 0) at framed (1, 1).
                    let framed = (y0 + 1) * (sw + 2) + (x0 + 1);
                    (framed as u32, ax, ay)
                }
            };
            taps.last = taps.last.max(index as usize);
            taps.index.push(index);
            taps.ax.push(ax);
            taps.ay.push(ay);
        }
        taps
    }

    /// [`Taps::of`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn of_avx2(width: usize, height: usize, map_x: &[f32], map_y: &[f32]) -> Taps {
        Taps::of(width, height, map_x, map_y)
    }
}

/// `src` framed by one black pixel on every side ((width + 2) x (height + 2), raw (0, 0) at
/// (1, 1)), with [`FRAME_SLACK`] bytes after it: the image the taps index (the AVX2 path reads
/// each tap pair as 4 bytes).
fn framed(src: &GrayImage) -> Vec<u8> {
    let (w, h, fw) = (src.width, src.height, src.width + 2);
    let mut framed = vec![0u8; fw * (h + 2) + FRAME_SLACK];
    for (row, raw) in framed[fw..]
        .chunks_exact_mut(fw)
        .zip(src.data.chunks_exact(w))
    {
        row[1..=w].copy_from_slice(raw);
    }
    framed
}

/// Resamples the framed raw image (`fw` wide) at every pixel's taps into `out`.
#[inline(always)]
fn resample((index, ax, ay): (&[u32], &[f32], &[f32]), framed: &[u8], fw: usize, out: &mut [u8]) {
    for (((o, &k), &ax), &ay) in out.iter_mut().zip(index).zip(ax).zip(ay) {
        let k = k as usize;
        let top = framed[k] as f32 * (1.0 - ax) + framed[k + 1] as f32 * ax;
        let bottom = framed[k + fw] as f32 * (1.0 - ax) + framed[k + fw + 1] as f32 * ax;
        *o = grey_of(top * (1.0 - ay) + bottom * ay);
    }
}

/// Bytes the framed image carries past its last row, so that a 4-byte load at any tap pair
/// stays inside it.
const FRAME_SLACK: usize = 3;

/// [`resample`] eight pixels at a time with AVX2: each row's tap pair read as one gathered
/// 4-byte word, then the same single-precision products and sums in the same order (no fused
/// multiply-add), so the same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn resample_avx2(t: &Taps, framed: &[u8], fw: usize, out: &mut [u8]) {
    use std::arch::x86_64::*;
    let n = out.len();
    let last = t.last;
    assert!(
        t.index.len() == n && t.ax.len() == n && t.ay.len() == n,
        "one tap per pixel"
    );
    assert!(
        last + fw + 4 <= framed.len(),
        "every gather inside the frame"
    );
    assert!(i32::try_from(last + fw).is_ok(), "gather offsets fit i32");
    let lanes = n / 8 * 8;
    // SAFETY: every load and store below reads or writes 8 elements at i < lanes <= n of
    // slices with n elements (checked above); the gathers read 4 bytes at framed[k] and
    // framed[k + fw] for indices k <= last, inside `framed` by the check above.
    unsafe {
        let (one, half, zero, top_grey) = (
            _mm256_set1_ps(1.0),
            _mm256_set1_ps(0.5),
            _mm256_setzero_ps(),
            _mm256_set1_ps(255.0),
        );
        let byte = _mm256_set1_epi32(0xff);
        let row = _mm256_set1_epi32(fw as i32);
        let base = framed.as_ptr() as *const i32;
        for i in (0..lanes).step_by(8) {
            let k = _mm256_loadu_si256(t.index.as_ptr().add(i) as *const __m256i);
            let ax = _mm256_loadu_ps(t.ax.as_ptr().add(i));
            let ay = _mm256_loadu_ps(t.ay.as_ptr().add(i));
            let up = _mm256_i32gather_epi32::<1>(base, k);
            let down = _mm256_i32gather_epi32::<1>(base, _mm256_add_epi32(k, row));
            let grey = |w: __m256i, shift: i32| {
                let v = match shift {
                    0 => w,
                    _ => _mm256_srli_epi32::<8>(w),
                };
                _mm256_cvtepi32_ps(_mm256_and_si256(v, byte))
            };
            let bx = _mm256_sub_ps(one, ax);
            let top = _mm256_add_ps(
                _mm256_mul_ps(grey(up, 0), bx),
                _mm256_mul_ps(grey(up, 8), ax),
            );
            let bottom = _mm256_add_ps(
                _mm256_mul_ps(grey(down, 0), bx),
                _mm256_mul_ps(grey(down, 8), ax),
            );
            let v = _mm256_add_ps(
                _mm256_mul_ps(top, _mm256_sub_ps(one, ay)),
                _mm256_mul_ps(bottom, ay),
            );
            // (v + 0.5).clamp(0, 255) as u8: max with 0 first maps NaN to 0, as `as u8` does.
            let v = _mm256_min_ps(_mm256_max_ps(_mm256_add_ps(v, half), zero), top_grey);
            let q = _mm256_cvttps_epi32(v);
            let mut lane = [0i32; 8];
            _mm256_storeu_si256(lane.as_mut_ptr() as *mut __m256i, q);
            for (o, l) in out[i..i + 8].iter_mut().zip(lane) {
                *o = l as u8;
            }
        }
    }
    let tail = (&t.index[lanes..], &t.ax[lanes..], &t.ay[lanes..]);
    resample(tail, framed, fw, &mut out[lanes..]);
}

/// Where the bilinear sample at raw pixel (mx, my) of a `sw` x `sh` image starts: its top-left
/// tap (x0, y0) and the weights (ax, ay) of the right and lower taps; `None` when none of its
/// taps falls inside the image (the rectified pixel stays black). The one rule the checked
/// path and the precomputed taps share.
#[inline(always)]
fn bilinear_origin(mx: f32, my: f32, sw: i64, sh: i64) -> Option<(i64, i64, f32, f32)> {
    let (x0f, y0f) = (mx.floor(), my.floor());
    let (x0, y0) = (x0f as i64, y0f as i64);
    if x0 < -1 || y0 < -1 || x0 >= sw || y0 >= sh {
        return None;
    }
    Some((x0, y0, mx - x0f, my - y0f))
}

/// The bilinear sample of `src` from its [`bilinear_origin`], taps outside the image black.
fn resample_checked(src: &GrayImage, (x0, y0, ax, ay): (i64, i64, f32, f32)) -> u8 {
    let (sw, sh) = (src.width as i64, src.height as i64);
    let px = |x: i64, y: i64| -> f32 {
        if x < 0 || y < 0 || x >= sw || y >= sh {
            0.0
        } else {
            src.data[(y * sw + x) as usize] as f32
        }
    };
    let top = px(x0, y0) * (1.0 - ax) + px(x0 + 1, y0) * ax;
    let bottom = px(x0, y0 + 1) * (1.0 - ax) + px(x0 + 1, y0 + 1) * ax;
    grey_of(top * (1.0 - ay) + bottom * ay)
}

/// A resampled value rounded to a grey level.
#[inline]
fn grey_of(v: f32) -> u8 {
    (v + 0.5).clamp(0.0, 255.0) as u8
}

/// A rectified stereo rig: rotations, shared intrinsics, baseline and remap maps.
#[derive(Clone, Debug)]
pub struct StereoRectification {
    /// Rectifying rotation of the left camera (`X_rect = r_left * X_left_raw`).
    pub r_left: Rotation3<f64>,
    /// Rectifying rotation of the right camera.
    pub r_right: Rotation3<f64>,
    /// Shared rectified focal length (fx = fy), pixels.
    pub focal: f64,
    /// Shared rectified principal point, pixels.
    pub principal_point: Vector2<f64>,
    /// Distance between the optical centres, metres.
    pub baseline: f64,
    /// Image size (same as the raw left image).
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// T_body_rectified-left: the rectified left camera's pose in the body frame.
    pub t_b_left: Isometry3<f64>,
    left: RawCamera,
    right: RawCamera,
    map_left: RemapMap,
    map_right: RemapMap,
}

/// `X_right = R X_left + T` from the two cameras' body extrinsics.
pub fn relative_pose(left: &RawCamera, right: &RawCamera) -> Isometry3<f64> {
    right.t_bs.inverse() * left.t_bs
}

/// A stereo pair's two cameras must have one image size (`what`: the file that says so).
fn same_size(left: &RawCamera, right: &RawCamera, what: &str) -> Result<(), DatasetError> {
    if (left.width, left.height) != (right.width, right.height) {
        return Err(DatasetError::invalid(
            what,
            format!(
                "left and right cameras differ in size ({}x{} vs {}x{})",
                left.width, left.height, right.width, right.height
            ),
        ));
    }
    Ok(())
}

impl StereoRectification {
    /// Computes the rectification of a horizontal stereo pair from its two calibrations.
    /// Fails when the cameras differ in size or the baseline is degenerate.
    pub fn new(left: &RawCamera, right: &RawCamera) -> Result<Self, DatasetError> {
        same_size(left, right, "sensor.yaml")?;
        let rel = relative_pose(left, right);
        let r = rel.rotation.to_rotation_matrix();
        let t_vec = rel.translation.vector;
        let baseline = t_vec.norm();
        if !(baseline.is_finite() && baseline > 1e-6) {
            return Err(DatasetError::invalid(
                "sensor.yaml",
                format!("degenerate stereo baseline {baseline} m"),
            ));
        }
        // Half rotations: the two cameras meet in the middle.
        let om = r.scaled_axis();
        let r_r = Rotation3::from_scaled_axis(-0.5 * om);
        let t = r_r * t_vec;
        // Rotate t onto the x axis (y for vertical rigs, which we do not expect but handle).
        let idx = if t.x.abs() > t.y.abs() { 0 } else { 1 };
        let c = t[idx];
        let mut uu = Vector3::zeros();
        uu[idx] = if c > 0.0 { 1.0 } else { -1.0 };
        let mut ww = t.cross(&uu);
        let nw = ww.norm();
        if nw > 0.0 {
            ww *= (c.abs() / t.norm()).clamp(-1.0, 1.0).acos() / nw;
        }
        let w_r = Rotation3::from_scaled_axis(ww);
        let r_left = w_r * r_r.inverse();
        let r_right = w_r * r_r;

        let (nx, ny) = (left.width as f64, left.height as f64);
        // Initial focal: the smaller (radially corrected) focal across the axis of the baseline.
        let mut fc = f64::MAX;
        for cam in [left, right] {
            let mut f = if idx == 0 { cam.fy } else { cam.fx };
            let k1 = cam.distortion.k1;
            if k1 < 0.0 {
                f *= 1.0 + k1 * (nx * nx + ny * ny) / (4.0 * f * f);
            }
            fc = fc.min(f);
        }
        // Principal points: centre the rectified image corners, then share them.
        let mut cc = [Vector2::zeros(); 2];
        for (k, (cam, rot)) in [(left, &r_left), (right, &r_right)].into_iter().enumerate() {
            let mut avg = Vector2::zeros();
            for (u, v) in [
                (0.0, 0.0),
                (nx - 1.0, 0.0),
                (0.0, ny - 1.0),
                (nx - 1.0, ny - 1.0),
            ] {
                avg += project_rotated(
                    cam,
                    rot,
                    (u, v),
                    fc,
                    &Vector2::zeros(),
                    OPENCV_UNDISTORT_ITERS,
                );
            }
            avg /= 4.0;
            cc[k] = Vector2::new((nx - 1.0) / 2.0, (ny - 1.0) / 2.0) - avg;
        }
        let c = (cc[0] + cc[1]) / 2.0;
        // alpha = 0: scale the focal so the inner (all-valid) rectangle fills the image
        // (OpenCV's formula, including its `width - cx` rather than `width - 1 - cx`).
        let mut s = 0.0f64;
        for (cam, rot) in [(left, &r_left), (right, &r_right)] {
            let inner = inner_rectangle(cam, rot, fc, &c);
            s = s
                .max(c.x / (c.x - inner[0]))
                .max(c.y / (c.y - inner[1]))
                .max((nx - c.x) / (inner[2] - c.x))
                .max((ny - c.y) / (inner[3] - c.y));
        }
        if !(s.is_finite() && s > 0.0) {
            return Err(DatasetError::invalid(
                "sensor.yaml",
                "rectification failed: the cameras' views do not overlap",
            ));
        }
        let focal = fc * s;
        StereoRectification::from_parts(left, right, r_left, r_right, focal, c, baseline)
    }

    /// A rectification given rather than computed: the rotations, shared intrinsics and
    /// baseline a settings file carries (ORB-SLAM2's `LEFT.R` / `LEFT.P`...), as ORB-SLAM2's
    /// stereo examples take them. `left.t_bs` places the raw left camera in the body frame
    /// (identity when unknown). Fails when the two cameras differ in size.
    #[allow(clippy::too_many_arguments)]
    pub fn from_parts(
        left: &RawCamera,
        right: &RawCamera,
        r_left: Rotation3<f64>,
        r_right: Rotation3<f64>,
        focal: f64,
        principal_point: Vector2<f64>,
        baseline: f64,
    ) -> Result<Self, DatasetError> {
        same_size(left, right, "settings")?;
        let t_b_left = left.t_bs
            * Isometry3::from_parts(
                Translation3::identity(),
                UnitQuaternion::from_rotation_matrix(&r_left.inverse()),
            );
        let empty = || RemapMap::new(0, 0, vec![], vec![]);
        let mut rect = StereoRectification {
            r_left,
            r_right,
            focal,
            principal_point,
            baseline,
            width: left.width,
            height: left.height,
            t_b_left,
            left: left.clone(),
            right: right.clone(),
            map_left: empty(),
            map_right: empty(),
        };
        rect.map_left = rect.build_map(false);
        rect.map_right = rect.build_map(true);
        Ok(rect)
    }

    /// The raw left camera the rectification was made for.
    pub fn left_raw(&self) -> &RawCamera {
        &self.left
    }

    /// The raw right camera the rectification was made for.
    pub fn right_raw(&self) -> &RawCamera {
        &self.right
    }

    fn build_map(&self, right: bool) -> RemapMap {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut map_x = Vec::with_capacity(w * h);
        let mut map_y = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let (u, v) = self.raw_of_rectified(right, x as f64, y as f64);
                map_x.push(u as f32);
                map_y.push(v as f32);
            }
        }
        RemapMap::new(w, h, map_x, map_y)
    }

    /// Raw pixel of the camera (left or `right`) seen at rectified pixel (u, v).
    pub fn raw_of_rectified(&self, right: bool, u: f64, v: f64) -> (f64, f64) {
        let (cam, rot) = if right {
            (&self.right, &self.r_right)
        } else {
            (&self.left, &self.r_left)
        };
        let ray = Vector3::new(
            (u - self.principal_point.x) / self.focal,
            (v - self.principal_point.y) / self.focal,
            1.0,
        );
        let p = rot.inverse() * ray;
        cam.distort_project(p.x / p.z, p.y / p.z)
    }

    /// Rectified pixel of a raw pixel of the camera (left or `right`).
    pub fn rectify_point(&self, right: bool, u: f64, v: f64) -> (f64, f64) {
        let (cam, rot) = if right {
            (&self.right, &self.r_right)
        } else {
            (&self.left, &self.r_left)
        };
        let p = project_rotated(cam, rot, (u, v), self.focal, &self.principal_point, 100);
        (p.x, p.y)
    }

    /// Rectifies a raw left image.
    pub fn rectify_left(&self, raw: &GrayImage) -> GrayImage {
        self.map_left.remap(raw)
    }

    /// Rectifies a raw right image.
    pub fn rectify_right(&self, raw: &GrayImage) -> GrayImage {
        self.map_right.remap(raw)
    }

    /// The left map (rectified pixel -> raw pixel).
    pub fn map_left(&self) -> &RemapMap {
        &self.map_left
    }

    /// The rectified camera slam-core sees: shared intrinsics, no distortion, `bf = focal *
    /// baseline`, stereo sensor, fps from the calibration, `th_depth` as given.
    pub fn camera(&self, th_depth: f64) -> Camera {
        Camera {
            fx: self.focal,
            fy: self.focal,
            cx: self.principal_point.x,
            cy: self.principal_point.y,
            width: self.width,
            height: self.height,
            distortion: None,
            bf: self.focal * self.baseline,
            th_depth,
            fps: self.left.rate_hz,
            sensor: SensorKind::Stereo,
        }
    }
}

/// Raw pixel (u, v) -> undistorted ray (`iters` fixed-point steps) -> rotated by `rot` ->
/// pinhole with focal `f` and principal point `c`.
fn project_rotated(
    cam: &RawCamera,
    rot: &Rotation3<f64>,
    (u, v): (f64, f64),
    f: f64,
    c: &Vector2<f64>,
    iters: usize,
) -> Vector2<f64> {
    let (x, y) = cam.undistort_normalize_iters(u, v, iters);
    let p = rot * Vector3::new(x, y, 1.0);
    Vector2::new(f * p.x / p.z + c.x, f * p.y / p.z + c.y)
}

/// OpenCV's inner rectangle (x0, y0, x1, y1) of a camera's valid rectified region, from a 9x9
/// grid of raw pixels spanning the image: the largest extent of the left column, smallest of the
/// right column, and likewise for rows.
fn inner_rectangle(cam: &RawCamera, rot: &Rotation3<f64>, f: f64, c: &Vector2<f64>) -> [f64; 4] {
    const N: usize = 9;
    let (w, h) = (cam.width as f64, cam.height as f64);
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MIN, f64::MIN, f64::MAX, f64::MAX);
    for j in 0..N {
        for i in 0..N {
            let u = i as f64 * w / (N - 1) as f64;
            let v = j as f64 * h / (N - 1) as f64;
            let p = project_rotated(cam, rot, (u, v), f, c, OPENCV_UNDISTORT_ITERS);
            if i == 0 {
                x0 = x0.max(p.x);
            }
            if i == N - 1 {
                x1 = x1.min(p.x);
            }
            if j == 0 {
                y0 = y0.max(p.y);
            }
            if j == N - 1 {
                y1 = y1.min(p.y);
            }
        }
    }
    [x0, y0, x1, y1]
}

/// The rotation nearest to `m` (nalgebra's `from_matrix`, whose result it gives bit for bit),
/// or `None` when `m` is far from any rotation (`|m^T m - I| > 0.5`, or not finite). The check
/// comes first because `from_matrix` never returns for some such matrices: with an entry of
/// 7e61 (a fuzzed `sensor.yaml`) its search cannot see a rotation's entries beside it and
/// loops forever.
pub(crate) fn near_rotation(m: &Matrix3<f64>) -> Option<Rotation3<f64>> {
    let err = (m.transpose() * m - Matrix3::identity()).abs().max();
    if err.is_nan() || err > 0.5 {
        return None;
    }
    Some(Rotation3::from_matrix_eps(
        m,
        f64::EPSILON,
        1000,
        Rotation3::identity(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rig(rot_left: Vector3<f64>, rot_right: Vector3<f64>) -> (RawCamera, RawCamera) {
        let d = Distortion {
            k1: -0.25,
            k2: 0.07,
            p1: 0.0003,
            p2: -0.0002,
            k3: 0.0,
        };
        let left = RawCamera {
            width: 640,
            height: 480,
            fx: 460.0,
            fy: 458.0,
            cx: 322.0,
            cy: 243.0,
            distortion: d,
            t_bs: Isometry3::new(Vector3::new(0.01, -0.05, 0.02), rot_left),
            rate_hz: 20.0,
        };
        let right = RawCamera {
            fx: 455.0,
            fy: 454.0,
            cx: 318.0,
            cy: 250.0,
            distortion: Distortion { k1: -0.27, ..d },
            t_bs: left.t_bs
                * Isometry3::new(Vector3::new(0.12, 0.003, -0.002), rot_right - rot_left),
            ..left.clone()
        };
        (left, right)
    }

    #[test]
    fn rectified_rows_agree_and_baseline_is_kept() {
        let (l, r) = rig(
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(0.01, -0.02, 0.015),
        );
        let rect = StereoRectification::new(&l, &r).unwrap();
        assert!((rect.baseline - Vector3::<f64>::new(0.12, 0.003, -0.002).norm()).abs() < 1e-12);
        let rel = relative_pose(&l, &r);
        // Points in front of the rig: project raw (distorted), rectify, compare rows.
        for (x, y, z) in [
            (0.3, 0.2, 2.0),
            (-0.8, -0.5, 3.0),
            (0.0, 0.0, 1.5),
            (1.0, -0.6, 4.0),
        ] {
            let pl = Vector3::new(x, y, z);
            let pr = rel * nalgebra::Point3::from(pl);
            let (ul, vl) = l.distort_project(pl.x / pl.z, pl.y / pl.z);
            let (ur, vr) = r.distort_project(pr.x / pr.z, pr.y / pr.z);
            let (a, b) = (
                rect.rectify_point(false, ul, vl),
                rect.rectify_point(true, ur, vr),
            );
            assert!((a.1 - b.1).abs() < 1e-6, "rows {} vs {}", a.1, b.1);
            // Disparity = f * B / Z_rect.
            let z_rect = (rect.r_left * pl).z;
            let disp = a.0 - b.0;
            assert!((disp - rect.focal * rect.baseline / z_rect).abs() < 1e-6);
        }
    }

    #[test]
    fn maps_invert_point_rectification() {
        let (l, r) = rig(Vector3::new(0.0, 0.01, 0.0), Vector3::new(0.0, -0.01, 0.01));
        let rect = StereoRectification::new(&l, &r).unwrap();
        for (u, v) in [(10.0, 20.0), (320.0, 240.0), (600.0, 400.0)] {
            let (ru, rv) = rect.raw_of_rectified(true, u, v);
            let (bu, bv) = rect.rectify_point(true, ru, rv);
            assert!((bu - u).abs() < 1e-6 && (bv - v).abs() < 1e-6);
        }
        // alpha = 0: every rectified pixel samples inside the raw image.
        let m = rect.map_left();
        for (x, y) in [(0, 0), (639, 0), (0, 479), (639, 479), (320, 0), (0, 240)] {
            let (mx, my) = m.lookup(x, y);
            assert!(
                mx > -0.5 && my > -0.5 && mx < 640.0 && my < 480.0,
                "{mx},{my}"
            );
        }
    }

    #[test]
    fn identity_rig_is_identity() {
        let mut l = rig(Vector3::zeros(), Vector3::zeros()).0;
        l.distortion = Distortion {
            k1: 0.0,
            k2: 0.0,
            p1: 0.0,
            p2: 0.0,
            k3: 0.0,
        };
        l.fx = l.fy;
        let mut r = l.clone();
        r.t_bs = l.t_bs * Isometry3::translation(0.1, 0.0, 0.0);
        let rect = StereoRectification::new(&l, &r).unwrap();
        assert!((rect.focal - l.fy).abs() < 1e-9, "{}", rect.focal);
        let img = GrayImage {
            width: 640,
            height: 480,
            data: (0..640 * 480).map(|i| (i * 7 % 251) as u8).collect(),
        };
        assert_eq!(rect.rectify_left(&img).data, img.data);
    }
    #[test]
    fn precomputed_taps_resample_bit_for_bit_as_the_checked_path() {
        // Raw pixels everywhere a rectified pixel may sample: inside, on every border (taps
        // half outside), wholly outside, at exact integers and fractions, and NaN.
        let (w, h) = (37usize, 23usize);
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut map_x = Vec::new();
        let mut map_y = Vec::new();
        for i in 0..w * h {
            let r = next();
            // A coordinate along an axis of `n` pixels.
            let pick = |k: u64, n: usize| -> f32 {
                let n = n as u64;
                match k % 8 {
                    0 => (k % (n + 4)) as f32 - 2.0,
                    1 => -1.5 + (k % 1000) as f32 / 1000.0,
                    2 => n as f32 - 1.5 + (k % 1000) as f32 / 500.0,
                    _ => ((k >> 8) % (100 * n)) as f32 / 100.0,
                }
            };
            let (x, y) = if i == 5 {
                (f32::NAN, 3.0)
            } else {
                (pick(r, w), pick(r >> 20, h))
            };
            map_x.push(x);
            map_y.push(y);
        }
        let map = RemapMap::new(w, h, map_x.clone(), map_y.clone());
        let (mut outside, mut border) = (0, 0);
        for (&x, &y) in map_x.iter().zip(&map_y) {
            let (x0, y0) = (x.floor() as i64, y.floor() as i64);
            if x0 < -1 || y0 < -1 || x0 >= w as i64 || y0 >= h as i64 {
                outside += 1;
            } else if x0 < 0 || y0 < 0 || x0 + 1 >= w as i64 || y0 + 1 >= h as i64 {
                border += 1;
            }
        }
        let inside = w * h - outside - border;
        assert!(
            outside > 20 && border > 20 && inside > w * h / 4,
            "every kind drawn"
        );
        let img = GrayImage {
            width: w,
            height: h,
            data: (0..w * h).map(|_| next() as u8).collect(),
        };
        let fast = map.remap(&img);
        let checked = map.remap_checked(&img).data;
        assert_eq!(fast.data, checked);
        // The portable path too (what a CPU without AVX2 runs).
        let mut portable = vec![0u8; w * h];
        let t = &map.taps;
        resample(
            (&t.index, &t.ax, &t.ay),
            &framed(&img),
            w + 2,
            &mut portable,
        );
        assert_eq!(portable, checked);
        assert!(fast.data.iter().filter(|&&v| v != 0).count() > inside / 2);
        // A raw image of another size than the map's takes the checked path.
        let small = GrayImage {
            width: w - 3,
            height: h - 2,
            data: img.data[..(w - 3) * (h - 2)].to_vec(),
        };
        assert_eq!(map.remap(&small).data, map.remap_checked(&small).data);
    }
}
