//! Round trips through the synthetic generator's writers: a sequence written in the TUM RGB-D
//! layout or the EuRoC layout (`datasets::write::write_synthetic`) reads back with the
//! same frames (bytes), timestamps and ground-truth poses, and equals the in-memory
//! `from_synth` sequence.

use datasets::{from_synth, load_euroc, load_path, load_tum, Format};
use synth::{Generator, SynthConfig};

const N: usize = 4;

#[test]
fn tum_layout_round_trips() {
    let gen = Generator::new(SynthConfig::preset("kinect").unwrap(), 11);
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("synthetic_kinect");
    datasets::write::write_synthetic(&gen, N, &dir, |_| {}).unwrap();
    let seq = load_tum(&dir, Some(gen.camera())).unwrap();
    let mem = from_synth(&gen, N);
    assert_eq!(seq.format, Format::TumRgbd);
    assert_eq!(mem.format, Format::TumRgbd);
    assert_eq!(seq.camera, gen.camera());
    assert_eq!(seq.len(), N);
    for i in 0..N {
        let f = gen.frame(i);
        let (a, b) = (&seq.frames[i], &mem.frames[i]);
        assert!((a.timestamp - f.timestamp).abs() < 1e-6, "frame {i} stamp");
        assert_eq!(*a.image, f.gray, "frame {i} grey");
        assert_eq!(a.depth.as_deref(), f.depth.as_ref(), "frame {i} depth");
        assert_eq!(a.image, b.image);
        assert_eq!(a.depth, b.depth);
        assert!((a.timestamp - b.timestamp).abs() < 1e-6);
    }
    let (gt, gt_mem) = (seq.groundtruth.unwrap(), mem.groundtruth.unwrap());
    assert_eq!(gt.stamps.len(), N);
    for i in 0..N {
        let p = gen.pose(i);
        assert!((gt.poses[i].translation.vector - p.translation.vector).norm() < 1e-8);
        assert!(gt.poses[i].rotation.angle_to(&p.rotation) < 1e-8);
        assert_eq!(gt_mem.poses[i], p);
        assert!((gt.stamps[i] - gt_mem.stamps[i]).abs() < 1e-6);
    }
}

#[test]
fn euroc_layout_round_trips() {
    let gen = Generator::new(SynthConfig::preset("stereo").unwrap(), 5);
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("synthetic_stereo");
    datasets::write::write_synthetic(&gen, N, &dir, |_| {}).unwrap();
    let seq = load_path(&dir).unwrap();
    assert_eq!(seq.format, Format::EurocStereo);
    assert_eq!(load_euroc(&dir).unwrap().len(), N);
    // The written pair is already rectified: rectification must be the identity.
    let cam = gen.camera();
    let c = &seq.camera;
    assert!(
        (c.fx - cam.fx).abs() < 1e-6
            && (c.cx - cam.cx).abs() < 1e-6
            && (c.cy - cam.cy).abs() < 1e-6
    );
    assert!((c.bf - cam.bf).abs() < 1e-6, "bf {} vs {}", c.bf, cam.bf);
    let mem = from_synth(&gen, N);
    assert_eq!(mem.format, Format::EurocStereo);
    for i in 0..N {
        let f = gen.frame(i);
        let a = &seq.frames[i];
        assert!((a.timestamp - f.timestamp).abs() < 1e-6, "frame {i} stamp");
        assert_eq!(*a.image, f.gray, "frame {i} left");
        assert_eq!(a.right.as_deref(), f.right.as_ref(), "frame {i} right");
        assert_eq!(a.image, mem.frames[i].image);
    }
    // Ground truth is the body; body * t_bs is the camera pose the generator rendered.
    let gt = seq.groundtruth.unwrap();
    let t_bs = seq.t_bs.unwrap();
    assert_eq!(gt.stamps.len(), N);
    for i in 0..N {
        let cam_pose = gt.poses[i] * t_bs;
        let p = gen.pose(i);
        assert!(
            (cam_pose.translation.vector - p.translation.vector).norm() < 1e-6,
            "frame {i}"
        );
        assert!(cam_pose.rotation.angle_to(&p.rotation) < 1e-6);
    }
}

