//! Where generated frames go besides memory: dataset folders other programs read, and pictures.
//!
//! - [`tum`]: the TUM RGB-D layout (RGB-D sequences);
//! - [`euroc`]: the EuRoC ASL layout (stereo sequences);
//! - [`contact`]: a contact sheet (colour | depth | depth error) of a few frames;
//! - [`frame_cache`]: a folder of rendered frames that processes share;
//! - `write` (private): the staging folder, text and PNG files they share.

pub mod contact;
pub mod euroc;
pub mod frame_cache;
pub mod tum;
mod write;
