//! Local mapping for one new keyframe, run to completion before the next frame is tracked
//! (ORB-SLAM2's LocalMapping::Run body): process the keyframe, cull recent map points,
//! triangulate new points with neighbours, fuse duplicates, local bundle adjustment, cull
//! redundant keyframes.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

use super::pose_estimation::{measurement_for, renormalized, NoiseHooks};
use crate::camera::Camera;
use crate::data::{KeyFrameId, Map, MapPointId, ScaleLevels};
use crate::matching::epipolar::{fundamental_12, search_for_triangulation};
use crate::matching::fuse::fuse;
use crate::optimize::{
    local_bundle_adjustment, BaConfig, BaKeyFrame, BaObservation, BaPoint, BaProblem,
};
use crate::solve::triangulate_linear;
use crate::techniques::mcor::map_point_cluster;
use crate::techniques::{
    FrameView, McorParams, Scope, Sightings, SightingsJudgement, FRAME_VIEW_SOURCE_BIT,
};

/// Local-mapping thresholds (ORB-SLAM2 RGB-D / stereo values).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MappingParams {
    /// Recent points with found / visible below this are culled (0.25).
    pub min_found_ratio: f64,
    /// Recent points with at most this many observations (`n_obs`) two keyframes after their
    /// creation are culled (3).
    pub min_observations: u32,
    /// Covisible keyframes used for triangulation (10).
    pub triangulation_neighbours: usize,
    /// Parallax cosine above which two rays are too parallel to triangulate (0.9998).
    pub max_parallax_cos: f64,
    /// Scale-consistency slack, multiplied by the pyramid scale factor (1.5).
    pub scale_consistency: f64,
    /// Covisible keyframes whose points are fused (10), and their neighbours (5).
    pub fuse_neighbours: usize,
    /// See `fuse_neighbours`.
    pub fuse_second_neighbours: usize,
    /// Fusion search radius, pixels x scale (3).
    pub fuse_radius: f64,
    /// Keyframe culling: redundancy ratio of close points seen by `redundant_observers` others
    /// at the same or finer scale (0.9).
    pub redundant_ratio: f64,
    /// See `redundant_ratio` (3).
    pub redundant_observers: usize,
    /// Run local BA (on by default; off only for tests and profiling).
    pub local_ba: bool,
    /// Cull redundant keyframes (on by default).
    pub keyframe_culling: bool,
}

impl Default for MappingParams {
    fn default() -> Self {
        MappingParams {
            min_found_ratio: 0.25,
            min_observations: 3,
            triangulation_neighbours: 10,
            max_parallax_cos: 0.9998,
            scale_consistency: 1.5,
            fuse_neighbours: 10,
            fuse_second_neighbours: 5,
            fuse_radius: 3.0,
            redundant_ratio: 0.9,
            redundant_observers: 3,
            local_ba: true,
            keyframe_culling: true,
        }
    }
}

/// Shared inputs of local mapping.
#[derive(Clone, Copy, Debug)]
pub struct MappingContext<'a> {
    /// The camera.
    pub camera: &'a Camera,
    /// Pyramid scale table.
    pub levels: &'a ScaleLevels,
    /// Thresholds.
    pub params: &'a MappingParams,
    /// Local BA iteration budget.
    pub ba: &'a BaConfig,
    /// MC-OR / AVC switches (AVC changes the BA residual).
    pub hooks: NoiseHooks<'a>,
}

/// What one local-mapping step did, with its time split.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MappingReport {
    /// Recent map points culled.
    pub culled_points: usize,
    /// Map points triangulated with neighbours.
    pub triangulated_points: usize,
    /// Points fused or added to keyframes by the neighbour search.
    pub fused_points: usize,
    /// Observations erased by local BA.
    pub ba_outliers: usize,
    /// Map points MC-OR's CL test culled before local BA (`scope = "tracking+mapping"`).
    pub mcor_culled_points: usize,
    /// Keyframe observations MC-OR's FL test kept out of local BA and erased
    /// (`scope = "tracking+mapping"`).
    pub mcor_erased_observations: usize,
    /// Keyframes culled as redundant.
    pub culled_keyframes: usize,
    /// Wall time of everything but BA, milliseconds.
    pub time_mapping_ms: f64,
    /// Wall time of local BA, milliseconds.
    pub time_ba_ms: f64,
}

