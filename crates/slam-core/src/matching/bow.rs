//! Keyframe -> frame matching guided by the bag of words (ORB-SLAM2's SearchByBoW): only
//! features under the same direct-index node of the vocabulary are compared, with the
//! acceptance rules of [`super::brute`] (best distance <= TH_LOW, ratio to the second best in
//! the node, rotation-consistency check). Used for the reference-keyframe fallback (ratio 0.7)
//! and relocalization (0.75) when a vocabulary is loaded.

use super::RotationHistogram;
use crate::data::{Features, KeyFrame, Map, MapPointId};
use crate::feature::{hamming, TH_LOW};
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
    let mut matches: Vec<Option<MapPointId>> = vec![None; frame.len()];
    let mut hist = RotationHistogram::new();
    let mut n = 0;
    for (kf_feats, frame_feats) in kf_fv.common_nodes(frame_fv) {
        for &i in kf_feats {
            let Some(id) = kf.map_points[i] else {
                continue;
            };
            if map.map_point(id).is_none() {
                continue;
            }
            let d_kf = &kf.features.descriptors[i];
            let (mut best, mut best2, mut best_idx) = (u32::MAX, u32::MAX, usize::MAX);
            for &j in frame_feats {
                if matches[j].is_some() {
                    continue;
                }
                let d = hamming(d_kf, &frame.descriptors[j]);
                if d < best {
                    best2 = best;
                    best = d;
                    best_idx = j;
                } else if d < best2 {
                    best2 = d;
                }
            }
            if best <= TH_LOW && (best as f64) < ratio * best2 as f64 {
                matches[best_idx] = Some(id);
                n += 1;
                hist.add(
                    kf.features.keypoints[i].angle,
                    frame.keypoints[best_idx].angle,
                    best_idx,
                );
            }
        }
    }
    for j in hist.rejected() {
        matches[j] = None;
        n -= 1;
    }
    (matches, n)
}
