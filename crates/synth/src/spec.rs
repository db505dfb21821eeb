//! The specification of a sequence: everything that defines it besides the seed, each
//! stage's options side by side — the camera (and a stereo rig), the camera path and motion
//! scale ([`crate::motion`]), the room and moving people ([`crate::world`]), the imaging and the
//! depth-sensor model ([`crate::sensor`]), the clocks and the motion-capture system
//! ([`crate::motion::clock`]). Each option type lives with the stage that reads it; this file
//! puts them together, checks them ([`SynthConfig::validate`]) and strips effects off one at a
//! time for ablations ([`SynthConfig::without`], [`EFFECTS`]). The named presets and twins that
//! fill it in are in `catalog`.

use nalgebra::Isometry3;
use slam_core::{Camera, SensorKind};
use std::sync::Arc;

use crate::error::SynthError;
use crate::motion::clock::{MocapClock, MocapNoise, StreamStamps};
use crate::motion::handheld::{HandHeldPath, Tremor};
use crate::motion::trajectory::Trajectory;
use crate::sensor::depth::{DepthNoise, DEPTH_FACTOR};
use crate::sensor::imaging::Imaging;
use crate::sensor::render::{ImageConfig, Supersampling};
use crate::world::layout::SceneSpec;
use crate::world::people::CHAIRS;
use crate::world::scene::MovingObjects;

/// Everything that defines a sequence besides the seed.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthConfig {
    /// Camera (intrinsics, size, fps, sensor). `SensorKind::Rgbd` renders depth; `Stereo`
    /// renders a right image at baseline `bf / fx` instead. Default: `Camera::tum_fr3()`.
    pub camera: Camera,
    /// Camera path (default `Xyz`).
    pub trajectory: Trajectory,
    /// Time scale of the camera motion: 2 moves twice as fast per frame (default 1).
    pub motion_scale: f64,
    /// Image formation.
    pub image: ImageConfig,
    /// The colour camera's imaging effects (exposure, rolling shutter, vignetting,
    /// auto-exposure, sensor noise); all off by default.
    pub imaging: Imaging,
    /// Depth-sensor model (ignored for stereo).
    pub depth_noise: DepthNoise,
    /// Units per metre of the 16-bit depth the sensor records (RGB-D): the measured depth is
    /// rounded to them in memory, as the TUM writer stores it (default 5000, TUM's; the fr2
    /// twins 5208, the factor ORB-SLAM2's TUM2.yaml reads real fr2 files with, whose Kinect
    /// records depth 4 % long).
    pub depth_units_per_metre: f64,
    /// Moving objects, off by default.
    pub moving_objects: Option<MovingObjects>,
    /// Frames `[start, start + n)` fully covered by a flat featureless surface 0.5 m in front of
    /// the camera (as a hand over the lens), for relocalisation tests. Off by default.
    pub occlusion: Option<(usize, usize)>,
    /// A calibrated, unrectified stereo rig (stereo only): the right image is rendered by its
    /// own camera (intrinsics, lens distortion) at its own pose, and the EuRoC writer puts both
    /// calibrations in `sensor.yaml`. `None` (default): a rectified pair, the right camera
    /// being the left one shifted by `bf / fx` along x.
    pub rig: Option<StereoRig>,
    /// Motion-capture noise on the ground truth the writers put on disk (and the in-memory
    /// sequence's ground truth); the rendering always uses the exact poses. Off by default.
    pub mocap_noise: Option<MocapNoise>,
    /// How the images are stamped (RGB-D only): each stream at its own capture instant with the
    /// host's arrival jitter, as TUM's recordings are. Off by default: every image carries the
    /// exact colour capture instant.
    pub stamps: Option<StreamStamps>,
    /// The motion-capture system's own clock (RGB-D only): ground truth sampled at its rate and
    /// phase, not at the frame instants. Off by default: one exact-time pose per frame.
    pub mocap_clock: Option<MocapClock>,
    /// The room and its furniture (default: the office with its fixed furniture).
    pub scene: SceneSpec,
}

/// An unrectified stereo rig as a calibration describes it (EuRoC's `sensor.yaml` pair): the
/// left camera is [`SynthConfig::camera`], the right one is here.
#[derive(Clone, Debug, PartialEq)]
pub struct StereoRig {
    /// The right camera (cam1): its intrinsics, size and lens distortion.
    pub right: Camera,
    /// Pose of the right camera in the left camera's frame, T_cam0_cam1.
    pub left_from_right: Isometry3<f64>,
    /// Pose of the left camera in the body (IMU) frame, T_BS of cam0: the ground truth is
    /// written for the body, as EuRoC's is.
    pub body_from_left: Isometry3<f64>,
}

impl StereoRig {
    /// T_BS of the right camera: its pose in the body frame.
    pub fn body_from_right(&self) -> Isometry3<f64> {
        self.body_from_left * self.left_from_right
    }
}

