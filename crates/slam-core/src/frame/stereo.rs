//! Stereo matching of a rectified pair (ORB-SLAM2's `ComputeStereoMatches`): every left
//! keypoint looks for the right keypoint of closest descriptor on the same row band and a
//! neighbouring octave, then the match is refined by SAD correlation of an 11 x 11 window on the
//! keypoint's pyramid level and a parabola through the three SAD values around the minimum,
//! which gives the disparity to a fraction of a pixel. Matches at the edge of the search range,
//! with an implausible parabola, outside the valid disparity range or whose SAD is far above
//! the median are rejected.
//!
//! Deliberate differences from ORB-SLAM2, both for sub-pixel accuracy (measured on a synthetic
//! pair: within 0.2 px for 42 % of the matches with ORB-SLAM2's choices, 95 % with ours):
//! - the windows are compared after removing their mean intensity, not their centre pixel
//!   (one noisy pixel no longer shifts the whole window);
//! - the integer minimum and the outlier test use SAD as ORB-SLAM2, but the parabola is fitted
//!   to the sum of squared differences, which is quadratic near its minimum, so the fitted
//!   vertex is not pulled towards whole pixels as the V-shaped SAD curve pulls it.

use crate::feature::{hamming, Descriptor, KeyPoint, Pyramid, ScaleInfo, TH_HIGH, TH_LOW};
use crate::image::GrayImage;

/// Parameters of the stereo matcher; defaults are ORB-SLAM2's.
#[derive(Clone, Debug, PartialEq)]
pub struct StereoParams {
    /// Largest descriptor distance of a candidate match, strictly below (default
    /// (TH_HIGH + TH_LOW) / 2 = 75).
    pub max_descriptor_distance: u32,
    /// Half-size of the SAD window in level pixels (default 5: an 11 x 11 window).
    pub sad_half_window: usize,
    /// Half-range of the SAD search around the descriptor match, level pixels (default 5).
    pub sad_search: usize,
    /// Half-height of the row band searched, in units of the right keypoint's scale factor
    /// (default 2: rows within 2 * 1.2^octave px).
    pub row_band: f64,
    /// A match is dropped when its SAD exceeds this factor times the median SAD
    /// (default 1.5 * 1.4 = 2.1).
    pub sad_median_factor: f64,
}

impl Default for StereoParams {
    fn default() -> Self {
        StereoParams {
            max_descriptor_distance: (TH_HIGH + TH_LOW) / 2,
            sad_half_window: 5,
            sad_search: 5,
            row_band: 2.0,
            sad_median_factor: 1.5 * 1.4,
        }
    }
}

/// Level-0 <-> level coordinate maps of one pyramid level (pixel-centre convention, see
/// `feature::extractor`).
#[derive(Clone, Copy, Debug)]
struct LevelMap {
    sx: f64,
    sy: f64,
}

impl LevelMap {
    fn new(base: &GrayImage, level: &GrayImage) -> Self {
        LevelMap {
            sx: base.width as f64 / level.width as f64,
            sy: base.height as f64 / level.height as f64,
        }
    }
    fn to_level_x(self, x: f64) -> f64 {
        (x + 0.5) / self.sx - 0.5
    }
    fn to_level_y(self, y: f64) -> f64 {
        (y + 0.5) / self.sy - 0.5
    }
    fn to_base_x(self, x: f64) -> f64 {
        (x + 0.5) * self.sx - 0.5
    }
}

/// Everything the matcher reads: both keypoint sets, descriptors and pyramids.
pub struct StereoInput<'a> {
    /// Left keypoints (rectified image coordinates, level 0).
    pub left: &'a [KeyPoint],
    /// Left descriptors.
    pub left_desc: &'a [Descriptor],
    /// Right keypoints.
    pub right: &'a [KeyPoint],
    /// Right descriptors.
    pub right_desc: &'a [Descriptor],
    /// Left pyramid (unblurred levels).
    pub left_pyr: &'a Pyramid,
    /// Right pyramid.
    pub right_pyr: &'a Pyramid,
    /// Scale tables of both pyramids.
    pub scale: &'a ScaleInfo,
}

