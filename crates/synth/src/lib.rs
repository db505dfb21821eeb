//! synth: photo-like synthetic RGB-D and stereo sequences with exact ground truth and a
//! controllable depth-sensor noise model (after Nguyen et al. 2012), for CI regression and as
//! the embedded default sequence of `noisefree run`.
//!
//! Module map:
//! - [`config`]: `SynthConfig`, each noise component its own switch, and the named presets;
//! - [`scene`], [`texture`]: the textured room, its objects and walking "people";
//! - [`people`]: articulated people who walk, stop, turn, sit and get up (fr3 walking /
//!   sitting twins);
//! - [`trajectory`]: smooth `xyz`, `rpy`, `spin` and `loop` camera paths;
//! - [`handheld`]: hand-held paths with a recorded sequence's duration and mean speeds;
//! - [`recorded`]: recorded TUM trajectories levelled and placed in the room, interpolated;
//! - [`render`]: the parallel ray-caster (depth, incidence, ids, anti-aliased colour, lens
//!   distortion, colour exposed over time);
//! - [`imaging`]: the colour camera's exposure, rolling shutter, vignetting, auto-exposure and
//!   sensor noise;
//! - [`noise`]: the depth-sensor model and image noise;
//! - [`hash`]: counter-based per-pixel randomness (order- and thread-independent);
//! - [`generator`]: random access to frames of a (config, seed) sequence;
//! - [`twins`]: twins of the paper's TUM and EuRoC sequences (camera, motion statistics,
//!   imaging, motion-capture noise);
//! - [`tum`], [`euroc`]: writers of the TUM RGB-D and EuRoC ASL folder layouts;
//! - [`contact`]: a contact-sheet picture (RGB | depth | depth noise) of a sequence.

pub mod config;
pub mod contact;
pub mod euroc;
pub mod generator;
pub mod handheld;
pub mod hash;
pub mod imaging;
pub mod layout;
pub mod noise;
pub mod people;
pub mod recorded;
pub mod render;
pub mod scene;
pub mod texture;
pub mod trajectory;
pub mod tum;
pub mod twins;
mod write;

use std::path::PathBuf;

pub use config::{
    preset_names, AxialNoise, DepthLag, DepthNoise, DisparityQuantisation, Holes, ImageConfig,
    LateralNoise, Misregistration, MocapClock, MocapNoise, MovingObjects, Preset, StereoRig,
    StreamStamps, Supersampling, SynthConfig, SystematicDistortion, Trajectory, EFFECTS,
};
pub use contact::{contact_sheet, write_contact_sheet};
pub use euroc::write_euroc;
pub use generator::{Generator, SynthFrame};
pub use imaging::Imaging;
pub use recorded::RecordedPath;
pub use tum::write_tum;

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
    /// The output folder exists and is not empty.
    #[error("{0}: output folder exists and is not empty (remove it or choose another)")]
    OutputExists(PathBuf),
}
