//! Writes any sequence — perturbed or not, real, synthetic or a twin — as a folder other tools
//! read: the TUM RGB-D layout for RGB-D (`rgb/`, `depth/`, `rgb.txt`, `depth.txt`,
//! `associations.txt`, `groundtruth.txt`) and the EuRoC ASL layout for stereo (`mav0/cam0`,
//! `mav0/cam1` with `data.csv` and a rectified-pinhole `sensor.yaml`,
//! `state_groundtruth_estimate0/data.csv`). Beside them: `camera-orbslam2.yaml` and
//! `camera-orbslam3.yaml` (the sequence's camera as ORB-SLAM2 / ORB-SLAM3 settings, which
//! `noisefree run --path DIR --camera` reads back). Images keep the input's pixel format: 8-bit
//! RGB PNGs where the input had colour (whose grey, as the readers make it, is what slam-core
//! saw), 8-bit grey PNGs otherwise; depth 16-bit PNGs on the sequence's own depth grid, stamps and poses with every digit,
//! so noisefree reading the folder gets the same bits it wrote. Everything goes to a staging
//! folder renamed into place at the end: no half-written folder looks complete.

use crate::PerturbError;
use datasets::settings::{write_settings, CameraSettings, SettingsFormat};
use datasets::{Format, FrameReader, Sequence};
use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};
use nalgebra::Isometry3;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

fn werr(path: &Path, e: impl std::fmt::Display) -> PerturbError {
    PerturbError::Write {
        path: path.to_path_buf(),
        msg: e.to_string(),
    }
}

fn text(path: &Path, s: &str) -> Result<(), PerturbError> {
    std::fs::write(path, s).map_err(|e| werr(path, e))
}

fn png(
    path: &Path,
    data: &[u8],
    w: usize,
    h: usize,
    ty: ExtendedColorType,
) -> Result<(), PerturbError> {
    let file = std::fs::File::create(path).map_err(|e| werr(path, e))?;
    let enc = PngEncoder::new_with_quality(
        std::io::BufWriter::new(file),
        CompressionType::Fast,
        FilterType::Sub,
    );
    enc.write_image(data, w as u32, h as u32, ty)
        .map_err(|e| werr(path, e))
}

/// The whole nanoseconds an EuRoC file stores for stamp `t` seconds: the value that
/// `datasets::euroc::ns_to_s` reads back to exactly `t`.
pub fn stamp_ns(t: f64) -> i64 {
    let secs = t.floor();
    let base = secs as i64 * 1_000_000_000 + ((t - secs) * 1e9).round() as i64;
    for k in 0..1000i64 {
        for cand in [base + k, base - k] {
            if datasets::euroc::ns_to_s(cand) == t {
                return cand;
            }
        }
    }
    base
}

fn pose_digits(p: &Isometry3<f64>) -> ([f64; 3], [f64; 4]) {
    let v = p.translation.vector;
    let q = p.rotation.coords; // x, y, z, w
    ([v.x, v.y, v.z], [q.w, q.x, q.y, q.z])
}

/// Writes `frames` of `seq` into `dir` (which must not exist or be empty) in the layout of its
/// sensor; `note` goes into `perturbation.txt` (what was applied, with which seed), `progress`
/// gets the frames written so far. `source`: the folder the sequence was read from, if any: its
/// ground-truth file is copied as distributed (byte for byte) rather than written anew.
pub fn write_folder(
    seq: &Sequence,
    frames: &FrameReader,
    dir: &Path,
    note: &str,
    source: Option<&Path>,
    progress: impl Fn(usize) + Sync,
) -> Result<(), PerturbError> {
    if dir.exists()
        && std::fs::read_dir(dir)
            .map_err(|e| werr(dir, e))?
            .next()
            .is_some()
    {
        return Err(werr(dir, "the output folder exists and is not empty"));
    }
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let parent = match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent).map_err(|e| werr(&parent, e))?;
    let tmp = parent.join(format!(".{name}.tmp-{}", std::process::id()));
    if tmp.exists() {
        std::fs::remove_dir_all(&tmp).map_err(|e| werr(&tmp, e))?;
    }
    std::fs::create_dir_all(&tmp).map_err(|e| werr(&tmp, e))?;
    let written = match seq.format {
        Format::TumRgbd => write_tum(seq, frames, &tmp, &progress),
        Format::EurocStereo => write_euroc(seq, frames, &tmp, &progress),
    }
    .and_then(|()| copy_groundtruth(seq.format, source, &tmp))
    .and_then(|()| {
        for format in [SettingsFormat::Orbslam2, SettingsFormat::Orbslam3] {
            let s = write_settings(
                &CameraSettings::of_camera(&seq.camera, seq.depth_factor, None),
                format,
                &seq.name,
            );
            text(&tmp.join(format!("camera-{}.yaml", format.name())), &s)?;
        }
        text(&tmp.join("perturbation.txt"), &format!("{note}\n"))
    });
    if let Err(e) = written {
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(e);
    }
    if dir.exists() {
        std::fs::remove_dir(dir).map_err(|e| werr(dir, e))?;
    }
    std::fs::rename(&tmp, dir).map_err(|e| werr(dir, e))
}