/// Computes, per left keypoint, the right coordinate `u_right` (level-0 pixels, -1 when
/// unmatched) and the depth `bf / disparity` in metres (-1 when unmatched). `bf` is the
/// baseline times fx, `fx` the focal length (the largest disparity searched is `fx`, i.e.
/// depths down to one baseline, as ORB-SLAM2).
pub fn compute_stereo_matches(
    input: &StereoInput<'_>,
    bf: f64,
    fx: f64,
    params: &StereoParams,
) -> (Vec<f32>, Vec<f32>) {
    let n = input.left.len();
    let mut u_right = vec![-1.0f32; n];
    let mut depth = vec![-1.0f32; n];
    let Some(base_r) = input.right_pyr.levels.first() else {
        return (u_right, depth);
    };
    let Some(base_l) = input.left_pyr.levels.first() else {
        return (u_right, depth);
    };
    let rows = base_r.height;
    if rows == 0 || input.right.is_empty() {
        return (u_right, depth);
    }

    // Row index of the right keypoints: keypoint j is listed on every row within its band.
    let band = |kp: &KeyPoint| {
        let r = params.row_band * input.scale.scale_factors[kp.octave];
        let lo = (kp.y as f64 - r).floor().max(0.0) as usize;
        let hi = ((kp.y as f64 + r).ceil().max(0.0) as usize).min(rows - 1);
        (lo, hi)
    };
    let mut start = vec![0u32; rows + 1];
    for kp in input.right {
        let (lo, hi) = band(kp);
        for y in lo..=hi {
            start[y + 1] += 1;
        }
    }
    for y in 0..rows {
        start[y + 1] += start[y];
    }
    let mut fill = start[..rows].to_vec();
    let mut items = vec![0u32; start[rows] as usize];
    for (j, kp) in input.right.iter().enumerate() {
        let (lo, hi) = band(kp);
        for y in lo..=hi {
            items[fill[y] as usize] = j as u32;
            fill[y] += 1;
        }
    }

    let min_d = 0.0f64;
    let max_d = fx; // bf / (baseline) = fx
    let w = params.sad_half_window as isize;
    let l = params.sad_search as isize;
    let mut sads = vec![0u32; 2 * params.sad_search + 1];
    let mut ssds = vec![0u64; 2 * params.sad_search + 1];
    let mut accepted: Vec<(u32, usize)> = Vec::new();

    for (i, kp_l) in input.left.iter().enumerate() {
        let v_l = kp_l.y as f64;
        let u_l = kp_l.x as f64;
        let row = v_l.round();
        if row < 0.0 || row as usize >= rows {
            continue;
        }
        let row = row as usize;
        let cands = &items[start[row] as usize..start[row + 1] as usize];
        if cands.is_empty() {
            continue;
        }
        let level = kp_l.octave;
        let (min_u, max_u) = (u_l - max_d, u_l - min_d);
        let mut best_dist = u32::MAX;
        let mut best_j = usize::MAX;
        for &j in cands {
            let kp_r = &input.right[j as usize];
            if kp_r.octave + 1 < level || kp_r.octave > level + 1 {
                continue;
            }
            let u_r = kp_r.x as f64;
            if u_r < min_u || u_r > max_u {
                continue;
            }
            let d = hamming(&input.left_desc[i], &input.right_desc[j as usize]);
            if d < best_dist {
                best_dist = d;
                best_j = j as usize;
            }
        }
        if best_dist >= params.max_descriptor_distance {
            continue;
        }

        // Sub-pixel refinement by SAD on the left keypoint's level.
        let (Some(img_l), Some(img_r)) = (
            input.left_pyr.levels.get(level),
            input.right_pyr.levels.get(level),
        ) else {
            continue;
        };
        let map = LevelMap::new(base_l, img_l);
        let map_r = LevelMap::new(base_r, img_r);
        let su_l = map.to_level_x(u_l).round() as isize;
        let sv_l = map.to_level_y(v_l).round() as isize;
        let su_r0 = map_r.to_level_x(input.right[best_j].x as f64).round() as isize;
        let (lw, lh) = (img_l.width as isize, img_l.height as isize);
        let rw = img_r.width as isize;
        if su_l - w < 0 || su_l + w >= lw || sv_l - w < 0 || sv_l + w >= lh {
            continue;
        }
        if su_r0 - l - w < 0 || su_r0 + l + w >= rw || sv_l + w >= img_r.height as isize {
            continue;
        }
        let mut best_sad = u32::MAX;
        let mut best_inc = 0isize;
        // Window means (the brightness offset between the two cameras is removed with them).
        let win = (2 * w + 1) as usize;
        let sum_l = window_sum(&img_l.data, lw, su_l - w, sv_l - w, win);
        for inc in -l..=l {
            let ur = su_r0 + inc;
            let sum_r = window_sum(&img_r.data, rw, ur - w, sv_l - w, win);
            // Offset rounded to whole grey levels keeps the arithmetic in integers.
            let offset = (sum_l - sum_r).div_euclid((win * win) as i32);
            let mut sad = 0u32;
            let mut ssd = 0u64;
            for dy in -w..=w {
                let rl = ((sv_l + dy) * lw + su_l - w) as usize;
                let rr = ((sv_l + dy) * rw + ur - w) as usize;
                let a = &img_l.data[rl..rl + win];
                let b = &img_r.data[rr..rr + win];
                for (&pa, &pb) in a.iter().zip(b) {
                    let e = pa as i32 - pb as i32 - offset;
                    sad += e.unsigned_abs();
                    ssd += (e * e) as u64;
                }
            }
            sads[(inc + l) as usize] = sad;
            ssds[(inc + l) as usize] = ssd;
            if sad < best_sad {
                best_sad = sad;
                best_inc = inc;
            }
        }
        if best_inc == -l || best_inc == l {
            continue;
        }
        let k = (best_inc + l) as usize;
        let (d1, d2, d3) = (ssds[k - 1] as f64, ssds[k] as f64, ssds[k + 1] as f64);
        let denom = 2.0 * (d1 + d3 - 2.0 * d2);
        if denom <= 0.0 {
            continue;
        }
        let delta = (d1 - d3) / denom;
        if !(-1.0..=1.0).contains(&delta) {
            continue;
        }
        let mut best_u_r = map_r.to_base_x((su_r0 + best_inc) as f64 + delta);
        let mut disparity = u_l - best_u_r;
        if disparity >= min_d && disparity < max_d {
            if disparity <= 0.0 {
                disparity = 0.01;
                best_u_r = u_l - 0.01;
            }
            depth[i] = (bf / disparity) as f32;
            u_right[i] = best_u_r as f32;
            accepted.push((best_sad, i));
        }
    }

    // Drop matches whose correlation is far worse than the typical one.
    if !accepted.is_empty() {
        let mut s: Vec<u32> = accepted.iter().map(|a| a.0).collect();
        s.sort_unstable();
        let median = s[s.len() / 2] as f64;
        let th = params.sad_median_factor * median;
        for &(sad, i) in &accepted {
            if sad as f64 > th {
                u_right[i] = -1.0;
                depth[i] = -1.0;
            }
        }
    }
    (u_right, depth)
}

