//! Round trips through the synthetic generator's writers: a sequence written in the TUM RGB-D
//! layout (`synth::write_tum`) or the EuRoC layout (`synth::write_euroc`) reads back with the
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
    synth::write_tum(&gen, N, &dir, |_| {}).unwrap();
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
    synth::write_euroc(&gen, N, &dir, |_| {}).unwrap();
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
