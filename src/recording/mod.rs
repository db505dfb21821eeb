//! A run recorded for the Rerun viewer (`noisefree run --rerun FILE.rrd`, `noisefree view`):
//! what the SLAM saw, kept and rejected, frame by frame, on one scrubbable timeline.
//!
//! - [`fate`]: the fate of every keypoint of a frame (kept, rejected by the chi2 test, by
//!   MC-OR's cluster or feature test, by rigid consensus, without depth, unmatched), the
//!   classes the recording colours;
//! - [`avc`]: AVC's virtual camera for a few matches of each frame;
//! - [`output`]: the recording's file, checked before a run starts;
//! - `rrd` (cargo feature `rerun`): the recording itself, written with the official `rerun`
//!   crate. Without the feature, `--rerun` says how to build it in.
//!
//! The entity paths are the recording's interface (the tests read them back with Rerun's own
//! decoder):
//!
//! | path | what |
//! |---|---|
//! | `world/groundtruth` | the ground truth's path (line strip) |
//! | `world/slam` | the SLAM world, placed on the ground truth by the alignment `eval` uses |
//! | `world/slam/estimate` | the estimated camera path (line strip) |
//! | `world/slam/camera` | the camera's estimated pose, per frame |
//! | `world/slam/camera/image` | the pinhole with the sequence's intrinsics |
//! | `.../image/colour`, `depth`, `right` | the images the system read (perturbed where the run was) |
//! | `.../image/keypoints/<fate>` | the frame's keypoints by [`fate::Fate`]; an MC-OR rejection labelled with the thresholds it exceeded (`tau_MF`, `tau_GF`, `tau_MG`) |
//! | `world/slam/camera/avc/virtual_cameras`, `rays` | under AVC, [`avc::SAMPLES_PER_FRAME`] matches' virtual cameras C' and their rays to the measured point D and the map point M (camera frame) |
//! | `world/slam/map/points`, `keyframes`, `covisibility` | the map at each keyframe |
//! | `events` | keyframes, relocalizations and loop closures (text log) |
//! | `stats/<name>` | inliers, outliers, MC-OR rejections, tracking and mapping ms, error (m) |

// Without the recording built in, only the tests read the fates and the virtual cameras.
#[cfg_attr(not(feature = "rerun"), allow(dead_code))]
pub mod avc;
#[cfg_attr(not(feature = "rerun"), allow(dead_code))]
pub mod fate;
pub mod output;
#[cfg(feature = "rerun")]
mod rrd;

#[cfg(feature = "rerun")]
pub use rrd::{record_run, view};

/// Whether this binary was built with the recording (cargo feature `rerun`).
pub const AVAILABLE: bool = cfg!(feature = "rerun");

/// What a binary without the recording says: how to get one that has it.
pub const HOW_TO_GET_IT: &str = "this noisefree was built without the Rerun recording; build \
     it with `cargo build --release --features rerun` (or `make view`), then open the file with \
     the viewer (`pip install rerun-sdk==0.36.3`, `rerun FILE.rrd`)";
