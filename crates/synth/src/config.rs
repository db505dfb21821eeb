//! Configuration of a synthetic sequence: camera, trajectory, scene options, image noise and
//! every component of the depth-sensor model, each its own switch; plus the named presets.

use nalgebra::Isometry3;
use slam_core::{Camera, SensorKind};
use std::fmt;
use std::path::Path;
use std::sync::Arc;

use crate::handheld::HandHeldPath;
use crate::imaging::Imaging;
use crate::people::Activity;
use crate::recorded::RecordedPath;
use crate::SynthError;

/// Camera path through the room. The built-in paths run at the camera's frame rate, are smooth
/// (C-infinity), and move at most a few cm and a few degrees per frame at `motion_scale` 1; a
/// recorded path moves as its recording did.
#[derive(Clone, Debug, PartialEq)]
pub enum Trajectory {
    /// Handheld-like translation (+-25 cm) with a gentle look-at wobble, like fr1/fr3 `xyz`.
    Xyz,
    /// Rotation-heavy: roll / pitch / yaw of +-15..20 degrees around a nearly fixed point, like `rpy`.
    Rpy,
    /// A full 360-degree turn about the vertical in 20 s, from near the middle of the room.
    Spin,
    /// A closed circuit around the room for loop closing: the camera walks a rounded path
    /// (an ellipse of 1.6 x 1.5 m semi-axes, 9.8 m round) at hand-held height (1.5 m), looking
    /// ahead along the path at the walls and furniture, with a gentle hand-held wobble; one
    /// circuit in [`crate::trajectory::LOOP_PERIOD`] = 40 s.
    /// The path is periodic: at 40 s the camera is back at its start pose and then re-sees
    /// the start (render ~55 s = 1650 frames for the circuit plus 15 s of revisit).
    Loop,
    /// A recorded path: a TUM trajectory file levelled and placed in the room (see
    /// [`crate::recorded`]); time is the recording's, since its first stamp.
    Recorded(Arc<RecordedPath>),
    /// A hand-held path with a recorded sequence's duration and mean speeds (the twins'; see
    /// [`crate::handheld`]); time since its start.
    HandHeld(Arc<HandHeldPath>),
}

impl Trajectory {
    /// Names of the built-in paths, accepted by [`Trajectory::from_name`].
    pub const NAMES: [&'static str; 4] = ["xyz", "rpy", "spin", "loop"];

    /// Parses a built-in name: `xyz`, `rpy`, `spin` or `loop`.
    pub fn from_name(name: &str) -> Result<Self, SynthError> {
        match name {
            "xyz" => Ok(Trajectory::Xyz),
            "rpy" => Ok(Trajectory::Rpy),
            "spin" => Ok(Trajectory::Spin),
            "loop" => Ok(Trajectory::Loop),
            _ => Err(SynthError::UnknownName {
                what: "trajectory",
                name: name.to_string(),
                valid: Self::NAMES.join(", "),
            }),
        }
    }

    /// Parses a command-line value: a built-in name, else the path of an existing TUM
    /// trajectory file, read and fitted into the room by [`RecordedPath::load`]. A value that is
    /// neither fails with the valid names.
    pub fn from_arg(value: &str) -> Result<Self, SynthError> {
        if let Ok(t) = Self::from_name(value) {
            return Ok(t);
        }
        let path = Path::new(value);
        if path.is_file() {
            return Ok(Trajectory::Recorded(Arc::new(RecordedPath::load(path)?)));
        }
        Err(SynthError::UnknownName {
            what: "trajectory",
            name: value.to_string(),
            valid: format!(
                "{}, or the path of a TUM trajectory file",
                Self::NAMES.join(", ")
            ),
        })
    }

    /// The built-in path's name, or a recorded path's file name as given.
    pub fn name(&self) -> &str {
        match self {
            Trajectory::Xyz => "xyz",
            Trajectory::Rpy => "rpy",
            Trajectory::Spin => "spin",
            Trajectory::Loop => "loop",
            Trajectory::Recorded(r) => r.label(),
            Trajectory::HandHeld(h) => h.label(),
        }
    }

    /// How long the path lasts in seconds of trajectory time, `None` for the built-in paths
    /// (defined for all times).
    pub fn duration(&self) -> Option<f64> {
        match self {
            Trajectory::Recorded(r) => Some(r.duration()),
            Trajectory::HandHeld(h) => Some(h.duration()),
            _ => None,
        }
    }
}

/// How many rays are averaged for a pixel's colour (depth always comes from the pixel centre).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Supersampling {
    /// One ray through the pixel centre (aliased edges).
    None,
    /// Centre ray weighted 1/2 plus the four pixel corners weighted 1/8 each (corners shared
    /// with the neighbours): about 2 rays per pixel. Default.
    Quincunx,
    /// An n x n grid of rays inside the pixel (n >= 2), plus the centre ray for depth.
    Grid(u32),
}

