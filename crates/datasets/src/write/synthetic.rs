//! A generated sequence written as the folder of its sensor: the TUM RGB-D layout for RGB-D
//! (`rgb/<stamp>.png` 8-bit RGB, `depth/<stamp>.png` 16-bit at the configuration's units per
//! metre, each image named by its own stream's stamp; the associations TUM's associate.py
//! finds, [`synth::Generator::stream_pairs`]; the ground truth with the configuration's
//! motion-capture noise and clock) and the EuRoC ASL layout for stereo (the BODY pose as
//! ground truth; a rectified pinhole pair for the `stereo` preset, or a calibrated rig's raw,
//! distorted images with each camera's intrinsics, distortion and T_BS, so a reader rectifies
//! them as it does real EuRoC data).
//!
//! An RGB-D folder carries its camera as `camera-orbslam2.yaml` and `camera-orbslam3.yaml`, which
//! `run --path` reads before any guess from the folder's name (a twin of fr1 under any name is
//! read with fr1's camera).
//!
//! The camera is not at the body origin (see [`synth::output::body`]), so readers that forget
//! the body-to-camera conversion get a visibly wrong trajectory.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use image::ExtendedColorType;
use rayon::prelude::*;
use synth::motion::clock::stamp_name;
use synth::output::body::{body_from_cam1, body_from_left, groundtruth_body};
use synth::Generator;

use super::euroc::{self, EurocLists, EurocSensor};
use super::files::{depth_png, mkdir, png, write_atomically};
use super::tum::{self, TumEntry, TumLists};
use super::Digits;
use crate::settings::CameraSettings;
use crate::DatasetError;

/// Writes frames `0..n` of `gen` into `dir`: TUM RGB-D for an RGB-D configuration, EuRoC ASL
/// for stereo. Frames are rendered and encoded in parallel; `progress(k)` gets the frames
/// written so far. `dir` must not exist or be empty; frames beyond a recorded trajectory are
/// refused first. The same configuration, seed and `n` always give the same bytes.
pub fn write_synthetic(
    gen: &Generator,
    n: usize,
    dir: &Path,
    progress: impl Fn(usize) + Sync,
) -> Result<(), DatasetError> {
    gen.check_frames(n)?;
    write_atomically(dir, |root| {
        if gen.config().is_rgbd() {
            write_tum(gen, n, root, &progress)?;
            super::sequence::camera_files(
                root,
                &CameraSettings::of_camera(
                    &gen.camera(),
                    Some(gen.config().depth_units_per_metre),
                    None,
                ),
                &title(gen),
            )
        } else {
            write_euroc(gen, n, root, &progress)
        }
    })
}

/// The title of the lists: the seed and the trajectory.
fn title(gen: &Generator) -> String {
    format!(
        "synthetic noisefree sequence, seed {}, trajectory {}",
        gen.seed(),
        gen.config().trajectory.name()
    )
}

fn write_tum(
    gen: &Generator,
    n: usize,
    root: &Path,
    progress: &(impl Fn(usize) + Sync),
) -> Result<(), DatasetError> {
    let (rgb_dir, depth_dir) = (root.join("rgb"), root.join("depth"));
    mkdir(&rgb_dir)?;
    mkdir(&depth_dir)?;
    let done = AtomicUsize::new(0);
    let units = gen.config().depth_units_per_metre;
    (0..n)
        .into_par_iter()
        .try_for_each(|i| -> Result<(), DatasetError> {
            let f = gen.frame(i);
            let (w, h) = (f.gray.width, f.gray.height);
            if let Some(rgb) = &f.rgb {
                let name = format!("{}.png", stamp_name(f.timestamp));
                png(&rgb_dir.join(name), rgb, w, h, ExtendedColorType::Rgb8)?;
            }
            if let Some(d) = &f.depth {
                let name = format!("{}.png", stamp_name(gen.depth_timestamp(i)));
                depth_png(&depth_dir.join(name), &d.data, w, h, units)?;
            }
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            Ok(())
        })?;
    let entry = |dir: &str, t: f64| TumEntry {
        stamp: t,
        file: format!("{dir}/{}.png", stamp_name(t)),
    };
    tum::write_lists(
        root,
        &TumLists {
            title: title(gen),
            colour: true,
            rgb: (0..n).map(|i| entry("rgb", gen.timestamp(i))).collect(),
            depth: (0..n)
                .map(|i| entry("depth", gen.depth_timestamp(i)))
                .collect(),
            associations: gen.stream_pairs(n),
            groundtruth: Some(gen.groundtruth(n)),
            digits: Digits::Dataset,
        },
    )
}

fn write_euroc(
    gen: &Generator,
    n: usize,
    root: &Path,
    progress: &(impl Fn(usize) + Sync),
) -> Result<(), DatasetError> {
    euroc::create_folders(root)?;
    let done = AtomicUsize::new(0);
    let stamp = |i: usize| gen.stamp_ns(i) as i64;
    (0..n)
        .into_par_iter()
        .try_for_each(|i| -> Result<(), DatasetError> {
            let f = gen.frame(i);
            let (w, h) = (f.gray.width, f.gray.height);
            let left = euroc::image_path(root, 0, stamp(i));
            png(&left, &f.gray.data, w, h, ExtendedColorType::L8)?;
            if let Some(r) = &f.right {
                let right = euroc::image_path(root, 1, stamp(i));
                png(&right, &r.data, w, h, ExtendedColorType::L8)?;
            }
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            Ok(())
        })?;
    let rig = gen.config().rig.as_ref();
    let left = gen.camera();
    let (right, t_bs1) = match rig {
        Some(r) => (r.right.clone(), r.body_from_right()),
        None => (left.clone(), body_from_cam1(left.baseline())),
    };
    let kind = if rig.is_some() {
        "raw, distorted"
    } else {
        "rectified pinhole"
    };
    let sensor = |name: &str, t_bs, camera: slam_core::Camera| EurocSensor {
        comment: format!("synthetic noisefree {name} (seed {}, {kind})", gen.seed()),
        t_bs,
        // Every digit of a rig's T_BS, so the reader's rectification is the in-memory one's.
        t_bs_digits: if rig.is_some() {
            Digits::Exact
        } else {
            Digits::Dataset
        },
        distortion: match (rig, camera.distortion) {
            (Some(_), Some(d)) => Some([d.k1, d.k2, d.p1, d.p2]),
            _ => None,
        },
        camera,
    };
    euroc::write_lists(
        root,
        &EurocLists {
            stamps_ns: (0..n).map(stamp).collect(),
            sensors: [
                sensor("cam0", body_from_left(gen), left),
                sensor("cam1", t_bs1, right),
            ],
            body_comment: "synthetic noisefree body (IMU) frame".into(),
            groundtruth: Some(
                (0..n)
                    .map(|i| (stamp(i), groundtruth_body(gen, i)))
                    .collect(),
            ),
            digits: Digits::Dataset,
        },
    )
}
