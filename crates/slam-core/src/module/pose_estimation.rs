//! Pose-only optimization of a tracked frame against its matched map points (ORB-SLAM2's
//! Optimizer::PoseOptimization as called by tracking and relocalization), with the paper's two
//! techniques plugged into its hook points:
//! 1. [`measurement_for`]: the residual built for one keypoint (ORB-SLAM2: 2-D mono or 3-D
//!    stereo / RGB-D with `ur = u - bf / depth`); with AVC on, a keypoint with measured depth gets
//!    the 4-D [`VirtualCameraResidual`] instead (also in local BA, which calls this too);
//! 2. the `between_rounds` gate of [`optimize_frame_pose`], run before every optimization round
//!    with the current pose: MC-OR ([`RoundGate`], in [`crate::techniques::mcor`]) excludes observations there, and AVC
//!    re-aims every virtual camera from the current pose.
//!
//! MC-OR clusters are not stored: a map point's cluster is derived from its keyframe
//! observations when a frame is gated — each observing keyframe's keypoint back-projected with
//! its measured depth and placed with that keyframe's *current* pose (so clusters follow local
//! BA's corrections for free, and memory is what the map already holds; the transient
//! [`McorCluster`](crate::techniques::mcor::McorCluster) caps itself at [`crate::techniques::MCOR_CLUSTER_CAPACITY`] features, folding
//! older ones into the centroid's running sum). Keyframe poses do not change during a pose
//! optimization, so the clusters are built once per call and only the current frame's feature
//! moves between rounds. By default MC-OR gates pose-only optimization only (the paper: it acts
//! "before every run of the pose optimization block") as a filter before the chi2 test; its
//! readings (`McorParams::verdict`, `scope`) let its consensus keep a match the chi2 test drops
//! ([`Admission::Kept`]) and let it judge local BA's observations too
//! ([`crate::module::local_mapping`]).

use std::cell::RefCell;
use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Vector3};

use crate::camera::Camera;
use crate::data::{Features, Map, MapPointId, ScaleLevels, TrackedFrame};
use crate::optimize::{
    pose_optimization_with, Admission, Measurement, PoseObservation, PoseOptConfig,
};
use crate::techniques::mcor::{ClusterCache, Exceeded, McorVerdict, RoundGate, TappedVerdicts};
use crate::techniques::params::{AvcParams, McorParams};
use crate::techniques::rigid_consensus::{
    nested, rigid_consensus, ConsensusMatch, RigidConsensusParams,
};
use crate::techniques::{VirtualCameraRef, VirtualCameraResidual};

/// `t` with its rotation quaternion renormalised. Products of unit quaternions drift off unit
/// norm by rounding, and the constant-velocity model (`V = T_c T_l^-1`, then `V T_c`) multiplies
/// those norms frame after frame, so without this the drift grows exponentially (a quaternion of
/// norm 0.5 after ~40 frames, i.e. a scaled rotation). Every pose the system keeps goes through it.
pub fn renormalized(t: &Isometry3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(
        t.translation,
        nalgebra::UnitQuaternion::new_normalize(*t.rotation.quaternion()),
    )
}

/// The techniques switched on for a run (both `None` = ORB-SLAM2 baseline).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoiseHooks<'a> {
    /// MC-OR parameters when on.
    pub mcor: Option<&'a McorParams>,
    /// AVC parameters when on.
    pub avc: Option<&'a AvcParams>,
    /// Rigid consensus (beyond the paper) when on: gates pose-only optimization.
    pub rc: Option<&'a RigidConsensusParams>,
    /// MC-OR's clusters of the frame being tracked, shared by all its gates (the system's;
    /// `None`: each call builds its own). Only valid while the map does not change: the owner
    /// invalidates it when a frame starts.
    pub clusters: Option<&'a RefCell<ClusterCache>>,
}

/// The measurement of keypoint `i` (hook point 1). Baseline: stereo / RGB-D keypoints with a
/// right coordinate give the 3-D residual, others the 2-D one. With `hooks.avc` set, a keypoint
/// with measured depth gets the 4-D AVC residual, its virtual camera aimed from `estimate`, the
/// current estimate of the map point in this camera's coordinates (metres).
pub fn measurement_for(
    camera: &Camera,
    features: &Features,
    i: usize,
    hooks: &NoiseHooks,
    estimate: &Vector3<f64>,
) -> Measurement {
    if let Some(r) = avc_residual_for(camera, features, i, hooks, estimate) {
        return Measurement::VirtualCamera(VirtualCameraRef::single(r));
    }
    builtin_measurement(features, i)
}

/// The baseline's measurement of keypoint `i`: the 3-D residual with a right coordinate, else
/// the 2-D one.
fn builtin_measurement(features: &Features, i: usize) -> Measurement {
    let kp = &features.keypoints[i];
    match features.u_right_of(i) {
        Some(ur) => Measurement::Stereo {
            u: kp.x as f64,
            v: kp.y as f64,
            ur,
        },
        None => Measurement::Mono {
            u: kp.x as f64,
            v: kp.y as f64,
        },
    }
}

/// The AVC residual of keypoint `i` when AVC is on and the keypoint has a measured depth.
fn avc_residual_for(
    camera: &Camera,
    features: &Features,
    i: usize,
    hooks: &NoiseHooks,
    estimate: &Vector3<f64>,
) -> Option<VirtualCameraResidual> {
    let depth = avc_depth(features, i, hooks)?;
    let avc = hooks.avc?;
    let kp = &features.keypoints[i];
    VirtualCameraResidual::with_aim_from(
        camera,
        kp.x as f64,
        kp.y as f64,
        depth,
        avc.baseline,
        avc.aim,
        estimate,
    )
    .map(|r| r.with_gate(avc.gate.chi2()))
}

/// The measured depth of keypoint `i` when AVC is on and gives it its residual (a measured
/// depth, a valid baseline): exactly when [`avc_residual_for`] builds one.
fn avc_depth(features: &Features, i: usize, hooks: &NoiseHooks) -> Option<f64> {
    let avc = hooks.avc?;
    features
        .depth_of(i)
        .filter(|&depth| VirtualCameraResidual::is_defined(depth, avc.baseline))
}

