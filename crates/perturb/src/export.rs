//! A perturbed copy of a sequence as a folder any SLAM program reads: the sequence written by
//! `datasets::write::write_sequence` (TUM RGB-D or EuRoC ASL, with the camera as ORB-SLAM2 /
//! ORB-SLAM3 settings beside it, the input's pixel format kept, every digit of stamps and
//! poses), plus `perturbation.txt`, which says what was applied and with which seed.

use crate::PerturbError;
use datasets::{FrameReader, Sequence};
use std::path::Path;

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
    let extra = [("perturbation.txt", format!("{note}\n"))];
    Ok(datasets::write::write_sequence(
        seq, frames, dir, &extra, source, progress,
    )?)
}
