//! The recording, written with the official `rerun` crate: a run's frames as they were tracked
//! ([`record_run`]) and any trajectory files beside a ground truth ([`view`]). Entity paths:
//! [`super::ENTITY_PATHS`].

use super::avc::{sample_virtual_cameras, VirtualCameraSample};
use super::fate::{keypoint_fates, Fate};
use super::output;
use crate::runner::{run_observed, ExtractedSequence, Observation, RunOutcome};
use anyhow::{Context, Result};
use ate_eval::{evaluate_ate, AteOptions, Trajectory};
use datasets::{FrameReader, Sequence};
use image::ImageEncoder;
use nalgebra::Isometry3;
use rerun::RecordingStream;
use slam_core::place::Vocabulary;
use slam_core::system::Config;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Runs `config` over `seq` as [`crate::runner::run_sequence`] does (or over `extracted`),
/// recording every frame into `path`: the images `images` gives (the perturbed ones when the
/// run is perturbed), each keypoint's fate, the map at each keyframe, the events and the
/// per-frame scalars; then the estimate placed on the ground truth as `eval` aligns it, with
/// each frame's error. The trajectory is the unrecorded run's, bit for bit.
pub fn record_run(
    path: &Path,
    seq: &Sequence,
    images: &FrameReader,
    extracted: Option<&ExtractedSequence>,
    config: &Config,
    vocabulary: Option<&Arc<Vocabulary>>,
    on_frame: impl FnMut(usize),
) -> Result<RunOutcome> {
    let tmp = output::partial(path);
    let rec = rerun::RecordingStreamBuilder::new("noisefree")
        .save(&tmp)
        .with_context(|| format!("creating {}", tmp.display()))?;
    let c = &seq.camera;
    rec.log_static(
        "world/slam/camera/image",
        &rerun::Pinhole::new([
            [c.fx as f32, 0.0, 0.0],
            [0.0, c.fy as f32, 0.0],
            [c.cx as f32, c.cy as f32, 1.0],
        ])
        .with_resolution([c.width as f32, c.height as f32]),
    )?;
    let mut first_error: Option<anyhow::Error> = None;
    let outcome = run_observed(seq, extracted, config, vocabulary, on_frame, |o| {
        if first_error.is_none() {
            if let Err(e) = frame(&rec, images, o) {
                first_error = Some(e.context(format!("recording frame {}", o.index)));
            }
        }
    });
    if let Some(e) = first_error {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    trajectory(&rec, seq, &outcome)?;
    rec.flush_blocking()
        .with_context(|| format!("writing {}", tmp.display()))?;
    drop(rec);
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))?;
    Ok(outcome)
}

/// The frame's timelines: its index, and its stamp (a duration when it is not a date).
fn set_time(rec: &RecordingStream, index: usize, stamp: f64) {
    rec.set_time_sequence("frame", index as i64);
    if stamp > 1e8 {
        rec.set_timestamp_secs_since_epoch("time", stamp);
    } else {
        rec.set_duration_secs("time", stamp);
    }
}

