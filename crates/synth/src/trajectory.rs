//! Smooth ground-truth camera trajectories (camera-to-world poses as functions of time):
//! handheld-like `xyz`, rotation-heavy `rpy` and a 360-degree `spin`. Camera convention as in
//! TUM / ORB-SLAM2: x right, y down, z forward.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::config::Trajectory;

/// Camera-to-world rotation of a camera at `eye` looking at `target`, world z up.
pub fn look_at(eye: &Vector3<f64>, target: &Vector3<f64>) -> Rotation3<f64> {
    let z = (target - eye).normalize();
    let x = z.cross(&Vector3::z()).normalize();
    let y = z.cross(&x);
    Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]))
}

/// Sum of sines with incommensurate periods: smooth, non-repeating, amplitude about `amp`.
fn wobble(t: f64, amp: f64, periods: [f64; 2], phase: f64) -> f64 {
    use std::f64::consts::TAU;
    amp * (0.7 * (TAU * t / periods[0] + phase).sin()
        + 0.3 * (TAU * t / periods[1] + 1.7 * phase).sin())
}

/// Camera-to-world pose of `trajectory` at time `t` seconds (already scaled by the motion scale).
pub fn pose_at(trajectory: Trajectory, t: f64) -> Isometry3<f64> {
    let (eye, rot) = match trajectory {
        Trajectory::Xyz => {
            let eye = Vector3::new(
                wobble(t, 0.28, [7.3, 3.1], 0.0),
                -0.75 + wobble(t, 0.2, [9.7, 4.3], 1.1),
                1.45 + wobble(t, 0.15, [6.1, 2.9], 2.3),
            );
            let target = Vector3::new(
                wobble(t, 0.15, [11.0, 5.3], 0.5),
                1.05,
                0.85 + wobble(t, 0.08, [8.9, 3.7], 0.9),
            );
            (eye, look_at(&eye, &target))
        }
        Trajectory::Rpy => {
            let eye = Vector3::new(
                wobble(t, 0.03, [5.0, 2.3], 0.2),
                -0.75 + wobble(t, 0.03, [6.0, 2.7], 0.7),
                1.45 + wobble(t, 0.02, [4.0, 1.9], 1.3),
            );
            let base = look_at(&eye, &Vector3::new(0.0, 1.05, 0.85));
            // Roll about the optical axis, pitch about x, yaw about y (camera frame).
            let roll = wobble(t, 18f64.to_radians(), [5.3, 2.2], 0.4);
            let pitch = wobble(t, 10f64.to_radians(), [6.7, 2.9], 1.9);
            let yaw = wobble(t, 20f64.to_radians(), [8.1, 3.3], 3.1);
            let local = Rotation3::from_axis_angle(&Vector3::y_axis(), yaw)
                * Rotation3::from_axis_angle(&Vector3::x_axis(), pitch)
                * Rotation3::from_axis_angle(&Vector3::z_axis(), roll);
            (eye, base * local)
        }
        Trajectory::Spin => {
            let heading = std::f64::consts::TAU * t / 20.0 + std::f64::consts::FRAC_PI_2;
            let eye = Vector3::new(
                0.1 * (0.5 * t).sin(),
                -0.3 + 0.1 * (0.37 * t).cos(),
                1.4 + 0.05 * (0.8 * t).sin(),
            );
            let pitch = -0.3 + 0.05 * (0.6 * t).sin();
            let dir = Vector3::new(
                heading.cos() * pitch.cos(),
                heading.sin() * pitch.cos(),
                pitch.sin(),
            );
            (eye, look_at(&eye, &(eye + dir)))
        }
    };
    Isometry3::from_parts(
        Translation3::from(eye),
        UnitQuaternion::from_rotation_matrix(&rot),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{ROOM_HALF, ROOM_HEIGHT};

    #[test]
    fn trajectories_are_smooth_and_stay_in_the_room() {
        for traj in [Trajectory::Xyz, Trajectory::Rpy, Trajectory::Spin] {
            let mut prev = pose_at(traj, 0.0);
            let (mut max_dt, mut max_dr) = (0.0f64, 0.0f64);
            for i in 1..1800 {
                let p = pose_at(traj, i as f64 / 30.0);
                let d = prev.inverse() * p;
                max_dt = max_dt.max(d.translation.vector.norm());
                max_dr = max_dr.max(d.rotation.angle());
                let e = p.translation.vector;
                assert!(e.x.abs() < ROOM_HALF - 0.5 && e.y.abs() < ROOM_HALF - 0.5);
                assert!(e.z > 0.8 && e.z < ROOM_HEIGHT - 0.5);
                prev = p;
            }
            assert!(max_dt < 0.02, "{traj:?}: {max_dt} m/frame");
            assert!(
                max_dr < 2f64.to_radians(),
                "{traj:?}: {} deg/frame",
                max_dr.to_degrees()
            );
            // It does move.
            assert!(max_dt > 0.001 || max_dr > 0.2f64.to_radians(), "{traj:?}");
        }
    }

    #[test]
    fn look_at_points_the_optical_axis() {
        let eye = Vector3::new(0.0, 0.0, 1.0);
        let target = Vector3::new(1.0, 2.0, 0.5);
        let r = look_at(&eye, &target);
        let z = r * Vector3::z();
        assert!((z - (target - eye).normalize()).norm() < 1e-12);
        // Image y (down) points downwards in the world.
        assert!((r * Vector3::y()).z < 0.0);
        assert!((r.matrix().determinant() - 1.0).abs() < 1e-12);
    }
}