/// Photometric settings of the rendered images.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageConfig {
    /// Standard deviation of the additive Gaussian grey-level noise, in grey levels (default 2.0).
    pub noise_sigma: f64,
    /// Anti-aliasing (default [`Supersampling::Quincunx`]).
    pub supersampling: Supersampling,
    /// Ambient share of the Lambertian shading, 0..1 (default 0.45).
    pub ambient: f64,
}

impl Default for ImageConfig {
    fn default() -> Self {
        ImageConfig {
            noise_sigma: 2.0,
            supersampling: Supersampling::Quincunx,
            ambient: 0.45,
        }
    }
}

/// Axial noise after Nguyen et al. 2012: sigma_z(z, theta) = a + b (z - z0)^2 metres, plus
/// (when `grazing` is on) 0.0001 / sqrt(z) * theta^2 / (pi/2 - theta)^2 for incidence theta.
#[derive(Clone, Debug, PartialEq)]
pub struct AxialNoise {
    /// Constant term `a`, metres (default 0.0012).
    pub a: f64,
    /// Quadratic coefficient `b`, 1/metre (default 0.0019).
    pub b: f64,
    /// Depth of the minimum, metres (default 0.4).
    pub z0: f64,
    /// Add Nguyen's grazing-angle term (default true).
    pub grazing: bool,
}

impl Default for AxialNoise {
    fn default() -> Self {
        AxialNoise {
            a: 0.0012,
            b: 0.0019,
            z0: 0.4,
            grazing: true,
        }
    }
}

impl AxialNoise {
    /// Standard deviation in metres at depth `z` (metres) and incidence angle `theta` (radians).
    pub fn sigma(&self, z: f64, theta: f64) -> f64 {
        let mut s = self.a + self.b * (z - self.z0).powi(2);
        if self.grazing {
            let t = theta.clamp(0.0, std::f64::consts::FRAC_PI_2 - 1e-3);
            s += 0.0001 / z.max(1e-3).sqrt() * t * t / (std::f64::consts::FRAC_PI_2 - t).powi(2);
        }
        s
    }
}

/// Disparity quantisation of a structured-light sensor: depth is measured as disparity
/// d = bf / z rounded to 1/`subpixel` pixel, then converted back.
#[derive(Clone, Debug, PartialEq)]
pub struct DisparityQuantisation {
    /// Projector-camera baseline times focal length, metres * pixels (Kinect v1: 0.075 m * 580 px = 43.5).
    pub bf: f64,
    /// Disparity sub-pixel resolution, steps per pixel (Kinect v1: 8).
    pub subpixel: f64,
}

impl Default for DisparityQuantisation {
    fn default() -> Self {
        DisparityQuantisation {
            bf: 43.5,
            subpixel: 8.0,
        }
    }
}

/// Lateral noise: a pixel's depth is taken from the neighbour at an offset of
/// (round N(0, sigma), round N(0, sigma)) pixels, which mixes fore- and background at boundaries.
#[derive(Clone, Debug, PartialEq)]
pub struct LateralNoise {
    /// Standard deviation of the offset, pixels (default 0.8).
    pub sigma_px: f64,
}

impl Default for LateralNoise {
    fn default() -> Self {
        LateralNoise { sigma_px: 0.8 }
    }
}

/// Where the sensor returns no depth (value 0).
#[derive(Clone, Debug, PartialEq)]
pub struct Holes {
    /// Minimum range, metres (default 0.4).
    pub min_range: f64,
    /// Maximum range where every pixel still has depth, metres (default 4.0).
    pub max_range: f64,
    /// The per-pixel cut-off is uniform in [max_range, max_range + max_range_spread] (default 1.0 m).
    pub max_range_spread: f64,
    /// Incidence angle beyond which no depth is returned, degrees (default 78).
    pub max_incidence_deg: f64,
    /// Probability of a hole at a depth-boundary pixel (default 0.35).
    pub boundary_probability: f64,
    /// A pixel is on a boundary when a 4-neighbour's depth differs by more than this fraction
    /// of its own depth (default 0.05).
    pub boundary_jump: f64,
}

