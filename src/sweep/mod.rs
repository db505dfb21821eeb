//! Sweeps: the expansion of sequences x configurations x parameter grids x seeds into runs
//! ([`plan`]), and the append-only, resumable record of finished runs ([`store`]).

pub mod plan;
pub mod store;
