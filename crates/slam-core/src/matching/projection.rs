//! Searches that project map points into the current frame and match them to keypoints near
//! the projection (ORB-SLAM2's ORBmatcher::SearchByProjection in its three variants).

use std::collections::BTreeSet;

use nalgebra::{Isometry3, Point3, Vector2, Vector3};

use super::RotationHistogram;
use crate::camera::Camera;
use crate::data::{Features, KeyFrameId, Map, MapPoint, MapPointId, ScaleLevels, TrackedFrame};
use crate::feature::{hamming, Descriptor, TH_HIGH};

/// A map point predicted to be visible in a frame (ORB-SLAM2's `mbTrackInView` data).
#[derive(Clone, Copy, Debug)]
pub struct VisiblePoint {
    /// The map point.
    pub id: MapPointId,
    /// Projected column, pixels.
    pub u: f64,
    /// Projected row, pixels.
    pub v: f64,
    /// Projected right-image column (`u - bf / z`).
    pub u_right: f64,
    /// Pyramid level predicted from the distance.
    pub level: usize,
    /// Cosine between the viewing ray and the point's mean viewing direction.
    pub view_cos: f64,
}

/// Frustum test of ORB-SLAM2's Frame::isInFrustum: in front of the camera, inside the image,
/// within the scale-invariance distance range (0.8 min .. 1.2 max) and seen at an angle with
/// `cos >= view_cos_limit` (0.5) from its mean viewing direction.
pub fn is_in_frustum(
    mp: &MapPoint,
    tcw: &Isometry3<f64>,
    center: &Vector3<f64>,
    camera: &Camera,
    levels: &ScaleLevels,
    view_cos_limit: f64,
) -> Option<VisiblePoint> {
    let (pc, uv) = project_into_image(tcw, &mp.position, camera)?;
    let po = mp.position - center;
    let dist = po.norm();
    if dist < 0.8 * mp.min_distance || dist > 1.2 * mp.max_distance {
        return None;
    }
    let view_cos = po.dot(&mp.normal) / dist;
    if view_cos < view_cos_limit {
        return None;
    }
    Some(VisiblePoint {
        id: mp.id,
        u: uv.x,
        v: uv.y,
        u_right: uv.x - camera.bf / pc.z,
        level: mp.predict_scale(dist, levels),
        view_cos,
    })
}

/// Local-map search (ORB-SLAM2's SearchByProjection(Frame, MapPoints, th)): for each visible
/// point, keypoints within `th * (2.5 if view_cos > 0.998 else 4.0) * scale[level]` on levels
/// `level - 1 ..= level`, best Hamming distance <= TH_HIGH, rejected when the second best is on
/// the same level and `best > ratio * second`. Keypoints already matched to an observed map
/// point are skipped. Returns the number of new matches.
pub fn search_local_points(
    frame: &mut TrackedFrame,
    points: &[VisiblePoint],
    th: f64,
    ratio: f64,
    map: &Map,
    levels: &ScaleLevels,
) -> usize {
    let features = frame.features.clone();
    let mut n = 0;
    for vp in points {
        let Some(mp) = map.map_point(vp.id) else {
            continue;
        };
        let r = th * if vp.view_cos > 0.998 { 2.5 } else { 4.0 } * levels.scale(vp.level);
        let candidates =
            features.features_in_area(vp.u, vp.v, r, vp.level as i32 - 1, vp.level as i32);
        let (mut best, mut best2) = (u32::MAX, u32::MAX);
        let (mut best_level, mut best_level2) = (-1i64, -1i64);
        let mut best_idx = usize::MAX;
        for idx in candidates {
            if matched_to_observed(frame, idx, map) {
                continue;
            }
            if let Some(ur) = features.u_right_of(idx) {
                if (vp.u_right - ur).abs() > r * levels.scale(vp.level) {
                    continue;
                }
            }
            let d = hamming(&mp.descriptor, &features.descriptors[idx]);
            let lvl = features.keypoints[idx].octave as i64;
            if d < best {
                best2 = best;
                best_level2 = best_level;
                best = d;
                best_level = lvl;
                best_idx = idx;
            } else if d < best2 {
                best_level2 = lvl;
                best2 = d;
            }
        }
        if best <= TH_HIGH {
            if best_level == best_level2 && best as f64 > ratio * best2 as f64 {
                continue;
            }
            frame.map_points[best_idx] = Some(vp.id);
            frame.outliers[best_idx] = false;
            n += 1;
        }
    }
    n
}

