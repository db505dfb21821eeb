//! Sweeps: the expansion of sequences x configurations x parameter grids x seeds into runs
//! ([`plan`]), the sweep's phases from plan to record ([`execute`]), one run of ours
//! ([`job`]) and of an external system ([`external_run`]), the bars ([`progress`]), the
//! append-only, resumable record of finished runs ([`store`]), what they cost ([`cost`]) and
//! the runs a folder was asked for ([`planned`]).

pub mod execute;
pub mod external_run;
pub mod job;
pub mod plan;
pub mod progress;
pub use results::{cost, planned, spread, store};
