//! The trajectory type: timestamps in time order with a pose each, in the TUM convention
//! (each pose maps the sensor frame into the world frame, T_world_sensor).

use nalgebra::{Isometry3, Point3, Vector3};

/// A timed sequence of poses T_world_sensor. Stamps are seconds in non-decreasing order; they
/// repeat only where a file was read keeping every line (`StampPolicy::KeepAll` of the `stamps` module).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// Timestamps in seconds, non-decreasing.
    pub stamps: Vec<f64>,
    /// One pose per stamp, T_world_sensor.
    pub poses: Vec<Isometry3<f64>>,
}

impl Trajectory {
    /// An empty trajectory.
    pub fn new() -> Self {
        Self::default()
    }

    /// Builds a trajectory from parallel vectors; the caller guarantees equal lengths.
    pub fn from_parts(stamps: Vec<f64>, poses: Vec<Isometry3<f64>>) -> Self {
        assert_eq!(
            stamps.len(),
            poses.len(),
            "stamps and poses must have equal length"
        );
        Trajectory { stamps, poses }
    }

    /// Appends a pose at a stamp.
    pub fn push(&mut self, stamp: f64, pose: Isometry3<f64>) {
        self.stamps.push(stamp);
        self.poses.push(pose);
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.stamps.len()
    }

    /// Whether there is no pose.
    pub fn is_empty(&self) -> bool {
        self.stamps.is_empty()
    }

    /// Positions of the sensor in the world frame.
    pub fn positions(&self) -> Vec<Vector3<f64>> {
        self.poses.iter().map(|p| p.translation.vector).collect()
    }

    /// Total path length in metres (sum of distances between consecutive positions).
    pub fn path_length(&self) -> f64 {
        self.poses
            .windows(2)
            .map(|w| (w[1].translation.vector - w[0].translation.vector).norm())
            .sum()
    }

    /// The same trajectory expressed for another rigidly attached frame: given
    /// `t_sensor_other` (maps `other` coordinates into the sensor frame), returns poses
    /// T_world_other = T_world_sensor * t_sensor_other.
    pub fn change_sensor_frame(&self, t_sensor_other: &Isometry3<f64>) -> Trajectory {
        Trajectory {
            stamps: self.stamps.clone(),
            poses: self.poses.iter().map(|p| p * t_sensor_other).collect(),
        }
    }

    /// Converts an EuRoC cam0 trajectory to the body (IMU) frame of the ground truth.
    /// `t_bs` is the `T_BS` of cam0's `sensor.yaml` (maps cam0 coordinates into the body frame),
    /// so T_world_body = T_world_cam0 * T_BS^-1. Estimates in camera frame must go through this
    /// before they are compared with EuRoC's body-frame ground truth.
    pub fn cam_to_body(&self, t_bs: &Isometry3<f64>) -> Trajectory {
        self.change_sensor_frame(&t_bs.inverse())
    }

    /// Applies a similarity transform x -> s R x + t to every position, and R to every
    /// orientation (used to show an aligned estimate).
    pub fn transformed(&self, scale: f64, rt: &Isometry3<f64>) -> Trajectory {
        let poses = self
            .poses
            .iter()
            .map(|p| {
                let pos = rt * Point3::from(p.translation.vector * scale);
                Isometry3::from_parts(pos.coords.into(), rt.rotation * p.rotation)
            })
            .collect();
        Trajectory {
            stamps: self.stamps.clone(),
            poses,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    #[test]
    fn cam_to_body_inverts_body_to_cam() {
        let t_bs = Isometry3::from_parts(
            Translation3::new(-0.02, -0.06, 0.01),
            UnitQuaternion::from_euler_angles(0.01, -0.02, 1.56),
        );
        let body = Isometry3::from_parts(
            Translation3::new(1.0, 2.0, 0.5),
            UnitQuaternion::from_euler_angles(0.3, 0.1, -0.4),
        );
        // The camera pose of a body pose is T_w_b * T_BS.
        let cam = Trajectory::from_parts(vec![0.0], vec![body * t_bs]);
        let back = cam.cam_to_body(&t_bs);
        assert!(
            (back.poses[0].to_homogeneous() - body.to_homogeneous())
                .abs()
                .max()
                < 1e-12
        );
    }

    #[test]
    fn path_length_sums_segments() {
        let mut t = Trajectory::new();
        t.push(0.0, Isometry3::translation(0.0, 0.0, 0.0));
        t.push(1.0, Isometry3::translation(3.0, 4.0, 0.0));
        t.push(2.0, Isometry3::translation(3.0, 4.0, 1.0));
        assert!((t.path_length() - 6.0).abs() < 1e-12);
    }
}
