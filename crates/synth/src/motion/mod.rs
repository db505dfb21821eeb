//! How the camera moves and when it looks: the camera path of a sequence and its clocks.
//!
//! Lowest first (each file uses only those above it in this list, and the world):
//! - [`smooth`]: the presets' built-in paths (`xyz`, `rpy`, `spin`, `loop`) and the look-at
//!   rotation;
//! - [`handheld`]: hand-held paths with a recorded sequence's duration and mean speeds (the
//!   twins');
//! - [`recorded`]: recorded TUM trajectories levelled and placed in the room, interpolated;
//! - [`trajectory`]: the [`trajectory::Trajectory`] of a sequence, one of the above, and its
//!   pose at any time;
//! - [`clock`]: capture instants, image stamps with arrival jitter, colour-depth pairing, and
//!   the ground truth as a motion-capture system records it.

pub mod clock;
pub mod handheld;
pub mod recorded;
pub mod smooth;
pub mod trajectory;
