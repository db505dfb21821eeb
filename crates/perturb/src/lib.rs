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
//! - [`export`]: a perturbed copy as a TUM RGB-D or EuRoC ASL folder (`datasets::write`) with
//!   what was applied beside it;
//! - [`error`]: [`PerturbError`], what can go wrong naming, checking or applying a chain.
//!
//! Determinism: every draw is a hash of (perturbation seed, family, its place in the chain,
//! source frame, pixel), so frames can be read in any order, in parallel, with the same bytes
//! on any machine; level 0 returns the input frame itself.

pub mod apply;
pub mod calibration;
pub mod chains;
pub mod depth;
pub mod error;
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
pub use error::PerturbError;
pub use export::write_folder;
pub use family::{Domain, Family, Perturbation};
pub use spec::{ablation_axes, Axis, Chain, Subject};
