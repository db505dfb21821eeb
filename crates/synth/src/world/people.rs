//! People for the twins of TUM's fr3 walking and sitting sequences: articulated bodies (torso,
//! head, arms, thighs, shanks) that walk at human speed, stop, turn, sit down on chairs and get
//! up, each limb moving on its own, so that parts of a person stay still for a while (a seated
//! torso) and then move (an arm that gestures, legs that stand up).
//!
//! A person follows a looping script of actions drawn from the scene seed: walk to a point of
//! the floor between the camera and the desk (1-3 m from a camera in front of the desk), pause,
//! turn, walk back, sit on their chair, sit for a few seconds while gesturing, stand up. Sitting
//! people ([`Activity::Sitting`]) stay seated the whole sequence: they lean, turn their heads
//! and gesture, moving little, as in fr3_sitting_*.
//!
//! Body measures are those of an adult of about 1.75 m (anthropometric tables round to a few
//! cm: hip height 0.92 m, thigh 0.45 m, shank with foot 0.47 m, torso 0.56 m, arm 0.62 m);
//! walking speed 1.2 m/s (the 1-1.4 m/s; comfortable adult gait), a full gait cycle of
//! 1.4 m (two steps of 0.7 m), hip swing +-22 degrees, knee flexion up to 40 degrees.
//!
//! World frame as the scene's: x, y horizontal, z up; a body's local frame has x forward, y to
//! its left, z up; a limb hangs along its local -z from its joint, swung by `pitch` about the
//! body's lateral axis (positive: the far end swings forward).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::world::shape::Shape;

/// What the people of a scene do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Activity {
    /// Walk about between the camera and the desk, stop, turn, sit down for a while, get up
    /// (fr3_walking_*).
    Walking,
    /// Stay seated at the desk, leaning, turning heads and gesturing (fr3_sitting_*).
    Sitting,
}

/// Walking speed, m/s.
pub const WALK_SPEED: f64 = 1.2;
/// Distance of one full gait cycle (two steps), metres.
pub const STRIDE: f64 = 1.4;
/// Hip swing amplitude while walking, radians.
const HIP_SWING: f64 = 22.0 * PI / 180.0;
/// Largest knee flexion while walking, radians.
const KNEE_FLEX: f64 = 40.0 * PI / 180.0;
/// Arm swing amplitude while walking, radians.
const ARM_SWING: f64 = 18.0 * PI / 180.0;
/// Turning rate on the spot, radians per second.
const TURN_RATE: f64 = 4.0;
/// Duration of sitting down or standing up, seconds.
const SIT_TRANSITION: f64 = 1.3;
/// Hip height standing, metres.
const HIP_STANDING: f64 = 0.92;
/// Hip height seated (seat 0.45 m + half a thigh's thickness), metres.
const HIP_SEATED: f64 = 0.52;
const THIGH: f64 = 0.45;
const SHANK: f64 = 0.47;
const TORSO_HALF: [f64; 3] = [0.11, 0.19, 0.28];
const SHOULDER_ABOVE_HIP: f64 = 0.54;
const ARM: f64 = 0.62;
const HIP_HALF_WIDTH: f64 = 0.1;
const SHOULDER_HALF_WIDTH: f64 = 0.24;

/// Body parts of a person, in [`Person::pose`] order.
pub const PARTS: [&str; 8] = [
    "torso",
    "head",
    "left arm",
    "right arm",
    "left thigh",
    "right thigh",
    "left shank",
    "right shank",
];

/// The shapes of the body parts, in [`PARTS`] order, each centred on its local origin.
pub fn part_shapes() -> [Shape; 8] {
    let limb = |radius: f64, length: f64| Shape::Cylinder {
        radius,
        half_height: length / 2.0,
    };
    [
        Shape::Cuboid { half: TORSO_HALF },
        Shape::Cylinder {
            radius: 0.095,
            half_height: 0.12,
        },
        limb(0.045, ARM),
        limb(0.045, ARM),
        limb(0.075, THIGH),
        limb(0.075, THIGH),
        limb(0.055, SHANK),
        limb(0.055, SHANK),
    ]
}

