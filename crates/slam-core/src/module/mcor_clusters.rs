//! MC-OR's clusters of the map points one frame matched, derived from the map once per frame
//! and shared by every gate of that frame: the motion-model and local-map pose optimizations,
//! relocalization's, and the per-frame statistics.
//!
//! A cluster is a function of the map: its point's keyframe observations and frame views, placed
//! with the keyframes' current poses. Tracking a frame changes none of them (only bookkeeping
//! counters), so within a frame a cluster built once stays right; the system forgets every
//! cluster when a frame starts. Each cluster is built as
//! [`map_point_cluster`](super::pose_estimation::map_point_cluster) builds it, feature for
//! feature and sum for sum, with each keyframe's inverse pose computed once per frame instead
//! of once per feature, into the reused arena of
//! [`PreparedClusters`]. Before this cache every gate rebuilt
//! every cluster: 54 % of an MC-OR run's instructions on the 300-frame kinect sequence.

use nalgebra::Isometry3;

use crate::data::{KeyFrameId, Map, MapPointId};
use crate::module::noise::ClusterViews;
use crate::techniques::mcor::ClusterFeature;
use crate::techniques::mcor_prepared::PreparedClusters;
use crate::Camera;

/// A generation no slot is ever tagged with (the cache starts at generation 0).
const NEVER: u64 = u64::MAX;

/// The frame's prepared clusters and the keyframe poses they were placed with.
#[derive(Clone, Debug, Default)]
pub struct FrameClusters {
    /// The frame the clusters belong to (`None`: empty).
    frame: Option<u64>,
    /// The reading the clusters were built with.
    views: Option<ClusterViews>,
    /// Bumped whenever the clusters are forgotten; tags the slots below.
    generation: u64,
    prepared: PreparedClusters,
    /// Per map point (by index): the generation and index of its prepared cluster.
    slots: Vec<(u64, usize)>,
    /// Per keyframe (by index): its camera-to-world poses this generation.
    keyframes: Vec<KeyFramePoses>,
}

/// A keyframe's camera-to-world poses as the clusters place features with them.
#[derive(Clone, Copy, Debug)]
struct KeyFramePoses {
    generation: u64,
    /// `T_wc` of a good keyframe (its observations' features).
    twc_good: Option<Isometry3<f64>>,
    /// The inverse of [`Map::keyframe_pose_any`] (frame views, culled references included).
    twc_any: Option<Isometry3<f64>>,
}

impl FrameClusters {
    /// Empty.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets every cluster: the map may have changed.
    pub fn invalidate(&mut self) {
        self.frame = None;
        self.generation += 1;
        self.prepared.clear();
    }

    /// Makes the cache that of frame `frame_id`, forgetting the clusters of any other frame.
    pub fn for_frame(&mut self, frame_id: u64) {
        if self.frame != Some(frame_id) {
            self.invalidate();
            self.frame = Some(frame_id);
        }
    }

    /// The prepared clusters (indices from [`cluster`](Self::cluster)).
    pub fn prepared(&self) -> &PreparedClusters {
        &self.prepared
    }

    /// The index of map point `id`'s cluster in [`prepared`](Self::prepared), built on first
    /// use in this frame; `None` when the point is not in the map (or culled).
    pub fn cluster(
        &mut self,
        map: &Map,
        id: MapPointId,
        camera: &Camera,
        views: ClusterViews,
    ) -> Option<usize> {
        let m = map.map_point(id)?;
        if self.views != Some(views) {
            self.generation += 1;
            self.prepared.clear();
            self.views = Some(views);
        }
        if self.slots.len() <= id.index() {
            self.slots.resize(id.index() + 1, (NEVER, 0));
        }
        let (generation, k) = self.slots[id.index()];
        if generation == self.generation {
            return Some(k);
        }
        self.prepared.begin();
        for (&kf, &idx) in &m.observations {
            let Some(k) = map.keyframe(kf) else {
                continue;
            };
            let Some(pc) = k.features.unproject_camera(idx, camera) else {
                continue;
            };
            let Some(twc) = self.poses(map, kf).twc_good else {
                continue;
            };
            if let Some(f) = ClusterFeature::new(kf.0 as u64, pc, &twc) {
                self.prepared.push(&f);
            }
        }
        if views == ClusterViews::EveryFrame {
            let (sum, count) = m.views.folded();
            self.prepared.add_folded(sum, count);
            for v in m.views.views() {
                let twk = self.poses(map, v.reference).twc_any;
                self.prepared.push(&v.feature_placed_by(twk.as_ref()));
            }
        }
        let k = self.prepared.finish(m.position);
        self.slots[id.index()] = (self.generation, k);
        Some(k)
    }

    /// `T_wc` of keyframe `kf` when good (`.0`), and the inverse of
    /// [`Map::keyframe_pose_any`] (`.1`); both computed once per frame.
    fn poses(&mut self, map: &Map, kf: KeyFrameId) -> &KeyFramePoses {
        if self.keyframes.len() <= kf.index() {
            self.keyframes.resize(
                kf.index() + 1,
                KeyFramePoses {
                    generation: NEVER,
                    twc_good: None,
                    twc_any: None,
                },
            );
        }
        let slot = &mut self.keyframes[kf.index()];
        if slot.generation != self.generation {
            *slot = KeyFramePoses {
                generation: self.generation,
                twc_good: map.keyframe(kf).map(|k| k.tcw.inverse()),
                twc_any: map.keyframe_pose_any(kf).map(|t| t.inverse()),
            };
        }
        slot
    }
}
