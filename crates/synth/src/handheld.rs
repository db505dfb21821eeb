//! Hand-held camera paths with a recorded sequence's motion statistics: a smooth random path of
//! the eye inside a box and of the point it looks at inside another, optional turns about the
//! vertical, roll, and physiological hand tremor (2-8 Hz) on top; time-scaled so that the mean
//! translational speed, and rotation-scaled so that the mean angular speed, equal the figures
//! the benchmark publishes for the sequence (measured here as there: from poses at 100 Hz).
//!
//! The path is a pure function of its parameters and its own seed, so a twin's camera follows
//! the same path for every sequence seed (as a recorded sequence does for every run).

use std::f64::consts::TAU;

use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::trajectory::look_at;

/// An axis-aligned box of the room (world frame, metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    /// Centre.
    pub centre: [f64; 3],
    /// Half extents.
    pub half: [f64; 3],
}

/// Hand tremor: small fast motion on top of the intended path (physiological tremor lies at
/// 4-12 Hz with amplitudes of tenths of a millimetre to a few millimetres at the hand).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tremor {
    /// RMS displacement per axis, metres.
    pub position_m: f64,
    /// RMS rotation per axis, radians.
    pub angle_rad: f64,
}

/// A walk round a closed ellipse in the floor plane (fr3_long_office_household circles its
/// desks): the eye's box rides along it; the speed of the walk follows from the time scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// Semi-axes along x and y, metres (about the eye box's centre).
    pub semi_axes: [f64; 2],
    /// Angle on the ellipse at the start, radians.
    pub start_rad: f64,
    /// Turns per second of path time, before time scaling.
    pub rate: f64,
}

/// What a hand-held path must reproduce and where it may go.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionSpec {
    /// Name used in messages and file names (the twin's).
    pub label: String,
    /// Duration, seconds.
    pub duration_s: f64,
    /// Mean translational speed over the duration, m/s.
    pub mean_speed: f64,
    /// Mean angular speed over the duration, rad/s.
    pub mean_angular_speed: f64,
    /// Where the eye moves.
    pub eye: Region,
    /// Where the camera looks (scaled about its centre to reach the angular speed).
    pub target: Region,
    /// Whole turns about the vertical over the duration (fr1_360: about one).
    pub turns: f64,
    /// A walk round an ellipse carrying the eye's box, if any.
    pub orbit: Option<Orbit>,
    /// Whether the camera keeps pointing at the target while the eye moves (`true`), or keeps
    /// the orientation it has from the eye box's centre (`false`: translation without the
    /// rotation that tracking would add, as in TUM's `xyz` sequences).
    pub track_target: bool,
    /// Roll amplitude about the optical axis before scaling, radians.
    pub roll_rad: f64,
    /// Hand tremor.
    pub tremor: Tremor,
    /// Seed of the path's own random phases and frequencies.
    pub seed: u64,
}

/// One sine component.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Sine {
    amp: f64,
    freq: f64,
    phase: f64,
}

fn sum(s: &[Sine], t: f64) -> f64 {
    s.iter()
        .map(|c| c.amp * (TAU * c.freq * t + c.phase).sin())
        .sum()
}

/// `n` components with amplitudes summing to 1 (so the sum stays within -1..1) and
/// frequencies in `lo..hi` Hz.
fn components(rng: &mut ChaCha8Rng, n: usize, lo: f64, hi: f64) -> Vec<Sine> {
    let mut c: Vec<Sine> = (0..n)
        .map(|_| Sine {
            amp: rng.random_range(0.3..1.0),
            freq: rng.random_range(lo..hi),
            phase: rng.random_range(0.0..TAU),
        })
        .collect();
    let total: f64 = c.iter().map(|s| s.amp).sum();
    for s in &mut c {
        s.amp /= total;
    }
    c
}

/// Components with unit RMS (independent sines: rms = sqrt(sum amp^2 / 2)).
fn unit_rms(mut c: Vec<Sine>) -> Vec<Sine> {
    let rms = (c.iter().map(|s| s.amp * s.amp).sum::<f64>() / 2.0).sqrt();
    for s in &mut c {
        s.amp /= rms;
    }
    c
}

