//! The ground-truth families: errors of the file a run is scored against, not of the input, as
//! a motion-capture system's clock, noise and hand-eye calibration leave them.
//!
//! - `gt-offset:L` (ms): every ground-truth stamp moved L ms earlier, so the estimate at time t
//!   is paired with the pose taken at t + L ms: what `noisefree eval --offset` (seconds added to
//!   the estimate's stamps) gives with L / 1000 on the unperturbed files. Positive L: the
//!   ground truth runs late.
//! - `gt-jitter:L` (mm): every position moved by independent N(0, L mm) per world axis (the
//!   orientation is left exact: ATE reads positions only).
//! - `gt-hand-eye:L` (mm and degrees): every pose times one fixed error transform, a rotation of
//!   L degrees about an axis and a translation of L mm along a direction, both drawn once from
//!   the perturbation seed: the marker-to-camera calibration off by that much.

use crate::family::{Domain, Family, Perturbation};
use ate_eval::Trajectory;
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use synth::hash::{NoiseKey, Stream};

/// A unit vector drawn uniformly on the sphere from `key` (indices `i`, `i + 1`).
fn direction(key: NoiseKey, i: u64) -> Unit<Vector3<f64>> {
    let z = 2.0 * key.uniform(i) - 1.0;
    let a = key.uniform(i + 1) * std::f64::consts::TAU;
    let r = (1.0 - z * z).max(0.0).sqrt();
    Unit::new_normalize(Vector3::new(r * a.cos(), r * a.sin(), z))
}

/// The fixed error transform of `gt-hand-eye` at `level` for member seed `seed`.
pub fn hand_eye_error(level: f64, seed: u64) -> Isometry3<f64> {
    let key = NoiseKey::new(seed, 0, Stream::Mocap);
    let axis = direction(key, 0);
    let t = direction(key, 2).into_inner() * (level / 1000.0);
    Isometry3::from_parts(
        Translation3::from(t),
        UnitQuaternion::from_axis_angle(&axis, level.to_radians()),
    )
}

/// `gt` with the ground-truth `members` (each with its member seed) applied in order.
pub fn perturb_groundtruth(gt: &Trajectory, members: &[(Perturbation, u64)]) -> Trajectory {
    let mut out = gt.clone();
    for &(p, seed) in members {
        debug_assert_eq!(p.family.domain(), Domain::GroundTruth);
        match p.family {
            Family::GtOffset => {
                let dt = p.level / 1000.0;
                for t in &mut out.stamps {
                    *t -= dt;
                }
            }
            Family::GtJitter => {
                let key = NoiseKey::new(seed, 0, Stream::Mocap);
                let sigma = p.level / 1000.0;
                for (i, pose) in out.poses.iter_mut().enumerate() {
                    let (a, b) = key.normal2(2 * i as u64);
                    let c = key.normal(2 * i as u64 + 1);
                    pose.translation.vector += Vector3::new(a, b, c) * sigma;
                }
            }
            Family::GtHandEye => {
                let e = hand_eye_error(p.level, seed);
                for pose in &mut out.poses {
                    *pose *= e;
                }
            }
            _ => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize) -> Trajectory {
        Trajectory {
            stamps: (0..n).map(|i| i as f64 * 0.01).collect(),
            poses: (0..n)
                .map(|i| Isometry3::translation(i as f64 * 0.004, 0.0, 0.0))
                .collect(),
        }
    }

    fn at(family: Family, level: f64) -> (Perturbation, u64) {
        (Perturbation { family, level }, 3)
    }

    #[test]
    fn offset_moves_stamps_only() {
        let gt = line(50);
        let out = perturb_groundtruth(&gt, &[at(Family::GtOffset, 10.0)]);
        for (a, b) in out.stamps.iter().zip(&gt.stamps) {
            assert!((b - a - 0.010).abs() < 1e-12);
        }
        assert_eq!(out.poses, gt.poses);
    }

    #[test]
    fn jitter_has_its_sigma_per_axis() {
        let gt = line(20_000);
        let out = perturb_groundtruth(&gt, &[at(Family::GtJitter, 2.0)]);
        let d: Vec<Vector3<f64>> = out
            .poses
            .iter()
            .zip(&gt.poses)
            .map(|(a, b)| a.translation.vector - b.translation.vector)
            .collect();
        for axis in 0..3 {
            let var = d.iter().map(|v| v[axis] * v[axis]).sum::<f64>() / d.len() as f64;
            let sigma_mm = var.sqrt() * 1000.0;
            assert!((sigma_mm - 2.0).abs() < 0.05, "axis {axis}: {sigma_mm}");
        }
        assert_eq!(out.stamps, gt.stamps);
        assert!(out
            .poses
            .iter()
            .zip(&gt.poses)
            .all(|(a, b)| a.rotation == b.rotation));
    }

    #[test]
    fn hand_eye_is_one_fixed_error_of_the_level() {
        let e = hand_eye_error(2.0, 3);
        assert!((e.translation.vector.norm() - 0.002).abs() < 1e-12);
        assert!((e.rotation.angle().to_degrees() - 2.0).abs() < 1e-9);
        let gt = line(10);
        let out = perturb_groundtruth(&gt, &[at(Family::GtHandEye, 2.0)]);
        for (a, b) in out.poses.iter().zip(&gt.poses) {
            let rel = b.inverse() * a;
            assert!((rel.translation.vector - e.translation.vector).norm() < 1e-12);
            assert!(rel.rotation.angle_to(&e.rotation) < 1e-12);
        }
    }
}
