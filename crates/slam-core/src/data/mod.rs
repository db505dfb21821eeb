//! The map: keyframes and map points stored in arenas indexed by typed ids, with observations
//! kept both ways (keyframe -> map point per keypoint, map point -> keyframe), the covisibility
//! graph (edge weight = number of shared map points) and the spanning tree. Every container is
//! iterated in id order, so the same input gives the same map.

mod features;
mod frame_views;
mod graph;
mod keyframe;
mod levels;
mod map;
mod map_point;
mod tracked_frame;

pub use crate::ids::{KeyFrameId, MapPointId};
pub use features::{undistorted_bounds, FeatureGrid, Features, GRID_COLS, GRID_ROWS};
pub use frame_views::{FrameView, FrameViews, FRAME_VIEW_SOURCE_BIT, MCOR_CLUSTER_CAPACITY};
pub use graph::COVISIBILITY_MIN_WEIGHT;
pub use keyframe::KeyFrame;
pub use levels::ScaleLevels;
pub use map::Map;
pub use map_point::{predict_scale, MapPoint};
pub use tracked_frame::TrackedFrame;
