//! Relocalization when tracking is lost (ORB-SLAM2's Tracking::Relocalization): candidate
//! keyframes from the keyframe database (shared words, score accumulated over covisible
//! keyframes) matched by BoW-guided search; without a vocabulary, by descriptor similarity
//! (brute force over the keyframes). Then per candidate a seeded pose RANSAC, pose optimization
//! and up to two projection searches to gather at least 50 inliers. Candidates are tried one after the other in score
//! order (ORB-SLAM2 interleaves 5 RANSAC iterations per candidate; same acceptance rules).

use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::pose_estimation::{optimize_frame_pose, pose_correspondences, NoiseHooks};
use crate::camera::Camera;
use crate::data::{KeyFrameId, Map, ScaleLevels, TrackedFrame};
use crate::matching::bow::search_by_bow;
use crate::matching::brute::{search_keyframe_frame, similarity_score};
use crate::matching::projection::search_by_projection_keyframe;
use crate::optimize::PoseOptConfig;
use crate::place::PlaceRecognition;
use crate::solve::{pose_ransac, PoseRansacParams};

/// Relocalization thresholds (ORB-SLAM2's values where it has them).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RelocalizationParams {
    /// Frame keypoints sampled (evenly by index) to score candidate keyframes (300).
    pub score_sample: usize,
    /// Candidates kept: score >= this fraction of the best score (0.75, as ORB-SLAM2's
    /// accumulated-score filter).
    pub score_ratio: f64,
    /// At most this many candidates are tried (10).
    pub max_candidates: usize,
    /// Descriptor ratio test of the keyframe -> frame search (0.75).
    pub match_ratio: f64,
    /// Matches a candidate needs before RANSAC (15).
    pub min_matches: usize,
    /// RANSAC: confidence (0.99), minimum inliers (10), iterations (300), inlier ratio (0.5),
    /// chi2 gate (5.991).
    pub ransac_probability: f64,
    /// See `ransac_probability`.
    pub ransac_min_inliers: usize,
    /// See `ransac_probability`.
    pub ransac_max_iterations: usize,
    /// See `ransac_probability`.
    pub ransac_epsilon: f64,
    /// See `ransac_probability`.
    pub ransac_chi2: f64,
    /// Inliers needed to accept a relocalization (50).
    pub min_inliers: usize,
}

impl Default for RelocalizationParams {
    fn default() -> Self {
        RelocalizationParams {
            score_sample: 300,
            score_ratio: 0.75,
            max_candidates: 10,
            match_ratio: 0.75,
            min_matches: 15,
            ransac_probability: 0.99,
            ransac_min_inliers: 10,
            ransac_max_iterations: 300,
            ransac_epsilon: 0.5,
            ransac_chi2: 5.991,
            min_inliers: 50,
        }
    }
}

/// Shared inputs of relocalization.
#[derive(Clone, Copy, Debug)]
pub struct RelocalizationContext<'a> {
    /// The camera.
    pub camera: &'a Camera,
    /// Pyramid scale table.
    pub levels: &'a ScaleLevels,
    /// Thresholds.
    pub params: &'a RelocalizationParams,
    /// Pose-only optimization schedule.
    pub pose_cfg: &'a PoseOptConfig,
    /// MC-OR / AVC switches.
    pub hooks: NoiseHooks<'a>,
    /// Vocabulary and keyframe database: candidates from the database and BoW-guided matching
    /// as in ORB-SLAM2; without them, the brute-force stand-ins of [`relocalization_candidates`]
    /// and [`search_keyframe_frame`].
    pub place: Option<&'a PlaceRecognition>,
}