impl Default for Holes {
    fn default() -> Self {
        Holes {
            min_range: 0.4,
            max_range: 4.0,
            max_range_spread: 1.0,
            max_incidence_deg: 78.0,
            boundary_probability: 0.35,
            boundary_jump: 0.05,
        }
    }
}

/// RGB-to-depth misregistration: the depth at RGB pixel (u, v) is the sensor's depth at
/// (u + dx, v + dy) (nearest pixel).
#[derive(Clone, Debug, PartialEq)]
pub struct Misregistration {
    /// Horizontal shift, pixels (preset `boundary`: 4).
    pub dx_px: f64,
    /// Vertical shift, pixels (preset `boundary`: 1).
    pub dy_px: f64,
}

/// Depth time lag (as fr2's depth / colour offset, or an unsynchronised sensor): the depth image
/// is rendered from the camera pose and scene `frames` frames earlier, but stamped as the colour.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthLag {
    /// Lag in frames, may be fractional (preset `lag`: 2).
    pub frames: f64,
}

/// Systematic depth distortion of a miscalibrated sensor: z' = z (1 + scale_error +
/// wobble_amplitude * (r / r_max)^2 * cos(2 pi r / wobble_period_px)), r = distance from the
/// image centre in pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct SystematicDistortion {
    /// Relative depth scale error (preset `distorted`: 0.04, i.e. +4 %).
    pub scale_error: f64,
    /// Relative amplitude of the radial wobble at the image corner (preset: 0.015).
    pub wobble_amplitude: f64,
    /// Radial period of the wobble, pixels (preset: 180).
    pub wobble_period_px: f64,
}

impl Default for SystematicDistortion {
    fn default() -> Self {
        SystematicDistortion {
            scale_error: 0.04,
            wobble_amplitude: 0.015,
            wobble_period_px: 180.0,
        }
    }
}

/// The depth-sensor model (RGB-D only). `None` switches a component off.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DepthNoise {
    /// Random axial noise.
    pub axial: Option<AxialNoise>,
    /// Disparity quantisation.
    pub quantisation: Option<DisparityQuantisation>,
    /// Lateral (neighbour-mixing) noise.
    pub lateral: Option<LateralNoise>,
    /// Missing depth.
    pub holes: Option<Holes>,
    /// RGB-depth misregistration.
    pub misregistration: Option<Misregistration>,
    /// Depth time lag.
    pub lag: Option<DepthLag>,
    /// Systematic (calibration) distortion.
    pub distortion: Option<SystematicDistortion>,
}

impl DepthNoise {
    /// The Kinect-like model: axial + quantisation + lateral + holes, all at their defaults.
    pub fn kinect() -> Self {
        DepthNoise {
            axial: Some(AxialNoise::default()),
            quantisation: Some(DisparityQuantisation::default()),
            lateral: Some(LateralNoise::default()),
            holes: Some(Holes::default()),
            ..DepthNoise::default()
        }
    }
}

/// Independently moving textured objects ("people", like fr3_walking).
#[derive(Clone, Debug, PartialEq)]
pub struct MovingObjects {
    /// How many (1..=3; default 2).
    pub count: usize,
    /// Walking speed multiplier (default 1; 1 is about 0.4-0.6 m/s). Not used by bodies.
    pub speed: f64,
    /// Articulated people doing this instead of the textured blocks (count 1..=2), with the
    /// desk's chairs (default `None`: blocks, as the `walking` preset has always had).
    pub bodies: Option<Activity>,
}

impl Default for MovingObjects {
    fn default() -> Self {
        MovingObjects {
            count: 2,
            speed: 1.0,
            bodies: None,
        }
    }
}

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

/// The kind of room a sequence is rendered in ([`crate::layout`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Room {
    /// The 5 x 5 x 2.7 m office around a desk of every preset (larger with a seeded layout).
    #[default]
    Office,
    /// A motion-capture room like EuRoC's Vicon room: about 8 x 8 x 4 m, its walls lined with
    /// grey padded mats, a grey carpet with marker strips, a play mat and a checkerboard.
    ViconRoom,
    /// An industrial hall like EuRoC's machine hall: about 20 x 14 x 9 m of concrete with
    /// machines, columns, shelves and crates.
    MachineHall,
}

