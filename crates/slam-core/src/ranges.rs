//! The valid range of every value of a [`Config`], checked where a configuration is read (the
//! CLI's config TOML, its switches): a value that parses but makes no sense is refused with
//! its name, its value and the range, as `orb.scale_factor = 0.5: must be > 1`, instead of
//! running (a scale factor below 1 grows the image pyramid instead of shrinking it: 11.6 GB
//! for a 6-frame run before this check).
//!
//! What is checked: ratios and probabilities lie in their interval; radii, windows, distances
//! and chi2 gates are finite and positive; the ORB pyramid shrinks and fits in memory; counts
//! that set how much work is done (RANSAC iterations, hypotheses, LM iterations) have a ceiling
//! (a mistyped 10^12 would never finish). Counts that are thresholds ("at least N inliers")
//! take any value: an unreachable threshold is a configuration that fails, not one that breaks.

use crate::system::{BaselineRole, ClusterViews, Config, Sightings};
use std::fmt;

/// A configuration value outside its valid range.
#[derive(Clone, Debug, PartialEq)]
pub struct RangeError {
    /// Dotted name of the value as the config TOML spells it (`orb.scale_factor`).
    pub key: String,
    /// The value given.
    pub value: String,
    /// The range it must lie in (`must be > 1`).
    pub rule: String,
}

impl fmt::Display for RangeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {}: {}", self.key, self.value, self.rule)
    }
}

impl std::error::Error for RangeError {}

/// Collects the checks of one configuration, keeping the first failure.
struct Checker {
    prefix: &'static str,
    first: Option<RangeError>,
}

impl Checker {
    fn fail(&mut self, key: &str, value: impl fmt::Display, rule: String) {
        if self.first.is_none() {
            self.first = Some(RangeError {
                key: if self.prefix.is_empty() {
                    key.to_string()
                } else {
                    format!("{}.{key}", self.prefix)
                },
                value: value.to_string(),
                rule,
            });
        }
    }

    /// `lo < v` (and finite).
    fn above(&mut self, key: &str, v: f64, lo: f64) {
        if !(v > lo && v.is_finite()) {
            self.fail(key, v, format!("must be > {lo}"));
        }
    }

    /// `lo <= v <= hi`.
    fn within(&mut self, key: &str, v: f64, lo: f64, hi: f64) {
        if !(lo <= v && v <= hi) {
            self.fail(key, v, format!("must be in [{lo}, {hi}]"));
        }
    }

    /// `lo < v <= hi`.
    fn above_to(&mut self, key: &str, v: f64, lo: f64, hi: f64) {
        if !(lo < v && v <= hi) {
            self.fail(key, v, format!("must be > {lo} and <= {hi}"));
        }
    }

    /// `lo < v < hi`.
    fn between(&mut self, key: &str, v: f64, lo: f64, hi: f64) {
        if !(lo < v && v < hi) {
            self.fail(key, v, format!("must be > {lo} and < {hi}"));
        }
    }

    /// `lo <= n <= hi` for a count.
    fn count(&mut self, key: &str, n: u64, lo: u64, hi: u64) {
        if !(lo..=hi).contains(&n) {
            self.fail(key, n, format!("must be in {lo}..={hi}"));
        }
    }

    fn section(&mut self, prefix: &'static str) {
        self.prefix = prefix;
    }
}

/// Ceiling of the counts that set how much work one step does (RANSAC iterations, LM
/// iterations, hypotheses): 100 times ORB-SLAM2's largest.
pub const MAX_WORK_COUNT: u64 = 100_000;

/// Most ORB features per frame: a hundred times ORB-SLAM2's 1000-2000.
pub const MAX_FEATURES: u64 = 200_000;

/// Most pyramid levels (ORB-SLAM2: 8; at scale 1.2 the 32nd level is 290 times smaller).
pub const MAX_LEVELS: u64 = 32;

