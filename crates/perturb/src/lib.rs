//! perturb: graded, seeded perturbations of any sequence — real TUM / EuRoC folders, synthetic
//! presets and twins, RGB-D and stereo — applied between the sequence reader and every consumer
//! (a run, a sweep's shared feature extraction, the folder written for an external system), so
//! a perturbed frame means the same thing to all of them.
//!
//! - [`family`]: the taxonomy (families, what they act on, units, ranges);
//! - [`chains`]: named camera chains, a real camera's systematic errors at the literature's
//!   levels;
//! - [`spec`]: the `family:level+...` spelling of chains and sweep axes;
//! - [`calibration`]: the camera a system is given (`focal-error`, ...), images untouched;
//! - [`groundtruth`]: the ground truth a run is scored against (`gt-offset`, ...);
//! - [`systematic`]: a real depth sensor's systematic errors (`depth-distortion`,
//!   `depth-registration`, `ir-shadow`, `disparity-quantization`), fixed for a sequence;
//! - [`depth`], [`image`], [`occluders`], [`stereo`]: what each family does to one frame,
//!   through synth's sensor models (`synth::sensor`) where one exists, so the synthetic
//!   sequences and the perturbations share one noise model;
//! - [`apply`]: [`perturb_sequence`] wraps a sequence's frame reader (time families pick and
//!   re-stamp frames, the others change their content);
//! - [`export`]: writes any sequence (perturbed or not) as a TUM RGB-D or EuRoC ASL folder any
//!   tool reads back to the same bits.
//!
//! Determinism: every draw is a hash of (perturbation seed, family, its place in the chain,
//! source frame, pixel), so frames can be read in any order, in parallel, with the same bytes
//! on any machine; level 0 returns the input frame itself.

pub mod apply;
pub mod calibration;
pub mod chains;
pub mod depth;
pub mod export;
pub mod family;
pub mod groundtruth;
pub mod image;
pub mod occluders;
pub mod spec;
pub mod stereo;
pub mod systematic;

pub use apply::{perturb_sequence, Perturber};
pub use chains::NamedChain;
pub use export::write_folder;
pub use family::{Domain, Family, Perturbation};
pub use spec::{ablation_axes, Axis, Chain, Subject};

/// What can go wrong when a perturbation is named, checked or applied.
#[derive(Debug, thiserror::Error)]
pub enum PerturbError {
    /// A family name that does not exist.
    #[error("unknown perturbation {name:?}; known: {known}")]
    UnknownFamily {
        /// The name given.
        name: String,
        /// Every known family.
        known: String,
    },
    /// A level outside the family's range.
    #[error("{family}:{level}: the level must be {range}")]
    LevelOutOfRange {
        /// The family.
        family: &'static str,
        /// The level given.
        level: f64,
        /// What is valid.
        range: String,
    },
    /// A malformed spelling.
    #[error("{text:?}: expected {expected}")]
    Syntax {
        /// The text given.
        text: String,
        /// What was expected.
        expected: String,
    },
    /// A family that does not apply to the sequence's sensor.
    #[error("{family} does not apply to {sequence}, a {sensor} sequence")]
    WrongSensor {
        /// The family.
        family: &'static str,
        /// The sequence.
        sequence: String,
        /// Its sensor.
        sensor: &'static str,
    },
    /// A family that needs something the sequence does not have (lens distortion to leave
    /// out, ground truth to perturb).
    #[error("{family} does not apply to {sequence}: {why}")]
    NotApplicable {
        /// The family.
        family: &'static str,
        /// The sequence.
        sequence: String,
        /// What it lacks.
        why: String,
    },
    /// Reading a frame of the underlying sequence failed.
    #[error(transparent)]
    Dataset(#[from] datasets::DatasetError),
}

/// The seed of one member of a chain: the perturbation seed, the family and its position mixed,
/// so two members never share random numbers.
pub(crate) fn member_seed(seed: u64, family: Family, position: usize) -> u64 {
    use synth::hash::mix64;
    mix64(seed ^ mix64(0x5045_5254_5552_4221 ^ ((family as u64) << 8) ^ position as u64))
}
