//! Any sequence noisefree can read — real, synthetic, a twin, perturbed or not — written as a
//! folder other tools read, in the layout of its sensor, with `camera-orbslam2.yaml` and
//! `camera-orbslam3.yaml` beside it (the sequence's camera as ORB-SLAM2 / ORB-SLAM3 settings,
//! which `noisefree run --path DIR --camera` reads back). Images keep the input's pixel
//! format: 8-bit RGB PNGs where the input had colour (whose grey, as the readers make it, is
//! what slam-core saw), 8-bit grey otherwise; depth as 16-bit PNGs at the sequence's depth
//! factor; stamps and poses with every digit ([`Digits::Exact`]), so noisefree reading the
//! folder gets the bits it wrote. A stereo sequence is written as the rectified pinhole pair
//! slam-core saw.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use image::ExtendedColorType;
use nalgebra::Isometry3;
use rayon::prelude::*;

use super::euroc::{self, stamp_ns, EurocLists, EurocSensor};
use super::files::{depth_png, mkdir, png, text, write_atomically};
use super::tum::{self, TumEntry, TumLists};
use super::Digits;
use crate::settings::{write_settings, CameraSettings, SettingsFormat};
use crate::{DatasetError, Format, FrameReader, Sequence};

/// The depth factor written when a sequence does not say its own (TUM's 5000 per metre).
pub const DEFAULT_DEPTH_UNITS: f64 = 5000.0;

/// Writes the frames of `frames` (the images of `seq`) into `dir`, which must not exist or be
/// empty, plus `extra` files (name, content) at its top. `source`: the folder the sequence was
/// read from, if any: its ground-truth file is copied as distributed (byte for byte) rather
/// than written anew. `progress(k)` gets the frames written so far. Everything goes through a
/// staging folder: no half-written folder looks complete.
pub fn write_sequence(
    seq: &Sequence,
    frames: &FrameReader,
    dir: &Path,
    extra: &[(&str, String)],
    source: Option<&Path>,
    progress: impl Fn(usize) + Sync,
) -> Result<(), DatasetError> {
    write_atomically(dir, |root| {
        match seq.format {
            Format::TumRgbd => write_tum(seq, frames, root, &progress)?,
            Format::EurocStereo => write_euroc(seq, frames, root, &progress)?,
        }
        copy_groundtruth(seq.format, source, root)?;
        camera_files(
            root,
            &CameraSettings::of_camera(&seq.camera, seq.depth_factor, None),
            &seq.name,
        )?;
        for (name, content) in extra {
            text(&root.join(name), content)?;
        }
        Ok(())
    })
}

/// The folder's camera as `camera-orbslam2.yaml` and `camera-orbslam3.yaml` at its top: the
/// camera `noisefree run --path` reads the folder with ([`crate::folder_settings`]) and the one
/// another SLAM system is given, so nobody guesses it from the folder's name.
pub(super) fn camera_files(
    root: &Path,
    settings: &CameraSettings,
    title: &str,
) -> Result<(), DatasetError> {
    for format in [SettingsFormat::Orbslam2, SettingsFormat::Orbslam3] {
        let s = write_settings(settings, format, title);
        text(&root.join(format!("camera-{}.yaml", format.name())), &s)?;
    }
    Ok(())
}

/// The ground-truth file of a source folder, where it has one, copied over the one written from
/// memory.
fn copy_groundtruth(
    format: Format,
    source: Option<&Path>,
    root: &Path,
) -> Result<(), DatasetError> {
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
            mkdir(parent)?;
        }
        std::fs::copy(&from, &to).map_err(|e| DatasetError::io(&from, e))?;
    }
    Ok(())
}

