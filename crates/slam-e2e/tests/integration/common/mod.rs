//! Shared helpers of the end-to-end tests: run the system over a synthetic sequence and score
//! its trajectory (SE3 Umeyama alignment on frame-index correspondences, ATE RMSE).

#![allow(dead_code)]

use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Vector3};
use slam_core::solve::absolute_orientation;
use slam_core::system::{Config, System, TrackingState};
use slam_core::FrameInput;
use synth::{Generator, SynthConfig};

/// What a run produced.
pub struct Run {
    /// Estimated T_world_camera per tracked frame, with its frame index.
    pub estimate: Vec<(usize, Isometry3<f64>)>,
    /// Ground-truth T_world_camera per frame.
    pub truth: Vec<Isometry3<f64>>,
    /// Tracking state per frame.
    pub states: Vec<TrackingState>,
    /// Keyframes at the end.
    pub keyframes: usize,
    /// The raw trajectory (timestamp, pose), for bit-identity checks.
    pub trajectory: Vec<(f64, Isometry3<f64>)>,
}

/// Rendered frames of a synthetic sequence with their true poses, to track once or many times.
pub struct Rendered {
    /// The camera.
    pub camera: slam_core::Camera,
    /// The frames, in order.
    pub frames: Vec<FrameInput>,
    /// Ground-truth T_world_camera per frame.
    pub truth: Vec<Isometry3<f64>>,
}

/// Renders `n` frames of `synth_cfg` with `seed`, on as many threads as there are cores (each
/// frame is a pure function of the configuration, seed and index, so the bytes do not depend on
/// the split).
///
/// The frames go through the frame cache the workspace's test processes share
/// (`target/tmp/synth-frames`, [`synth::CachedFrames`]): the same bits as rendering them, each
/// rendered once however many suites use it.
pub fn render(synth_cfg: SynthConfig, seed: u64, n: usize) -> Rendered {
    let gen = Generator::new(synth_cfg, seed);
    let camera = gen.camera();
    let cache = std::path::Path::new(concat!(env!("CARGO_TARGET_TMPDIR"), "/synth-frames"));
    let gen = synth::CachedFrames::new(gen, Some(cache));
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get());
    let chunk = n.div_ceil(threads).max(1);
    let rendered: Vec<(FrameInput, Isometry3<f64>)> = std::thread::scope(|s| {
        let gen = &gen;
        let handles: Vec<_> = (0..n)
            .step_by(chunk)
            .map(|start| {
                s.spawn(move || {
                    (start..(start + chunk).min(n))
                        .map(|i| gen.input(i))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("render thread"))
            .collect()
    });
    let (frames, truth) = rendered.into_iter().unzip();
    Rendered {
        camera,
        frames,
        truth,
    }
}

/// Renders `n` frames of `synth_cfg` with `seed` and tracks them.
pub fn run(synth_cfg: SynthConfig, seed: u64, n: usize, config: Config) -> Run {
    track(&render(synth_cfg, seed, n), config)
}

/// Tracks rendered frames with `config`.
pub fn track(rendered: &Rendered, config: Config) -> Run {
    let mut system = System::new(rendered.camera.clone(), config);
    let truth = rendered.truth.clone();
    let mut states = Vec::new();
    let mut stamps = Vec::new();
    for (i, input) in rendered.frames.iter().enumerate() {
        let r = system.track(input);
        if std::env::var_os("NF_VERBOSE").is_some() {
            let s = &r.stats;
            eprintln!(
                "{i:4} {:?} kp {} m {} in {} trk {} kf {} ({}/{}) reloc {} t {:.1}/{:.1}/{:.1}/{:.1}",
                s.state, s.n_keypoints, s.n_matches, s.n_inliers, s.n_tracked_map_points,
                s.keyframe_inserted, s.n_keyframes, s.n_map_points, s.relocalized,
                s.time_features_ms, s.time_tracking_ms, s.time_mapping_ms, s.time_ba_ms
            );
        }
        states.push(r.state);
        stamps.push(input.timestamp);
    }
    let trajectory = system.trajectory();
    let estimate = trajectory
        .iter()
        .map(|(t, p)| {
            let i = stamps
                .iter()
                .position(|s| s == t)
                .expect("stamp of an input frame");
            (i, *p)
        })
        .collect();
    Run {
        estimate,
        truth,
        states,
        keyframes: system.keyframe_count(),
        trajectory,
    }
}

/// Position error (metres) of each estimated position after the SE3 alignment of all of them
/// to their true positions (`estimate[k]` pairs with `truth[k]`).
pub fn aligned_errors(estimate: &[Vector3<f64>], truth: &[Vector3<f64>]) -> Vec<f64> {
    let t = absolute_orientation(estimate, truth).expect("enough poses");
    estimate
        .iter()
        .zip(truth)
        .map(|(e, g)| (t.transform_point(&Point3::from(*e)).coords - g).norm())
        .collect()
}

/// ATE RMSE (metres) of the tracked frames after SE3 alignment to the truth.
pub fn ate_rmse(run: &Run) -> f64 {
    let est: Vec<Vector3<f64>> = run
        .estimate
        .iter()
        .map(|(_, p)| p.translation.vector)
        .collect();
    let gt: Vec<Vector3<f64>> = run
        .estimate
        .iter()
        .map(|(i, _)| run.truth[*i].translation.vector)
        .collect();
    let errors = aligned_errors(&est, &gt);
    (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt()
}

/// Number of frames whose state is tracked.
pub fn tracked(run: &Run) -> usize {
    run.states.iter().filter(|s| s.is_tracked()).count()
}

/// The vocabulary shipped in assets/ (the one the binary compiles in).
pub fn shipped_vocabulary() -> Arc<slam_core::place::Vocabulary> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../assets/vocabulary/noisefree-k10L5.voc"
    );
    let bytes = std::fs::read(path).expect("the shipped vocabulary");
    Arc::new(slam_core::place::Vocabulary::from_binary(&bytes).expect("valid vocabulary"))
}