/// Local-mapping state: map points created recently, still on probation.
#[derive(Clone, Debug, Default)]
pub struct LocalMapper {
    /// Recently created map points (culled unless observed enough).
    pub recent_points: Vec<MapPointId>,
}

impl LocalMapper {
    /// Runs local mapping for keyframe `kf`; `created` are the points its insertion created.
    pub fn process(
        &mut self,
        kf: KeyFrameId,
        created: Vec<MapPointId>,
        map: &mut Map,
        ctx: &MappingContext,
    ) -> MappingReport {
        let t0 = Instant::now();
        let mut report = MappingReport::default();
        self.process_new_keyframe(kf, created, map, ctx);
        report.culled_points = self.map_point_culling(kf, map, ctx);
        report.triangulated_points = self.create_new_map_points(kf, map, ctx);
        report.fused_points = search_in_neighbors(kf, map, ctx);
        let mut ba_ms = 0.0;
        if ctx.params.local_ba && map.keyframe_count() > 2 {
            let tb = Instant::now();
            let erased = local_ba(kf, map, ctx);
            report.ba_outliers = erased.chi2;
            report.mcor_culled_points = erased.mcor_culled_points;
            report.mcor_erased_observations = erased.mcor_observations;
            ba_ms = tb.elapsed().as_secs_f64() * 1e3;
        }
        if ctx.params.keyframe_culling {
            report.culled_keyframes = keyframe_culling(kf, map, ctx);
        }
        report.time_ba_ms = ba_ms;
        report.time_mapping_ms = t0.elapsed().as_secs_f64() * 1e3 - ba_ms;
        report
    }

    /// Adds the keyframe's observations of the map points tracking matched, updates their
    /// descriptors and normals, and connects the keyframe to the covisibility graph.
    fn process_new_keyframe(
        &mut self,
        kf: KeyFrameId,
        created: Vec<MapPointId>,
        map: &mut Map,
        ctx: &MappingContext,
    ) {
        let slots: Vec<(usize, MapPointId)> = map
            .keyframe(kf)
            .map(|k| {
                k.map_points
                    .iter()
                    .enumerate()
                    .filter_map(|(i, m)| m.map(|m| (i, m)))
                    .collect()
            })
            .unwrap_or_default();
        for (i, id) in slots {
            let Some(mp) = map.map_point(id) else {
                map.keyframe_mut(kf).expect("good").map_points[i] = None;
                continue;
            };
            match mp.observations.get(&kf) {
                None => {
                    map.add_observation(id, kf, i);
                    map.update_normal_and_depth(id, ctx.levels);
                    map.compute_distinctive_descriptor(id);
                }
                Some(&j) if j != i => {
                    // The same point matched twice in the frame: keep the first observation.
                    map.keyframe_mut(kf).expect("good").map_points[i] = None;
                }
                Some(_) => {}
            }
        }
        self.recent_points.extend(created);
        map.update_connections(kf);
    }

    /// ORB-SLAM2's MapPointCulling over the recent points.
    fn map_point_culling(&mut self, kf: KeyFrameId, map: &mut Map, ctx: &MappingContext) -> usize {
        let current = kf.0;
        let mut culled = 0;
        let mut keep = Vec::with_capacity(self.recent_points.len());
        for &id in &self.recent_points {
            let Some(mp) = map.map_point(id) else {
                continue;
            };
            let age = current.saturating_sub(mp.first_kf.0);
            if mp.found_ratio() < ctx.params.min_found_ratio
                || (age >= 2 && mp.n_obs <= ctx.params.min_observations)
            {
                map.set_map_point_bad(id);
                culled += 1;
            } else if age < 3 {
                keep.push(id);
            }
        }
        self.recent_points = keep;
        culled
    }

