//! Rigid consensus (RC): noisefree's own answer to moving people, beyond the paper. Not part of
//! the paper's MC-OR or AVC; a configuration and a column of its own.
//!
//! MC-OR asks, per landmark, whether its sightings agree with each other. RC asks, per frame,
//! which matches agree with one rigid motion of the camera: the largest set of matches that a
//! single pose explains is the static world, and everything that moves on its own (a person,
//! a limb) falls outside it, however coherently its points move together. It is the
//! consensus test of RANSAC (Fischler and Bolles 1981) over 3-D-3-D correspondences, each
//! hypothesis the absolute orientation (Horn 1987) of three matches with measured depth, and
//! hypotheses compared by their MSAC cost (Torr and Zisserman 2000): each match's chi2 of the
//! RGB-D residual (u, v, u_right) truncated at ORB-SLAM2's own gate. The consensus is the set of
//! matches inside their gates at the best hypothesis. The robust least squares of ORB-SLAM2 (and MC-OR's metre thresholds) settle
//! between the room and the people when the people's points are many and near; a consensus
//! does not average, it picks.
//!
//! Two things make the static world win when people cover much of the view:
//! - **Evidence of time.** A match counts with the number of keyframes that saw its map point,
//!   capped ([`RigidConsensusParams::weight_cap`]): the room has been seen from many keyframes,
//!   a walking person's points are re-created as the person moves and have few.
//! - **The prior.** The motion-model pose the tracker starts from is a hypothesis too.
//! - **Evidence from the first second.** A match also weighs the frames that found its map
//!   point ([`RigidConsensusParams::frames_per_weight`]), which grow thirty times faster than
//!   keyframes.
//!
//! A consensus can also be wrong on a static scene: at close range every hypothesis is a few
//! millimetres off, the near points fall outside their tight gates, and the best hypothesis is
//! the one the far points alone fit, whose translation they barely fix (twin_fr2_coke: a pose
//! 25 mm off, then 64 mm after an optimization over the far points). So when a drawn hypothesis
//! beats the prior, the tracker solves from the prior as well, and keeps that solution when it
//! is [`nested`]: it holds the consensus solution's inliers and adds matches as long-seen as
//! them (the room's near points do; a walker's young points, which a dragged pose also gains,
//! do not).
//!
//! Hypotheses are drawn by a generator keyed by the frame id and the call, not by the run's
//! RNG, so the gate is deterministic and leaves the run's random stream as it is.

use nalgebra::{Isometry3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::optimize::Measurement;
use crate::solve::absolute_orientation;
use crate::Camera;

/// Parameters of the rigid-consensus gate (defaults: 64 hypotheses are enough to draw a
/// triple of static points with probability above 99.9 % when they carry half the weight).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RigidConsensusParams {
    /// Hypotheses drawn per pose optimization (three depth matches each), besides the prior.
    pub hypotheses: usize,
    /// Fewer matches with depth than this: no gate (the frame is left to the optimizer).
    pub min_depth_matches: usize,
    /// A match weighs the number of keyframes that saw its map point (or the frames that found
    /// it over `frames_per_weight`, if more), at most this many.
    pub weight_cap: u32,
    /// Keypoints within this many pixels of a rejected match with depth, and within
    /// `mask_depth_m` of its depth, create no map points when the frame becomes a keyframe
    /// (they are on the same moving body); 0 turns the mask off (the default). The first
    /// version masked 24 px: on the sitting twin with a moving camera that cost 12 % of the map
    /// points and the baseline's accuracy, and with `veto_rounds` 1 the walking twins need no
    /// mask (w_static 4.9 / 4.8 mm, w_rpy 15.3 mm, `walking` 1.3 mm without it).
    pub mask_radius_px: f64,
    /// Depth tolerance of the mask, metres.
    pub mask_depth_m: f64,
    /// Rounds of the pose optimization (ORB-SLAM2 runs 4) from whose start the matches outside
    /// the consensus are kept out. In later rounds the optimizer's own chi2 test at the pose
    /// solved from the consensus decides, so a static match that the consensus pose (fitted to
    /// three-point samples and depth) placed just outside its gate is not lost to the frame:
    /// with every round vetoed (4) the sitting twin with a moving camera lost 10 % of its map
    /// points and ended 12 % worse than the baseline. A rejected match seeds the map-point mask
    /// only when the final pose rejects it too.
    pub veto_rounds: usize,
    /// A solution from the motion prior replaces the consensus's when its inliers hold this
    /// share of the consensus solution's inlier weight, and more weight besides. Not all of it:
    /// a consensus solution that drifted along the far points also keeps a few matches that
    /// only the wrong pose explains (8 % on a twin_fr2_coke frame whose two solutions were
    /// 70 mm apart, 160 inliers against 225). At 0.8 a walker-dragged solution passed on
    /// `walking-stereo` (151 mm against 1.9 mm).
    pub nested_share: f64,
    /// ... and when the matches it adds weigh on average at least this share of the consensus
    /// solution's mean weight (see [`nested`]).
    pub nested_evidence: f64,
    /// A match also weighs the frames that found its map point divided by this (0: keyframes
    /// only): evidence of time that exists from the first second, when every map point has
    /// been seen by one to three keyframes.
    pub frames_per_weight: u32,
}