/// The exact bits of a pose (translation, then quaternion), to tell whether two poses are
/// the same number for number.
fn pose_bits(t: &Isometry3<f64>) -> [u64; 7] {
    let v = t.translation.vector;
    let q = t.rotation.coords;
    [v.x, v.y, v.z, q.x, q.y, q.z, q.w].map(f64::to_bits)
}

/// Keypoints on the same moving body as a match the rigid consensus rejected: within
/// `mask_radius_px` of a rejected keypoint with depth and within `mask_depth_m` of its depth.
/// They create no map points when the frame becomes a keyframe, so that walkers who fill the
/// view do not fill the young map with points that move.
fn dynamic_mask(
    frame: &TrackedFrame,
    params: &RigidConsensusParams,
    index: &[usize],
    rejected: &[bool],
) -> Vec<bool> {
    let f = &frame.features;
    let radius = params.mask_radius_px as f32;
    let seeds: Vec<(f32, f32, f64)> = index
        .iter()
        .zip(rejected)
        .filter(|(_, &r)| r)
        .filter_map(|(&i, _)| {
            let kp = &f.keypoints[i];
            f.depth_of(i).map(|d| (kp.x, kp.y, d))
        })
        .collect();
    if seeds.is_empty() || radius <= 0.0 {
        return vec![false; f.len()];
    }
    // The seeds bucketed in square cells as wide as the radius: a keypoint looks at its own
    // cell and the eight around it.
    let cell = |v: f32| (v.max(0.0) / radius) as usize;
    let cols = seeds.iter().map(|s| cell(s.0)).max().unwrap_or(0) + 2;
    let rows = seeds.iter().map(|s| cell(s.1)).max().unwrap_or(0) + 2;
    let mut grid: Vec<Vec<usize>> = vec![Vec::new(); cols * rows];
    for (k, s) in seeds.iter().enumerate() {
        grid[cell(s.1) * cols + cell(s.0)].push(k);
    }
    let r2 = radius * radius;
    (0..f.len())
        .map(|i| {
            let kp = &f.keypoints[i];
            let Some(d) = f.depth_of(i) else {
                return false;
            };
            let (cx, cy) = (cell(kp.x), cell(kp.y));
            (cy.saturating_sub(1)..(cy + 2).min(rows))
                .flat_map(|gy| (cx.saturating_sub(1)..(cx + 2).min(cols)).map(move |gx| (gx, gy)))
                .flat_map(|(gx, gy)| &grid[gy * cols + gx])
                .any(|&k| {
                    let (x, y, ds) = seeds[k];
                    let (dx, dy) = (kp.x - x, kp.y - y);
                    dx * dx + dy * dy <= r2 && (d - ds).abs() <= params.mask_depth_m
                })
        })
        .collect()
}

/// Outcome of one pose optimization of a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PoseOptCounts {
    /// Matches that entered the optimization.
    pub n_matches: usize,
    /// Matches classified inlier at the final pose.
    pub n_inliers: usize,
    /// MC-OR: matches whose cluster failed the CL test at the last gating (before the last
    /// round), 0 when MC-OR is off.
    pub n_mcor_rejected_clusters: usize,
    /// MC-OR: matches whose own feature failed the FL test at the last gating.
    pub n_mcor_rejected_features: usize,
}

/// One match of a [`PoseOptRecord`]: what the optimizer saw and decided for it.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseOptMatch {
    /// Keypoint index in the frame.
    pub keypoint: usize,
    /// The matched map point.
    pub map_point: MapPointId,
    /// Its position (world frame, metres) as the optimizer used it.
    pub point_world: Vector3<f64>,
    /// Inlier at the final pose (not a chi2 outlier, not excluded by MC-OR).
    pub inlier: bool,
    /// MC-OR's verdict at the last gating (before the last round); `None` when MC-OR is off.
    pub mcor: Option<McorVerdict>,
    /// For an MC-OR rejection, which thresholds its metrics exceeded at that gating (none
    /// otherwise).
    pub mcor_exceeded: Exceeded,
}

/// What one call of [`optimize_frame_pose`] did, as recorded by [`tap_pose_optimizations`]:
/// the data behind the paper's Fig. 7 (rejected features of a frame) and Table II (error terms
/// of the observations at the estimated pose), which the system's per-frame statistics only
/// count and which tracking erases (outliers are unmatched once a frame is done).
#[derive(Clone, Debug, PartialEq)]
pub struct PoseOptRecord {
    /// Frame counter of the optimized frame.
    pub frame_id: u64,
    /// The optimized pose (world -> camera).
    pub tcw: Isometry3<f64>,
    /// Every match that entered the optimization, in keypoint order.
    pub matches: Vec<PoseOptMatch>,
}

thread_local! {
    /// Records of the active [`tap_pose_optimizations`] on this thread, if any.
    static POSE_OPT_TAP: RefCell<Option<Vec<PoseOptRecord>>> = const { RefCell::new(None) };
}

/// Restores the enclosing tap (if any) when a tapped call ends, even by unwinding.
struct TapGuard(Option<Vec<PoseOptRecord>>);

impl Drop for TapGuard {
    fn drop(&mut self) {
        let outer = self.0.take();
        POSE_OPT_TAP.with(|t| *t.borrow_mut() = outer);
    }
}

/// Analysis tap: runs `f` and returns, with its result, a record of every [`optimize_frame_pose`]
/// call it made on this thread (in call order; the last record of a tracked frame is its final,
/// local-map optimization). The system runs synchronously on the caller's thread, so wrapping
/// `System::track` captures that frame's optimizations. Costs one thread-local check per
/// optimization when no tap is active. Nested taps each see only their own calls.
pub fn tap_pose_optimizations<R>(f: impl FnOnce() -> R) -> (R, Vec<PoseOptRecord>) {
    let outer = POSE_OPT_TAP.with(|t| t.borrow_mut().replace(Vec::new()));
    let guard = TapGuard(outer);
    let r = f();
    let records = POSE_OPT_TAP
        .with(|t| t.borrow_mut().take())
        .unwrap_or_default();
    drop(guard);
    (r, records)
}

