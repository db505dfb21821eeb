//! The named presets, each named after the effect it models (`clean`, `kinect`, `boundary`,
//! `walking`, `stereo`, `distorted`, `lag`, `hard`, `occluded`, `loop`, `walking-stereo`), and
//! the twins of the
//! paper's sequences ([`crate::catalog::twins`]): a name becomes a [`SynthConfig`].

use slam_core::{Camera, SensorKind};
use std::fmt;

use crate::catalog::twins::{self, TwinSpec, TWINS};
use crate::error::SynthError;
use crate::motion::trajectory::Trajectory;
use crate::sensor::depth::{
    DepthLag, DepthNoise, LateralNoise, Misregistration, SystematicDistortion,
};
use crate::sensor::render::ImageConfig;
use crate::spec::SynthConfig;
use crate::world::scene::MovingObjects;

/// The stereo camera of the `stereo` preset: EuRoC-like 752x480 rectified pinhole, baseline
/// 0.11 m, ThDepth 35, 30 Hz.
pub fn stereo_camera() -> Camera {
    let fx = 458.0;
    Camera {
        fx,
        fy: 458.0,
        cx: 375.5,
        cy: 239.5,
        width: 752,
        height: 480,
        distortion: None,
        bf: fx * 0.11,
        th_depth: 35.0,
        fps: 30.0,
        sensor: SensorKind::Stereo,
    }
}

/// Named presets, from easy to hard; each is named after the effect it models.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// No noise at all: exact depth, noiseless images.
    Clean,
    /// Kinect v1 model: axial + disparity quantisation + lateral 0.8 px + holes; image noise 2.
    Kinect,
    /// Kinect plus strong lateral mixing (2.5 px) and 4 px RGB-depth misregistration.
    Boundary,
    /// Kinect plus two walking "people" covering 20-40 % of the view (fr3_walking-like).
    Walking,
    /// Rectified stereo pair, baseline 0.11 m, 752x480, no depth image.
    Stereo,
    /// Kinect plus a systematic depth error (+4 % scale, 1.5 % radial wobble).
    Distorted,
    /// Kinect plus a 2-frame depth lag and 1.5x faster motion.
    Lag,
    /// Everything that breaks a baseline: walking people, systematic distortion, lag, fast motion.
    Hard,
    /// Kinect with frames 120..150 covered by a featureless surface (relocalisation).
    Occluded,
    /// Loop closing: the [`Trajectory::Loop`] circuit (40 s round the room, then the start
    /// re-seen) with sensor errors that make odometry drift before the revisit — the
    /// `distorted` depth error, stronger. Its default length is the circuit plus the revisit
    /// ([`Preset::default_frames`]).
    Loop,
    /// The `stereo` pair with `walking`'s two people crossing the view: a moving scene for
    /// stereo depth (the rigid consensus's stereo path).
    WalkingStereo,
    /// A twin of one of the paper's sequences (TUM or EuRoC): index into
    /// [`TWINS`].
    Twin(usize),
}

const PRESETS: [(Preset, &str); 11] = [
    (Preset::Clean, "clean"),
    (Preset::Kinect, "kinect"),
    (Preset::Boundary, "boundary"),
    (Preset::Walking, "walking"),
    (Preset::Stereo, "stereo"),
    (Preset::Distorted, "distorted"),
    (Preset::Lag, "lag"),
    (Preset::Hard, "hard"),
    (Preset::Occluded, "occluded"),
    (Preset::Loop, "loop"),
    (Preset::WalkingStereo, "walking-stereo"),
];

/// Names of all presets: the effect presets easy to hard, then the twins.
pub fn preset_names() -> &'static [&'static str] {
    static NAMES: std::sync::OnceLock<Vec<&'static str>> = std::sync::OnceLock::new();
    NAMES.get_or_init(|| Preset::all().map(|p| p.name()).collect())
}

impl Preset {
    /// All presets: the effect presets easy to hard, then the twins in Table III order.
    pub fn all() -> impl Iterator<Item = Preset> {
        PRESETS
            .iter()
            .map(|(p, _)| *p)
            .chain((0..TWINS.len()).map(Preset::Twin))
    }

