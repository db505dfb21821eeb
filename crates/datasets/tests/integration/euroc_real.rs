//! The EuRoC reader and rectification on real data: the first 95 stereo frames of V1_01_easy
//! (`shared/data/euroc_v101_head`, beside the repository). Checks the rectified camera against
//! ORB-SLAM2's EuRoC.yaml (fx 435.20, cx 367.45, cy 252.20, baseline 0.11008 m), the frame and
//! ground-truth counts, the body-camera extrinsic, and that textured patches of the rectified
//! pair match on the same row (integer rows; the sub-pixel check is `rectify_render.rs`).

use datasets::euroc::read_sensor_yaml;
use datasets::{load_euroc, load_path, Format};
use slam_core::{GrayImage, SensorKind};
use std::path::PathBuf;

fn data_dir() -> PathBuf {
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let candidates = [
        std::env::var_os("NOISEFREE_EUROC_HEAD").map(PathBuf::from),
        Some(here.join("../../../shared/data/euroc_v101_head")),
        Some(PathBuf::from("/work/shared/data/euroc_v101_head")),
    ];
    candidates
        .into_iter()
        .flatten()
        .find(|p| p.join("mav0").is_dir())
        .expect(
            "real EuRoC frames not found: set NOISEFREE_EUROC_HEAD to shared/data/euroc_v101_head",
        )
}

#[test]
fn loads_rectifies_and_matches_orbslam2_settings() {
    let dir = data_dir();
    let seq = load_euroc(&dir).unwrap();
    assert_eq!(seq.format, Format::EurocStereo);
    assert_eq!(seq.len(), 95);
    let c = &seq.camera;
    assert_eq!((c.width, c.height), (752, 480));
    assert_eq!(c.sensor, SensorKind::Stereo);
    assert!(c.distortion.is_none());
    assert_eq!(c.fx, c.fy);
    // ORB-SLAM2's EuRoC.yaml (OpenCV stereoRectify, alpha 0): 435.2047, 367.4517, 252.2009.
    // We emulate OpenCV's 5-step undistortPoints there, so the values agree to ~1e-4.
    assert!((c.fx - 435.2046959714599).abs() < 1e-3, "fx {}", c.fx);
    assert!((c.cx - 367.4517211914062).abs() < 1e-3, "cx {}", c.cx);
    assert!((c.cy - 252.2008514404297).abs() < 1e-3, "cy {}", c.cy);
    assert!(
        (c.baseline() - 0.11008).abs() < 1e-4,
        "baseline {}",
        c.baseline()
    );
    assert!((c.bf - 47.90639384423901).abs() < 1e-3, "bf {}", c.bf);
    assert_eq!((c.th_depth, c.fps), (35.0, 20.0));
    assert!((seq.frames[0].timestamp - 1_403_715_273.262_143).abs() < 1e-5);
    for f in &seq.frames {
        assert!(f.depth.is_none());
        let r = f.right.as_ref().unwrap();
        assert_eq!((r.width, r.height, f.image.width), (752, 480, 752));
    }
    let gt = seq.groundtruth.as_ref().unwrap();
    assert_eq!(gt.stamps.len(), 76);

    // t_bs is cam0's T_BS with the (small) rectifying rotation folded in.
    let raw = read_sensor_yaml(&dir.join("mav0/cam0/sensor.yaml")).unwrap();
    let t_bs = seq.t_bs.unwrap();
    assert!((t_bs.translation.vector - raw.t_bs.translation.vector).norm() < 1e-12);
    let angle = t_bs.rotation.angle_to(&raw.t_bs.rotation);
    assert!(
        angle > 1e-4 && angle < 0.02,
        "rectifying rotation {angle} rad"
    );
    // Body ground truth * raw T_BS gives the cam0 ground truth the README ships.
    let cam0 = ate_eval::io::read_tum(&dir.join("groundtruth_cam0.tum.txt")).unwrap();
    let p = gt.poses[0] * raw.t_bs;
    assert!((gt.stamps[0] - cam0.stamps[0]).abs() < 1e-6);
    assert!((p.translation.vector - cam0.poses[0].translation.vector).norm() < 1e-4);

    // load_path detects EuRoC.
    assert_eq!(load_path(&dir).unwrap().len(), 95);
}

/// Zero-mean normalised cross-correlation of a (2r+1)^2 patch at (x, y) in `a` against
/// (x - d, y + dy) in `b`.
fn zncc(a: &GrayImage, b: &GrayImage, x: usize, y: usize, d: usize, dy: i32, r: usize) -> f64 {
    let n = ((2 * r + 1) * (2 * r + 1)) as f64;
    let (mut sa, mut sb, mut saa, mut sbb, mut sab) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for j in 0..=2 * r {
        for i in 0..=2 * r {
            let (ax, ay) = (x + i - r, y + j - r);
            let (bx, by) = (ax - d, (ay as i32 + dy) as usize);
            let (va, vb) = (a.get(ax, ay) as f64, b.get(bx, by) as f64);
            sa += va;
            sb += vb;
            saa += va * va;
            sbb += vb * vb;
            sab += va * vb;
        }
    }
    let cov = sab - sa * sb / n;
    let den = ((saa - sa * sa / n) * (sbb - sb * sb / n)).sqrt();
    if den > 0.0 {
        cov / den
    } else {
        0.0
    }
}

#[test]
fn rectified_pairs_match_on_the_same_row() {
    let seq = load_euroc(&data_dir()).unwrap();
    let f = &seq.frames[0];
    let (l, r) = (&*f.image, &**f.right.as_ref().unwrap());
    let rad = 10;
    let (mut same_row, mut total) = (0, 0);
    for y in (30..450).step_by(20) {
        for x in (140..730).step_by(20) {
            let mut best = (f64::MIN, 0i32);
            for dy in -3..=3 {
                for d in 0..=120 {
                    let c = zncc(l, r, x, y, d, dy, rad);
                    if c > best.0 {
                        best = (c, dy);
                    }
                }
            }
            // Only confident matches. Edges slanted a little off horizontal stay ambiguous
            // along their direction (a row off plus a disparity off), hence the 90 % below.
            if best.0 < 0.9 {
                continue;
            }
            total += 1;
            if best.1 == 0 {
                same_row += 1;
            }
        }
    }
    assert!(total >= 30, "too few confident matches ({total})");
    assert!(
        same_row as f64 >= 0.9 * total as f64,
        "{same_row}/{total} patches matched on the same row"
    );
    eprintln!("{same_row}/{total} confident matches on the same row");
}
