//! Hand-held camera paths with a recorded sequence's motion statistics: a smooth random path of
//! the eye inside a box and of the point it looks at inside another, optional turns about the
//! vertical, roll, and hand shake (4-9 Hz) on top. The smooth path is time-scaled so that its
//! mean translational speed, and rotation-scaled so that its mean angular speed, equal the
//! figures the benchmark publishes for the sequence; the shake is then scaled so that the
//! motion from frame to frame exceeds the smooth motion by the ratio measured on a real
//! hand-held sequence ([`Shake`]).
//!
//! Why two levels: TUM's published speeds describe the smooth motion. On the real fr2_desk
//! (../shared/data/tum_fr2_desk) the ground truth at 100 Hz gives 0.193 m/s, as published,
//! but 54 deg/s of rotation (motion-capture noise); over 1 s steps it gives 6.0 deg/s, near the
//! published 6.34. From frame to frame (33 ms) the ORB-SLAM2 estimate of the same sequence
//! turns 10.8 deg/s against 6.2 over 1 s steps (ratio 1.74), the ground truth 10.3 over 0.1 s
//! against 6.0 (1.72); both include some noise of their own, so the ratio is an upper bound.
//!
//! The path is a pure function of its parameters and its own seed, so a twin's camera follows
//! the same path for every sequence seed (as a recorded sequence does for every run).

use std::f64::consts::TAU;

use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::motion::smooth::look_at;

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
    /// Whether the target box turns with the walk about the eye box's centre (the walker
    /// looks outwards, at the walls beyond: fr1_room), rather than staying put (looking
    /// inwards at what the walk circles: fr3_long_office_household). The target box is then
    /// given as seen from the walk's start.
    pub carry_target: bool,
}

/// How much faster the camera moves from frame to frame than its smooth path: the shake's
/// amplitudes are solved so that the mean speeds between frames at `rate_hz` are these
/// multiples of the smooth path's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shake {
    /// Frame rate at which the ratios are measured, Hz.
    pub rate_hz: f64,
    /// Frame-to-frame over smooth mean translational speed (fr2_desk ground truth: 1.05).
    pub speed_ratio: f64,
    /// Frame-to-frame over smooth mean angular speed (fr2_desk: 1.7).
    pub angular_ratio: f64,
}

