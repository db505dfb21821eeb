//! In-memory synthetic sequences: the frames of a `synth::Generator` wrapped as a [`Sequence`]
//! without touching the disk (the embedded default of `noisefree run`). Frames are rendered in
//! parallel with rayon; their order and bytes do not depend on the thread count.
//!
//! A configuration with a calibrated rig (`synth::StereoRig`: the EuRoC twins, distorted and
//! unrectified) is rectified here exactly as the EuRoC reader rectifies the folder the
//! `synth` command writes: the same [`StereoRectification`] of the same calibration, the
//! ground truth the body pose (with the configuration's motion-capture noise) and `t_bs` the
//! rectified left camera in the body, so `run --seq twin_v101` sees what `run --path` of its
//! written folder sees.

use crate::rectify::{RawCamera, StereoRectification};
use crate::{Format, Sequence};
use rayon::prelude::*;
use slam_core::{Camera, Distortion, FrameInput, SensorKind};
use std::path::Path;
use std::sync::Arc;

/// The rectification of a generator with a calibrated rig, `None` without one.
fn rectification(gen: &synth::Generator) -> Option<StereoRectification> {
    let rig = gen.config().rig.as_ref()?;
    let raw = |c: &Camera, t_bs| RawCamera {
        width: c.width,
        height: c.height,
        fx: c.fx,
        fy: c.fy,
        cx: c.cx,
        cy: c.cy,
        distortion: c.distortion.unwrap_or(Distortion {
            k1: 0.0,
            k2: 0.0,
            p1: 0.0,
            p2: 0.0,
            k3: 0.0,
        }),
        t_bs,
        rate_hz: c.fps,
    };
    // T_BS as the reader gets it from the written sensor.yaml (every digit written, the
    // rotation re-orthonormalised as `read_sensor_yaml` does), so both rectifications agree
    // to the bit.
    let as_read = |t: nalgebra::Isometry3<f64>| {
        let m = t.to_homogeneous().fixed_view::<3, 3>(0, 0).into_owned();
        let rot = nalgebra::Rotation3::from_matrix(&m);
        nalgebra::Isometry3::from_parts(
            t.translation,
            nalgebra::UnitQuaternion::from_rotation_matrix(&rot),
        )
    };
    let left = raw(&gen.camera(), as_read(rig.body_from_left));
    let right = raw(&rig.right, as_read(rig.body_from_right()));
    // The rig is validated with the configuration (same size, a real baseline).
    StereoRectification::new(&left, &right).ok()
}

/// Camera, ground-truth pose of frame `i` and `t_bs` of `gen`'s sequence as a reader gives
/// them: rectified with the body ground truth for a rig, else the camera and its pose.
fn geometry(
    gen: &synth::Generator,
    rect: Option<&StereoRectification>,
) -> (Camera, Option<nalgebra::Isometry3<f64>>) {
    match rect {
        Some(r) => (r.camera(crate::euroc::EUROC_TH_DEPTH), Some(r.t_b_left)),
        None => (gen.camera(), None),
    }
}

/// The ground truth of frames `0..n` as the writers put it on disk: for a rig the body pose
/// at each frame's stamp (EuRoC's ground truth shares the camera's clock), else the
/// generator's motion-capture record of the camera ([`synth::Generator::groundtruth`]: at the
/// frame instants, or on the motion-capture clock); with the configuration's motion-capture
/// noise.
fn groundtruth(gen: &synth::Generator, rig: bool, n: usize) -> ate_eval::Trajectory {
    if rig {
        ate_eval::Trajectory {
            stamps: (0..n).map(|i| gen.timestamp(i)).collect(),
            poses: (0..n)
                .map(|i| synth::output::body::groundtruth_body(gen, i))
                .collect(),
        }
    } else {
        let (stamps, poses) = gen.groundtruth(n).into_iter().unzip();
        ate_eval::Trajectory { stamps, poses }
    }
}

