//! Writes a generated stereo sequence in the EuRoC ASL layout: `mav0/cam0|cam1/data/<ns>.png`,
//! `data.csv` (`#timestamp [ns],filename`), `sensor.yaml` (T_BS, rate, resolution, intrinsics,
//! distortion), `mav0/body.yaml` and `mav0/state_groundtruth_estimate0/data.csv` with the BODY
//! pose in EuRoC's column layout.
//!
//! Two kinds of pair: a rectified pinhole pair (the `stereo` preset: zero distortion, cam1 the
//! baseline along cam0's x), or a calibrated rig ([`crate::spec::StereoRig`], the EuRoC
//! twins): each camera's own intrinsics, distortion and T_BS, the images distorted and
//! unrectified, so a reader rectifies them as it does real EuRoC data.
//!
//! The camera is not at the body origin: cam0 sits at [`body_from_cam0`] (a rotation of about
//! 90 degrees about z plus a few centimetres, like EuRoC's) or at the rig's T_BS, so readers
//! that forget the body-to-camera conversion get a visibly wrong trajectory. With
//! [`crate::motion::clock::MocapNoise`] the written ground truth carries motion-capture noise
//! ([`Generator::measured_pose`]).

use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use image::ExtendedColorType;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rayon::prelude::*;
use slam_core::Camera;

use crate::error::SynthError;
use crate::generator::Generator;
use crate::output::write::{mkdir, png, text, Staging};

/// T_BS of cam0: pose of the left camera in the body (IMU) frame.
pub fn body_from_cam0() -> Isometry3<f64> {
    let r = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::FRAC_PI_2)
        * UnitQuaternion::from_euler_angles(-0.0257, 0.0149, 0.0042);
    Isometry3::from_parts(Translation3::new(-0.0216, -0.0647, 0.0098), r)
}

/// T_BS of cam1: cam0 shifted by the stereo baseline along its x axis.
pub fn body_from_cam1(baseline: f64) -> Isometry3<f64> {
    body_from_cam0() * Translation3::new(baseline, 0.0, 0.0)
}

/// The body pose T_WB of a camera-to-world pose of cam0 (the rectified pair's
/// [`body_from_cam0`]).
pub fn body_pose(pose_wc0: &Isometry3<f64>) -> Isometry3<f64> {
    pose_wc0 * body_from_cam0().inverse()
}

/// T_BS of cam0 of `gen`'s sequence: its rig's, else [`body_from_cam0`].
pub fn body_from_left(gen: &Generator) -> Isometry3<f64> {
    gen.config()
        .rig
        .as_ref()
        .map_or_else(body_from_cam0, |r| r.body_from_left)
}

/// The ground truth written for frame `index`: the body pose T_WB, exact or with the
/// configuration's motion-capture noise.
pub fn groundtruth_body(gen: &Generator, index: usize) -> Isometry3<f64> {
    let b = gen.pose(index) * body_from_left(gen).inverse();
    gen.measured_pose(&b, index)
}

fn sensor_yaml(name: &str, t_bs: &Isometry3<f64>, gen: &Generator, c: &Camera) -> String {
    let m = t_bs.to_homogeneous();
    let rig = gen.config().rig.is_some();
    let kind = if rig {
        "raw, distorted"
    } else {
        "rectified pinhole"
    };
    let dist = match (rig, c.distortion) {
        (true, Some(d)) => format!("{:?}, {:?}, {:?}, {:?}", d.k1, d.k2, d.p1, d.p2),
        _ => "0.0, 0.0, 0.0, 0.0".to_string(),
    };
    let row = |r: usize| {
        let (a, b, c, d) = (m[(r, 0)], m[(r, 1)], m[(r, 2)], m[(r, 3)]);
        if rig {
            // Every digit, so the reader's rectification is the in-memory one's.
            format!("{a:?}, {b:?}, {c:?}, {d:?}")
        } else {
            format!("{a:.12}, {b:.12}, {c:.12}, {d:.12}")
        }
    };
    format!(
        "%YAML:1.0\n\
         # General sensor definitions.\n\
         sensor_type: camera\n\
         comment: synthetic noisefree {name} (seed {seed}, {kind})\n\
         \n\
         # Sensor extrinsics wrt. the body-frame.\n\
         T_BS:\n  cols: 4\n  rows: 4\n  data: [{r0},\n         {r1},\n         {r2},\n         0.0, 0.0, 0.0, 1.0]\n\
         \n\
         # Camera specific definitions.\n\
         rate_hz: {rate}\n\
         resolution: [{w}, {h}]\n\
         camera_model: pinhole\n\
         intrinsics: [{fx:?}, {fy:?}, {cx:?}, {cy:?}] #fu, fv, cu, cv\n\
         distortion_model: radial-tangential\n\
         distortion_coefficients: [{dist}]\n",
        seed = gen.seed(),
        r0 = row(0),
        r1 = row(1),
        r2 = row(2),
        rate = c.fps,
        w = c.width,
        h = c.height,
        fx = c.fx,
        fy = c.fy,
        cx = c.cx,
        cy = c.cy,
    )
}

