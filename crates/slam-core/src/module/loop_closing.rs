//! Loop closing (ORB-SLAM2's `LoopClosing`, fixed scale for stereo / RGB-D), run on every
//! keyframe after its local mapping:
//!
//! 1. **Detection**: keyframe-database candidates that score at least the lowest BoW score of
//!    the keyframe's covisible keyframes and are not connected to it, grouped by covisibility;
//!    a candidate counts once its group has been consistent with a group of the previous
//!    keyframes three times in a row.
//! 2. **Verification**: BoW matches between the keyframe and the candidate (ratio 0.75, >= 20),
//!    a seeded RANSAC for the keyframe's pose in the candidate's frame of reference (>= 20
//!    inliers, chi2 9.21), a guided search (radius 7.5), pose refinement (>= 20 inliers), then
//!    the map points of the candidate and its covisible keyframes projected in (radius 10):
//!    accepted with >= 40 matches. Deviation, as in relocalization: the transform comes from
//!    3-point absolute orientation on measured depth and a pose-only refinement in the current
//!    keyframe, where ORB-SLAM2 runs its Sim3 solver and Sim3 optimization with scale fixed.
//! 3. **Correction**: the keyframe and its covisible keyframes take the loop's pose, their map
//!    points move with them, matched points are fused with the loop's, the loop's map points
//!    are fused into the corrected keyframes (radius 4), the covisibility graph is updated, and
//!    the essential graph ([`super::essential_graph`]) spreads the correction over the map.
//!    A global bundle adjustment ([`super::global_ba`]) follows; the system decides when its
//!    result is merged.

use std::collections::{BTreeMap, BTreeSet};

use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::essential_graph::{optimize_essential_graph, LoopCorrection};
use super::pose_estimation::{optimize_frame_pose, pose_correspondences, without_tap, NoiseHooks};
use crate::camera::Camera;
use crate::data::{KeyFrameId, Map, MapPointId, ScaleLevels, TrackedFrame};
use crate::feature::{TH_HIGH, TH_LOW};
use crate::matching::bow::search_by_bow;
use crate::matching::fuse::fuse;
use crate::matching::projection::search_by_projection_keyframe;
use crate::optimize::PoseOptConfig;
use crate::place::{score_l1, PlaceRecognition};
use crate::solve::{pose_ransac, PoseRansacParams};

/// Loop-closing settings (ORB-SLAM2's values).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LoopClosingParams {
    /// Loop closing on (the baseline runs with it, as ORB-SLAM2 does); off for ablations.
    pub enabled: bool,
    /// No detection until this many keyframes after the last loop / the map's start (10).
    pub min_keyframes_between: u32,
    /// Consecutive consistent detections a candidate group needs (3).
    pub consistency: usize,
    /// Descriptor ratio test of the BoW search (0.75).
    pub match_ratio: f64,
    /// BoW matches a candidate needs (20).
    pub min_bow_matches: usize,
    /// RANSAC: iterations (300), minimum inliers (20), chi2 gate (9.21).
    pub ransac_iterations: usize,
    /// See `ransac_iterations`.
    pub ransac_min_inliers: usize,
    /// See `ransac_iterations`.
    pub ransac_chi2: f64,
    /// Search radius of the guided search after RANSAC, pixels at level 0 (7.5).
    pub guided_radius: f64,
    /// Inliers the refined transform needs (20).
    pub min_refined_inliers: usize,
    /// Search radius for the loop neighbourhood's map points, pixels at level 0 (10).
    pub projection_radius: f64,
    /// Matches with the loop neighbourhood a loop needs to be accepted (40).
    pub min_total_matches: usize,
    /// Fusion radius of the loop's map points into the corrected keyframes (4).
    pub fuse_radius: f64,
    /// Covisibility weight of essential-graph edges (100).
    pub essential_min_weight: u32,
    /// LM iterations of the essential graph (20).
    pub essential_iterations: usize,
    /// Run a global bundle adjustment after each loop (true).
    pub global_ba: bool,
    /// LM iterations of the global bundle adjustment (10).
    pub global_ba_iterations: usize,
}

impl Default for LoopClosingParams {
    fn default() -> Self {
        LoopClosingParams {
            enabled: true,
            min_keyframes_between: 10,
            consistency: 3,
            match_ratio: 0.75,
            min_bow_matches: 20,
            ransac_iterations: 300,
            ransac_min_inliers: 20,
            ransac_chi2: 9.21,
            guided_radius: 7.5,
            min_refined_inliers: 20,
            projection_radius: 10.0,
            min_total_matches: 40,
            fuse_radius: 4.0,
            essential_min_weight: 100,
            essential_iterations: 20,
            global_ba: true,
            global_ba_iterations: 10,
        }
    }
}