    /// The preset's name.
    pub fn name(&self) -> &'static str {
        if let Preset::Twin(i) = self {
            return TWINS.get(*i).map_or("?", |t| t.name);
        }
        PRESETS
            .iter()
            .find(|(p, _)| p == self)
            .map(|(_, n)| *n)
            .unwrap_or("?")
    }

    /// Looks a preset up by name; the error lists the valid names.
    pub fn from_name(name: &str) -> Result<Preset, SynthError> {
        Preset::all()
            .find(|p| p.name() == name)
            .ok_or_else(|| SynthError::UnknownName {
                what: "preset",
                name: name.to_string(),
                valid: preset_names().join(", "),
            })
    }

    /// The twin this preset is, if it is one.
    pub fn twin(&self) -> Option<&'static TwinSpec> {
        match self {
            Preset::Twin(i) => TWINS.get(*i),
            _ => None,
        }
    }

    /// The configuration of this preset.
    pub fn config(&self) -> SynthConfig {
        let kinect = SynthConfig {
            depth_noise: DepthNoise::kinect(),
            ..SynthConfig::default()
        };
        match self {
            Preset::Clean => SynthConfig {
                image: ImageConfig {
                    noise_sigma: 0.0,
                    ..ImageConfig::default()
                },
                ..SynthConfig::default()
            },
            Preset::Kinect => kinect,
            Preset::Boundary => {
                let mut c = kinect;
                c.depth_noise.lateral = Some(LateralNoise { sigma_px: 2.5 });
                c.depth_noise.misregistration = Some(Misregistration {
                    dx_px: 4.0,
                    dy_px: 1.0,
                });
                c
            }
            Preset::Walking => SynthConfig {
                moving_objects: Some(MovingObjects::default()),
                ..kinect
            },
            Preset::Stereo => SynthConfig {
                camera: stereo_camera(),
                ..SynthConfig::default()
            },
            Preset::WalkingStereo => SynthConfig {
                camera: stereo_camera(),
                moving_objects: Some(MovingObjects::default()),
                ..SynthConfig::default()
            },
            Preset::Distorted => {
                let mut c = kinect;
                c.depth_noise.distortion = Some(SystematicDistortion::default());
                c
            }
            Preset::Lag => {
                let mut c = kinect;
                c.depth_noise.lag = Some(DepthLag { frames: 2.0 });
                c.motion_scale = 1.5;
                c
            }
            Preset::Hard => {
                let mut c = kinect;
                c.moving_objects = Some(MovingObjects::default());
                c.depth_noise.distortion = Some(SystematicDistortion::default());
                c.depth_noise.lag = Some(DepthLag { frames: 2.0 });
                c.motion_scale = 1.5;
                c
            }
            Preset::Occluded => SynthConfig {
                occlusion: Some((120, 30)),
                ..kinect
            },
            Preset::Twin(i) => twins::config(&TWINS[*i]),
            Preset::Loop => {
                let mut c = kinect;
                c.trajectory = Trajectory::Loop;
                c.depth_noise.distortion = Some(SystematicDistortion {
                    scale_error: 0.0,
                    wobble_amplitude: 0.03,
                    ..SystematicDistortion::default()
                });
                c
            }
        }
    }

    /// Frames a sequence of this preset has when the user does not say: 300 (10 s at 30 Hz),
    /// except `loop`: its whole circuit plus 15 s of revisit (55 s, 1650 frames), enough
    /// keyframes in the revisited place for loop closing's 3-keyframe consistency check; and the
    /// twins: their real sequence's duration.
    pub fn default_frames(&self) -> usize {
        match self {
            Preset::Loop => 1650,
            Preset::Twin(i) => twins::frames(&TWINS[*i]),
            _ => 300,
        }
    }
}

impl fmt::Display for Preset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl SynthConfig {
    /// The configuration of the preset called `name`; the error lists the valid names.
    pub fn preset(name: &str) -> Result<SynthConfig, SynthError> {
        Ok(Preset::from_name(name)?.config())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::EFFECTS;

    #[test]
    fn every_preset_name_round_trips_and_validates() {
        // On every core: a twin's configuration solves its hand-held path (64 presets, 17 s on
        // one core).
        use rayon::prelude::*;
        preset_names().par_iter().for_each(|name| {
            let p = Preset::from_name(name).unwrap();
            assert_eq!(p.name(), *name);
            p.config().validate().unwrap();
        });
        assert_eq!(Preset::all().count(), preset_names().len());
    }

    /// `full` without each effect in turn, each checked valid and idempotent (removing twice is
    /// removing once).
    fn without_each(full: &SynthConfig) -> Vec<(&'static str, SynthConfig)> {
        EFFECTS
            .iter()
            .map(|&(name, _)| {
                let mut c = full.clone();
                c.without(name).unwrap();
                c.validate().unwrap();
                let mut again = c.clone();
                again.without(name).unwrap();
                assert_eq!(again, c, "{name}: removing twice is removing once");
                (name, c)
            })
            .collect()
    }

    #[test]
    fn every_effect_can_be_removed_alone() {
        let full = SynthConfig::preset("twin_fr1_desk").unwrap();
        for (name, c) in without_each(&full) {
            // Each effect the twin has is gone.
            if !matches!(name, "misregistration" | "depth_distortion") {
                assert_ne!(c, full, "{name}: the twin has this effect");
            }
        }
        let e = full.clone().without("fog").unwrap_err().to_string();
        assert!(e.contains("fog") && e.contains("rolling_shutter"), "{e}");
    }

    #[test]
    fn every_effect_can_be_removed_from_a_euroc_twin() {
        let full = SynthConfig::preset("twin_v101").unwrap();
        let stripped = without_each(&full);
        let of = |effect: &str| &stripped.iter().find(|(n, _)| *n == effect).unwrap().1;
        // The lens goes from both cameras of the rig; the mocap noise from the ground truth.
        let c = of("lens");
        assert!(c.camera.distortion.is_none());
        assert!(c.rig.as_ref().unwrap().right.distortion.is_none());
        assert!(of("mocap_noise").mocap_noise.is_none());
    }

    #[test]
    fn unknown_preset_lists_valid_names() {
        let e = SynthConfig::preset("noisy").unwrap_err().to_string();
        assert!(
            e.contains("noisy") && e.contains("kinect") && e.contains("walking"),
            "{e}"
        );
    }

    #[test]
    fn stereo_preset_has_no_depth_and_11cm_baseline() {
        let c = SynthConfig::preset("stereo").unwrap();
        assert!(!c.is_rgbd());
        assert!((c.camera.baseline() - 0.11).abs() < 1e-12);
    }
}
