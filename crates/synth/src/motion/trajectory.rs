//! The camera path of a sequence ([`Trajectory`]): a built-in smooth path
//! ([`crate::motion::smooth`]), a hand-held path with a recorded sequence's statistics
//! ([`crate::motion::handheld`]) or a recorded path ([`crate::motion::recorded`]), and the
//! camera-to-world pose on it at any time ([`pose_at`]).

use std::path::Path;
use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, UnitQuaternion};

use crate::error::SynthError;
use crate::motion::handheld::HandHeldPath;
use crate::motion::recorded::RecordedPath;
use crate::motion::smooth;

/// Camera path through the room. The built-in paths run at the camera's frame rate, are smooth
/// (C-infinity), and move at most a few cm and a few degrees per frame at `motion_scale` 1; a
/// recorded path moves as its recording did.
#[derive(Clone, Debug, PartialEq)]
pub enum Trajectory {
    /// Handheld-like translation (+-25 cm) with a gentle look-at wobble, like fr1/fr3 `xyz`.
    Xyz,
    /// Rotation-heavy: roll / pitch / yaw of +-15..20 degrees around a nearly fixed point, like `rpy`.
    Rpy,
    /// A full 360-degree turn about the vertical in 20 s, from near the middle of the room.
    Spin,
    /// A closed circuit around the room for loop closing: the camera walks a rounded path
    /// (an ellipse of 1.6 x 1.5 m semi-axes, 9.8 m round) at hand-held height (1.5 m), looking
    /// ahead along the path at the walls and furniture, with a gentle hand-held wobble; one
    /// circuit in [`crate::motion::smooth::LOOP_PERIOD`] = 40 s.
    /// The path is periodic: at 40 s the camera is back at its start pose and then re-sees
    /// the start (render ~55 s = 1650 frames for the circuit plus 15 s of revisit).
    Loop,
    /// A recorded path: a TUM trajectory file levelled and placed in the room (see
    /// [`crate::motion::recorded`]); time is the recording's, since its first stamp.
    Recorded(Arc<RecordedPath>),
    /// A hand-held path with a recorded sequence's duration and mean speeds (the twins'; see
    /// [`crate::motion::handheld`]); time since its start.
    HandHeld(Arc<HandHeldPath>),
}

impl Trajectory {
    /// Names of the built-in paths, accepted by [`Trajectory::from_name`].
    pub const NAMES: [&'static str; 4] = ["xyz", "rpy", "spin", "loop"];

    /// Parses a built-in name: `xyz`, `rpy`, `spin` or `loop`.
    pub fn from_name(name: &str) -> Result<Self, SynthError> {
        match name {
            "xyz" => Ok(Trajectory::Xyz),
            "rpy" => Ok(Trajectory::Rpy),
            "spin" => Ok(Trajectory::Spin),
            "loop" => Ok(Trajectory::Loop),
            _ => Err(SynthError::UnknownName {
                what: "trajectory",
                name: name.to_string(),
                valid: Self::NAMES.join(", "),
            }),
        }
    }

    /// Parses a command-line value: a built-in name, else the path of an existing TUM
    /// trajectory file, read and fitted into the room by [`RecordedPath::load`]. A value that is
    /// neither fails with the valid names.
    pub fn from_arg(value: &str) -> Result<Self, SynthError> {
        if let Ok(t) = Self::from_name(value) {
            return Ok(t);
        }
        let path = Path::new(value);
        if path.is_file() {
            return Ok(Trajectory::Recorded(Arc::new(RecordedPath::load(path)?)));
        }
        Err(SynthError::UnknownName {
            what: "trajectory",
            name: value.to_string(),
            valid: format!(
                "{}, or the path of a TUM trajectory file",
                Self::NAMES.join(", ")
            ),
        })
    }

    /// The built-in path's name, or a recorded path's file name as given.
    pub fn name(&self) -> &str {
        match self {
            Trajectory::Xyz => "xyz",
            Trajectory::Rpy => "rpy",
            Trajectory::Spin => "spin",
            Trajectory::Loop => "loop",
            Trajectory::Recorded(r) => r.label(),
            Trajectory::HandHeld(h) => h.label(),
        }
    }

    /// How long the path lasts in seconds of trajectory time, `None` for the built-in paths
    /// (defined for all times).
    pub fn duration(&self) -> Option<f64> {
        match self {
            Trajectory::Recorded(r) => Some(r.duration()),
            Trajectory::HandHeld(h) => Some(h.duration()),
            _ => None,
        }
    }
}

/// Camera-to-world pose of `trajectory` at time `t` seconds (already scaled by the motion
/// scale). A recorded path is clamped to its recording outside it.
pub fn pose_at(trajectory: &Trajectory, t: f64) -> Isometry3<f64> {
    let (eye, rot) = match trajectory {
        Trajectory::Recorded(path) => return path.pose_at(t),
        Trajectory::HandHeld(path) => return path.pose_at(t),
        Trajectory::Loop => smooth::loop_pose(t),
        Trajectory::Xyz => smooth::xyz(t),
        Trajectory::Rpy => smooth::rpy(t),
        Trajectory::Spin => smooth::spin(t),
    };
    Isometry3::from_parts(
        Translation3::from(eye),
        UnitQuaternion::from_rotation_matrix(&rot),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::smooth::LOOP_PERIOD;
    use crate::world::layout::{furniture_clearance, ROOM_HALF, ROOM_HEIGHT};
    use nalgebra::Vector3;

    #[test]
    fn trajectories_are_smooth_and_stay_in_the_room() {
        for traj in [
            Trajectory::Xyz,
            Trajectory::Rpy,
            Trajectory::Spin,
            Trajectory::Loop,
        ] {
            let mut prev = pose_at(&traj, 0.0);
            let (mut max_dt, mut max_dr) = (0.0f64, 0.0f64);
            for i in 1..1800 {
                let p = pose_at(&traj, i as f64 / 30.0);
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
    fn loop_returns_to_its_start_after_a_long_excursion() {
        let start = pose_at(&Trajectory::Loop, 0.0);
        let back = pose_at(&Trajectory::Loop, LOOP_PERIOD);
        let d = start.inverse() * back;
        assert!(d.translation.vector.norm() < 1e-9 && d.rotation.angle() < 1e-9);
        // Far from the start half-way, and it looks at every wall on the way round.
        let half = pose_at(&Trajectory::Loop, LOOP_PERIOD / 2.0);
        assert!((half.translation.vector - start.translation.vector).norm() > 2.0);
        let mut turned = 0.0;
        let mut prev = start.rotation * Vector3::z();
        for i in 1..=400 {
            let z =
                pose_at(&Trajectory::Loop, LOOP_PERIOD * i as f64 / 400.0).rotation * Vector3::z();
            let (a, b) = (prev.xy(), z.xy());
            turned += (a.x * b.y - a.y * b.x).atan2(a.dot(&b));
            prev = z;
        }
        assert!((turned - std::f64::consts::TAU).abs() < 1e-6, "{turned}");
        // Never closer than 0.3 m to the furniture.
        let clear = (0..2400)
            .map(|i| {
                let p = pose_at(&Trajectory::Loop, LOOP_PERIOD * i as f64 / 2400.0);
                furniture_clearance(&p.translation.vector)
            })
            .fold(f64::INFINITY, f64::min);
        assert!(clear > 0.3, "{clear} m from the furniture");
    }
}
