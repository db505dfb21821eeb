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

/// Which samples over the step are taken: every pose's (TUM's evaluate_rpe.py, evo's
/// `--all_pairs`) or back-to-back ones, each starting where the previous ended (evo's default).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RpePairs {
    /// A sample from every associated pose: overlapping. The default.
    #[default]
    All,
    /// Non-overlapping samples: the next one starts at the previous one's end pose.
    Consecutive,
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

/// Computes the RPE of `est` against `gt` over `delta`, a sample from every pose
/// ([`RpePairs::All`]).
pub fn evaluate_rpe(
    gt: &Trajectory,
    est: &Trajectory,
    delta: RpeDelta,
    opts: &AteOptions,
) -> Result<RpeResult> {
    evaluate_rpe_with(gt, est, delta, RpePairs::All, opts)
}

/// [`evaluate_rpe`] with the samples `pairs` says.
pub fn evaluate_rpe_with(
    gt: &Trajectory,
    est: &Trajectory,
    delta: RpeDelta,
    pairs_taken: RpePairs,
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
    let stamps: Vec<f64> = pairs.iter().map(|&(i, _)| gt.stamps[i]).collect();
    for (a, b) in taken(steps(&stamps, delta), pairs_taken) {
        let (gi, ei) = pairs[a];
        let (gj, ej) = pairs[b];
        let rel_gt = gt.poses[gi].inverse() * gt.poses[gj];
        let rel_est = scaled(&est.poses[ei]).inverse() * scaled(&est.poses[ej]);
        let e = rel_gt.inverse() * rel_est;
        trans_errors.push(e.translation.vector.norm());
        rot_errors.push(e.rotation.angle().to_degrees());
    }
    if let Some(e) = trans_errors
        .iter()
        .chain(&rot_errors)
        .find(|e| !e.is_finite())
    {
        return Err(Error::NotFinite(format!(
            "a relative error of {e} (positions too large to measure)"
        )));
    }
    if trans_errors.is_empty() {
        // Found replaying a fuzz input: this said "only 2000 pose pairs associated (need at
        // least 2)" for 2000 pairs spanning less than the step.
        return Err(Error::NoRpeSample {
            pairs: pairs.len(),
            step: match delta {
                RpeDelta::Frames(1) => "1 frame".into(),
                RpeDelta::Frames(n) => format!("{n} frames"),
                RpeDelta::Seconds(s) => format!("{s} s"),
            },
        });
    }
    Ok(RpeResult {
        trans: ErrorStats::from_errors(&trans_errors),
        rot: ErrorStats::from_errors(&rot_errors),
        trans_errors,
        rot_errors,
    })
}

/// Of the samples `all` (in order of their first pose), those `pairs` takes: every one, or
/// back to back (the first, then the first starting at or after the previous one's end).
fn taken(all: Vec<(usize, usize)>, pairs: RpePairs) -> Vec<(usize, usize)> {
    match pairs {
        RpePairs::All => all,
        RpePairs::Consecutive => {
            let mut out: Vec<(usize, usize)> = Vec::new();
            for (a, b) in all {
                if out.last().is_none_or(|&(_, end)| a >= end) {
                    out.push((a, b));
                }
            }
            out
        }
    }
}

