//! Names that become specifications: the top of the crate, which nothing else in it uses.
//!
//! - [`twins`]: twins of the paper's TUM and EuRoC sequences (camera, motion statistics,
//!   imaging, depth model, clocks, motion-capture noise, room), with the sources of the values;
//! - [`presets`]: the named presets, each after the effect it models, and the twins by name.

pub mod presets;
pub mod twins;