/// A sequence with TUM's clocks (colour and depth stamped apart with jitter, ground truth on a
/// 100 Hz motion-capture clock with noise) reads back as the in-memory sequence: the same
/// frames and colour stamps, the same ground truth, and the reader's own colour-depth
/// association of rgb.txt and depth.txt finds the pairs of associations.txt.
#[test]
fn tum_stream_stamps_round_trip() {
    let mut c = SynthConfig::preset("kinect").unwrap();
    c.depth_noise.lag = Some(synth::DepthLag { frames: 1.0 / 3.0 });
    c.stamps = Some(synth::StreamStamps {
        rgb_jitter_s: 0.0015,
        depth_jitter_s: Some(0.0015),
    });
    c.mocap_clock = Some(synth::MocapClock { rate_hz: 100.0 });
    c.mocap_noise = Some(synth::MocapNoise {
        position_m: 0.0002,
        angle_rad: 0.0003,
    });
    let gen = Generator::new(c, 12);
    let n = 6;
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("synthetic_clocks");
    datasets::write::write_synthetic(&gen, n, &dir, |_| {}).unwrap();
    let mem = from_synth(&gen, n);
    let with_assoc = load_tum(&dir, Some(gen.camera())).unwrap();
    std::fs::remove_file(dir.join("associations.txt")).unwrap();
    let associated = load_tum(&dir, Some(gen.camera())).unwrap();
    for seq in [&with_assoc, &associated] {
        assert_eq!(seq.len(), n);
        for i in 0..n {
            let (a, b) = (&seq.frames[i], &mem.frames[i]);
            assert!(
                (a.timestamp - gen.timestamp(i)).abs() < 1e-6,
                "frame {i} stamp"
            );
            assert!((a.timestamp - b.timestamp).abs() < 1e-6);
            assert_eq!(a.image, b.image, "frame {i} grey");
            assert_eq!(a.depth, b.depth, "frame {i} depth");
        }
        // The depth files carry their own stamps, 11 ms (+ jitter) before the colour's.
        let (gt, gt_mem) = (
            seq.groundtruth.as_ref().unwrap(),
            mem.groundtruth.as_ref().unwrap(),
        );
        assert_eq!(gt.stamps.len(), gt_mem.stamps.len());
        assert!(gt.stamps.len() >= (n - 1) * 10 / 3, "{}", gt.stamps.len());
        for k in 0..gt.stamps.len() {
            assert!((gt.stamps[k] - gt_mem.stamps[k]).abs() < 1e-6);
            let d = gt.poses[k].inverse() * gt_mem.poses[k];
            assert!(d.translation.vector.norm() < 1e-8 && d.rotation.angle() < 1e-8);
            // The motion-capture noise is on both: the pose is not the path's exact one.
            let t = gt_mem.stamps[k] - synth::motion::clock::T0_NS as f64 * 1e-9;
            let exact = gen.pose_at_time(t);
            assert!((gt_mem.poses[k].translation.vector - exact.translation.vector).norm() > 0.0);
        }
    }
    let depth_txt = std::fs::read_to_string(dir.join("depth.txt")).unwrap();
    let depth_stamps: Vec<f64> = depth_txt
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split(' ').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(depth_stamps.len(), n);
    for (i, &d) in depth_stamps.iter().enumerate() {
        let dt = gen.timestamp(i) - d;
        assert!((dt - 1.0 / 90.0).abs() < 0.0061, "frame {i}: {dt}");
        assert!((d - gen.depth_timestamp(i)).abs() < 1e-6);
    }
}

/// `kinect` with fr1/fr2's free-running depth stream: stamps jittered, depth 11 ms early.
fn free_running(seed: u64) -> Generator {
    let mut c = SynthConfig::preset("kinect").unwrap();
    c.depth_noise.lag = Some(synth::DepthLag { frames: 1.0 / 3.0 });
    c.stamps = Some(synth::StreamStamps {
        rgb_jitter_s: 0.0015,
        depth_jitter_s: Some(0.0015),
    });
    Generator::new(c, seed)
}