impl Default for SynthConfig {
    fn default() -> Self {
        SynthConfig {
            camera: Camera::tum_fr3(),
            trajectory: Trajectory::Xyz,
            motion_scale: 1.0,
            image: ImageConfig::default(),
            imaging: Imaging::default(),
            depth_noise: DepthNoise::default(),
            depth_units_per_metre: DEPTH_FACTOR,
            moving_objects: None,
            occlusion: None,
            rig: None,
            mocap_noise: None,
            stamps: None,
            mocap_clock: None,
            scene: SceneSpec::default(),
        }
    }
}

/// The effects a configuration can be stripped of one at a time ([`SynthConfig::without`]),
/// with what each removes: the names of an ablation.
pub const EFFECTS: [(&str, &str); 19] = [
    (
        "lens",
        "lens distortion written into the images (the camera becomes a pinhole)",
    ),
    ("blur", "exposure integration: motion blur"),
    ("rolling_shutter", "rows read out one after another"),
    ("vignetting", "brightness fall-off towards the corners"),
    (
        "auto_exposure",
        "exposure and gain following the scene's brightness",
    ),
    (
        "sensor_noise",
        "shot and read noise (the constant image noise stays)",
    ),
    (
        "image_noise",
        "all image noise: sensor noise and the constant grey-level noise",
    ),
    (
        "tremor",
        "hand tremor on a hand-held path (mean speeds re-solved without it)",
    ),
    (
        "depth_lag",
        "depth sampled at a different instant from colour",
    ),
    ("axial", "axial depth noise"),
    ("quantisation", "disparity quantisation of depth"),
    ("lateral", "lateral depth noise"),
    (
        "holes",
        "depth holes (range, grazing incidence, boundaries)",
    ),
    ("misregistration", "RGB-depth misregistration"),
    ("depth_distortion", "systematic depth distortion"),
    (
        "mocap_noise",
        "motion-capture noise on the written ground truth",
    ),
    (
        "layout",
        "furniture and clutter drawn from the seed (back to the room's fixed layout)",
    ),
    (
        "stamp_jitter",
        "each stream stamped at its own capture instant with arrival jitter (back to exact colour stamps)",
    ),
    (
        "mocap_clock",
        "ground truth on the motion-capture system's own clock (back to exact poses at the frame instants)",
    ),
];

impl SynthConfig {
    /// This configuration without the effect called `name` (see [`EFFECTS`]); an unknown name
    /// is an error listing the valid ones. Removing an effect the configuration does not have
    /// changes nothing.
    pub fn without(&mut self, name: &str) -> Result<(), SynthError> {
        let d = &mut self.depth_noise;
        match name {
            "lens" => {
                self.camera.distortion = None;
                if let Some(r) = &mut self.rig {
                    r.right.distortion = None;
                }
            }
            "blur" => self.imaging.exposure = None,
            "rolling_shutter" => self.imaging.rolling_shutter = None,
            "vignetting" => self.imaging.vignetting = None,
            "auto_exposure" => self.imaging.auto_exposure = None,
            "sensor_noise" => self.imaging.sensor_noise = None,
            "image_noise" => {
                self.imaging.sensor_noise = None;
                self.image.noise_sigma = 0.0;
            }
            "tremor" => {
                if let Trajectory::HandHeld(p) = &self.trajectory {
                    let mut spec = p.spec().clone();
                    spec.tremor = Tremor {
                        position_m: 0.0,
                        angle_rad: 0.0,
                    };
                    spec.shake = None;
                    self.trajectory = Trajectory::HandHeld(Arc::new(HandHeldPath::new(spec)));
                }
            }
            "depth_lag" => d.lag = None,
            "axial" => d.axial = None,
            "quantisation" => d.quantisation = None,
            "lateral" => d.lateral = None,
            "holes" => d.holes = None,
            "misregistration" => d.misregistration = None,
            "depth_distortion" => d.distortion = None,
            "mocap_noise" => self.mocap_noise = None,
            "layout" => self.scene.seeded_layout = false,
            "stamp_jitter" => self.stamps = None,
            "mocap_clock" => self.mocap_clock = None,
            _ => {
                return Err(SynthError::UnknownName {
                    what: "effect",
                    name: name.to_string(),
                    valid: EFFECTS.map(|e| e.0).join(", "),
                })
            }
        }
        Ok(())
    }

    /// Whether this configuration renders a depth image (RGB-D) rather than a right image.
    pub fn is_rgbd(&self) -> bool {
        self.camera.sensor == SensorKind::Rgbd
    }

