//! The built-in smooth camera paths of the presets (camera-to-world poses as functions of
//! time): hand-held-like `xyz`, rotation-heavy `rpy`, a 360-degree `spin`, a closed `loop`
//! around the room; and [`look_at`], which aims the camera for them and for the hand-held paths.
//! Camera convention as in TUM / ORB-SLAM2: x right, y down, z forward.

use nalgebra::{Matrix3, Rotation3, Vector3};

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

/// Seconds of one circuit of the `loop` path ([`loop_pose`]) (at motion scale 1); the path is periodic.
pub const LOOP_PERIOD: f64 = 40.0;

/// Centre of the `loop` ellipse in the floor plane, metres: off the room centre so that the
/// path keeps clear of the pillar at (-1.3, 0.3), the shelf at x = 1.95 and the cabinet.
const LOOP_CENTRE: [f64; 2] = [-0.25, 0.1];
/// Semi-axes of the `loop` ellipse along x and y, metres.
const LOOP_SEMI_AXES: [f64; 2] = [1.6, 1.5];
/// Mean camera height of the `loop`, metres (hand-held, above the cabinet and the monitor).
const LOOP_HEIGHT: f64 = 1.5;
/// Angle on the ellipse where the `loop` starts (and, each period, ends), radians.
const LOOP_START: f64 = -2.4;

/// A harmonic of the loop frequency: periodic in [`LOOP_PERIOD`], so the wobble returns with
/// the camera.
fn harmonic(t: f64, k: f64, amp: f64, phase: f64) -> f64 {
    amp * (std::f64::consts::TAU * k * t / LOOP_PERIOD + phase).sin()
}

/// The `loop` pose: eye on the ellipse (counter-clockwise seen from above), looking ahead
/// along the path (the ellipse's radial angle plus 90 degrees) and slightly down at the walls
/// and furniture in front, with hand-held wobble of a few cm and a few degrees.
pub fn loop_pose(t: f64) -> (Vector3<f64>, Rotation3<f64>) {
    let angle = LOOP_START + std::f64::consts::TAU * t / LOOP_PERIOD;
    let eye = Vector3::new(
        LOOP_CENTRE[0] + LOOP_SEMI_AXES[0] * angle.cos() + harmonic(t, 3.0, 0.04, 0.4),
        LOOP_CENTRE[1] + LOOP_SEMI_AXES[1] * angle.sin() + harmonic(t, 5.0, 0.03, 1.3),
        LOOP_HEIGHT + harmonic(t, 4.0, 0.04, 2.1) + harmonic(t, 9.0, 0.015, 0.2),
    );
    let heading = angle
        + std::f64::consts::FRAC_PI_2
        + harmonic(t, 3.0, 8f64.to_radians(), 2.6)
        + harmonic(t, 7.0, 3f64.to_radians(), 0.9);
    let pitch = -0.2 + harmonic(t, 5.0, 4f64.to_radians(), 1.7);
    let roll = harmonic(t, 6.0, 3f64.to_radians(), 0.5) + harmonic(t, 11.0, 1f64.to_radians(), 2.9);
    let dir = Vector3::new(
        heading.cos() * pitch.cos(),
        heading.sin() * pitch.cos(),
        pitch.sin(),
    );
    let rot = look_at(&eye, &(eye + dir)) * Rotation3::from_axis_angle(&Vector3::z_axis(), roll);
    (eye, rot)
}

/// The `xyz` pose (eye, camera-to-world rotation) at `t`: hand-held-like translation of
/// +-25 cm with a gentle look-at wobble towards the desk.
pub fn xyz(t: f64) -> (Vector3<f64>, Rotation3<f64>) {
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

/// The `rpy` pose at `t`: roll, pitch and yaw of +-15..20 degrees around a nearly fixed point.
pub fn rpy(t: f64) -> (Vector3<f64>, Rotation3<f64>) {
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

/// The `spin` pose at `t`: a full turn about the vertical in 20 s from near the middle of the
/// room.
pub fn spin(t: f64) -> (Vector3<f64>, Rotation3<f64>) {
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

#[cfg(test)]
mod tests {
    use super::*;

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