/// Sum of the `n x n` window with top-left corner (x0, y0) of a row-major image of width `w`.
fn window_sum(data: &[u8], w: isize, x0: isize, y0: isize, n: usize) -> i32 {
    (0..n as isize)
        .map(|dy| {
            let r = ((y0 + dy) * w + x0) as usize;
            data[r..r + n].iter().map(|&p| p as i32).sum::<i32>()
        })
        .sum()
}

#[cfg(test)]
pub(crate) mod tests {
    use std::sync::Arc;

    use crate::camera::{Camera, SensorKind};
    use crate::feature::test_scene::TestScene;
    use crate::feature::{OrbConfig, OrbExtractor};
    use crate::frame::Frame;
    use crate::image::FrameInput;

    /// EuRoC-like rectified stereo camera.
    pub(crate) fn stereo_camera() -> Camera {
        Camera {
            fx: 435.2,
            fy: 435.2,
            cx: 367.45,
            cy: 252.2,
            width: 752,
            height: 480,
            distortion: None,
            bf: 47.9,
            th_depth: 35.0,
            fps: 20.0,
            sensor: SensorKind::Stereo,
        }
    }

    /// True disparity of the three fronto-parallel planes (horizontal bands).
    fn disparity(v: f64) -> f64 {
        if v < 160.0 {
            12.3
        } else if v < 320.0 {
            27.65
        } else {
            41.45
        }
    }

    #[test]
    fn stereo_disparity_is_subpixel_accurate() {
        let scene = TestScene::random(752.0, 480.0, 450, 7);
        let left = scene.render(752, 480, |u, v| (u, v));
        // The right camera sees scene point x at u - d: right(u) = left(u + d).
        let right = scene.render(752, 480, |u, v| (u + disparity(v), v));
        let input = FrameInput {
            timestamp: 1.5,
            image: Arc::new(left),
            depth: None,
            right: Some(Arc::new(right)),
        };
        let cam = stereo_camera();
        let mut ex = OrbExtractor::new(OrbConfig::stereo());
        let f = Frame::new(3, &input, &cam, &mut ex);
        assert_eq!((f.id, f.timestamp), (3, 1.5));
        let mut errors = Vec::new();
        for i in 0..f.len() {
            if f.u_right[i] < 0.0 {
                assert!(f.depth[i] <= 0.0);
                continue;
            }
            let kp = f.keypoints[i];
            let v = kp.y as f64;
            let margin = 7.0 * f.scale.scale_factors[kp.octave];
            if (v - 160.0).abs() < margin || (v - 320.0).abs() < margin {
                continue; // the SAD window straddles two planes
            }
            let d = (kp.x - f.u_right[i]) as f64;
            assert!((f.depth[i] as f64 - cam.bf / d).abs() < 1e-3);
            errors.push((d - disparity(v)).abs());
        }
        let good = errors.iter().filter(|&&e| e < 0.2).count();
        let frac = good as f64 / errors.len() as f64;
        let mut sorted = errors.clone();
        sorted.sort_by(f64::total_cmp);
        eprintln!(
            "stereo: {} of {} keypoints matched (away from plane seams), {:.1} % within 0.2 px, median error {:.3} px",
            errors.len(),
            f.len(),
            100.0 * frac,
            sorted[sorted.len() / 2]
        );
        assert!(errors.len() > 500, "{} matches", errors.len());
        // Measured (seed 7): 599 matches, 95.5 % within 0.2 px, median error 0.043 px.
        assert!(frac > 0.85, "{frac}");
    }
}