/// The 2-D/3-D correspondences of the matched keypoints of `features` (`matches[i]`: the map
/// point keypoint `i` matched) for [`crate::solve::pose_ransac`], with the keypoint index of
/// each.
pub(crate) fn pose_correspondences(
    matches: &[Option<MapPointId>],
    features: &Features,
    map: &Map,
    camera: &Camera,
    levels: &ScaleLevels,
) -> (Vec<crate::solve::PoseCorrespondence>, Vec<usize>) {
    let mut corr = Vec::new();
    let mut corr_idx = Vec::new();
    for (i, m) in matches.iter().enumerate() {
        let Some(mp) = m.and_then(|id| map.map_point(id)) else {
            continue;
        };
        let kp = &features.keypoints[i];
        corr.push(crate::solve::PoseCorrespondence {
            point_world: mp.position,
            u: kp.x as f64,
            v: kp.y as f64,
            point_camera: features.unproject_camera(i, camera),
            sigma2: levels.sigma2(kp.octave),
        });
        corr_idx.push(i);
    }
    (corr, corr_idx)
}

/// Runs `f` with the analysis tap of this thread (if any) suspended: optimizations that are not
/// the tracking of the frame, such as loop verification, stay out of the frame's record.
pub(crate) fn without_tap<R>(f: impl FnOnce() -> R) -> R {
    let outer = POSE_OPT_TAP.with(|t| t.borrow_mut().take());
    let guard = TapGuard(outer);
    let r = f();
    drop(guard);
    r
}

fn tap_active() -> bool {
    POSE_OPT_TAP.with(|t| t.borrow().is_some())
}

fn tap_push(record: PoseOptRecord) {
    POSE_OPT_TAP.with(|t| {
        if let Some(v) = t.borrow_mut().as_mut() {
            v.push(record);
        }
    });
}

/// What [`frame_observations`] builds.
struct FrameObservations {
    /// One per match, in keypoint order.
    obs: Vec<PoseObservation>,
    /// Each observation's keypoint.
    index: Vec<usize>,
    /// The AVC residuals, built together.
    avc: Arc<[VirtualCameraResidual]>,
    /// Per AVC residual: its observation and the keypoint's depth.
    avc_at: Vec<(usize, f64)>,
}

/// The observations of `frame`'s matches for pose optimization, in keypoint order, with their
/// keypoint indices (each match's outlier flag cleared). Under AVC, a keypoint with depth gets a
/// virtual-camera residual aimed from `initial`; those residuals are built into one set (one
/// allocation), returned with where each sits (`(observation, depth)`).
fn frame_observations(
    frame: &mut TrackedFrame,
    map: &Map,
    camera: &Camera,
    levels: &ScaleLevels,
    hooks: &NoiseHooks,
    initial: &Isometry3<f64>,
) -> FrameObservations {
    let mut obs = Vec::with_capacity(frame.len());
    let mut index = Vec::with_capacity(frame.len());
    // The observations that get an AVC residual, with their keypoint's depth: their residuals
    // are built below into one set, in place (one allocation, nothing copied).
    let mut avc_at: Vec<(usize, f64)> = Vec::new();
    for i in 0..frame.len() {
        let Some(mp) = frame.map_points[i].and_then(|id| map.map_point(id)) else {
            continue;
        };
        frame.outliers[i] = false;
        let measurement = match avc_depth(&frame.features, i, hooks) {
            Some(depth) => {
                avc_at.push((obs.len(), depth));
                // Replaced by the residual's place in the set below.
                Measurement::Mono { u: 0.0, v: 0.0 }
            }
            None => builtin_measurement(&frame.features, i),
        };
        obs.push(PoseObservation {
            point_world: mp.position,
            measurement,
            inv_sigma2: levels.inv_sigma2(frame.features.keypoints[i].octave),
        });
        index.push(i);
    }
    let avc: Arc<[VirtualCameraResidual]> = match hooks.avc {
        Some(params) => avc_at
            .iter()
            .map(|&(k, depth)| {
                let kp = &frame.features.keypoints[index[k]];
                let estimate = (*initial * Point3::from(obs[k].point_world)).coords;
                VirtualCameraResidual::with_aim_from(
                    camera,
                    kp.x as f64,
                    kp.y as f64,
                    depth,
                    params.baseline,
                    params.aim,
                    &estimate,
                )
                .expect("avc_depth admits what the residual accepts")
                .with_gate(params.gate.chi2())
            })
            .collect(),
        None => Arc::new([]),
    };
    for (n, &(k, _)) in avc_at.iter().enumerate() {
        let r = VirtualCameraRef::new(&avc, n).expect("one residual per AVC observation");
        obs[k].measurement = Measurement::VirtualCamera(r);
    }
    FrameObservations {
        obs,
        index,
        avc,
        avc_at,
    }
}

/// The matches as rigid consensus reads them: map point, back-projection, the baseline's
/// measurement (aimed from `initial`) and how established the point is.
fn consensus_matches(
    frame: &TrackedFrame,
    map: &Map,
    camera: &Camera,
    index: &[usize],
    obs: &[PoseObservation],
    initial: &Isometry3<f64>,
) -> Vec<ConsensusMatch> {
    index
        .iter()
        .zip(obs)
        .map(|(&i, o)| {
            let m = map.map_point(frame.map_points[i].expect("matched"));
            let estimate = (*initial * Point3::from(o.point_world)).coords;
            ConsensusMatch {
                map_point: o.point_world,
                point_camera: frame.features.unproject_camera(i, camera),
                measurement: measurement_for(
                    camera,
                    &frame.features,
                    i,
                    &NoiseHooks::default(),
                    &estimate,
                ),
                inv_sigma2: o.inv_sigma2,
                keyframes: m.map_or(0, |m| m.observations.len() as u32),
                frames_found: m.map_or(0, |m| m.n_found),
            }
        })
        .collect()
}