impl Default for RigidConsensusParams {
    fn default() -> Self {
        RigidConsensusParams {
            hypotheses: 64,
            min_depth_matches: 12,
            weight_cap: 4,
            mask_radius_px: 0.0,
            mask_depth_m: 0.15,
            veto_rounds: 1,
            nested_share: 0.9,
            nested_evidence: 0.75,
            frames_per_weight: 8,
        }
    }
}

/// One match of the frame: its map point, the keypoint's measurement and, with depth, the
/// keypoint back-projected in the camera.
#[derive(Clone, Debug)]
pub struct ConsensusMatch {
    /// M, world (metres).
    pub map_point: Vector3<f64>,
    /// The keypoint back-projected with its measured depth, camera frame (metres).
    pub point_camera: Option<Vector3<f64>>,
    /// The baseline measurement (stereo-like with depth, monocular without).
    pub measurement: Measurement,
    /// Information weight of the keypoint's octave.
    pub inv_sigma2: f64,
    /// Keyframes that saw the map point.
    pub keyframes: u32,
    /// Frames in which tracking found the map point (an inlier of the frame's final pose).
    pub frames_found: u32,
}

/// The consensus found for a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Consensus {
    /// The pose (world to camera) that explains the most weight.
    pub tcw: Isometry3<f64>,
    /// Per match: inside the consensus.
    pub inlier: Vec<bool>,
    /// Its MSAC cost (weighted chi2 truncated at the gates).
    pub cost: f64,
    /// Whether the prior pose itself was the best hypothesis (a refit of it counts as the prior
    /// only when it costs exactly as much).
    pub prior_won: bool,
}

/// The chi2 of match `m` at pose `tcw`, `None` behind the camera.
fn chi2(camera: &Camera, tcw: &Isometry3<f64>, m: &ConsensusMatch) -> Option<f64> {
    let p = tcw * nalgebra::Point3::from(m.map_point);
    m.measurement
        .evaluate(camera, &p.coords)
        .map(|b| m.inv_sigma2 * b.residual.norm_squared())
}

/// Whether match `m` passes its chi2 gate at pose `tcw`.
fn agrees(camera: &Camera, tcw: &Isometry3<f64>, m: &ConsensusMatch) -> bool {
    chi2(camera, tcw, m).is_some_and(|c| c <= m.measurement.chi2_threshold())
}

fn weight(params: &RigidConsensusParams, m: &ConsensusMatch) -> f64 {
    let by_frames = m
        .frames_found
        .checked_div(params.frames_per_weight)
        .unwrap_or(0);
    m.keyframes.max(by_frames).clamp(1, params.weight_cap) as f64
}

