//! The errors of this crate: every stage reports through [`SynthError`], and errors about a
//! file name the file (and the line, for a malformed line).

use std::path::PathBuf;

/// Everything that can go wrong in this crate; file errors name the file.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// A preset or trajectory name that does not exist.
    #[error("unknown {what} '{name}' (valid: {valid})")]
    UnknownName {
        /// What was looked up ("preset", "trajectory").
        what: &'static str,
        /// The name given.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
    },
    /// A configuration value out of its range.
    #[error("invalid synthetic configuration: {0}")]
    InvalidConfig(String),
    /// Reading or writing a file or folder failed.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// Encoding a PNG failed.
    #[error("{path}: {source}")]
    Image {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: image::ImageError,
    },
    /// A malformed line of an input file (a recorded trajectory).
    #[error("{path}:{line}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong with the line.
        message: String,
    },
    /// A recorded trajectory that cannot be placed in the synthetic room (too large, too few
    /// poses, no down direction).
    #[error("{path}: {message}")]
    TrajectoryFit {
        /// The trajectory file.
        path: PathBuf,
        /// Why, with the figures (extents, room size).
        message: String,
    },
    /// More frames asked for than a recorded trajectory covers.
    #[error(
        "trajectory {trajectory} lasts {duration:.3} s, but {frames} frames need {needed:.3} s \
         of it (at this frame rate and motion scale at most {max_frames} frames fit)"
    )]
    TrajectoryTooShort {
        /// The trajectory (a recorded path's file).
        trajectory: String,
        /// Its duration, seconds.
        duration: f64,
        /// Frames asked for.
        frames: usize,
        /// Trajectory time of the last frame asked for, seconds.
        needed: f64,
        /// The largest frame count that fits.
        max_frames: usize,
    },
}
