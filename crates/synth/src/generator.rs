//! The sequence generator: random access to frame `i` of (specification, seed) — images,
//! depth, timestamp and exact ground-truth pose — computed from scratch, so frames can be
//! produced in any order and in parallel with identical bytes. It builds the world and the
//! camera path of the specification once, then per frame: ray-casts the view
//! ([`crate::sensor::render`]), images it ([`crate::sensor::imaging`]), measures depth through
//! the sensor model ([`crate::sensor::depth`]) and stamps it ([`crate::motion::clock`]).

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

use nalgebra::{Isometry3, Translation3};
use slam_core::{Camera, ColourImage, DepthImage, FrameInput, GrayImage};

use crate::error::SynthError;
use crate::hash::{NoiseKey, Stream};
use crate::motion::clock::Clock;
use crate::motion::trajectory::pose_at;
use crate::sensor::depth::sensor_depth;
use crate::sensor::imaging::{
    exposed_gray8, exposed_rgb8, noisy_gray8, noisy_rgb8, rgb_to_gray, ExposureSettings, Photometry,
};
use crate::sensor::render::RenderOutput;
use crate::sensor::render::{Exposed, Shading, Supersampling, View};
use crate::spec::SynthConfig;
use crate::world::layout::{layout, SceneSpec, SightLine};
use crate::world::scene::{Scene, MOVING_ID_BASE, OCCLUDER_ID};

/// One generated frame.
#[derive(Clone, Debug)]
pub struct SynthFrame {
    /// Frame index in the sequence.
    pub index: usize,
    /// Capture time, seconds since the epoch (TUM: whole microseconds; stereo: nanoseconds).
    pub timestamp: f64,
    /// Grey (left) image, with image noise.
    pub gray: GrayImage,
    /// RGB8 colour image (RGB-D only), row-major `width * height * 3`; `gray` is its
    /// OpenCV-weighted grey conversion.
    pub rgb: Option<Vec<u8>>,
    /// Measured depth in metres, 0 = hole, multiples of 1/5000 m (RGB-D only).
    pub depth: Option<DepthImage>,
    /// Exact depth of the colour camera at this frame's pose and time (no noise, no lag, no
    /// misregistration), metres. Present for RGB-D and stereo.
    pub depth_true: Option<DepthImage>,
    /// Rectified right image (stereo only), with image noise.
    pub right: Option<GrayImage>,
    /// Exact camera-to-world pose of the left / colour camera.
    pub pose_wc: Isometry3<f64>,
    /// Per pixel: true where a moving object is seen (only when moving objects are on).
    pub moving_mask: Option<Vec<bool>>,
}

impl SynthFrame {
    /// What a SLAM system is given of this frame (grey image, measured depth or right image,
    /// and the colour image the grey one is the luma of); the ground-truth fields are dropped.
    pub fn into_input(self) -> FrameInput {
        let (width, height) = (self.gray.width, self.gray.height);
        FrameInput {
            timestamp: self.timestamp,
            image: Arc::new(self.gray),
            depth: self.depth.map(Arc::new),
            right: self.right.map(Arc::new),
            colour: self.rgb.map(|data| {
                Arc::new(ColourImage {
                    width,
                    height,
                    data,
                })
            }),
        }
    }
}

/// Time samples per pixel of a rolling-shutter render without exposure blur (they only
/// anti-alias: all fall at the row's instant).
const ROLLING_SHUTTER_SAMPLES: usize = 4;

/// Side length divisor of the auto-exposure metering preview (640x480 meters at 80x60).
const METER_DIVISOR: u32 = 8;

/// Where the right camera is relative to the left one.
#[derive(Clone, Copy, Debug)]
enum Offset {
    /// A rectified pair: the baseline along x (the arithmetic the `stereo` preset has always
    /// used, so its bytes stay).
    Shift(Translation3<f64>),
    /// A calibrated rig: T_cam0_cam1.
    Pose(Isometry3<f64>),
}

impl Offset {
    /// The right camera's pose given the left one's.
    fn apply(&self, pose_wc: &Isometry3<f64>) -> Isometry3<f64> {
        match self {
            Offset::Shift(t) => pose_wc * t,
            Offset::Pose(p) => pose_wc * p,
        }
    }
}