/// One frame: images, keypoints by fate, scalars, events and, at a keyframe, the map.
fn frame(rec: &RecordingStream, images: &FrameReader, o: &Observation<'_>) -> Result<()> {
    let stats = &o.result.stats;
    set_time(rec, o.index, stats.timestamp);
    let input = images.read(o.index)?;
    let root = "world/slam/camera/image";
    match &input.colour {
        Some(c) => rec.log(
            format!("{root}/colour"),
            &jpeg(&c.data, c.width, c.height, image::ExtendedColorType::Rgb8)?,
        )?,
        None => rec.log(
            format!("{root}/colour"),
            &jpeg(
                &input.image.data,
                input.image.width,
                input.image.height,
                image::ExtendedColorType::L8,
            )?,
        )?,
    }
    if let Some(d) = &input.depth {
        let mm: Vec<u16> = d
            .data
            .iter()
            .map(|&z| {
                if z.is_finite() && z > 0.0 {
                    (z * 1000.0).round().min(65535.0) as u16
                } else {
                    0
                }
            })
            .collect();
        let mut png = Vec::new();
        image::codecs::png::PngEncoder::new(&mut png).write_image(
            &mm.iter().flat_map(|v| v.to_be_bytes()).collect::<Vec<u8>>(),
            d.width as u32,
            d.height as u32,
            image::ExtendedColorType::L16,
        )?;
        rec.log(
            format!("{root}/depth"),
            &rerun::EncodedDepthImage::new(png)
                .with_media_type(rerun::MediaType::png())
                .with_meter(1000.0),
        )?;
    }
    if let Some(r) = &input.right {
        rec.log(
            format!("{root}/right"),
            &jpeg(&r.data, r.width, r.height, image::ExtendedColorType::L8)?,
        )?;
    }
    let Some(frame) = o.system.last_frame() else {
        return Ok(());
    };
    let last = o.final_optimization();
    let fates = keypoint_fates(frame, last);
    // Which thresholds each MC-OR rejection exceeded, by keypoint.
    let exceeded: HashMap<usize, String> = last
        .map_or(&[][..], |r| &r.matches[..])
        .iter()
        .filter(|m| m.mcor_exceeded.any())
        .map(|m| (m.keypoint, m.mcor_exceeded.names()))
        .collect();
    for fate in Fate::ALL {
        let (points, labels): (Vec<[f32; 2]>, Vec<String>) = fates
            .iter()
            .zip(&frame.features.keypoints)
            .enumerate()
            .filter(|(_, (f, _))| **f == fate)
            .map(|(i, (_, k))| ([k.x, k.y], exceeded.get(&i).cloned().unwrap_or_default()))
            .unzip();
        let [r, g, b] = fate.colour();
        let mut points = rerun::Points2D::new(points)
            .with_colors([rerun::Color::from_rgb(r, g, b)])
            .with_radii([2.5]);
        if matches!(fate, Fate::McorCluster | Fate::McorFeature) {
            points = points.with_labels(labels).with_show_labels(false);
        }
        rec.log(format!("{root}/keypoints/{}", fate.name()), &points)?;
    }
    if let (Some(avc), Some(last)) = (&o.system.config().avc, last) {
        virtual_cameras(
            rec,
            &sample_virtual_cameras(frame, last, o.system.camera(), avc.baseline),
        )?;
    }
    for (name, v) in [
        ("inliers", stats.n_inliers as f64),
        ("outliers", stats.n_outliers as f64),
        (
            "mcor_rejected",
            (stats.n_mcor_rejected_clusters + stats.n_mcor_rejected_features) as f64,
        ),
        ("tracking_ms", stats.time_tracking_ms),
        ("mapping_ms", stats.time_mapping_ms + stats.time_ba_ms),
    ] {
        rec.log(format!("stats/{name}"), &rerun::Scalars::new([v]))?;
    }
    for (happened, what) in [
        (stats.relocalized, "relocalized"),
        (stats.loop_closed, "loop closed"),
        (stats.keyframe_inserted, "keyframe"),
    ] {
        if happened {
            rec.log(
                "events",
                &rerun::TextLog::new(format!("frame {}: {what}", o.index)),
            )?;
        }
    }
    if stats.keyframe_inserted {
        map(rec, o)?;
    }
    Ok(())
}

/// AVC's virtual cameras of a frame's sampled matches, in the camera's frame: the centres C',
/// and from each a ray to the measured point D (yellow) and to the map point M (cyan).
fn virtual_cameras(rec: &RecordingStream, samples: &[VirtualCameraSample]) -> Result<()> {
    let f32s = |v: &nalgebra::Vector3<f64>| -> [f32; 3] { v.map(|x| x as f32).into() };
    let centres: Vec<[f32; 3]> = samples.iter().map(|s| f32s(&s.centre)).collect();
    rec.log(
        "world/slam/camera/avc/virtual_cameras",
        &rerun::Points3D::new(centres)
            .with_colors([rerun::Color::from_rgb(255, 220, 0)])
            .with_radii([0.005])
            .with_labels(
                samples
                    .iter()
                    .map(|s| format!("C' of keypoint {}", s.keypoint)),
            ),
    )?;
    let mut rays = Vec::new();
    let mut colours = Vec::new();
    for s in samples {
        rays.push(vec![f32s(&s.centre), f32s(&s.measured)]);
        colours.push(rerun::Color::from_rgb(255, 220, 0));
        rays.push(vec![f32s(&s.centre), f32s(&s.map_point)]);
        colours.push(rerun::Color::from_rgb(0, 220, 255));
    }
    rec.log(
        "world/slam/camera/avc/rays",
        &rerun::LineStrips3D::new(rays).with_colors(colours),
    )?;
    Ok(())
}

