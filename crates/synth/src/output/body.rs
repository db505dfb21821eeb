//! The body (IMU) frame of a generated stereo sequence, in which EuRoC states its ground truth.
//!
//! The camera is not at the body origin: cam0 sits at [`body_from_cam0`] (a rotation of about
//! 90 degrees about z plus a few centimetres, like EuRoC's) or at the rig's T_BS, so readers
//! that forget the body-to-camera conversion get a visibly wrong trajectory. With
//! [`crate::motion::clock::MocapNoise`] the recorded body pose carries motion-capture noise
//! ([`Generator::measured_pose`]). The folder writer (`datasets::write`) and the in-memory
//! sequence (`datasets::synthetic`) both take the ground truth from here.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use crate::generator::Generator;

/// T_BS of cam0 of a rectified pair: pose of the left camera in the body (IMU) frame.
pub fn body_from_cam0() -> Isometry3<f64> {
    let r = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2)
        * UnitQuaternion::from_euler_angles(-0.0257, 0.0149, 0.0042);
    Isometry3::from_parts(Translation3::new(-0.0216, -0.0647, 0.0098), r)
}

/// T_BS of cam1 of a rectified pair: cam0 shifted by the stereo baseline along its x axis.
pub fn body_from_cam1(baseline: f64) -> Isometry3<f64> {
    body_from_cam0() * Translation3::new(baseline, 0.0, 0.0)
}

/// The body pose T_WB of a camera-to-world pose of cam0 (the rectified pair's
/// [`body_from_cam0`]).
pub fn body_pose(pose_wc0: &Isometry3<f64>) -> Isometry3<f64> {
    pose_wc0 * body_from_cam0().inverse()
}

/// T_BS of cam0 of `gen`'s sequence: its rig's, else [`body_from_cam0`].
pub fn body_from_left(gen: &Generator) -> Isometry3<f64> {
    gen.config()
        .rig
        .as_ref()
        .map_or_else(body_from_cam0, |r| r.body_from_left)
}

/// The ground truth of frame `index`: the body pose T_WB, exact or with the configuration's
/// motion-capture noise.
pub fn groundtruth_body(gen: &Generator, index: usize) -> Isometry3<f64> {
    let b = gen.pose(index) * body_from_left(gen).inverse();
    gen.measured_pose(&b, index)
}
