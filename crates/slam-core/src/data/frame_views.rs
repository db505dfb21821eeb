//! A map point's frame views: the sightings by tracked frames that MC-OR's every-frame reading
//! clusters (paper III-A: a landmark "tracked across N camera views", its centroid G "updated
//! after every camera viewpoint"), stored on the point as the map's data.
//!
//! With `ClusterViews::EveryFrame` (MC-OR's `cluster_views`), every tracked frame that keeps a
//! match of a map point as an inlier (under `sightings = "all"`: every matched sighting, outliers
//! included; see `techniques::mcor::frame_gate::frame_sightings`) and is not made a keyframe (a keyframe's observation is in
//! the cluster already) stores its 3-D feature on the point. A view is kept relative to the
//! frame's reference keyframe, so when bundle adjustment or a loop correction moves that
//! keyframe the view moves with it, as keyframe observations do. Memory is bounded as
//! MC-OR's cluster's: the [`MCOR_CLUSTER_CAPACITY`] most recent views individually, older ones
//! folded into a running world sum (placed where they were when folded).

use std::collections::VecDeque;

use nalgebra::{Isometry3, Point3, Vector3};

use crate::ids::KeyFrameId;

/// How many sightings a map point's record, and MC-OR's cluster built from it, hold
/// individually: the most recent ones; older ones are folded into a running sum of their world
/// positions (the paper bounds neither; this bounds memory and the gate's cost).
pub const MCOR_CLUSTER_CAPACITY: usize = 32;

/// Tag of a frame view's `source` in a cluster (keyframe ids and the current frame's tag never
/// carry this bit), so views never collide with keyframe observations.
pub const FRAME_VIEW_SOURCE_BIT: u64 = 1 << 62;

/// One frame's 3-D feature of a map point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameView {
    /// Id of the frame that saw the point.
    pub frame: u64,
    /// The frame's reference keyframe, which carries the view when the map moves.
    pub reference: KeyFrameId,
    /// The keypoint back-projected with its measured depth, in the frame's camera (metres).
    pub point_camera: Vector3<f64>,
    /// The same point in the reference keyframe's camera, from the frame's tracked pose.
    pub point_reference: Vector3<f64>,
    /// The same point in the world when it was stored (used if the keyframe is gone).
    pub point_world: Vector3<f64>,
}

impl FrameView {
    /// The view of frame `frame` tracked at `tcw` (world to camera), with reference keyframe
    /// `reference` at `tkw` (world to keyframe camera), of a keypoint back-projected to
    /// `point_camera`. `None` without a finite positive depth.
    pub fn new(
        frame: u64,
        tcw: &Isometry3<f64>,
        reference: KeyFrameId,
        tkw: &Isometry3<f64>,
        point_camera: Vector3<f64>,
    ) -> Option<FrameView> {
        Self::placed(frame, &tcw.inverse(), reference, tkw, point_camera)
    }

    /// [`new`](Self::new) given the frame's inverse pose `twc` (camera to world): for callers
    /// storing many views of one frame (the same bits as `new` with `twc.inverse()`).
    pub fn placed(
        frame: u64,
        twc: &Isometry3<f64>,
        reference: KeyFrameId,
        tkw: &Isometry3<f64>,
        point_camera: Vector3<f64>,
    ) -> Option<FrameView> {
        let finite = point_camera.iter().all(|x| x.is_finite());
        if !finite || point_camera.z <= 0.0 {
            return None;
        }
        let world = twc * Point3::from(point_camera);
        Some(FrameView {
            frame,
            reference,
            point_camera,
            point_reference: (tkw * world).coords,
            point_world: world.coords,
        })
    }
}

/// The frame views of one map point, with bounded memory.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameViews {
    recent: VecDeque<FrameView>,
    folded_sum: Vector3<f64>,
    folded_count: u64,
}

impl FrameViews {
    /// Adds the newest view; when full, the oldest is folded into the running sum at its
    /// stored world position.
    pub fn push(&mut self, view: FrameView) {
        if self.recent.len() == MCOR_CLUSTER_CAPACITY {
            if let Some(old) = self.recent.pop_front() {
                self.folded_sum += old.point_world;
                self.folded_count += 1;
            }
        }
        self.recent.push_back(view);
    }

    /// Absorbs the views of a point fused into this one (map-point replacement), in frame
    /// order; views of a frame already present are not repeated.
    pub fn merge(&mut self, other: &FrameViews) {
        self.folded_sum += other.folded_sum;
        self.folded_count += other.folded_count;
        let mut all: Vec<FrameView> = self.recent.drain(..).collect();
        for v in &other.recent {
            if !all.iter().any(|w| w.frame == v.frame) {
                all.push(*v);
            }
        }
        all.sort_by_key(|v| v.frame);
        for v in all {
            self.push(v);
        }
    }

    /// Views held individually, oldest first.
    pub fn views(&self) -> impl ExactSizeIterator<Item = &FrameView> + '_ {
        self.recent.iter()
    }

    /// The world positions of the views folded out of the ring, summed, and their number.
    pub fn folded(&self) -> (Vector3<f64>, u64) {
        (self.folded_sum, self.folded_count)
    }

    /// Every view ever stored, folded ones included.
    pub fn total_count(&self) -> u64 {
        self.folded_count + self.recent.len() as u64
    }

    /// Whether no view was ever stored.
    pub fn is_empty(&self) -> bool {
        self.total_count() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merging_keeps_frame_order_and_drops_repeats() {
        let id = Isometry3::identity();
        let view = |f: u64| {
            FrameView::new(f, &id, KeyFrameId(0), &id, Vector3::new(0.0, 0.0, 1.0)).unwrap()
        };
        let mut a = FrameViews::default();
        let mut b = FrameViews::default();
        for f in [1, 4, 6] {
            a.push(view(f));
        }
        for f in [2, 4, 9] {
            b.push(view(f));
        }
        a.merge(&b);
        let frames: Vec<u64> = a.views().map(|v| v.frame).collect();
        assert_eq!(frames, vec![1, 2, 4, 6, 9]);
    }
}
