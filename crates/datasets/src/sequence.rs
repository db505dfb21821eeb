//! A decoded sequence: the camera, every frame's images (decoded once, shared read-only through
//! `Arc` by all runs of a sweep), ground truth and the body-camera extrinsic.
//!
//! Memory: a 640x480 TUM frame holds 307 KB of grey (u8) plus 1.23 MB of depth (f32), about
//! 1.5 MB per frame, so fr2_coke's ~2500 frames take ~3.8 GB; an EuRoC 752x480 stereo frame holds
//! 0.72 MB (two u8 images), ~2.7 GB for MH01's 3682 frames. Cloning a `Sequence` is cheap
//! (images are `Arc`s); load it once and hand clones or references to each run. A colour frame
//! read through a [`FrameReader`] also holds its colour image (0.9 MB at 640x480), which a
//! loaded `Sequence` drops ([`FrameReader::without_colour`]).

use std::sync::Arc;

use nalgebra::Isometry3;
use rayon::prelude::*;
use slam_core::{Camera, FrameInput};

use crate::DatasetError;

/// Which dataset layout a sequence came from: it decides how estimates are compared with
/// ground truth (EuRoC ground truth is the body frame, see [`Sequence::t_bs`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// TUM RGB-D layout (`rgb.txt`, `depth.txt`, `groundtruth.txt`); also synthetic RGB-D
    /// sequences, whose ground truth is the camera pose as in TUM.
    TumRgbd,
    /// EuRoC ASL layout (`mav0/cam0`, `mav0/cam1`), rectified stereo; also synthetic stereo
    /// sequences (which have no `t_bs`: their ground truth is the camera pose).
    EurocStereo,
}

/// A sequence ready for slam-core.
#[derive(Clone, Debug)]
pub struct Sequence {
    /// Short name (the folder name, or the synthetic preset).
    pub name: String,
    /// The camera slam-core sees: TUM intrinsics with their distortion (fr1/fr2 keypoints are
    /// undistorted by slam-core), or the rectified EuRoC camera (no distortion, stereo `bf`).
    pub camera: Camera,
    /// Frames in time order; images are `Arc`-shared.
    pub frames: Vec<FrameInput>,
    /// Ground truth (seconds; TUM convention T_world_camera, or T_world_body for EuRoC), when
    /// the folder has it.
    pub groundtruth: Option<ate_eval::Trajectory>,
    /// EuRoC: T_body_camera of the camera the estimates are expressed in, i.e. the *rectified*
    /// left camera (raw cam0's `T_BS` times the inverse rectifying rotation). Convert a cam0
    /// estimate to the body frame with `T_world_body = T_world_cam * t_bs.inverse()`.
    pub t_bs: Option<Isometry3<f64>>,
    /// The layout it came from.
    pub format: Format,
    /// What was repaired while reading the sequence's files (e.g. a ground truth with
    /// repeated stamps, read as evaluate_ate.py reads it), one line each, for the user to see.
    pub notes: Vec<String>,
    /// RGB-D: the depth PNG value per metre the depth images were read with (a settings
    /// file's `DepthMapFactor`).
    pub depth_factor: Option<f64>,
    /// Stereo with raw images: the rectification applied to them (a settings file's
    /// `LEFT.*` / `RIGHT.*`); `None` when the images come rectified.
    pub rectification: Option<Arc<crate::rectify::StereoRectification>>,
}

impl Sequence {
    /// Number of frames.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether the sequence has no frames.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Bytes held by the decoded images (shared images counted once per frame).
    pub fn image_bytes(&self) -> usize {
        self.frames
            .iter()
            .map(|f| {
                f.image.data.len()
                    + f.depth.as_ref().map_or(0, |d| d.data.len() * 4)
                    + f.right.as_ref().map_or(0, |r| r.data.len())
            })
            .sum()
    }
}

/// Reads one frame of a sequence.
type ReadFrame = dyn Fn(usize) -> Result<FrameInput, DatasetError> + Send + Sync;

/// The frames of an opened sequence, read (decoded from disk, or rendered) on demand, so a
/// caller that turns frames into something smaller (a sweep extracting features) holds only a
/// few decoded frames at a time instead of the whole sequence (see the memory note above).
#[derive(Clone)]
pub struct FrameReader {
    len: usize,
    read: Arc<ReadFrame>,
}

impl std::fmt::Debug for FrameReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "FrameReader({} frames)", self.len)
    }
}

impl FrameReader {
    /// `len` frames, frame `i` read by `read(i)`.
    pub fn new(
        len: usize,
        read: impl Fn(usize) -> Result<FrameInput, DatasetError> + Send + Sync + 'static,
    ) -> Self {
        FrameReader {
            len,
            read: Arc::new(read),
        }
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are no frames.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Keeps only the first `n` frames.
    pub fn truncate(&mut self, n: usize) {
        self.len = self.len.min(n);
    }

    /// Reads frame `i` (a file that cannot be read or has the wrong size is an error naming it).
    ///
    /// # Panics
    /// When `i >= len()` (a caller bug).
    pub fn read(&self, i: usize) -> Result<FrameInput, DatasetError> {
        assert!(i < self.len, "frame {i} of {}", self.len);
        (self.read)(i)
    }

    /// Frames `range`, read in parallel with rayon; the first error in frame order, whatever
    /// thread hit it first.
    pub fn read_range(
        &self,
        range: std::ops::Range<usize>,
    ) -> Result<Vec<FrameInput>, DatasetError> {
        range
            .into_par_iter()
            .map(|i| self.read(i))
            .collect::<Vec<Result<FrameInput, DatasetError>>>()
            .into_iter()
            .collect()
    }

    /// Every frame, read in parallel.
    pub fn read_all(&self) -> Result<Vec<FrameInput>, DatasetError> {
        self.read_range(0..self.len)
    }

    /// The same frames without their colour images: what tracking needs, for a consumer that
    /// holds many frames at once (a loaded [`Sequence`]).
    pub fn without_colour(&self) -> FrameReader {
        let inner = self.clone();
        FrameReader::new(self.len, move |i| {
            inner.read(i).map(FrameInput::without_colour)
        })
    }
}