/// Writes frames 0..n of `gen` (a stereo generator) into `dir` in the EuRoC ASL layout.
/// Frames are generated and encoded in parallel; `progress(k)` gets the frames written so far.
/// Everything goes to a staging folder renamed to `dir` at the end; `dir` must not exist or be
/// empty.
pub fn write_euroc(
    gen: &Generator,
    n: usize,
    dir: &Path,
    progress: impl Fn(usize) + Sync,
) -> Result<(), SynthError> {
    if gen.config().is_rgbd() {
        return Err(SynthError::InvalidConfig(
            "the EuRoC layout needs a stereo configuration (use write_tum for RGB-D)".into(),
        ));
    }
    gen.check_frames(n)?;
    Staging::write_atomically(dir, |tmp| write_into(gen, n, tmp, &progress))
}

fn write_into(
    gen: &Generator,
    n: usize,
    root: &Path,
    progress: &(impl Fn(usize) + Sync),
) -> Result<(), SynthError> {
    let mav = root.join("mav0");
    let cams = [mav.join("cam0"), mav.join("cam1")];
    for c in &cams {
        mkdir(&c.join("data"))?;
    }
    let gt_dir = mav.join("state_groundtruth_estimate0");
    mkdir(&gt_dir)?;
    let done = AtomicUsize::new(0);
    (0..n)
        .into_par_iter()
        .try_for_each(|i| -> Result<(), SynthError> {
            let f = gen.frame(i);
            let name = format!("{}.png", gen.stamp_ns(i));
            let (w, h) = (f.gray.width, f.gray.height);
            png(
                &cams[0].join("data").join(&name),
                &f.gray.data,
                w,
                h,
                ExtendedColorType::L8,
            )?;
            if let Some(r) = &f.right {
                png(
                    &cams[1].join("data").join(&name),
                    &r.data,
                    w,
                    h,
                    ExtendedColorType::L8,
                )?;
            }
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            Ok(())
        })?;
    let mut csv = String::from("#timestamp [ns],filename\n");
    let mut gt = String::from(
        "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n",
    );
    for i in 0..n {
        let ns = gen.stamp_ns(i);
        // Infallible: writing into a String.
        let _ = writeln!(csv, "{ns},{ns}.png");
        let b = groundtruth_body(gen, i);
        let p = b.translation.vector;
        let mut q = *b.rotation.quaternion();
        if q.w < 0.0 {
            q = -q;
        }
        let _ = writeln!(
            gt,
            "{ns},{:.9},{:.9},{:.9},{:.9},{:.9},{:.9},{:.9}",
            p.x, p.y, p.z, q.w, q.i, q.j, q.k
        );
    }
    let left = gen.camera();
    let (right, t_bs1) = match &gen.config().rig {
        Some(r) => (r.right.clone(), r.body_from_right()),
        None => (left.clone(), body_from_cam1(left.baseline())),
    };
    text(&cams[0].join("data.csv"), &csv)?;
    text(&cams[1].join("data.csv"), &csv)?;
    text(
        &cams[0].join("sensor.yaml"),
        &sensor_yaml("cam0", &body_from_left(gen), gen, &left),
    )?;
    text(
        &cams[1].join("sensor.yaml"),
        &sensor_yaml("cam1", &t_bs1, gen, &right),
    )?;
    text(
        &mav.join("body.yaml"),
        "%YAML:1.0\ncomment: synthetic noisefree body (IMU) frame\n",
    )?;
    text(&gt_dir.join("data.csv"), &gt)
}