    /// Triangulates unmatched keypoints of `kf` with its best covisible keyframes
    /// (ORB-SLAM2's CreateNewMapPoints for stereo / RGB-D).
    fn create_new_map_points(
        &mut self,
        kf: KeyFrameId,
        map: &mut Map,
        ctx: &MappingContext,
    ) -> usize {
        let Some(k1) = map.keyframe(kf) else {
            return 0;
        };
        let cam = ctx.camera;
        let lv = ctx.levels;
        let neighbours = k1.best_covisibles(ctx.params.triangulation_neighbours);
        let ratio_factor = ctx.params.scale_consistency * lv.scale_factor;
        let baseline = cam.baseline();
        let mut n_new = 0;
        for kf2 in neighbours {
            let (Some(k1), Some(k2)) = (map.keyframe(kf), map.keyframe(kf2)) else {
                continue;
            };
            let (o1, o2) = (k1.center(), k2.center());
            if (o2 - o1).norm() < baseline {
                continue;
            }
            let f12 = fundamental_12(k1, k2, cam);
            let pairs = search_for_triangulation(k1, k2, &f12, map, cam, lv);
            let (t1, t2) = (k1.tcw, k2.tcw);
            let (r_wc1, r_wc2) = (t1.rotation.inverse(), t2.rotation.inverse());
            let mut new_points = Vec::new();
            for (i1, i2) in pairs {
                let (f1, f2) = (&k1.features, &k2.features);
                let (kp1, kp2) = (&f1.keypoints[i1], &f2.keypoints[i2]);
                let (ur1, ur2) = (f1.u_right_of(i1), f2.u_right_of(i2));
                let xn1 = Vector3::new(
                    (kp1.x as f64 - cam.cx) / cam.fx,
                    (kp1.y as f64 - cam.cy) / cam.fy,
                    1.0,
                );
                let xn2 = Vector3::new(
                    (kp2.x as f64 - cam.cx) / cam.fx,
                    (kp2.y as f64 - cam.cy) / cam.fy,
                    1.0,
                );
                let ray1 = r_wc1 * xn1;
                let ray2 = r_wc2 * xn2;
                let cos_rays = ray1.dot(&ray2) / (ray1.norm() * ray2.norm());
                let stereo_cos = |d: Option<f64>| {
                    d.map(|z| (2.0 * (baseline / 2.0).atan2(z)).cos())
                        .unwrap_or(1.1)
                };
                let cos_s1 = if ur1.is_some() {
                    stereo_cos(f1.depth_of(i1))
                } else {
                    1.1
                };
                let cos_s2 = if ur2.is_some() {
                    stereo_cos(f2.depth_of(i2))
                } else {
                    1.1
                };
                let cos_stereo = cos_s1.min(cos_s2);
                let x3d = if cos_rays < cos_stereo
                    && cos_rays > 0.0
                    && (ur1.is_some() || ur2.is_some() || cos_rays < ctx.params.max_parallax_cos)
                {
                    match triangulate_linear(&xn1, &xn2, &t1, &t2) {
                        Some(x) => x,
                        None => continue,
                    }
                } else if ur1.is_some() && cos_s1 < cos_s2 {
                    match f1.unproject_camera(i1, cam) {
                        Some(pc) => t1.inverse_transform_point(&Point3::from(pc)).coords,
                        None => continue,
                    }
                } else if ur2.is_some() && cos_s2 < cos_s1 {
                    match f2.unproject_camera(i2, cam) {
                        Some(pc) => t2.inverse_transform_point(&Point3::from(pc)).coords,
                        None => continue,
                    }
                } else {
                    continue;
                };
                let check = |t: &nalgebra::Isometry3<f64>,
                             kp: &crate::feature::KeyPoint,
                             ur: Option<f64>|
                 -> bool {
                    let pc = t.transform_point(&Point3::from(x3d)).coords;
                    if pc.z <= 0.0 {
                        return false;
                    }
                    let uv = cam.project(&pc);
                    let (ex, ey) = (uv.x - kp.x as f64, uv.y - kp.y as f64);
                    let s2 = lv.sigma2(kp.octave);
                    match ur {
                        None => ex * ex + ey * ey <= 5.991 * s2,
                        Some(ur) => {
                            let er = uv.x - cam.bf / pc.z - ur;
                            ex * ex + ey * ey + er * er <= 7.8 * s2
                        }
                    }
                };
                if !check(&t1, kp1, ur1) || !check(&t2, kp2, ur2) {
                    continue;
                }
                let dist1 = (x3d - o1).norm();
                let dist2 = (x3d - o2).norm();
                if dist1 == 0.0 || dist2 == 0.0 {
                    continue;
                }
                let ratio_dist = dist2 / dist1;
                let ratio_octave = lv.scale(kp1.octave) / lv.scale(kp2.octave);
                if ratio_dist * ratio_factor < ratio_octave
                    || ratio_dist > ratio_octave * ratio_factor
                {
                    continue;
                }
                new_points.push((x3d, i1, i2, f1.descriptors[i1]));
            }
            for (x3d, i1, i2, desc) in new_points {
                // A keypoint may have been used with an earlier neighbour.
                let taken = |m: &Map, k: KeyFrameId, i: usize| {
                    m.keyframe(k)
                        .is_none_or(|k| k.map_points[i].is_some_and(|p| m.map_point(p).is_some()))
                };
                if taken(map, kf, i1) || taken(map, kf2, i2) {
                    continue;
                }
                let id = map.create_map_point(x3d, desc, kf);
                map.add_observation(id, kf, i1);
                map.add_observation(id, kf2, i2);
                map.compute_distinctive_descriptor(id);
                map.update_normal_and_depth(id, lv);
                self.recent_points.push(id);
                n_new += 1;
            }
        }
        n_new
    }
}