/// Where a body part is at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PartPose {
    /// Centre of the part's shape, world, metres.
    pub centre: Vector3<f64>,
    /// Heading about the vertical, radians (local x forward).
    pub yaw: f64,
    /// Swing about the body's lateral axis, radians (positive: the lower end forward).
    pub pitch: f64,
}

/// A chair of a scene with people: seat centre on the floor plane and the heading of a person
/// seated on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chair {
    /// Seat centre, world x, y (metres).
    pub at: [f64; 2],
    /// Heading of the seated person, radians.
    pub yaw: f64,
}

impl Chair {
    /// Where a person stands before sitting down: a step in front of the seat.
    fn stand_spot(&self) -> [f64; 2] {
        [
            self.at[0] + 0.3 * self.yaw.cos(),
            self.at[1] + 0.3 * self.yaw.sin(),
        ]
    }
}

/// The chairs of a scene with people: two at the near side of the desk, facing each other (so
/// seated people show the camera their profiles).
pub const CHAIRS: [Chair; 2] = [
    Chair {
        at: [-0.62, 0.22],
        yaw: 0.0,
    },
    Chair {
        at: [0.62, 0.22],
        yaw: PI,
    },
];

/// The floor area people walk in: between a camera in front of the desk and the desk's chairs,
/// clear of the furniture (x range, y range; metres).
pub const WALK_AREA: ([f64; 2], [f64; 2]) = ([-1.45, 1.35], [-0.85, -0.15]);

/// One action of a script, over `[t0, t1)` seconds of the script's cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Segment {
    t0: f64,
    t1: f64,
    action: Action,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Action {
    /// Stand at `at`, turning from `from` to `to`.
    Turn { at: [f64; 2], from: f64, to: f64 },
    /// Walk in a straight line, gait phase counted from `distance0` metres walked before.
    Walk {
        from: [f64; 2],
        to: [f64; 2],
        yaw: f64,
        distance0: f64,
    },
    /// Stand still.
    Stand { at: [f64; 2], yaw: f64 },
    /// Sit down (`down`) or stand up from chair `chair`.
    Sit { chair: Chair, down: bool },
    /// Seated.
    Seated { chair: Chair },
}

/// Root state of a body at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Root {
    at: [f64; 2],
    yaw: f64,
    /// 0 standing, 1 seated.
    seated: f64,
    /// 0 still, 1 full walking gait.
    gait: f64,
    /// Gait phase, radians.
    phase: f64,
}

/// One person: a looping script and the phases of their seated gestures.
#[derive(Clone, Debug, PartialEq)]
pub struct Person {
    script: Vec<Segment>,
    cycle: f64,
    /// Start of the script at scene time 0, seconds into the cycle.
    offset: f64,
    gesture_phase: [f64; 3],
}

/// Shortest signed angle from `a` to `b`.
fn angle_to(a: f64, b: f64) -> f64 {
    (b - a + PI).rem_euclid(TAU) - PI
}

