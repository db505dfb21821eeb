//! The map arenas and the observation bookkeeping that keeps keyframes and map points
//! consistent both ways (ORB-SLAM2's AddObservation / EraseObservation / Replace / SetBadFlag).

use std::sync::Arc;

use nalgebra::{Isometry3, Vector3};

use super::features::Features;
use super::{KeyFrame, KeyFrameId, MapPoint, MapPointId, ScaleLevels};
use crate::feature::{hamming, Descriptor};

/// All keyframes and map points of a run. Culled entries stay in the arenas flagged `bad`
/// (stale ids keep resolving); accessors without `_any` return only good ones.
#[derive(Clone, Debug, Default)]
pub struct Map {
    keyframes: Vec<KeyFrame>,
    map_points: Vec<MapPoint>,
    n_good_keyframes: usize,
    n_good_map_points: usize,
}

impl Map {
    /// An empty map.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of keyframes not culled.
    pub fn keyframe_count(&self) -> usize {
        self.n_good_keyframes
    }

    /// Number of map points not culled.
    pub fn map_point_count(&self) -> usize {
        self.n_good_map_points
    }

    /// Adds a keyframe (without map points or edges) and returns its id.
    pub fn create_keyframe(
        &mut self,
        frame_id: u64,
        timestamp: f64,
        tcw: Isometry3<f64>,
        features: Arc<Features>,
    ) -> KeyFrameId {
        let id = KeyFrameId(self.keyframes.len() as u32);
        self.keyframes
            .push(KeyFrame::new(id, frame_id, timestamp, tcw, features));
        self.n_good_keyframes += 1;
        id
    }

    /// Adds a map point (without observations) and returns its id.
    pub fn create_map_point(
        &mut self,
        position: Vector3<f64>,
        descriptor: Descriptor,
        reference_kf: KeyFrameId,
    ) -> MapPointId {
        let id = MapPointId(self.map_points.len() as u32);
        self.map_points
            .push(MapPoint::new(id, position, descriptor, reference_kf));
        self.n_good_map_points += 1;
        id
    }

    /// A good keyframe.
    #[inline]
    pub fn keyframe(&self, id: KeyFrameId) -> Option<&KeyFrame> {
        self.keyframes.get(id.index()).filter(|k| !k.bad)
    }

    /// A keyframe, culled or not.
    #[inline]
    pub fn keyframe_any(&self, id: KeyFrameId) -> Option<&KeyFrame> {
        self.keyframes.get(id.index())
    }

    /// A good keyframe, mutably.
    #[inline]
    pub fn keyframe_mut(&mut self, id: KeyFrameId) -> Option<&mut KeyFrame> {
        self.keyframes.get_mut(id.index()).filter(|k| !k.bad)
    }

    /// A good map point.
    #[inline]
    pub fn map_point(&self, id: MapPointId) -> Option<&MapPoint> {
        self.map_points.get(id.index()).filter(|m| !m.bad)
    }

    /// A map point, culled or not.
    #[inline]
    pub fn map_point_any(&self, id: MapPointId) -> Option<&MapPoint> {
        self.map_points.get(id.index())
    }

    /// A good map point, mutably.
    #[inline]
    pub fn map_point_mut(&mut self, id: MapPointId) -> Option<&mut MapPoint> {
        self.map_points.get_mut(id.index()).filter(|m| !m.bad)
    }

    /// Good keyframes in id order.
    pub fn keyframes(&self) -> impl Iterator<Item = &KeyFrame> {
        self.keyframes.iter().filter(|k| !k.bad)
    }

    /// Good map points in id order.
    pub fn map_points(&self) -> impl Iterator<Item = &MapPoint> {
        self.map_points.iter().filter(|m| !m.bad)
    }

    /// Ids of good keyframes in id order.
    pub fn keyframe_ids(&self) -> Vec<KeyFrameId> {
        self.keyframes().map(|k| k.id).collect()
    }

    /// Follows the replacement chain of a fused point to the good point that stands for it.
    pub fn resolve(&self, id: MapPointId) -> Option<MapPointId> {
        let mut cur = id;
        for _ in 0..64 {
            let mp = self.map_points.get(cur.index())?;
            if !mp.bad {
                return Some(cur);
            }
            cur = mp.replaced_by?;
        }
        None
    }

    /// Records that keypoint `idx` of `kf` observes `mp` (both directions). A stereo / RGB-D
    /// observation counts twice in `n_obs`, as in ORB-SLAM2.
    pub fn add_observation(&mut self, mp: MapPointId, kf: KeyFrameId, idx: usize) {
        let stereo = {
            let k = &mut self.keyframes[kf.index()];
            k.map_points[idx] = Some(mp);
            k.features.u_right[idx] >= 0.0
        };
        let m = &mut self.map_points[mp.index()];
        if m.observations.insert(kf, idx).is_none() {
            m.n_obs += if stereo { 2 } else { 1 };
        }
    }

    /// Removes the observation of `mp` by `kf` (both directions). A point left with two or fewer
    /// observations (`n_obs`) is culled, as in ORB-SLAM2.
    pub fn erase_observation(&mut self, mp: MapPointId, kf: KeyFrameId) {
        let Some(idx) = self.map_points[mp.index()].observations.remove(&kf) else {
            return;
        };
        let stereo = {
            let k = &mut self.keyframes[kf.index()];
            if k.map_points[idx] == Some(mp) {
                k.map_points[idx] = None;
            }
            k.features.u_right[idx] >= 0.0
        };
        let m = &mut self.map_points[mp.index()];
        m.n_obs = m.n_obs.saturating_sub(if stereo { 2 } else { 1 });
        if m.reference_kf == kf {
            if let Some((&first, _)) = m.observations.iter().next() {
                m.reference_kf = first;
            }
        }
        if m.n_obs <= 2 {
            self.set_map_point_bad(mp);
        }
    }

