//! EuRoC ASL reader: `mav0/cam0` and `mav0/cam1` (`data.csv`, `data/*.png`, `sensor.yaml`),
//! rectified with [`crate::rectify`], and `mav0/state_groundtruth_estimate0/data.csv` (body
//! frame) when present. Left and right frames are paired by timestamp (within 1 ms; the
//! VI-sensor triggers both cameras together).

use crate::decode::read_gray;
use crate::rectify::{RawCamera, StereoRectification};
use crate::tum::{associate, check_size, folder_name};
use crate::{DatasetError, Format, FrameReader, Sequence};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use slam_core::{Distortion, FrameInput};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// ORB-SLAM2's `ThDepth` for EuRoC (EuRoC.yaml): close points are nearer than 35 baselines.
pub const EUROC_TH_DEPTH: f64 = 35.0;

/// Left/right pairing window, seconds.
const STEREO_SYNC: f64 = 0.001;

/// Options of the EuRoC reader. `Default` gives ORB-SLAM2's settings.
#[derive(Clone, Debug, Default)]
pub struct EurocOptions {
    /// `ThDepth` of the rectified camera; `None`: [`EUROC_TH_DEPTH`].
    pub th_depth: Option<f64>,
    /// Read at most this many frames; `None`: all.
    pub max_frames: Option<usize>,
    /// A camera settings file (ORB-SLAM2 / ORB-SLAM3, see [`crate::settings`]) and what it
    /// says: its rectified camera and its rectification replace those computed from the
    /// `sensor.yaml` files (which still place cam0 in the body frame for the ground truth).
    pub settings: Option<(std::path::PathBuf, crate::settings::CameraSettings)>,
}

/// One row of a camera's `data.csv`: timestamp (ns), file name, line number.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvRow {
    /// Timestamp in nanoseconds.
    pub stamp_ns: i64,
    /// File name inside `data/`.
    pub file: String,
    /// 1-based line number.
    pub line: usize,
}

/// Nanoseconds to seconds without losing the sub-microsecond part to f64 rounding of 1.4e18.
pub fn ns_to_s(ns: i64) -> f64 {
    (ns / 1_000_000_000) as f64 + (ns % 1_000_000_000) as f64 * 1e-9
}

/// Reads a camera `data.csv` (`#timestamp [ns],filename`); timestamps must increase.
pub fn read_camera_csv(path: &Path) -> Result<Vec<CsvRow>, DatasetError> {
    if !path.is_file() {
        return Err(DatasetError::Missing {
            path: path.to_path_buf(),
            what: "an EuRoC camera list (timestamp [ns],filename)".into(),
        });
    }
    let text = std::fs::read_to_string(path).map_err(|e| DatasetError::io(path, e))?;
    let mut out: Vec<CsvRow> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let mut it = l.split(',');
        let (Some(ts), Some(file)) = (it.next(), it.next()) else {
            return Err(DatasetError::parse(
                path,
                line,
                "expected `timestamp_ns,filename`",
            ));
        };
        let stamp_ns: i64 = ts.trim().parse().map_err(|_| {
            DatasetError::parse(path, line, format!("bad timestamp `{}`", ts.trim()))
        })?;
        if let Some(prev) = out.last() {
            if stamp_ns <= prev.stamp_ns {
                return Err(DatasetError::parse(
                    path,
                    line,
                    format!(
                        "timestamp {stamp_ns} does not increase (line {})",
                        prev.line
                    ),
                ));
            }
        }
        out.push(CsvRow {
            stamp_ns,
            file: file.trim().to_string(),
            line,
        });
    }
    Ok(out)
}

/// Finds `key:` in a `sensor.yaml` and returns the text after the colon plus its line; for a
/// bracketed list spanning several lines, the lines up to `]` are joined.
fn yaml_value(text: &str, key: &str) -> Option<(String, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    for (i, l) in lines.iter().enumerate() {
        let t = l.trim_start();
        let Some(rest) = t.strip_prefix(key).and_then(|r| r.strip_prefix(':')) else {
            continue;
        };
        let rest = rest.split('#').next().unwrap_or("").trim();
        if rest.starts_with('[') && !rest.contains(']') {
            let mut joined = rest.to_string();
            for more in &lines[i + 1..] {
                let m = more.split('#').next().unwrap_or("");
                joined.push(' ');
                joined.push_str(m.trim());
                if m.contains(']') {
                    break;
                }
            }
            return Some((joined, i + 1));
        }
        return Some((rest.to_string(), i + 1));
    }
    None
}

