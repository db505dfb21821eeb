//! A map point (landmark): a 3-D position in the world with the keyframes that observe it, a
//! representative descriptor, a mean viewing direction and the distance range over which ORB's
//! scale pyramid can detect it.

use std::collections::BTreeMap;

use nalgebra::Vector3;

use super::frame_views::FrameViews;
use super::{KeyFrameId, MapPointId, ScaleLevels};
use crate::feature::Descriptor;

/// A 3-D landmark. Observations map each observing keyframe to the keypoint index in it.
#[derive(Clone, Debug)]
pub struct MapPoint {
    /// Arena id.
    pub id: MapPointId,
    /// Position in the world frame, metres.
    pub position: Vector3<f64>,
    /// Mean unit viewing direction (from the observing cameras to the point).
    pub normal: Vector3<f64>,
    /// Representative descriptor: the observation with the least median distance to the others.
    pub descriptor: Descriptor,
    /// Observing keyframes and the keypoint index in each (ordered by keyframe id).
    pub observations: BTreeMap<KeyFrameId, usize>,
    /// Number of observations, counting 2 for a stereo / RGB-D one (ORB-SLAM2's `nObs`).
    pub n_obs: u32,
    /// Keyframe whose observation sets the scale-invariance range.
    pub reference_kf: KeyFrameId,
    /// Keyframe that created the point (recent-point culling counts keyframes since it).
    pub first_kf: KeyFrameId,
    /// Minimum distance at which ORB can still detect the point (coarsest level), metres.
    pub min_distance: f64,
    /// Maximum distance at which ORB can still detect the point (finest level), metres.
    pub max_distance: f64,
    /// Frames in whose frustum the point was predicted to be (tracking statistics).
    pub n_visible: u32,
    /// Frames in which the point was actually matched and kept as an inlier.
    pub n_found: u32,
    /// When the point was fused into another, the one that replaced it.
    pub replaced_by: Option<MapPointId>,
    /// Culled (or replaced): kept in the arena only so stale ids resolve.
    pub bad: bool,
    /// Tracking marker: id + 1 of the last frame whose local map included this point.
    pub track_reference_frame: u64,
    /// Tracking marker: id + 1 of the last frame that matched this point.
    pub last_frame_seen: u64,
    /// Local-mapping marker: id + 1 of the keyframe whose fusion last considered this point.
    pub fuse_candidate_for_kf: u32,
    /// Local-mapping marker: id + 1 of the keyframe whose local BA last included this point.
    pub ba_local_for_kf: u32,
    /// MC-OR's frame views of the point (only stored under
    /// `ClusterViews::EveryFrame`; empty otherwise).
    pub views: FrameViews,
}

impl MapPoint {
    /// A new point seen by `kf` (observations are added through [`crate::data::Map`]).
    pub fn new(
        id: MapPointId,
        position: Vector3<f64>,
        descriptor: Descriptor,
        kf: KeyFrameId,
    ) -> Self {
        MapPoint {
            id,
            position,
            normal: Vector3::zeros(),
            descriptor,
            observations: BTreeMap::new(),
            n_obs: 0,
            reference_kf: kf,
            first_kf: kf,
            min_distance: 0.0,
            max_distance: f64::INFINITY,
            n_visible: 1,
            n_found: 1,
            replaced_by: None,
            bad: false,
            track_reference_frame: 0,
            last_frame_seen: 0,
            fuse_candidate_for_kf: 0,
            ba_local_for_kf: 0,
            views: FrameViews::default(),
        }
    }

    /// Ratio of frames that matched the point to frames that should have (culling statistic).
    pub fn found_ratio(&self) -> f64 {
        self.n_found as f64 / self.n_visible.max(1) as f64
    }

    /// The pyramid level at which a point at `distance` metres should be detected
    /// (ORB-SLAM2's `PredictScale`), clamped to the pyramid.
    pub fn predict_scale(&self, distance: f64, levels: &ScaleLevels) -> usize {
        predict_scale(self.max_distance, distance, levels)
    }

    /// Whether `kf` observes the point.
    pub fn is_observed_by(&self, kf: KeyFrameId) -> bool {
        self.observations.contains_key(&kf)
    }
}

/// Pyramid level predicted for a point of maximum detection distance `max_distance` seen at
/// `distance`: `ceil(log(max_distance / distance) / log(scale_factor))`, clamped.
pub fn predict_scale(max_distance: f64, distance: f64, levels: &ScaleLevels) -> usize {
    let ratio = max_distance / distance.max(1e-9);
    let level = (ratio.ln() / levels.log_scale_factor).ceil();
    if level.is_nan() || level < 0.0 {
        0
    } else {
        (level as usize).min(levels.n_levels - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn predicted_scale_grows_as_point_approaches() {
        let levels = ScaleLevels::new(8, 1.2);
        // A point first seen at level 0 from 2 m: max distance 2 m.
        assert_eq!(predict_scale(2.0, 2.0, &levels), 0);
        assert_eq!(predict_scale(2.0, 2.0 / 1.2, &levels), 1);
        assert_eq!(predict_scale(2.0, 2.0 / 1.2f64.powi(3) + 1e-9, &levels), 3);
        assert_eq!(predict_scale(2.0, 0.01, &levels), 7);
        assert_eq!(predict_scale(2.0, 5.0, &levels), 0);
    }
}
