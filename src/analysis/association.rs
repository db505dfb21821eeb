//! Ground truth for data association: was a match of the pose optimization the same physical
//! point as its map point, a different one (a mismatch), or a point on a moving object?
//!
//! The outlier counts of Fig. 8 only mean something if one knows what the outliers are: wrong
//! descriptor matches that any robust optimizer should drop, or correct matches whose depth is
//! bad (what MC-OR and AVC address), or moving objects. On a synthetic sequence the truth is
//! known per pixel, so every match can be checked. A map point's identity is the true surface
//! point of its observation in the earliest keyframe still observing it (true depth, true pose);
//! a match is *correct* when that point projects, in the current frame's true camera, within
//! [`PIXEL_TOLERANCE`] pixels (times the keypoint's octave scale) of the matched keypoint and
//! agrees in 3-D with the keypoint's own true surface point (so a point hidden behind a
//! foreground surface does not count as seen).

use std::collections::BTreeMap;

use nalgebra::{Isometry3, Point3, Vector3};
use slam_core::data::{Features, Map, MapPointId};
use slam_core::Camera;
use synth::SynthFrame;

use crate::analysis::correlation::depth_at_raw_pixel;

/// Reprojection tolerance of a correct association at octave 0, pixels (scaled by the octave's
/// scale factor): about three times the keypoint localisation noise of FAST.
pub const PIXEL_TOLERANCE: f64 = 3.0;

/// 3-D tolerance of a correct association: this constant plus [`DEPTH_TOLERANCE`] of the depth.
pub const DISTANCE_TOLERANCE: f64 = 0.03;

/// Depth-proportional part of the 3-D tolerance.
pub const DEPTH_TOLERANCE: f64 = 0.03;

/// The truth about one keypoint: its true surface point in the world and whether it lies on a
/// moving object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeypointTruth {
    /// True surface point (world frame of the ground truth, metres).
    pub point_world: Vector3<f64>,
    /// On a moving object at that frame.
    pub moving: bool,
}

/// What a match was, judged against the truth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Association {
    /// The same static surface point as its map point.
    Correct,
    /// A different surface point (a descriptor mismatch, or a point seen through an occluder).
    Wrong,
    /// The keypoint or the map point's reference observation lies on a moving object.
    Moving,
    /// No true depth at one of the two keypoints (the truth cannot tell).
    Unknown,
}

impl Association {
    /// Column index in [`AssociationCounts`].
    fn index(self) -> usize {
        match self {
            Association::Correct => 0,
            Association::Wrong => 1,
            Association::Moving => 2,
            Association::Unknown => 3,
        }
    }
}

/// Matches counted by (inlier, outlier) x (correct, wrong, moving, unknown).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AssociationCounts {
    /// `[0]`: inliers, `[1]`: outliers; columns in [`Association`] order.
    pub counts: [[usize; 4]; 2],
}

impl AssociationCounts {
    /// Counts one match.
    pub fn add(&mut self, inlier: bool, a: Association) {
        self.counts[usize::from(!inlier)][a.index()] += 1;
    }

    /// The count of `a` among inliers (`inlier`) or outliers.
    pub fn get(&self, inlier: bool, a: Association) -> usize {
        self.counts[usize::from(!inlier)][a.index()]
    }

    /// All inliers (`inlier`) or all outliers.
    pub fn total(&self, inlier: bool) -> usize {
        self.counts[usize::from(!inlier)].iter().sum()
    }
}

/// The true surface points of a frame's keypoints, remembered for the frames that became
/// keyframes (a few kilobytes each, not the depth images).
#[derive(Clone, Debug, Default)]
pub struct KeyframeTruth {
    frames: BTreeMap<u64, Vec<Option<KeypointTruth>>>,
}

impl KeyframeTruth {
    /// Remembers the truth of every keypoint of `features`, extracted from `frame`.
    pub fn remember(&mut self, camera: &Camera, frame: &SynthFrame, features: &Features) {
        let truth = (0..features.keypoints.len())
            .map(|i| keypoint_truth(camera, frame, features, i))
            .collect();
        self.frames.insert(frame.index as u64, truth);
    }

    /// The truth of keypoint `i` of frame `frame_id`, if remembered and known.
    pub fn get(&self, frame_id: u64, i: usize) -> Option<KeypointTruth> {
        self.frames.get(&frame_id)?.get(i).copied().flatten()
    }
}

/// The true surface point of keypoint `i` of `features` (extracted from `frame`): the
/// noiseless depth at its raw pixel, back-projected and placed with the true pose.
pub fn keypoint_truth(
    camera: &Camera,
    frame: &SynthFrame,
    features: &Features,
    i: usize,
) -> Option<KeypointTruth> {
    let kp = features.keypoints.get(i)?;
    let (u, v) = (kp.x as f64, kp.y as f64);
    let z = depth_at_raw_pixel(camera, frame.depth_true.as_ref()?, u, v)?;
    let point_camera = Vector3::new(
        (u - camera.cx) / camera.fx * z,
        (v - camera.cy) / camera.fy * z,
        z,
    );
    let (x, y) = camera.distort_point(u, v);
    let moving = frame.moving_mask.as_ref().is_some_and(|mask| {
        let (px, py) = (x.round(), y.round());
        px >= 0.0
            && py >= 0.0
            && (px as usize) < frame.gray.width
            && (py as usize) < frame.gray.height
            && mask[py as usize * frame.gray.width + px as usize]
    });
    Some(KeypointTruth {
        point_world: (frame.pose_wc * Point3::from(point_camera)).coords,
        moving,
    })
}

