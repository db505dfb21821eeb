//! Essential-graph optimization after a loop correction (ORB-SLAM2's `OptimizeEssentialGraph`,
//! scale fixed for stereo / RGB-D): every mapped keyframe is a vertex, the loop keyframe is held
//! fixed, and the edges keep the relative poses keyframes had before the loop (spanning tree,
//! earlier loop edges, strong covisibility) or after its correction (the new loop links). The
//! map points follow the keyframe that corrected them, or their reference keyframe.

use std::collections::{BTreeMap, BTreeSet};

use nalgebra::{Isometry3, Point3};

use crate::data::{KeyFrameId, Map, MapPointId, ScaleLevels};
use crate::module::pose_estimation::renormalized;
use crate::optimize::{optimize_pose_graph, PoseGraph, PoseGraphEdge, PoseGraphReport};

/// What the loop correction hands to the essential graph.
#[derive(Clone, Debug)]
pub struct LoopCorrection {
    /// The keyframe that closed the loop.
    pub current: KeyFrameId,
    /// The keyframe it was matched to (held fixed).
    pub loop_kf: KeyFrameId,
    /// Poses (`Tcw`) of the corrected keyframes before their correction.
    pub non_corrected: BTreeMap<KeyFrameId, Isometry3<f64>>,
    /// Per corrected keyframe, the keyframes the loop newly connected it to.
    pub loop_connections: BTreeMap<KeyFrameId, BTreeSet<KeyFrameId>>,
    /// Map points moved by the correction, with the keyframe that moved them.
    pub corrected_by: BTreeMap<MapPointId, KeyFrameId>,
}

/// Whether `kf` has been through local mapping (the first keyframe, or one with a parent in the
/// spanning tree). Keyframes still waiting for mapping (`--mapping-lag`) are not part of the
/// graph yet, as in ORB-SLAM2 where they are not in the map until mapped.
pub fn is_mapped(map: &Map, kf: KeyFrameId) -> bool {
    map.keyframe(kf)
        .is_some_and(|k| k.id.0 == 0 || k.parent.is_some())
}

/// Builds and optimizes the essential graph for `correction` with edges of covisibility weight
/// at least `min_weight` (ORB-SLAM2: 100), `iterations` LM iterations (20), then moves the
/// keyframes and map points. Returns the optimizer's report.
pub fn optimize_essential_graph(
    map: &mut Map,
    correction: &LoopCorrection,
    min_weight: u32,
    iterations: usize,
    levels: &ScaleLevels,
) -> PoseGraphReport {
    let vertices: Vec<KeyFrameId> = map
        .keyframe_ids()
        .into_iter()
        .filter(|&k| is_mapped(map, k))
        .collect();
    let index: BTreeMap<KeyFrameId, usize> =
        vertices.iter().enumerate().map(|(i, &k)| (k, i)).collect();
    let poses: Vec<Isometry3<f64>> = vertices
        .iter()
        .map(|&k| map.keyframe(k).expect("vertex").tcw)
        .collect();
    // Relative poses from before the loop where the keyframe was corrected.
    let before = |k: KeyFrameId| {
        correction
            .non_corrected
            .get(&k)
            .copied()
            .unwrap_or_else(|| poses[index[&k]])
    };
    let mut edges = Vec::new();
    let mut inserted: BTreeSet<(KeyFrameId, KeyFrameId)> = BTreeSet::new();
    let pair = |a: KeyFrameId, b: KeyFrameId| if a < b { (a, b) } else { (b, a) };
    // 1. The new loop links, measured at the corrected poses.
    for (&ki, linked) in &correction.loop_connections {
        let Some(&i) = index.get(&ki) else {
            continue;
        };
        for &kj in linked {
            let Some(&j) = index.get(&kj) else {
                continue;
            };
            let is_the_loop = ki == correction.current && kj == correction.loop_kf;
            let weight = map.keyframe(ki).map_or(0, |k| k.weight(kj));
            if !is_the_loop && weight < min_weight {
                continue;
            }
            if inserted.insert(pair(ki, kj)) {
                edges.push(PoseGraphEdge {
                    i,
                    j,
                    t_ij: poses[i] * poses[j].inverse(),
                });
            }
        }
    }
    // 2. Spanning tree, earlier loop edges and strong covisibility, measured before the loop.
    for (i, &ki) in vertices.iter().enumerate() {
        let k = map.keyframe(ki).expect("vertex");
        let mut add = |kj: KeyFrameId, edges: &mut Vec<PoseGraphEdge>| {
            let Some(&j) = index.get(&kj) else {
                return;
            };
            if inserted.insert(pair(ki, kj)) {
                edges.push(PoseGraphEdge {
                    i,
                    j,
                    t_ij: before(ki) * before(kj).inverse(),
                });
            }
        };
        if let Some(parent) = k.parent {
            add(parent, &mut edges);
        }
        for &kl in &k.loop_edges {
            if kl < ki {
                add(kl, &mut edges);
            }
        }
        for &(kn, w) in &k.ordered_connections {
            if w < min_weight {
                break;
            }
            if Some(kn) != k.parent && !k.children.contains(&kn) && kn < ki {
                add(kn, &mut edges);
            }
        }
    }
    let fixed = vertices.iter().map(|&k| k == correction.loop_kf).collect();
    let mut graph = PoseGraph {
        poses: poses.clone(),
        fixed,
        edges,
    };
    let report = optimize_pose_graph(&mut graph, iterations);
    // Points first (they need the poses from before the optimization), then keyframes.
    let point_ids: Vec<MapPointId> = map.map_points().map(|m| m.id).collect();
    for id in point_ids {
        let m = map.map_point(id).expect("good");
        let reference = correction
            .corrected_by
            .get(&id)
            .copied()
            .unwrap_or(m.reference_kf);
        let Some(&r) = index.get(&reference) else {
            continue;
        };
        let p_r = poses[r] * Point3::from(m.position);
        let moved = graph.poses[r].inverse_transform_point(&p_r).coords;
        map.map_point_mut(id).expect("good").position = moved;
        map.update_normal_and_depth(id, levels);
    }
    for (i, &k) in vertices.iter().enumerate() {
        if let Some(kf) = map.keyframe_mut(k) {
            kf.tcw = renormalized(&graph.poses[i]);
        }
    }
    report
}
