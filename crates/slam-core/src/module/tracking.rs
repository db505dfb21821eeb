//! Frame-to-map tracking (ORB-SLAM2's Tracking): the constant-velocity motion model with a
//! projection search, the reference-keyframe fallback, and local-map tracking (covisible
//! keyframes and their neighbours, frustum test, scale-predicted search), each followed by a
//! pose-only optimization.

use serde::{Deserialize, Serialize};

use super::pose_estimation::{optimize_frame_pose, renormalized, NoiseHooks};
use crate::camera::{Camera, SensorKind};
use crate::data::{KeyFrameId, Map, MapPointId, ScaleLevels, TrackedFrame};
use crate::matching::bow::search_by_bow;
use crate::matching::brute::search_keyframe_frame;
use crate::matching::projection::{
    is_in_frustum, search_by_projection_last_frame, search_local_points,
};
use crate::optimize::PoseOptConfig;
use crate::place::PlaceRecognition;

/// Tracking thresholds; defaults are ORB-SLAM2's RGB-D / stereo values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TrackingParams {
    /// Motion-model search window for RGB-D, pixels x scale of the octave (15).
    pub motion_window_rgbd: f64,
    /// Motion-model search window for stereo, pixels x scale of the octave (7).
    pub motion_window_stereo: f64,
    /// Motion-model matches below which the window is doubled and, after that, the model fails (20).
    pub motion_min_matches: usize,
    /// Inliers (with observations) needed after the motion model / reference keyframe (10).
    pub min_inliers_frame: usize,
    /// Matches needed to try the reference-keyframe pose (15).
    pub reference_min_matches: usize,
    /// Descriptor ratio test of the reference-keyframe search (0.7).
    pub reference_ratio: f64,
    /// Local-map search: radius factor for RGB-D (3), stereo (1), and just after a
    /// relocalization (5), multiplied by 2.5 / 4.0 (viewing angle) and the predicted scale.
    pub local_window_rgbd: f64,
    /// See `local_window_rgbd`.
    pub local_window_stereo: f64,
    /// See `local_window_rgbd`.
    pub local_window_after_reloc: f64,
    /// Ratio test of the local-map search when best and second are on the same level (0.8).
    pub local_ratio: f64,
    /// Minimum cosine between viewing ray and a point's mean viewing direction (0.5 = 60 deg).
    pub view_cos_limit: f64,
    /// Maximum number of local keyframes (80).
    pub max_local_keyframes: usize,
    /// Covisible neighbours considered per local keyframe (10).
    pub local_neighbours: usize,
    /// Local-map inliers needed to stay tracked (30).
    pub min_inliers_local_map: usize,
    /// Local-map inliers needed within `fps` frames of a relocalization (50).
    pub min_inliers_after_reloc: usize,
}

impl Default for TrackingParams {
    fn default() -> Self {
        TrackingParams {
            motion_window_rgbd: 15.0,
            motion_window_stereo: 7.0,
            motion_min_matches: 20,
            min_inliers_frame: 10,
            reference_min_matches: 15,
            reference_ratio: 0.7,
            local_window_rgbd: 3.0,
            local_window_stereo: 1.0,
            local_window_after_reloc: 5.0,
            local_ratio: 0.8,
            view_cos_limit: 0.5,
            max_local_keyframes: 80,
            local_neighbours: 10,
            min_inliers_local_map: 30,
            min_inliers_after_reloc: 50,
        }
    }
}

/// Shared, read-only inputs of the tracking steps.
#[derive(Clone, Copy, Debug)]
pub struct TrackingContext<'a> {
    /// The camera.
    pub camera: &'a Camera,
    /// Pyramid scale table.
    pub levels: &'a ScaleLevels,
    /// Thresholds.
    pub params: &'a TrackingParams,
    /// Pose-only optimization schedule.
    pub pose_cfg: &'a PoseOptConfig,
    /// MC-OR / AVC switches.
    pub hooks: NoiseHooks<'a>,
    /// Sequence frame rate (ORB-SLAM2's maxFrames).
    pub max_frames: u64,
    /// Vocabulary (and database): reference-keyframe tracking matches by BoW when present.
    pub place: Option<&'a PlaceRecognition>,
}