/// Candidate keyframes ranked by similarity score (descending, ties by id).
pub fn relocalization_candidates(
    frame: &TrackedFrame,
    map: &Map,
    params: &RelocalizationParams,
) -> Vec<KeyFrameId> {
    let n = frame.len();
    if n == 0 {
        return Vec::new();
    }
    let step = (n as f64 / params.score_sample.max(1) as f64).max(1.0);
    let sample: Vec<usize> = (0..params.score_sample.min(n))
        .map(|k| ((k as f64 * step) as usize).min(n - 1))
        .collect();
    let mut scored: Vec<(usize, KeyFrameId)> = map
        .keyframes()
        .map(|k| (similarity_score(k, &frame.features, &sample, 0.8), k.id))
        .filter(|&(s, _)| s > 0)
        .collect();
    let best = scored.iter().map(|s| s.0).max().unwrap_or(0);
    scored.retain(|&(s, _)| s as f64 >= params.score_ratio * best as f64);
    scored.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    scored
        .into_iter()
        .take(params.max_candidates)
        .map(|s| s.1)
        .collect()
}

/// Tries to relocalize `frame`; on success its pose and matches are set and the candidate
/// keyframe that worked is returned.
pub fn relocalize(
    frame: &mut TrackedFrame,
    map: &Map,
    ctx: &RelocalizationContext,
    rng: &mut ChaCha8Rng,
) -> Option<KeyFrameId> {
    let p = ctx.params;
    let ransac = PoseRansacParams {
        probability: p.ransac_probability,
        min_inliers: p.ransac_min_inliers,
        max_iterations: p.ransac_max_iterations,
        epsilon: p.ransac_epsilon,
        chi2_threshold: p.ransac_chi2,
    };
    let candidates = match ctx.place {
        Some(place) => {
            let fb = frame.bow(place);
            place.database.relocalization_candidates(
                &fb.bow,
                |k| {
                    map.keyframe(k)
                        .and_then(|kf| kf.bow.as_deref())
                        .map(|b| &b.bow)
                },
                |k, n| {
                    map.keyframe(k)
                        .map_or_else(Vec::new, |kf| kf.best_covisibles(n))
                },
            )
        }
        None => relocalization_candidates(frame, map, p),
    };
    for kf in candidates {
        let Some(k) = map.keyframe(kf) else {
            continue;
        };
        let (matches, n) = match (&frame.bow, &k.bow) {
            (Some(fb), Some(kb)) if ctx.place.is_some() => search_by_bow(
                k,
                &kb.features,
                &frame.features,
                &fb.features,
                p.match_ratio,
                map,
            ),
            _ => search_keyframe_frame(k, &frame.features, p.match_ratio, map),
        };
        if n < p.min_matches {
            continue;
        }
        let (corr, corr_idx) =
            pose_correspondences(&matches, &frame.features, map, ctx.camera, ctx.levels);
        let Some(hyp) = pose_ransac(&corr, ctx.camera, &ransac, rng) else {
            continue;
        };
        frame.clear_matches();
        for (c, &i) in corr_idx.iter().enumerate() {
            if hyp.inliers[c] {
                frame.map_points[i] = matches[i];
            }
        }
        frame.tcw = Some(hyp.tcw);
        let opt = |f: &mut TrackedFrame| {
            optimize_frame_pose(f, map, ctx.camera, ctx.levels, ctx.pose_cfg, &ctx.hooks).n_inliers
        };
        let mut n_good = opt(frame);
        if n_good < 10 {
            continue;
        }
        frame.drop_outliers();
        if n_good < p.min_inliers {
            let found = frame.matched_map_points();
            let added = search_by_projection_keyframe(
                frame, kf, &found, 10.0, 100, map, ctx.camera, ctx.levels,
            );
            if added + n_good >= p.min_inliers {
                n_good = opt(frame);
                if n_good > 30 && n_good < p.min_inliers {
                    let found = frame.matched_map_points();
                    let added = search_by_projection_keyframe(
                        frame, kf, &found, 3.0, 64, map, ctx.camera, ctx.levels,
                    );
                    if n_good + added >= p.min_inliers {
                        n_good = opt(frame);
                    }
                }
                frame.drop_outliers();
            }
        }
        if n_good >= p.min_inliers {
            return Some(kf);
        }
    }
    frame.clear_matches();
    None
}
