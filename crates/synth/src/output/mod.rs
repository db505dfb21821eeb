//! Where generated frames go besides memory, and the frame their ground truth is stated in.
//!
//! - [`body`]: the body (IMU) frame of a stereo sequence, EuRoC's frame of ground truth;
//! - [`contact`]: a contact sheet (colour | depth | depth error) of a few frames;
//! - [`frame_cache`]: a folder of rendered frames that processes share.
//!
//! Dataset folders (TUM RGB-D, EuRoC ASL) are written by `datasets::write`, beside the readers
//! they must round-trip with.

pub mod body;
pub mod contact;
pub mod frame_cache;