/// Tracking state carried from frame to frame.
#[derive(Clone, Debug, Default)]
pub struct Tracker {
    /// The previous frame (with its matches and pose).
    pub last_frame: Option<TrackedFrame>,
    /// Constant-velocity model `T_current_last`, when the last two frames were tracked.
    pub velocity: Option<nalgebra::Isometry3<f64>>,
    /// Reference keyframe (most shared points with the last tracked frame).
    pub reference_kf: Option<KeyFrameId>,
    /// Frame id of the last relocalization.
    pub last_reloc_frame: Option<u64>,
    /// Local keyframes of the last local-map update.
    pub local_keyframes: Vec<KeyFrameId>,
    /// Local map points of the last local-map update.
    pub local_points: Vec<MapPointId>,
    /// Inliers with observations of the last local-map tracking.
    pub matches_inliers: usize,
    /// Matches that entered the last local-map pose optimization.
    pub local_matches: usize,
}

impl Tracker {
    /// Whether `frame_id` is within `n` frames after the last relocalization.
    pub fn recently_relocalized(&self, frame_id: u64, n: u64) -> bool {
        self.last_reloc_frame.is_some_and(|r| frame_id < r + n)
    }

    /// Replaces fused map points in the last frame by the points that absorbed them.
    pub fn check_replaced_in_last_frame(&mut self, map: &Map) {
        if let Some(last) = &mut self.last_frame {
            for slot in last.map_points.iter_mut() {
                if let Some(id) = *slot {
                    *slot = map.resolve(id);
                }
            }
        }
    }

    /// Re-expresses the last frame's pose relative to its reference keyframe, which local BA may
    /// have moved since (ORB-SLAM2's UpdateLastFrame; `t_last_ref` is the stored relative pose).
    pub fn update_last_frame(
        &mut self,
        map: &Map,
        t_last_ref: Option<(KeyFrameId, nalgebra::Isometry3<f64>)>,
    ) {
        if let (Some(last), Some((kf, tlr))) = (&mut self.last_frame, t_last_ref) {
            if let Some(pose) = map.keyframe_pose_any(kf) {
                last.tcw = Some(renormalized(&(tlr * pose)));
            }
        }
    }

    /// Drops outlier matches of `frame`, marks the dropped points as not to be searched again
    /// in this frame, and returns the matches whose map point has observations.
    fn discard_outliers(frame: &mut TrackedFrame, map: &mut Map) -> usize {
        let mut n = 0;
        for i in 0..frame.len() {
            let Some(id) = frame.map_points[i] else {
                continue;
            };
            if frame.outliers[i] {
                frame.map_points[i] = None;
                frame.outliers[i] = false;
                if let Some(mp) = map.map_point_mut(id) {
                    mp.last_frame_seen = frame.id + 1;
                }
            } else if map.map_point(id).is_some_and(|m| m.n_obs > 0) {
                n += 1;
            }
        }
        n
    }

    /// Tracks against the reference keyframe by descriptor matching, starting from the last
    /// pose (ORB-SLAM2's TrackReferenceKeyFrame).
    pub fn track_reference_keyframe(
        &mut self,
        frame: &mut TrackedFrame,
        map: &mut Map,
        ctx: &TrackingContext,
    ) -> bool {
        let (Some(kf), Some(last_pose)) = (
            self.reference_kf.and_then(|k| map.keyframe(k)),
            self.last_frame.as_ref().and_then(|l| l.tcw),
        ) else {
            return false;
        };
        let ratio = ctx.params.reference_ratio;
        let (matches, n) = match (ctx.place, kf.bow.as_deref()) {
            (Some(place), Some(kb)) => {
                let fb = frame.bow(place);
                search_by_bow(kf, &kb.features, &frame.features, &fb.features, ratio, map)
            }
            _ => search_keyframe_frame(kf, &frame.features, ratio, map),
        };
        if n < ctx.params.reference_min_matches {
            return false;
        }
        frame.map_points = matches;
        frame.outliers.iter_mut().for_each(|o| *o = false);
        frame.tcw = Some(last_pose);
        optimize_frame_pose(frame, map, ctx.camera, ctx.levels, ctx.pose_cfg, &ctx.hooks);
        Self::discard_outliers(frame, map) >= ctx.params.min_inliers_frame
    }

