//! Errors of trajectory reading and evaluation, and the warnings of a reader that repaired its
//! input. Every error or warning about a file names the file and, where it applies, the
//! 1-based line, so that a user can fix the input at once.

use std::path::PathBuf;

/// What can go wrong while reading trajectories or evaluating them.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file could not be opened or read.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error: in the message, not a `source` too, so that a chain of
        /// errors printed whole (`{:#}`) names it once.
        cause: std::io::Error,
    },
    /// A line of the file is malformed (wrong field count, not a number, NaN, bad rotation...).
    #[error("{path}:{line}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong with the line.
        message: String,
    },
    /// Timestamps do not strictly increase down the file, and the reader was asked to refuse
    /// that (`StampPolicy::Strict` of the `stamps` module).
    #[error("{path}:{line}: timestamp {stamp} is not after the previous one ({previous}); with --strict, trajectories must be sorted by time without duplicates")]
    Unsorted {
        /// The file.
        path: PathBuf,
        /// 1-based line number of the offending stamp.
        line: usize,
        /// The offending stamp (seconds).
        stamp: f64,
        /// The stamp before it (seconds).
        previous: f64,
    },
    /// A file holds no pose at all.
    #[error("{path}: no poses in the file")]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A KITTI pose file and its timestamps file disagree in length.
    #[error("{path}: {times} timestamps for {poses} poses")]
    LengthMismatch {
        /// The timestamps file.
        path: PathBuf,
        /// Number of timestamps.
        times: usize,
        /// Number of poses.
        poses: usize,
    },
    /// Too few associated pose pairs for an alignment / statistic to mean anything.
    #[error("only {pairs} pose pairs associated (need at least {needed}); check the time offset, --max-diff, and that both files cover the same time span")]
    TooFewPairs {
        /// Number of associated pairs.
        pairs: usize,
        /// Minimum required.
        needed: usize,
    },
    /// The alignment is undefined (e.g. all positions identical for a Sim3 fit).
    #[error("alignment is degenerate: {0}")]
    Degenerate(String),
    /// No two associated poses are the relative pose error's step apart.
    #[error("no relative pose error sample over {step} among the {pairs} associated pose pairs; check --rpe-frames / --rpe-seconds against the trajectories' length")]
    NoRpeSample {
        /// Number of associated pairs.
        pairs: usize,
        /// The step (`3 frames`, `0.05 s`).
        step: String,
    },
    /// An error came out infinite or NaN (positions near the largest doubles).
    #[error("the errors are not finite: {0}")]
    NotFinite(String),
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, Error>;

/// A note about an input that was accepted after a repair (e.g. a quaternion normalised, or
/// repeated stamps resolved).
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    /// The file.
    pub path: PathBuf,
    /// 1-based line number, when the note is about one line (not the whole file).
    pub line: Option<usize>,
    /// What was repaired.
    pub message: String,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{}: {}", self.path.display(), line, self.message),
            None => write!(f, "{}: {}", self.path.display(), self.message),
        }
    }
}
