//! Fig. 8 and Fig. 7 on a synthetic sequence: the baseline (ORB-SLAM2) and MC-OR run on the same
//! frames; per frame, the inliers and outliers of the final pose optimization of each and the
//! matches MC-OR rejected (clusters and single features); and one frame's features drawn with
//! MC-OR's verdicts. Because the sequence is synthetic, the rejections are also checked
//! against the truth: the true depth error of rejected versus kept features, and how many lie
//! on moving objects.

use crate::analysis::association::{
    classify, Association, AssociationCounts, KeyframeTruth, TrackedTruth,
};
use crate::analysis::correlation::{depth_at_raw_pixel, median_abs};
use crate::analysis::stream::{for_each_chunk, frame_input};
use crate::report::panels::{Mark, MarkedFeature};
use ate_eval::{evaluate_ate, AteOptions, Trajectory};
use nalgebra::Isometry3;
use slam_core::module::pose_estimation::{tap_pose_optimizations, PoseOptRecord};
use slam_core::system::{Config, FrameStats, System};
use slam_core::techniques::McorVerdict;
use slam_core::{FrameInput, GrayImage};
use synth::{Generator, SynthFrame};

/// The frame chosen for Fig. 7, with what is needed to draw it.
#[derive(Clone, Debug)]
pub struct Fig7Frame {
    /// Frame index.
    pub index: usize,
    /// Its grey image.
    pub image: GrayImage,
    /// Per pixel: on a moving object (presets with walking people).
    pub moving: Option<Vec<bool>>,
    /// Its matched features at raw pixels with MC-OR's verdict at the last gating.
    pub features: Vec<MarkedFeature>,
}

impl Fig7Frame {
    /// Number of rejected features (feature- and cluster-level).
    pub fn n_rejected(&self) -> usize {
        self.features
            .iter()
            .filter(|f| f.mark != Mark::Kept)
            .count()
    }
}

/// Truth about MC-OR's verdicts, over all tracked frames of the MC-OR run (last gating of each
/// frame's final pose optimization; matches with measured and true depth).
#[derive(Clone, Debug, Default)]
pub struct VerdictTruth {
    /// |Z_D - Z_true| of kept matches, metres.
    pub kept_depth_errors: Vec<f64>,
    /// |Z_D - Z_true| of matches rejected by the FL test, metres.
    pub feature_depth_errors: Vec<f64>,
    /// |Z_D - Z_true| of matches rejected by the CL test, metres.
    pub cluster_depth_errors: Vec<f64>,
    /// Kept matches on a moving object / all kept matches (with a moving mask).
    pub kept_on_moving: (usize, usize),
    /// Rejected matches (either test) on a moving object / all rejected.
    pub rejected_on_moving: (usize, usize),
}

/// The truth about one run's tracking: what its matches were and where its camera was.
#[derive(Clone, Debug, Default)]
pub struct RunTruth {
    /// The final pose optimization's matches of every tracked frame, by inlier / outlier and
    /// true association.
    pub associations: AssociationCounts,
    /// Per frame: distance (metres) of the estimated camera centre from the true one, the
    /// estimate placed in the truth's world by the first frame's true pose (the system's world
    /// is its first camera); `None` when not tracked.
    pub position_errors: Vec<Option<f64>>,
    /// Per frame: inliers of the final pose optimization on moving objects.
    pub moving_inliers: Vec<usize>,
    keyframes: KeyframeTruth,
}

