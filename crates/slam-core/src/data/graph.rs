//! Covisibility graph and spanning tree maintenance (ORB-SLAM2's UpdateConnections and the
//! graph part of KeyFrame::SetBadFlag).

use std::collections::{BTreeMap, BTreeSet};

use super::{KeyFrameId, Map};

/// Minimum number of shared map points for a covisibility edge (ORB-SLAM2: 15).
pub const COVISIBILITY_MIN_WEIGHT: u32 = 15;

impl Map {
    /// Recomputes the covisibility edges of `kf` from its map points' observations: edges of
    /// weight >= 15 (or only the strongest when none reaches 15) on both sides. On the first
    /// update the strongest neighbour becomes the spanning-tree parent.
    pub fn update_connections(&mut self, kf: KeyFrameId) {
        let Some(k) = self.keyframe(kf) else {
            return;
        };
        let mut counter: BTreeMap<KeyFrameId, u32> = BTreeMap::new();
        for mp in k.map_points.iter().flatten() {
            let Some(m) = self.map_point(*mp) else {
                continue;
            };
            for &other in m.observations.keys() {
                if other != kf && self.keyframe(other).is_some() {
                    *counter.entry(other).or_insert(0) += 1;
                }
            }
        }
        if counter.is_empty() {
            return;
        }
        let mut best = (KeyFrameId(0), 0u32);
        for (&other, &w) in &counter {
            if w > best.1 {
                best = (other, w);
            }
        }
        let mut kept: BTreeMap<KeyFrameId, u32> = counter
            .iter()
            .filter(|&(_, &w)| w >= COVISIBILITY_MIN_WEIGHT)
            .map(|(&o, &w)| (o, w))
            .collect();
        if kept.is_empty() {
            kept.insert(best.0, best.1);
        }
        for (&other, &w) in &kept {
            let o = self.keyframe_any_mut(other);
            o.connections.insert(kf, w);
            o.sort_connections();
        }
        let is_root = kf.0 == 0;
        let k = self.keyframe_any_mut(kf);
        k.connections = kept;
        k.sort_connections();
        if k.parent.is_none() && !is_root {
            let parent = k.ordered_connections[0].0;
            k.parent = Some(parent);
            self.keyframe_any_mut(parent).children.insert(kf);
        }
    }

    /// Culls a keyframe (never the first one, nor one with loop edges): drops its edges and observations (points left
    /// with too few observations are culled too), hands its children to the best-connected
    /// keyframe among its parent and already re-attached siblings, and stores its pose relative
    /// to its parent for the trajectory.
    pub fn set_keyframe_bad(&mut self, kf: KeyFrameId) {
        if kf.0 == 0 || self.keyframe(kf).is_none_or(|k| !k.loop_edges.is_empty()) {
            return;
        }
        let connections: Vec<KeyFrameId> = self.keyframe_any_mut(kf).covisibles();
        for other in connections {
            let o = self.keyframe_any_mut(other);
            o.connections.remove(&kf);
            o.sort_connections();
        }
        let points: Vec<_> = self
            .keyframe_any_mut(kf)
            .map_points
            .iter()
            .flatten()
            .copied()
            .collect();
        for mp in points {
            if self.map_point(mp).is_some() {
                self.erase_observation(mp, kf);
            }
        }
        let (parent, mut children) = {
            let k = self.keyframe_any_mut(kf);
            k.connections.clear();
            k.ordered_connections.clear();
            (k.parent, std::mem::take(&mut k.children))
        };
        let Some(parent) = parent else {
            self.flag_keyframe_bad(kf);
            return;
        };
        let mut candidates: BTreeSet<KeyFrameId> = BTreeSet::new();
        candidates.insert(parent);
        while !children.is_empty() {
            let mut best: Option<(KeyFrameId, KeyFrameId, u32)> = None;
            for &child in &children {
                let Some(c) = self.keyframe(child) else {
                    continue;
                };
                for &(neighbour, w) in &c.ordered_connections {
                    if candidates.contains(&neighbour) && best.is_none_or(|b| w > b.2) {
                        best = Some((child, neighbour, w));
                    }
                }
            }
            let Some((child, new_parent, _)) = best else {
                break;
            };
            self.keyframe_any_mut(child).parent = Some(new_parent);
            self.keyframe_any_mut(new_parent).children.insert(child);
            candidates.insert(child);
            children.remove(&child);
        }
        for child in children {
            self.keyframe_any_mut(child).parent = Some(parent);
            self.keyframe_any_mut(parent).children.insert(child);
        }
        let parent_tcw = self.keyframe_any_mut(parent).tcw;
        self.keyframe_any_mut(parent).children.remove(&kf);
        let k = self.keyframe_any_mut(kf);
        k.t_child_parent = Some(k.tcw * parent_tcw.inverse());
        self.flag_keyframe_bad(kf);
    }

