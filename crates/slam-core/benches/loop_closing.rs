//! Loop closing on a map of 300 keyframes: detection per keyframe (database query, covisibility
//! groups, consistency), the closing keyframe's verification + correction, the essential-graph
//! optimization alone, and a global bundle adjustment over the whole map.
//!
//! The map: 900 rendered frames of a camera turning on the spot 1.5 times (`kinect` preset,
//! `spin` trajectory), every third frame a keyframe. Map points come from the keyframes' depth;
//! a keypoint that matches (by projection within 3 px and Hamming distance < 50) a point of the
//! previous ten keyframes observes it instead, so the covisibility graph and the spanning tree
//! are those of a real map. The poses carry a drift growing with the keyframe index (0.012 deg
//! of yaw and 0.4 mm per keyframe), so at the revisit (second half turn) the map is 2.4 deg and
//! 8 cm off where it began, and there is a loop to find and close. Setup renders the frames
//! (about a minute); run with `cargo bench -p slam-core --bench loop_closing`.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use slam_core::data::{Features, KeyFrameId, Map, MapPointId, ScaleLevels};
use slam_core::feature::{hamming, OrbConfig, OrbExtractor};
use slam_core::frame::Frame;
use slam_core::module::essential_graph::{optimize_essential_graph, LoopCorrection};
use slam_core::module::global_ba::global_bundle_adjustment;
use slam_core::module::loop_closing::{LoopCloser, LoopClosingParams, LoopContext};
use slam_core::module::pose_estimation::NoiseHooks;
use slam_core::optimize::PoseOptConfig;
use slam_core::place::{PlaceRecognition, Vocabulary};
use slam_core::{Camera, FrameInput};
use synth::{Generator, Preset, Trajectory};

const FRAMES: usize = 900;
const EVERY: usize = 3;
const WINDOW: usize = 10;

fn features_of(gen: &Generator, i: usize, orb: &OrbConfig) -> Features {
    let f = gen.frame(i);
    let camera = gen.camera();
    let input = FrameInput {
        timestamp: f.timestamp,
        image: Arc::new(f.gray),
        depth: f.depth.map(Arc::new),
        right: f.right.map(Arc::new),
    };
    let mut ex = OrbExtractor::new(orb.clone());
    let fr = Frame::new(i as u64, &input, &camera, &mut ex);
    Features::new(fr.keypoints, fr.descriptors, fr.depth, fr.u_right, &camera)
}

/// Camera-to-world drift after `k` keyframes: a yaw about the vertical and a sideways offset.
fn drift(k: usize) -> Isometry3<f64> {
    let k = k as f64;
    Isometry3::from_parts(
        Translation3::new(0.0004 * k, 0.0, 0.0),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), (0.012 * k).to_radians()),
    )
}

struct Scene {
    camera: Camera,
    levels: ScaleLevels,
    map: Map,
    place: PlaceRecognition,
}

fn build() -> Scene {
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
    let levels = ScaleLevels::new(orb.n_levels, orb.scale_factor);
    let frames: Vec<usize> = (0..FRAMES).step_by(EVERY).collect();
    let all: Vec<Features> = frames
        .par_iter()
        .map(|&i| features_of(&gen, i, &orb))
        .collect();
    let mut map = Map::new();
    let mut place = PlaceRecognition::new(voc);
    let mut recent: Vec<(KeyFrameId, Vec<MapPointId>)> = Vec::new();
    for (k, (&i, f)) in frames.iter().zip(&all).enumerate() {
        let true_tcw = gen.pose(i).inverse();
        let tcw = (drift(k) * gen.pose(i)).inverse();
        let f = Arc::new(f.clone());
        let kf = map.create_keyframe(i as u64, i as f64, tcw, f.clone());
        let mut taken = vec![false; f.len()];
        let mut seen: BTreeSet<MapPointId> = BTreeSet::new();
        for (_, points) in recent.iter().rev() {
            for &mp in points {
                let Some(m) = map.map_point(mp) else {
                    continue;
                };
                if !seen.insert(mp) {
                    continue;
                }
                // Data association with the true pose (the map point's drift is that of its
                // keyframe, a few keyframes back).
                let pc = true_tcw * drift(k).inverse() * nalgebra::Point3::from(m.position);
                if pc.z < 0.1 {
                    continue;
                }
                let uv = camera.project(&pc.coords);
                let best = f
                    .features_in_area(uv.x, uv.y, 3.0, 0, -1)
                    .into_iter()
                    .filter(|&j| !taken[j])
                    .map(|j| (hamming(&f.descriptors[j], &m.descriptor), j))
                    .min();
                if let Some((d, j)) = best {
                    if d < 50 {
                        taken[j] = true;
                        map.add_observation(mp, kf, j);
                    }
                }
            }
        }
        let mut created = Vec::new();
        for (j, _) in taken.iter().enumerate().filter(|(_, &t)| !t) {
            if let Some(pc) = f.unproject_camera(j, &camera) {
                let mp = map.create_map_point(tcw.inverse() * pc, f.descriptors[j], kf);
                map.add_observation(mp, kf, j);
                created.push(mp);
            }
        }
        let fb = place.frame_bow(&f.descriptors);
        place.database.add(kf, &fb.bow);
        map.keyframe_mut(kf).expect("new keyframe").bow = Some(fb);
        map.update_connections(kf);
        recent.push((kf, created));
        if recent.len() > WINDOW {
            recent.remove(0);
        }
    }
    let ids: Vec<MapPointId> = map.map_points().map(|m| m.id).collect();
    for mp in ids {
        map.compute_distinctive_descriptor(mp);
        map.update_normal_and_depth(mp, &levels);
    }
    Scene {
        camera,
        levels,
        map,
        place,
    }
}

