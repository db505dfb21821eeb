//! Making a keyframe from the current frame (ORB-SLAM2's CreateNewKeyFrame for RGB-D / stereo):
//! the keyframe takes the frame's matches, and new map points are created from its closest
//! keypoints with a measured depth — all with depth below ThDepth, or the 100 closest if fewer.

use nalgebra::Point3;

use crate::camera::Camera;
use crate::data::{KeyFrameId, Map, MapPointId, ScaleLevels, TrackedFrame};

/// Minimum number of depth points a new keyframe visits (ORB-SLAM2: 100).
pub const MIN_CLOSE_POINTS: usize = 100;

/// Inserts `frame` as a keyframe and creates its close-depth map points. Returns the keyframe
/// and the points created (which go to local mapping's recent list). The keyframe keeps the
/// frame's matches as they are (outliers too: local BA decides); local mapping adds their
/// observations.
pub fn create_keyframe(
    frame: &mut TrackedFrame,
    map: &mut Map,
    camera: &Camera,
    levels: &ScaleLevels,
) -> Option<(KeyFrameId, Vec<MapPointId>)> {
    let tcw = frame.tcw?;
    let kf = map.create_keyframe(frame.id, frame.timestamp, tcw, frame.features.clone());
    {
        let k = map.keyframe_mut(kf).expect("just created");
        for (slot, mp) in k.map_points.iter_mut().zip(&frame.map_points) {
            *slot = *mp;
        }
    }
    let mut by_depth: Vec<(f64, usize)> = (0..frame.len())
        .filter_map(|i| frame.features.depth_of(i).map(|z| (z, i)))
        .collect();
    by_depth.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let twc = tcw.inverse();
    let th_depth = camera.close_depth();
    let mut created = Vec::new();
    for (n_points, &(z, i)) in by_depth.iter().enumerate() {
        let create = match frame.map_points[i] {
            None => true,
            Some(id) => map.map_point(id).is_none_or(|m| m.n_obs < 1),
        } && !frame.dynamic.get(i).copied().unwrap_or(false);
        if create {
            let kp = &frame.features.keypoints[i];
            let pc = camera.unproject(kp.x as f64, kp.y as f64, z);
            let pw = twc.transform_point(&Point3::from(pc)).coords;
            let mp = map.create_map_point(pw, frame.features.descriptors[i], kf);
            map.add_observation(mp, kf, i);
            map.compute_distinctive_descriptor(mp);
            map.update_normal_and_depth(mp, levels);
            frame.map_points[i] = Some(mp);
            frame.outliers[i] = false;
            created.push(mp);
        }
        if z > th_depth && n_points + 1 > MIN_CLOSE_POINTS {
            break;
        }
    }
    Some((kf, created))
}
