//! Global bundle adjustment after a loop closure (ORB-SLAM2's `RunGlobalBundleAdjustment`):
//! every mapped keyframe (the first one fixed) and every map point they see, robust kernel, 10
//! iterations. ORB-SLAM2 runs it in a thread while tracking and mapping go on, then merges:
//! keyframes created meanwhile follow their spanning-tree parent's correction and new map
//! points their reference keyframe's. [`global_bundle_adjustment`] optimizes a snapshot and
//! [`apply_global_ba`] merges it whenever the system decides the thread would have finished.

use std::collections::{BTreeMap, BTreeSet, VecDeque};

use nalgebra::{Isometry3, Point3, Vector3};

use crate::camera::Camera;
use crate::data::{KeyFrameId, Map, MapPointId, ScaleLevels};
use crate::module::essential_graph::is_mapped;
use crate::module::pose_estimation::{measurement_for, renormalized, NoiseHooks};
use crate::optimize::{
    local_bundle_adjustment, BaConfig, BaKeyFrame, BaObservation, BaPoint, BaProblem,
};

/// The result of a global BA, relative to the map it was run on.
#[derive(Clone, Debug, Default)]
pub struct GlobalBaResult {
    /// Keyframe poses (`Tcw`) before and after the optimization.
    pub keyframes: BTreeMap<KeyFrameId, (Isometry3<f64>, Isometry3<f64>)>,
    /// Optimized map point positions.
    pub points: BTreeMap<MapPointId, Vector3<f64>>,
    /// LM iterations run.
    pub iterations: usize,
}

/// Optimizes all mapped keyframes and the map points they observe, without touching `map`.
pub fn global_bundle_adjustment(
    map: &Map,
    camera: &Camera,
    levels: &ScaleLevels,
    hooks: &NoiseHooks,
    iterations: usize,
) -> GlobalBaResult {
    let keyframes: Vec<KeyFrameId> = map
        .keyframe_ids()
        .into_iter()
        .filter(|&k| is_mapped(map, k))
        .collect();
    let kf_index: BTreeMap<KeyFrameId, usize> =
        keyframes.iter().enumerate().map(|(i, &k)| (k, i)).collect();
    let mut problem = BaProblem::default();
    for &k in &keyframes {
        problem.keyframes.push(BaKeyFrame {
            tcw: map.keyframe(k).expect("mapped").tcw,
            fixed: k.0 == 0,
        });
    }
    let mut point_ids = Vec::new();
    for m in map.map_points() {
        let observers: Vec<(usize, usize)> = m
            .observations
            .iter()
            .filter_map(|(k, &idx)| kf_index.get(k).map(|&ki| (ki, idx)))
            .collect();
        if observers.is_empty() {
            continue;
        }
        let pi = problem.points.len();
        problem.points.push(BaPoint {
            position: m.position,
        });
        point_ids.push(m.id);
        for (ki, idx) in observers {
            let k = map.keyframe(keyframes[ki]).expect("mapped");
            problem.observations.push(BaObservation {
                keyframe: ki,
                point: pi,
                measurement: measurement_for(
                    camera,
                    &k.features,
                    idx,
                    hooks,
                    &k.to_camera(&m.position),
                ),
                inv_sigma2: levels.inv_sigma2(k.features.keypoints[idx].octave),
            });
        }
    }
    let mut result = GlobalBaResult::default();
    if problem.keyframes.len() < 2 || problem.observations.is_empty() {
        return result;
    }
    let before: Vec<Isometry3<f64>> = problem.keyframes.iter().map(|k| k.tcw).collect();
    let cfg = BaConfig {
        first_pass_iterations: iterations,
        second_pass_iterations: 0,
    };
    let report = local_bundle_adjustment(camera, &mut problem, &cfg);
    result.iterations = report.iterations;
    for (i, &k) in keyframes.iter().enumerate() {
        result
            .keyframes
            .insert(k, (before[i], renormalized(&problem.keyframes[i].tcw)));
    }
    for (pi, &id) in point_ids.iter().enumerate() {
        result.points.insert(id, problem.points[pi].position);
    }
    result
}

/// Merges `result` into `map`: optimized keyframes and points take their new values; keyframes
/// added since follow their spanning-tree parent (breadth first from the first keyframe),
/// points added since follow their reference keyframe.
pub fn apply_global_ba(map: &mut Map, result: &GlobalBaResult, levels: &ScaleLevels) {
    if result.keyframes.is_empty() {
        return;
    }
    // Per keyframe: pose now (before the merge) and merged pose.
    let mut merged: BTreeMap<KeyFrameId, (Isometry3<f64>, Isometry3<f64>)> = BTreeMap::new();
    let mut queue: VecDeque<KeyFrameId> = VecDeque::new();
    let mut seen: BTreeSet<KeyFrameId> = BTreeSet::new();
    for (&k, &(_, after)) in &result.keyframes {
        if let Some(kf) = map.keyframe(k) {
            merged.insert(k, (kf.tcw, after));
        }
    }
    if map.keyframe(KeyFrameId(0)).is_some() {
        queue.push_back(KeyFrameId(0));
        seen.insert(KeyFrameId(0));
    }
    while let Some(k) = queue.pop_front() {
        let Some(&(parent_now, parent_new)) = merged.get(&k) else {
            continue;
        };
        let children: Vec<KeyFrameId> = map
            .keyframe(k)
            .map(|kf| kf.children.iter().copied().collect())
            .unwrap_or_default();
        for c in children {
            if !seen.insert(c) {
                continue;
            }
            if let (std::collections::btree_map::Entry::Vacant(e), Some(child)) =
                (merged.entry(c), map.keyframe(c))
            {
                let t_child_parent = child.tcw * parent_now.inverse();
                e.insert((child.tcw, renormalized(&(t_child_parent * parent_new))));
            }
            queue.push_back(c);
        }
    }
    let ids: Vec<MapPointId> = map.map_points().map(|m| m.id).collect();
    for id in ids {
        let m = map.map_point(id).expect("good");
        let position = match result.points.get(&id) {
            Some(&p) => p,
            None => match merged.get(&m.reference_kf) {
                Some((now, new)) => {
                    new.inverse_transform_point(&(now * Point3::from(m.position)))
                        .coords
                }
                None => continue,
            },
        };
        map.map_point_mut(id).expect("good").position = position;
        map.update_normal_and_depth(id, levels);
    }
    for (k, (_, new)) in merged {
        if let Some(kf) = map.keyframe_mut(k) {
            kf.tcw = new;
        }
    }
}
