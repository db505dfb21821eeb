//! The frame being tracked (and the previous one): its shared features, its pose estimate and the
//! map point matched to each keypoint, with the outlier flags of the last pose optimization.

use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Vector3};

use super::features::Features;
use super::{KeyFrameId, MapPointId};

/// A frame in tracking. `map_points[i]` is the map point matched to keypoint `i`, `outliers[i]`
/// whether the last pose optimization rejected that match.
#[derive(Clone, Debug)]
pub struct TrackedFrame {
    /// Frame counter of the run (0-based, every input frame).
    pub id: u64,
    /// Capture time, seconds.
    pub timestamp: f64,
    /// Keypoints, descriptors, depth, grid.
    pub features: Arc<Features>,
    /// Pose estimate world -> camera, once known.
    pub tcw: Option<Isometry3<f64>>,
    /// Map point per keypoint.
    pub map_points: Vec<Option<MapPointId>>,
    /// Outlier flag per keypoint.
    pub outliers: Vec<bool>,
    /// Reference keyframe (the one sharing most map points, set by local-map tracking).
    pub reference_kf: Option<KeyFrameId>,
    /// Per keypoint: on a moving body according to the rigid consensus (beyond the paper;
    /// empty when it is off). Such keypoints create no map points at keyframe insertion.
    pub dynamic: Vec<bool>,
    /// BoW vector and direct index, once computed (only with a vocabulary, and only when
    /// reference tracking, relocalization or a new keyframe needs them).
    pub bow: Option<Arc<crate::place::FrameBow>>,
}

impl TrackedFrame {
    /// The frame's BoW (computed with `place` the first time it is asked for).
    pub fn bow(&mut self, place: &crate::place::PlaceRecognition) -> Arc<crate::place::FrameBow> {
        self.bow
            .get_or_insert_with(|| place.frame_bow(&self.features.descriptors))
            .clone()
    }

    /// A frame with no pose and no matches yet.
    pub fn new(id: u64, timestamp: f64, features: Arc<Features>) -> Self {
        let n = features.len();
        TrackedFrame {
            id,
            timestamp,
            features,
            tcw: None,
            map_points: vec![None; n],
            outliers: vec![false; n],
            reference_kf: None,
            dynamic: Vec::new(),
            bow: None,
        }
    }

    /// Number of keypoints.
    pub fn len(&self) -> usize {
        self.features.len()
    }

    /// Whether the frame has no keypoints.
    pub fn is_empty(&self) -> bool {
        self.features.is_empty()
    }

    /// Camera centre in the world (origin if the pose is unknown).
    pub fn center(&self) -> Vector3<f64> {
        self.tcw
            .map(|t| t.inverse_transform_point(&Point3::origin()).coords)
            .unwrap_or_else(Vector3::zeros)
    }

    /// Drops every match.
    pub fn clear_matches(&mut self) {
        self.map_points.iter_mut().for_each(|m| *m = None);
        self.outliers.iter_mut().for_each(|o| *o = false);
    }

    /// Number of matched keypoints.
    pub fn n_matches(&self) -> usize {
        self.map_points.iter().flatten().count()
    }

    /// Drops the matches the last pose optimization flagged as outliers.
    pub fn drop_outliers(&mut self) {
        for (m, o) in self.map_points.iter_mut().zip(self.outliers.iter_mut()) {
            if *o {
                *m = None;
                *o = false;
            }
        }
    }

    /// The map points matched so far (for searches that must not match them again).
    pub fn matched_map_points(&self) -> std::collections::BTreeSet<MapPointId> {
        self.map_points.iter().flatten().copied().collect()
    }
}