impl RunTruth {
    /// Tracks `frame` (as `input`) with `system` under the optimization tap and records the
    /// truth of the outcome; returns the frame's final pose optimization if it was tracked.
    fn track(
        &mut self,
        system: &mut System,
        frame: &SynthFrame,
        input: &FrameInput,
        origin: &Isometry3<f64>,
    ) -> Option<PoseOptRecord> {
        let (result, records) = tap_pose_optimizations(|| system.track(input));
        let tracked = result.state.is_tracked();
        let last = system.last_frame().filter(|_| tracked);
        let camera = system.camera().clone();
        if let (Some(last), true) = (last, result.stats.keyframe_inserted) {
            self.keyframes.remember(&camera, frame, &last.features);
        }
        self.position_errors
            .push(last.and_then(|f| f.tcw).map(|tcw| {
                let estimate = origin * tcw.inverse();
                (estimate.translation.vector - frame.pose_wc.translation.vector).norm()
            }));
        let record = records
            .into_iter()
            .rev()
            .find(|r| r.frame_id == frame.index as u64);
        let (Some(record), Some(last)) = (record, last) else {
            self.moving_inliers.push(0);
            return None;
        };
        let truth = TrackedTruth {
            camera: &camera,
            frame,
            features: &last.features,
            scale_factor: system.config().orb.scale_factor,
        };
        let mut moving_inliers = 0;
        for m in &record.matches {
            let a = classify(
                &truth,
                m.keypoint,
                system.map(),
                m.map_point,
                &self.keyframes,
            );
            self.associations.add(m.inlier, a);
            moving_inliers += usize::from(m.inlier && a == Association::Moving);
        }
        self.moving_inliers.push(moving_inliers);
        Some(record)
    }
}

/// What an outlier analysis produced.
#[derive(Clone, Debug)]
pub struct OutlierData {
    /// Per-frame statistics of the baseline run.
    pub baseline: Vec<FrameStats>,
    /// Per-frame statistics of the MC-OR run.
    pub mcor: Vec<FrameStats>,
    /// ATE RMSE (metres) of the baseline and MC-OR runs, when computable.
    pub ate: (Option<f64>, Option<f64>),
    /// The Fig. 7 frame, when any frame of the MC-OR run was tracked.
    pub fig7: Option<Fig7Frame>,
    /// The verdicts against the truth.
    pub truth: VerdictTruth,
    /// The baseline's and the MC-OR run's matches and positions against the truth.
    pub runs: (RunTruth, RunTruth),
}

fn ate_of(system: &System, gt: &Trajectory) -> Option<f64> {
    let mut est = Trajectory::new();
    for (t, pose) in system.trajectory() {
        est.push(t, pose);
    }
    evaluate_ate(gt, &est, &AteOptions::default())
        .ok()
        .map(|a| a.stats.rmse)
}