/// RGB-D: the depth units the generator writes (`crate::write::write_synthetic`) and the reader reads.
fn depth_factor(gen: &synth::Generator) -> Option<f64> {
    gen.config()
        .is_rgbd()
        .then(|| gen.config().depth_units_per_metre)
}

/// Frame `i` as the system gets it (from the cache when it has it): rectified when there is a
/// rig.
fn input(frames: &synth::CachedFrames, i: usize, rect: Option<&StereoRectification>) -> FrameInput {
    let (mut input, _) = frames.input(i);
    if let Some(r) = rect {
        input.image = Arc::new(r.rectify_left(&input.image));
        input.right = input.right.map(|g| Arc::new(r.rectify_right(&g)));
    }
    input
}

/// Colour frame `i` with the depth image of frame `j` (the pair the reader's association makes,
/// [`synth::Generator::stream_pairs`]; `j == i` but where a free-running depth stream's jitter
/// pairs the next one).
fn paired(mut colour: FrameInput, depth: &FrameInput) -> FrameInput {
    colour.depth = depth.depth.clone();
    colour
}

/// The first `n_frames` frames of `gen` with exact ground truth (T_world_camera, TUM
/// convention). RGB-D presets give [`Format::TumRgbd`], stereo presets [`Format::EurocStereo`]
/// without `t_bs` (their ground truth is already the camera pose); a calibrated rig is
/// rectified and has body ground truth with `t_bs` (see the module documentation). The
/// sequence holds the colour-depth pairs the TUM reader would associate in the written folder
/// ([`synth::Generator::stream_pairs`]; every frame with its own images but where a free-running
/// depth stream's jitter makes a frame borrow a depth image or drop out).
pub fn from_synth(gen: &synth::Generator, n_frames: usize) -> Sequence {
    from_synth_cached(gen, n_frames, None)
}

/// [`from_synth`] with the frames read from, or rendered into, the frame cache folder `cache`
/// ([`synth::CachedFrames`]: the same frames, bit for bit).
pub fn from_synth_cached(
    gen: &synth::Generator,
    n_frames: usize,
    cache: Option<&Path>,
) -> Sequence {
    let rect = rectification(gen);
    let (camera, t_bs) = geometry(gen, rect.as_ref());
    let rig = rect.is_some();
    let cached = synth::CachedFrames::new(gen.clone(), cache);
    let rendered: Vec<FrameInput> = (0..n_frames)
        .into_par_iter()
        .map(|i| input(&cached, i, rect.as_ref()))
        .collect();
    let frames = gen
        .stream_pairs(n_frames)
        .into_iter()
        .map(|(i, j)| paired(rendered[i].clone(), &rendered[j]))
        .collect();
    let format = match camera.sensor {
        SensorKind::Rgbd => Format::TumRgbd,
        SensorKind::Stereo => Format::EurocStereo,
    };
    Sequence {
        name: format!("synthetic-seed{}", gen.seed()),
        camera,
        frames,
        groundtruth: Some(groundtruth(gen, rig, n_frames)),
        t_bs,
        format,
        notes: Vec::new(),
        depth_factor: depth_factor(gen),
        rectification: rect.map(Arc::new),
    }
}

/// The first `n_frames` frames of `gen` as an opened sequence: ground truth now, frames rendered
/// when the reader reads them (the same frames, bit for bit, as [`from_synth`]; a frame that
/// borrows the next frame's depth renders that frame too).
pub fn open_synth(gen: &synth::Generator, n_frames: usize) -> (Sequence, crate::FrameReader) {
    open_synth_cached(gen, n_frames, None)
}