/// The room and how its furniture is placed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneSpec {
    /// The room.
    pub room: Room,
    /// Furniture and clutter drawn from the sequence seed (room size, what stands where, what
    /// lies on the desk), kept off the camera's lines of sight. Off: the office's fixed
    /// furniture, or the other rooms' layout of seed 0.
    pub seeded_layout: bool,
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

/// White noise of a motion-capture system on the ground-truth poses: each written pose is the
/// true one moved by an independent Gaussian displacement (per world axis) and rotated by an
/// independent Gaussian rotation vector (per body axis), drawn from the sequence seed and the
/// frame ([`crate::Generator::measured_pose`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MocapNoise {
    /// Standard deviation of the position error per axis, metres.
    pub position_m: f64,
    /// Standard deviation of the orientation error per axis, radians (0: orientation exact).
    pub angle_rad: f64,
}

/// How a recording stamps its images, as a host stamps TUM's Kinect streams on arrival: the
/// colour image at its capture instant plus a white arrival jitter drawn per frame, the depth
/// image either with the colour's stamp (hardware-synchronised streams: fr3's Xtion) or at its
/// own capture instant (a [`DepthLag`] earlier) with its own jitter (free-running streams: fr1
/// and fr2's Kinects) ([`crate::Generator::timestamp`], [`crate::Generator::depth_timestamp`]).
/// The images are not touched: the jitter is an error of the stamps, which evaluation against
/// the ground truth and the readers' colour-depth association see. Without it every image
/// carries the exact colour capture instant (a depth lag then lies about its time, as an
/// unsynchronised sensor does).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamStamps {
    /// Standard deviation of a colour stamp's error from its capture instant, seconds (drawn
    /// Gaussian, clipped at 4 sigma so that stamps stay in order).
    pub rgb_jitter_s: f64,
    /// The same for a depth stamp of a free-running depth stream, seconds; `None`: the depth
    /// image is stamped with its colour image's stamp.
    pub depth_jitter_s: Option<f64>,
}

/// The motion-capture system's own clock: the ground truth is sampled every `1 / rate_hz`
/// seconds from a phase drawn from the seed, stamped to 0.1 ms as TUM's files are, and not at
/// the frame instants ([`crate::Generator::groundtruth`]); evaluation then pairs each frame with
/// the nearest sample, without interpolation, as evaluate_ate.py and evo do on real files.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MocapClock {
    /// Sampling rate, Hz (TUM's MotionAnalysis system: 100).
    pub rate_hz: f64,
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
            depth_units_per_metre: crate::noise::DEPTH_FACTOR,
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
    /// A twin of one of the paper's sequences (TUM or EuRoC): index into
    /// [`crate::twins::TWINS`].
    Twin(usize),
}

const PRESETS: [(Preset, &str); 10] = [
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
            .chain((0..crate::twins::TWINS.len()).map(Preset::Twin))
    }

    /// The preset's name.
    pub fn name(&self) -> &'static str {
        if let Preset::Twin(i) = self {
            return crate::twins::TWINS.get(*i).map_or("?", |t| t.name);
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
    pub fn twin(&self) -> Option<&'static crate::twins::TwinSpec> {
        match self {
            Preset::Twin(i) => crate::twins::TWINS.get(*i),
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
            Preset::Twin(i) => crate::twins::config(&crate::twins::TWINS[*i]),
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
            Preset::Twin(i) => crate::twins::frames(&crate::twins::TWINS[*i]),
            _ => 300,
        }
    }
}

impl fmt::Display for Preset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
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
                    spec.tremor = crate::handheld::Tremor {
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

    /// The configuration of the preset called `name`; the error lists the valid names.
    pub fn preset(name: &str) -> Result<SynthConfig, SynthError> {
        Ok(Preset::from_name(name)?.config())
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
            if m.bodies.is_some() && m.count > crate::people::CHAIRS.len() {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_name_round_trips_and_validates() {
        for name in preset_names() {
            let p = Preset::from_name(name).unwrap();
            assert_eq!(p.name(), *name);
            p.config().validate().unwrap();
        }
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

    #[test]
    fn axial_sigma_matches_nguyen() {
        let a = AxialNoise {
            grazing: false,
            ..AxialNoise::default()
        };
        assert!((a.sigma(1.0, 0.0) - (0.0012 + 0.0019 * 0.36)).abs() < 1e-12);
        let g = AxialNoise::default();
        assert!(g.sigma(2.0, 1.3) > a.sigma(2.0, 1.3) + 0.001);
    }
}
