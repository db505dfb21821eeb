//! slam-core: an ORB-SLAM2-class sparse-indirect visual SLAM system for RGB-D and rectified
//! stereo, with the two techniques of "Towards Noise Resilient SLAM" (MC-OR and AVC) as
//! switches. It does no file I/O and never prints: the CLI hands it frames and takes back poses.
//!
//! Module map (after stella_vslam's split by role):
//! - [`camera`], [`image`]: sensor model and the plain images handed in;
//! - [`feature`]: ORB extraction (pyramid, FAST, distribution, orientation, BRIEF);
//! - [`frame`]: a tracked frame (keypoints, descriptors, depth / stereo, cell grid);
//! - [`geometry`]: SE3 / SO3 maps and the perturbation convention;
//! - [`optimize`]: residuals, pose-only optimization, local bundle adjustment;
//! - [`data`]: the map (keyframes, map points and their frame views, covisibility) in arenas
//!   with typed ids;
//! - [`matching`]: projection, stereo and fuse searches;
//! - [`module`]: tracking, local mapping, relocalization, loop closing;
//! - [`techniques`]: the paper's contribution, each technique in one place: MC-OR
//!   ([`techniques::mcor`]: clusters, metrics, gate, fast path, the frame's cache and its hook
//!   into pose optimization), AVC ([`techniques::avc`]), their parameters and readings
//!   ([`techniques::params`]), and noisefree's rigid consensus beyond the paper;
//! - [`place`]: place recognition (vocabulary, BoW vectors, keyframe database, training);
//! - [`solve`]: triangulation, absolute orientation, pose RANSAC;
//! - [`system`]: the synchronous `System` tying them together; [`ranges`]: the valid range of
//!   every configuration value (`Config::check`).

pub mod camera;
pub mod data;
pub mod feature;
pub mod frame;
pub mod geometry;
pub mod hash;
pub mod ids;
pub mod image;
pub mod matching;
pub mod module;
pub mod optimize;
pub mod place;
pub mod ranges;
pub mod solve;
pub mod system;
pub mod techniques;

pub use camera::{Camera, Distortion, SensorKind};
pub use image::{rgb_to_gray, ColourImage, DepthImage, FrameInput, GrayImage};
