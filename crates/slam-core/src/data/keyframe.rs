//! A keyframe: a frame kept in the map, with its pose, its features, the map point matched to
//! each keypoint, its covisibility edges and its place in the spanning tree.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Vector3};

use super::features::Features;
use super::{KeyFrameId, MapPointId};

/// A keyframe. `map_points[i]` is the map point matched to keypoint `i`.
#[derive(Clone, Debug)]
pub struct KeyFrame {
    /// Arena id (creation order).
    pub id: KeyFrameId,
    /// Id of the frame it was made from.
    pub frame_id: u64,
    /// Capture time, seconds.
    pub timestamp: f64,
    /// Pose: world -> camera.
    pub tcw: Isometry3<f64>,
    /// Keypoints, descriptors, depth and grid, shared with the frame it came from.
    pub features: Arc<Features>,
    /// Map point per keypoint.
    pub map_points: Vec<Option<MapPointId>>,
    /// Covisibility edges: neighbour -> number of shared map points (only edges kept by the
    /// last connection update: weight >= 15, or the single strongest).
    pub connections: BTreeMap<KeyFrameId, u32>,
    /// `connections` sorted by decreasing weight, ties by increasing id.
    pub ordered_connections: Vec<(KeyFrameId, u32)>,
    /// Spanning-tree parent (the neighbour of highest weight at the first connection update).
    pub parent: Option<KeyFrameId>,
    /// Spanning-tree children.
    pub children: BTreeSet<KeyFrameId>,
    /// Culled: kept in the arena so frames referencing it still resolve their pose.
    pub bad: bool,
    /// Pose relative to its parent (`Tcw * Twp`), fixed when the keyframe is culled, so the
    /// trajectory of frames referencing it follows later corrections of the parent.
    pub t_child_parent: Option<Isometry3<f64>>,
    /// Tracking marker: id + 1 of the last frame whose local map included this keyframe.
    pub track_reference_frame: u64,
    /// Local-mapping markers: id + 1 of the keyframe whose local BA made this one a variable /
    /// a fixed keyframe, or whose fusion targeted it.
    pub ba_local_for_kf: u32,
    /// See `ba_local_for_kf`.
    pub ba_fixed_for_kf: u32,
    /// See `ba_local_for_kf`.
    pub fuse_target_for_kf: u32,
    /// BoW vector and direct index (when the system has a vocabulary).
    pub bow: Option<Arc<crate::place::FrameBow>>,
    /// Keyframes a closed loop linked to this one: edges of the essential graph, and the
    /// reason this keyframe is never culled (ORB-SLAM2's loop edges and `mbNotErase`).
    pub loop_edges: BTreeSet<KeyFrameId>,
}

impl KeyFrame {
    /// A keyframe without map points or edges.
    pub fn new(
        id: KeyFrameId,
        frame_id: u64,
        timestamp: f64,
        tcw: Isometry3<f64>,
        features: Arc<Features>,
    ) -> Self {
        let n = features.len();
        KeyFrame {
            id,
            frame_id,
            timestamp,
            tcw,
            features,
            map_points: vec![None; n],
            connections: BTreeMap::new(),
            ordered_connections: Vec::new(),
            parent: None,
            children: BTreeSet::new(),
            bad: false,
            t_child_parent: None,
            track_reference_frame: 0,
            ba_local_for_kf: 0,
            ba_fixed_for_kf: 0,
            fuse_target_for_kf: 0,
            bow: None,
            loop_edges: BTreeSet::new(),
        }
    }

    /// Camera centre in the world frame.
    pub fn center(&self) -> Vector3<f64> {
        self.tcw.inverse_transform_point(&Point3::origin()).coords
    }

    /// World point expressed in camera coordinates.
    #[inline]
    pub fn to_camera(&self, pw: &Vector3<f64>) -> Vector3<f64> {
        self.tcw.transform_point(&Point3::from(*pw)).coords
    }

    /// Covisibility weight towards `other` (0 when not connected).
    pub fn weight(&self, other: KeyFrameId) -> u32 {
        self.connections.get(&other).copied().unwrap_or(0)
    }

    /// The `n` neighbours of highest weight.
    pub fn best_covisibles(&self, n: usize) -> Vec<KeyFrameId> {
        self.ordered_connections
            .iter()
            .take(n)
            .map(|&(k, _)| k)
            .collect()
    }

    /// All neighbours by decreasing weight.
    pub fn covisibles(&self) -> Vec<KeyFrameId> {
        self.ordered_connections.iter().map(|&(k, _)| k).collect()
    }

    /// Recomputes `ordered_connections` from `connections`.
    pub(crate) fn sort_connections(&mut self) {
        let mut v: Vec<(KeyFrameId, u32)> =
            self.connections.iter().map(|(&k, &w)| (k, w)).collect();
        v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        self.ordered_connections = v;
    }
}
