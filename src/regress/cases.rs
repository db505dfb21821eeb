//! The cases of the regression suite and the figures a run of one produces.

use crate::runner::RunOutcome;
use crate::sweep::plan::ConfigKind;
use serde::{Deserialize, Serialize};
use slam_core::hash::{fnv1a_continue, FNV1A_OFFSET};

/// One synthetic sequence of the suite: which path through the system it exercises.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SuiteSequence {
    /// Synthetic preset (datasets.toml / `synth --preset`).
    pub preset: &'static str,
    /// Camera trajectory overriding the preset's (`synth --trajectory`), if any.
    pub trajectory: Option<&'static str>,
    /// Speed-up of the trajectory (1 = as the preset; 2 = the same path in half the time).
    pub motion_scale: f64,
    /// Frames rendered and tracked.
    pub frames: usize,
    /// Seed of the sequence's realization (scene, textures, noise).
    pub synth_seed: u64,
    /// What the sequence is there to exercise.
    pub exercises: &'static str,
    /// Configurations run beyond the paper's four.
    pub extra: &'static [ConfigKind],
}

impl SuiteSequence {
    /// The preset, with the trajectory when it overrides the preset's and the speed-up when
    /// there is one: `stereo-spin`, `distorted-spin-x3`.
    pub fn label(&self) -> String {
        let mut l = match self.trajectory {
            Some(t) => format!("{}-{t}", self.preset),
            None => self.preset.to_string(),
        };
        if self.motion_scale != 1.0 {
            l.push_str(&format!("-x{}", self.motion_scale));
        }
        l
    }

    /// Renders the sequence (deterministic: preset, trajectory and seed fix every pixel).
    pub fn render(&self) -> anyhow::Result<datasets::Sequence> {
        let mut config = synth::SynthConfig::preset(self.preset)?;
        if let Some(t) = self.trajectory {
            config.trajectory = synth::Trajectory::from_name(t)?;
        }
        config.motion_scale *= self.motion_scale;
        let generator = synth::Generator::try_new(config, self.synth_seed)?;
        let cache = synth::cache_dir_from_env().map_err(anyhow::Error::msg)?;
        let mut seq = datasets::from_synth_cached(&generator, self.frames, cache.as_deref());
        seq.name = self.label();
        Ok(seq)
    }
}

/// The suite's sequences; every one runs under each of the four configurations (and its
/// `extra` ones) with run seed
/// [`SUITE_SEED`]. Short enough that rendering and tracking all of them takes about a minute
/// on two cores in the tests' optimised dev profile.
pub const SUITE: [SuiteSequence; 6] = [
    SuiteSequence {
        preset: "kinect",
        trajectory: None,
        motion_scale: 1.0,
        frames: 150,
        synth_seed: 0,
        exercises: "RGB-D with the Kinect depth-noise model",
        extra: &[],
    },
    SuiteSequence {
        preset: "stereo",
        trajectory: Some("spin"),
        motion_scale: 1.0,
        frames: 150,
        synth_seed: 0,
        exercises: "rectified stereo (EuRoC-like pair) turning on the spot: stereo matching, \
                    keyframes and local BA from stereo points",
        extra: &[],
    },
    SuiteSequence {
        preset: "walking",
        trajectory: None,
        motion_scale: 1.0,
        frames: 150,
        synth_seed: 0,
        exercises: "moving people: outliers, MC-OR's rejections",
        extra: &[ConfigKind::McorKeyframes, ConfigKind::Rc],
    },
    SuiteSequence {
        preset: "occluded",
        trajectory: None,
        motion_scale: 1.0,
        frames: 180,
        synth_seed: 0,
        exercises: "tracking lost behind a covered lens (frames 120-149), relocalization",
        extra: &[],
    },
    SuiteSequence {
        preset: "distorted",
        trajectory: Some("spin"),
        motion_scale: 3.0,
        frames: 300,
        synth_seed: 0,
        exercises: "a full turn on the spot in 6.7 s with systematic depth error (drift), then \
                    the start seen again: loop detection, correction, essential graph, global BA",
        extra: &[],
    },
    SuiteSequence {
        preset: "twin_fr3_w_static",
        trajectory: None,
        motion_scale: 1.0,
        frames: 60,
        synth_seed: 0,
        exercises: "a twin: articulated people walking in an office before a still fr3 camera, \
                    the Kinect colour imaging (blur, rolling shutter, auto-exposure, noise) and \
                    depth model; MC-OR's two cluster readings and the rigid consensus",
        extra: &[ConfigKind::McorKeyframes, ConfigKind::Rc],
    },
];

