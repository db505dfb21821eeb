//! Keyframe -> frame matching by descriptor alone, for tracking the reference keyframe when the
//! motion model fails and for relocalization. ORB-SLAM2 restricts candidates to the same
//! vocabulary node (SearchByBoW); without a vocabulary we compare against every keypoint of the
//! frame, with the same acceptance rules: best distance <= TH_LOW, ratio to the second best
//! < `ratio` (0.7 for tracking, 0.75 for relocalization), rotation-consistency check.

use super::RotationHistogram;
use crate::data::{Features, KeyFrame, Map, MapPointId};
use crate::feature::{hamming, TH_LOW};

/// Matches the map points of `kf` to keypoints of `frame`. Returns, per frame keypoint, the
/// matched map point, and the number of matches.
pub fn search_keyframe_frame(
    kf: &KeyFrame,
    frame: &Features,
    ratio: f64,
    map: &Map,
) -> (Vec<Option<MapPointId>>, usize) {
    let mut matches: Vec<Option<MapPointId>> = vec![None; frame.len()];
    let mut hist = RotationHistogram::new();
    let mut n = 0;
    for (i, slot) in kf.map_points.iter().enumerate() {
        let Some(id) = *slot else {
            continue;
        };
        if map.map_point(id).is_none() {
            continue;
        }
        let d_kf = &kf.features.descriptors[i];
        let (mut best, mut best2, mut best_idx) = (u32::MAX, u32::MAX, usize::MAX);
        for (j, d_f) in frame.descriptors.iter().enumerate() {
            if matches[j].is_some() {
                continue;
            }
            let d = hamming(d_kf, d_f);
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
    for j in hist.rejected() {
        matches[j] = None;
        n -= 1;
    }
    (matches, n)
}

/// Number of keypoints of `frame` (among `sample`) whose best match in `kf` (descriptor only)
/// has distance <= TH_LOW and passes the ratio test: a cheap similarity score used to rank
/// relocalization candidates (our stand-in for ORB-SLAM2's bag-of-words score).
pub fn similarity_score(kf: &KeyFrame, frame: &Features, sample: &[usize], ratio: f64) -> usize {
    let mut n = 0;
    for &j in sample {
        let d_f = &frame.descriptors[j];
        let (mut best, mut best2) = (u32::MAX, u32::MAX);
        for (i, d_kf) in kf.features.descriptors.iter().enumerate() {
            if kf.map_points[i].is_none() {
                continue;
            }
            let d = hamming(d_kf, d_f);
            if d < best {
                best2 = best;
                best = d;
            } else if d < best2 {
                best2 = d;
            }
        }
        if best <= TH_LOW && (best as f64) < ratio * best2 as f64 {
            n += 1;
        }
    }
    n
}