    /// Tracks with the constant-velocity model and a projection search from the last frame
    /// (ORB-SLAM2's TrackWithMotionModel).
    pub fn track_with_motion_model(
        &mut self,
        frame: &mut TrackedFrame,
        map: &mut Map,
        ctx: &TrackingContext,
    ) -> bool {
        let (Some(v), Some(last)) = (self.velocity, self.last_frame.as_ref()) else {
            return false;
        };
        let Some(last_pose) = last.tcw else {
            return false;
        };
        frame.tcw = Some(renormalized(&(v * last_pose)));
        frame.clear_matches();
        let th = match ctx.camera.sensor {
            SensorKind::Stereo => ctx.params.motion_window_stereo,
            SensorKind::Rgbd => ctx.params.motion_window_rgbd,
        };
        let mut n = search_by_projection_last_frame(frame, last, th, map, ctx.camera, ctx.levels);
        if n < ctx.params.motion_min_matches {
            frame.clear_matches();
            n = search_by_projection_last_frame(frame, last, 2.0 * th, map, ctx.camera, ctx.levels);
        }
        if n < ctx.params.motion_min_matches {
            return false;
        }
        optimize_frame_pose(frame, map, ctx.camera, ctx.levels, ctx.pose_cfg, &ctx.hooks);
        Self::discard_outliers(frame, map) >= ctx.params.min_inliers_frame
    }

