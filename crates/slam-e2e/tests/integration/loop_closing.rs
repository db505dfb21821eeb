//! Loop closing. Verification: a revisit of a mapped place (the same image, seen from a drifted
//! estimate) verifies and gets the place's pose back, while a larger replica of the place (the
//! same image with every depth scaled: a perceptual alias that no BoW score can tell apart)
//! does not.

use crate::common;

use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use slam_core::camera::Camera;
use slam_core::data::{Features, KeyFrameId, Map, ScaleLevels};
use slam_core::module::loop_closing::{verify_loop, LoopClosingParams, LoopContext};
use slam_core::optimize::PoseOptConfig;
use slam_core::place::{PlaceRecognition, Vocabulary};

use common::shipped_vocabulary;
use slam_core::system::{Config, System};

/// A map of a camera turning on the spot for a few seconds (no revisit): the first 120 frames
/// of the place-recognition suite's turn (seed 5, 1.5 times the spin's speed, about 110
/// degrees), so the shared frame cache renders them once.
fn mapped(vocabulary: &Arc<Vocabulary>) -> System {
    let mut cfg = synth::Preset::Kinect.config();
    cfg.trajectory = synth::Trajectory::Spin;
    cfg.motion_scale = 1.5;
    let rendered = common::render(cfg, 5, 120);
    let mut system = System::with_vocabulary(
        rendered.camera.clone(),
        Config::default(),
        vocabulary.clone(),
    );
    for f in &rendered.frames {
        system.track(f);
    }
    system
}

/// Adds to `map` a keyframe with the image (keypoints, descriptors, words) of keyframe `of`,
/// placed at `pose`, with its own map points from its depths times `depth_scale`: the same
/// picture of a place whose geometry is that of `of` (scale 1) or a larger replica of it.
fn replica(
    map: &mut Map,
    of: KeyFrameId,
    pose: Isometry3<f64>,
    depth_scale: f32,
    camera: &Camera,
) -> KeyFrameId {
    let k = map.keyframe(of).expect("good").clone();
    let f = &k.features;
    let depth: Vec<f32> = f
        .depth
        .iter()
        .map(|&z| if z > 0.0 { z * depth_scale } else { z })
        .collect();
    let u_right = f
        .keypoints
        .iter()
        .zip(&depth)
        .map(|(kp, &z)| {
            if z > 0.0 {
                kp.x - (camera.bf / z as f64) as f32
            } else {
                -1.0
            }
        })
        .collect();
    let features = Arc::new(Features::new(
        f.keypoints.clone(),
        f.descriptors.clone(),
        depth,
        u_right,
        camera,
    ));
    let dup = map.create_keyframe(10_000, k.timestamp + 100.0, pose, features.clone());
    map.keyframe_mut(dup).expect("new").bow = k.bow.clone();
    let twc = pose.inverse();
    for i in 0..features.len() {
        if let Some(pc) = features.unproject_camera(i, camera) {
            let pw = (twc * Point3::from(pc)).coords;
            let mp = map.create_map_point(pw, features.descriptors[i], dup);
            map.add_observation(mp, dup, i);
        }
    }
    dup
}

