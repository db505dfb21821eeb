//! MC-OR's clusters of the map points the frames match, derived from the map once and kept
//! while the map stands still: shared by every gate of a frame (motion-model, reference-keyframe,
//! relocalization and local-map pose optimizations, the per-frame statistics) and by the frames
//! between two changes of the map.
//!
//! A cluster is a function of the map: its point's position, keyframe observations and frame
//! views, placed with the keyframes' current poses. Tracking changes none of them but the views
//! (a tracked frame appends one to each point it kept), and [`ClusterCache::push_view`] appends
//! that view to a kept cluster as a rebuild would. Everything else that moves a cluster
//! (a new keyframe, local mapping and its BA, fusion and culling, loop closing, a global BA) is
//! the owner's to report with [`ClusterCache::invalidate`]; the [`System`](crate::system::System)
//! does so before a frame whenever the map changed since the last one. Each cluster is built
//! as [`map_point_cluster`](super::frame_gate::map_point_cluster) builds it, feature for
//! feature, with each keyframe's inverse pose computed once per map state instead of once per
//! feature. Before this cache every gate rebuilt every cluster: 54 % of an MC-OR run's
//! instructions on the 300-frame kinect sequence.
//!
//! Beside the clusters, the cache keeps the verdicts of the frame being gated ([`GateMemo`]),
//! so that its gates compute a verdict again only when the pose moved far enough to change it.

use nalgebra::Isometry3;

use super::cluster::ClusterFeature;
use super::prepared::{GateMemo, PreparedCluster};
use crate::data::{FrameView, FrameViews};
use crate::data::{KeyFrameId, Map, MapPointId};
use crate::techniques::params::{ClusterViews, McorParams};
use crate::Camera;

/// A generation no slot is ever tagged with (the cache starts at generation 0).
const NEVER: u64 = u64::MAX;

/// The prepared clusters of the map as it stands, and the keyframe poses they were placed with.
#[derive(Clone, Debug, Default)]
pub struct ClusterCache {
    /// The reading the clusters were built with.
    views: Option<ClusterViews>,
    /// Bumped whenever the clusters are forgotten; tags the slots below.
    generation: u64,
    /// Per map point (by index): the generation its cluster was built in, and the cluster.
    clusters: Vec<(u64, PreparedCluster)>,
    /// Per keyframe (by index): its camera-to-world poses this generation.
    keyframes: Vec<KeyFramePoses>,
    /// Checking: every kept cluster handed out is compared with one rebuilt from the map.
    check: bool,
    /// Kept clusters checked so far.
    checked: u64,
    /// The verdicts of the frame being gated (see [`GateMemo`]).
    memo: GateMemo,
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

impl ClusterCache {
    /// Empty.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets every cluster: the map changed.
    pub fn invalidate(&mut self) {
        self.generation += 1;
    }

    /// Makes sure map point `id`'s cluster is built for the map as it stands; `false` when the
    /// point is not in the map (or culled). Read it with [`cluster`](Self::cluster).
    pub fn prepare(
        &mut self,
        map: &Map,
        id: MapPointId,
        camera: &Camera,
        views: ClusterViews,
    ) -> bool {
        if map.map_point(id).is_none() {
            return false;
        }
        if self.views != Some(views) {
            self.invalidate();
            self.views = Some(views);
        }
        if self.clusters.len() <= id.index() {
            self.clusters
                .resize_with(id.index() + 1, || (NEVER, PreparedCluster::default()));
        }
        if self.clusters[id.index()].0 == self.generation {
            if self.check {
                let kept = std::mem::take(&mut self.clusters[id.index()].1);
                let rebuilt = self.build(map, id, camera, views, PreparedCluster::default(), true);
                assert_eq!(kept, rebuilt, "the kept cluster of {id} is not the map's");
                self.checked += 1;
                self.clusters[id.index()].1 = kept;
            }
            return true;
        }
        let cluster = std::mem::take(&mut self.clusters[id.index()].1);
        let cluster = self.build(map, id, camera, views, cluster, false);
        self.clusters[id.index()] = (self.generation, cluster);
        true
    }

    /// Checks every cluster the cache hands out again, against one rebuilt from the map (a
    /// difference panics): for tests of the cache's invalidation.
    pub fn set_check(&mut self, on: bool) {
        self.check = on;
    }

    /// Kept clusters checked against the map since [`set_check`](Self::set_check).
    pub fn checked(&self) -> u64 {
        self.checked
    }

