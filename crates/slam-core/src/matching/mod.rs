//! Descriptor matching between frames, keyframes and map points, one file per strategy (after
//! stella_vslam's `match/`): [`projection`] (map points projected into a frame: motion model,
//! local map, relocalization), [`bow`] (keyframe -> frame under the same vocabulary node, for
//! the reference-keyframe fallback and relocalization), [`brute`] (the same by descriptor only,
//! when no vocabulary is loaded), [`epipolar`] (keyframe pairs for
//! triangulation), [`fuse`] (merging duplicate map points). All searches use the ORB-SLAM2
//! thresholds (`TH_HIGH`, `TH_LOW`) and the rotation-consistency histogram below.

pub mod bow;
pub mod brute;
pub mod epipolar;
pub mod fuse;
pub mod projection;

/// Number of bins of the rotation histogram: 30-degree bins. ORB-SLAM2 declares
/// `HISTO_LENGTH = 30` but bins with `round(rot / 30)`, which makes 30-degree bins; we keep
/// that effective width and wrap 360 degrees onto bin 0 (ORB-SLAM2 leaves it in a 13th bin).
pub const ROTATION_BINS: usize = 12;

/// Rotation-consistency check: the difference of keypoint orientations of true matches is about
/// the same for all of them (the in-plane camera rotation); matches outside the three most
/// populated bins are rejected (bins under 10 % of the largest are not kept).
#[derive(Clone, Debug)]
pub struct RotationHistogram {
    bins: Vec<Vec<usize>>,
}

impl Default for RotationHistogram {
    fn default() -> Self {
        RotationHistogram {
            bins: vec![Vec::new(); ROTATION_BINS],
        }
    }
}

impl RotationHistogram {
    /// An empty histogram.
    pub fn new() -> Self {
        Self::default()
    }

    /// Records match `item` whose keypoints have orientations `angle_a` and `angle_b` (degrees).
    pub fn add(&mut self, angle_a: f32, angle_b: f32, item: usize) {
        let mut rot = (angle_a - angle_b) as f64;
        if rot < 0.0 {
            rot += 360.0;
        }
        let bin = (rot * ROTATION_BINS as f64 / 360.0).round() as usize % ROTATION_BINS;
        self.bins[bin].push(item);
    }

    /// The items outside the (up to) three dominant bins, in insertion order per bin.
    pub fn rejected(&self) -> Vec<usize> {
        let counts: Vec<usize> = self.bins.iter().map(Vec::len).collect();
        let (mut m1, mut m2, mut m3) = (usize::MAX, usize::MAX, usize::MAX);
        for (i, &c) in counts.iter().enumerate() {
            let cnt = |m: usize| if m == usize::MAX { 0 } else { counts[m] };
            if c > cnt(m1) {
                m3 = m2;
                m2 = m1;
                m1 = i;
            } else if c > cnt(m2) {
                m3 = m2;
                m2 = i;
            } else if c > cnt(m3) {
                m3 = i;
            }
        }
        let max1 = if m1 == usize::MAX { 0 } else { counts[m1] };
        let weak = |m: usize| m == usize::MAX || (counts[m] as f64) < 0.1 * max1 as f64;
        if weak(m2) {
            m2 = usize::MAX;
            m3 = usize::MAX;
        } else if weak(m3) {
            m3 = usize::MAX;
        }
        let mut out = Vec::new();
        for (i, b) in self.bins.iter().enumerate() {
            if i != m1 && i != m2 && i != m3 {
                out.extend_from_slice(b);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_histogram_keeps_dominant_rotation() {
        let mut h = RotationHistogram::new();
        // 20 matches with ~0 degree rotation (some just below 360), 2 wild ones.
        for i in 0..10 {
            h.add(10.0 + i as f32, 8.0, i);
        }
        for i in 10..20 {
            h.add(355.0, 1.0, i);
        }
        h.add(100.0, 0.0, 20);
        h.add(200.0, 0.0, 21);
        let rejected = h.rejected();
        assert_eq!(rejected, vec![20, 21]);
    }
}
