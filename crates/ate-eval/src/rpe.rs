//! Relative pose error: the drift of the estimate over a fixed delta (frames or seconds),
//! E_ij = (G_i^-1 G_j)^-1 (P_i^-1 P_j) over associated pairs, split into its translational
//! (metres) and rotational (degrees) parts. Independent of the SE3 alignment; under Sim3 the
//! estimate's translations are scaled first.

use crate::align::{umeyama, AlignmentMode};
use crate::associate::associate;
use crate::ate::AteOptions;
use crate::error::{Error, Result};
use crate::stats::ErrorStats;
use crate::trajectory::Trajectory;
use nalgebra::{Isometry3, Vector3};

/// The step between the two poses of each relative-error sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RpeDelta {
    /// A fixed number of associated poses.
    Frames(usize),
    /// A time interval in seconds (the first pose at least this much later).
    Seconds(f64),
}

/// Translational and rotational relative error statistics.
#[derive(Clone, Debug)]
pub struct RpeResult {
    /// Translational error in metres.
    pub trans: ErrorStats,
    /// Rotational error in degrees.
    pub rot: ErrorStats,
    /// Per-sample translational errors (metres).
    pub trans_errors: Vec<f64>,
    /// Per-sample rotational errors (degrees).
    pub rot_errors: Vec<f64>,
}

/// Computes the RPE of `est` against `gt` over `delta`.
pub fn evaluate_rpe(
    gt: &Trajectory,
    est: &Trajectory,
    delta: RpeDelta,
    opts: &AteOptions,
) -> Result<RpeResult> {
    let pairs = associate(
        &gt.stamps,
        &est.stamps,
        opts.max_difference,
        opts.offset,
        opts.association,
    );
    if pairs.len() < 2 {
        return Err(Error::TooFewPairs {
            pairs: pairs.len(),
            needed: 2,
        });
    }
    let scale = if opts.alignment == AlignmentMode::Sim3 {
        let g: Vec<Vector3<f64>> = pairs
            .iter()
            .map(|&(i, _)| gt.poses[i].translation.vector)
            .collect();
        let e: Vec<Vector3<f64>> = pairs
            .iter()
            .map(|&(_, j)| est.poses[j].translation.vector)
            .collect();
        umeyama(&e, &g, AlignmentMode::Sim3)?.scale
    } else {
        1.0
    };
    let scaled = |p: &Isometry3<f64>| {
        let mut q = *p;
        q.translation.vector *= scale;
        q
    };
    let mut trans_errors = Vec::new();
    let mut rot_errors = Vec::new();
    for a in 0..pairs.len() {
        let b = match delta {
            RpeDelta::Frames(n) => {
                if n == 0 || a + n >= pairs.len() {
                    break;
                }
                a + n
            }
            RpeDelta::Seconds(s) => {
                let target = gt.stamps[pairs[a].0] + s;
                match (a + 1..pairs.len()).find(|&k| gt.stamps[pairs[k].0] >= target) {
                    Some(k) => k,
                    None => break,
                }
            }
        };
        let (gi, ei) = pairs[a];
        let (gj, ej) = pairs[b];
        let rel_gt = gt.poses[gi].inverse() * gt.poses[gj];
        let rel_est = scaled(&est.poses[ei]).inverse() * scaled(&est.poses[ej]);
        let e = rel_gt.inverse() * rel_est;
        trans_errors.push(e.translation.vector.norm());
        rot_errors.push(e.rotation.angle().to_degrees());
    }
    if trans_errors.is_empty() {
        return Err(Error::TooFewPairs {
            pairs: pairs.len(),
            needed: 2,
        });
    }
    Ok(RpeResult {
        trans: ErrorStats::from_errors(&trans_errors),
        rot: ErrorStats::from_errors(&rot_errors),
        trans_errors,
        rot_errors,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    #[test]
    fn constant_drift_per_step_is_measured() {
        // The estimate adds 1 cm forward and 1 degree yaw per frame relative to the truth.
        let mut gt = Trajectory::new();
        let mut est = Trajectory::new();
        let step_gt =
            Isometry3::from_parts(Translation3::new(0.1, 0.0, 0.0), UnitQuaternion::identity());
        let drift = Isometry3::from_parts(
            Translation3::new(0.01, 0.0, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, 1f64.to_radians()),
        );
        let (mut g, mut e) = (Isometry3::identity(), Isometry3::identity());
        for i in 0..20 {
            gt.push(i as f64, g);
            est.push(i as f64, e);
            g *= step_gt;
            e = e * step_gt * drift;
        }
        let r = evaluate_rpe(&gt, &est, RpeDelta::Frames(1), &AteOptions::default()).unwrap();
        assert_eq!(r.trans.count, 19);
        assert!((r.rot.mean - 1.0).abs() < 1e-9);
        assert!((r.trans.mean - 0.01).abs() < 1e-9);
        // A rigidly moved copy has zero RPE whatever the delta.
        let moved = gt.transformed(1.0, &Isometry3::translation(1.0, 2.0, 3.0));
        let r = evaluate_rpe(&gt, &moved, RpeDelta::Seconds(2.5), &AteOptions::default()).unwrap();
        assert!(r.trans.max < 1e-12 && r.rot.max < 1e-9);
        assert_eq!(r.trans.count, 17);
    }
}