/// MSAC cost of a hypothesis (Torr and Zisserman 2000): each match's chi2 truncated at its
/// gate, weighted. Lower is better. Counting inliers alone cannot tell the room's pose from
/// a pose that follows a near body and turns to keep the far room inside its gates (the
/// depth-parallax ambiguity); the truncated cost can, since the far room then sits at the edge
/// of its gates instead of at their centre.
///
/// Scoring stops as soon as the sum exceeds `bound` (the best cost so far: a hypothesis that
/// costs more loses whatever the rest adds); the value returned is then only known to exceed it.
fn cost(
    camera: &Camera,
    params: &RigidConsensusParams,
    tcw: &Isometry3<f64>,
    matches: &[ConsensusMatch],
    bound: f64,
) -> f64 {
    let mut sum = 0.0;
    for m in matches {
        let th = m.measurement.chi2_threshold();
        sum += weight(params, m) * chi2(camera, tcw, m).map_or(th, |c| c.min(th));
        if sum > bound {
            break;
        }
    }
    sum
}

/// Whether the inlier set `outer` holds most of `inner` (at least
/// [`RigidConsensusParams::nested_share`] of its weight) and adds matches as established as
/// those of `inner` (their mean weight at least [`RigidConsensusParams::nested_evidence`] of
/// `inner`'s): the two solutions then agree on the static world and `outer` explains more of it.
/// A pose dragged by a walker near the camera can hold the far room as well and add the
/// walker's young points; the room's own near points, as old as the rest, pass.
pub fn nested(
    params: &RigidConsensusParams,
    matches: &[ConsensusMatch],
    inner: &[bool],
    outer: &[bool],
) -> bool {
    let (mut w_inner, mut w_both, mut w_extra) = (0.0, 0.0, 0.0);
    let (mut n_inner, mut n_extra) = (0usize, 0usize);
    for ((m, &i), &o) in matches.iter().zip(inner).zip(outer) {
        let w = weight(params, m);
        if i {
            w_inner += w;
            n_inner += 1;
            if o {
                w_both += w;
            }
        } else if o {
            w_extra += w;
            n_extra += 1;
        }
    }
    n_inner > 0
        && w_both + w_extra > w_inner
        && w_both >= params.nested_share * w_inner
        && w_extra / n_extra.max(1) as f64 >= params.nested_evidence * w_inner / n_inner as f64
}