/// Shared inputs of loop closing.
#[derive(Clone, Copy, Debug)]
pub struct LoopContext<'a> {
    /// The camera.
    pub camera: &'a Camera,
    /// Pyramid scale table.
    pub levels: &'a ScaleLevels,
    /// Thresholds.
    pub params: &'a LoopClosingParams,
    /// Pose-only optimization schedule (for the transform's refinement).
    pub pose_cfg: &'a PoseOptConfig,
    /// Vocabulary and keyframe database.
    pub place: &'a PlaceRecognition,
}

/// A closed loop.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopEvent {
    /// The keyframe that closed it.
    pub current: KeyFrameId,
    /// The keyframe it was matched to.
    pub loop_kf: KeyFrameId,
    /// Matches between the keyframe and the loop's neighbourhood.
    pub matches: usize,
    /// How far the correction moved the keyframe, metres.
    pub correction_m: f64,
    /// How far it turned it, degrees.
    pub correction_deg: f64,
}

/// What loop closing did for one keyframe.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoopReport {
    /// Candidates passed the consistency check (a loop was detected, not necessarily closed).
    pub detected: bool,
    /// The loop closed, if one did.
    pub closed: Option<LoopEvent>,
}

/// Loop-closing state across keyframes.
#[derive(Clone, Debug, Default)]
pub struct LoopCloser {
    /// Candidate groups of the previous keyframe and how many times each has been consistent.
    consistent_groups: Vec<(BTreeSet<KeyFrameId>, usize)>,
    /// The keyframe of the last closed loop.
    last_loop_kf: Option<KeyFrameId>,
    /// Every loop closed so far.
    pub loops: Vec<LoopEvent>,
}

/// A verified loop: the keyframe's pose in the loop's frame of reference and its matches.
#[derive(Clone, Debug)]
pub struct VerifiedLoop {
    /// The candidate that passed.
    pub loop_kf: KeyFrameId,
    /// The current keyframe's pose (`Tcw`) consistent with the loop keyframe's map.
    pub tcw: nalgebra::Isometry3<f64>,
    /// Per keypoint of the current keyframe, the loop map point it matched.
    pub matched: Vec<Option<MapPointId>>,
    /// Map points of the loop keyframe and its covisible keyframes.
    pub loop_points: Vec<MapPointId>,
}

impl LoopCloser {
    /// Detects, verifies and corrects a loop at keyframe `kf` (already locally mapped).
    pub fn process(
        &mut self,
        kf: KeyFrameId,
        map: &mut Map,
        ctx: &LoopContext,
        rng: &mut ChaCha8Rng,
    ) -> LoopReport {
        let mut report = LoopReport::default();
        let candidates = self.detect(kf, map, ctx);
        if candidates.is_empty() {
            return report;
        }
        report.detected = true;
        let Some(m) = without_tap(|| verify_loop(kf, &candidates, map, ctx, rng)) else {
            return report;
        };
        let before = map.keyframe(kf).expect("good").tcw;
        let event = LoopEvent {
            current: kf,
            loop_kf: m.loop_kf,
            matches: m.matched.iter().flatten().count(),
            correction_m: (before.inverse().translation.vector
                - m.tcw.inverse().translation.vector)
                .norm(),
            correction_deg: before.rotation.angle_to(&m.tcw.rotation).to_degrees(),
        };
        correct_loop(kf, &m, map, ctx);
        self.consistent_groups.clear();
        self.last_loop_kf = Some(kf);
        self.loops.push(event.clone());
        report.closed = Some(event);
        report
    }