/// The samples `(a, b)` of pair indices over `delta`, for pairs whose ground-truth stamps are
/// `stamps`: b = a + n over frames; over seconds the first pair at least `s` after pair a,
/// until there is none. With stamps in time order (as read) and their targets `t + s` in order
/// too, b only moves forward, so it is searched from where the previous search ended: linear
/// in the pairs, not quadratic when `s` spans many of them. Stamps out of order are searched
/// from pair a + 1 each time.
fn steps(stamps: &[f64], delta: RpeDelta) -> Vec<(usize, usize)> {
    use std::cmp::Ordering::{Equal, Greater};
    let n = stamps.len();
    match delta {
        RpeDelta::Frames(k) => {
            if k == 0 {
                return Vec::new();
            }
            (0..n.saturating_sub(k)).map(|a| (a, a + k)).collect()
        }
        RpeDelta::Seconds(s) => {
            let in_order = |x: &[f64]| x.windows(2).all(|w| w[0] <= w[1]);
            let targets: Vec<f64> = stamps.iter().map(|t| t + s).collect();
            let forward_only =
                in_order(stamps) && in_order(&targets) && targets.iter().all(|t| !t.is_nan());
            let mut out = Vec::new();
            let mut b = 0;
            for (a, &target) in targets.iter().enumerate() {
                b = if forward_only { b.max(a + 1) } else { a + 1 };
                while b < n && !matches!(stamps[b].partial_cmp(&target), Some(Greater | Equal)) {
                    b += 1;
                }
                if b == n {
                    break;
                }
                out.push((a, b));
            }
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    #[test]
    fn consecutive_samples_start_where_the_previous_ended() {
        let stamps: Vec<f64> = (0..7).map(f64::from).collect();
        let all = steps(&stamps, RpeDelta::Frames(2));
        assert_eq!(all, [(0, 2), (1, 3), (2, 4), (3, 5), (4, 6)]);
        assert_eq!(taken(all.clone(), RpePairs::All), all);
        assert_eq!(taken(all, RpePairs::Consecutive), [(0, 2), (2, 4), (4, 6)]);
        let over_seconds = steps(&stamps, RpeDelta::Seconds(2.5));
        assert_eq!(taken(over_seconds, RpePairs::Consecutive), [(0, 3), (3, 6)]);
    }

    /// The samples as found until issue 45: over seconds, a scan from pair a + 1 for every a
    /// (quadratic when `s` spans many pairs).
    fn steps_scanning(stamps: &[f64], delta: RpeDelta) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for a in 0..stamps.len() {
            let b = match delta {
                RpeDelta::Frames(n) => {
                    if n == 0 || a + n >= stamps.len() {
                        break;
                    }
                    a + n
                }
                RpeDelta::Seconds(s) => {
                    let target = stamps[a] + s;
                    match (a + 1..stamps.len()).find(|&k| stamps[k] >= target) {
                        Some(k) => k,
                        None => break,
                    }
                }
            };
            out.push((a, b));
        }
        out
    }

    #[test]
    fn samples_over_seconds_are_those_of_the_scan() {
        let mut state = 45u64;
        let mut unit = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for case in 0..3000 {
            let n = (unit() * 80.0) as usize;
            let mut stamps: Vec<f64> = Vec::new();
            let mut t = 1_305_031_102.0;
            for _ in 0..n {
                // Steps of 0 (repeats) to 0.1 s; now and then one back in time.
                t += [0.0, 0.001, 0.033, 0.1, -0.05][(unit() * 5.0) as usize];
                stamps.push(t);
            }
            if case % 7 == 0 && n > 0 {
                stamps[(unit() * n as f64) as usize] =
                    [f64::NAN, f64::INFINITY, -1e300][(unit() * 3.0) as usize];
            }
            let s = [
                0.0,
                -0.5,
                0.05,
                0.1,
                1.0,
                1e9,
                f64::NAN,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ][case % 9];
            assert_eq!(
                steps(&stamps, RpeDelta::Seconds(s)),
                steps_scanning(&stamps, RpeDelta::Seconds(s)),
                "{stamps:?} {s}"
            );
            for k in [0, 1, 3, n] {
                assert_eq!(
                    steps(&stamps, RpeDelta::Frames(k)),
                    steps_scanning(&stamps, RpeDelta::Frames(k))
                );
            }
        }
        // A frame count past the end gives no sample (the scan's a + n overflowed).
        assert!(steps(&[0.0, 1.0], RpeDelta::Frames(usize::MAX)).is_empty());
    }

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

    #[test]
    fn pairs_spanning_less_than_the_step_say_so() {
        let mut gt = Trajectory::new();
        for i in 0..20 {
            gt.push(i as f64 * 0.01, Isometry3::translation(i as f64, 0.0, 0.0));
        }
        for (delta, want) in [
            (
                RpeDelta::Seconds(0.5),
                "no relative pose error sample over 0.5 s among the 20",
            ),
            (
                RpeDelta::Frames(20),
                "over 20 frames among the 20 associated pose pairs",
            ),
        ] {
            let e = evaluate_rpe(&gt, &gt, delta, &AteOptions::default()).unwrap_err();
            assert!(e.to_string().contains(want), "{e}");
        }
    }
}
