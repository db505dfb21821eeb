//! The paper's two noise-resilience techniques as standalone building blocks, and the data
//! helpers of its analyses:
//! - [`mcor`]: Map-point Consensus based Outlier Rejection (III-A, Algorithm 1) — per-map-point
//!   clusters of back-projected observations, FL / CL metrics and the hierarchical gate run
//!   before every pose-optimization round;
//! - [`mcor_prepared`]: the same gate over clusters summed once per frame (what the system
//!   runs; exact);
//! - [`mcor_views`]: the every-frame reading of MC-OR's cluster (frame views stored on map
//!   points);
//! - [`avc`]: the Adaptive Virtual Camera (III-B, Eq. 8-12): its 4-D residual, a
//!   [`crate::optimize::CameraResidual`] for pose-only optimization and bundle adjustment (in
//!   [`crate::optimize::virtual_camera`]), and the measurement a keypoint with depth gets;
//! - [`rigid_consensus`](mod@rigid_consensus): noisefree's own gate beyond the paper, the largest set of matches
//!   one rigid camera motion explains (RANSAC over 3-D-3-D matches);
//! - [`correlation`]: the error terms and Pearson correlations of Table II.
//!
//! The system switches them on through `Config::mcor` / `Config::avc`
//! ([`params`]); the hook points are in [`crate::module::pose_estimation`].

pub mod avc;
pub mod correlation;
pub mod mcor;
pub mod mcor_prepared;
pub mod mcor_views;
pub mod params;
pub mod rigid_consensus;
#[cfg(test)]
mod test_support;

pub use avc::{avc_measurement, virtual_camera_direction, VirtualCameraRef, VirtualCameraResidual};
pub use correlation::{correlation_analysis, error_terms, pearson, CorrelationTable, ErrorTerms};
pub use mcor::{
    cluster_passes, feature_metrics, feature_passes, mcor_gate, ClusterFeature, ClusterMetrics,
    Exceeded, FeatureMetrics, McorCluster, McorMatch, McorMetrics, McorOutcome, McorSelection,
    McorVerdict, SightingsJudgement, MCOR_CLUSTER_CAPACITY,
};
pub use mcor_views::{FrameView, FrameViews, FRAME_VIEW_SOURCE_BIT};
pub use params::{
    AvcAim, AvcGate, AvcParams, BaselineRole, ClusterViews, McorParams, Scope, Sightings, Verdict,
};
pub use rigid_consensus::{rigid_consensus, Consensus, ConsensusMatch, RigidConsensusParams};
