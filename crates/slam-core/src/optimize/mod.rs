//! Nonlinear least squares for tracking and mapping: reprojection residuals as plain data,
//! pose-only optimization with chi2 outlier rounds, sparse (local or global) bundle adjustment and
//! SE(3) pose-graph optimization for loop closing, all
//! driven by one Levenberg-Marquardt loop with g2o's damping schedule (what ORB-SLAM2 runs).
//!
//! Poses follow the convention of [`crate::geometry`]: `Tcw`, left perturbation
//! `T <- exp(xi) * T`, `xi = [omega; upsilon]`. Residuals are functions of the point in camera
//! coordinates ([`Measurement`]), so a new residual such as the paper's 4-D AVC term plugs in
//! through [`CameraResidual`] without touching the solvers.

mod camera_residual;
mod dense_cholesky;
mod envelope;
mod fixed_mul;
mod lm;
mod local_ba;
#[cfg(test)]
pub(crate) mod numdiff;
mod ordering;
mod packed;
mod pose_graph;
mod pose_only;
mod residual;
mod robust;
#[cfg(test)]
pub(crate) mod test_scene;
pub mod virtual_camera;

pub use camera_residual::{chi2_95, CameraResidual, ResidualBlock, MAX_RESIDUAL_DOF, MIN_DEPTH};
pub use local_ba::{
    local_bundle_adjustment, BaConfig, BaKeyFrame, BaObservation, BaPoint, BaProblem, BaReport,
};
pub use pose_graph::{optimize_pose_graph, PoseGraph, PoseGraphEdge, PoseGraphReport};
pub use pose_only::{
    pose_optimization, pose_optimization_with, Admission, BetweenRounds, PoseObservation,
    PoseOptConfig, PoseOptResult,
};
pub use residual::Measurement;
pub use robust::Huber;
pub use virtual_camera::AvcAim;