    /// Culls a map point: removes it from every observing keyframe.
    pub fn set_map_point_bad(&mut self, mp: MapPointId) {
        let m = &mut self.map_points[mp.index()];
        if m.bad {
            return;
        }
        m.bad = true;
        self.n_good_map_points -= 1;
        let obs = std::mem::take(&mut m.observations);
        m.n_obs = 0;
        for (kf, idx) in obs {
            let k = &mut self.keyframes[kf.index()];
            if k.map_points[idx] == Some(mp) {
                k.map_points[idx] = None;
            }
        }
    }

    /// Fuses `old` into `new` (ORB-SLAM2's Replace): every keyframe that saw `old` now sees
    /// `new` unless it already does; `old` is culled and points to `new`.
    pub fn replace_map_point(&mut self, old: MapPointId, new: MapPointId) {
        if old == new || self.map_points[old.index()].bad || self.map_points[new.index()].bad {
            return;
        }
        let (obs, found, visible, views) = {
            let m = &mut self.map_points[old.index()];
            m.bad = true;
            m.replaced_by = Some(new);
            m.n_obs = 0;
            (
                std::mem::take(&mut m.observations),
                m.n_found,
                m.n_visible,
                std::mem::take(&mut m.views),
            )
        };
        self.n_good_map_points -= 1;
        for (kf, idx) in obs {
            if self.map_points[new.index()].observations.contains_key(&kf) {
                let k = &mut self.keyframes[kf.index()];
                if k.map_points[idx] == Some(old) {
                    k.map_points[idx] = None;
                }
            } else {
                self.add_observation(new, kf, idx);
            }
        }
        let m = &mut self.map_points[new.index()];
        m.n_found += found;
        m.n_visible += visible;
        if !views.is_empty() {
            m.views.merge(&views);
        }
        self.compute_distinctive_descriptor(new);
    }

    /// Sets the representative descriptor of `mp`: the observed descriptor with the least median
    /// Hamming distance to the others.
    pub fn compute_distinctive_descriptor(&mut self, mp: MapPointId) {
        let descs: Vec<Descriptor> = self.map_points[mp.index()]
            .observations
            .iter()
            .filter_map(|(kf, &idx)| {
                let k = &self.keyframes[kf.index()];
                (!k.bad).then(|| k.features.descriptors[idx])
            })
            .collect();
        let n = descs.len();
        if n == 0 {
            return;
        }
        let mut best = (u32::MAX, 0usize);
        let mut row = vec![0u32; n];
        for i in 0..n {
            for j in 0..n {
                row[j] = hamming(&descs[i], &descs[j]);
            }
            row.sort_unstable();
            let median = row[(n - 1) / 2];
            if median < best.0 {
                best = (median, i);
            }
        }
        self.map_points[mp.index()].descriptor = descs[best.1];
    }

    /// Updates the mean viewing direction and the scale-invariance distance range of `mp` from
    /// its observations and its reference keyframe.
    pub fn update_normal_and_depth(&mut self, mp: MapPointId, levels: &ScaleLevels) {
        let m = &self.map_points[mp.index()];
        if m.bad || m.observations.is_empty() {
            return;
        }
        let p = m.position;
        let mut normal = Vector3::zeros();
        for kf in m.observations.keys() {
            let d = p - self.keyframes[kf.index()].center();
            let n = d.norm();
            if n > 0.0 {
                normal += d / n;
            }
        }
        let reference = if m.observations.contains_key(&m.reference_kf) {
            m.reference_kf
        } else {
            *m.observations.keys().next().expect("non-empty")
        };
        let rk = &self.keyframes[reference.index()];
        let idx = m.observations[&reference];
        let dist = (p - rk.center()).norm();
        let level = rk.features.keypoints[idx].octave;
        let max_distance = dist * levels.scale(level);
        let m = &mut self.map_points[mp.index()];
        m.reference_kf = reference;
        m.max_distance = max_distance;
        m.min_distance = max_distance / levels.max_scale();
        let nn = normal.norm();
        if nn > 0.0 {
            m.normal = normal / nn;
        }
    }

    /// Marks a keyframe culled (done by [`Map::set_keyframe_bad`], which also fixes the graph).
    pub(crate) fn flag_keyframe_bad(&mut self, kf: KeyFrameId) {
        let k = &mut self.keyframes[kf.index()];
        if !k.bad {
            k.bad = true;
            self.n_good_keyframes -= 1;
        }
    }

    /// Mutable access to a keyframe, culled or not (graph maintenance only).
    pub(crate) fn keyframe_any_mut(&mut self, id: KeyFrameId) -> &mut KeyFrame {
        &mut self.keyframes[id.index()]
    }

    /// Number of map points of `kf` observed (`n_obs`) at least `min_obs` times
    /// (ORB-SLAM2's TrackedMapPoints, used by the keyframe decision).
    pub fn tracked_map_points(&self, kf: KeyFrameId, min_obs: u32) -> usize {
        let Some(k) = self.keyframe(kf) else {
            return 0;
        };
        k.map_points
            .iter()
            .flatten()
            .filter(|&&id| self.map_point(id).is_some_and(|m| m.n_obs >= min_obs))
            .count()
    }
}
