//! End-to-end tests of the ORB-SLAM2 baseline on synthetic sequences (100-180 frames of 640x480
//! RGB-D, 150 of 752x480 stereo turning on the spot): accuracy per preset with every frame tracked, relocalization after an
//! occlusion, and bit-identical reruns. Each test renders and tracks its sequence in well under a
//! minute in the (optimised) dev profile.

use crate::common;

use slam_core::system::{Config, TrackingState};
use synth::Preset;

use common::{ate_rmse, render, run, track, tracked};

/// The kinect, occluded and stereo sequences are those of seed 0, which the command-line tests
/// and the regression suite render too: through the shared frame cache they are rendered once.
const FRAMES: usize = 150;
const STEREO_FRAMES: usize = 150;

/// The one sequence of the suites without noise, so rendered for this test alone: 100 frames.
#[test]
fn clean_rgbd_tracks_every_frame_with_subcentimetre_ate() {
    const CLEAN_FRAMES: usize = 100;
    let r = run(Preset::Clean.config(), 1, CLEAN_FRAMES, Config::default());
    let ate = ate_rmse(&r);
    eprintln!("clean: ATE {:.2} mm, {} keyframes", ate * 1e3, r.keyframes);
    assert_eq!(tracked(&r), CLEAN_FRAMES);
    assert!(ate < 0.01, "ATE {ate}");
}

#[test]
fn kinect_noise_rgbd_stays_below_three_centimetres() {
    let r = run(Preset::Kinect.config(), 0, FRAMES, Config::default());
    let ate = ate_rmse(&r);
    eprintln!("kinect: ATE {:.2} mm, {} keyframes", ate * 1e3, r.keyframes);
    assert_eq!(tracked(&r), FRAMES);
    assert!(ate < 0.03, "ATE {ate}");
}

/// The stereo pair turning on the spot: the first frames of the regression suite's
/// `stereo-spin` (seed 0), rendered once through the shared frame cache.
#[test]
fn stereo_tracks_every_frame_below_three_centimetres() {
    let mut cfg = Preset::Stereo.config();
    cfg.trajectory = synth::Trajectory::Spin;
    let r = run(cfg, 0, STEREO_FRAMES, Config::stereo());
    let ate = ate_rmse(&r);
    eprintln!("stereo: ATE {:.2} mm, {} keyframes", ate * 1e3, r.keyframes);
    assert_eq!(tracked(&r), STEREO_FRAMES);
    assert!(ate < 0.03, "ATE {ate}");
}

#[test]
fn occlusion_is_followed_by_relocalization() {
    // Frames 120..150 show a featureless surface; tracking must be lost there and recovered
    // by relocalization afterwards, with an accurate trajectory again. The regression suite's
    // `occluded` sequence, all of its 180 frames.
    let n = 180;
    let r = run(Preset::Occluded.config(), 0, n, Config::default());
    let lost = r.states[120..150]
        .iter()
        .filter(|s| **s == TrackingState::Lost)
        .count();
    let reloc = r
        .states
        .iter()
        .position(|s| *s == TrackingState::Relocalized)
        .expect("relocalized");
    let ate = ate_rmse(&r);
    eprintln!(
        "occluded: lost {lost} of the 30 occluded frames, relocalized at {reloc}, tracked {}, ATE {:.2} mm",
        tracked(&r),
        ate * 1e3
    );
    assert!(lost >= 25, "lost only {lost}");
    assert!((150..165).contains(&reloc), "relocalized at {reloc}");
    assert!(r.states[reloc..].iter().all(|s| s.is_tracked()));
    assert!(ate < 0.03, "ATE {ate}");
}

#[test]
fn same_seed_gives_bit_identical_trajectory() {
    // Rendered once: the system must not depend on anything but its input and seed.
    let frames = render(Preset::Kinect.config(), 0, 80);
    let a = track(&frames, Config::default());
    let b = track(&frames, Config::default());
    assert!(same_bytes(&a, &b));
}

/// Whether two runs produced the same trajectory bytes.
fn same_bytes(a: &common::Run, b: &common::Run) -> bool {
    a.trajectory.len() == b.trajectory.len()
        && a.trajectory
            .iter()
            .zip(&b.trajectory)
            .all(|((ta, pa), (tb, pb))| {
                ta.to_bits() == tb.to_bits()
                    && pa
                        .to_homogeneous()
                        .iter()
                        .zip(pb.to_homogeneous().iter())
                        .all(|(x, y)| x.to_bits() == y.to_bits())
            })
}

#[test]
fn mapping_lag_spreads_seeded_runs_reproducibly() {
    // Synchronous (the paper's protocol): without relocalization the seed changes nothing.
    let n = 90;
    let sync = |seed| Config {
        seed,
        ..Config::default()
    };
    let frames = render(Preset::Kinect.config(), 0, n);
    let s1 = track(&frames, sync(1));
    let s2 = track(&frames, sync(2));
    assert!(same_bytes(&s1, &s2));
    // Emulated concurrent mapping: another seed maps keyframes at other times, so the
    // trajectory differs; the same seed repeats itself; accuracy holds.
    let lagged = |seed| Config {
        seed,
        mapping_lag: 3,
        ..Config::default()
    };
    let a = track(&frames, lagged(1));
    let b = track(&frames, lagged(1));
    let c = track(&frames, lagged(2));
    assert!(same_bytes(&a, &b));
    assert!(!same_bytes(&a, &c));
    assert!(!same_bytes(&a, &s1));
    for r in [&a, &c] {
        assert_eq!(tracked(r), n);
        let ate = ate_rmse(r);
        assert!(ate < 0.01, "ATE {ate}");
    }
}