#[test]
fn verification_accepts_a_revisit_and_rejects_a_larger_replica_of_the_place() {
    let vocabulary = shipped_vocabulary();
    let system = mapped(&vocabulary);
    let camera = system.camera().clone();
    let place = PlaceRecognition::new(vocabulary);
    let levels = ScaleLevels::new(8, 1.2);
    let params = LoopClosingParams::default();
    let pose_cfg = PoseOptConfig::default();
    let ctx = LoopContext {
        camera: &camera,
        levels: &levels,
        params: &params,
        pose_cfg: &pose_cfg,
        place: &place,
    };
    // The keyframe with most map points stands for the place seen before.
    let of = system
        .map()
        .keyframes()
        .max_by_key(|k| {
            (
                k.map_points.iter().flatten().count(),
                std::cmp::Reverse(k.id),
            )
        })
        .expect("keyframes")
        .id;
    let truth = system.map().keyframe(of).expect("good").tcw;
    // Drift: the revisit's own estimate is 0.6 m and 15 degrees away.
    let drifted = Isometry3::from_parts(
        Translation3::new(0.4, -0.2, 0.4),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 15f64.to_radians()),
    ) * truth;
    let mut rng = ChaCha8Rng::seed_from_u64(0);

    let mut map = system.map().clone();
    let revisit = replica(&mut map, of, drifted, 1.0, &camera);
    let found = verify_loop(revisit, &[of], &map, &ctx, &mut rng).expect("the revisit verifies");
    let centre = |t: &Isometry3<f64>| t.inverse().translation.vector;
    let err = (centre(&found.tcw) - centre(&truth)).norm();
    assert!(err < 0.01, "loop pose {err} m from the place's pose");
    assert!(found.matched.iter().flatten().count() >= params.min_total_matches);

    for scale in [1.5f32, 2.0] {
        let mut map = system.map().clone();
        let alias = replica(&mut map, of, drifted, scale, &camera);
        let verdict = verify_loop(alias, &[of], &map, &ctx, &mut rng);
        assert!(
            verdict.is_none(),
            "a {scale}x replica of the place was taken for it ({} matches)",
            verdict.map_or(0, |m| m.matched.iter().flatten().count())
        );
    }
}

/// Largest per-frame position error (metres) of a run after SE3 alignment, with its frame.
fn worst_frame(trajectory: &[(f64, Isometry3<f64>)], truth: &[Isometry3<f64>]) -> (f64, usize) {
    let est: Vec<Vector3<f64>> = trajectory
        .iter()
        .map(|(_, p)| p.translation.vector)
        .collect();
    let gt: Vec<Vector3<f64>> = truth.iter().map(|p| p.translation.vector).collect();
    common::aligned_errors(&est, &gt)
        .into_iter()
        .enumerate()
        .fold(
            (0.0, 0),
            |(w, wi), (i, e)| if e > w { (e, i) } else { (w, wi) },
        )
}

/// A seed, its number of loops, its trajectory and the frame its first loop closed at.
type LaggedRun = (u64, usize, Vec<(f64, Isometry3<f64>)>, Option<usize>);

/// Under `--mapping-lag` the loop correction and the global BA land while later frames are
/// tracked; each frame must move with its reference keyframe, or the frame of the merge keeps
/// its pose in the uncorrected map and the next ones track from there (before the fix: 41-184 mm
/// off the truth at single frames of the turn at twice the spin's speed; after: 13-27 mm at
/// worst, the drift of the turn before its loop closes). The sequence is the regression suite's
/// `distorted-spin-x3`: a turn in 200 frames, the loop closing at frames 245-260 of 300, every
/// frame within 19-25 mm when written.
#[test]
fn a_loop_closed_under_mapping_lag_keeps_every_frame_on_the_trajectory() {
    let mut cfg = synth::Preset::Distorted.config();
    cfg.trajectory = synth::Trajectory::Spin;
    cfg.motion_scale *= 3.0;
    let rendered = common::render(cfg, 0, 300);
    let vocabulary = shipped_vocabulary();
    let runs: Vec<LaggedRun> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..3)
            .map(|seed| {
                let (rendered, vocabulary) = (&rendered, vocabulary.clone());
                s.spawn(move || {
                    let config = Config {
                        seed,
                        mapping_lag: 3,
                        ..Config::default()
                    };
                    let mut system =
                        System::with_vocabulary(rendered.camera.clone(), config, vocabulary);
                    let mut closed_at = None;
                    for (i, f) in rendered.frames.iter().enumerate() {
                        if system.track(f).stats.loop_closed {
                            closed_at.get_or_insert(i);
                        }
                    }
                    (seed, system.loops().len(), system.trajectory(), closed_at)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("run"))
            .collect()
    });
    for (seed, loops, trajectory, closed_at) in runs {
        assert_eq!(trajectory.len(), rendered.frames.len());
        assert_eq!(loops, 1, "seed {seed}: the turn closes once");
        let (worst, at) = worst_frame(&trajectory, &rendered.truth);
        eprintln!(
            "seed {seed}: loop closed at frame {closed_at:?}, worst frame {at}, {:.1} mm",
            worst * 1e3
        );
        assert!(
            worst < 0.035,
            "seed {seed}: frame {at} is {:.1} mm off",
            worst * 1e3
        );
    }
}
