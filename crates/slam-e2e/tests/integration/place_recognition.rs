//! Place recognition in the running system. A camera turning on the spot is "kidnapped" back to
//! a view it saw seconds before (the sequence cuts from frame 200, half a turn, back to
//! frame 30): tracking is lost at the cut, and relocalization must find the keyframes of
//! that earlier view through the keyframe database and BoW-guided matching, on the first frame
//! after the cut, and put the camera where it really is. And BoW-guided matching finds most of
//! what brute-force matching finds between a keyframe and a later frame.

use crate::common;

use nalgebra::{Point3, Vector3};
use slam_core::data::Features;
use slam_core::feature::OrbExtractor;
use slam_core::frame::Frame;
use slam_core::matching::bow::search_by_bow;
use slam_core::matching::brute::search_keyframe_frame;
use slam_core::place::PlaceRecognition;
use slam_core::solve::absolute_orientation;
use slam_core::system::{Config, System, TrackingState};
use slam_core::FrameInput;
use synth::{Generator, Preset, Trajectory};

use common::shipped_vocabulary;

#[test]
fn kidnapped_camera_relocalizes_at_once_to_the_right_place() {
    let mut cfg = Preset::Kinect.config();
    cfg.trajectory = Trajectory::Spin;
    cfg.motion_scale = 1.5;
    const CUT: usize = 200;
    let gen = Generator::new(cfg.clone(), 5);
    let rendered = common::render(cfg, 5, CUT);
    // Frames 0..200 (11 keyframes when written), then frames 30..70 again with later stamps.
    let order: Vec<usize> = (0..CUT).chain(30..70).collect();
    let mut system = System::with_vocabulary(
        rendered.camera.clone(),
        Config::default(),
        shipped_vocabulary(),
    );
    let mut states = Vec::new();
    let mut truth = Vec::new();
    let mut estimate = Vec::new();
    for (k, &i) in order.iter().enumerate() {
        let input = FrameInput {
            timestamp: gen.timestamp(k),
            ..rendered.frames[i].clone()
        };
        let r = system.track(&input);
        states.push(r.state);
        truth.push(rendered.truth[i].translation.vector);
        estimate.push(r.tcw.map(|t| t.inverse().translation.vector));
    }
    let keyframes_before_cut = system.frame_stats()[CUT - 1].n_keyframes;
    let reloc = states
        .iter()
        .position(|s| *s == TrackingState::Relocalized)
        .expect("relocalized");
    eprintln!(
        "{keyframes_before_cut} keyframes before the cut; states around it: {:?}; relocalized at {reloc}",
        &states[CUT - 1..CUT + 3]
    );
    assert!(
        keyframes_before_cut >= 10,
        "{keyframes_before_cut} keyframes"
    );
    assert!(states[..CUT].iter().all(|s| s.is_tracked()));
    assert!((CUT..=CUT + 1).contains(&reloc), "relocalized at {reloc}");
    assert!(states[reloc..].iter().all(|s| s.is_tracked()));
    // Align the estimate to the truth on the frames before the cut, then check where the
    // relocalized frames are.
    let pairs: Vec<(Vector3<f64>, Vector3<f64>)> = (0..CUT)
        .filter_map(|k| estimate[k].map(|e| (e, truth[k])))
        .collect();
    let (est, gt): (Vec<_>, Vec<_>) = pairs.into_iter().unzip();
    let t = absolute_orientation(&est, &gt).expect("alignment");
    for k in reloc..order.len() {
        let e = t.transform_point(&Point3::from(estimate[k].expect("tracked")));
        let err = (e.coords - truth[k]).norm();
        assert!(
            err < 0.03,
            "frame {k} (view of frame {}): {err:.3} m off",
            order[k]
        );
    }
}

#[test]
fn bow_matching_finds_most_brute_force_matches() {
    let gen = Generator::new(Preset::Kinect.config(), 6);
    let voc = shipped_vocabulary();
    let place = PlaceRecognition::new(voc.clone());
    let config = Config::default();
    let mut system = System::with_vocabulary(gen.camera(), config.clone(), voc);
    let input = |i: usize| gen.frame(i).into_input();
    for i in 0..40 {
        system.track(&input(i));
    }
    let camera = gen.camera();
    let mut extractor = OrbExtractor::new(config.orb.clone());
    let (mut brute_total, mut bow_total, mut both) = (0, 0, 0);
    let map = system.map();
    for kf in map.keyframes() {
        // A frame 8 frames after the keyframe's.
        let frame = Frame::new(
            999,
            &input(kf.frame_id as usize + 8),
            &camera,
            &mut extractor,
        );
        let features = Features::new(
            frame.keypoints,
            frame.descriptors,
            frame.depth,
            frame.u_right,
            &camera,
        );
        let fb = place.frame_bow(&features.descriptors);
        let kb = kf.bow.as_ref().expect("keyframes carry their BoW");
        let (brute, nb) = search_keyframe_frame(kf, &features, 0.7, map);
        let (bow, nw) = search_by_bow(kf, &kb.features, &features, &fb.features, 0.7, map);
        brute_total += nb;
        bow_total += nw;
        both += brute
            .iter()
            .zip(&bow)
            .filter(|(a, b)| a.is_some() && a == b)
            .count();
    }
    eprintln!("brute {brute_total}, bow {bow_total}, both {both}");
    assert!(brute_total > 200, "{brute_total}");
    assert!(
        both as f64 > 0.6 * brute_total as f64,
        "bow found {both} of brute's {brute_total}"
    );
}