/// Fuses the keyframe's points into its neighbours and theirs into it (ORB-SLAM2's
/// SearchInNeighbors), then refreshes descriptors, normals and covisibility.
fn search_in_neighbors(kf: KeyFrameId, map: &mut Map, ctx: &MappingContext) -> usize {
    let Some(k) = map.keyframe(kf) else {
        return 0;
    };
    let mark = kf.0 + 1;
    let first = k.best_covisibles(ctx.params.fuse_neighbours);
    let mut targets: Vec<KeyFrameId> = Vec::new();
    for t in first {
        let Some(kt) = map.keyframe_mut(t) else {
            continue;
        };
        if kt.fuse_target_for_kf == mark {
            continue;
        }
        kt.fuse_target_for_kf = mark;
        targets.push(t);
        let second = kt.best_covisibles(ctx.params.fuse_second_neighbours);
        for t2 in second {
            if t2 == kf {
                continue;
            }
            if let Some(k2) = map.keyframe_mut(t2) {
                if k2.fuse_target_for_kf != mark {
                    k2.fuse_target_for_kf = mark;
                    targets.push(t2);
                }
            }
        }
    }
    let own: Vec<MapPointId> = map
        .keyframe(kf)
        .map(|k| k.map_points.iter().flatten().copied().collect())
        .unwrap_or_default();
    let mut n = 0;
    for &t in &targets {
        n += fuse(t, &own, ctx.params.fuse_radius, map, ctx.camera, ctx.levels);
    }
    let mut candidates = Vec::new();
    for &t in &targets {
        let ids: Vec<MapPointId> = map
            .keyframe(t)
            .map(|k| k.map_points.iter().flatten().copied().collect())
            .unwrap_or_default();
        for id in ids {
            if let Some(mp) = map.map_point_mut(id) {
                if mp.fuse_candidate_for_kf != mark {
                    mp.fuse_candidate_for_kf = mark;
                    candidates.push(id);
                }
            }
        }
    }
    n += fuse(
        kf,
        &candidates,
        ctx.params.fuse_radius,
        map,
        ctx.camera,
        ctx.levels,
    );
    let own: Vec<MapPointId> = map
        .keyframe(kf)
        .map(|k| k.map_points.iter().flatten().copied().collect())
        .unwrap_or_default();
    for id in own {
        if map.map_point(id).is_some() {
            map.compute_distinctive_descriptor(id);
            map.update_normal_and_depth(id, ctx.levels);
        }
    }
    map.update_connections(kf);
    n
}

