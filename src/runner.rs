//! One SLAM run over a decoded sequence: feed every frame to `slam_core::System`, collect the
//! trajectory and per-frame statistics, and score it against ground truth with ate-eval in the
//! frame the ground truth is expressed in (EuRoC: body frame via T_BS).

use ate_eval::{evaluate_ate, AteOptions, AteResult, Trajectory};
use datasets::Sequence;
use slam_core::module::loop_closing::LoopEvent;
use slam_core::place::Vocabulary;
use slam_core::system::{Config, FrameStats, System};
use std::sync::Arc;
use std::time::Instant;

/// A run fails ('F' in the paper's tables) when fewer than this fraction of the frames have a
/// pose, or when no ATE can be computed at all.
pub const MIN_TRACKED_FRACTION: f64 = 0.8;

/// Everything a run produces.
#[derive(Clone, Debug)]
pub struct RunOutcome {
    /// Estimated camera trajectory (T_world_camera, TUM convention), tracked frames only.
    pub trajectory: Trajectory,
    /// Per-frame statistics, one per input frame.
    pub stats: Vec<FrameStats>,
    /// ATE against ground truth, when the sequence has ground truth and enough poses associate.
    pub ate: Option<AteResult>,
    /// Frames fed to the system.
    pub frames: usize,
    /// Frames with a pose.
    pub tracked: usize,
    /// Keyframes in the final map.
    pub keyframes: usize,
    /// Map points in the final map.
    pub map_points: usize,
    /// Whether loop closing ran (on in the configuration and a vocabulary loaded).
    pub loop_closing: bool,
    /// Loops closed, in order.
    pub loops: Vec<ClosedLoop>,
    /// Wall time of the run, seconds (single thread).
    pub wall_s: f64,
    /// The failure verdict ('F').
    pub failed: bool,
}

/// A loop the run closed.
#[derive(Clone, Debug, PartialEq)]
pub struct ClosedLoop {
    /// Index of the frame on which it closed (0-based).
    pub frame: usize,
    /// That frame's timestamp, seconds.
    pub timestamp: f64,
    /// The keyframes involved and the size of the correction.
    pub event: LoopEvent,
    /// Capture times of the closing keyframe and of the keyframe it was matched to, seconds.
    pub keyframe_stamps: (f64, f64),
    /// With ground truth: how far apart the two keyframes' true poses are (metres, degrees;
    /// body frame for EuRoC). A true loop joins views of one place; a false one, far apart
    /// or looking elsewhere.
    pub truth: Option<(f64, f64)>,
}

/// The ground-truth pose nearest to `stamp` (within 0.02 s, evaluate_ate.py's window).
fn truth_at(gt: &Trajectory, stamp: f64) -> Option<nalgebra::Isometry3<f64>> {
    let i = gt.stamps.partition_point(|&s| s < stamp);
    [i.checked_sub(1), Some(i)]
        .into_iter()
        .flatten()
        .filter(|&k| k < gt.stamps.len())
        .min_by(|&a, &b| {
            (gt.stamps[a] - stamp)
                .abs()
                .total_cmp(&(gt.stamps[b] - stamp).abs())
        })
        .filter(|&k| (gt.stamps[k] - stamp).abs() < 0.02)
        .map(|k| gt.poses[k])
}

impl RunOutcome {
    /// Frames processed per second of wall time.
    pub fn fps(&self) -> f64 {
        if self.wall_s > 0.0 {
            self.frames as f64 / self.wall_s
        } else {
            0.0
        }
    }

    /// ATE RMSE in metres, when computed.
    pub fn ate_rmse(&self) -> Option<f64> {
        self.ate.as_ref().map(|a| a.stats.rmse)
    }

    /// Mean over frames of (inliers, outliers) of the final pose optimization.
    pub fn mean_inliers_outliers(&self) -> (f64, f64) {
        let n = self.stats.len().max(1) as f64;
        let i: usize = self.stats.iter().map(|s| s.n_inliers).sum();
        let o: usize = self.stats.iter().map(|s| s.n_outliers).sum();
        (i as f64 / n, o as f64 / n)
    }
}

/// Runs `config` over `seq` with place recognition over `vocabulary` (brute-force stand-ins
/// without one), calling `on_frame` after each frame (for progress bars).
pub fn run_sequence(
    seq: &Sequence,
    config: &Config,
    vocabulary: Option<&Arc<Vocabulary>>,
    mut on_frame: impl FnMut(usize),
) -> RunOutcome {
    let start = Instant::now();
    let mut system = match vocabulary {
        Some(v) => System::with_vocabulary(seq.camera.clone(), config.clone(), v.clone()),
        None => System::new(seq.camera.clone(), config.clone()),
    };
    let mut stats = Vec::with_capacity(seq.frames.len());
    for (i, frame) in seq.frames.iter().enumerate() {
        let r = system.track(frame);
        stats.push(r.stats);
        on_frame(i + 1);
    }
    let wall_s = start.elapsed().as_secs_f64();
    let closing_frames = stats.iter().enumerate().filter(|(_, s)| s.loop_closed);
    let loops: Vec<ClosedLoop> = closing_frames
        .zip(system.loops())
        .map(|((frame, s), event)| {
            let stamp = |k| {
                system
                    .map()
                    .keyframe_any(k)
                    .map_or(f64::NAN, |kf| kf.timestamp)
            };
            let keyframe_stamps = (stamp(event.current), stamp(event.loop_kf));
            let truth = seq.groundtruth.as_ref().and_then(|gt| {
                let a = truth_at(gt, keyframe_stamps.0)?;
                let b = truth_at(gt, keyframe_stamps.1)?;
                Some((
                    (a.translation.vector - b.translation.vector).norm(),
                    a.rotation.angle_to(&b.rotation).to_degrees(),
                ))
            });
            ClosedLoop {
                frame,
                timestamp: s.timestamp,
                event: event.clone(),
                keyframe_stamps,
                truth,
            }
        })
        .collect();
    let mut trajectory = Trajectory::new();
    for (t, pose) in system.trajectory() {
        trajectory.push(t, pose);
    }
    let tracked = trajectory.len();
    let ate = seq.groundtruth.as_ref().and_then(|gt| {
        let est = match &seq.t_bs {
            Some(t_bs) => trajectory.cam_to_body(t_bs),
            None => trajectory.clone(),
        };
        evaluate_ate(gt, &est, &AteOptions::default()).ok()
    });
    let frames = seq.frames.len();
    let failed = ate.is_none() && seq.groundtruth.is_some()
        || (tracked as f64) < MIN_TRACKED_FRACTION * frames as f64;
    RunOutcome {
        trajectory,
        stats,
        ate,
        frames,
        tracked,
        keyframes: system.keyframe_count(),
        map_points: system.map_point_count(),
        loop_closing: config.loop_closing.enabled && vocabulary.is_some(),
        loops,
        wall_s,
        failed,
    }
}
