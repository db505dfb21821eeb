//! Keyframe -> frame matching guided by the bag of words (ORB-SLAM2's SearchByBoW): only
//! features under the same direct-index node of the vocabulary are compared, with the
//! acceptance rules of [`super::brute`] (best distance <= TH_LOW, ratio to the second best in
//! the node, rotation-consistency check). Used for the reference-keyframe fallback (ratio 0.7)
//! and relocalization (0.75) when a vocabulary is loaded.

use super::brute::KeyFrameMatcher;
use crate::data::{Features, KeyFrame, Map, MapPointId};
use crate::place::FeatureVector;

/// Matches the map points of `kf` (direct index `kf_fv`) to keypoints of `frame` (direct index
/// `frame_fv`). Returns, per frame keypoint, the matched map point, and the number of matches.
pub fn search_by_bow(
    kf: &KeyFrame,
    kf_fv: &FeatureVector,
    frame: &Features,
    frame_fv: &FeatureVector,
    ratio: f64,
    map: &Map,
) -> (Vec<Option<MapPointId>>, usize) {
    let mut m = KeyFrameMatcher::new(frame.len(), ratio);
    for (kf_feats, frame_feats) in kf_fv.common_nodes(frame_fv) {
        for &i in kf_feats {
            if let Some(id) = kf.map_points[i].filter(|&id| map.map_point(id).is_some()) {
                m.offer(kf, i, id, frame, frame_feats.iter().copied());
            }
        }
    }
    m.finish()
}