/// The scene of (config, seed): the configured room, its furniture kept off the camera's
/// lines of sight every quarter second of the path (the first minute of a path without end).
fn build_scene(config: &SynthConfig, seed: u64) -> Scene {
    let moving = config.moving_objects.as_ref();
    let people = moving.is_some_and(|m| m.bodies.is_some());
    if config.scene == SceneSpec::default() {
        return Scene::new(seed, moving);
    }
    let duration = config.trajectory.duration().unwrap_or(60.0);
    let sight: Vec<SightLine> = (0..=(duration / 0.25).floor() as usize)
        .map(|k| {
            let pose = pose_at(&config.trajectory, (k as f64 * 0.25).min(duration));
            let axis = pose.rotation * nalgebra::Vector3::z();
            SightLine::new(pose.translation.vector, axis)
        })
        .collect();
    Scene::with_layout(seed, moving, &layout(&config.scene, seed, &sight, people))
}

/// Generates the frames of one (config, seed) sequence.
#[derive(Clone, Debug)]
pub struct Generator {
    config: SynthConfig,
    seed: u64,
    scene: Arc<Scene>,
    /// The clocks of the sequence (stamps, ground truth), from the configuration.
    clock: Clock,
    /// Auto-exposure metering previews (grey radiance with vignetting) by frame, a pure
    /// function of (config, seed, frame) kept to avoid re-rendering the controller's history.
    metering: Arc<Mutex<BTreeMap<usize, Arc<Vec<f32>>>>>,
}

impl Generator {
    /// A generator for `config` and `seed`. The scene's textures are drawn here (tens of ms).
    /// Use [`Generator::try_new`] for configurations coming from users.
    pub fn new(config: SynthConfig, seed: u64) -> Self {
        let scene = Arc::new(build_scene(&config, seed));
        let clock = Clock {
            fps: config.camera.fps,
            rgbd: config.is_rgbd(),
            seed,
            stamps: config.stamps,
            depth_lag_frames: config.depth_noise.lag.as_ref().map_or(0.0, |l| l.frames),
            mocap_clock: config.mocap_clock,
            mocap_noise: config.mocap_noise,
        };
        Generator {
            config,
            seed,
            scene,
            clock,
            metering: Arc::default(),
        }
    }

    /// Like [`Generator::new`] after checking the configuration.
    pub fn try_new(config: SynthConfig, seed: u64) -> Result<Self, SynthError> {
        config.validate()?;
        Ok(Self::new(config, seed))
    }

    /// The camera of the sequence (RGB-D: TUM fr3 by default; stereo: the left camera, with
    /// `bf` giving the baseline).
    pub fn camera(&self) -> Camera {
        self.config.camera.clone()
    }

    /// The configuration.
    pub fn config(&self) -> &SynthConfig {
        &self.config
    }

    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The scene (for analyses and tests: surface distances, object ids).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Stamp of frame `index` (its colour image) in nanoseconds since the epoch
    /// ([`Clock::stamp_ns`]).
    pub fn stamp_ns(&self, index: usize) -> u64 {
        self.clock.stamp_ns(index)
    }

    /// Stamp of frame `index` in seconds since the epoch.
    pub fn timestamp(&self, index: usize) -> f64 {
        self.clock.timestamp(index)
    }

    /// Stamp of frame `index`'s depth image in nanoseconds since the epoch
    /// ([`Clock::depth_stamp_ns`]).
    pub fn depth_stamp_ns(&self, index: usize) -> u64 {
        self.clock.depth_stamp_ns(index)
    }

    /// Stamp of frame `index`'s depth image in seconds since the epoch.
    pub fn depth_timestamp(&self, index: usize) -> f64 {
        self.clock.depth_timestamp(index)
    }

    /// Which depth image goes with which colour image among frames `0..n`, as (colour frame,
    /// depth frame) sorted by colour frame: the pairs TUM's associate.py finds in the written
    /// `rgb.txt` and `depth.txt` ([`Clock::stream_pairs`]).
    pub fn stream_pairs(&self, n: usize) -> Vec<(usize, usize)> {
        self.clock.stream_pairs(n)
    }

    /// Seconds since frame 0 of frame `index`'s capture instant (what is rendered).
    pub fn time(&self, index: usize) -> f64 {
        self.clock.time(index)
    }

