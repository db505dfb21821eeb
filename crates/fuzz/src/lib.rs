//! fuzz: every file noisefree reads, fed a million malformed versions of itself.
//!
//! - [`engine`]: the seeded mutator, the counting allocator and the driver that judges a
//!   reader (no panic, no hang, time linear in the input, memory bounded by the input's size,
//!   errors that name the file) — on the standard library alone, so that the `noisefree`
//!   binary's tests share it for the formats the binary reads itself;
//! - [`targets`]: the readers of the library crates (TUM, EuRoC and KITTI text files,
//!   `sensor.yaml`, ORB-SLAM2/3 settings, both vocabulary forms, PNG and JPEG images);
//! - [`fixup`]: checksum and CRC repair, so mutations get past them to the parser;
//! - [`png`]: a small PNG writer for the image seeds the `image` crate cannot write (palettes,
//!   1/2/4-bit grey, interlaced, cut short).
//!
//! The `fuzz` binary runs a target for a while (`make fuzz`); the tests run a short fixed-seed
//! pass of every target (CI).

pub mod engine;
pub mod fixup;
pub mod png;
pub mod targets;

pub use engine::driver::{run, Limits, Report, Target};