    /// Candidates whose covisibility group has been consistent often enough.
    fn detect(&mut self, kf: KeyFrameId, map: &Map, ctx: &LoopContext) -> Vec<KeyFrameId> {
        let since = self.last_loop_kf.map_or(0, |k| k.0);
        let Some(k) = map.keyframe(kf) else {
            return Vec::new();
        };
        if kf.0 < since + ctx.params.min_keyframes_between {
            return Vec::new();
        }
        let Some(bow) = k.bow.as_deref() else {
            return Vec::new();
        };
        let bow_of = |id: KeyFrameId| {
            map.keyframe(id)
                .and_then(|x| x.bow.as_deref())
                .map(|b| &b.bow)
        };
        let mut min_score: f64 = 1.0;
        for n in k.covisibles() {
            if let Some(b) = bow_of(n) {
                min_score = min_score.min(score_l1(&bow.bow, b));
            }
        }
        let candidates = ctx.place.database.loop_candidates(
            kf,
            &bow.bow,
            min_score,
            |c| k.connections.contains_key(&c),
            bow_of,
            |c, n| {
                map.keyframe(c)
                    .map_or_else(Vec::new, |x| x.best_covisibles(n))
            },
        );
        if candidates.is_empty() {
            self.consistent_groups.clear();
            return Vec::new();
        }
        let mut enough = Vec::new();
        let mut current_groups: Vec<(BTreeSet<KeyFrameId>, usize)> = Vec::new();
        let mut group_taken = vec![false; self.consistent_groups.len()];
        for &c in &candidates {
            let Some(ck) = map.keyframe(c) else {
                continue;
            };
            let mut group: BTreeSet<KeyFrameId> = ck.connections.keys().copied().collect();
            group.insert(c);
            let mut consistent_for_some = false;
            let mut is_enough = false;
            for (g, (previous, count)) in self.consistent_groups.iter().enumerate() {
                if group.is_disjoint(previous) {
                    continue;
                }
                consistent_for_some = true;
                let count = count + 1;
                if !group_taken[g] {
                    current_groups.push((group.clone(), count));
                    group_taken[g] = true;
                }
                if count >= ctx.params.consistency && !is_enough {
                    enough.push(c);
                    is_enough = true;
                }
            }
            if !consistent_for_some {
                current_groups.push((group, 0));
            }
        }
        self.consistent_groups = current_groups;
        enough
    }

    /// The keyframe of the last closed loop.
    pub fn last_loop_keyframe(&self) -> Option<KeyFrameId> {
        self.last_loop_kf
    }
}

/// Verification (step 2 of the module documentation) of loop candidates for keyframe `kf`:
/// tries them in order and returns the first that passes every check, with the keyframe's
/// pose in the loop's frame of reference. Public for tests and analyses of false loops.
pub fn verify_loop(
    kf: KeyFrameId,
    candidates: &[KeyFrameId],
    map: &Map,
    ctx: &LoopContext,
    rng: &mut ChaCha8Rng,
) -> Option<VerifiedLoop> {
    let p = ctx.params;
    let k = map.keyframe(kf)?;
    let kb = k.bow.clone()?;
    let no_hooks = NoiseHooks {
        mcor: None,
        avc: None,
        rc: None,
        clusters: None,
    };
    for &c in candidates {
        let Some(lk) = map.keyframe(c) else {
            continue;
        };
        let Some(lb) = lk.bow.as_deref() else {
            continue;
        };
        let (mut matches, _) = search_by_bow(
            lk,
            &lb.features,
            &k.features,
            &kb.features,
            p.match_ratio,
            map,
        );
        // Only keypoints that are map points of the current keyframe take part (as ORB-SLAM2's
        // keyframe-to-keyframe search).
        for (i, m) in matches.iter_mut().enumerate() {
            if k.map_points[i].and_then(|id| map.map_point(id)).is_none() {
                *m = None;
            }
        }
        let n = matches.iter().flatten().count();
        if n < p.min_bow_matches {
            continue;
        }
        let (corr, corr_idx) =
            pose_correspondences(&matches, &k.features, map, ctx.camera, ctx.levels);
        let ransac = PoseRansacParams {
            probability: 0.99,
            min_inliers: p.ransac_min_inliers,
            max_iterations: p.ransac_iterations,
            epsilon: (p.ransac_min_inliers as f64 / corr.len().max(1) as f64).min(1.0),
            chi2_threshold: p.ransac_chi2,
        };
        let Some(hyp) = pose_ransac(&corr, ctx.camera, &ransac, rng) else {
            continue;
        };
        let mut frame = TrackedFrame::new(k.frame_id, k.timestamp, k.features.clone());
        for (ci, &i) in corr_idx.iter().enumerate() {
            if hyp.inliers[ci] {
                frame.map_points[i] = matches[i];
            }
        }
        frame.tcw = Some(hyp.tcw);
        let found = frame.matched_map_points();
        search_by_projection_keyframe(
            &mut frame,
            c,
            &found,
            p.guided_radius,
            TH_HIGH,
            map,
            ctx.camera,
            ctx.levels,
        );
        let refined = optimize_frame_pose(
            &mut frame,
            map,
            ctx.camera,
            ctx.levels,
            ctx.pose_cfg,
            &no_hooks,
        );
        if refined.n_inliers < p.min_refined_inliers {
            continue;
        }
        frame.drop_outliers();
        let mut neighbourhood = vec![c];
        neighbourhood.extend(lk.covisibles());
        let mut loop_points = Vec::new();
        let mut seen = BTreeSet::new();
        for &n in &neighbourhood {
            if let Some(nk) = map.keyframe(n) {
                for &id in nk.map_points.iter().flatten() {
                    if map.map_point(id).is_some() && seen.insert(id) {
                        loop_points.push(id);
                    }
                }
            }
        }
        for &n in &neighbourhood {
            let found = frame.matched_map_points();
            search_by_projection_keyframe(
                &mut frame,
                n,
                &found,
                p.projection_radius,
                TH_LOW,
                map,
                ctx.camera,
                ctx.levels,
            );
        }
        if frame.n_matches() >= p.min_total_matches {
            return Some(VerifiedLoop {
                loop_kf: c,
                tcw: frame.tcw?,
                matched: frame.map_points,
                loop_points,
            });
        }
    }
    None
}

