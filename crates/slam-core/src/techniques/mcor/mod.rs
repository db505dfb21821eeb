//! MC-OR, Map-point Consensus based Outlier Rejection (paper III-A, Algorithm 1), in one place:
//! - [`cluster`]: a map point's cluster of 3-D features, the FL / CL metrics (Eq. 1-6), the
//!   hierarchical gate over a frame's matches ([`mcor_gate`]), and which thresholds a rejection
//!   exceeded;
//! - [`prepared`]: the same verdicts over clusters summed once per frame, bit for bit (what the
//!   system runs), and the verdicts a frame keeps across its rounds;
//! - [`cache`]: the prepared clusters of the map points a frame matches, kept while the map
//!   stands still;
//! - [`views`]: a map point's frame views (the every-frame reading) as cluster features;
//! - [`frame_gate`]: the hook pose optimization calls before every round ([`RoundGate`]), what a
//!   verdict admits, and the views a tracked frame adds.
//!
//! Its parameters and readings are [`McorParams`](crate::techniques::params::McorParams); the
//! frame views themselves are map data ([`crate::data::FrameViews`]).

pub mod cache;
pub mod cluster;
pub mod frame_gate;
pub mod prepared;
pub mod views;

pub use cache::ClusterCache;
pub use cluster::{
    cluster_passes, feature_metrics, feature_passes, mcor_gate, ClusterFeature, ClusterMetrics,
    Exceeded, FeatureMetrics, McorCluster, McorMatch, McorMetrics, McorOutcome, McorSelection,
    McorVerdict, SightingsJudgement, MCOR_CLUSTER_CAPACITY,
};
pub use frame_gate::{
    admission, frame_sightings, map_point_cluster, mcor_frame_gate, mcor_frame_gate_with,
    RoundGate, TappedVerdicts,
};
pub use prepared::{gate_point, GateMemo, PreparedCluster};