/// The rigid consensus of `matches` around the prior pose `prior_tcw` (world to camera), with
/// hypotheses drawn from `key`. `None` when too few matches have depth to judge.
pub fn rigid_consensus(
    camera: &Camera,
    params: &RigidConsensusParams,
    prior_tcw: &Isometry3<f64>,
    matches: &[ConsensusMatch],
    key: u64,
) -> Option<Consensus> {
    let depth: Vec<usize> = (0..matches.len())
        .filter(|&i| matches[i].point_camera.is_some())
        .collect();
    if depth.len() < params.min_depth_matches.max(3) {
        return None;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(key ^ 0x52C0_25E2_5000_0001);
    let prior_cost = cost(camera, params, prior_tcw, matches, f64::INFINITY);
    let mut best = (*prior_tcw, prior_cost, true);
    // Matches are drawn in proportion to their weight: long-seen points seed most hypotheses.
    let mut cumulative = Vec::with_capacity(depth.len());
    let mut total = 0.0;
    for &i in &depth {
        total += weight(params, &matches[i]);
        cumulative.push(total);
    }
    let draw = |rng: &mut ChaCha8Rng| {
        let x = rng.random_range(0.0..total);
        depth[cumulative.partition_point(|&c| c <= x).min(depth.len() - 1)]
    };
    for _ in 0..params.hypotheses {
        let a = draw(&mut rng);
        let b = draw(&mut rng);
        let c = draw(&mut rng);
        if a == b || b == c || a == c {
            continue;
        }
        let from = [
            matches[a].map_point,
            matches[b].map_point,
            matches[c].map_point,
        ];
        let to = [a, b, c].map(|i| matches[i].point_camera.expect("depth match"));
        // Spread-out triples only: three points within 5 cm fix no rotation.
        let spread = (to[0] - to[1])
            .norm()
            .min((to[1] - to[2]).norm())
            .min((to[0] - to[2]).norm());
        if spread < 0.05 {
            continue;
        }
        let Some(t) = absolute_orientation(&from, &to) else {
            continue;
        };
        let s = cost(camera, params, &t, matches, best.1);
        if s < best.1 {
            best = (t, s, false);
        }
    }
    // Refit on the consensus (its depth matches), keep it if it costs no more.
    let (from, to): (Vec<Vector3<f64>>, Vec<Vector3<f64>>) = depth
        .iter()
        .filter(|&&i| agrees(camera, &best.0, &matches[i]))
        .map(|&i| {
            (
                matches[i].map_point,
                matches[i].point_camera.expect("depth"),
            )
        })
        .unzip();
    if let Some(t) = absolute_orientation(&from, &to) {
        let s = cost(camera, params, &t, matches, best.1);
        if s <= best.1 {
            best = (t, s, best.2 && s == best.1);
        }
    }
    let (tcw, cost, prior_won) = best;
    Some(Consensus {
        tcw,
        inlier: matches.iter().map(|m| agrees(camera, &tcw, m)).collect(),
        cost,
        prior_won,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    /// A frame seeing `n_static` room points and `n_moving` points of a body that moved by
    /// `body_shift` (world) since the map saw it; the camera moved by `camera_shift` from
    /// the prior.
    fn frame(
        n_static: usize,
        n_moving: usize,
        body_shift: Vector3<f64>,
        moving_keyframes: u32,
    ) -> (Camera, Isometry3<f64>, Vec<ConsensusMatch>) {
        let camera = Camera::tum_fr3();
        let truth = Isometry3::from_parts(
            Translation3::new(0.05, -0.02, 0.1),
            UnitQuaternion::from_euler_angles(0.02, -0.05, 0.01),
        );
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut matches = Vec::new();
        for k in 0..n_static + n_moving {
            let moving = k >= n_static;
            // A body 1.2 m away in the middle of the view, the room 2.5-4 m away.
            let (u, v, z) = if moving {
                (
                    rng.random_range(250.0..390.0),
                    rng.random_range(100.0..400.0),
                    rng.random_range(1.1..1.4),
                )
            } else {
                (
                    rng.random_range(20.0..620.0),
                    rng.random_range(20.0..460.0),
                    rng.random_range(2.5..4.0),
                )
            };
            let pc = camera.unproject(u, v, z);
            let mut world = truth.inverse() * nalgebra::Point3::from(pc);
            if moving {
                // The map saw the body where it was before it moved.
                world -= body_shift;
            }
            let ur = u - camera.bf / z;
            matches.push(ConsensusMatch {
                map_point: world.coords,
                point_camera: Some(pc),
                measurement: Measurement::Stereo { u, v, ur },
                inv_sigma2: 1.0,
                keyframes: if moving { moving_keyframes } else { 6 },
                frames_found: 0,
            });
        }
        (camera, truth, matches)
    }

    #[test]
    fn the_room_wins_over_a_body_that_moved() {
        // 200 room points and 120 on a body 1.2 m away that walked 5 cm since the map saw it
        // (its map points one keyframe old, the room's six).
        let (camera, truth, matches) = frame(200, 120, Vector3::new(0.05, 0.0, 0.0), 1);
        let prior = Isometry3::translation(0.01, 0.0, -0.01) * truth;
        let p = RigidConsensusParams::default();
        let c = rigid_consensus(&camera, &p, &prior, &matches, 9).unwrap();
        let err = (c.tcw.translation.vector - truth.translation.vector).norm();
        assert!(err < 0.002, "{err}");
        assert!(c.inlier[..200].iter().filter(|&&i| i).count() >= 195);
        assert_eq!(c.inlier[200..].iter().filter(|&&i| i).count(), 0);
        assert!(!c.prior_won);
        // Body and room with as long a history: the room, by its share of the matches and by
        // how well it fits (MSAC: a pose that follows the body keeps the far room only at the
        // edge of its gates).
        let room_wins = |n_room: usize, n_body: usize, body_keyframes: u32| {
            let (_, _, matches) =
                frame(n_room, n_body, Vector3::new(0.05, 0.0, 0.0), body_keyframes);
            let c = rigid_consensus(&camera, &p, &prior, &matches, 9).unwrap();
            let room = c.inlier[..n_room].iter().filter(|&&i| i).count();
            let body = c.inlier[n_room..].iter().filter(|&&i| i).count();
            room == n_room && body == 0
        };
        assert!(room_wins(200, 120, 6));
        // A body with three times the room's points and as long a history wins: the consensus
        // is a vote, and the weights of time are what protect the room then.
        assert!(!room_wins(100, 300, 6));
        assert!(room_wins(100, 300, 1));
    }

    #[test]
    fn a_static_frame_keeps_every_match_and_too_few_depths_give_no_gate() {
        let (camera, truth, matches) = frame(200, 0, Vector3::zeros(), 1);
        let c = rigid_consensus(
            &camera,
            &RigidConsensusParams::default(),
            &truth,
            &matches,
            1,
        )
        .unwrap();
        assert_eq!(c.inlier.iter().filter(|&&i| i).count(), 200);
        assert!(rigid_consensus(
            &camera,
            &RigidConsensusParams::default(),
            &truth,
            &matches[..5],
            1
        )
        .is_none());
        // Deterministic: the same key gives the same consensus.
        let prior = Isometry3::translation(0.02, 0.01, 0.0) * truth;
        let p = RigidConsensusParams::default();
        assert_eq!(
            rigid_consensus(&camera, &p, &prior, &matches, 4),
            rigid_consensus(&camera, &p, &prior, &matches, 4)
        );
    }

    #[test]
    fn frames_found_weigh_like_keyframes_from_the_first_second() {
        // A young map: room and body both seen by one keyframe, the body with twice the room's
        // matches. Counted by keyframes alone the body wins the vote; the room's points were
        // found in 40 frames (a body point moves out of its gate within a few), and win.
        let p = RigidConsensusParams::default();
        let (camera, truth, mut matches) = frame(100, 200, Vector3::new(0.05, 0.0, 0.0), 1);
        for m in &mut matches {
            m.keyframes = 1;
        }
        let prior = Isometry3::translation(0.01, 0.0, -0.01) * truth;
        let room = |c: &Consensus| c.inlier[..100].iter().filter(|&&i| i).count();
        let c = rigid_consensus(&camera, &p, &prior, &matches, 9).unwrap();
        assert!(room(&c) < 50, "{}", room(&c));
        for m in &mut matches[..100] {
            m.frames_found = 40;
        }
        for m in &mut matches[100..] {
            m.frames_found = 3;
        }
        let c = rigid_consensus(&camera, &p, &prior, &matches, 9).unwrap();
        assert_eq!(room(&c), 100);
        // frames_per_weight 0: keyframes only, as before.
        let keyframes_only = RigidConsensusParams {
            frames_per_weight: 0,
            ..p
        };
        let c = rigid_consensus(&camera, &keyframes_only, &prior, &matches, 9).unwrap();
        assert!(room(&c) < 50);
    }

    #[test]
    fn a_nested_solution_must_hold_the_consensus_and_add_established_matches() {
        let p = RigidConsensusParams::default();
        // 100 matches: 0..60 old (4 keyframes), 60..100 young (1 keyframe).
        let (_, _, mut matches) = frame(100, 0, Vector3::zeros(), 1);
        for (k, m) in matches.iter_mut().enumerate() {
            m.keyframes = if k < 60 { 4 } else { 1 };
        }
        let set = |r: std::ops::Range<usize>| (0..100).map(|k| r.contains(&k)).collect::<Vec<_>>();
        let inner = set(0..40);
        // Holds the consensus and adds old matches (the room's near points): nested.
        assert!(nested(&p, &matches, &inner, &set(0..60)));
        // Adds young matches only (a walker's): not nested.
        let mut young = set(0..40);
        young[60..100].iter_mut().for_each(|b| *b = true);
        assert!(!nested(&p, &matches, &inner, &young));
        // Loses a quarter of the consensus: not nested, whatever it adds; less than a tenth it may.
        assert!(!nested(&p, &matches, &inner, &set(10..60)));
        assert!(nested(&p, &matches, &inner, &set(3..60)));
        // Adds nothing: not nested (the consensus solution stays).
        assert!(!nested(&p, &matches, &inner, &inner));
    }
}