/// Runs `base_config` (the baseline) and `technique_config` (MC-OR, or another gate; the
/// `mcor` fields of [`OutlierData`] hold its run) over frames 0..n of `generator`, both
/// systems side by side on the same rendered frames. Fig. 7 shows frame `fig7_frame` if given,
/// else the frame with most MC-OR rejections.
pub fn collect(
    generator: &Generator,
    n: usize,
    base_config: &Config,
    technique_config: &Config,
    fig7_frame: Option<usize>,
    mut progress: impl FnMut(usize),
) -> OutlierData {
    let camera = generator.camera();
    let base_config = base_config.clone();
    let mcor_config = technique_config.clone();
    // The built-in vocabulary, as `noisefree run` uses by default.
    let voc = crate::vocab_file::default_vocabulary();
    let mut baseline = System::with_vocabulary(camera.clone(), base_config, voc.clone());
    let mut mcor = System::with_vocabulary(camera.clone(), mcor_config, voc);
    let mut fig7: Option<Fig7Frame> = None;
    let mut truth = VerdictTruth::default();
    let mut gt = Trajectory::new();
    let origin = generator.pose(0);
    let (mut base_truth, mut mcor_truth) = (RunTruth::default(), RunTruth::default());
    for_each_chunk(generator, n, |chunk| {
        let inputs: Vec<_> = chunk.iter().map(frame_input).collect();
        for f in &chunk {
            gt.push(f.timestamp, f.pose_wc);
        }
        rayon::join(
            || {
                for (frame, input) in chunk.iter().zip(&inputs) {
                    base_truth.track(&mut baseline, frame, input, &origin);
                }
            },
            || {
                for (frame, input) in chunk.iter().zip(&inputs) {
                    let Some(record) = mcor_truth.track(&mut mcor, frame, input, &origin) else {
                        continue;
                    };
                    let Some(last) = mcor.last_frame() else {
                        continue;
                    };
                    let mut features = Vec::with_capacity(record.matches.len());
                    for m in &record.matches {
                        let kp = &last.features.keypoints[m.keypoint];
                        let (x, y) = camera.distort_point(kp.x as f64, kp.y as f64);
                        let mark = match m.mcor {
                            Some(McorVerdict::RejectedFeature) => Mark::RejectedFeature,
                            Some(McorVerdict::RejectedCluster) => Mark::RejectedCluster,
                            _ => Mark::Kept,
                        };
                        features.push(MarkedFeature { x, y, mark });
                        let on_moving = frame.moving_mask.as_ref().and_then(|mask| {
                            let (px, py) = (x.round(), y.round());
                            (px >= 0.0
                                && py >= 0.0
                                && (px as usize) < frame.gray.width
                                && (py as usize) < frame.gray.height)
                                .then(|| mask[py as usize * frame.gray.width + px as usize])
                        });
                        if let Some(on) = on_moving {
                            let slot = if mark == Mark::Kept {
                                &mut truth.kept_on_moving
                            } else {
                                &mut truth.rejected_on_moving
                            };
                            slot.0 += on as usize;
                            slot.1 += 1;
                        }
                        let error = last.features.depth_of(m.keypoint).and_then(|d| {
                            let truth_img = frame.depth_true.as_ref()?;
                            let zt =
                                depth_at_raw_pixel(&camera, truth_img, kp.x as f64, kp.y as f64)?;
                            Some((d - zt).abs())
                        });
                        if let Some(e) = error {
                            match mark {
                                Mark::Kept => truth.kept_depth_errors.push(e),
                                Mark::RejectedFeature => truth.feature_depth_errors.push(e),
                                Mark::RejectedCluster => truth.cluster_depth_errors.push(e),
                            }
                        }
                    }
                    let candidate = Fig7Frame {
                        index: frame.index,
                        image: frame.gray.clone(),
                        moving: frame.moving_mask.clone(),
                        features,
                    };
                    let better = match (fig7_frame, &fig7) {
                        (Some(k), _) => k == frame.index,
                        (None, None) => true,
                        (None, Some(best)) => candidate.n_rejected() > best.n_rejected(),
                    };
                    if better {
                        fig7 = Some(candidate);
                    }
                }
            },
        );
        progress(chunk.last().map_or(0, |f| f.index + 1));
    });
    OutlierData {
        baseline: baseline.frame_stats().to_vec(),
        mcor: mcor.frame_stats().to_vec(),
        ate: (ate_of(&baseline, &gt), ate_of(&mcor, &gt)),
        fig7,
        truth,
        runs: (base_truth, mcor_truth),
    }
}

/// One row of the per-frame CSV.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FrameRow {
    /// Frame index.
    pub frame: usize,
    /// Timestamp, seconds.
    pub timestamp: f64,
    /// Baseline: tracked.
    pub orb_tracked: bool,
    /// Baseline: matches in the final pose optimization.
    pub orb_matches: usize,
    /// Baseline: inliers.
    pub orb_inliers: usize,
    /// Baseline: outliers (matches - inliers).
    pub orb_outliers: usize,
    /// MC-OR: tracked.
    pub mcor_tracked: bool,
    /// MC-OR: matches.
    pub mcor_matches: usize,
    /// MC-OR: inliers.
    pub mcor_inliers: usize,
    /// MC-OR: outliers (matches - inliers, MC-OR rejections included).
    pub mcor_outliers: usize,
    /// MC-OR: matches rejected by the CL (cluster) test.
    pub mcor_rejected_clusters: usize,
    /// MC-OR: matches rejected by the FL (feature) test.
    pub mcor_rejected_features: usize,
    /// Baseline: distance of the estimated camera centre from the true one, metres (empty
    /// when not tracked).
    pub orb_position_error: Option<f64>,
    /// MC-OR: the same.
    pub mcor_position_error: Option<f64>,
    /// Baseline: inliers on moving objects.
    pub orb_inliers_on_moving: usize,
    /// MC-OR: inliers on moving objects.
    pub mcor_inliers_on_moving: usize,
}