/// Largest pyramid scale factor (ORB-SLAM2: 1.2; 2 halves each level).
pub const MAX_SCALE_FACTOR: f64 = 4.0;

impl Config {
    /// Checks every value against its valid range (see the module doc); the first one outside
    /// it is the error, naming it as the config TOML does.
    pub fn check(&self) -> Result<(), RangeError> {
        let mut c = Checker {
            prefix: "orb",
            first: None,
        };
        self.check_orb(&mut c);
        self.check_tracking(&mut c);
        self.check_mapping(&mut c);
        self.check_loop_closing(&mut c);
        self.check_techniques(&mut c);
        c.first.map_or(Ok(()), Err)
    }

    /// The ORB extractor's values.
    fn check_orb(&self, c: &mut Checker) {
        let o = &self.orb;
        c.count("n_features", o.n_features as u64, 1, MAX_FEATURES);
        if o.n_features <= self.init_min_keypoints {
            // An unreachable threshold otherwise fails quietly; this one fails every frame.
            c.fail(
                "n_features",
                o.n_features,
                format!(
                    "must be above init_min_keypoints = {}: the map starts on a frame with more \
                     keypoints than that (ORB-SLAM2's initialisation), so no frame could start \
                     it; set init_min_keypoints below n_features with it",
                    self.init_min_keypoints
                ),
            );
        }
        c.above("scale_factor", o.scale_factor, 1.0);
        c.above_to("scale_factor", o.scale_factor, 1.0, MAX_SCALE_FACTOR);
        c.count("n_levels", o.n_levels as u64, 1, MAX_LEVELS);
        c.count("ini_th_fast", u64::from(o.ini_th_fast), 1, 255);
        c.count(
            "min_th_fast",
            u64::from(o.min_th_fast),
            1,
            u64::from(o.ini_th_fast.max(1)),
        );
    }

    /// Tracking's and the keyframe decision's values.
    fn check_tracking(&self, c: &mut Checker) {
        c.section("tracking");
        let t = &self.tracking;
        for (k, v) in [
            ("motion_window_rgbd", t.motion_window_rgbd),
            ("motion_window_stereo", t.motion_window_stereo),
            ("local_window_rgbd", t.local_window_rgbd),
            ("local_window_stereo", t.local_window_stereo),
            ("local_window_after_reloc", t.local_window_after_reloc),
        ] {
            c.above_to(k, v, 0.0, 1000.0);
        }
        c.above_to("reference_ratio", t.reference_ratio, 0.0, 1.0);
        c.above_to("local_ratio", t.local_ratio, 0.0, 1.0);
        c.within("view_cos_limit", t.view_cos_limit, -1.0, 1.0);

        c.section("keyframes");
        let k = &self.keyframes;
        if let Some(n) = k.max_frames {
            c.count("max_frames", n, 1, u64::MAX);
        }
        c.within("ref_ratio", k.ref_ratio, 0.0, 1.0);
        c.within(
            "ref_ratio_single_keyframe",
            k.ref_ratio_single_keyframe,
            0.0,
            1.0,
        );
        c.within("ref_ratio_weak", k.ref_ratio_weak, 0.0, 1.0);
    }

    /// Local mapping's and relocalization's values.
    fn check_mapping(&self, c: &mut Checker) {
        c.section("mapping");
        let m = &self.mapping;
        c.within("min_found_ratio", m.min_found_ratio, 0.0, 1.0);
        c.within("max_parallax_cos", m.max_parallax_cos, -1.0, 1.0);
        c.above_to("scale_consistency", m.scale_consistency, 0.0, 1000.0);
        c.above_to("fuse_radius", m.fuse_radius, 0.0, 1000.0);
        c.within("redundant_ratio", m.redundant_ratio, 0.0, 1.0);

        c.section("relocalization");
        let r = &self.relocalization;
        c.within("score_ratio", r.score_ratio, 0.0, 1.0);
        c.above_to("match_ratio", r.match_ratio, 0.0, 1.0);
        c.between("ransac_probability", r.ransac_probability, 0.0, 1.0);
        c.count(
            "ransac_max_iterations",
            r.ransac_max_iterations as u64,
            1,
            MAX_WORK_COUNT,
        );
        c.above_to("ransac_epsilon", r.ransac_epsilon, 0.0, 1.0);
        c.above("ransac_chi2", r.ransac_chi2, 0.0);
        c.count("score_sample", r.score_sample as u64, 1, MAX_FEATURES);
        c.count("max_candidates", r.max_candidates as u64, 1, MAX_WORK_COUNT);
    }