/// The colour-depth pairs of a free-running depth stream are the ones the TUM reader's
/// association (associate.py's) finds in the stamps as written; a frame whose jitter brings
/// the next depth image nearer borrows it, the frame after may drop out; the in-memory
/// sequence holds exactly those pairs, read eagerly or lazily.
#[test]
fn free_running_depth_pairs_as_the_reader_associates_them() {
    let n = 3000;
    let gen = free_running(0);
    let read = |s: f64| synth::motion::clock::stamp_name(s).parse::<f64>().unwrap();
    let rgb: Vec<f64> = (0..n).map(|i| read(gen.timestamp(i))).collect();
    let depth: Vec<f64> = (0..n).map(|i| read(gen.depth_timestamp(i))).collect();
    let pairs = gen.stream_pairs(n);
    assert_eq!(pairs, datasets::tum::associate(&rgb, &depth, 0.02));
    let borrowed = pairs.iter().filter(|(i, j)| i != j).count();
    assert!(borrowed >= 1 && borrowed < n / 50, "{borrowed}");
    assert!(
        pairs.len() < n && pairs.len() > n - n / 50,
        "{}",
        pairs.len()
    );
    // A synchronised or exactly stamped depth stream: every frame with its own depth.
    let exact = Generator::new(SynthConfig::preset("kinect").unwrap(), 0);
    assert_eq!(
        exact.stream_pairs(50),
        (0..50).map(|i| (i, i)).collect::<Vec<_>>()
    );

    // A short sequence with a borrowed depth image among its first frames (seed 401 is the
    // first with one in 8 frames).
    let k = 8;
    let gen = free_running(401);
    let pairs = gen.stream_pairs(k);
    assert!(pairs.iter().any(|(i, j)| i != j), "{pairs:?}");
    let mem = from_synth(&gen, k);
    assert_eq!(mem.frames.len(), pairs.len());
    for (f, &(i, j)) in mem.frames.iter().zip(&pairs) {
        assert_eq!(f.timestamp, gen.timestamp(i));
        if i != j {
            // Frame i's colour image with frame j's depth image.
            assert_eq!(*f.image, gen.frame(i).gray, "pair ({i}, {j})");
            assert_eq!(
                f.depth.as_deref(),
                gen.frame(j).depth.as_ref(),
                "pair ({i}, {j})"
            );
            assert_ne!(f.depth.as_deref(), gen.frame(i).depth.as_ref());
        }
    }
    let (_, reader) = datasets::open_synth(&gen, k);
    let lazy = reader.read_all().unwrap();
    assert_eq!(lazy.len(), mem.frames.len());
    for (a, b) in lazy.iter().zip(&mem.frames) {
        assert_eq!(
            (a.timestamp, &a.image, &a.depth),
            (b.timestamp, &b.image, &b.depth)
        );
    }
}

/// An fr2 twin's depth files hold what fr2's Kinect records (5208 units per metre, ORB-SLAM2's
/// TUM2.yaml factor): a folder named as an fr2 sequence reads back with fr2's camera and that
/// factor to exactly the in-memory depth.
#[test]
fn fr2_twin_depth_reads_back_with_orbslam2s_factor() {
    let mut c = SynthConfig::preset("twin_fr2_desk").unwrap();
    // The imaging effects cost time and do not touch depth.
    for e in [
        "blur",
        "rolling_shutter",
        "auto_exposure",
        "vignetting",
        "image_noise",
    ] {
        c.without(e).unwrap();
    }
    assert_eq!(c.depth_units_per_metre, 5208.0);
    let gen = Generator::new(c, 3);
    let n = 2;
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("rgbd_dataset_freiburg2_twin");
    datasets::write::write_synthetic(&gen, n, &dir, |_| {}).unwrap();
    let seq = load_tum(&dir, None).unwrap();
    let mem = from_synth(&gen, n);
    assert_eq!(seq.camera, gen.camera());
    assert_eq!(seq.len(), mem.frames.len());
    for (a, b) in seq.frames.iter().zip(&mem.frames) {
        assert_eq!(a.image, b.image);
        assert_eq!(a.depth, b.depth);
    }
    // Read with TUM's nominal 5000, the depth is 4 % long, as real fr2 files are.
    let nominal = datasets::load_tum_with(
        &dir,
        &datasets::TumOptions {
            depth_factor: Some(5000.0),
            ..Default::default()
        },
    )
    .unwrap();
    let (a, b) = (
        nominal.frames[0].depth.as_ref().unwrap(),
        mem.frames[0].depth.as_ref().unwrap(),
    );
    let (za, zb) = a
        .data
        .iter()
        .zip(&b.data)
        .find(|(&x, &y)| x > 0.0 && y > 0.0)
        .unwrap();
    assert!(
        ((za / zb) as f64 - 5208.0 / 5000.0).abs() < 1e-4,
        "{za} {zb}"
    );
}