/// A tracked frame as [`classify`] needs it: the camera, the synthetic frame (truth) and the
/// features the system extracted from it.
#[derive(Clone, Copy)]
pub struct TrackedTruth<'a> {
    /// The camera.
    pub camera: &'a Camera,
    /// The synthetic frame with its true depth, pose and moving mask.
    pub frame: &'a SynthFrame,
    /// The features the system extracted from it.
    pub features: &'a Features,
    /// The pyramid's scale factor (the tolerance grows with a keypoint's octave).
    pub scale_factor: f64,
}

/// Judges the match of keypoint `i` of `t` to map point `mp` of `map`.
pub fn classify(
    t: &TrackedTruth,
    i: usize,
    map: &Map,
    mp: MapPointId,
    keyframes: &KeyframeTruth,
) -> Association {
    let (camera, frame, features) = (t.camera, t.frame, t.features);
    let Some(current) = keypoint_truth(camera, frame, features, i) else {
        return Association::Unknown;
    };
    // The earliest keyframe still observing the point whose keypoint has a known truth.
    let reference = map.map_point(mp).and_then(|p| {
        p.observations.iter().find_map(|(&kf, &idx)| {
            let k = map.keyframe(kf)?;
            keyframes.get(k.frame_id, idx)
        })
    });
    let Some(reference) = reference else {
        return Association::Unknown;
    };
    if current.moving || reference.moving {
        return Association::Moving;
    }
    let kp = &features.keypoints[i];
    let same = same_point(
        camera,
        &frame.pose_wc,
        (kp.x as f64, kp.y as f64),
        t.scale_factor.powi(kp.octave as i32),
        &current.point_world,
        &reference.point_world,
    );
    if same {
        Association::Correct
    } else {
        Association::Wrong
    }
}

/// Whether the reference point `reference` (world) is what the keypoint at undistorted pixel
/// `uv` (octave scale `scale`) of a camera at true pose `pose_wc` sees, whose own true surface
/// point is `current`.
pub fn same_point(
    camera: &Camera,
    pose_wc: &Isometry3<f64>,
    uv: (f64, f64),
    scale: f64,
    current: &Vector3<f64>,
    reference: &Vector3<f64>,
) -> bool {
    let pc = pose_wc.inverse_transform_point(&Point3::from(*reference));
    if pc.z <= 0.0 {
        return false;
    }
    let (u, v) = (
        camera.fx * pc.x / pc.z + camera.cx,
        camera.fy * pc.y / pc.z + camera.cy,
    );
    let pixel = ((u - uv.0).powi(2) + (v - uv.1).powi(2)).sqrt();
    let distance = (current - reference).norm();
    pixel <= PIXEL_TOLERANCE * scale && distance <= DISTANCE_TOLERANCE + DEPTH_TOLERANCE * pc.z
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera::tum_fr3()
    }

    #[test]
    fn a_point_is_itself_and_not_its_neighbour_or_an_occluded_one() {
        let cam = camera();
        let pose = Isometry3::translation(0.1, -0.2, 0.3);
        // A surface point 2 m in front of the camera at pixel (400, 300).
        let (u, v, z) = (400.0, 300.0, 2.0);
        let pc = Vector3::new((u - cam.cx) / cam.fx * z, (v - cam.cy) / cam.fy * z, z);
        let world = (pose * Point3::from(pc)).coords;
        assert!(same_point(&cam, &pose, (u, v), 1.0, &world, &world));
        // A point 10 px to the side on the same wall: a mismatch at octave 0 ...
        let side = Vector3::new((u + 10.0 - cam.cx) / cam.fx * z, pc.y, z);
        let side_world = (pose * Point3::from(side)).coords;
        assert!(!same_point(&cam, &pose, (u, v), 1.0, &world, &side_world));
        // ... but within the tolerance of octave 7 (scale 1.2^7 = 3.6: 10.7 px), if in 3-D
        // it is close enough (2 m * 10/517 px = 3.9 cm < 3 cm + 6 cm).
        assert!(same_point(
            &cam,
            &pose,
            (u, v),
            1.2f64.powi(7),
            &world,
            &side_world
        ));
        // The same ray, 50 cm further: hidden behind the seen surface.
        let behind = (pose * Point3::from(pc * 1.25)).coords;
        assert!(!same_point(&cam, &pose, (u, v), 1.0, &world, &behind));
        // Behind the camera.
        let back = (pose * Point3::from(-pc)).coords;
        assert!(!same_point(&cam, &pose, (u, v), 1.0, &world, &back));
    }

    #[test]
    fn counts_split_inliers_and_outliers() {
        let mut c = AssociationCounts::default();
        c.add(true, Association::Correct);
        c.add(true, Association::Correct);
        c.add(false, Association::Wrong);
        c.add(false, Association::Moving);
        assert_eq!(c.get(true, Association::Correct), 2);
        assert_eq!(c.get(false, Association::Wrong), 1);
        assert_eq!(c.get(false, Association::Correct), 0);
        assert_eq!((c.total(true), c.total(false)), (2, 2));
    }
}