/// The ground-truth file of a source folder, where it has one, copied over the one written from
/// memory.
fn copy_groundtruth(
    format: Format,
    source: Option<&Path>,
    root: &Path,
) -> Result<(), PerturbError> {
    let Some(src) = source else { return Ok(()) };
    let rel = match format {
        Format::TumRgbd => "groundtruth.txt",
        Format::EurocStereo => "mav0/state_groundtruth_estimate0/data.csv",
    };
    let mut from = src.join(rel);
    if format == Format::EurocStereo && !from.is_file() {
        // A folder that is mav0 itself.
        from = src.join("state_groundtruth_estimate0/data.csv");
    }
    if from.is_file() {
        let to = root.join(rel);
        if let Some(parent) = to.parent() {
            std::fs::create_dir_all(parent).map_err(|e| werr(parent, e))?;
        }
        std::fs::copy(&from, &to).map_err(|e| werr(&from, e))?;
    }
    Ok(())
}

fn write_tum(
    seq: &Sequence,
    frames: &FrameReader,
    root: &Path,
    progress: &(impl Fn(usize) + Sync),
) -> Result<(), PerturbError> {
    let units = seq
        .depth_factor
        .unwrap_or(crate::apply::DEFAULT_DEPTH_UNITS);
    for d in ["rgb", "depth"] {
        std::fs::create_dir_all(root.join(d)).map_err(|e| werr(&root.join(d), e))?;
    }
    let done = AtomicUsize::new(0);
    let stamps: Vec<(f64, bool)> = (0..frames.len())
        .into_par_iter()
        .map(|i| -> Result<(f64, bool), PerturbError> {
            let f = frames.read(i)?;
            let file = format!("{:06}.png", i);
            // Colour stays colour (its grey, as a reader makes it, is what slam-core saw).
            match &f.colour {
                Some(c) => png(
                    &root.join("rgb").join(&file),
                    &c.data,
                    c.width,
                    c.height,
                    ExtendedColorType::Rgb8,
                )?,
                None => png(
                    &root.join("rgb").join(&file),
                    &f.image.data,
                    f.image.width,
                    f.image.height,
                    ExtendedColorType::L8,
                )?,
            }
            let d = f
                .depth
                .as_ref()
                .ok_or_else(|| werr(root, format!("frame {i} has no depth image")))?;
            let mut bytes = Vec::with_capacity(d.data.len() * 2);
            for &z in &d.data {
                let v = (z as f64 * units).round();
                let v = if v.is_finite() && v > 0.0 {
                    v.min(65535.0) as u16
                } else {
                    0
                };
                bytes.extend_from_slice(&v.to_ne_bytes());
            }
            png(
                &root.join("depth").join(&file),
                &bytes,
                d.width,
                d.height,
                ExtendedColorType::L16,
            )?;
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            Ok((f.timestamp, f.colour.is_some()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let colour = stamps.first().is_some_and(|s| s.1);
    let stamps: Vec<f64> = stamps.into_iter().map(|s| s.0).collect();
    let (mut rgb, mut depth, mut assoc) = (
        format!(
            "# {} images (noisefree perturb)\n# timestamp filename\n",
            if colour { "colour" } else { "grey" }
        ),
        String::from("# depth maps (noisefree perturb)\n# timestamp filename\n"),
        String::new(),
    );
    for (i, t) in stamps.iter().enumerate() {
        let _ = writeln!(rgb, "{t} rgb/{i:06}.png");
        let _ = writeln!(depth, "{t} depth/{i:06}.png");
        let _ = writeln!(assoc, "{t} rgb/{i:06}.png {t} depth/{i:06}.png");
    }
    text(&root.join("rgb.txt"), &rgb)?;
    text(&root.join("depth.txt"), &depth)?;
    text(&root.join("associations.txt"), &assoc)?;
    if let Some(gt) = &seq.groundtruth {
        let mut s = String::from("# timestamp tx ty tz qx qy qz qw\n");
        for (t, p) in gt.stamps.iter().zip(&gt.poses) {
            let (v, q) = pose_digits(p);
            let _ = writeln!(
                s,
                "{t} {} {} {} {} {} {} {}",
                v[0], v[1], v[2], q[1], q[2], q[3], q[0]
            );
        }
        text(&root.join("groundtruth.txt"), &s)?;
    }
    Ok(())
}

fn sensor_yaml(t_bs: &Isometry3<f64>, c: &slam_core::Camera, title: &str) -> String {
    let m = t_bs.to_homogeneous();
    let row = |r: usize| {
        format!(
            "{:?}, {:?}, {:?}, {:?}",
            m[(r, 0)],
            m[(r, 1)],
            m[(r, 2)],
            m[(r, 3)]
        )
    };
    format!(
        "%YAML:1.0\nsensor_type: camera\ncomment: {title} (noisefree perturb, rectified pinhole)\n\
         T_BS:\n  cols: 4\n  rows: 4\n  data: [{},\n         {},\n         {},\n         0.0, 0.0, 0.0, 1.0]\n\
         rate_hz: {:?}\nresolution: [{}, {}]\ncamera_model: pinhole\n\
         intrinsics: [{:?}, {:?}, {:?}, {:?}] #fu, fv, cu, cv\n\
         distortion_model: radial-tangential\ndistortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n",
        row(0),
        row(1),
        row(2),
        if c.fps > 0.0 { c.fps } else { 20.0 },
        c.width,
        c.height,
        c.fx,
        c.fy,
        c.cx,
        c.cy
    )
}

fn write_euroc(
    seq: &Sequence,
    frames: &FrameReader,
    root: &Path,
    progress: &(impl Fn(usize) + Sync),
) -> Result<(), PerturbError> {
    let mav = root.join("mav0");
    let cams = [mav.join("cam0"), mav.join("cam1")];
    for c in &cams {
        std::fs::create_dir_all(c.join("data")).map_err(|e| werr(c, e))?;
    }
    let done = AtomicUsize::new(0);
    let stamps: Vec<i64> = (0..frames.len())
        .into_par_iter()
        .map(|i| -> Result<i64, PerturbError> {
            let f = frames.read(i)?;
            let ns = stamp_ns(f.timestamp);
            let file = format!("{ns}.png");
            let r = f
                .right
                .as_ref()
                .ok_or_else(|| werr(root, format!("frame {i} has no right image")))?;
            for (img, cam) in [(&f.image, &cams[0]), (r, &cams[1])] {
                png(
                    &cam.join("data").join(&file),
                    &img.data,
                    img.width,
                    img.height,
                    ExtendedColorType::L8,
                )?;
            }
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            Ok(ns)
        })
        .collect::<Result<_, _>>()?;
    let mut csv = String::from("#timestamp [ns],filename\n");
    for ns in &stamps {
        let _ = writeln!(csv, "{ns},{ns}.png");
    }
    // The rectified pair: cam0 at the sequence's body-camera pose, cam1 `baseline` along its x.
    let t_b0 = seq.t_bs.unwrap_or_else(Isometry3::identity);
    let baseline = seq.camera.bf / seq.camera.fx;
    let t_b1 = t_b0 * Isometry3::translation(baseline, 0.0, 0.0);
    for (cam, t) in cams.iter().zip([t_b0, t_b1]) {
        text(&cam.join("data.csv"), &csv)?;
        text(
            &cam.join("sensor.yaml"),
            &sensor_yaml(&t, &seq.camera, &seq.name),
        )?;
    }
    if let Some(gt) = &seq.groundtruth {
        let dir = mav.join("state_groundtruth_estimate0");
        std::fs::create_dir_all(&dir).map_err(|e| werr(&dir, e))?;
        let mut s = String::from(
            "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n",
        );
        for (t, p) in gt.stamps.iter().zip(&gt.poses) {
            let (v, q) = pose_digits(p);
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{}",
                stamp_ns(*t),
                v[0],
                v[1],
                v[2],
                q[0],
                q[1],
                q[2],
                q[3]
            );
        }
        text(&dir.join("data.csv"), &s)?;
    }
    Ok(())
}
