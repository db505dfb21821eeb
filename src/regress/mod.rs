//! The regression suite CI runs (`noisefree regress`): a few short synthetic sequences that take
//! different paths through the system (RGB-D, stereo, moving objects, relocalization) times the
//! paper's four configurations, one seed each, compared with the committed golden figures of
//! `tests/golden/regression.toml`. A run is deterministic, so the figures only move when the
//! code does; the tolerances say how far they may move before that counts as a regression.
//!
//! - [`cases`]: the suite and what a run of a case measures;
//! - [`golden`]: the golden file, the comparison and its table;
//! - [`suite`]: one pass of the suite, the cases run and their figures and spreads measured.

pub mod cases;
pub mod golden;
pub mod suite;
