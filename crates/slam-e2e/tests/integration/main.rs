//! The slam-e2e crate's integration tests in one binary: one link, and one optimised copy of the
//! generic code they share, instead of one per file. A module per topic.

mod common;
mod end_to_end;
mod loop_closing;
mod mcor_cache;
mod place_recognition;