/// Rigid consensus's veto of one round: matches outside the consensus (`outside`) excluded while
/// `active` (its first rounds), every match free after.
fn apply_veto(excluded: &mut [Admission], outside: &[bool], active: bool) {
    if active {
        for (a, &o) in excluded.iter_mut().zip(outside) {
            *a = if o {
                Admission::Excluded
            } else {
                Admission::Free
            };
        }
    } else {
        excluded.fill(Admission::Free);
    }
}

/// What the tap records of each match: keypoint, map point, inlier at the final pose and MC-OR's
/// last verdict with the thresholds a rejection exceeded.
fn record_matches(
    frame: &TrackedFrame,
    index: &[usize],
    obs: &[PoseObservation],
    inliers: &[bool],
    last_verdicts: Option<TappedVerdicts>,
) -> Vec<PoseOptMatch> {
    index
        .iter()
        .enumerate()
        .map(|(k, &i)| PoseOptMatch {
            keypoint: i,
            map_point: frame.map_points[i].expect("matched"),
            point_world: obs[k].point_world,
            inlier: inliers[k],
            mcor: last_verdicts.as_ref().map(|v| v[k].0),
            mcor_exceeded: last_verdicts
                .as_ref()
                .map_or_else(Exceeded::default, |v| v[k].1),
        })
        .collect()
}