fn yaml_list(path: &Path, text: &str, key: &str, n: usize) -> Result<Vec<f64>, DatasetError> {
    let (v, line) = yaml_value(text, key)
        .ok_or_else(|| DatasetError::parse(path, 0, format!("missing `{key}`")))?;
    let inner = v
        .trim()
        .strip_prefix('[')
        .and_then(|s| s.strip_suffix(']'))
        .ok_or_else(|| DatasetError::parse(path, line, format!("`{key}` is not a [list]")))?;
    let vals: Result<Vec<f64>, _> = inner
        .split(',')
        .map(|s| s.trim())
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<f64>())
        .collect();
    let vals = vals.map_err(|e| DatasetError::parse(path, line, format!("`{key}`: {e}")))?;
    if let Some(v) = vals.iter().find(|v| !v.is_finite()) {
        return Err(DatasetError::parse(
            path,
            line,
            format!("`{key}` holds {v}, not a finite number"),
        ));
    }
    if vals.len() != n {
        return Err(DatasetError::parse(
            path,
            line,
            format!("`{key}` has {} values, expected {n}", vals.len()),
        ));
    }
    Ok(vals)
}

/// Parses an EuRoC camera `sensor.yaml`: `T_BS` (4x4 row-major), `resolution`, `intrinsics`
/// (fu, fv, cu, cv), `distortion_coefficients` (k1, k2, p1, p2) of a `radial-tangential` model,
/// `rate_hz`.
pub fn read_sensor_yaml(path: &Path) -> Result<RawCamera, DatasetError> {
    if !path.is_file() {
        return Err(DatasetError::Missing {
            path: path.to_path_buf(),
            what: "an EuRoC camera calibration".into(),
        });
    }
    let text = std::fs::read_to_string(path).map_err(|e| DatasetError::io(path, e))?;
    if let Some((model, line)) = yaml_value(&text, "distortion_model") {
        if model != "radial-tangential" {
            return Err(DatasetError::parse(
                path,
                line,
                format!("distortion model `{model}` is not supported (radial-tangential only)"),
            ));
        }
    }
    if let Some((model, line)) = yaml_value(&text, "camera_model") {
        if model != "pinhole" {
            return Err(DatasetError::parse(
                path,
                line,
                format!("camera model `{model}` is not supported (pinhole only)"),
            ));
        }
    }
    let t = yaml_list(path, &text, "data", 16)?;
    let res = yaml_list(path, &text, "resolution", 2)?;
    let k = yaml_list(path, &text, "intrinsics", 4)?;
    let d = yaml_list(path, &text, "distortion_coefficients", 4)?;
    let rate_hz = match yaml_value(&text, "rate_hz") {
        Some((v, line)) => v
            .parse::<f64>()
            .map_err(|e| DatasetError::parse(path, line, format!("`rate_hz`: {e}")))?,
        None => 20.0,
    };
    let m = Matrix3::new(t[0], t[1], t[2], t[4], t[5], t[6], t[8], t[9], t[10]);
    // The published rotations are orthonormal to ~1e-9; re-orthonormalise via the quaternion.
    let rot = crate::rectify::near_rotation(&m).unwrap_or_else(Rotation3::identity);
    let off = (rot.matrix() - m).norm();
    if off.is_nan() || off > 1e-3 {
        let line = yaml_value(&text, "data").map_or(0, |v| v.1);
        return Err(DatasetError::parse(
            path,
            line,
            "T_BS rotation part is not a rotation",
        ));
    }
    let t_bs = Isometry3::from_parts(
        Translation3::from(Vector3::new(t[3], t[7], t[11])),
        UnitQuaternion::from_rotation_matrix(&rot),
    );
    let side = f64::from(crate::settings::MAX_IMAGE_SIDE);
    if !(res
        .iter()
        .all(|&r| (1.0..=side).contains(&r) && r.fract() == 0.0))
    {
        let line = yaml_value(&text, "resolution").map_or(0, |v| v.1);
        return Err(DatasetError::parse(
            path,
            line,
            format!(
                "resolution = [{}, {}]: each side must be a whole number in 1..={side}",
                res[0], res[1]
            ),
        ));
    }
    if k[0] <= 0.0 || k[1] <= 0.0 {
        let line = yaml_value(&text, "intrinsics").map_or(0, |v| v.1);
        return Err(DatasetError::parse(
            path,
            line,
            format!("intrinsics: fu = {}, fv = {}: must be > 0", k[0], k[1]),
        ));
    }
    if !(rate_hz > 0.0 && rate_hz <= 10_000.0) {
        let line = yaml_value(&text, "rate_hz").map_or(0, |v| v.1);
        return Err(DatasetError::parse(
            path,
            line,
            format!("rate_hz = {rate_hz}: must be > 0 and <= 10000"),
        ));
    }
    Ok(RawCamera {
        width: res[0] as u32,
        height: res[1] as u32,
        fx: k[0],
        fy: k[1],
        cx: k[2],
        cy: k[3],
        distortion: Distortion {
            k1: d[0],
            k2: d[1],
            p1: d[2],
            p2: d[3],
            k3: 0.0,
        },
        t_bs,
        rate_hz,
    })
}

