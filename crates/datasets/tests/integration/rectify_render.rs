//! Rectification on rendered images: a synthetic stereo rig with a known small rotation between
//! the cameras and strong radial-tangential distortion views a plane of Gaussian dots. Both raw
//! images are rendered through the distortion, rectified with the remap maps, and the dots'
//! intensity centroids are located in both rectified images: corresponding dots must lie on the
//! same row within 0.1 px, at the disparity f * B / Z.

use datasets::rectify::{relative_pose, RawCamera, StereoRectification};
use nalgebra::{Isometry3, Point3, Vector3};
use slam_core::{Distortion, GrayImage};

const W: u32 = 640;
const H: u32 = 480;
/// Dots on the plane Z = PLANE_Z (left raw camera frame), spacing and blur in metres.
const PLANE_Z: f64 = 2.0;
const SPACING: f64 = 0.16;
const SIGMA: f64 = 0.012;

fn rig() -> (RawCamera, RawCamera) {
    let left = RawCamera {
        width: W,
        height: H,
        fx: 458.0,
        fy: 457.0,
        cx: 322.0,
        cy: 245.0,
        distortion: Distortion {
            k1: -0.28,
            k2: 0.074,
            p1: 0.0002,
            p2: 0.00002,
            k3: 0.0,
        },
        t_bs: Isometry3::new(
            Vector3::new(-0.02, -0.06, 0.01),
            Vector3::new(0.01, 0.02, 1.55),
        ),
        rate_hz: 20.0,
    };
    let right = RawCamera {
        fx: 457.0,
        fy: 456.0,
        cx: 380.0,
        cy: 255.0,
        distortion: Distortion {
            k1: -0.283,
            k2: 0.0745,
            p1: -0.0001,
            p2: -0.00003,
            k3: 0.0,
        },
        // 11 cm to the right, a little off-axis, rotated by ~1.3 degrees.
        t_bs: left.t_bs
            * Isometry3::new(
                Vector3::new(0.11, 0.002, -0.001),
                Vector3::new(0.008, -0.015, 0.012),
            ),
        ..left.clone()
    };
    (left, right)
}

/// Dot intensity at plane coordinates (X, Y): Gaussian blobs on a square grid.
fn texture(x: f64, y: f64) -> f64 {
    let gx = (x / SPACING).round() * SPACING;
    let gy = (y / SPACING).round() * SPACING;
    let r2 = (x - gx).powi(2) + (y - gy).powi(2);
    230.0 * (-r2 / (2.0 * SIGMA * SIGMA)).exp() + 10.0
}

/// Renders the raw (distorted) image of a camera whose pose in the left camera frame is
/// `left_from_cam`, with 3x3 supersampling.
fn render(cam: &RawCamera, left_from_cam: &Isometry3<f64>) -> GrayImage {
    let mut img = GrayImage::new(W as usize, H as usize);
    for v in 0..H as usize {
        for u in 0..W as usize {
            let mut acc = 0.0;
            for sj in 0..3 {
                for si in 0..3 {
                    let (su, sv) = (
                        u as f64 + (si as f64 - 1.0) / 3.0,
                        v as f64 + (sj as f64 - 1.0) / 3.0,
                    );
                    let (x, y) = cam.undistort_normalize(su, sv);
                    let o = left_from_cam.translation.vector;
                    let d = left_from_cam.rotation * Vector3::new(x, y, 1.0);
                    let s = (PLANE_Z - o.z) / d.z;
                    acc += texture(o.x + s * d.x, o.y + s * d.y);
                }
            }
            img.data[v * W as usize + u] = (acc / 9.0).round().clamp(0.0, 255.0) as u8;
        }
    }
    img
}

/// Intensity-weighted centroid (background removed) in a window around (u, v), re-centred
/// on its own result a few times so the window truncates the blob symmetrically.
fn centroid(img: &GrayImage, u: f64, v: f64, r: i64) -> Option<(f64, f64)> {
    let mut c = (u, v);
    for _ in 0..3 {
        c = centroid_once(img, c.0, c.1, r)?;
    }
    Some(c)
}

fn centroid_once(img: &GrayImage, u: f64, v: f64, r: i64) -> Option<(f64, f64)> {
    let (cu, cv) = (u.round() as i64, v.round() as i64);
    if cu - r < 0 || cv - r < 0 || cu + r >= img.width as i64 || cv + r >= img.height as i64 {
        return None;
    }
    let (mut sw, mut su, mut sv) = (0.0, 0.0, 0.0);
    for y in cv - r..=cv + r {
        for x in cu - r..=cu + r {
            let w = (img.get(x as usize, y as usize) as f64 - 10.0).max(0.0);
            sw += w;
            su += w * x as f64;
            sv += w * y as f64;
        }
    }
    (sw > 0.0).then(|| (su / sw, sv / sw))
}

#[test]
fn rendered_dots_share_rows_after_rectification() {
    let (left, right) = rig();
    let rect = StereoRectification::new(&left, &right).unwrap();
    let right_from_left = relative_pose(&left, &right);
    let left_from_right = right_from_left.inverse();
    let raw_l = render(&left, &Isometry3::identity());
    let raw_r = render(&right, &left_from_right);
    let (rl, rr) = (rect.rectify_left(&raw_l), rect.rectify_right(&raw_r));

    let mut checked = 0;
    let mut worst: f64 = 0.0;
    for j in -8..=8 {
        for i in -10..=10 {
            let p = Point3::new(i as f64 * SPACING, j as f64 * SPACING, PLANE_Z);
            let pr = right_from_left * p;
            if pr.z <= 0.0 {
                continue;
            }
            // Predicted rectified positions, then measured centroids near them.
            let (ul, vl) = left.distort_project(p.x / p.z, p.y / p.z);
            let (ur, vr) = right.distort_project(pr.x / pr.z, pr.y / pr.z);
            let a = rect.rectify_point(false, ul, vl);
            let b = rect.rectify_point(true, ur, vr);
            let margin = 20.0;
            let inside = |q: (f64, f64)| {
                q.0 > margin && q.1 > margin && q.0 < W as f64 - margin && q.1 < H as f64 - margin
            };
            if !inside(a) || !inside(b) {
                continue;
            }
            let (Some(ml), Some(mr)) = (centroid(&rl, a.0, a.1, 10), centroid(&rr, b.0, b.1, 10))
            else {
                continue;
            };
            // The measurement agrees with the prediction (the maps are right) ...
            assert!(
                (ml.0 - a.0).abs() < 0.3 && (ml.1 - a.1).abs() < 0.3,
                "{ml:?} vs {a:?}"
            );
            // ... and the rows agree.
            let dy = (ml.1 - mr.1).abs();
            worst = worst.max(dy);
            assert!(dy < 0.1, "dot ({i},{j}): rows {} vs {}", ml.1, mr.1);
            // Disparity = f B / Z in the rectified left frame.
            let z = (rect.r_left * p.coords).z;
            let disp = ml.0 - mr.0;
            assert!(
                (disp - rect.focal * rect.baseline / z).abs() < 0.2,
                "disparity {disp}"
            );
            checked += 1;
        }
    }
    assert!(checked > 80, "only {checked} dots checked");
    eprintln!("{checked} dots, worst row difference {worst:.4} px");
}
