//! MC-OR's hook into pose-only optimization, and the gate over a frame's matches as the
//! analyses run it. [`RoundGate`] is what `optimize_frame_pose` calls before every round: the
//! verdict of each match at the round's pose (Algorithm 1 over prepared clusters), and what the
//! verdict admits ([`admission`]: excluded, left to the chi2 test, or, under `verdict =
//! "consensus"`, kept). [`frame_sightings`] are the views a tracked frame adds to its points'
//! clusters (the every-frame reading, `sightings`); [`map_point_cluster`] and
//! [`mcor_frame_gate`] the same clusters and verdicts built directly from the map, for the
//! analyses and as the reference the cache is checked against.

use std::cell::RefCell;

use nalgebra::{Isometry3, Vector3};

use super::cache::ClusterCache;
use super::cluster::{ClusterFeature, Exceeded, McorCluster, McorOutcome, McorVerdict};
use super::prepared::{gate_point, GateMemo, PreparedCluster};
use crate::camera::Camera;
use crate::data::{FrameView, Map, MapPointId, TrackedFrame};
use crate::optimize::Admission;
use crate::techniques::params::{ClusterViews, McorParams, Sightings, Verdict};

/// Each match's verdict at a gate, with the thresholds a rejection exceeded: what a tapped run
/// records.
pub type TappedVerdicts = Vec<(McorVerdict, Exceeded)>;

/// MC-OR's gate of one pose optimization (hook point 2 of
/// [`optimize_frame_pose`](crate::module::pose_estimation::optimize_frame_pose)): the clusters of
/// its matches, prepared once in the frame's cache, each match's current feature, and the
/// verdicts kept across the rounds and the gates of the frame.
pub struct RoundGate<'a> {
    params: &'a McorParams,
    /// Per match: its keypoint and map point (the cluster's key in the cache).
    matches: Vec<(usize, MapPointId)>,
    /// Per match: the keypoint back-projected with its depth (camera frame), when it has one.
    gated: Vec<Option<Vector3<f64>>>,
    /// Per match: |p| of that point, how far a pose change can move it.
    gated_norm: Vec<f64>,
    memo: RefCell<GateMemo>,
}

impl<'a> RoundGate<'a> {
    /// The gate of `frame`'s matches `index` (keypoint indices, each with a map point of `map`),
    /// their clusters prepared in `clusters` (the map is fixed during the optimization).
    pub fn prepare(
        clusters: &mut ClusterCache,
        map: &Map,
        camera: &Camera,
        frame: &TrackedFrame,
        index: &[usize],
        params: &'a McorParams,
    ) -> Self {
        let matches: Vec<(usize, MapPointId)> = index
            .iter()
            .map(|&i| {
                let mp = frame.map_points[i].expect("matched");
                let prepared = clusters.prepare(map, mp, camera, params.cluster_views);
                assert!(prepared, "a matched map point is in the map");
                (i, mp)
            })
            .collect();
        let memo = RefCell::new(clusters.take_memo(frame.id, frame.len(), params));
        let gated: Vec<Option<Vector3<f64>>> = index
            .iter()
            .map(|&i| gate_point(frame.features.unproject_camera(i, camera)))
            .collect();
        let gated_norm = gated.iter().map(|p| p.map_or(0.0, |p| p.norm())).collect();
        Self {
            params,
            matches,
            gated,
            gated_norm,
            memo,
        }
    }

    /// Gates the matches at the round's pose `twc` (camera to world), setting each match's
    /// admission in `excluded`; returns the matches rejected by the cluster and by the feature
    /// test, and with `tapped` each verdict with the thresholds a rejection exceeded (the fast
    /// verdict stops at the first, so they are computed again in full for the rejected).
    pub fn gate(
        &self,
        clusters: &ClusterCache,
        twc: &Isometry3<f64>,
        excluded: &mut [Admission],
        tapped: bool,
    ) -> ((usize, usize), Option<TappedVerdicts>) {
        let params = self.params;
        let mut memo = self.memo.borrow_mut();
        memo.moves(twc);
        let mut verdicts = Vec::new();
        let mut rejected = (0, 0);
        let matches = self.matches.iter().zip(&self.gated).zip(&self.gated_norm);
        for (e, ((&(i, id), p), &p_norm)) in excluded.iter_mut().zip(matches) {
            let verdict = memo.verdict((i, id), p_norm, || {
                clusters
                    .cluster(id)
                    .verdict_with_reach(params, twc, p.as_ref())
            });
            match verdict {
                McorVerdict::RejectedCluster => rejected.0 += 1,
                McorVerdict::RejectedFeature => rejected.1 += 1,
                McorVerdict::Kept => {}
            }
            *e = admission(params, verdict, clusters.cluster(id), p.is_some());
            if tapped {
                let exceeded = match verdict {
                    McorVerdict::Kept => Exceeded::default(),
                    _ => {
                        let metrics = clusters.cluster(id).metrics(params, twc, p.as_ref());
                        Exceeded::of(params, &metrics, verdict)
                    }
                };
                verdicts.push((verdict, exceeded));
            }
        }
        (rejected, tapped.then_some(verdicts))
    }

    /// Hands the verdicts back to the frame's cache, for its next gate.
    pub fn finish(self, clusters: &mut ClusterCache) {
        clusters.put_memo(self.memo.into_inner());
    }
}