/// Motion-model search (ORB-SLAM2's SearchByProjection(CurrentFrame, LastFrame, th)): projects
/// the last frame's inlier map points with the current pose estimate and searches within
/// `th * scale[octave]` on a level range that depends on forward / backward motion (only for
/// stereo / RGB-D: motion along the optical axis larger than the baseline). Best distance
/// <= TH_HIGH, no ratio test, rotation check. Returns the number of matches.
pub fn search_by_projection_last_frame(
    current: &mut TrackedFrame,
    last: &TrackedFrame,
    th: f64,
    map: &Map,
    camera: &Camera,
    levels: &ScaleLevels,
) -> usize {
    let (Some(tcw), Some(tlw)) = (current.tcw, last.tcw) else {
        return 0;
    };
    let twc = tcw.inverse().translation.vector;
    let tlc = tlw.transform_point(&Point3::from(twc)).coords;
    let baseline = camera.baseline();
    let forward = tlc.z > baseline;
    let backward = -tlc.z > baseline;
    let features = current.features.clone();
    let mut hist = RotationHistogram::new();
    let mut n = 0;
    for i in 0..last.len() {
        let Some(id) = last.map_points[i] else {
            continue;
        };
        if last.outliers[i] {
            continue;
        }
        let Some(mp) = map.map_point(id) else {
            continue;
        };
        let Some((pc, uv)) = project_into_image(&tcw, &mp.position, camera) else {
            continue;
        };
        let last_octave = last.features.keypoints[i].octave as i32;
        let radius = th * levels.scale(last_octave as usize);
        let candidates = if forward {
            features.features_in_area(uv.x, uv.y, radius, last_octave, -1)
        } else if backward {
            features.features_in_area(uv.x, uv.y, radius, 0, last_octave)
        } else {
            features.features_in_area(uv.x, uv.y, radius, last_octave - 1, last_octave + 1)
        };
        let ur_proj = uv.x - camera.bf / pc.z;
        let best = closest_descriptor(&features, candidates, &mp.descriptor, |idx| {
            matched_to_observed(current, idx, map)
                || features
                    .u_right_of(idx)
                    .is_some_and(|ur| (ur_proj - ur).abs() > radius)
        });
        if let Some((_, best_idx)) = best.filter(|(d, _)| *d <= TH_HIGH) {
            current.map_points[best_idx] = Some(id);
            current.outliers[best_idx] = false;
            n += 1;
            hist.add(
                last.features.keypoints[i].angle,
                features.keypoints[best_idx].angle,
                best_idx,
            );
        }
    }
    n - unmatch_rotation_outliers(current, &hist)
}

/// Relocalization search (ORB-SLAM2's SearchByProjection(CurrentFrame, KF, AlreadyFound, th,
/// ORBdist)): projects the map points of `kf` not in `already_found` with the current pose,
/// within the distance range, radius `th * scale[predicted level]` over levels +-1, best
/// distance <= `orb_dist`, rotation check. Returns the number of new matches.
#[allow(clippy::too_many_arguments)]
pub fn search_by_projection_keyframe(
    current: &mut TrackedFrame,
    kf: KeyFrameId,
    already_found: &BTreeSet<MapPointId>,
    th: f64,
    orb_dist: u32,
    map: &Map,
    camera: &Camera,
    levels: &ScaleLevels,
) -> usize {
    let (Some(tcw), Some(k)) = (current.tcw, map.keyframe(kf)) else {
        return 0;
    };
    let center = current.center();
    let features = current.features.clone();
    let mut hist = RotationHistogram::new();
    let mut n = 0;
    for (i, slot) in k.map_points.iter().enumerate() {
        let Some(id) = *slot else {
            continue;
        };
        if already_found.contains(&id) {
            continue;
        }
        let Some(mp) = map.map_point(id) else {
            continue;
        };
        let Some((_, uv)) = project_into_image(&tcw, &mp.position, camera) else {
            continue;
        };
        let dist = (mp.position - center).norm();
        if dist < mp.min_distance || dist > mp.max_distance {
            continue;
        }
        let level = mp.predict_scale(dist, levels) as i32;
        let radius = th * levels.scale(level as usize);
        let candidates = features.features_in_area(uv.x, uv.y, radius, level - 1, level + 1);
        let best = closest_descriptor(&features, candidates, &mp.descriptor, |idx| {
            current.map_points[idx].is_some()
        });
        if let Some((_, best_idx)) = best.filter(|(d, _)| *d <= orb_dist) {
            current.map_points[best_idx] = Some(id);
            current.outliers[best_idx] = false;
            n += 1;
            hist.add(
                k.features.keypoints[i].angle,
                features.keypoints[best_idx].angle,
                best_idx,
            );
        }
    }
    n - unmatch_rotation_outliers(current, &hist)
}

/// The camera-frame point and pixel of world point `position` seen with pose `tcw`, if it lies
/// in front of the camera and inside the image.
fn project_into_image(
    tcw: &Isometry3<f64>,
    position: &Vector3<f64>,
    camera: &Camera,
) -> Option<(Point3<f64>, Vector2<f64>)> {
    let pc = tcw.transform_point(&Point3::from(*position));
    if pc.z <= 0.0 {
        return None;
    }
    let uv = camera.project(&pc.coords);
    camera.in_image(uv.x, uv.y).then_some((pc, uv))
}

/// Whether keypoint `idx` of `frame` is already matched to a map point some keyframe observes
/// (such matches are kept; a search only fills free or tentative slots).
fn matched_to_observed(frame: &TrackedFrame, idx: usize, map: &Map) -> bool {
    frame.map_points[idx]
        .and_then(|id| map.map_point(id))
        .is_some_and(|m| m.n_obs > 0)
}

/// The candidate keypoint whose descriptor is closest (Hamming) to `descriptor`, with its
/// distance, skipping the candidates `skip` rules out; `None` when none is left. Ties keep the
/// first candidate.
fn closest_descriptor(
    features: &Features,
    candidates: impl IntoIterator<Item = usize>,
    descriptor: &Descriptor,
    mut skip: impl FnMut(usize) -> bool,
) -> Option<(u32, usize)> {
    let mut best: Option<(u32, usize)> = None;
    for idx in candidates {
        if skip(idx) {
            continue;
        }
        let d = hamming(descriptor, &features.descriptors[idx]);
        if best.is_none_or(|(b, _)| d < b) {
            best = Some((d, idx));
        }
    }
    best
}

/// Undoes the matches whose rotation is inconsistent with the dominant ones (ORB-SLAM2's
/// rotation-consistency check); returns how many.
fn unmatch_rotation_outliers(frame: &mut TrackedFrame, hist: &RotationHistogram) -> usize {
    let rejected = hist.rejected();
    for &idx in &rejected {
        frame.map_points[idx] = None;
    }
    rejected.len()
}