fn loop_closing(c: &mut Criterion) {
    let t = Instant::now();
    let scene = build();
    let observations: usize = scene.map.map_points().map(|m| m.observations.len()).sum();
    eprintln!(
        "map: {} keyframes, {} map points, {} observations (built in {:.0} s)",
        scene.map.keyframe_count(),
        scene.map.map_point_count(),
        observations,
        t.elapsed().as_secs_f64()
    );
    let params = LoopClosingParams::default();
    let pose_cfg = PoseOptConfig::default();
    let ctx = LoopContext {
        camera: &scene.camera,
        levels: &scene.levels,
        params: &params,
        pose_cfg: &pose_cfg,
        place: &scene.place,
    };
    // One pass over the keyframes in order, as the system runs loop closing after each mapped
    // keyframe: the time per keyframe, and the state just before the loop closes.
    let ids = scene.map.keyframe_ids();
    let mut map = scene.map.clone();
    let mut closer = LoopCloser::default();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let mut before_closing = None;
    let mut detect_ms = Vec::new();
    for &kf in &ids {
        let (m0, c0) = (map.clone(), closer.clone());
        let t = Instant::now();
        let report = closer.process(kf, &mut map, &ctx, &mut rng);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        if let Some(event) = report.closed {
            eprintln!(
                "loop closed at keyframe {} (frame {}) with keyframe {} (frame {}): {} matches, \
                 corrected by {:.3} m / {:.2} deg, {ms:.1} ms",
                kf.0,
                map.keyframe(kf).map_or(0, |k| k.frame_id),
                event.loop_kf.0,
                map.keyframe(event.loop_kf).map_or(0, |k| k.frame_id),
                event.matches,
                event.correction_m,
                event.correction_deg
            );
            if before_closing.is_none() {
                before_closing = Some((kf, m0, c0));
            }
        } else {
            detect_ms.push(ms);
        }
    }
    detect_ms.sort_by(f64::total_cmp);
    eprintln!(
        "detection without a closure, per keyframe: mean {:.3} ms, median {:.3} ms, max {:.3} ms \
         over {} keyframes",
        detect_ms.iter().sum::<f64>() / detect_ms.len().max(1) as f64,
        detect_ms.get(detect_ms.len() / 2).copied().unwrap_or(0.0),
        detect_ms.last().copied().unwrap_or(0.0),
        detect_ms.len()
    );

    let mut g = c.benchmark_group("loop closing, 300 keyframes");
    g.sample_size(10);
    // Detection for the last keyframe with a fresh closer (no consistent groups yet): database
    // query, minimum score from the covisibles, groups; nothing to verify.
    let last = *ids.last().expect("keyframes");
    g.bench_function("detection (last keyframe, revisit)", |b| {
        b.iter_batched(
            || (scene.map.clone(), LoopCloser::default()),
            |(mut m, mut cl)| cl.process(last, &mut m, &ctx, &mut rng),
            BatchSize::LargeInput,
        )
    });
    if let Some((kf, m0, c0)) = before_closing {
        g.bench_function(
            "closing keyframe: detection + verification + correction",
            |b| {
                b.iter_batched(
                    || (m0.clone(), c0.clone(), ChaCha8Rng::seed_from_u64(0)),
                    |(mut m, mut cl, mut r)| cl.process(kf, &mut m, &ctx, &mut r),
                    BatchSize::LargeInput,
                )
            },
        );
    } else {
        eprintln!("no loop closed on this map: the closing benchmark is skipped");
    }
    // The essential graph alone: the last keyframe and its covisibles moved onto the loop's
    // (undrifted) frame, linked to the first keyframes of the revisited place.
    let n = ids.len();
    let loop_kf = ids[n - 1 - (600 / EVERY)];
    let current = ids[n - 1];
    let correction_for = |map: &mut Map| {
        let shift = drift(n - 1).inverse() * drift(n - 1 - 600 / EVERY);
        let mut c = LoopCorrection {
            current,
            loop_kf,
            non_corrected: BTreeMap::new(),
            loop_connections: BTreeMap::new(),
            corrected_by: BTreeMap::new(),
        };
        let mut group = map.keyframe(current).expect("kf").covisibles();
        group.push(current);
        for k in group {
            let kfm = map.keyframe_mut(k).expect("kf");
            c.non_corrected.insert(k, kfm.tcw);
            kfm.tcw = (shift.inverse() * kfm.tcw.inverse()).inverse();
        }
        let mut linked: BTreeSet<KeyFrameId> = map
            .keyframe(loop_kf)
            .expect("kf")
            .covisibles()
            .into_iter()
            .collect();
        linked.insert(loop_kf);
        c.loop_connections.insert(current, linked);
        c
    };
    {
        let mut m = scene.map.clone();
        let corr = correction_for(&mut m);
        let t = Instant::now();
        let report = optimize_essential_graph(&mut m, &corr, 100, 20, &scene.levels);
        eprintln!(
            "essential graph: {:?} in {:.1} ms",
            report,
            t.elapsed().as_secs_f64() * 1e3
        );
    }
    g.bench_function("essential graph (20 iterations)", |b| {
        b.iter_batched(
            || {
                let mut m = scene.map.clone();
                let corr = correction_for(&mut m);
                (m, corr)
            },
            |(mut m, corr)| optimize_essential_graph(&mut m, &corr, 100, 20, &scene.levels),
            BatchSize::LargeInput,
        )
    });
    let hooks = NoiseHooks {
        mcor: None,
        avc: None,
    };
    g.bench_function("global BA (10 iterations)", |b| {
        b.iter(|| global_bundle_adjustment(&scene.map, &scene.camera, &scene.levels, &hooks, 10))
    });
    g.finish();
}

criterion_group!(benches, loop_closing);
criterion_main!(benches);
