//! The datasets crate's integration tests in one binary: one link, and one optimised copy of the
//! generic code they share, instead of one per file. A module per topic.

mod common;
mod euroc_real;
mod fetch_http;
mod rectify_render;
mod settings;
mod synth_roundtrip;
mod tum_reader;
mod write_sequence;
mod write_synthetic;
