//! The paper's analyses of MC-OR and AVC on synthetic sequences, where the truth is known
//! (`noisefree analyze`):
//! - [`stream`]: frames of a synthetic sequence generated in parallel chunks and fed in order,
//!   so memory stays bounded whatever the length;
//! - [`correlation`]: Table II — correlations of the virtual-camera error terms with the
//!   z-normalised 3-D error, the 2-D projective errors and the *true* depth error;
//! - [`association`]: the truth of each match (same point, mismatch, moving object);
//! - [`outliers`]: Fig. 8 (inliers / outliers per frame with and without MC-OR) and Fig. 7 (one
//!   frame with the features MC-OR rejected);
//! - [`report`]: their Markdown and Fig. 8, from what the others measured; the drawing
//!   primitives are the results report's (`results::report::panels`).

pub mod association;
pub mod correlation;
pub mod outliers;
pub mod report;
pub mod stream;
