//! Geometric solvers used by the modules: two-view linear triangulation, rigid absolute
//! orientation (Horn / Kabsch) and a seeded RANSAC for the camera pose from 2-D / 3-D
//! correspondences (relocalization).

mod absolute_orientation;
mod pose_ransac;
mod triangulation;

pub use absolute_orientation::absolute_orientation;
pub use pose_ransac::{pose_ransac, PoseCorrespondence, PoseRansacParams, PoseRansacResult};
pub use triangulation::triangulate_linear;
