//! Keyframe -> frame matching by descriptor alone, for tracking the reference keyframe when the
//! motion model fails and for relocalization. ORB-SLAM2 restricts candidates to the same
//! vocabulary node (SearchByBoW); without a vocabulary we compare against every keypoint of the
//! frame, with the same acceptance rules: best distance <= TH_LOW, ratio to the second best
//! < `ratio` (0.7 for tracking, 0.75 for relocalization), rotation-consistency check.

use super::RotationHistogram;
use crate::data::{Features, KeyFrame, Map, MapPointId};
use crate::feature::{hamming, TH_LOW};

/// Keyframe -> frame matches being gathered: each keyframe feature with a map point is offered
/// its candidate frame keypoints; the closest unmatched one is taken if it passes TH_LOW and the
/// ratio test, then the rotation-consistency check prunes the lot. Shared by the brute-force
/// search here and the BoW-guided one ([`super::bow`]), which differ only in the candidates.
pub(crate) struct KeyFrameMatcher {
    matches: Vec<Option<MapPointId>>,
    hist: RotationHistogram,
    n: usize,
    ratio: f64,
}

impl KeyFrameMatcher {
    /// No matches yet for a frame of `n_frame` keypoints.
    pub(crate) fn new(n_frame: usize, ratio: f64) -> Self {
        KeyFrameMatcher {
            matches: vec![None; n_frame],
            hist: RotationHistogram::new(),
            n: 0,
            ratio,
        }
    }

    /// Offers keyframe feature `i` (map point `id`) the frame keypoints `candidates`.
    pub(crate) fn offer(
        &mut self,
        kf: &KeyFrame,
        i: usize,
        id: MapPointId,
        frame: &Features,
        candidates: impl IntoIterator<Item = usize>,
    ) {
        let d_kf = &kf.features.descriptors[i];
        let (mut best, mut best2, mut best_idx) = (u32::MAX, u32::MAX, usize::MAX);
        for j in candidates {
            if self.matches[j].is_some() {
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
        if best <= TH_LOW && (best as f64) < self.ratio * best2 as f64 {
            self.matches[best_idx] = Some(id);
            self.n += 1;
            self.hist.add(
                kf.features.keypoints[i].angle,
                frame.keypoints[best_idx].angle,
                best_idx,
            );
        }
    }

    /// The matches after the rotation check: per frame keypoint its map point, and the count.
    pub(crate) fn finish(mut self) -> (Vec<Option<MapPointId>>, usize) {
        for j in self.hist.rejected() {
            self.matches[j] = None;
            self.n -= 1;
        }
        (self.matches, self.n)
    }
}

/// Matches the map points of `kf` to keypoints of `frame`. Returns, per frame keypoint, the
/// matched map point, and the number of matches.
pub fn search_keyframe_frame(
    kf: &KeyFrame,
    frame: &Features,
    ratio: f64,
    map: &Map,
) -> (Vec<Option<MapPointId>>, usize) {
    let mut m = KeyFrameMatcher::new(frame.len(), ratio);
    for (i, slot) in kf.map_points.iter().enumerate() {
        if let Some(id) = slot.filter(|&id| map.map_point(id).is_some()) {
            m.offer(kf, i, id, frame, 0..frame.len());
        }
    }
    m.finish()
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
