//! The SLAM modules, one job each (after stella_vslam's `module/`): [`pose_estimation`] (pose-only
//! optimization of a frame, with the MC-OR / AVC hook points), [`tracking`] (motion model,
//! reference keyframe, local map), [`keyframe_decision`] and [`keyframe_insertion`] (when and how a
//! frame becomes a keyframe), [`local_mapping`] (new points, fusion, culling, local BA) and
//! [`relocalization`], [`loop_closing`] with its [`essential_graph`] and [`global_ba`]. The paper's
//! techniques and their parameters are in [`crate::techniques`] (MC-OR's cluster cache and gate in
//! [`crate::techniques::mcor`]).

pub mod essential_graph;
pub mod global_ba;
pub mod keyframe_decision;
pub mod keyframe_insertion;
pub mod local_mapping;
pub mod loop_closing;
pub mod pose_estimation;
pub mod relocalization;
#[cfg(test)]
pub(crate) mod test_map;
pub mod tracking;
