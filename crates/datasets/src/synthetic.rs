//! In-memory synthetic sequences: the frames of a `synth::Generator` wrapped as a [`Sequence`]
//! without touching the disk (the embedded default of `noisefree run`). Frames are rendered in
//! parallel with rayon; their order and bytes do not depend on the thread count.

use crate::{Format, Sequence};
use rayon::prelude::*;
use slam_core::SensorKind;

/// The first `n_frames` frames of `gen` with exact ground truth (T_world_camera, TUM
/// convention). RGB-D presets give [`Format::TumRgbd`], stereo presets [`Format::EurocStereo`]
/// without `t_bs` (their ground truth is already the camera pose).
pub fn from_synth(gen: &synth::Generator, n_frames: usize) -> Sequence {
    let camera = gen.camera();
    let rendered: Vec<synth::SynthFrame> = (0..n_frames)
        .into_par_iter()
        .map(|i| gen.frame(i))
        .collect();
    let mut stamps = Vec::with_capacity(n_frames);
    let mut poses = Vec::with_capacity(n_frames);
    let frames = rendered
        .into_iter()
        .map(|f| {
            stamps.push(f.timestamp);
            poses.push(f.pose_wc);
            f.into_input()
        })
        .collect();
    let format = match camera.sensor {
        SensorKind::Rgbd => Format::TumRgbd,
        SensorKind::Stereo => Format::EurocStereo,
    };
    Sequence {
        name: format!("synthetic-seed{}", gen.seed()),
        camera,
        frames,
        groundtruth: Some(ate_eval::Trajectory { stamps, poses }),
        t_bs: None,
        format,
        notes: Vec::new(),
    }
}

/// The first `n_frames` frames of `gen` as an opened sequence: ground truth now, frames rendered
/// when the reader reads them (the same frames, bit for bit, as [`from_synth`]).
pub fn open_synth(gen: &synth::Generator, n_frames: usize) -> (Sequence, crate::FrameReader) {
    let camera = gen.camera();
    let stamps = (0..n_frames).map(|i| gen.timestamp(i)).collect();
    let poses = (0..n_frames).map(|i| gen.pose(i)).collect();
    let format = match camera.sensor {
        SensorKind::Rgbd => Format::TumRgbd,
        SensorKind::Stereo => Format::EurocStereo,
    };
    let seq = Sequence {
        name: format!("synthetic-seed{}", gen.seed()),
        camera,
        frames: Vec::new(),
        groundtruth: Some(ate_eval::Trajectory { stamps, poses }),
        t_bs: None,
        format,
        notes: Vec::new(),
    };
    let gen = gen.clone();
    let frames = crate::FrameReader::new(n_frames, move |i| Ok(gen.frame(i).into_input()));
    (seq, frames)
}