/// The MC-OR cluster of map point `mp`: every observing (good) keyframe's keypoint with a
/// measured depth, back-projected and placed with the keyframe's current pose, in keyframe-id
/// order (so the ring keeps the most recent keyframes); under
/// [`ClusterViews::EveryFrame`] followed by the point's stored frame views (oldest first, each
/// placed through its reference keyframe's current pose), so the ring keeps the most recent
/// views.
pub fn map_point_cluster(
    map: &Map,
    mp: MapPointId,
    camera: &Camera,
    views: ClusterViews,
) -> McorCluster {
    let mut cluster = McorCluster::new();
    let Some(m) = map.map_point(mp) else {
        return cluster;
    };
    for (&kf, &idx) in &m.observations {
        let Some(k) = map.keyframe(kf) else {
            continue;
        };
        let Some(pc) = k.features.unproject_camera(idx, camera) else {
            continue;
        };
        if let Some(f) = ClusterFeature::new(kf.0 as u64, pc, &k.tcw.inverse()) {
            cluster.push(f);
        }
    }
    if views == ClusterViews::EveryFrame {
        cluster.extend_with_views(&m.views, |kf| map.keyframe_pose_any(kf));
    }
    cluster
}

/// Algorithm 1 over the matches of `frame` at pose `tcw` (world -> camera), as the gate of
/// [`optimize_frame_pose`](crate::module::pose_estimation::optimize_frame_pose) runs it; returns the matched keypoint indices (ascending) and the
/// outcome per match. For analyses (paper Fig. 7, 8) and the per-frame statistics.
pub fn mcor_frame_gate(
    frame: &TrackedFrame,
    map: &Map,
    camera: &Camera,
    params: &McorParams,
    tcw: &Isometry3<f64>,
) -> (Vec<usize>, McorOutcome) {
    mcor_frame_gate_with(frame, map, camera, params, tcw, &mut ClusterCache::new())
}

/// [`mcor_frame_gate`] with the clusters kept in `clusters` (built there on first use, reused
/// while the map does not change; its owner invalidates it when the map does).
pub fn mcor_frame_gate_with(
    frame: &TrackedFrame,
    map: &Map,
    camera: &Camera,
    params: &McorParams,
    tcw: &Isometry3<f64>,
    clusters: &mut ClusterCache,
) -> (Vec<usize>, McorOutcome) {
    let twc = tcw.inverse();
    let mut index = Vec::new();
    let mut outcome = McorOutcome {
        verdicts: Vec::new(),
        n_rejected_clusters: 0,
        n_rejected_features: 0,
    };
    let mut matched = Vec::new();
    for i in 0..frame.len() {
        let Some(id) = frame.map_points[i] else {
            continue;
        };
        if clusters.prepare(map, id, camera, params.cluster_views) {
            matched.push((i, id));
        }
    }
    // The frame's pose optimizations gated these matches at nearby poses.
    let mut memo = clusters.take_memo(frame.id, frame.len(), params);
    memo.moves(&twc);
    for (i, id) in matched {
        index.push(i);
        let point_camera = gate_point(frame.features.unproject_camera(i, camera));
        let p_norm = point_camera.map_or(0.0, |p| p.norm());
        outcome.push(memo.verdict((i, id), p_norm, || {
            clusters
                .cluster(id)
                .verdict_with_reach(params, &twc, point_camera.as_ref())
        }));
    }
    clusters.put_memo(memo);
    (index, outcome)
}

/// What MC-OR's verdict on a match does in pose-only optimization: a rejected match is
/// excluded; a kept one is left to the chi2 test (`verdict = "filter"`), or, under `verdict =
/// "consensus"`, kept whatever its chi2 when its cluster holds at least
/// `consensus_min_sightings` sightings and the keypoint has depth (`with_depth`) for the
/// cluster to agree with.
pub fn admission(
    params: &McorParams,
    verdict: McorVerdict,
    cluster: &PreparedCluster,
    with_depth: bool,
) -> Admission {
    match verdict {
        McorVerdict::RejectedCluster | McorVerdict::RejectedFeature => Admission::Excluded,
        McorVerdict::Kept
            if params.verdict == Verdict::Consensus
                && with_depth
                && cluster.sightings() >= u64::from(params.consensus_min_sightings) =>
        {
            Admission::Kept
        }
        McorVerdict::Kept => Admission::Free,
    }
}

/// The views tracked frame `frame` adds to its map points' clusters, in keypoint order: one
/// per matched keypoint with depth that ended the frame as an inlier, or, under `sightings =
/// "all"`, per matched keypoint with depth, chi2 and MC-OR outliers included. Nothing unless
/// `params` keeps the frame's views ([`McorParams::keeps_views_of`]) and the frame has a pose
/// and a reference keyframe. Not for a frame made a keyframe: its matches are keyframe
/// observations already.
pub fn frame_sightings(
    frame: &TrackedFrame,
    map: &Map,
    camera: &Camera,
    params: &McorParams,
) -> Vec<(MapPointId, FrameView)> {
    if !params.keeps_views_of(frame.id) {
        return Vec::new();
    }
    let (Some(tcw), Some(reference)) = (frame.tcw, frame.reference_kf) else {
        return Vec::new();
    };
    let Some(tkw) = map.keyframe_pose_any(reference) else {
        return Vec::new();
    };
    let twc = tcw.inverse();
    let mut views = Vec::new();
    for i in 0..frame.len() {
        let Some(id) = frame.map_points[i] else {
            continue;
        };
        if frame.outliers[i] && params.sightings == Sightings::Inliers {
            continue;
        }
        let Some(pc) = frame.features.unproject_camera(i, camera) else {
            continue;
        };
        if let Some(view) = FrameView::placed(frame.id, &twc, reference, &tkw, pc) {
            views.push((id, view));
        }
    }
    views
}