    /// The ground truth of frames `0..n` as the motion-capture system records it: (stamp in
    /// seconds since the epoch, camera-to-world pose with the motion-capture noise), on its own
    /// clock if it has one ([`Clock::groundtruth`]).
    pub fn groundtruth(&self, n: usize) -> Vec<(f64, Isometry3<f64>)> {
        self.clock.groundtruth(n, |t| self.pose_at_time(t))
    }

    /// Exact camera-to-world pose at `t` seconds since frame 0.
    pub fn pose_at_time(&self, t: f64) -> Isometry3<f64> {
        pose_at(&self.config.trajectory, t * self.config.motion_scale)
    }

    /// Checks that frames `0..n` lie within the trajectory: a recorded path lasts only as long
    /// as its recording, and asking for more frames than it covers is an error naming its
    /// duration and the largest frame count that fits. Built-in paths never end. (A depth lag
    /// looks back in time and is clamped to the recording's start.)
    pub fn check_frames(&self, n: usize) -> Result<(), SynthError> {
        let Some(duration) = self.config.trajectory.duration() else {
            return Ok(());
        };
        let scale = self.config.motion_scale;
        let fits = |frames: usize| frames == 0 || self.time(frames - 1) * scale <= duration;
        if fits(n) {
            return Ok(());
        }
        // The largest count that fits: the estimate from the frame rate, corrected for the
        // rounding of stamps to whole microseconds (time() is monotone in the index).
        let rate = self.config.camera.fps / scale.max(1e-300);
        let mut max = ((duration * rate).floor().min(1e12) as usize).saturating_add(1);
        while max > 1 && !fits(max) {
            max -= 1;
        }
        while max < n && fits(max + 1) {
            max += 1;
        }
        Err(SynthError::TrajectoryTooShort {
            trajectory: self.config.trajectory.name().to_string(),
            duration,
            frames: n,
            needed: self.time(n - 1) * scale,
            max_frames: max,
        })
    }

    /// Exact camera-to-world pose of frame `index`.
    pub fn pose(&self, index: usize) -> Isometry3<f64> {
        self.pose_at_time(self.time(index))
    }

    /// `pose` (of frame `index`) as a motion-capture system reports it
    /// ([`Clock::measured_pose`]).
    pub fn measured_pose(&self, pose: &Isometry3<f64>, index: usize) -> Isometry3<f64> {
        self.clock.measured_pose(pose, index)
    }

    fn occluded(&self, index: usize) -> bool {
        self.config
            .occlusion
            .is_some_and(|(s, n)| index >= s && index < s.saturating_add(n))
    }