/// Optimizes `frame.tcw` (must be set) against its matched map points and sets
/// `frame.outliers`. Returns the match / inlier counts. With fewer than 3 matches the pose is
/// left unchanged (ORB-SLAM2 returns 0 inliers then).
pub fn optimize_frame_pose(
    frame: &mut TrackedFrame,
    map: &Map,
    camera: &Camera,
    levels: &ScaleLevels,
    cfg: &PoseOptConfig,
    hooks: &NoiseHooks,
) -> PoseOptCounts {
    let Some(initial) = frame.tcw else {
        return PoseOptCounts::default();
    };
    let FrameObservations {
        obs,
        index,
        avc,
        avc_at,
    } = frame_observations(frame, map, camera, levels, hooks, &initial);
    if obs.len() < 3 {
        return PoseOptCounts {
            n_matches: obs.len(),
            ..PoseOptCounts::default()
        };
    }
    // Rigid consensus (beyond the paper): the matches one rigid camera motion explains. Its
    // hypotheses must beat the pose the optimizer solves from the motion prior (and the prior
    // itself); when one does, the optimization runs again from the consensus pose with the
    // matches outside the consensus kept out of its first rounds.
    let rc_matches: Option<Vec<ConsensusMatch>> = hooks.rc.map(|_| {
        frame.dynamic.clear();
        consensus_matches(frame, map, camera, &index, &obs, &initial)
    });
    // MC-OR clusters (the map is fixed during this call; the frame's own cache when the system
    // keeps one, shared with the frame's other gates) and the current features.
    let mut own_clusters = None;
    let mut shared_clusters = hooks.clusters.map(|c| c.borrow_mut());
    let clusters: &mut ClusterCache = match shared_clusters.as_deref_mut() {
        Some(c) => c,
        None => own_clusters.get_or_insert_with(ClusterCache::new),
    };
    // MC-OR's gate of this call: the matches' clusters, prepared once, and its verdicts kept
    // across the rounds and the gates of this frame.
    let mcor = hooks
        .mcor
        .map(|params| RoundGate::prepare(clusters, map, camera, frame, &index, params));
    let shared: &ClusterCache = clusters;
    let tapped = tap_active();
    let rc_veto_rounds = hooks.rc.map_or(0, |p| p.veto_rounds);
    // One pose optimization from `start`; `veto` (one per match) keeps matches out of the
    // first `veto_rounds` rounds. Returned with MC-OR's outcome of its last round (rejected
    // clusters and features, and the verdicts when tapped), so that the counts reported are
    // those of the solution kept.
    // The pose the virtual cameras were last aimed from: the residuals were built aimed from
    // `initial`, so the first round from `initial` need not aim them again (the same
    // operations on the same bits).
    let aimed_from = std::cell::Cell::new(Some(pose_bits(&initial)));
    let optimize = |start: &Isometry3<f64>, veto: Option<&[bool]>| {
        let mut last_gate = (0, 0);
        let mut last_verdicts: Option<TappedVerdicts> = None;
        // Hook point 2, before every round with the latest pose: re-aim the virtual cameras,
        // then re-run MC-OR (an observation rejected at a poor early pose may come back).
        let mut gate = |round: usize, pose: &Isometry3<f64>, excluded: &mut [Admission]| {
            if aimed_from.get() != Some(pose_bits(pose)) {
                for (r, &(k, _)) in avc.iter().zip(&avc_at) {
                    r.aim_at(&(pose * Point3::from(obs[k].point_world)).coords);
                }
                aimed_from.set(Some(pose_bits(pose)));
            }
            if let Some(out) = veto {
                apply_veto(excluded, out, round < rc_veto_rounds);
            }
            if let Some(mcor) = &mcor {
                let (counts, verdicts) = mcor.gate(shared, &pose.inverse(), excluded, tapped);
                last_gate = counts;
                last_verdicts = verdicts;
            }
        };
        let result = pose_optimization_with(camera, start, &obs, cfg, &mut gate);
        (result, last_gate, last_verdicts)
    };
    let consensus = match (hooks.rc, &rc_matches) {
        (Some(params), Some(matches)) => {
            let key = frame.id.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ obs.len() as u64;
            rigid_consensus(camera, params, &initial, matches, key).map(|c| (params, matches, c))
        }
        _ => None,
    };
    let (result, last_gate, last_verdicts) = match consensus {
        None => optimize(&initial, None),
        Some((params, matches, c)) => {
            let outside: Vec<bool> = c.inlier.iter().map(|&i| !i).collect();
            let mut solved = optimize(&c.tcw, Some(&outside));
            if !c.prior_won {
                // A drawn hypothesis beat the prior: solve from the prior as well, and keep that
                // solution when it explains what the consensus solution explains and more.
                let base = optimize(&initial, None);
                if nested(params, matches, &solved.0.inliers, &base.0.inliers) {
                    solved = base;
                }
            }
            if params.mask_radius_px > 0.0 && c.share < params.mask_below_share {
                // Seeds of the mask: matches outside the consensus that the final pose
                // rejects too.
                let seeds: Vec<bool> = outside
                    .iter()
                    .zip(&solved.0.inliers)
                    .map(|(&o, &inlier)| o && !inlier)
                    .collect();
                frame.dynamic = dynamic_mask(frame, params, &index, &seeds);
            }
            solved
        }
    };
    if let Some(mcor) = mcor {
        mcor.finish(clusters);
    }
    frame.tcw = Some(renormalized(&result.pose));
    for (k, &i) in index.iter().enumerate() {
        frame.outliers[i] = !result.inliers[k];
    }
    if tapped {
        tap_push(PoseOptRecord {
            frame_id: frame.id,
            tcw: frame.tcw.expect("just set"),
            matches: record_matches(frame, &index, &obs, &result.inliers, last_verdicts),
        });
    }
    PoseOptCounts {
        n_matches: obs.len(),
        n_inliers: result.n_inliers,
        n_mcor_rejected_clusters: last_gate.0,
        n_mcor_rejected_features: last_gate.1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::KeyFrameId;
    use crate::module::test_map::{scene, scene_with, shifted, twc};
    use crate::techniques::mcor::{
        frame_sightings, map_point_cluster, mcor_frame_gate, mcor_frame_gate_with, mcor_gate,
        McorCluster, McorMatch,
    };
    use crate::techniques::params::{ClusterViews, Sightings, Verdict};
    use crate::techniques::{AvcGate, FrameView, FRAME_VIEW_SOURCE_BIT};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn start_pose() -> Isometry3<f64> {
        (Isometry3::translation(0.02, -0.01, 0.015) * twc(3)).inverse()
    }

    /// `frame`'s pose optimized from [`start_pose`] with `hooks` and the default settings.
    fn optimize_from_start(
        frame: &mut TrackedFrame,
        map: &Map,
        camera: &Camera,
        hooks: &NoiseHooks,
    ) -> PoseOptCounts {
        frame.tcw = Some(start_pose());
        let levels = ScaleLevels::new(8, 1.2);
        optimize_frame_pose(
            frame,
            map,
            camera,
            &levels,
            &PoseOptConfig::default(),
            hooks,
        )
    }

    fn error_m(tcw: &Isometry3<f64>) -> f64 {
        (tcw.inverse().translation.vector - twc(3).translation.vector).norm()
    }

    #[test]
    fn mcor_rejects_gross_depth_features_before_optimization() {
        let gross = [3, 17, 40, 77, 101];
        let (camera, map, mut frame, _) = scene(&gross);
        let params = McorParams::default();
        let hooks = NoiseHooks {
            mcor: Some(&params),
            avc: None,
            rc: None,
            clusters: None,
        };
        let counts = optimize_from_start(&mut frame, &map, &camera, &hooks);
        assert_eq!(counts.n_matches, 120);
        assert_eq!(counts.n_mcor_rejected_clusters, 0);
        assert_eq!(counts.n_mcor_rejected_features, gross.len());
        for &g in &gross {
            assert!(frame.outliers[g], "gross feature {g} must be an outlier");
        }
        assert!(counts.n_inliers >= 110, "{counts:?}");
        assert!(error_m(&frame.tcw.unwrap()) < 0.005);
        // The analysis helper reproduces the gate at the final pose.
        let (index, outcome) = mcor_frame_gate(&frame, &map, &camera, &params, &frame.tcw.unwrap());
        assert_eq!(index.len(), 120);
        for &g in &gross {
            assert_eq!(outcome.verdicts[g], McorVerdict::RejectedFeature);
        }
        assert_eq!(outcome.n_rejected_features, gross.len());
    }

    #[test]
    fn mcor_rejects_the_cluster_of_a_drifted_map_point() {
        let (camera, mut map, frame, _) = scene(&[]);
        let id = frame.map_points[10].unwrap();
        map.map_point_mut(id).unwrap().position += Vector3::new(0.0, 0.6, 0.0);
        let (_, outcome) = mcor_frame_gate(
            &frame,
            &map,
            &camera,
            &McorParams::default(),
            &twc(3).inverse(),
        );
        assert_eq!(outcome.verdicts[10], McorVerdict::RejectedCluster);
        assert_eq!(
            (outcome.n_rejected_clusters, outcome.n_rejected_features),
            (1, 0)
        );
        // A cluster holds one feature per observing keyframe with depth.
        let cluster = map_point_cluster(
            &map,
            frame.map_points[0].unwrap(),
            &camera,
            ClusterViews::Keyframes,
        );
        assert_eq!(cluster.len(), 3);
    }

    #[test]
    fn the_frame_gate_over_cached_clusters_is_the_gate_over_rebuilt_clusters() {
        // Points 0-29 moved by up to 0.9 m since the keyframes saw them; each has 0-45
        // frame views (so rings fold).
        let (camera, mut map, frame, _) =
            scene_with(|k| if k < 30 { 0.03 * k as f64 } else { 0.0 });
        let kfs: Vec<_> = map.keyframes().map(|k| k.id).collect();
        for i in 0..frame.len() {
            let (Some(id), Some(pc)) = (
                frame.map_points[i],
                frame.features.unproject_camera(i, &camera),
            ) else {
                continue;
            };
            for f in 0..(i * 7 % 46) as u64 {
                let r = kfs[(i + f as usize) % kfs.len()];
                let tkw = twc(r.index() % 3).inverse();
                let tcw = twc(3).inverse();
                let view = FrameView::new(100 + f, &tcw, r, &tkw, pc * (1.0 + 0.001 * f as f64));
                map.map_point_mut(id).unwrap().views.push(view.unwrap());
            }
        }
        let mut cache = ClusterCache::new();
        for views in [ClusterViews::Keyframes, ClusterViews::EveryFrame] {
            for depth_normalised in [false, true] {
                for tau in [0.02, 0.1, 0.3, 0.7] {
                    let params = McorParams {
                        cluster_views: views,
                        depth_normalised,
                        tau_mf: tau,
                        tau_gf: tau,
                        tau_mg: tau * 0.7,
                        view_stride: 1,
                        ..McorParams::default()
                    };
                    let tcw = twc(3).inverse();
                    let (index, outcome) =
                        mcor_frame_gate_with(&frame, &map, &camera, &params, &tcw, &mut cache);
                    let clusters: Vec<McorCluster> = index
                        .iter()
                        .map(|&i| {
                            map_point_cluster(&map, frame.map_points[i].unwrap(), &camera, views)
                        })
                        .collect();
                    let matches: Vec<McorMatch> = index
                        .iter()
                        .zip(&clusters)
                        .map(|(&i, c)| McorMatch {
                            cluster: c,
                            map_point: map
                                .map_point(frame.map_points[i].unwrap())
                                .unwrap()
                                .position,
                            point_camera: frame.features.unproject_camera(i, &camera),
                        })
                        .collect();
                    let expected = mcor_gate(&params, &tcw.inverse(), &matches);
                    assert_eq!(
                        outcome, expected,
                        "{views:?} normalised {depth_normalised} tau {tau}"
                    );
                    // Both kinds of rejection occur somewhere in the sweep of thresholds.
                    assert!(outcome.n_kept() > 0);
                }
            }
        }
    }

    #[test]
    fn every_frame_clusters_reject_a_point_that_moved_and_stayed_where_keyframes_did_not() {
        // Point 10 moved 0.6 m (along the current ray) after the keyframes saw it, and 20
        // tracked frames since have seen it at its new place: a person who walked and stopped.
        let (camera, mut map, frame, _) = scene_with(|k| if k == 10 { 0.6 } else { 0.0 });
        let id = frame.map_points[10].unwrap();
        let moved = frame.features.unproject_camera(10, &camera).unwrap();
        let kf2 = map.keyframes().nth(2).unwrap().id;
        let tkw = twc(2).inverse();
        for f in 10..30 {
            let view = FrameView::new(f, &twc(3).inverse(), kf2, &tkw, moved).unwrap();
            map.map_point_mut(id).unwrap().views.push(view);
        }
        let gate = |views| {
            let params = McorParams {
                cluster_views: views,
                ..McorParams::default()
            };
            mcor_frame_gate(&frame, &map, &camera, &params, &twc(3).inverse()).1
        };
        // Keyframes alone: M, G and the current feature are close enough (0.6 m < tau_MF 0.7,
        // |M - G| 0.15 m < tau_MG 0.5): the moved point passes as static.
        let kf = gate(ClusterViews::Keyframes);
        assert_eq!(kf.verdicts[10], McorVerdict::Kept);
        assert_eq!(kf.n_kept(), 120);
        // Every frame: G follows the 20 views to 0.52 m from M, beyond tau_MG.
        let every = gate(ClusterViews::EveryFrame);
        assert_eq!(every.verdicts[10], McorVerdict::RejectedCluster);
        assert_eq!(
            (every.n_rejected_clusters, every.n_rejected_features),
            (1, 0)
        );
        let cluster = map_point_cluster(&map, id, &camera, ClusterViews::EveryFrame);
        assert_eq!(cluster.total_count(), 3 + 20);
        let m = map.map_point(id).unwrap().position;
        let g = cluster.centroid().unwrap();
        // G: 3 keyframe features at M (up to pixel noise), 20 views where the point moved.
        let d = ((twc(3) * Point3::from(moved)).coords - m).norm();
        assert!(d > 0.6 && d < 0.7, "{d}");
        let expected = 20.0 * d / 23.0;
        assert!(
            ((m - g).norm() - expected).abs() < 0.005,
            "{}",
            (m - g).norm()
        );
    }

    #[test]
    fn rc_vetoes_its_rounds_and_masks_from_the_final_verdict() {
        // Five matches with depth 1.5 m too far. Far away that error moves the stereo
        // coordinate by less than ORB-SLAM2's gate, and the optimizer alone keeps such a match.
        let gross = [3, 17, 40, 77, 101];
        let run = |rc: Option<&RigidConsensusParams>| {
            let (camera, map, mut frame, _) = scene(&gross);
            let hooks = NoiseHooks {
                mcor: None,
                avc: None,
                rc,
                clusters: None,
            };
            let counts = optimize_from_start(&mut frame, &map, &camera, &hooks);
            (frame, counts)
        };
        let (plain, _) = run(None);
        let kept_by_the_optimizer: Vec<usize> = gross
            .iter()
            .copied()
            .filter(|&g| !plain.outliers[g])
            .collect();
        assert!(!kept_by_the_optimizer.is_empty() && kept_by_the_optimizer.len() < gross.len());
        // The consensus holds 115 of 120 matches here: the default draws no mask (a static
        // frame's rejected matches are not a body); a share gate above 1 draws it always.
        let always = 1.01;
        let default_gate = RigidConsensusParams::default().mask_below_share;
        for (veto_rounds, mask_radius_px, mask_below_share) in [
            (4, 24.0, always),
            (1, 24.0, always),
            (1, 16.0, always),
            (1, 0.0, always),
            (1, 16.0, default_gate),
        ] {
            let params = RigidConsensusParams {
                veto_rounds,
                mask_radius_px,
                mask_below_share,
                ..RigidConsensusParams::default()
            };
            let (frame, counts) = run(Some(&params));
            let case =
                format!("veto {veto_rounds}, mask {mask_radius_px} below share {mask_below_share}");
            let kept: Vec<usize> = gross
                .iter()
                .copied()
                .filter(|&g| !frame.outliers[g])
                .collect();
            if veto_rounds >= PoseOptConfig::default().rounds {
                // Vetoed in every round: only what both the consensus and the optimizer keep.
                assert!(
                    kept.iter().all(|g| kept_by_the_optimizer.contains(g)),
                    "{case}"
                );
            } else {
                // Vetoed in the first round only: the optimizer's own test decides after it.
                assert_eq!(kept, kept_by_the_optimizer, "{case}");
            }
            assert!(counts.n_inliers >= 110, "{case}: {counts:?}");
            assert!(error_m(&frame.tcw.unwrap()) < 0.005, "{case}");
            // The mask: every match outside the consensus that the final pose rejects too
            // seeds it (and covers its own keypoint); a radius of 0 turns it off, and so does
            // a consensus that holds more than `mask_below_share` of the weight.
            let masked: Vec<usize> = (0..frame.dynamic.len())
                .filter(|&i| frame.dynamic[i])
                .collect();
            if mask_radius_px > 0.0 && mask_below_share > 1.0 {
                for g in gross.iter().filter(|g| !kept.contains(g)) {
                    assert!(masked.contains(g), "{case}: {g} not masked ({masked:?})");
                }
                for g in &kept {
                    assert!(!masked.contains(g), "{case}: kept {g} masked");
                }
                assert!(masked.len() < 40, "{case}: {} masked", masked.len());
            } else {
                assert!(masked.is_empty(), "{case}: {masked:?}");
            }
        }
    }

    #[test]
    fn the_dynamic_mask_covers_exactly_the_keypoints_near_a_rejected_match_in_image_and_depth() {
        // 120 keypoints spread over the image at 1.5-4 m; the mask, bucketed in cells, must
        // agree with its definition checked against every rejected match, for radii that make
        // cells smaller and larger than the spacing of the keypoints.
        let (_, _, frame, _) = scene(&[]);
        let index: Vec<usize> = (0..frame.len()).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let rejected: Vec<bool> = index.iter().map(|_| rng.random_bool(0.2)).collect();
        let f = &frame.features;
        for (radius, depth_m) in [(8.0, 0.15), (16.0, 0.15), (60.0, 0.3), (200.0, 0.05)] {
            let params = RigidConsensusParams {
                mask_radius_px: radius,
                mask_depth_m: depth_m,
                ..RigidConsensusParams::default()
            };
            let mask = dynamic_mask(&frame, &params, &index, &rejected);
            let expected: Vec<bool> = (0..f.len())
                .map(|i| {
                    let kp = &f.keypoints[i];
                    let d = f.depth_of(i).expect("every keypoint has depth");
                    (0..f.len()).any(|j| {
                        let s = &f.keypoints[j];
                        let r2 = (kp.x - s.x).powi(2) + (kp.y - s.y).powi(2);
                        rejected[j]
                            && r2 <= (radius * radius) as f32
                            && (d - f.depth_of(j).expect("depth")).abs() <= depth_m
                    })
                })
                .collect();
            assert_eq!(mask, expected, "radius {radius} px, {depth_m} m");
            // Every rejected keypoint covers itself; at 200 px with 5 cm some keypoints are
            // masked by a rejected neighbour, not only by themselves.
            assert!(index.iter().all(|&i| !rejected[i] || mask[i]));
            let by_neighbours = (0..f.len()).filter(|&i| mask[i] && !rejected[i]).count();
            if radius >= 60.0 {
                assert!(by_neighbours > 0, "radius {radius}: no neighbour masked");
            }
        }
        // No rejected match: nothing masked.
        let params = RigidConsensusParams::default();
        let none = vec![false; index.len()];
        assert!(dynamic_mask(&frame, &params, &index, &none)
            .iter()
            .all(|&m| !m));
    }

    #[test]
    fn avc_builds_four_dof_residuals_and_recovers_the_pose() {
        let (camera, map, mut frame, points) = scene(&[]);
        let avc = AvcParams::default();
        let hooks = NoiseHooks {
            mcor: None,
            avc: Some(&avc),
            rc: None,
            clusters: None,
        };
        let estimate = (start_pose() * Point3::from(points[0])).coords;
        let m = measurement_for(&camera, &frame.features, 0, &hooks, &estimate);
        assert_eq!(m.dof(), 4);
        let base = measurement_for(
            &camera,
            &frame.features,
            0,
            &NoiseHooks::default(),
            &estimate,
        );
        assert_eq!(base.dof(), 3);
        let counts = optimize_from_start(&mut frame, &map, &camera, &hooks);
        assert!(counts.n_inliers >= 115, "{counts:?}");
        assert!(error_m(&frame.tcw.unwrap()) < 0.005);
    }

    #[test]
    fn tap_records_the_gate_verdicts_and_inliers() {
        let gross = [3, 17, 40];
        let (camera, map, mut frame, _) = scene(&gross);
        frame.tcw = Some(start_pose());
        let params = McorParams::default();
        let hooks = NoiseHooks {
            mcor: Some(&params),
            avc: None,
            rc: None,
            clusters: None,
        };
        let levels = ScaleLevels::new(8, 1.2);
        let cfg = PoseOptConfig::default();
        // Untapped calls record nothing, and a tap sees only its own calls.
        let (counts, records) = tap_pose_optimizations(|| {
            let c = optimize_frame_pose(&mut frame, &map, &camera, &levels, &cfg, &hooks);
            let (_, inner) = tap_pose_optimizations(|| ());
            assert!(inner.is_empty());
            c
        });
        assert_eq!(records.len(), 1);
        let r = &records[0];
        assert_eq!(r.frame_id, frame.id);
        assert_eq!(r.tcw, frame.tcw.unwrap());
        assert_eq!(r.matches.len(), counts.n_matches);
        assert_eq!(
            r.matches.iter().filter(|m| m.inlier).count(),
            counts.n_inliers
        );
        let rejected: Vec<usize> = r
            .matches
            .iter()
            .filter(|m| m.mcor == Some(McorVerdict::RejectedFeature))
            .map(|m| m.keypoint)
            .collect();
        assert_eq!(rejected, gross);
        // Each rejection names the thresholds it exceeded; a kept match names none.
        for m in &r.matches {
            assert_eq!(m.mcor_exceeded.any(), m.mcor != Some(McorVerdict::Kept));
            assert!(
                !m.mcor_exceeded.tau_mg,
                "a feature rejection is FL: tau_MF, tau_GF"
            );
        }
        for m in &r.matches {
            assert_eq!(frame.outliers[m.keypoint], !m.inlier);
        }
        // Without MC-OR the verdicts are absent; after the tap nothing is recorded.
        let (_, records) = tap_pose_optimizations(|| {
            optimize_frame_pose(
                &mut frame,
                &map,
                &camera,
                &levels,
                &cfg,
                &NoiseHooks::default(),
            )
        });
        assert!(records[0].matches.iter().all(|m| m.mcor.is_none()));
        assert!(!tap_active());
    }

    /// The raw chi2 of keypoint `k`'s baseline residual at `tcw` (octave 0: unit weight).
    fn baseline_chi2(frame: &TrackedFrame, map: &Map, camera: &Camera, k: usize) -> f64 {
        let mp = map.map_point(frame.map_points[k].unwrap()).unwrap();
        let p_c = (frame.tcw.unwrap() * Point3::from(mp.position)).coords;
        let block = builtin_measurement(&frame.features, k)
            .evaluate(camera, &p_c)
            .unwrap();
        block.residual.norm_squared()
    }

    #[test]
    fn consensus_keeps_a_match_whose_cluster_agrees_although_its_chi2_exceeds_the_gate() {
        let (camera, map, frame, _) = scene(&[]);
        // 12 px off along the row: a reprojection error far above the gate, a back-projection
        // a few centimetres from the map point (well inside MC-OR's 0.7 m).
        let moved = [5, 9];
        let frame = shifted(&frame, &camera, &moved, 12.0);
        let filter = McorParams::default();
        let consensus = McorParams {
            verdict: Verdict::Consensus,
            ..McorParams::default()
        };
        // The scene's clusters hold three keyframe sightings: one more than a young cluster.
        let young = McorParams {
            consensus_min_sightings: 4,
            ..consensus.clone()
        };
        for (params, kept) in [(&filter, false), (&consensus, true), (&young, false)] {
            let mut f = frame.clone();
            let hooks = NoiseHooks {
                mcor: Some(params),
                ..NoiseHooks::default()
            };
            let counts = optimize_from_start(&mut f, &map, &camera, &hooks);
            assert!(error_m(&f.tcw.unwrap()) < 0.01, "{params:?}");
            for &k in &moved {
                let chi2 = baseline_chi2(&f, &map, &camera, k);
                assert!(chi2 > 7.815, "match {k}: chi2 {chi2}");
                assert_eq!(!f.outliers[k], kept, "match {k} under {params:?}");
            }
            assert_eq!(counts.n_mcor_rejected_features, 0);
        }
    }

    #[test]
    fn all_sightings_put_a_sighting_the_chi2_test_rejected_in_its_cluster() {
        let (camera, map, frame, _) = scene(&[]);
        let mut f = shifted(&frame, &camera, &[7], 12.0);
        let filter = McorParams::default();
        let hooks = NoiseHooks {
            mcor: Some(&filter),
            ..NoiseHooks::default()
        };
        optimize_from_start(&mut f, &map, &camera, &hooks);
        assert!(f.outliers[7], "the shifted match is a chi2 outlier");
        assert!(!f.outliers[8]);
        f.reference_kf = Some(KeyFrameId(2));
        let source = FRAME_VIEW_SOURCE_BIT | f.id;
        for (sightings, outlier_joins) in [(Sightings::Inliers, false), (Sightings::All, true)] {
            let params = McorParams {
                sightings,
                ..McorParams::default()
            };
            let mut m = map.clone();
            for (id, view) in frame_sightings(&f, &m, &camera, &params) {
                m.map_point_mut(id).unwrap().views.push(view);
            }
            let holds = |k: usize| {
                map_point_cluster(&m, f.map_points[k].unwrap(), &camera, params.cluster_views)
                    .features()
                    .any(|c| c.source() == source)
            };
            assert_eq!(holds(7), outlier_joins, "{sightings:?}");
            assert!(holds(8), "an inlier's sighting joins under {sightings:?}");
        }
    }

    #[test]
    fn the_three_dof_gate_reading_gates_avc_at_orb_slam2s_stereo_gate() {
        let (camera, map, frame, points) = scene(&[]);
        let estimate = (start_pose() * Point3::from(points[0])).coords;
        for (gate, chi2) in [(AvcGate::FourDof, 9.488), (AvcGate::ThreeDof, 7.815)] {
            let avc = AvcParams {
                gate,
                ..AvcParams::default()
            };
            let hooks = NoiseHooks {
                avc: Some(&avc),
                ..NoiseHooks::default()
            };
            let m = measurement_for(&camera, &frame.features, 0, &hooks, &estimate);
            assert_eq!(m.dof(), 4);
            assert_eq!(m.chi2_threshold(), chi2);
            assert_eq!(m.huber_delta(), chi2.sqrt());
            // The pose optimization classifies by that gate: under the tap, every match's
            // inlier flag is its AVC chi2 against it.
            let mut f = frame.clone();
            let (_, records) = tap_pose_optimizations(|| {
                optimize_from_start(&mut f, &map, &camera, &hooks);
            });
            let record = records.last().unwrap();
            let tcw = record.tcw;
            for r in &record.matches {
                let p_c = (tcw * Point3::from(r.point_world)).coords;
                let m = measurement_for(&camera, &f.features, r.keypoint, &hooks, &p_c);
                let c = m.evaluate(&camera, &p_c).unwrap().residual.norm_squared();
                // Aimed from the final pose rather than the last round's start: equal away
                // from the gate.
                if (c - chi2).abs() > 0.5 {
                    assert_eq!(r.inlier, c <= chi2, "chi2 {c} against {chi2}");
                }
            }
        }
    }
}