/// Local BA around `kf` (ORB-SLAM2's LocalBundleAdjustment): `kf` and its covisible keyframes
/// are free (keyframe 0 fixed), the other keyframes seeing their points are fixed. Observations
/// BA flags are erased from the map. Under MC-OR's `scope = "tracking+mapping"` the local
/// points are judged first ([`mcor_before_local_ba`]). Returns what was erased.
fn local_ba(kf: KeyFrameId, map: &mut Map, ctx: &MappingContext) -> LocalBaErasures {
    let mut erasures = LocalBaErasures::default();
    let Some(mut ba) = local_ba_problem(kf, map, ctx, &mut erasures) else {
        return erasures;
    };
    let report = local_bundle_adjustment(ctx.camera, &mut ba.problem, ctx.ba);
    let keep_sightings = ctx
        .hooks
        .mcor
        .is_some_and(|m| m.sightings == Sightings::All);
    let erase = |map: &mut Map, mp: MapPointId, o: KeyFrameId| {
        let good = map.map_point(mp).is_some();
        if good {
            if keep_sightings {
                keep_sighting_as_view(map, mp, o, ctx.camera);
            }
            map.erase_observation(mp, o);
        }
        good
    };
    for (k, &(mp, o)) in ba.obs_ids.iter().enumerate() {
        if report.outliers[k] && erase(map, mp, o) {
            erasures.chi2 += 1;
        }
    }
    for &(mp, o) in &ba.mcor_out {
        if erase(map, mp, o) {
            erasures.mcor_observations += 1;
        }
    }
    for (&id, &ki) in &ba.kf_index {
        if !ba.problem.keyframes[ki].fixed {
            if let Some(k) = map.keyframe_mut(id) {
                k.tcw = renormalized(&ba.problem.keyframes[ki].tcw);
            }
        }
    }
    for (pi, &mp) in ba.points.iter().enumerate() {
        if let Some(m) = map.map_point_mut(mp) {
            m.position = ba.problem.points[pi].position;
            map.update_normal_and_depth(mp, ctx.levels);
        }
    }
    erasures
}

/// The local BA problem around `kf`, and how its entries map back to the map.
struct LocalBa {
    problem: BaProblem,
    /// Each BA observation's map point and keyframe.
    obs_ids: Vec<(MapPointId, KeyFrameId)>,
    /// Each keyframe's index in the problem.
    kf_index: BTreeMap<KeyFrameId, usize>,
    /// Each BA point's map point.
    points: Vec<MapPointId>,
    /// Observations MC-OR kept out of the problem, to be erased.
    mcor_out: BTreeSet<(MapPointId, KeyFrameId)>,
}

