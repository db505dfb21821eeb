//! The synth crate's integration tests in one binary: one link, and one optimised copy of the
//! generic code they share, instead of one per file. A module per topic.

mod clocks;
mod contact_sheet;
mod frames;
mod imaging;
mod orb;
mod recorded;