fn write_tum(
    seq: &Sequence,
    frames: &FrameReader,
    root: &Path,
    progress: &(impl Fn(usize) + Sync),
) -> Result<(), DatasetError> {
    let units = seq.depth_factor.unwrap_or(DEFAULT_DEPTH_UNITS);
    mkdir(&root.join("rgb"))?;
    mkdir(&root.join("depth"))?;
    let done = AtomicUsize::new(0);
    let stamps: Vec<(f64, bool)> = (0..frames.len())
        .into_par_iter()
        .map(|i| -> Result<(f64, bool), DatasetError> {
            let f = frames.read(i)?;
            let file = format!("{i:06}.png");
            // Colour stays colour (its grey, as a reader makes it, is what slam-core saw).
            let rgb = root.join("rgb").join(&file);
            match &f.colour {
                Some(c) => png(&rgb, &c.data, c.width, c.height, ExtendedColorType::Rgb8)?,
                None => png(
                    &rgb,
                    &f.image.data,
                    f.image.width,
                    f.image.height,
                    ExtendedColorType::L8,
                )?,
            }
            let d = f.depth.as_ref().ok_or_else(|| {
                DatasetError::invalid(root, format!("frame {i} has no depth image"))
            })?;
            depth_png(
                &root.join("depth").join(&file),
                &d.data,
                d.width,
                d.height,
                units,
            )?;
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            Ok((f.timestamp, f.colour.is_some()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let entry = |dir: &str, i: usize, t: f64| TumEntry {
        stamp: t,
        file: format!("{dir}/{i:06}.png"),
    };
    let groundtruth = seq.groundtruth.as_ref().map(|gt| {
        gt.stamps
            .iter()
            .copied()
            .zip(gt.poses.iter().copied())
            .collect::<Vec<(f64, Isometry3<f64>)>>()
    });
    tum::write_lists(
        root,
        &TumLists {
            title: format!("{} (noisefree)", seq.name),
            colour: stamps.first().is_some_and(|s| s.1),
            rgb: stamps
                .iter()
                .enumerate()
                .map(|(i, s)| entry("rgb", i, s.0))
                .collect(),
            depth: stamps
                .iter()
                .enumerate()
                .map(|(i, s)| entry("depth", i, s.0))
                .collect(),
            associations: (0..stamps.len()).map(|i| (i, i)).collect(),
            groundtruth,
            digits: Digits::Exact,
        },
    )
}

fn write_euroc(
    seq: &Sequence,
    frames: &FrameReader,
    root: &Path,
    progress: &(impl Fn(usize) + Sync),
) -> Result<(), DatasetError> {
    euroc::create_folders(root)?;
    let done = AtomicUsize::new(0);
    let stamps: Vec<i64> = (0..frames.len())
        .into_par_iter()
        .map(|i| -> Result<i64, DatasetError> {
            let f = frames.read(i)?;
            let ns = stamp_ns(f.timestamp);
            let r = f.right.as_ref().ok_or_else(|| {
                DatasetError::invalid(root, format!("frame {i} has no right image"))
            })?;
            for (cam, img) in [&f.image, r].into_iter().enumerate() {
                let path = euroc::image_path(root, cam, ns);
                png(
                    &path,
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
    // The rectified pair: cam0 at the sequence's body-camera pose, cam1 `baseline` along its x.
    let t_b0 = seq.t_bs.unwrap_or_else(Isometry3::identity);
    let baseline = seq.camera.bf / seq.camera.fx;
    let t_b1 = t_b0 * Isometry3::translation(baseline, 0.0, 0.0);
    let mut camera = seq.camera.clone();
    if camera.fps <= 0.0 {
        // EuRoC's rate where the sequence does not say.
        camera.fps = 20.0;
    }
    let sensor = |name: &str, t_bs| EurocSensor {
        comment: format!("{} {name} (noisefree, rectified pinhole)", seq.name),
        t_bs,
        t_bs_digits: Digits::Exact,
        camera: camera.clone(),
        distortion: None,
    };
    let groundtruth = seq.groundtruth.as_ref().map(|gt| {
        gt.stamps
            .iter()
            .map(|&t| stamp_ns(t))
            .zip(gt.poses.iter().copied())
            .collect()
    });
    euroc::write_lists(
        root,
        &EurocLists {
            stamps_ns: stamps,
            sensors: [sensor("cam0", t_b0), sensor("cam1", t_b1)],
            body_comment: format!("{} body (IMU) frame (noisefree)", seq.name),
            groundtruth,
            digits: Digits::Exact,
        },
    )
}
