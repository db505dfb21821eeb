//! Keyframe-pair matching for triangulation (ORB-SLAM2's SearchForTriangulation): keypoints not
//! yet associated to a map point in either keyframe, matched by descriptor (<= TH_LOW) among
//! candidates that lie on the epipolar line (squared distance < 3.84 sigma^2) and, when neither
//! has a depth, not near the epipole. With a vocabulary, candidates are limited to the same
//! direct-index node, as ORB-SLAM2 does (visited node by node); without one, every unassociated
//! keypoint of the second keyframe is scanned (exhaustive, same acceptance).

use nalgebra::{Matrix3, Vector3};

use super::RotationHistogram;
use crate::camera::Camera;
use crate::data::{KeyFrame, Map, ScaleLevels};
use crate::feature::{hamming, TH_LOW};
use crate::geometry::skew;

/// Fundamental matrix `F12` with `x1^T F12 x2 = 0` for pixels x1 in `kf1` and x2 in `kf2`.
pub fn fundamental_12(kf1: &KeyFrame, kf2: &KeyFrame, camera: &Camera) -> Matrix3<f64> {
    let r1w = kf1.tcw.rotation.to_rotation_matrix().into_inner();
    let t1w = kf1.tcw.translation.vector;
    let r2w = kf2.tcw.rotation.to_rotation_matrix().into_inner();
    let t2w = kf2.tcw.translation.vector;
    let r12 = r1w * r2w.transpose();
    let t12 = -r12 * t2w + t1w;
    let k_inv = Matrix3::new(
        1.0 / camera.fx,
        0.0,
        -camera.cx / camera.fx,
        0.0,
        1.0 / camera.fy,
        -camera.cy / camera.fy,
        0.0,
        0.0,
        1.0,
    );
    k_inv.transpose() * skew(&t12) * r12 * k_inv
}

/// Pairs `(idx1, idx2)` of unassociated keypoints of `kf1` and `kf2` that satisfy the epipolar
/// constraint `f12`, one-to-one, after the rotation-consistency check.
pub fn search_for_triangulation(
    kf1: &KeyFrame,
    kf2: &KeyFrame,
    f12: &Matrix3<f64>,
    map: &Map,
    camera: &Camera,
    levels: &ScaleLevels,
) -> Vec<(usize, usize)> {
    // Epipole: centre of kf1 seen from kf2.
    let c2 = kf2.to_camera(&kf1.center());
    let (ex, ey) = if c2.z.abs() > 1e-12 {
        let p = camera.project(&c2);
        (p.x, p.y)
    } else {
        (f64::INFINITY, f64::INFINITY)
    };
    let free =
        |kf: &KeyFrame, i: usize| kf.map_points[i].is_none_or(|m| map.map_point(m).is_none());
    // Candidate groups: features of kf1 and of kf2 that may match each other.
    let groups: Vec<(Vec<usize>, Vec<usize>)> = match (kf1.bow.as_deref(), kf2.bow.as_deref()) {
        (Some(b1), Some(b2)) => b1
            .features
            .common_nodes(&b2.features)
            .map(|(f1, f2)| {
                (
                    f1.iter().copied().filter(|&i| free(kf1, i)).collect(),
                    f2.iter().copied().filter(|&i| free(kf2, i)).collect(),
                )
            })
            .collect(),
        _ => vec![(
            (0..kf1.features.len()).filter(|&i| free(kf1, i)).collect(),
            (0..kf2.features.len()).filter(|&i| free(kf2, i)).collect(),
        )],
    };
    let mut matched2 = vec![false; kf2.features.len()];
    let mut pairs: Vec<(usize, usize)> = Vec::new();
    let mut hist = RotationHistogram::new();
    for (idx1, free2) in groups
        .iter()
        .flat_map(|(g1, g2)| g1.iter().map(move |&i| (i, g2)))
    {
        let kp1 = &kf1.features.keypoints[idx1];
        let stereo1 = kf1.features.u_right_of(idx1).is_some();
        let d1 = &kf1.features.descriptors[idx1];
        let x1 = Vector3::new(kp1.x as f64, kp1.y as f64, 1.0);
        let line = f12.transpose() * x1;
        let den = line.x * line.x + line.y * line.y;
        if den <= 0.0 {
            continue;
        }
        let (mut best, mut best_idx) = (TH_LOW + 1, usize::MAX);
        for &idx2 in free2 {
            if matched2[idx2] {
                continue;
            }
            let d = hamming(d1, &kf2.features.descriptors[idx2]);
            if d > TH_LOW || d > best {
                continue;
            }
            let kp2 = &kf2.features.keypoints[idx2];
            let (x2, y2) = (kp2.x as f64, kp2.y as f64);
            let stereo2 = kf2.features.u_right_of(idx2).is_some();
            if !stereo1 && !stereo2 {
                let (dx, dy) = (ex - x2, ey - y2);
                if dx * dx + dy * dy < 100.0 * levels.scale(kp2.octave) {
                    continue;
                }
            }
            let num = line.x * x2 + line.y * y2 + line.z;
            if num * num / den < 3.84 * levels.sigma2(kp2.octave) {
                best = d;
                best_idx = idx2;
            }
        }
        if best_idx != usize::MAX {
            matched2[best_idx] = true;
            hist.add(
                kp1.angle,
                kf2.features.keypoints[best_idx].angle,
                pairs.len(),
            );
            pairs.push((idx1, best_idx));
        }
    }
    let mut keep = vec![true; pairs.len()];
    for k in hist.rejected() {
        keep[k] = false;
    }
    pairs
        .into_iter()
        .zip(keep)
        .filter_map(|(p, k)| k.then_some(p))
        .collect()
}