    /// Map point `id`'s cluster built from the map into `cluster`'s buffer, with the keyframe
    /// poses kept for this generation or, `fresh`, read from the map again.
    fn build(
        &mut self,
        map: &Map,
        id: MapPointId,
        camera: &Camera,
        views: ClusterViews,
        mut cluster: PreparedCluster,
        fresh: bool,
    ) -> PreparedCluster {
        let poses = |cache: &mut Self, kf| {
            if fresh {
                cache.generation_poses(map, kf, NEVER)
            } else {
                *cache.poses(map, kf)
            }
        };
        let m = map.map_point(id).expect("checked by the caller");
        cluster.reset(m.position);
        for (&kf, &idx) in &m.observations {
            let Some(k) = map.keyframe(kf) else {
                continue;
            };
            let Some(pc) = k.features.unproject_camera(idx, camera) else {
                continue;
            };
            let Some(twc) = poses(self, kf).twc_good else {
                continue;
            };
            if let Some(f) = ClusterFeature::new(kf.0 as u64, pc, &twc) {
                cluster.push(&f);
            }
        }
        if views == ClusterViews::EveryFrame {
            let (sum, count) = m.views.folded();
            cluster.add_folded(sum, count);
            for v in m.views.views() {
                let twk = poses(self, v.reference).twc_any;
                cluster.push(&ClusterFeature::of_view_placed_by(v, twk.as_ref()));
            }
        }
        cluster.seal();
        cluster
    }

    /// The verdicts kept for frame `frame_id` (with `n_keypoints` keypoints) under `params`
    /// while the clusters stand, or an empty memo for them; give it back with
    /// [`put_memo`](Self::put_memo).
    pub fn take_memo(
        &mut self,
        frame_id: u64,
        n_keypoints: usize,
        params: &McorParams,
    ) -> GateMemo {
        let key = (frame_id, self.generation, self.views);
        let mut memo = std::mem::take(&mut self.memo);
        if memo.is_for(key, params) {
            return memo;
        }
        // A new frame (or map, or thresholds): forget the verdicts, keep the buffers.
        memo.start(key, params, n_keypoints, self.check);
        memo
    }

    /// Keeps `memo` for the frame's next gate.
    pub fn put_memo(&mut self, memo: GateMemo) {
        self.memo = memo;
    }

    /// Kept verdicts checked against computed ones since [`set_check`](Self::set_check).
    pub fn checked_verdicts(&self) -> u64 {
        self.memo.checked()
    }

    /// Map point `id`'s cluster, prepared for the map as it stands.
    ///
    /// # Panics
    /// When [`prepare`](Self::prepare) did not build it since the last invalidation (a caller
    /// bug).
    pub fn cluster(&self, id: MapPointId) -> &PreparedCluster {
        let (generation, cluster) = &self.clusters[id.index()];
        assert_eq!(*generation, self.generation, "cluster of {id} not prepared");
        cluster
    }

    /// Tells the cache that `view` was just pushed onto map point `id`'s frame views, which now
    /// are `views`: a cluster kept for the point takes it as a rebuild would. (Views of a point
    /// without a kept cluster need nothing: it is built from the map when needed.)
    pub fn push_view(&mut self, map: &Map, id: MapPointId, view: &FrameView, views: &FrameViews) {
        if self.views != Some(ClusterViews::EveryFrame) {
            return;
        }
        if !matches!(self.clusters.get(id.index()), Some((g, _)) if *g == self.generation) {
            return;
        }
        let twk = self.poses(map, view.reference).twc_any;
        let feature = ClusterFeature::of_view_placed_by(view, twk.as_ref());
        self.clusters[id.index()]
            .1
            .push_view(&feature, views.folded(), views.views().len());
    }

    /// `T_wc` of keyframe `kf` when good, and the inverse of [`Map::keyframe_pose_any`]; both
    /// computed once per generation.
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
        if self.keyframes[kf.index()].generation != self.generation {
            self.keyframes[kf.index()] = self.generation_poses(map, kf, self.generation);
        }
        &self.keyframes[kf.index()]
    }

    /// Keyframe `kf`'s poses read from the map, tagged `generation`.
    fn generation_poses(&self, map: &Map, kf: KeyFrameId, generation: u64) -> KeyFramePoses {
        KeyFramePoses {
            generation,
            twc_good: map.keyframe(kf).map(|k| k.tcw.inverse()),
            twc_any: map.keyframe_pose_any(kf).map(|t| t.inverse()),
        }
    }
}