/// The map as a keyframe left it: points coloured by how many keyframes see them (red: one,
/// green: ten or more), keyframe centres, and the newest keyframe's covisibility edges.
fn map(rec: &RecordingStream, o: &Observation<'_>) -> Result<()> {
    let map = o.system.map();
    let (mut points, mut colours) = (Vec::new(), Vec::new());
    for p in map.map_points().filter(|p| !p.bad) {
        points.push(p.position.map(|x| x as f32).into());
        let t = (p.observations.len().min(10) as f32) / 10.0;
        colours.push(rerun::Color::from_rgb(
            (255.0 * (1.0 - t)) as u8,
            (255.0 * t) as u8,
            60,
        ));
    }
    let points: Vec<[f32; 3]> = points;
    rec.log(
        "world/slam/map/points",
        &rerun::Points3D::new(points)
            .with_colors(colours)
            .with_radii([0.01]),
    )?;
    let keyframes: Vec<_> = map.keyframes().filter(|k| !k.bad).collect();
    let centres: Vec<[f32; 3]> = keyframes
        .iter()
        .map(|k| k.center().map(|x| x as f32).into())
        .collect();
    rec.log(
        "world/slam/map/keyframes",
        &rerun::Points3D::new(centres)
            .with_colors([rerun::Color::from_rgb(60, 120, 255)])
            .with_radii([0.02]),
    )?;
    if let Some(newest) = keyframes.iter().max_by_key(|k| k.id) {
        let a: [f32; 3] = newest.center().map(|x| x as f32).into();
        let edges: Vec<Vec<[f32; 3]>> = newest
            .covisibles()
            .into_iter()
            .filter_map(|k| map.keyframe_any(k))
            .map(|k| vec![a, k.center().map(|x| x as f32).into()])
            .collect();
        rec.log(
            "world/slam/map/covisibility",
            &rerun::LineStrips3D::new(edges).with_colors([rerun::Color::from_rgb(120, 200, 255)]),
        )?;
    }
    Ok(())
}

/// An 8-bit image as a JPEG the recording carries (a raw frame would be 10 to 40 times larger).
fn jpeg(
    data: &[u8],
    width: usize,
    height: usize,
    colour: image::ExtendedColorType,
) -> Result<rerun::EncodedImage> {
    let mut bytes = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 85).write_image(
        data,
        width as u32,
        height as u32,
        colour,
    )?;
    Ok(rerun::EncodedImage::new(bytes).with_media_type(rerun::MediaType::jpeg()))
}

/// The SLAM world placed on the ground truth as `eval` places it (SE(3), the estimate in the
/// ground truth's frame: EuRoC's body through T_BS), the two paths, the camera per frame and
/// each frame's translational error.
fn trajectory(rec: &RecordingStream, seq: &Sequence, outcome: &RunOutcome) -> Result<()> {
    let est = &outcome.trajectory;
    let index: HashMap<u64, usize> = outcome
        .stats
        .iter()
        .enumerate()
        .map(|(i, s)| (s.timestamp.to_bits(), i))
        .collect();
    // The run's own score ([`crate::runner`]): the alignment and errors `eval` gives.
    let ate = &outcome.ate;
    let alignment = ate
        .as_ref()
        .map_or(Isometry3::identity(), |a| a.alignment.rt);
    rec.log_static("world/slam", &transform(&alignment))?;
    if let Some(gt) = &seq.groundtruth {
        rec.log_static(
            "world/groundtruth",
            &path_strip(gt).with_colors([rerun::Color::from_rgb(90, 90, 90)]),
        )?;
    }
    rec.log_static(
        "world/slam/estimate",
        &path_strip(est).with_colors([rerun::Color::from_rgb(230, 120, 20)]),
    )?;
    for (stamp, pose) in est.stamps.iter().zip(&est.poses) {
        let Some(&i) = index.get(&stamp.to_bits()) else {
            continue;
        };
        set_time(rec, i, *stamp);
        rec.log("world/slam/camera", &transform(pose))?;
    }
    if let Some(ate) = &ate {
        for (&(_, e), err) in ate.pairs.iter().zip(&ate.errors) {
            let stamp = est.stamps[e];
            if let Some(&i) = index.get(&stamp.to_bits()) {
                set_time(rec, i, stamp);
                rec.log("stats/error_m", &rerun::Scalars::new([*err]))?;
            }
        }
    }
    Ok(())
}