/// Builds [`local_ba`]'s problem (MC-OR's culling done, counted in `erasures`); `None` when
/// `kf` is gone or every keyframe is fixed.
fn local_ba_problem(
    kf: KeyFrameId,
    map: &mut Map,
    ctx: &MappingContext,
    erasures: &mut LocalBaErasures,
) -> Option<LocalBa> {
    let k = map.keyframe(kf)?;
    let mut local: Vec<KeyFrameId> = vec![kf];
    local.extend(k.covisibles());
    let mut kf_index: BTreeMap<KeyFrameId, usize> = BTreeMap::new();
    let mut problem = BaProblem::default();
    for &id in &local {
        if let Some(k) = map.keyframe(id) {
            kf_index.insert(id, problem.keyframes.len());
            problem.keyframes.push(BaKeyFrame {
                tcw: k.tcw,
                fixed: id.0 == 0,
            });
        }
    }
    let mut points: Vec<MapPointId> = Vec::new();
    let mut seen = BTreeSet::new();
    for &id in &local {
        let Some(k) = map.keyframe(id) else {
            continue;
        };
        for &mp in k.map_points.iter().flatten() {
            if map.map_point(mp).is_some() && seen.insert(mp) {
                points.push(mp);
            }
        }
    }
    let mut mcor_out = BTreeSet::new();
    if let Some(params) = ctx.hooks.mcor.filter(|m| m.scope == Scope::TrackingMapping) {
        let (kept, out, culled) = mcor_before_local_ba(map, points, ctx.camera, params);
        (points, mcor_out) = (kept, out);
        erasures.mcor_culled_points = culled;
    }
    // Fixed keyframes: observers of local points outside the window.
    for &mp in &points {
        for &o in map.map_point(mp).expect("good").observations.keys() {
            if let std::collections::btree_map::Entry::Vacant(e) = kf_index.entry(o) {
                if let Some(k) = map.keyframe(o) {
                    e.insert(problem.keyframes.len());
                    problem.keyframes.push(BaKeyFrame {
                        tcw: k.tcw,
                        fixed: true,
                    });
                }
            }
        }
    }
    if problem.keyframes.iter().all(|k| k.fixed) {
        return None;
    }
    let mut obs_ids: Vec<(MapPointId, KeyFrameId)> = Vec::new();
    for (pi, &mp) in points.iter().enumerate() {
        let m = map.map_point(mp).expect("good");
        problem.points.push(BaPoint {
            position: m.position,
        });
        for (&o, &idx) in &m.observations {
            let Some(&ki) = kf_index.get(&o) else {
                continue;
            };
            if mcor_out.contains(&(mp, o)) {
                continue;
            }
            let k = map.keyframe(o).expect("indexed keyframes are good");
            problem.observations.push(BaObservation {
                keyframe: ki,
                point: pi,
                measurement: measurement_for(
                    ctx.camera,
                    &k.features,
                    idx,
                    &ctx.hooks,
                    &k.to_camera(&m.position),
                ),
                inv_sigma2: ctx.levels.inv_sigma2(k.features.keypoints[idx].octave),
            });
            obs_ids.push((mp, o));
        }
    }
    Some(LocalBa {
        problem,
        obs_ids,
        kf_index,
        points,
        mcor_out,
    })
}

/// What [`local_ba`] erased.
#[derive(Clone, Copy, Debug, Default)]
struct LocalBaErasures {
    /// Observations BA's chi2 test flagged.
    chi2: usize,
    /// Points MC-OR's CL test culled.
    mcor_culled_points: usize,
    /// Observations MC-OR's FL test kept out.
    mcor_observations: usize,
}

/// MC-OR's `scope = "tracking+mapping"` reading before local BA: every local point's cluster
/// (as tracking builds it) judged by Algorithm 1 over its sightings. A point whose cluster fails
/// the CL test is culled; a keyframe observation whose feature fails the FL test is returned, to
/// be kept out of BA and erased after it (a point with no observation left leaves the
/// problem). Returns the points left, those observations and the number culled.
fn mcor_before_local_ba(
    map: &mut Map,
    points: Vec<MapPointId>,
    camera: &Camera,
    params: &McorParams,
) -> (Vec<MapPointId>, BTreeSet<(MapPointId, KeyFrameId)>, usize) {
    let mut kept = Vec::with_capacity(points.len());
    let mut out = BTreeSet::new();
    let mut culled = 0;
    for mp in points {
        let Some(position) = map.map_point(mp).map(|m| m.position) else {
            continue;
        };
        let cluster = map_point_cluster(map, mp, camera, params.cluster_views);
        match cluster.judge_sightings(params, &position) {
            SightingsJudgement::Cull => {
                map.set_map_point_bad(mp);
                culled += 1;
            }
            SightingsJudgement::Keep { rejected } => {
                let before = out.len();
                out.extend(
                    rejected
                        .into_iter()
                        .filter(|s| s & FRAME_VIEW_SOURCE_BIT == 0)
                        .map(|s| (mp, KeyFrameId(s as u32))),
                );
                // A point none of whose observations is left is not optimized.
                let n_obs = map.map_point(mp).map_or(0, |m| m.observations.len());
                if out.len() - before < n_obs {
                    kept.push(mp);
                }
            }
        }
    }
    (kept, out, culled)
}

