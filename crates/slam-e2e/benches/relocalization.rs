//! Relocalization against a map of 1000 keyframes: candidates from the keyframe database with
//! BoW-guided matching (ORB-SLAM2's way, the default with a vocabulary) against the brute-force
//! stand-in (every keyframe scored by descriptor matching), for a frame whose place is in the map.
//!
//! The map: 1000 frames of a camera turning on the spot (1.7 turns), each made a keyframe with a
//! map point for every keypoint with depth (placed with the true pose). Setup renders the frames
//! (about a minute); run with `cargo bench -p slam-e2e --bench relocalization`.

use std::sync::Arc;

use criterion::{criterion_group, criterion_main, Criterion};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use slam_core::data::{Features, KeyFrameId, Map, ScaleLevels, TrackedFrame};
use slam_core::feature::{OrbConfig, OrbExtractor};
use slam_core::frame::Frame;
use slam_core::module::pose_estimation::NoiseHooks;
use slam_core::module::relocalization::{relocalize, RelocalizationContext, RelocalizationParams};
use slam_core::optimize::PoseOptConfig;
use slam_core::place::{PlaceRecognition, Vocabulary};
use synth::{Generator, Preset, Trajectory};

const KEYFRAMES: usize = 1000;

fn features_of(gen: &Generator, i: usize, orb: &OrbConfig) -> Features {
    let camera = gen.camera();
    let input = gen.frame(i).into_input();
    let mut ex = OrbExtractor::new(orb.clone());
    let fr = Frame::new(i as u64, &input, &camera, &mut ex);
    Features::new(fr.keypoints, fr.descriptors, fr.depth, fr.u_right, &camera)
}

fn relocalization(c: &mut Criterion) {
    let bytes = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../assets/vocabulary/noisefree-k10L5.voc"
    ))
    .expect("the shipped vocabulary");
    let voc = Arc::new(Vocabulary::from_binary(&bytes).expect("valid vocabulary"));
    let mut cfg = Preset::Kinect.config();
    cfg.trajectory = Trajectory::Spin;
    let gen = Generator::new(cfg, 8);
    let camera = gen.camera();
    let orb = OrbConfig::default();
    let all: Vec<Features> = (0..=KEYFRAMES)
        .into_par_iter()
        .map(|i| features_of(&gen, i, &orb))
        .collect();
    let mut map = Map::new();
    let mut place = PlaceRecognition::new(voc);
    for (i, f) in all.iter().take(KEYFRAMES).enumerate() {
        let tcw = gen.pose(i).inverse();
        let f = Arc::new(f.clone());
        let kf = map.create_keyframe(i as u64, i as f64, tcw, f.clone());
        for k in 0..f.len() {
            if let Some(pc) = f.unproject_camera(k, &camera) {
                let mp = map.create_map_point(tcw.inverse() * pc, f.descriptors[k], kf);
                map.add_observation(mp, kf, k);
            }
        }
        let fb = place.frame_bow(&f.descriptors);
        place.database.add(kf, &fb.bow);
        map.keyframe_mut(kf).expect("new keyframe").bow = Some(fb);
    }
    for kf in map.keyframe_ids() {
        map.update_connections(kf);
    }
    // The query: a new frame between two keyframes' views (frame 1000 = 1.67 turns, a place
    // the map saw at frame 400 as well).
    let query = Arc::new(all[KEYFRAMES].clone());
    let levels = ScaleLevels::new(orb.n_levels, orb.scale_factor);
    let params = RelocalizationParams::default();
    let pose_cfg = PoseOptConfig::default();
    let attempt = |place: Option<&PlaceRecognition>| {
        let ctx = RelocalizationContext {
            camera: &camera,
            levels: &levels,
            params: &params,
            pose_cfg: &pose_cfg,
            hooks: NoiseHooks {
                mcor: None,
                avc: None,
                rc: None,
                clusters: None,
            },
            place,
        };
        let mut frame = TrackedFrame::new(KEYFRAMES as u64, 1e4, query.clone());
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        relocalize(&mut frame, &map, &ctx, &mut rng)
    };
    let found = |kf: Option<KeyFrameId>| kf.map(|k| k.0);
    eprintln!(
        "relocalized against keyframe {:?} (database + BoW) / {:?} (brute force)",
        found(attempt(Some(&place))),
        found(attempt(None))
    );
    let mut g = c.benchmark_group("relocalization, 1000 keyframes");
    g.sample_size(10);
    g.bench_function("database + BoW matching", |b| {
        b.iter(|| attempt(Some(&place)))
    });
    g.bench_function("brute force", |b| b.iter(|| attempt(None)));
    g.finish();
}

criterion_group!(benches, relocalization);
criterion_main!(benches);