/// The frame-to-frame shake of hand-held TUM sequences, measured on fr2_desk (see the module
/// documentation): 1.05 in translation, 1.7 in rotation, at 30 Hz.
pub const TUM_SHAKE: Shake = Shake {
    rate_hz: 30.0,
    speed_ratio: 1.05,
    angular_ratio: 1.7,
};

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
    /// Hand tremor: its spectral shape, and its amplitudes unless `shake` solves them.
    pub tremor: Tremor,
    /// Frame-to-frame shake to reach by scaling the tremor, if any.
    pub shake: Option<Shake>,
    /// How the mean speeds are measured when solving ([`HandHeldPath::smooth_speeds`]):
    /// `None`, along the smooth path, between samples at [`STATS_RATE`]; `Some(w)`, from the
    /// displacement and rotation between poses `w` seconds apart, divided by `w`. TUM's
    /// statistics script computes its page's figures with `w` = 1 s, which falls below the
    /// speed along the path where the path turns back within a second (fast hand-held
    /// sweeps, rotation on the spot).
    pub speed_window_s: Option<f64>,
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
    /// Scales of the tremor's displacement and rotation (1 without `shake`).
    tremor_scale: [f64; 2],
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
            tremor_scale: [1.0, 1.0],
        };
        path.solve();
        path
    }

    /// Bisection of `set(x)` over `lo..hi` (geometric when `log`) until `measure()` reaches
    /// `goal` (assumed increasing in x); leaves the midpoint set.
    fn bisect(
        &mut self,
        (mut lo, mut hi): (f64, f64),
        log: bool,
        steps: usize,
        goal: f64,
        set: impl Fn(&mut Self, f64),
        measure: impl Fn(&Self) -> f64,
    ) {
        let mid = |lo: f64, hi: f64| {
            if log {
                (lo * hi).sqrt()
            } else {
                0.5 * (lo + hi)
            }
        };
        for _ in 0..steps {
            let m = mid(lo, hi);
            set(self, m);
            if measure(self) < goal {
                lo = m;
            } else {
                hi = m;
            }
        }
        set(self, mid(lo, hi));
    }

    /// Solves the time scale for the mean speed and the rotation scale for the mean angular
    /// speed of the smooth path, then (with a [`Shake`]) the tremor scales for the
    /// frame-to-frame speeds.
    fn solve(&mut self) {
        let (v, w) = (self.spec.mean_speed, self.spec.mean_angular_speed);
        self.bisect(
            (1e-4, 100.0),
            true,
            32,
            v,
            |p, x| p.time_scale = x,
            |p| p.smooth_speeds().0,
        );
        self.bisect(
            (0.0, 20.0),
            false,
            24,
            w,
            |p, x| p.rotation_scale = x,
            |p| p.smooth_speeds().1,
        );
        if let Some(shake) = self.spec.shake {
            // The two tremor amplitudes barely interact: solve each with the other in place.
            for _ in 0..2 {
                self.bisect(
                    (0.0, 50.0),
                    false,
                    20,
                    shake.speed_ratio * v,
                    |p, x| p.tremor_scale[0] = x,
                    |p| p.frame_speeds(shake.rate_hz).0,
                );
                self.bisect(
                    (0.0, 50.0),
                    false,
                    20,
                    shake.angular_ratio * w,
                    |p, x| p.tremor_scale[1] = x,
                    |p| p.frame_speeds(shake.rate_hz).1,
                );
            }
        }
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
        self.pose_with(t, true)
    }

    /// The pose at `t`, with or without the tremor.
    fn pose_with(&self, t: f64, tremor: bool) -> Isometry3<f64> {
        let s = &self.spec;
        let u = t * self.time_scale;
        let on = if tremor { 1.0 } else { 0.0 };
        let tp = on * self.tremor_scale[0] * s.tremor.position_m;
        let orbit = s.orbit.map_or([0.0; 3], |o| {
            let a = o.start_rad + TAU * o.rate * u;
            [o.semi_axes[0] * a.cos(), o.semi_axes[1] * a.sin(), 0.0]
        });
        // The angle walked round the orbit, when the target turns with it.
        let carried = s.orbit.filter(|o| o.carry_target).map(|o| TAU * o.rate * u);
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
        let mut aim = centre + target_offset;
        if let Some(angle) = carried {
            let c = Vector3::from(s.eye.centre);
            aim = c + Rotation3::from_axis_angle(&Vector3::z_axis(), angle) * (aim - c);
        }
        let target = from + spin * (aim - from);
        let base = look_at(&from, &target);
        let roll = k * s.roll_rad * sum(&self.roll, u);
        let ta = on * self.tremor_scale[1] * s.tremor.angle_rad;
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

    /// Mean translational (m/s) and angular (rad/s) speed of the smooth path (no tremor) over
    /// the duration, as the spec's [`MotionSpec::speed_window_s`] measures them (by default
    /// from poses at [`STATS_RATE`]): what the benchmark publishes.
    pub fn smooth_speeds(&self) -> (f64, f64) {
        match self.spec.speed_window_s {
            None => self.speeds(STATS_RATE, false),
            Some(w) => self.windowed_speeds(w),
        }
    }

    /// Mean translational and angular speed of the smooth path between poses `window` seconds
    /// apart, the first of each pair every 1 / [`STATS_RATE`] s from the start.
    fn windowed_speeds(&self, window: f64) -> (f64, f64) {
        let pairs = ((self.spec.duration_s - window) * STATS_RATE).floor();
        if !(pairs >= 1.0 && window > 0.0) {
            return (0.0, 0.0);
        }
        let n = pairs as usize;
        let (mut lin, mut ang) = (0.0, 0.0);
        for i in 0..n {
            let t = i as f64 / STATS_RATE;
            let d = self.pose_with(t, false).inverse() * self.pose_with(t + window, false);
            lin += d.translation.vector.norm();
            ang += d.rotation.angle();
        }
        (lin / (n as f64 * window), ang / (n as f64 * window))
    }

    /// Mean translational and angular speed between frames at `rate_hz`, tremor included.
    pub fn frame_speeds(&self, rate_hz: f64) -> (f64, f64) {
        self.speeds(rate_hz, true)
    }

    /// The tremor's RMS displacement (m) and rotation (rad) per axis, as solved.
    pub fn tremor_rms(&self) -> (f64, f64) {
        (
            self.tremor_scale[0] * self.spec.tremor.position_m,
            self.tremor_scale[1] * self.spec.tremor.angle_rad,
        )
    }

    fn speeds(&self, rate: f64, tremor: bool) -> (f64, f64) {
        let n = (self.spec.duration_s * rate).floor() as usize;
        if n == 0 {
            return (0.0, 0.0);
        }
        let dt = 1.0 / rate;
        let (mut lin, mut ang) = (0.0, 0.0);
        let mut prev = self.pose_with(0.0, tremor);
        for i in 1..=n {
            let next = self.pose_with(i as f64 * dt, tremor);
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
            shake: None,
            speed_window_s: None,
            seed: 7,
        }
    }

    #[test]
    fn solved_path_has_the_asked_mean_speeds() {
        let p = HandHeldPath::new(spec());
        let (v, w) = p.smooth_speeds();
        assert!((v - 0.25).abs() < 0.0025, "{v}");
        assert!((w - 0.3).abs() < 0.003, "{w}");
        // With a shake, the frame-to-frame speeds are the asked multiples and the smooth
        // path keeps its speeds.
        let shaky = HandHeldPath::new(MotionSpec {
            shake: Some(TUM_SHAKE),
            ..spec()
        });
        let (v, w) = shaky.smooth_speeds();
        assert!((v - 0.25).abs() < 0.0025 && (w - 0.3).abs() < 0.003);
        let (fv, fw) = shaky.frame_speeds(30.0);
        assert!((fv / 0.25 - 1.05).abs() < 0.01, "{fv}");
        assert!((fw / 0.3 - 1.7).abs() < 0.02, "{fw}");
        // Deterministic in the spec.
        assert_eq!(HandHeldPath::new(spec()).pose_at(3.3), p.pose_at(3.3));
    }

    #[test]
    fn a_speed_window_solves_for_the_figures_over_it() {
        let windowed = HandHeldPath::new(MotionSpec {
            speed_window_s: Some(1.0),
            ..spec()
        });
        let (v, w) = windowed.smooth_speeds();
        assert!((v - 0.25).abs() < 0.0025, "{v}");
        assert!((w - 0.3).abs() < 0.003, "{w}");
        // Chords of a second are shorter than the path along them: the windowed path moves
        // faster along itself than the default one.
        let (av, aw) = windowed.speeds(STATS_RATE, false);
        assert!(av > 0.25 && aw > 0.3, "{av} {aw}");
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
    fn a_carried_target_looks_outwards_round_the_orbit() {
        let mut s = spec();
        s.orbit = Some(Orbit {
            semi_axes: [1.0, 1.0],
            start_rad: -std::f64::consts::FRAC_PI_2,
            rate: 0.05,
            carry_target: true,
        });
        // Beyond the eye at the start, as seen from the orbit's centre.
        s.target = Region {
            centre: [0.0, -4.0, 1.2],
            half: [0.3, 0.1, 0.1],
        };
        s.roll_rad = 0.0;
        let p = HandHeldPath::new(s.clone());
        let centre = Vector3::from(s.eye.centre);
        let mut dots = Vec::new();
        for i in 0..40 {
            let pose = p.pose_at(i as f64 * 0.5);
            let out = pose.translation.vector - centre;
            let axis = pose.rotation * Vector3::z();
            let (o, a) = (out.xy().normalize(), axis.xy().normalize());
            dots.push(o.dot(&a));
        }
        // The optical axis points away from the orbit's centre all the way round (swaying
        // by up to 60 degrees to reach the asked angular speed).
        let mean = dots.iter().sum::<f64>() / dots.len() as f64;
        assert!(mean > 0.6 && dots.iter().all(|&d| d > 0.3), "{dots:?}");
        // Not carried, the same target is looked at from everywhere: inwards half the time.
        let fixed = HandHeldPath::new(MotionSpec {
            orbit: s.orbit.map(|o| Orbit {
                carry_target: false,
                ..o
            }),
            ..s
        });
        let inwards = (0..40)
            .map(|i| fixed.pose_at(i as f64 * 0.5))
            .filter(|q| {
                let out = q.translation.vector - centre;
                (q.rotation * Vector3::z()).xy().dot(&out.xy()) < 0.0
            })
            .count();
        assert!(inwards > 5, "{inwards}");
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
