//! When a tracked frame becomes a keyframe (ORB-SLAM2's NeedNewKeyFrame for RGB-D / stereo).

use serde::{Deserialize, Serialize};

use crate::camera::Camera;
use crate::data::{KeyFrameId, Map, TrackedFrame};

/// Keyframe-decision thresholds (ORB-SLAM2 RGB-D / stereo values).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct KeyFrameParams {
    /// Frames between keyframes after which one is inserted anyway (c1a); `None` = the
    /// sequence frame rate, as ORB-SLAM2's maxFrames.
    pub max_frames: Option<u64>,
    /// Minimum frames between keyframes (0).
    pub min_frames: u64,
    /// Tracked close points below which close points are needed (100).
    pub close_tracked_max: usize,
    /// Untracked close points above which close points are needed (70).
    pub close_untracked_min: usize,
    /// Ratio of the reference keyframe's matches below which a keyframe is wanted (0.75; 0.4
    /// while the map holds a single keyframe).
    pub ref_ratio: f64,
    /// See `ref_ratio`.
    pub ref_ratio_single_keyframe: f64,
    /// Ratio for condition c1c (0.25).
    pub ref_ratio_weak: f64,
    /// Inliers a new keyframe must have (more than 15).
    pub min_inliers: usize,
    /// Whether ORB-SLAM2's condition c1b ("local mapping is idle") may hold: local mapping is
    /// always idle in the synchronous run (as in the paper's synchronised ORB-SLAM2), so
    /// keyframes are inserted whenever c2 holds; with an emulated mapping lag
    /// (`Config::mapping_lag`) it holds only while no keyframe waits. `false` drops c1b and
    /// keeps only c1a / c1c, which inserts fewer keyframes.
    pub mapping_idle: bool,
}

impl Default for KeyFrameParams {
    fn default() -> Self {
        KeyFrameParams {
            max_frames: None,
            min_frames: 0,
            close_tracked_max: 100,
            close_untracked_min: 70,
            ref_ratio: 0.75,
            ref_ratio_single_keyframe: 0.4,
            ref_ratio_weak: 0.25,
            min_inliers: 15,
            mapping_idle: true,
        }
    }
}

/// What the decision looked at.
#[derive(Clone, Copy, Debug)]
pub struct KeyFrameDecisionInput {
    /// Current frame id.
    pub frame_id: u64,
    /// Frame id of the last keyframe.
    pub last_keyframe_frame: u64,
    /// Frame id of the last relocalization.
    pub last_reloc_frame: Option<u64>,
    /// Local-map inliers of the current frame.
    pub matches_inliers: usize,
    /// Reference keyframe.
    pub reference_kf: KeyFrameId,
    /// Keyframes waiting for local mapping (always 0 in the synchronous run).
    pub keyframes_in_queue: usize,
}

/// ORB-SLAM2's rule: c1 = (c1a: max frames passed) || (c1b: min frames passed and mapping idle)
/// || (c1c: inliers < 0.25 ref matches or close points needed); c2 = (inliers < ratio * ref
/// matches or close points needed) && inliers > 15; insert when c1 && c2, and, while local
/// mapping is busy, only if fewer than 3 keyframes wait for it (RGB-D / stereo).
pub fn need_new_keyframe(
    frame: &TrackedFrame,
    input: &KeyFrameDecisionInput,
    map: &Map,
    camera: &Camera,
    params: &KeyFrameParams,
) -> bool {
    let max_frames = params
        .max_frames
        .unwrap_or(camera.fps.round().max(1.0) as u64);
    let n_kfs = map.keyframe_count();
    if input
        .last_reloc_frame
        .is_some_and(|r| input.frame_id < r + max_frames)
        && n_kfs as u64 > max_frames
    {
        return false;
    }
    let min_obs = if n_kfs <= 2 { 2 } else { 3 };
    let ref_matches = map.tracked_map_points(input.reference_kf, min_obs) as f64;
    let th_depth = camera.close_depth();
    let (mut tracked_close, mut untracked_close) = (0usize, 0usize);
    for i in 0..frame.len() {
        let Some(z) = frame.features.depth_of(i) else {
            continue;
        };
        if z < th_depth {
            if frame.map_points[i].is_some() && !frame.outliers[i] {
                tracked_close += 1;
            } else {
                untracked_close += 1;
            }
        }
    }
    let need_close =
        tracked_close < params.close_tracked_max && untracked_close > params.close_untracked_min;
    let ratio = if n_kfs < 2 {
        params.ref_ratio_single_keyframe
    } else {
        params.ref_ratio
    };
    let inliers = input.matches_inliers as f64;
    let since = input.frame_id.saturating_sub(input.last_keyframe_frame);
    let c1a = since >= max_frames;
    let idle = input.keyframes_in_queue == 0;
    let c1b = params.mapping_idle && idle && since >= params.min_frames;
    let c1c = inliers < ref_matches * params.ref_ratio_weak || need_close;
    let c2 =
        (inliers < ref_matches * ratio || need_close) && input.matches_inliers > params.min_inliers;
    (c1a || c1b || c1c) && c2 && (idle || input.keyframes_in_queue < MAX_KEYFRAMES_IN_QUEUE)
}

/// Keyframes that may wait for a busy local mapping before tracking stops inserting more
/// (ORB-SLAM2's RGB-D / stereo rule).
pub const MAX_KEYFRAMES_IN_QUEUE: usize = 3;