/// The `mav0` folder of an EuRoC sequence: `dir/mav0`, or `dir` itself if it is `mav0`.
fn mav0_of(dir: &Path) -> Result<PathBuf, DatasetError> {
    if dir.join("mav0").is_dir() {
        Ok(dir.join("mav0"))
    } else if dir.join("cam0").is_dir() {
        Ok(dir.to_path_buf())
    } else {
        Err(DatasetError::Missing {
            path: dir.join("mav0"),
            what: "the EuRoC ASL folder (mav0/cam0, mav0/cam1)".into(),
        })
    }
}

/// Loads an EuRoC folder (containing `mav0/`) with ORB-SLAM2's settings, rectified.
pub fn load_euroc(dir: &Path) -> Result<Sequence, DatasetError> {
    load_euroc_with(dir, &EurocOptions::default())
}

/// Loads an EuRoC folder with explicit options.
pub fn load_euroc_with(dir: &Path, opts: &EurocOptions) -> Result<Sequence, DatasetError> {
    let (mut seq, frames) = open_euroc_with(dir, opts)?;
    seq.frames = frames.read_all()?;
    Ok(seq)
}

/// Opens an EuRoC folder: sensor files, frame lists, rectification and ground truth are read
/// now, the images when the returned reader reads them (the sequence's `frames` stay empty).
pub fn open_euroc_with(
    dir: &Path,
    opts: &EurocOptions,
) -> Result<(Sequence, FrameReader), DatasetError> {
    let mav0 = mav0_of(dir)?;
    let name = if mav0 == dir {
        dir.parent()
            .map(folder_name)
            .unwrap_or_else(|| "mav0".into())
    } else {
        folder_name(dir)
    };
    let left = read_sensor_yaml(&mav0.join("cam0/sensor.yaml"))?;
    let right = read_sensor_yaml(&mav0.join("cam1/sensor.yaml"))?;
    let rect = match &opts.settings {
        None => StereoRectification::new(&left, &right).map_err(|e| match e {
            DatasetError::Invalid { msg, .. } => {
                DatasetError::invalid(mav0.join("cam1/sensor.yaml"), msg)
            }
            other => other,
        })?,
        Some((path, s)) => match s.rectification(path, left.t_bs)? {
            Some(r) => r,
            // A file without a rectification takes the images as rectified already.
            None => crate::settings::CameraSettings::of_camera(&s.camera, None, None)
                .rectification(path, left.t_bs)?
                .ok_or_else(|| DatasetError::invalid(path, "no stereo camera"))?,
        },
    };
    let rect = Arc::new(rect);
    let rows0 = read_camera_csv(&mav0.join("cam0/data.csv"))?;
    let rows1 = read_camera_csv(&mav0.join("cam1/data.csv"))?;
    let t0: Vec<f64> = rows0.iter().map(|r| ns_to_s(r.stamp_ns)).collect();
    let t1: Vec<f64> = rows1.iter().map(|r| ns_to_s(r.stamp_ns)).collect();
    let mut pairs = associate(&t0, &t1, STEREO_SYNC);
    if let Some(n) = opts.max_frames {
        pairs.truncate(n);
    }
    if pairs.is_empty() {
        return Err(DatasetError::invalid(
            &mav0,
            "no synchronised cam0/cam1 frames",
        ));
    }
    let (w, h) = (left.width as usize, left.height as usize);
    let th_depth = opts.th_depth.unwrap_or(EUROC_TH_DEPTH);
    let (camera, t_bs) = match &opts.settings {
        None => (rect.camera(th_depth), rect.t_b_left),
        Some((_, s)) => (s.camera.clone(), rect.t_b_left),
    };
    let data = mav0.clone();
    let rectification = rect.clone();
    let frames = FrameReader::new(pairs.len(), move |k| {
        let (i, j) = pairs[k];
        let lp = data.join("cam0/data").join(&rows0[i].file);
        let rp = data.join("cam1/data").join(&rows1[j].file);
        let l = read_gray(&lp)?;
        check_size(&lp, l.width, l.height, w, h, "cam0/sensor.yaml resolution")?;
        let r = read_gray(&rp)?;
        check_size(&rp, r.width, r.height, w, h, "cam1/sensor.yaml resolution")?;
        Ok(FrameInput {
            timestamp: t0[i],
            image: Arc::new(rect.rectify_left(&l)),
            depth: None,
            right: Some(Arc::new(rect.rectify_right(&r))),
            colour: None,
        })
    });
    let gt_path = mav0.join("state_groundtruth_estimate0/data.csv");
    let mut notes = Vec::new();
    let groundtruth = if gt_path.is_file() {
        Some(crate::tum::read_groundtruth(
            &gt_path,
            ate_eval::io::Format::Euroc,
            &mut notes,
        )?)
    } else {
        None
    };
    let seq = Sequence {
        name,
        camera,
        frames: Vec::new(),
        groundtruth,
        t_bs: Some(t_bs),
        format: Format::EurocStereo,
        notes,
        depth_factor: None,
        rectification: Some(rectification),
    };
    Ok((seq, frames))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ns_to_s_keeps_nanoseconds() {
        let t = ns_to_s(1_403_715_273_262_142_976);
        assert!((t - 1_403_715_273.262_143).abs() < 1e-6);
    }

    #[test]
    fn yaml_multiline_list() {
        let text = "T_BS:\n  cols: 4\n  data: [1, 2,\n   3, 4] # c\nrate_hz: 20\n";
        let (v, line) = yaml_value(text, "data").unwrap();
        assert_eq!(line, 3);
        assert!(v.starts_with('[') && v.ends_with(']'), "{v}");
        assert_eq!(yaml_value(text, "rate_hz").unwrap().0, "20");
    }

    #[test]
    fn a_t_bs_entry_of_7e61_is_refused_at_once() {
        // Found by fuzzing: nalgebra's `from_matrix` looped forever on this matrix.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sensor.yaml");
        std::fs::write(
            &p,
            "T_BS:\n  data: [1, 0, 0, 0, 0, 1, 7e61, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n\
             resolution: [752, 480]\nintrinsics: [458, 457, 367, 248]\n\
             distortion_coefficients: [0, 0, 0, 0]\n",
        )
        .unwrap();
        let e = read_sensor_yaml(&p).unwrap_err().to_string();
        assert!(
            e.contains("sensor.yaml") && e.contains("not a rotation"),
            "{e}"
        );
    }

    #[test]
    fn csv_rejects_bad_rows_with_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("data.csv");
        std::fs::write(&p, "#timestamp [ns],filename\n10,a.png\nx,b.png\n").unwrap();
        let e = read_camera_csv(&p).unwrap_err().to_string();
        assert!(e.contains("data.csv:3"), "{e}");
    }
}
