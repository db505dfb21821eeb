//! The paper's two noise-resilience techniques as standalone building blocks, and the data
//! helpers of its analyses:
//! - [`mcor`]: Map-point Consensus based Outlier Rejection (III-A, Algorithm 1), one folder:
//!   per-map-point clusters of back-projected observations, FL / CL metrics, the hierarchical
//!   gate, its exact fast path over prepared clusters, the frame's cluster cache, and the hook
//!   run before every pose-optimization round;
//! - [`avc`]: the Adaptive Virtual Camera (III-B, Eq. 8-12): its 4-D residual, a
//!   [`crate::optimize::CameraResidual`] for pose-only optimization and bundle adjustment (in
//!   [`crate::optimize::virtual_camera`]), and the measurement a keypoint with depth gets;
//! - [`rigid_consensus`](mod@rigid_consensus): noisefree's own gate beyond the paper, the largest set of matches
//!   one rigid camera motion explains (RANSAC over 3-D-3-D matches);
//! - [`correlation`]: the error terms and Pearson correlations of Table II.
//!
//! The system switches them on through `Config::mcor` / `Config::avc`
//! ([`params`]); the hook points are in [`crate::module::pose_estimation`], MC-OR's a call of
//! [`mcor::RoundGate`].

pub mod avc;
pub mod correlation;
pub mod mcor;
pub mod params;
pub mod rigid_consensus;
#[cfg(test)]
mod test_support;

pub use crate::data::{FrameView, FrameViews, FRAME_VIEW_SOURCE_BIT};
pub use avc::{avc_measurement, virtual_camera_direction, VirtualCameraRef, VirtualCameraResidual};
pub use correlation::{correlation_analysis, error_terms, pearson, CorrelationTable, ErrorTerms};
pub use mcor::{
    cluster_passes, feature_metrics, feature_passes, mcor_gate, ClusterFeature, ClusterMetrics,
    Exceeded, FeatureMetrics, McorCluster, McorMatch, McorMetrics, McorOutcome, McorSelection,
    McorVerdict, SightingsJudgement, MCOR_CLUSTER_CAPACITY,
};
pub use params::{
    AvcAim, AvcGate, AvcParams, BaselineRole, ClusterViews, McorParams, Scope, Sightings, Verdict,
};
pub use rigid_consensus::{rigid_consensus, Consensus, ConsensusMatch, RigidConsensusParams};