    /// Local keyframes: those observing the frame's map points, plus for each (until 80) its
    /// best covisible neighbour, a child and the parent not yet included. The keyframe sharing
    /// most points becomes the reference. ORB-SLAM2 quirk kept: adding a parent ends the
    /// expansion loop.
    fn update_local_keyframes(
        &mut self,
        frame: &mut TrackedFrame,
        map: &mut Map,
        ctx: &TrackingContext,
    ) {
        let mark = frame.id + 1;
        let mut counter: std::collections::BTreeMap<KeyFrameId, u32> = Default::default();
        for slot in frame.map_points.iter_mut() {
            let Some(id) = *slot else {
                continue;
            };
            match map.map_point(id) {
                Some(mp) => {
                    for &kf in mp.observations.keys() {
                        *counter.entry(kf).or_insert(0) += 1;
                    }
                }
                None => *slot = None,
            }
        }
        self.local_keyframes.clear();
        if counter.is_empty() {
            return;
        }
        let mut best = (KeyFrameId(0), 0u32);
        for (&kf, &c) in &counter {
            if map.keyframe(kf).is_none() {
                continue;
            }
            if c > best.1 {
                best = (kf, c);
            }
            self.local_keyframes.push(kf);
            if let Some(k) = map.keyframe_mut(kf) {
                k.track_reference_frame = mark;
            }
        }
        let first_level = self.local_keyframes.len();
        'outer: for i in 0..first_level {
            if self.local_keyframes.len() > ctx.params.max_local_keyframes {
                break;
            }
            let kf = self.local_keyframes[i];
            let (neighbours, children, parent) = {
                let k = map.keyframe(kf).expect("good");
                (
                    k.best_covisibles(ctx.params.local_neighbours),
                    k.children.iter().copied().collect::<Vec<_>>(),
                    k.parent,
                )
            };
            for n in neighbours {
                if let Some(k) = map.keyframe_mut(n) {
                    if k.track_reference_frame != mark {
                        k.track_reference_frame = mark;
                        self.local_keyframes.push(n);
                        break;
                    }
                }
            }
            for c in children {
                if let Some(k) = map.keyframe_mut(c) {
                    if k.track_reference_frame != mark {
                        k.track_reference_frame = mark;
                        self.local_keyframes.push(c);
                        break;
                    }
                }
            }
            if let Some(p) = parent {
                if let Some(k) = map.keyframe_mut(p) {
                    if k.track_reference_frame != mark {
                        k.track_reference_frame = mark;
                        self.local_keyframes.push(p);
                        break 'outer;
                    }
                }
            }
        }
        if best.1 > 0 {
            self.reference_kf = Some(best.0);
            frame.reference_kf = Some(best.0);
        }
    }

    /// Local map points: every map point of the local keyframes, once.
    fn update_local_points(&mut self, frame: &TrackedFrame, map: &mut Map) {
        let mark = frame.id + 1;
        self.local_points.clear();
        for &kf in &self.local_keyframes {
            let Some(k) = map.keyframe(kf) else {
                continue;
            };
            let ids: Vec<MapPointId> = k.map_points.iter().flatten().copied().collect();
            for id in ids {
                if let Some(mp) = map.map_point_mut(id) {
                    if mp.track_reference_frame != mark {
                        mp.track_reference_frame = mark;
                        self.local_points.push(id);
                    }
                }
            }
        }
    }

    /// Projects the local map points into the frame and matches those predicted visible.
    fn search_local_points(
        &mut self,
        frame: &mut TrackedFrame,
        map: &mut Map,
        ctx: &TrackingContext,
    ) {
        let mark = frame.id + 1;
        for slot in frame.map_points.iter_mut() {
            let Some(id) = *slot else {
                continue;
            };
            match map.map_point_mut(id) {
                Some(mp) => {
                    mp.n_visible += 1;
                    mp.last_frame_seen = mark;
                }
                None => *slot = None,
            }
        }
        let Some(tcw) = frame.tcw else {
            return;
        };
        let center = frame.center();
        let mut visible = Vec::new();
        for &id in &self.local_points {
            let Some(mp) = map.map_point(id) else {
                continue;
            };
            if mp.last_frame_seen == mark {
                continue;
            }
            if let Some(vp) = is_in_frustum(
                mp,
                &tcw,
                &center,
                ctx.camera,
                ctx.levels,
                ctx.params.view_cos_limit,
            ) {
                visible.push(vp);
            }
        }
        for vp in &visible {
            if let Some(mp) = map.map_point_mut(vp.id) {
                mp.n_visible += 1;
            }
        }
        if visible.is_empty() {
            return;
        }
        let th = if self.recently_relocalized(frame.id, 2) {
            ctx.params.local_window_after_reloc
        } else {
            match ctx.camera.sensor {
                SensorKind::Stereo => ctx.params.local_window_stereo,
                SensorKind::Rgbd => ctx.params.local_window_rgbd,
            }
        };
        search_local_points(frame, &visible, th, ctx.params.local_ratio, map, ctx.levels);
    }

    /// Tracks the local map (ORB-SLAM2's TrackLocalMap): update local keyframes and points,
    /// search them, optimize the pose, count inliers. Returns whether tracking succeeded.
    pub fn track_local_map(
        &mut self,
        frame: &mut TrackedFrame,
        map: &mut Map,
        ctx: &TrackingContext,
    ) -> bool {
        self.update_local_keyframes(frame, map, ctx);
        self.update_local_points(frame, map);
        self.search_local_points(frame, map, ctx);
        let counts =
            optimize_frame_pose(frame, map, ctx.camera, ctx.levels, ctx.pose_cfg, &ctx.hooks);
        self.local_matches = counts.n_matches;
        let mut inliers = 0;
        for i in 0..frame.len() {
            let Some(id) = frame.map_points[i] else {
                continue;
            };
            if !frame.outliers[i] {
                if let Some(mp) = map.map_point_mut(id) {
                    mp.n_found += 1;
                    if mp.n_obs > 0 {
                        inliers += 1;
                    }
                }
            } else if ctx.camera.sensor == SensorKind::Stereo {
                frame.map_points[i] = None;
            }
        }
        self.matches_inliers = inliers;
        if self.recently_relocalized(frame.id, ctx.max_frames)
            && inliers < ctx.params.min_inliers_after_reloc
        {
            return false;
        }
        inliers >= ctx.params.min_inliers_local_map
    }
}
