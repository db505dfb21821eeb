//! The one error type of the crate: a perturbation misnamed, out of range, or not applicable
//! to the sequence (each message names what was given and what is valid), or the underlying
//! sequence failing to read or write.

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