/// [`open_synth`] with the frames read from, or rendered into, the frame cache folder `cache`
/// ([`synth::CachedFrames`]: the same frames, bit for bit).
pub fn open_synth_cached(
    gen: &synth::Generator,
    n_frames: usize,
    cache: Option<&Path>,
) -> (Sequence, crate::FrameReader) {
    let rect = rectification(gen);
    let (camera, t_bs) = geometry(gen, rect.as_ref());
    let rig = rect.is_some();
    let format = match camera.sensor {
        SensorKind::Rgbd => Format::TumRgbd,
        SensorKind::Stereo => Format::EurocStereo,
    };
    let mut seq = Sequence {
        name: format!("synthetic-seed{}", gen.seed()),
        camera,
        frames: Vec::new(),
        groundtruth: Some(groundtruth(gen, rig, n_frames)),
        t_bs,
        format,
        notes: Vec::new(),
        depth_factor: depth_factor(gen),
        rectification: None,
    };
    let pairs = gen.stream_pairs(n_frames);
    let cached = synth::CachedFrames::new(gen.clone(), cache);
    let rect = rect.map(Arc::new);
    seq.rectification = rect.clone();
    let frames = crate::FrameReader::new(pairs.len(), move |k| {
        let (i, j) = pairs[k];
        let colour = input(&cached, i, rect.as_deref());
        Ok(if j == i {
            colour
        } else {
            paired(colour, &input(&cached, j, rect.as_deref()))
        })
    });
    (seq, frames)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The EuRoC twin's written ASL folder reads back through the EuRoC reader: rectified to
    /// ORB-SLAM2's EuRoC camera (the real calibration), the same frames and ground truth as
    /// the in-memory sequence, the ground truth in the body frame with T_BS.
    #[test]
    fn euroc_twin_folder_reads_back_like_real_euroc() {
        let cfg = synth::SynthConfig::preset("twin_v101").unwrap();
        let gen = synth::Generator::new(cfg, 4);
        let n = 2;
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("twin");
        crate::write::write_synthetic(&gen, n, &out, |_| ()).unwrap();
        let disk = crate::euroc::load_euroc(&out).unwrap();
        // ORB-SLAM2's EuRoC.yaml, which our rectification of the real files reproduces.
        let c = &disk.camera;
        assert!((c.fx - 435.2047).abs() < 1e-3, "{}", c.fx);
        assert!((c.cx - 367.4517).abs() < 1e-3 && (c.cy - 252.2009).abs() < 1e-3);
        assert!((c.bf - 47.9064).abs() < 1e-3, "{}", c.bf);
        assert_eq!((c.width, c.height, c.fps), (752, 480, 20.0));
        let mem = from_synth(&gen, n);
        assert_eq!(mem.camera, disk.camera);
        assert_eq!(mem.t_bs, disk.t_bs);
        let (gd, gm) = (
            disk.groundtruth.as_ref().unwrap(),
            mem.groundtruth.as_ref().unwrap(),
        );
        let t_bs = disk.t_bs.unwrap();
        for i in 0..n {
            assert_eq!(disk.frames[i].image.data, mem.frames[i].image.data);
            assert_eq!(
                disk.frames[i].right.as_ref().unwrap().data,
                mem.frames[i].right.as_ref().unwrap().data
            );
            assert!((disk.frames[i].timestamp - mem.frames[i].timestamp).abs() < 1e-9);
            // Written with 9 decimals.
            let d = gd.poses[i].inverse() * gm.poses[i];
            assert!(d.translation.vector.norm() < 1e-8 && d.rotation.angle() < 1e-8);
            // Body ground truth times T_BS is the rectified left camera: at the true camera
            // centre within the motion-capture noise (1 mm per axis), and looking the same way
            // up to the rectification's small rotation and the noise's 0.1 degree.
            let cam = gd.poses[i] * t_bs;
            let truth = gen.pose(i);
            let e = (cam.translation.vector - truth.translation.vector).norm();
            assert!(e < 0.006, "{e}");
            assert!((truth.rotation.inverse() * cam.rotation).angle() < 0.03);
            // The body is not the camera: T_BS moves it by centimetres and turns it by 90 deg.
            let body_offset = (gd.poses[i].translation.vector - truth.translation.vector).norm();
            assert!(body_offset > 0.03, "{body_offset}");
        }
    }
}
