//! synth: photo-like synthetic RGB-D and stereo sequences with exact ground truth and a
//! controllable depth-sensor noise model (after Nguyen et al. 2012), for CI regression and as
//! the embedded default sequence of `noisefree run`.
//!
//! The pipeline, and the module map: a catalog entry ([`catalog`]: a preset or a twin) becomes
//! a specification ([`spec`]); the generator ([`generator`]) builds its world ([`world`]) and
//! camera path ([`motion`]) once, then renders each frame through the sensor ([`sensor`]:
//! ray-casting, imaging, depth noise) and stamps it ([`motion::clock`]); the frame is kept in
//! memory or written out ([`output`]: contact sheet, frame cache; dataset folders are written by
//! `datasets::write`).
//!
//! Imports run one way, down this list (a file uses only files of lower layers, and of its
//! own folder those it lists above it); `tools/import_graph.py` checks it:
//! - [`catalog`]: `presets` (the named presets) and `twins` (the paper's sequences) — names
//!   become specifications;
//! - [`output`]: `body` (the body frame of stereo ground truth), `contact` (a contact sheet),
//!   `frame_cache` (rendered frames shared between processes);
//! - [`generator`]: random access to the frames of a (specification, seed) sequence;
//! - [`spec`]: [`SynthConfig`], every stage's options side by side, checked and ablated;
//! - [`sensor`]: `imaging` (exposure, rolling shutter, vignetting, auto-exposure, sensor
//!   noise), `render` (the ray-caster), `depth` (the depth-sensor model);
//! - [`motion`]: `smooth`, `handheld`, `recorded` (camera paths), `trajectory` (the path of a
//!   sequence), `clock` (stamps, ground truth, motion-capture clock and noise);
//! - [`world`]: `shape`, `texture`, `people`, `layout` (rooms and furniture), `scene`;
//! - [`hash`] (counter-based per-pixel randomness, order- and thread-independent) and
//!   [`error`]: the leaves.
//!
//! The types most users need are re-exported here.

pub mod catalog;
pub mod error;
pub mod generator;
pub mod hash;
pub mod motion;
pub mod output;
pub mod sensor;
pub mod spec;
pub mod world;

pub use catalog::presets::{preset_names, Preset};
pub use catalog::twins::TwinSpec;
pub use error::SynthError;
pub use generator::{Generator, SynthFrame};
pub use motion::clock::{MocapClock, MocapNoise, StreamStamps};
pub use motion::handheld::HandHeldPath;
pub use motion::recorded::RecordedPath;
pub use motion::trajectory::Trajectory;
pub use output::contact::{contact_sheet, write_contact_sheet};
pub use output::frame_cache::{
    cache_dir_from_env, cache_limit_from_env, CachedFrames, CACHE_ENV, CACHE_LIMIT_ENV,
    DEFAULT_LIMIT_GB,
};
pub use sensor::depth::{
    AxialNoise, BlobHoles, DepthLag, DepthNoise, DisparityQuantisation, FlyingPixels, Holes,
    LateralNoise, Misregistration, SystematicDistortion,
};
pub use sensor::imaging::Imaging;
pub use sensor::render::{ImageConfig, Supersampling};
pub use spec::{StereoRig, SynthConfig, EFFECTS};
pub use world::layout::{Room, SceneSpec};
pub use world::people::Activity;
pub use world::scene::MovingObjects;