/// A pose (sensor to world) as a Rerun transform of its entity into its parent's frame.
fn transform(pose: &Isometry3<f64>) -> rerun::Transform3D {
    let t = pose.translation.vector.map(|x| x as f32);
    let q = pose.rotation.coords.map(|x| x as f32);
    rerun::Transform3D::from_translation_rotation(
        [t.x, t.y, t.z],
        rerun::Quaternion::from_xyzw([q.x, q.y, q.z, q.w]),
    )
}

/// A trajectory's positions as one line strip.
fn path_strip(t: &Trajectory) -> rerun::LineStrips3D {
    let strip: Vec<[f32; 3]> = t
        .poses
        .iter()
        .map(|p| p.translation.vector.map(|x| x as f32).into())
        .collect();
    rerun::LineStrips3D::new([strip])
}

/// `noisefree view`: the ground truth `gt` and each estimate of `estimates` (file, label),
/// each aligned as `eval` aligns it (`opts`), as paths on one recording written to `out`, with
/// each estimate's per-pose error on the `time` timeline.
pub fn view(
    gt: &Trajectory,
    estimates: &[(PathBuf, String, Trajectory)],
    opts: &AteOptions,
    out: &Path,
) -> Result<()> {
    let tmp = output::partial(out);
    let rec = rerun::RecordingStreamBuilder::new("noisefree view")
        .save(&tmp)
        .with_context(|| format!("creating {}", tmp.display()))?;
    rec.log_static(
        "world/groundtruth",
        &path_strip(gt).with_colors([rerun::Color::from_rgb(90, 90, 90)]),
    )?;
    for (k, (file, label, est)) in estimates.iter().enumerate() {
        let ate = evaluate_ate(gt, est, opts)
            .with_context(|| format!("aligning {} to the ground truth", file.display()))?;
        let aligned = est.transformed(ate.alignment.scale, &ate.alignment.rt);
        let [r, g, b] = PALETTE[k % PALETTE.len()];
        let entity = format!("world/estimates/{}", entity_name(label));
        rec.log_static(
            entity.as_str(),
            &path_strip(&aligned)
                .with_colors([rerun::Color::from_rgb(r, g, b)])
                .with_labels([format!("{label}: ATE {:.4} m", ate.stats.rmse)]),
        )?;
        for (&(_, e), err) in ate.pairs.iter().zip(&ate.errors) {
            set_time(&rec, e, est.stamps[e]);
            rec.log(
                format!("stats/{}/error_m", entity_name(label)),
                &rerun::Scalars::new([*err]),
            )?;
        }
    }
    rec.flush_blocking()
        .with_context(|| format!("writing {}", tmp.display()))?;
    drop(rec);
    std::fs::rename(&tmp, out).with_context(|| format!("writing {}", out.display()))?;
    Ok(())
}

/// One colour per estimate, in the order given (Okabe and Ito's colour-blind-safe set).
const PALETTE: [[u8; 3]; 6] = [
    [230, 159, 0],
    [86, 180, 233],
    [0, 158, 115],
    [213, 94, 0],
    [204, 121, 167],
    [0, 114, 178],
];

/// A label as one entity-path part: letters, digits, `-` and `_`; anything else becomes `_`.
fn entity_name(label: &str) -> String {
    label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}