/// A hand-held path solved for a [`MotionSpec`].
#[derive(Clone, Debug, PartialEq)]
pub struct HandHeldPath {
    spec: MotionSpec,
    eye: [Vec<Sine>; 3],
    target: [Vec<Sine>; 3],
    roll: Vec<Sine>,
    tremor_pos: [Vec<Sine>; 3],
    tremor_rot: [Vec<Sine>; 3],
    /// Path time per second (scales the smooth path's frequencies, not the tremor's).
    time_scale: f64,
    /// Scale of the target box and the roll about their centre.
    rotation_scale: f64,
}

/// Sampling rate of the motion statistics, Hz (the TUM motion-capture rate).
pub const STATS_RATE: f64 = 100.0;

impl HandHeldPath {
    /// Draws the path's components from the spec's seed and solves the two scales so the
    /// mean speeds equal the spec's. The smooth path's components lie at 0.02-0.15 Hz of path
    /// time, the tremor's at 4-9 Hz.
    pub fn new(spec: MotionSpec) -> HandHeldPath {
        let mut rng = ChaCha8Rng::seed_from_u64(spec.seed ^ 0x4A4E_D4E1_D000_0017);
        let mut three = |lo: f64, hi: f64, n: usize| {
            [
                components(&mut rng, n, lo, hi),
                components(&mut rng, n, lo, hi),
                components(&mut rng, n, lo, hi),
            ]
        };
        let eye = three(0.02, 0.15, 4);
        let target = three(0.02, 0.12, 3);
        let tremor_pos = three(4.0, 9.0, 3).map(unit_rms);
        let tremor_rot = three(4.0, 9.0, 3).map(unit_rms);
        let roll = components(&mut rng, 3, 0.03, 0.2);
        let mut path = HandHeldPath {
            spec,
            eye,
            target,
            roll,
            tremor_pos,
            tremor_rot,
            time_scale: 1.0,
            rotation_scale: 1.0,
        };
        path.solve();
        path
    }