/// The per-frame rows (frames present in both runs).
pub fn rows(data: &OutlierData) -> Vec<FrameRow> {
    data.baseline
        .iter()
        .zip(&data.mcor)
        .enumerate()
        .map(|(i, (b, m))| FrameRow {
            frame: i,
            timestamp: b.timestamp,
            orb_tracked: b.state.is_tracked(),
            orb_matches: b.n_matches,
            orb_inliers: b.n_inliers,
            orb_outliers: b.n_outliers,
            mcor_tracked: m.state.is_tracked(),
            mcor_matches: m.n_matches,
            mcor_inliers: m.n_inliers,
            mcor_outliers: m.n_outliers,
            mcor_rejected_clusters: m.n_mcor_rejected_clusters,
            mcor_rejected_features: m.n_mcor_rejected_features,
            orb_position_error: data.runs.0.position_errors.get(i).copied().flatten(),
            mcor_position_error: data.runs.1.position_errors.get(i).copied().flatten(),
            orb_inliers_on_moving: data.runs.0.moving_inliers.get(i).copied().unwrap_or(0),
            mcor_inliers_on_moving: data.runs.1.moving_inliers.get(i).copied().unwrap_or(0),
        })
        .collect()
}

/// Mean of a per-frame count over tracked frames (0 without any).
pub fn mean_tracked(stats: &[FrameStats], f: impl Fn(&FrameStats) -> usize) -> f64 {
    let tracked: Vec<&FrameStats> = stats.iter().filter(|s| s.state.is_tracked()).collect();
    if tracked.is_empty() {
        return 0.0;
    }
    tracked.iter().map(|s| f(s) as f64).sum::<f64>() / tracked.len() as f64
}

/// Median and fraction above `threshold` metres of |Z_D - Z_true| (NaN median when empty).
pub fn error_summary(errors: &[f64], threshold: f64) -> (f64, f64) {
    if errors.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let above = errors.iter().filter(|e| **e > threshold).count();
    (
        median_abs(errors.iter().copied()),
        above as f64 / errors.len() as f64,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summaries_of_counts_and_errors() {
        let mut a = FrameStats {
            timestamp: 0.0,
            state: slam_core::system::TrackingState::Ok,
            n_keypoints: 0,
            n_matches: 10,
            n_inliers: 8,
            n_outliers: 2,
            n_tracked_map_points: 0,
            n_mcor_rejected_clusters: 0,
            n_mcor_rejected_features: 0,
            keyframe_inserted: false,
            relocalized: false,
            loop_detected: false,
            loop_closed: false,
            n_loops: 0,
            n_keyframes: 0,
            n_map_points: 0,
            time_features_ms: 0.0,
            time_tracking_ms: 0.0,
            time_mapping_ms: 0.0,
            time_ba_ms: 0.0,
            time_loop_ms: 0.0,
        };
        let mut lost = a.clone();
        lost.state = slam_core::system::TrackingState::Lost;
        lost.n_inliers = 100;
        a.n_inliers = 4;
        let stats = vec![a.clone(), lost, a];
        assert_eq!(mean_tracked(&stats, |s| s.n_inliers), 4.0);
        assert_eq!(mean_tracked(&[], |s| s.n_inliers), 0.0);
        let (median, above) = error_summary(&[0.01, 0.2, 0.03, 0.5], 0.1);
        assert_eq!((median, above), (0.2, 0.5));
        assert!(error_summary(&[], 0.1).0.is_nan());
    }
}
