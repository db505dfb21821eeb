//! The files of the EuRoC ASL layout besides the images: `mav0/cam0|cam1/data.csv`
//! (`#timestamp [ns],filename`), each camera's `sensor.yaml` (T_BS, rate, resolution,
//! intrinsics, distortion), `mav0/body.yaml` and
//! `mav0/state_groundtruth_estimate0/data.csv` (the body pose in EuRoC's column order), as
//! [`crate::euroc`] reads them back. Images go to [`image_path`].

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::Isometry3;
use slam_core::Camera;

use super::files::{mkdir, text};
use super::Digits;
use crate::DatasetError;

/// The whole nanoseconds an EuRoC file stores for a stamp of `t` seconds: the value that
/// [`crate::euroc::ns_to_s`] reads back to exactly `t` where one exists near `t * 1e9`.
pub fn stamp_ns(t: f64) -> i64 {
    let secs = t.floor();
    let base = secs as i64 * 1_000_000_000 + ((t - secs) * 1e9).round() as i64;
    for k in 0..1000i64 {
        for cand in [base + k, base - k] {
            if crate::euroc::ns_to_s(cand) == t {
                return cand;
            }
        }
    }
    base
}

/// The `mav0` folder of an EuRoC sequence rooted at `root`.
pub fn mav0(root: &Path) -> PathBuf {
    root.join("mav0")
}

/// Creates `mav0/cam0/data` and `mav0/cam1/data` under `root`.
pub fn create_folders(root: &Path) -> Result<(), DatasetError> {
    for cam in 0..2 {
        mkdir(&mav0(root).join(format!("cam{cam}")).join("data"))?;
    }
    Ok(())
}

/// Where camera `cam`'s (0 left, 1 right) image of stamp `ns` goes.
pub fn image_path(root: &Path, cam: usize, ns: i64) -> PathBuf {
    mav0(root)
        .join(format!("cam{cam}"))
        .join("data")
        .join(format!("{ns}.png"))
}

/// One camera's `sensor.yaml`.
#[derive(Clone, Debug)]
pub struct EurocSensor {
    /// The `comment:` line (what the camera is and whether its images are rectified).
    pub comment: String,
    /// T_BS: the camera's pose in the body (IMU) frame.
    pub t_bs: Isometry3<f64>,
    /// How T_BS is printed: [`Digits::Exact`] where a reader must rectify exactly as the
    /// writer did, [`Digits::Dataset`] (12 decimals) otherwise.
    pub t_bs_digits: Digits,
    /// Intrinsics, size and rate (`rate_hz`).
    pub camera: Camera,
    /// Radial-tangential k1, k2, p1, p2 of raw images; `None` for rectified ones (zeros).
    pub distortion: Option<[f64; 4]>,
}

/// Everything the text files of an EuRoC folder say.
#[derive(Clone, Debug)]
pub struct EurocLists {
    /// Stamps of the stereo pairs in nanoseconds, in time order (both cameras' `data.csv`).
    pub stamps_ns: Vec<i64>,
    /// cam0 and cam1.
    pub sensors: [EurocSensor; 2],
    /// The `comment:` of `mav0/body.yaml`.
    pub body_comment: String,
    /// Body poses T_world_body with their stamps in nanoseconds; none written when `None`.
    pub groundtruth: Option<Vec<(i64, Isometry3<f64>)>>,
    /// How the ground truth is printed.
    pub digits: Digits,
}

/// One line of the ground-truth CSV, `ns,px,py,pz,qw,qx,qy,qz`: with [`Digits::Dataset`] 9
/// decimals and qw >= 0, with [`Digits::Exact`] every digit of the pose as it is.
pub fn groundtruth_line(ns: i64, pose: &Isometry3<f64>, digits: Digits) -> String {
    let ([x, y, z], [qx, qy, qz, qw]) = digits.pose_values(pose);
    format!("{ns},{x},{y},{z},{qw},{qx},{qy},{qz}")
}

/// A camera's `sensor.yaml`, laid out as EuRoC's own.
pub fn sensor_yaml(s: &EurocSensor) -> String {
    let m = s.t_bs.to_homogeneous();
    let row = |r: usize| {
        let (a, b, c, d) = (m[(r, 0)], m[(r, 1)], m[(r, 2)], m[(r, 3)]);
        match s.t_bs_digits {
            Digits::Exact => format!("{a:?}, {b:?}, {c:?}, {d:?}"),
            Digits::Dataset => format!("{a:.12}, {b:.12}, {c:.12}, {d:.12}"),
        }
    };
    let dist = match s.distortion {
        Some([k1, k2, p1, p2]) => format!("{k1:?}, {k2:?}, {p1:?}, {p2:?}"),
        None => "0.0, 0.0, 0.0, 0.0".to_string(),
    };
    let c = &s.camera;
    format!(
        "%YAML:1.0\n\
         # General sensor definitions.\n\
         sensor_type: camera\n\
         comment: {comment}\n\
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
        comment = s.comment,
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

/// Writes both cameras' `data.csv` and `sensor.yaml`, `mav0/body.yaml` and (when there is one)
/// the ground truth into the folder rooted at `root`.
pub fn write_lists(root: &Path, lists: &EurocLists) -> Result<(), DatasetError> {
    let mav = mav0(root);
    let mut csv = String::from("#timestamp [ns],filename\n");
    // Infallible: writing into a String.
    for ns in &lists.stamps_ns {
        let _ = writeln!(csv, "{ns},{ns}.png");
    }
    for (cam, sensor) in lists.sensors.iter().enumerate() {
        let dir = mav.join(format!("cam{cam}"));
        mkdir(&dir)?;
        text(&dir.join("data.csv"), &csv)?;
        text(&dir.join("sensor.yaml"), &sensor_yaml(sensor))?;
    }
    text(
        &mav.join("body.yaml"),
        &format!("%YAML:1.0\ncomment: {}\n", lists.body_comment),
    )?;
    if let Some(gt) = &lists.groundtruth {
        let dir = mav.join("state_groundtruth_estimate0");
        mkdir(&dir)?;
        let mut s = String::from(
            "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n",
        );
        for (ns, pose) in gt {
            let _ = writeln!(s, "{}", groundtruth_line(*ns, pose, lists.digits));
        }
        text(&dir.join("data.csv"), &s)?;
    }
    Ok(())
}
