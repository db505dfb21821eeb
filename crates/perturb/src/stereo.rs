//! `stereo-misalignment`: the right camera of a rectified pair rotated about its x axis, as an
//! imperfect rectification (or a rig bent after calibration) leaves it: a scene point no longer
//! lies on the same row in both images, which is what row-wise stereo matching assumes.

use crate::image::bilinear;
use rayon::prelude::*;
use slam_core::{Camera, GrayImage};

/// The right image as a camera rotated by `degrees` about its x axis would see it:
/// `out(p) = in(K R^T K^-1 p)` with bilinear sampling (edges clamped).
pub fn rotate_right(img: &GrayImage, camera: &Camera, degrees: f64) -> GrayImage {
    let a = degrees.to_radians();
    let (c, s) = (a.cos(), a.sin());
    let (fx, fy, cx, cy) = (camera.fx, camera.fy, camera.cx, camera.cy);
    let w = img.width;
    let data = (0..img.width * img.height)
        .into_par_iter()
        .map(|i| {
            let (u, v) = ((i % w) as f64, (i / w) as f64);
            // Ray of the rotated camera, back into the original one (R^T about x).
            let (x, y) = ((u - cx) / fx, (v - cy) / fy);
            let (yr, zr) = (c * y + s, -s * y + c);
            let (su, sv) = (fx * x / zr + cx, fy * yr / zr + cy);
            (bilinear(img, su, sv) + 0.5).clamp(0.0, 255.0) as u8
        })
        .collect();
    GrayImage {
        width: img.width,
        height: img.height,
        data,
    }
}