    /// Checks the values a user can get wrong (sizes, rates, ranges).
    pub fn validate(&self) -> Result<(), SynthError> {
        let bad = |m: &str| Err(SynthError::InvalidConfig(m.to_string()));
        let c = &self.camera;
        if c.width < 16 || c.height < 16 || c.width > 8192 || c.height > 8192 {
            return bad("image size must be within 16..8192 pixels");
        }
        if !(c.fx > 0.0 && c.fy > 0.0 && c.fps > 0.0) {
            return bad("fx, fy and fps must be positive");
        }
        if c.sensor == SensorKind::Stereo && c.bf <= 0.0 {
            return bad("stereo needs a positive bf");
        }
        if !(self.motion_scale.is_finite() && self.motion_scale >= 0.0) {
            return bad("motion_scale must be finite and >= 0");
        }
        if self.image.noise_sigma.is_nan() || self.image.noise_sigma < 0.0 {
            return bad("image noise sigma must be >= 0");
        }
        if let Supersampling::Grid(n) = self.image.supersampling {
            if !(2..=8).contains(&n) {
                return bad("grid supersampling must be 2..=8");
            }
        }
        let im = &self.imaging;
        if let Some(e) = &im.exposure {
            if !(e.time_s >= 0.0 && e.time_s <= 1.0 / c.fps + 1e-12) {
                return bad("exposure time must be within 0..one frame period");
            }
            if !(1..=64).contains(&e.samples) {
                return bad("exposure samples must be 1..=64");
            }
        }
        if let Some(r) = &im.rolling_shutter {
            if !(r.readout_s >= 0.0 && r.readout_s <= 1.0 / c.fps + 1e-12) {
                return bad("rolling-shutter readout must be within 0..one frame period");
            }
        }
        if let Some(v) = &im.vignetting {
            if !(0.0..=1.0).contains(&v.corner) {
                return bad("vignetting corner illumination must be within 0..1");
            }
        }
        if let Some(a) = &im.auto_exposure {
            if !(a.target > 0.0
                && a.target < 255.0
                && (0.0..=1.0).contains(&a.rate)
                && a.step_ev > 0.0
                && a.max_time_s > 0.0
                && a.max_gain >= 1.0
                && a.history <= 1000)
            {
                return bad("auto-exposure needs 0 < target < 255, rate in 0..1, step_ev > 0, max_time_s > 0, max_gain >= 1, history <= 1000");
            }
        }
        if let Some(n) = &im.sensor_noise {
            if !(n.read_dn >= 0.0 && n.electrons_per_dn > 0.0) {
                return bad("sensor noise needs read_dn >= 0 and electrons_per_dn > 0");
            }
        }
        if let Some(r) = &self.rig {
            if c.sensor != SensorKind::Stereo {
                return bad("a stereo rig needs a stereo camera");
            }
            let q = &r.right;
            if q.width != c.width || q.height != c.height || !(q.fx > 0.0 && q.fy > 0.0) {
                return bad("the rig's right camera needs the left one's size and positive fx, fy");
            }
        }
        if let Some(m) = &self.mocap_noise {
            if !(m.position_m >= 0.0 && m.angle_rad >= 0.0) {
                return bad("motion-capture noise needs position_m >= 0 and angle_rad >= 0");
            }
        }
        if !(1000.0..=10_000.0).contains(&self.depth_units_per_metre) {
            return bad("depth units per metre must be within 1000..10000");
        }
        if let Some(s) = &self.stamps {
            if !self.is_rgbd() {
                return bad("stream stamps are for RGB-D sequences (EuRoC's stamps are hardware-synchronised)");
            }
            // Clipped at 4 sigma: consecutive stamps stay at least a fifth of a period apart.
            let max = 0.1 / c.fps;
            let depth = s.depth_jitter_s.unwrap_or(0.0);
            if !((0.0..=max).contains(&s.rgb_jitter_s) && (0.0..=max).contains(&depth)) {
                return bad("stamp jitter must be within 0..a tenth of the frame period");
            }
        }
        if let Some(m) = &self.mocap_clock {
            if !self.is_rgbd() {
                return bad("a motion-capture clock is for RGB-D sequences (EuRoC's ground truth shares the camera's clock)");
            }
            if !(m.rate_hz >= 1.0 && m.rate_hz <= 10_000.0) {
                return bad("motion-capture rate must be within 1..10000 Hz");
            }
        }
        if let Some(m) = &self.moving_objects {
            if !(1..=3).contains(&m.count) {
                return bad("moving object count must be 1..=3");
            }
            if m.bodies.is_some() && m.count > CHAIRS.len() {
                return bad("at most 2 people (one chair each)");
            }
        }
        if let Some(l) = &self.depth_noise.lateral {
            if !(0.0..=10.0).contains(&l.sigma_px) {
                return bad("lateral sigma must be within 0..10 px");
            }
        }
        if let Some(m) = &self.depth_noise.misregistration {
            if m.dx_px.abs() > 64.0 || m.dy_px.abs() > 64.0 {
                return bad("misregistration must be within 64 px");
            }
        }
        Ok(())
    }
}