    /// Bisection (in log space) of the time scale for the mean speed, then of the rotation
    /// scale for the mean angular speed.
    fn solve(&mut self) {
        let (mut lo, mut hi) = (1e-4f64, 100.0f64);
        for _ in 0..32 {
            let mid = (lo * hi).sqrt();
            self.time_scale = mid;
            if self.mean_speeds().0 < self.spec.mean_speed {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        self.time_scale = (lo * hi).sqrt();
        let (mut lo, mut hi) = (0.0f64, 20.0f64);
        for _ in 0..24 {
            let mid = 0.5 * (lo + hi);
            self.rotation_scale = mid;
            if self.mean_speeds().1 < self.spec.mean_angular_speed {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        self.rotation_scale = 0.5 * (lo + hi);
    }

    /// Scale of the target box and the roll that reaches the spec's angular speed; 0 when the
    /// path turns faster than asked even without them (an orbit's own turning, the look-at
    /// tracking of the eye's motion).
    pub fn rotation_scale(&self) -> f64 {
        self.rotation_scale
    }

    /// The spec.
    pub fn spec(&self) -> &MotionSpec {
        &self.spec
    }

    /// Duration, seconds.
    pub fn duration(&self) -> f64 {
        self.spec.duration_s
    }

    /// The twin's name.
    pub fn label(&self) -> &str {
        &self.spec.label
    }

    /// Camera-to-world pose at `t` seconds.
    pub fn pose_at(&self, t: f64) -> Isometry3<f64> {
        let s = &self.spec;
        let u = t * self.time_scale;
        let tp = s.tremor.position_m;
        let orbit = s.orbit.map_or([0.0; 3], |o| {
            let a = o.start_rad + TAU * o.rate * u;
            [o.semi_axes[0] * a.cos(), o.semi_axes[1] * a.sin(), 0.0]
        });
        let eye = Vector3::from_fn(|i, _| {
            s.eye.centre[i]
                + orbit[i]
                + s.eye.half[i] * sum(&self.eye[i], u)
                + tp * sum(&self.tremor_pos[i], t)
        });
        let k = self.rotation_scale;
        let target_offset = Vector3::from_fn(|i, _| k * s.target.half[i] * sum(&self.target[i], u));
        let centre = Vector3::from(s.target.centre);
        // Turns about the vertical carry the look direction round the eye.
        let yaw = TAU * s.turns * t / s.duration_s.max(1e-9);
        let spin = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
        let from = if s.track_target {
            eye
        } else {
            Vector3::from(s.eye.centre)
        };
        let target = from + spin * (centre + target_offset - from);
        let base = look_at(&from, &target);
        let roll = k * s.roll_rad * sum(&self.roll, u);
        let ta = s.tremor.angle_rad;
        let tremor = Rotation3::from_euler_angles(
            ta * sum(&self.tremor_rot[0], t),
            ta * sum(&self.tremor_rot[1], t),
            ta * sum(&self.tremor_rot[2], t) + roll,
        );
        Isometry3::from_parts(
            Translation3::from(eye),
            UnitQuaternion::from_rotation_matrix(&(base * tremor)),
        )
    }

    /// Mean translational (m/s) and angular (rad/s) speed over the duration, from poses
    /// sampled at [`STATS_RATE`] as the benchmark computes them from its ground truth.
    pub fn mean_speeds(&self) -> (f64, f64) {
        let n = (self.spec.duration_s * STATS_RATE).floor() as usize;
        if n == 0 {
            return (0.0, 0.0);
        }
        let dt = 1.0 / STATS_RATE;
        let (mut lin, mut ang) = (0.0, 0.0);
        let mut prev = self.pose_at(0.0);
        for i in 1..=n {
            let next = self.pose_at(i as f64 * dt);
            let d = prev.inverse() * next;
            lin += d.translation.vector.norm();
            ang += d.rotation.angle();
            prev = next;
        }
        (lin / (n as f64 * dt), ang / (n as f64 * dt))
    }

    /// Every eye position over the duration at [`STATS_RATE`] (for clearance checks).
    pub fn eye_positions(&self) -> Vec<Vector3<f64>> {
        let n = (self.spec.duration_s * STATS_RATE).floor() as usize;
        (0..=n)
            .map(|i| self.pose_at(i as f64 / STATS_RATE).translation.vector)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> MotionSpec {
        MotionSpec {
            label: "test".into(),
            duration_s: 20.0,
            mean_speed: 0.25,
            mean_angular_speed: 0.3,
            eye: Region {
                centre: [0.0, -0.5, 1.4],
                half: [0.5, 0.3, 0.2],
            },
            target: Region {
                centre: [0.0, 1.0, 0.8],
                half: [0.4, 0.1, 0.2],
            },
            turns: 0.0,
            orbit: None,
            track_target: true,
            roll_rad: 0.1,
            tremor: Tremor {
                position_m: 0.001,
                angle_rad: 0.002,
            },
            seed: 7,
        }
    }

    #[test]
    fn solved_path_has_the_asked_mean_speeds() {
        let p = HandHeldPath::new(spec());
        let (v, w) = p.mean_speeds();
        assert!((v - 0.25).abs() < 0.0025, "{v}");
        assert!((w - 0.3).abs() < 0.003, "{w}");
        // Deterministic in the spec.
        assert_eq!(HandHeldPath::new(spec()).pose_at(3.3), p.pose_at(3.3));
    }

    #[test]
    fn eye_stays_in_its_box_plus_tremor() {
        let s = spec();
        let p = HandHeldPath::new(s.clone());
        for e in p.eye_positions() {
            for i in 0..3 {
                let slack = s.eye.half[i] + 10.0 * s.tremor.position_m;
                assert!((e[i] - s.eye.centre[i]).abs() <= slack, "{e:?}");
            }
        }
    }

    #[test]
    fn turns_carry_the_view_round() {
        let mut s = spec();
        s.turns = 1.0;
        s.mean_angular_speed = 0.7;
        let p = HandHeldPath::new(s);
        // Heading (look direction in the floor plane) turns by about a full circle.
        let heading = |t: f64| {
            let z = p.pose_at(t).rotation * Vector3::z();
            z.y.atan2(z.x)
        };
        let mut total = 0.0;
        let mut prev = heading(0.0);
        for i in 1..=200 {
            let h = heading(i as f64 * 0.1);
            let mut d = h - prev;
            if d > std::f64::consts::PI {
                d -= TAU;
            } else if d < -std::f64::consts::PI {
                d += TAU;
            }
            total += d;
            prev = h;
        }
        assert!((total.abs() - TAU).abs() < 0.8, "{total}");
    }
}