/// Run seed of every case (reaches relocalization's RANSAC).
pub const SUITE_SEED: u64 = 0;

/// One case: a suite sequence under one configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Case {
    /// The sequence.
    pub sequence: SuiteSequence,
    /// The configuration (paper column).
    pub kind: ConfigKind,
}

impl Case {
    /// `preset[-trajectory]/config`, the case's name in the golden file and the table.
    pub fn name(&self) -> String {
        format!("{}/{}", self.sequence.label(), self.kind.name())
    }
}

/// Every case of the suite, in file order.
pub fn all_cases() -> Vec<Case> {
    SUITE
        .iter()
        .flat_map(|&sequence| {
            ConfigKind::ALL
                .iter()
                .chain(sequence.extra)
                .map(move |&kind| Case { sequence, kind })
        })
        .collect()
}

/// What one run of a case measured: the figures the golden file keeps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Figures {
    /// ATE RMSE in metres; absent when none could be computed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ate_m: Option<f64>,
    /// Frames with a pose.
    pub tracked: usize,
    /// Keyframes in the final map.
    pub keyframes: usize,
    /// Map points in the final map.
    pub map_points: usize,
    /// Frames on which tracking was recovered by relocalization.
    pub relocalizations: usize,
    /// Loops closed. (absent in golden files from before loop closing: 0)
    #[serde(default)]
    pub loops: usize,
    /// FNV-1a 64 of the trajectory's bits (stamps and poses): any change of behaviour, however
    /// small, changes it.
    pub hash: String,
}

impl Figures {
    /// The figures of a finished run.
    pub fn of(outcome: &RunOutcome) -> Figures {
        Figures {
            ate_m: outcome.ate_rmse(),
            tracked: outcome.tracked,
            keyframes: outcome.keyframes,
            map_points: outcome.map_points,
            relocalizations: outcome.stats.iter().filter(|s| s.relocalized).count(),
            loops: outcome.loops.len(),
            hash: trajectory_hash(&outcome.trajectory),
        }
    }
}

/// FNV-1a 64 over the exact bits of every stamp and pose (translation, then the quaternion's
/// x, y, z, w), as 16 hex digits.
pub fn trajectory_hash(t: &ate_eval::Trajectory) -> String {
    let mut h = FNV1A_OFFSET;
    let mut eat = |v: f64| h = fnv1a_continue(h, &v.to_bits().to_le_bytes());
    for (s, p) in t.stamps.iter().zip(&t.poses) {
        eat(*s);
        let v = p.translation.vector;
        let q = p.rotation.coords;
        for x in [v.x, v.y, v.z, q.x, q.y, q.z, q.w] {
            eat(x);
        }
    }
    format!("{h:016x}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Isometry3;

    #[test]
    fn suite_covers_every_configuration_of_every_sequence_once() {
        let cases = all_cases();
        let extras: usize = SUITE.iter().map(|s| s.extra.len()).sum();
        assert_eq!(cases.len(), SUITE.len() * 4 + extras);
        let mut names: Vec<String> = cases.iter().map(Case::name).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), cases.len());
    }

    #[test]
    fn hash_sees_a_one_bit_change() {
        let mut t = ate_eval::Trajectory::new();
        t.push(1.0, Isometry3::translation(0.1, 0.2, 0.3));
        let a = trajectory_hash(&t);
        t.poses[0].translation.vector.y = f64::from_bits(0.2f64.to_bits() + 1);
        assert_ne!(a, trajectory_hash(&t));
        assert_eq!(a.len(), 16);
    }
}