    /// Loop closing's values.
    fn check_loop_closing(&self, c: &mut Checker) {
        c.section("loop_closing");
        let l = &self.loop_closing;
        c.count("consistency", l.consistency as u64, 1, MAX_WORK_COUNT);
        c.above_to("match_ratio", l.match_ratio, 0.0, 1.0);
        c.count(
            "ransac_iterations",
            l.ransac_iterations as u64,
            1,
            MAX_WORK_COUNT,
        );
        c.above("ransac_chi2", l.ransac_chi2, 0.0);
        c.above_to("guided_radius", l.guided_radius, 0.0, 1000.0);
        c.above_to("projection_radius", l.projection_radius, 0.0, 1000.0);
        c.above_to("fuse_radius", l.fuse_radius, 0.0, 1000.0);
        c.count(
            "essential_iterations",
            l.essential_iterations as u64,
            0,
            MAX_WORK_COUNT,
        );
        c.count(
            "global_ba_iterations",
            l.global_ba_iterations as u64,
            0,
            MAX_WORK_COUNT,
        );
    }

    /// The techniques' values (MC-OR, AVC, the RGB-D baseline, rigid consensus), when on.
    fn check_techniques(&self, c: &mut Checker) {
        if let Some(m) = &self.mcor {
            c.section("mcor");
            c.above("tau_mf", m.tau_mf, 0.0);
            c.above("tau_gf", m.tau_gf, 0.0);
            c.above("tau_mg", m.tau_mg, 0.0);
            c.count(
                "view_stride",
                u64::from(m.view_stride),
                1,
                u64::from(u32::MAX),
            );
            if m.sightings == Sightings::All && m.cluster_views != ClusterViews::EveryFrame {
                c.fail(
                    "sightings",
                    "\"all\"",
                    "needs cluster_views = \"every-frame\" (a tracked frame's sightings are \
                     frame views)"
                        .to_string(),
                );
            }
        }
        if let Some(a) = &self.avc {
            c.section("avc");
            c.above_to("baseline", a.baseline, 0.0, 100.0);
            if let (BaselineRole::Camera, Some(b)) = (a.b_role, self.rgbd_baseline) {
                if b != a.baseline {
                    c.fail(
                        "b_role",
                        "\"camera\"",
                        format!(
                            "b = {} is the camera's baseline, but rgbd_baseline = {b} gives \
                             another: set one of them",
                            a.baseline
                        ),
                    );
                }
            }
        }
        if let Some(b) = self.rgbd_baseline {
            c.section("");
            c.above_to("rgbd_baseline", b, 0.0, 100.0);
        }
        if let Some(rc) = &self.rc {
            c.section("rc");
            c.count("hypotheses", rc.hypotheses as u64, 1, MAX_WORK_COUNT);
            c.count(
                "min_hypotheses",
                rc.min_hypotheses as u64,
                0,
                rc.hypotheses as u64,
            );
            c.between("confidence", rc.confidence, 0.0, 1.0);
            c.within("mask_radius_px", rc.mask_radius_px, 0.0, 1000.0);
            c.within("mask_depth_m", rc.mask_depth_m, 0.0, 1000.0);
            c.within("mask_below_share", rc.mask_below_share, 0.0, 1.0);
            c.within("nested_share", rc.nested_share, 0.0, 1.0);
            c.within("nested_evidence", rc.nested_evidence, 0.0, 1000.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::system::{AvcParams, McorParams, RigidConsensusParams};

    #[test]
    fn the_defaults_and_every_technique_on_are_in_range() {
        let all = Config {
            mcor: Some(McorParams::default()),
            avc: Some(AvcParams::default()),
            rc: Some(RigidConsensusParams::default()),
            ..Config::default()
        };
        for c in [Config::default(), Config::stereo(), all] {
            assert_eq!(c.check(), Ok(()));
        }
    }

    #[test]
    fn features_too_few_to_initialise_are_refused_naming_the_threshold() {
        let mut cfg = Config::default();
        cfg.orb.n_features = 500;
        let e = cfg.check().unwrap_err();
        assert_eq!(
            (e.key.as_str(), e.value.as_str()),
            ("orb.n_features", "500")
        );
        assert!(e.rule.contains("init_min_keypoints = 500"), "{e}");
        cfg.init_min_keypoints = 400;
        assert_eq!(cfg.check(), Ok(()), "a lower start threshold makes it run");
    }

    #[test]
    fn a_shrinking_scale_factor_is_refused_with_its_range() {
        let mut c = Config::default();
        c.orb.scale_factor = 0.5;
        let e = c.check().unwrap_err();
        assert_eq!(e.to_string(), "orb.scale_factor = 0.5: must be > 1");
        c.orb.scale_factor = f64::NAN;
        assert!(c.check().unwrap_err().to_string().contains("NaN"));
        c.orb.scale_factor = 1.2;
        c.orb.n_levels = 0;
        assert_eq!(
            c.check().unwrap_err().to_string(),
            "orb.n_levels = 0: must be in 1..=32"
        );
    }

    #[test]
    fn every_section_is_named_in_its_error() {
        let mut c = Config::default();
        c.relocalization = crate::module::relocalization::RelocalizationParams {
            ransac_probability: 1.0,
            ..c.relocalization
        };
        assert!(c
            .check()
            .unwrap_err()
            .to_string()
            .starts_with("relocalization.ransac_probability = 1: must be > 0 and < 1"));
        let mut c = Config::default();
        c.loop_closing.ransac_iterations = 1_000_000_000_000;
        assert_eq!(c.check().unwrap_err().key, "loop_closing.ransac_iterations");
        let c = Config {
            mcor: Some(McorParams {
                tau_mg: f64::INFINITY,
                ..McorParams::default()
            }),
            ..Config::default()
        };
        assert_eq!(
            c.check().unwrap_err().to_string(),
            "mcor.tau_mg = inf: must be > 0"
        );
        let c = Config {
            mcor: Some(McorParams {
                view_stride: 0,
                ..McorParams::default()
            }),
            ..Config::default()
        };
        assert_eq!(
            c.check().unwrap_err().to_string(),
            "mcor.view_stride = 0: must be in 1..=4294967295"
        );
    }

    #[test]
    fn readings_that_contradict_each_other_are_refused() {
        let c = Config {
            mcor: Some(McorParams {
                sightings: Sightings::All,
                cluster_views: ClusterViews::Keyframes,
                ..McorParams::default()
            }),
            ..Config::default()
        };
        let e = c.check().unwrap_err();
        assert_eq!(e.key, "mcor.sightings");
        assert!(e.rule.contains("every-frame"), "{e}");
        let c = Config {
            avc: Some(AvcParams {
                b_role: BaselineRole::Camera,
                baseline: 0.05,
                ..AvcParams::default()
            }),
            rgbd_baseline: Some(0.07),
            ..Config::default()
        };
        assert_eq!(c.check().unwrap_err().key, "avc.b_role");
        let c = Config {
            rgbd_baseline: Some(-1.0),
            ..Config::default()
        };
        assert_eq!(
            c.check().unwrap_err().to_string(),
            "rgbd_baseline = -1: must be > 0 and <= 100"
        );
    }
}
