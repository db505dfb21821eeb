//! Fusion of duplicate map points (ORB-SLAM2's ORBmatcher::Fuse): map points projected into a
//! keyframe that match a keypoint (reprojection chi2 < 5.99 mono / 7.8 stereo, Hamming
//! <= TH_LOW) either become observations of it or are merged with the map point it already has,
//! keeping the one with more observations.

use nalgebra::Point3;

use crate::camera::Camera;
use crate::data::{KeyFrameId, Map, MapPointId, ScaleLevels};
use crate::feature::{hamming, TH_LOW};

/// Fuses `points` into keyframe `kf` with search radius `th * scale[predicted level]`.
/// Returns the number of points fused or added.
pub fn fuse(
    kf: KeyFrameId,
    points: &[MapPointId],
    th: f64,
    map: &mut Map,
    camera: &Camera,
    levels: &ScaleLevels,
) -> usize {
    let Some(k) = map.keyframe(kf) else {
        return 0;
    };
    let tcw = k.tcw;
    let center = k.center();
    let features = k.features.clone();
    let mut n = 0;
    for &id in points {
        let Some(mp) = map.map_point(id) else {
            continue;
        };
        if mp.is_observed_by(kf) {
            continue;
        }
        let pc = tcw.transform_point(&Point3::from(mp.position));
        if pc.z <= 0.0 {
            continue;
        }
        let uv = camera.project(&pc.coords);
        if !camera.in_image(uv.x, uv.y) {
            continue;
        }
        let ur = uv.x - camera.bf / pc.z;
        let po = mp.position - center;
        let dist = po.norm();
        if dist < mp.min_distance || dist > mp.max_distance {
            continue;
        }
        if po.dot(&mp.normal) < 0.5 * dist {
            continue;
        }
        let level = mp.predict_scale(dist, levels);
        let radius = th * levels.scale(level);
        let (mut best, mut best_idx) = (u32::MAX, usize::MAX);
        for idx in features.features_in_area(uv.x, uv.y, radius, -1, -1) {
            let kp = &features.keypoints[idx];
            if kp.octave + 1 < level || kp.octave > level {
                continue;
            }
            let ex = uv.x - kp.x as f64;
            let ey = uv.y - kp.y as f64;
            let inv_s2 = levels.inv_sigma2(kp.octave);
            if let Some(kur) = features.u_right_of(idx) {
                let er = ur - kur;
                if (ex * ex + ey * ey + er * er) * inv_s2 > 7.8 {
                    continue;
                }
            } else if (ex * ex + ey * ey) * inv_s2 > 5.99 {
                continue;
            }
            let d = hamming(&mp.descriptor, &features.descriptors[idx]);
            if d < best {
                best = d;
                best_idx = idx;
            }
        }
        if best > TH_LOW {
            continue;
        }
        let existing = map
            .keyframe(kf)
            .and_then(|k| k.map_points[best_idx])
            .filter(|&e| map.map_point(e).is_some());
        match existing {
            Some(e) => {
                let (n_e, n_m) = (
                    map.map_point(e).unwrap().n_obs,
                    map.map_point(id).unwrap().n_obs,
                );
                if n_e > n_m {
                    map.replace_map_point(id, e);
                } else {
                    map.replace_map_point(e, id);
                }
            }
            None => map.add_observation(id, kf, best_idx),
        }
        n += 1;
    }
    n
}