fn heading(from: [f64; 2], to: [f64; 2]) -> f64 {
    (to[1] - from[1]).atan2(to[0] - from[0])
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Smooth 0 -> 1 over [0, 1].
fn smooth(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

struct ScriptBuilder {
    segments: Vec<Segment>,
    t: f64,
    at: [f64; 2],
    yaw: f64,
    walked: f64,
}

impl ScriptBuilder {
    fn push(&mut self, duration: f64, action: Action) {
        self.segments.push(Segment {
            t0: self.t,
            t1: self.t + duration,
            action,
        });
        self.t += duration;
    }

    fn turn_to(&mut self, yaw: f64) {
        let d = angle_to(self.yaw, yaw);
        if d.abs() > 1e-6 {
            let (at, from) = (self.at, self.yaw);
            self.push(
                0.2 + d.abs() / TURN_RATE,
                Action::Turn {
                    at,
                    from,
                    to: from + d,
                },
            );
        }
        self.yaw = yaw;
    }

    fn walk_to(&mut self, to: [f64; 2]) {
        let yaw = heading(self.at, to);
        self.turn_to(yaw);
        let d = dist(self.at, to);
        let from = self.at;
        let distance0 = self.walked;
        self.push(
            d / WALK_SPEED,
            Action::Walk {
                from,
                to,
                yaw,
                distance0,
            },
        );
        self.walked += d;
        self.at = to;
    }

    fn stand(&mut self, duration: f64) {
        let (at, yaw) = (self.at, self.yaw);
        self.push(duration, Action::Stand { at, yaw });
    }

    fn sit(&mut self, chair: Chair, seated_for: f64) {
        // Round the chairs' front, then to the spot in front of the seat.
        let spot = chair.stand_spot();
        self.walk_to([spot[0], WALK_AREA.1[1] - 0.1]);
        self.walk_to(spot);
        // Back to the seat, facing the way the seated person will.
        self.turn_to(chair.yaw);
        self.push(SIT_TRANSITION, Action::Sit { chair, down: true });
        self.push(seated_for, Action::Seated { chair });
        self.push(SIT_TRANSITION, Action::Sit { chair, down: false });
        self.at = chair.stand_spot();
        self.yaw = chair.yaw;
    }
}

impl Person {
    /// Person `index` of a scene doing `activity`, with a script drawn from `rng`.
    pub fn new(index: usize, activity: Activity, rng: &mut ChaCha8Rng) -> Person {
        let chair = CHAIRS[index % CHAIRS.len()];
        let gesture_phase = [
            rng.random_range(0.0..TAU),
            rng.random_range(0.0..TAU),
            rng.random_range(0.0..TAU),
        ];
        let mut b = ScriptBuilder {
            segments: Vec::new(),
            t: 0.0,
            at: chair.stand_spot(),
            yaw: chair.yaw,
            walked: 0.0,
        };
        match activity {
            Activity::Sitting => {
                b.push(3600.0, Action::Seated { chair });
            }
            Activity::Walking => {
                // From in front of the chair, four to six walks through the area with
                // pauses, back to the chair, seated a while, up again: the cycle ends where it
                // starts and repeats.
                let walks = rng.random_range(4..=6);
                let (xs, ys) = WALK_AREA;
                for _ in 0..walks {
                    // A point at least 1.6 m away, so that walks cross the view.
                    let mut to = b.at;
                    for _ in 0..32 {
                        to = [
                            rng.random_range(xs[0]..xs[1]),
                            rng.random_range(ys[0]..ys[1]),
                        ];
                        if dist(to, b.at) > 1.6 {
                            break;
                        }
                    }
                    b.walk_to(to);
                    if rng.random_bool(0.4) {
                        let pause = rng.random_range(0.3..1.0);
                        b.stand(pause);
                    }
                }
                let seated = rng.random_range(1.5..4.0);
                b.sit(chair, seated);
            }
        }
        let cycle = b.t;
        Person {
            script: b.segments,
            cycle,
            offset: if activity == Activity::Walking {
                rng.random_range(0.0..cycle)
            } else {
                0.0
            },
            gesture_phase,
        }
    }

    /// Duration of one cycle of the script, seconds.
    pub fn cycle(&self) -> f64 {
        self.cycle
    }

    fn root(&self, t: f64) -> (Root, bool) {
        let s = (t + self.offset).rem_euclid(self.cycle);
        let seg = self
            .script
            .iter()
            .find(|g| s < g.t1)
            .or(self.script.last())
            .expect("a script has actions");
        let u = ((s - seg.t0) / (seg.t1 - seg.t0)).clamp(0.0, 1.0);
        let still = |at: [f64; 2], yaw: f64| Root {
            at,
            yaw,
            seated: 0.0,
            gait: 0.0,
            phase: 0.0,
        };
        match seg.action {
            Action::Turn { at, from, to } => (still(at, from + (to - from) * smooth(u)), false),
            Action::Stand { at, yaw } => (still(at, yaw), false),
            Action::Walk {
                from,
                to,
                yaw,
                distance0,
            } => {
                let d = dist(from, to);
                let along = d * u;
                // The gait starts and stops within a quarter stride.
                let ramp = (along.min(d - along) / (0.25 * STRIDE)).min(1.0);
                (
                    Root {
                        at: [
                            from[0] + (to[0] - from[0]) * u,
                            from[1] + (to[1] - from[1]) * u,
                        ],
                        yaw,
                        seated: 0.0,
                        gait: smooth(ramp),
                        phase: TAU * (distance0 + along) / STRIDE,
                    },
                    false,
                )
            }
            Action::Sit { chair, down } => {
                let k = smooth(if down { u } else { 1.0 - u });
                let stand = chair.stand_spot();
                // The hips move back over the seat as they go down.
                let hips = [
                    stand[0] + (chair.at[0] - stand[0]) * k,
                    stand[1] + (chair.at[1] - stand[1]) * k,
                ];
                (
                    Root {
                        at: hips,
                        yaw: chair.yaw,
                        seated: k,
                        gait: 0.0,
                        phase: 0.0,
                    },
                    false,
                )
            }
            Action::Seated { chair } => (
                Root {
                    at: chair.at,
                    yaw: chair.yaw,
                    seated: 1.0,
                    gait: 0.0,
                    phase: 0.0,
                },
                true,
            ),
        }
    }

    /// The body parts at time `t` seconds, in [`PARTS`] order.
    pub fn pose(&self, t: f64) -> [PartPose; 8] {
        let (root, seated_still) = self.root(t);
        let yaw = root.yaw;
        let (cy, sy) = (yaw.cos(), yaw.sin());
        let fwd = Vector3::new(cy, sy, 0.0);
        let left = Vector3::new(-sy, cy, 0.0);
        let up = Vector3::z();
        // The far end of a limb of pitch p, hanging from its joint: forward * sin p - up * cos p.
        let down = |p: f64| fwd * p.sin() - up * p.cos();
        let k = root.seated;
        // Seated gestures: slow lean, head turns, one arm talking.
        let [g0, g1, g2] = self.gesture_phase;
        let gest = if seated_still { 1.0 } else { 0.0 };
        let lean = gest * (0.12 + 0.1 * (0.9 * t + g0).sin());
        let head_turn = gest * 0.45 * (0.35 * t + g1).sin();
        let talk = gest * (0.5 + 0.5 * (1.7 * t + g2).sin());

        let hip_h = HIP_STANDING + (HIP_SEATED - HIP_STANDING) * k;
        let pelvis = Vector3::new(root.at[0], root.at[1], hip_h);
        // Torso: leans forward while sitting down (k in (0, 1)) and when gesturing.
        let torso_lean = 0.35 * (PI * k).sin() + lean + 0.05 * root.gait;
        let spine = -down(-torso_lean); // points up and a little forward for a forward lean
        let torso_centre = pelvis + spine * TORSO_HALF[2];
        let shoulders = pelvis + spine * SHOULDER_ABOVE_HIP;
        let head = pelvis + spine * (2.0 * TORSO_HALF[2] + 0.02 + 0.12);

        let phase = root.phase;
        let g = root.gait;
        let mut parts = [PartPose {
            centre: Vector3::zeros(),
            yaw,
            pitch: 0.0,
        }; 8];
        parts[0] = PartPose {
            centre: torso_centre,
            yaw,
            pitch: -torso_lean,
        };
        parts[1] = PartPose {
            centre: head,
            yaw: yaw + head_turn,
            pitch: -torso_lean,
        };
        for (side, sign) in [(0usize, 1.0f64), (1, -1.0)] {
            let swing = g * HIP_SWING * (phase + side as f64 * PI).sin();
            // Thigh: swings while walking, forward and level when seated.
            let thigh_pitch = swing * (1.0 - k) + FRAC_PI_2 * k;
            // Knee: flexes in the swing phase; the shank hangs vertical when seated.
            let flex = g * KNEE_FLEX * (phase + side as f64 * PI + 0.6).sin().max(0.0);
            let shank_pitch = (thigh_pitch - flex) * (1.0 - k);
            let hip = pelvis + left * (sign * HIP_HALF_WIDTH);
            let knee = hip + down(thigh_pitch) * THIGH;
            parts[4 + side] = PartPose {
                centre: hip + down(thigh_pitch) * (THIGH / 2.0),
                yaw,
                pitch: thigh_pitch,
            };
            parts[6 + side] = PartPose {
                centre: knee + down(shank_pitch) * (SHANK / 2.0),
                yaw,
                pitch: shank_pitch,
            };
            // Arms swing against the leg of their side; seated, the right arm talks and the
            // left rests forward on the thigh.
            let arm_walk = -g * ARM_SWING * (phase + side as f64 * PI).sin();
            let arm_seated = if side == 1 { 0.5 + 0.6 * talk } else { 0.45 };
            let arm_pitch = arm_walk * (1.0 - k) + arm_seated * k - torso_lean;
            let shoulder = shoulders + left * (sign * SHOULDER_HALF_WIDTH);
            parts[2 + side] = PartPose {
                centre: shoulder + down(arm_pitch) * (ARM / 2.0),
                yaw,
                pitch: arm_pitch,
            };
        }
        parts
    }
}

/// The people of a scene: `count` persons doing `activity`, scripts drawn from `seed`.
pub fn people(seed: u64, count: usize, activity: Activity) -> Vec<Person> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x9E09_1E00_0000_0017);
    (0..count)
        .map(|i| Person::new(i, activity, &mut rng))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walkers_walk_at_human_speed_and_stop_sit_and_stand() {
        for seed in 0..4 {
            for p in people(seed, 2, Activity::Walking) {
                let dt = 0.05;
                let n = (p.cycle() / dt) as usize;
                let mut speeds = Vec::new();
                let mut seated = 0;
                let mut still = 0;
                for i in 0..n {
                    let t = i as f64 * dt;
                    let (a, _) = p.root(t);
                    let (b, _) = p.root(t + dt);
                    let v = dist(a.at, b.at) / dt;
                    speeds.push(v);
                    seated += (a.seated > 0.99) as usize;
                    still += (v < 1e-9) as usize;
                }
                let max = speeds.iter().cloned().fold(0.0, f64::max);
                assert!((max - WALK_SPEED).abs() < 0.05, "top speed {max}");
                assert!(seated > 0 && still > seated, "sits and stops");
                let walking = speeds.iter().filter(|&&v| v > 1.0).count();
                assert!(
                    walking as f64 > 0.35 * n as f64,
                    "mostly walking: {walking}/{n}"
                );
            }
        }
    }

    #[test]
    fn limbs_hang_from_their_joints() {
        // Standing still: legs vertical below the hips, the feet on the floor.
        let p = &people(1, 1, Activity::Walking)[0];
        for i in 0..400 {
            let t = i as f64 * 0.09;
            let parts = p.pose(t);
            let (root, _) = p.root(t);
            for side in 0..2 {
                let thigh = parts[4 + side];
                let shank = parts[6 + side];
                // The knee: the thigh's lower end equals the shank's upper end.
                let dt = |q: &PartPose, len: f64| {
                    let (cy, sy) = (q.yaw.cos(), q.yaw.sin());
                    let fwd = Vector3::new(cy, sy, 0.0);
                    (fwd * q.pitch.sin() - Vector3::z() * q.pitch.cos()) * (len / 2.0)
                };
                let knee_a = thigh.centre + dt(&thigh, THIGH);
                let knee_b = shank.centre - dt(&shank, SHANK);
                assert!((knee_a - knee_b).norm() < 1e-12, "t {t}");
                if root.gait == 0.0 && root.seated == 0.0 {
                    let foot = shank.centre + dt(&shank, SHANK);
                    assert!(foot.z.abs() < 1e-9, "foot at {foot:?}");
                }
            }
        }
    }

    #[test]
    fn seated_people_stay_on_their_chairs_and_move_only_limbs_and_heads() {
        let ps = people(2, 2, Activity::Sitting);
        for (i, p) in ps.iter().enumerate() {
            let a = p.pose(1.0);
            let b = p.pose(4.0);
            // Thighs and shanks still; the talking arm and the head move.
            for k in 4..8 {
                assert!((a[k].centre - b[k].centre).norm() < 1e-12);
            }
            assert!((a[3].centre - b[3].centre).norm() > 0.01);
            assert!((a[1].yaw - b[1].yaw).abs() > 0.01);
            let c = CHAIRS[i];
            let hip = (a[4].centre + a[5].centre) / 2.0;
            assert!((hip.x - (c.at[0] + 0.5 * THIGH * c.yaw.cos())).abs() < 1e-9);
        }
    }
}