/// Corrects the map for the verified loop `m` at keyframe `kf` (ORB-SLAM2's CorrectLoop).
fn correct_loop(kf: KeyFrameId, m: &VerifiedLoop, map: &mut Map, ctx: &LoopContext) {
    map.update_connections(kf);
    let k = map.keyframe(kf).expect("good");
    let mut connected = vec![kf];
    connected.extend(k.covisibles());
    let twc_old = k.tcw.inverse();
    let mut correction = LoopCorrection {
        current: kf,
        loop_kf: m.loop_kf,
        non_corrected: BTreeMap::new(),
        loop_connections: BTreeMap::new(),
        corrected_by: BTreeMap::new(),
    };
    let mut corrected = BTreeMap::new();
    for &ki in &connected {
        let Some(x) = map.keyframe(ki) else {
            continue;
        };
        correction.non_corrected.insert(ki, x.tcw);
        let new = if ki == kf {
            m.tcw
        } else {
            x.tcw * twc_old * m.tcw
        };
        corrected.insert(ki, new);
    }
    // Move the keyframes' map points with them (each point once), then the keyframes.
    for (&ki, new) in &corrected {
        let old = correction.non_corrected[&ki];
        let ids: Vec<MapPointId> = map
            .keyframe(ki)
            .map(|x| x.map_points.iter().flatten().copied().collect())
            .unwrap_or_default();
        for id in ids {
            if map.map_point(id).is_none() || correction.corrected_by.contains_key(&id) {
                continue;
            }
            let mp = map.map_point_mut(id).expect("good");
            let p_c = old * nalgebra::Point3::from(mp.position);
            mp.position = new.inverse_transform_point(&p_c).coords;
            correction.corrected_by.insert(id, ki);
            map.update_normal_and_depth(id, ctx.levels);
        }
        map.keyframe_mut(ki).expect("good").tcw = *new;
    }
    for &ki in &connected {
        map.update_connections(ki);
    }
    // The keyframe's matches: its own duplicates give way to the loop's points.
    for (i, slot) in m.matched.iter().enumerate() {
        let Some(loop_mp) = slot.filter(|&id| map.map_point(id).is_some()) else {
            continue;
        };
        let own = map
            .keyframe(kf)
            .and_then(|x| x.map_points[i])
            .filter(|&id| map.map_point(id).is_some());
        match own {
            Some(own) if own != loop_mp => map.replace_map_point(own, loop_mp),
            Some(_) => {}
            None => {
                if !map.map_point(loop_mp).expect("good").is_observed_by(kf) {
                    map.add_observation(loop_mp, kf, i);
                    map.compute_distinctive_descriptor(loop_mp);
                }
            }
        }
    }
    // Fuse the loop's map points into every corrected keyframe.
    for &ki in &connected {
        fuse(
            ki,
            &m.loop_points,
            ctx.params.fuse_radius,
            map,
            ctx.camera,
            ctx.levels,
        );
    }
    // The links the loop created (new neighbours that were not neighbours before and are not
    // among the corrected keyframes).
    let connected_set: BTreeSet<KeyFrameId> = connected.iter().copied().collect();
    for &ki in &connected {
        let previous: BTreeSet<KeyFrameId> = map
            .keyframe(ki)
            .map(|x| x.connections.keys().copied().collect())
            .unwrap_or_default();
        map.update_connections(ki);
        let Some(x) = map.keyframe(ki) else {
            continue;
        };
        let new: BTreeSet<KeyFrameId> = x
            .connections
            .keys()
            .copied()
            .filter(|n| !previous.contains(n) && !connected_set.contains(n))
            .collect();
        correction.loop_connections.insert(ki, new);
    }
    correction
        .loop_connections
        .entry(kf)
        .or_default()
        .insert(m.loop_kf);
    optimize_essential_graph(
        map,
        &correction,
        ctx.params.essential_min_weight,
        ctx.params.essential_iterations,
        ctx.levels,
    );
    if let Some(x) = map.keyframe_mut(kf) {
        x.loop_edges.insert(m.loop_kf);
    }
    if let Some(x) = map.keyframe_mut(m.loop_kf) {
        x.loop_edges.insert(kf);
    }
}
