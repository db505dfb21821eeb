//! The fate of every keypoint of a frame: what the recording colours. Each keypoint has exactly
//! one, so a frame's classes add up to its keypoints.

use slam_core::data::TrackedFrame;
use slam_core::module::pose_estimation::PoseOptRecord;
use slam_core::techniques::McorVerdict;

/// What became of one keypoint of a tracked frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Fate {
    /// Matched to a map point and an inlier of the frame's final pose.
    Kept,
    /// Matched, and rejected by the chi2 test of the final pose optimization.
    Chi2,
    /// Matched, and rejected by MC-OR because its map point's cluster failed the cluster-level
    /// test (tau_MF, tau_GF or tau_MG).
    McorCluster,
    /// Matched, and rejected by MC-OR because its own 3-D feature failed the feature-level test
    /// (tau_MF or tau_GF).
    McorFeature,
    /// Not matched: on a moving body according to the rigid consensus.
    Rc,
    /// Not matched, and without depth (no depth reading, no stereo match).
    NoDepth,
    /// Not matched, with depth.
    Unmatched,
}

impl Fate {
    /// Every fate, in the order the recording lists them.
    pub const ALL: [Fate; 7] = [
        Fate::Kept,
        Fate::Chi2,
        Fate::McorCluster,
        Fate::McorFeature,
        Fate::Rc,
        Fate::NoDepth,
        Fate::Unmatched,
    ];

    /// The name in the recording's entity path (`.../keypoints/<name>`).
    pub fn name(self) -> &'static str {
        match self {
            Fate::Kept => "kept",
            Fate::Chi2 => "chi2",
            Fate::McorCluster => "mcor_cluster",
            Fate::McorFeature => "mcor_feature",
            Fate::Rc => "rc",
            Fate::NoDepth => "no_depth",
            Fate::Unmatched => "unmatched",
        }
    }

    /// Its colour (RGB): green kept, orange chi2, red and magenta MC-OR, blue rc, grey without
    /// depth, white unmatched.
    pub fn colour(self) -> [u8; 3] {
        match self {
            Fate::Kept => [40, 200, 60],
            Fate::Chi2 => [255, 150, 0],
            Fate::McorCluster => [230, 20, 20],
            Fate::McorFeature => [220, 0, 220],
            Fate::Rc => [40, 110, 255],
            Fate::NoDepth => [128, 128, 128],
            Fate::Unmatched => [235, 235, 235],
        }
    }
}

/// The fate of every keypoint of `frame`, in keypoint order, from the frame's final pose
/// optimization `last` (the last one recorded for it; `None` when it was not tracked, and
/// every keypoint is then unmatched, with or without depth).
pub fn keypoint_fates(frame: &TrackedFrame, last: Option<&PoseOptRecord>) -> Vec<Fate> {
    let mut fates: Vec<Fate> = (0..frame.len())
        .map(|i| {
            if frame.dynamic.get(i).copied().unwrap_or(false) {
                Fate::Rc
            } else if frame.features.depth[i] <= 0.0 {
                Fate::NoDepth
            } else {
                Fate::Unmatched
            }
        })
        .collect();
    for m in last.map_or(&[][..], |r| &r.matches[..]) {
        let Some(f) = fates.get_mut(m.keypoint) else {
            continue;
        };
        *f = match (m.inlier, m.mcor) {
            (true, _) => Fate::Kept,
            (false, Some(McorVerdict::RejectedCluster)) => Fate::McorCluster,
            (false, Some(McorVerdict::RejectedFeature)) => Fate::McorFeature,
            (false, _) => Fate::Chi2,
        };
    }
    fates
}

/// How many keypoints have each fate, in [`Fate::ALL`]'s order.
#[cfg(test)]
pub fn counts(fates: &[Fate]) -> [usize; 7] {
    let mut n = [0; 7];
    for f in fates {
        let k = Fate::ALL.iter().position(|a| a == f).expect("every fate");
        n[k] += 1;
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runner::run_observed;
    use crate::select::{load, LoadOptions, Source};
    use datasets::Catalog;
    use slam_core::system::{Config, McorParams};

    /// On frames of the walking preset under MC-OR every keypoint gets one fate, the kept ones
    /// are the frame's inliers, and MC-OR rejects some: what the recording colours is what the
    /// system did.
    #[test]
    fn every_keypoint_has_one_fate_and_the_kept_are_the_inliers() {
        let seq = load(
            &Source::Catalog("walking".into()),
            &Catalog::embedded(),
            &LoadOptions::for_tests(30),
        )
        .expect("a preset");
        let config = Config {
            mcor: Some(McorParams::default()),
            ..Config::default()
        };
        let (mut mcor, mut frames) = (0, 0);
        run_observed(
            &seq,
            None,
            &config,
            None,
            |_| {},
            |o| {
                let frame = o.system.last_frame().expect("a frame");
                let last = o.final_optimization();
                let fates = keypoint_fates(frame, last);
                assert_eq!(fates.len(), o.result.stats.n_keypoints);
                let n = counts(&fates);
                assert_eq!(n.iter().sum::<usize>(), fates.len());
                if last.is_some() && o.index > 0 {
                    assert_eq!(n[0], o.result.stats.n_inliers, "frame {}", o.index);
                    frames += 1;
                }
                mcor += n[2] + n[3];
            },
        );
        assert!(frames > 20, "{frames} tracked frames");
        assert!(mcor > 0, "MC-OR rejects something on walking");
    }
}