    /// The grey radiance (at the nominal exposure, vignetting included) of a small preview of
    /// frame `index`: what the auto-exposure meters.
    fn metering_preview(&self, index: usize) -> Arc<Vec<f32>> {
        if let Some(p) = self
            .metering
            .lock()
            .ok()
            .and_then(|m| m.get(&index).cloned())
        {
            return p;
        }
        let cam = &self.config.camera;
        let k = METER_DIVISOR as f64;
        let small = Camera {
            width: (cam.width / METER_DIVISOR).max(1),
            height: (cam.height / METER_DIVISOR).max(1),
            fx: cam.fx / k,
            fy: cam.fy / k,
            cx: (cam.cx + 0.5) / k - 0.5,
            cy: (cam.cy + 0.5) / k - 0.5,
            ..cam.clone()
        };
        let t = self.time(index);
        let placed = self.scene.place(t);
        let out = View {
            scene: &self.scene,
            placed: &placed,
            camera: &small,
            pose_wc: self.pose_at_time(t),
            occluded: self.occluded(index),
        }
        .render(Some(Shading {
            supersampling: Supersampling::None,
            ambient: self.config.image.ambient,
        }));
        let vig = self.config.imaging.vignetting.as_ref();
        let w = small.width as usize;
        let grey: Vec<f32> = out
            .colour
            .unwrap_or_default()
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let l = 0.299 * c[0] as f64 + 0.587 * c[1] as f64 + 0.114 * c[2] as f64;
                let g = vig.map_or(1.0, |v| v.gain(&small, (i % w) as f64, (i / w) as f64));
                (l * g) as f32
            })
            .collect();
        let grey = Arc::new(grey);
        if let Ok(mut m) = self.metering.lock() {
            // Keep a window of recent frames: sequential generation re-reads only the last
            // `history` previews.
            let keep = self
                .config
                .imaging
                .auto_exposure
                .as_ref()
                .map_or(0, |a| 2 * a.history + 2);
            while m.len() > keep.max(1) {
                let Some((&first, _)) = m.iter().next() else {
                    break;
                };
                m.remove(&first);
            }
            m.insert(index, grey.clone());
        }
        grey
    }

    /// Exposure time, gain and radiance scale of frame `index`. Without auto-exposure: the
    /// nominal exposure at unit gain. With it: the controller run from a converged start
    /// `history` frames back, metering each frame's preview as the sensor would see it at the
    /// settings of that frame (clipped at 255).
    pub fn exposure_settings(&self, index: usize) -> ExposureSettings {
        let im = &self.config.imaging;
        let nominal = im.exposure.as_ref().map_or(0.0, |e| e.time_s);
        let Some(ae) = &im.auto_exposure else {
            return ExposureSettings {
                scale: 1.0,
                time_s: nominal,
                gain: 1.0,
            };
        };
        let start = index.saturating_sub(ae.history);
        let meter = |j: usize, scale: f64| {
            let p = self.metering_preview(j);
            p.iter()
                .map(|&l| (l as f64 * scale).min(255.0))
                .sum::<f64>()
                / p.len().max(1) as f64
        };
        // Converged at the start: the quantised scale that meters the target.
        // The controller's state is the scale the sensor can realise (exposure time and gain
        // within their limits).
        let mut scale = ae.settings(ae.converged(meter(start, 1.0)), nominal).scale;
        for j in start..index {
            scale = ae.settings(ae.step(scale, meter(j, scale)), nominal).scale;
        }
        ae.settings(scale, nominal)
    }

    fn photometry<'a>(&'a self, settings: &ExposureSettings, camera: &'a Camera) -> Photometry<'a> {
        let im = &self.config.imaging;
        Photometry {
            camera,
            scale: settings.scale,
            gain: settings.gain,
            vignetting: im.vignetting.as_ref(),
            sensor: im.sensor_noise.as_ref(),
            sigma: self.config.image.noise_sigma,
        }
    }

    /// Whether any photometric effect is on (else the older constant-noise path is used).
    fn photometric(&self) -> bool {
        let im = &self.config.imaging;
        im.vignetting.is_some() || im.auto_exposure.is_some() || im.sensor_noise.is_some()
    }

    /// Colour exposed over time (motion blur / rolling shutter) of `camera` at `offset` from
    /// the left / colour camera.
    fn exposed_colour(
        &self,
        t: f64,
        (camera, offset): (&Camera, Option<Offset>),
        occluded: bool,
        settings: &ExposureSettings,
    ) -> Vec<[f32; 3]> {
        let im = &self.config.imaging;
        let pose_at = |s: f64| match offset {
            Some(o) => o.apply(&self.pose_at_time(s)),
            None => self.pose_at_time(s),
        };
        let (exposure_s, samples) = match &im.exposure {
            Some(e) => (settings.time_s, e.samples as usize),
            None => (0.0, ROLLING_SHUTTER_SAMPLES),
        };
        Exposed {
            scene: &self.scene,
            camera,
            pose_at: &pose_at,
            occluded,
            time: t,
            exposure_s,
            readout_s: im.rolling_shutter.as_ref().map_or(0.0, |r| r.readout_s),
            samples,
            shading: Shading {
                supersampling: self.config.image.supersampling,
                ambient: self.config.image.ambient,
            },
        }
        .render()
    }

    /// Frame `index`'s measured depth (at time `t`): the depth sensor's model over the rendered
    /// `left` view, or over a view rendered at the depth's lag when the model has one.
    fn measured_depth(
        &self,
        index: usize,
        t: f64,
        left: &RenderOutput,
        occluded: bool,
    ) -> Vec<f32> {
        let cam = &self.config.camera;
        let model = &self.config.depth_noise;
        match &model.lag {
            Some(lag) if lag.frames != 0.0 => {
                let td = t - lag.frames / cam.fps;
                let placed_d = self.scene.place(td);
                let lagged = View {
                    scene: &self.scene,
                    placed: &placed_d,
                    camera: cam,
                    pose_wc: self.pose_at_time(td),
                    occluded,
                }
                .render(None);
                sensor_depth(
                    model,
                    self.config.depth_units_per_metre,
                    cam,
                    &lagged.depth,
                    &lagged.cos_incidence,
                    self.seed,
                    index,
                )
            }
            _ => sensor_depth(
                model,
                self.config.depth_units_per_metre,
                cam,
                &left.depth,
                &left.cos_incidence,
                self.seed,
                index,
            ),
        }
    }

    /// Generates frame `index` (deterministic in (config, seed, index)).
    pub fn frame(&self, index: usize) -> SynthFrame {
        let cam = &self.config.camera;
        let (w, h) = (cam.width as usize, cam.height as usize);
        let t = self.time(index);
        let pose_wc = self.pose_at_time(t);
        let occluded = self.occluded(index);
        let placed = self.scene.place(t);
        let shading = Shading {
            supersampling: self.config.image.supersampling,
            ambient: self.config.image.ambient,
        };
        let view = View {
            scene: &self.scene,
            placed: &placed,
            camera: cam,
            pose_wc,
            occluded,
        };
        let timed = self.config.imaging.is_timed();
        let settings = self.exposure_settings(index);
        let left = view.render(if timed { None } else { Some(shading) });
        let exposed;
        let colour: &[[f32; 3]] = if timed {
            exposed = self.exposed_colour(t, (cam, None), occluded, &settings);
            &exposed
        } else {
            left.colour.as_deref().unwrap_or(&[])
        };
        let sigma = self.config.image.noise_sigma;
        let key_left = NoiseKey::new(self.seed, index, Stream::ImageLeft);
        let moving_mask = self.config.moving_objects.as_ref().map(|_| {
            left.ids
                .iter()
                .map(|&id| (MOVING_ID_BASE..OCCLUDER_ID).contains(&id))
                .collect()
        });
        let depth_true = Some(DepthImage {
            width: w,
            height: h,
            data: left.depth.clone(),
        });
        if self.config.is_rgbd() {
            let rgb = if self.photometric() {
                exposed_rgb8(colour, &self.photometry(&settings, cam), key_left)
            } else {
                noisy_rgb8(colour, sigma, key_left)
            };
            let gray = GrayImage {
                width: w,
                height: h,
                data: rgb_to_gray(&rgb),
            };
            let measured = self.measured_depth(index, t, &left, occluded);
            SynthFrame {
                index,
                timestamp: self.timestamp(index),
                gray,
                rgb: Some(rgb),
                depth: Some(DepthImage {
                    width: w,
                    height: h,
                    data: measured,
                }),
                depth_true,
                right: None,
                pose_wc,
                moving_mask,
            }
        } else {
            let gray_of = |colour: &[[f32; 3]], camera: &Camera, key: NoiseKey| {
                if self.photometric() {
                    exposed_gray8(colour, &self.photometry(&settings, camera), key)
                } else {
                    noisy_gray8(colour, sigma, key)
                }
            };
            let gray = GrayImage {
                width: w,
                height: h,
                data: gray_of(colour, cam, key_left),
            };
            // The right camera: the calibrated rig's (own intrinsics, distortion and pose), or
            // the left one shifted by the baseline (a rectified pair).
            let (right_cam, offset) = match &self.config.rig {
                Some(r) => (&r.right, Offset::Pose(r.left_from_right)),
                None => (
                    cam,
                    Offset::Shift(Translation3::new(cam.baseline(), 0.0, 0.0)),
                ),
            };
            let right_colour = if timed {
                self.exposed_colour(t, (right_cam, Some(offset)), occluded, &settings)
            } else {
                let right_view = View {
                    scene: &self.scene,
                    placed: &placed,
                    camera: right_cam,
                    pose_wc: offset.apply(&pose_wc),
                    occluded,
                };
                right_view.render(Some(shading)).colour.unwrap_or_default()
            };
            let key_right = NoiseKey::new(self.seed, index, Stream::ImageRight);
            let right = GrayImage {
                width: w,
                height: h,
                data: gray_of(&right_colour, right_cam, key_right),
            };
            SynthFrame {
                index,
                timestamp: self.timestamp(index),
                gray,
                rgb: None,
                depth: None,
                depth_true,
                right: Some(right),
                pose_wc,
                moving_mask,
            }
        }
    }

    /// Frames 0..n in order (each generated on demand).
    pub fn frames(&self, n: usize) -> impl Iterator<Item = SynthFrame> + '_ {
        (0..n).map(move |i| self.frame(i))
    }
}