/// MC-OR's `sightings = "all"` reading: keyframe `kf`'s observation of map point `mp`, about
/// to be erased, stays in the point's cluster as a frame view of the keyframe's own frame
/// (carried by the keyframe, so it follows the keyframe's pose). Nothing without depth.
fn keep_sighting_as_view(map: &mut Map, mp: MapPointId, kf: KeyFrameId, camera: &Camera) {
    let Some(view) = map.keyframe(kf).and_then(|k| {
        let idx = *map.map_point(mp)?.observations.get(&kf)?;
        let pc = k.features.unproject_camera(idx, camera)?;
        FrameView::new(k.frame_id, &k.tcw, kf, &k.tcw, pc)
    }) else {
        return;
    };
    if let Some(m) = map.map_point_mut(mp) {
        m.views.push(view);
    }
}

/// Culls covisible keyframes whose close map points are mostly (> 90 %) seen by at least three
/// other keyframes at the same or finer scale (ORB-SLAM2's KeyFrameCulling).
fn keyframe_culling(kf: KeyFrameId, map: &mut Map, ctx: &MappingContext) -> usize {
    let Some(k) = map.keyframe(kf) else {
        return 0;
    };
    let th_depth = ctx.camera.close_depth();
    let th_obs = ctx.params.redundant_observers;
    let mut culled = 0;
    for candidate in k.covisibles() {
        if candidate.0 == 0 {
            continue;
        }
        let Some(c) = map.keyframe(candidate).filter(|c| c.loop_edges.is_empty()) else {
            continue;
        };
        let (mut n_points, mut n_redundant) = (0usize, 0usize);
        for (i, slot) in c.map_points.iter().enumerate() {
            let Some(mp) = slot.and_then(|id| map.map_point(id)) else {
                continue;
            };
            match c.features.depth_of(i) {
                Some(z) if z <= th_depth => {}
                _ => continue,
            }
            n_points += 1;
            if mp.n_obs as usize > th_obs {
                let level = c.features.keypoints[i].octave;
                let mut n_obs = 0;
                for (&o, &j) in &mp.observations {
                    if o == candidate {
                        continue;
                    }
                    let Some(ko) = map.keyframe(o) else {
                        continue;
                    };
                    if ko.features.keypoints[j].octave <= level + 1 {
                        n_obs += 1;
                        if n_obs >= th_obs {
                            break;
                        }
                    }
                }
                if n_obs >= th_obs {
                    n_redundant += 1;
                }
            }
        }
        if n_points > 0 && n_redundant as f64 > ctx.params.redundant_ratio * n_points as f64 {
            map.set_keyframe_bad(candidate);
            culled += 1;
        }
    }
    culled
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::module::test_map::scene;
    use crate::optimize::BaConfig;
    use std::sync::Arc;

    /// The test map with keyframe 2's depth of point 7 one metre too far and map point 10
    /// drifted 0.6 m from where its sightings put it; keyframes connected.
    fn judged_map() -> (Camera, Map, MapPointId, MapPointId) {
        let (camera, mut map, frame, _) = scene(&[]);
        let kf2 = KeyFrameId(2);
        let mut f = (*map.keyframe(kf2).unwrap().features).clone();
        f.depth[7] += 1.0;
        f.u_right[7] = (f.keypoints[7].x as f64 - camera.bf / f.depth[7] as f64) as f32;
        map.keyframe_mut(kf2).unwrap().features = Arc::new(f);
        let (p7, p10) = (frame.map_points[7].unwrap(), frame.map_points[10].unwrap());
        map.map_point_mut(p10).unwrap().position += Vector3::new(0.0, 0.6, 0.0);
        for k in 0..3 {
            map.update_connections(KeyFrameId(k));
        }
        (camera, map, p7, p10)
    }

    /// Local mapping's context with MC-OR's `mcor` on, AVC off.
    fn context<'a>(
        camera: &'a Camera,
        levels: &'a ScaleLevels,
        params: &'a MappingParams,
        ba: &'a BaConfig,
        mcor: &'a McorParams,
    ) -> MappingContext<'a> {
        MappingContext {
            camera,
            levels,
            params,
            ba,
            hooks: NoiseHooks {
                mcor: Some(mcor),
                ..NoiseHooks::default()
            },
        }
    }

    #[test]
    fn under_the_mapping_scope_local_ba_receives_no_observation_mcor_rejected() {
        let (camera, map, p7, p10) = judged_map();
        let levels = ScaleLevels::new(8, 1.2);
        let (params, ba) = (MappingParams::default(), BaConfig::default());
        let kf2 = KeyFrameId(2);
        for scope in [Scope::Tracking, Scope::TrackingMapping] {
            let mcor = McorParams {
                scope,
                ..McorParams::default()
            };
            let ctx = context(&camera, &levels, &params, &ba, &mcor);
            let mut m = map.clone();
            let mut erasures = LocalBaErasures::default();
            let problem = local_ba_problem(kf2, &mut m, &ctx, &mut erasures).unwrap();
            let mapping = scope == Scope::TrackingMapping;
            // The feature that fails MC-OR's FL test is not in the problem; the other
            // keyframes' sightings of its point are.
            assert_eq!(!problem.obs_ids.contains(&(p7, kf2)), mapping);
            assert_eq!(problem.mcor_out.contains(&(p7, kf2)), mapping);
            assert!(problem.obs_ids.contains(&(p7, KeyFrameId(1))));
            // The point whose cluster fails the CL test is culled, not optimized.
            assert_eq!(!problem.points.contains(&p10), mapping);
            assert_eq!(m.map_point(p10).is_none(), mapping);
            assert_eq!(erasures.mcor_culled_points, usize::from(mapping));
            let judged = problem
                .obs_ids
                .iter()
                .all(|o| !problem.mcor_out.contains(o));
            assert!(judged, "no rejected observation reaches BA");
        }
    }

    #[test]
    fn local_ba_erases_mcor_rejections_and_all_sightings_keep_them_as_views() {
        let (camera, map, p7, _) = judged_map();
        let levels = ScaleLevels::new(8, 1.2);
        let (params, ba) = (MappingParams::default(), BaConfig::default());
        let kf2 = KeyFrameId(2);
        for sightings in [Sightings::Inliers, Sightings::All] {
            let mcor = McorParams {
                scope: Scope::TrackingMapping,
                sightings,
                ..McorParams::default()
            };
            let ctx = context(&camera, &levels, &params, &ba, &mcor);
            let mut m = map.clone();
            let erasures = local_ba(kf2, &mut m, &ctx);
            assert!(erasures.mcor_observations >= 1, "{erasures:?}");
            let point = m.map_point(p7).unwrap();
            assert!(!point.observations.contains_key(&kf2));
            let frame_of_kf2 = m.keyframe(kf2).unwrap().frame_id;
            let kept = point.views.views().any(|v| v.frame == frame_of_kf2);
            assert_eq!(kept, sightings == Sightings::All, "{sightings:?}");
        }
    }
}