    /// Pose (world -> camera) of a keyframe even if culled: a culled keyframe's pose is its
    /// stored pose relative to its parent composed with the parent's (recursively).
    pub fn keyframe_pose_any(&self, kf: KeyFrameId) -> Option<nalgebra::Isometry3<f64>> {
        let mut cur = self.keyframe_any(kf)?;
        let mut t = nalgebra::Isometry3::identity();
        for _ in 0..100_000 {
            if !cur.bad {
                return Some(t * cur.tcw);
            }
            t *= cur.t_child_parent?;
            cur = self.keyframe_any(cur.parent?)?;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use nalgebra::{Isometry3, Vector3};

    use super::*;
    use crate::camera::Camera;
    use crate::data::features::tests::kp;
    use crate::data::features::Features;

    fn features(n: usize) -> Arc<Features> {
        let kps = (0..n)
            .map(|i| kp((i % 600) as f32 + 10.0, (i / 600) as f32 * 10.0 + 10.0, 0))
            .collect();
        Arc::new(Features::new(
            kps,
            (0..n).map(|i| [i as u64, 0, 0, 0]).collect(),
            vec![1.0; n],
            vec![100.0; n],
            &Camera::tum_fr3(),
        ))
    }

    /// Three keyframes; KF0-KF1 share 20 points, KF1-KF2 share 20, KF0-KF2 share 5.
    fn small_map() -> Map {
        let mut map = Map::new();
        let f = features(100);
        let ids: Vec<_> = (0..3)
            .map(|i| {
                let t = Isometry3::translation(0.1 * i as f64, 0.0, 0.0);
                map.create_keyframe(i, i as f64, t, f.clone())
            })
            .collect();
        let mut next = 0;
        let mut shared = |map: &mut Map, a: usize, b: usize, n: usize| {
            for _ in 0..n {
                let mp = map.create_map_point(Vector3::new(0.0, 0.0, 2.0), [0; 4], ids[a]);
                map.add_observation(mp, ids[a], next);
                map.add_observation(mp, ids[b], next);
                next += 1;
            }
        };
        shared(&mut map, 0, 1, 20);
        shared(&mut map, 1, 2, 20);
        shared(&mut map, 0, 2, 5);
        for &k in &ids {
            map.update_connections(k);
        }
        map
    }

    #[test]
    fn covisibility_weights_and_tree() {
        let map = small_map();
        let k0 = map.keyframe(KeyFrameId(0)).unwrap();
        let k1 = map.keyframe(KeyFrameId(1)).unwrap();
        let k2 = map.keyframe(KeyFrameId(2)).unwrap();
        assert_eq!(k1.weight(KeyFrameId(0)), 20);
        assert_eq!(k1.weight(KeyFrameId(2)), 20);
        // The weak KF0-KF2 edge (5 < 15) is not kept.
        assert_eq!(k0.weight(KeyFrameId(2)), 0);
        assert_eq!(k2.weight(KeyFrameId(0)), 0);
        assert_eq!(k1.parent, Some(KeyFrameId(0)));
        assert_eq!(k2.parent, Some(KeyFrameId(1)));
        assert!(k0.parent.is_none());
        // Observations both ways.
        for mp in map.map_points() {
            for (&kf, &idx) in &mp.observations {
                assert_eq!(map.keyframe(kf).unwrap().map_points[idx], Some(mp.id));
            }
            assert_eq!(mp.n_obs, 4);
        }
    }

    #[test]
    fn culling_a_keyframe_reattaches_children_and_keeps_poses() {
        let mut map = small_map();
        let before = map.keyframe(KeyFrameId(1)).unwrap().tcw;
        map.set_keyframe_bad(KeyFrameId(1));
        assert!(map.keyframe(KeyFrameId(1)).is_none());
        assert_eq!(map.keyframe_count(), 2);
        assert_eq!(
            map.keyframe(KeyFrameId(2)).unwrap().parent,
            Some(KeyFrameId(0))
        );
        assert!(map
            .keyframe(KeyFrameId(0))
            .unwrap()
            .children
            .contains(&KeyFrameId(2)));
        // Points seen only by KF1 and one other (n_obs 4 -> 2) are culled.
        assert_eq!(map.map_point_count(), 5);
        let pose = map.keyframe_pose_any(KeyFrameId(1)).unwrap();
        assert!((pose.translation.vector - before.translation.vector).norm() < 1e-12);
    }

    #[test]
    fn replace_moves_observations() {
        let mut map = small_map();
        let v: Vec<_> = map.map_points().map(|m| m.id).take(2).collect();
        let a = (v[0], v[1]);
        map.replace_map_point(a.0, a.1);
        assert!(map.map_point(a.0).is_none());
        assert_eq!(map.resolve(a.0), Some(a.1));
        // Both points were seen by KF0 and KF1: the duplicate slots are cleared.
        let m = map.map_point(a.1).unwrap();
        assert_eq!(m.observations.len(), 2);
        let k0 = map.keyframe(KeyFrameId(0)).unwrap();
        assert_eq!(
            k0.map_points
                .iter()
                .flatten()
                .filter(|&&p| p == a.0)
                .count(),
            0
        );
    }
}
