//! The sequence generator: random access to frame `i` of (config, seed) — images, depth,
//! timestamp and exact ground-truth pose — computed from scratch, so frames can be produced in
//! any order and in parallel with identical bytes.

use std::sync::Arc;

use nalgebra::{Isometry3, Translation3};
use slam_core::{Camera, DepthImage, FrameInput, GrayImage};

use crate::config::SynthConfig;
use crate::hash::{NoiseKey, Stream};
use crate::noise::{noisy_gray8, noisy_rgb8, rgb_to_gray, sensor_depth};
use crate::render::{Shading, View};
use crate::scene::{Scene, MOVING_ID_BASE, OCCLUDER_ID};
use crate::trajectory::pose_at;
use crate::SynthError;

/// Time stamp of frame 0 in nanoseconds since the epoch (an arbitrary date in 2014, like EuRoC's).
pub const T0_NS: u64 = 1_403_636_580_000_000_000;

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
    /// What a SLAM system is given of this frame (grey image, measured depth or right image);
    /// the ground-truth fields are dropped.
    pub fn into_input(self) -> FrameInput {
        FrameInput {
            timestamp: self.timestamp,
            image: Arc::new(self.gray),
            depth: self.depth.map(Arc::new),
            right: self.right.map(Arc::new),
        }
    }
}

/// Generates the frames of one (config, seed) sequence.
#[derive(Clone, Debug)]
pub struct Generator {
    config: SynthConfig,
    seed: u64,
    scene: Arc<Scene>,
}

impl Generator {
    /// A generator for `config` and `seed`. The scene's textures are drawn here (tens of ms).
    /// Use [`Generator::try_new`] for configurations coming from users.
    pub fn new(config: SynthConfig, seed: u64) -> Self {
        let scene = Arc::new(Scene::new(seed, config.moving_objects.as_ref()));
        Generator {
            config,
            seed,
            scene,
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

    /// Stamp of frame `index` in nanoseconds since the epoch. RGB-D stamps are whole
    /// microseconds (TUM files carry 6 decimals).
    pub fn stamp_ns(&self, index: usize) -> u64 {
        let dt = (index as f64 * 1e9 / self.config.camera.fps).round() as u64;
        let ns = T0_NS + dt;
        if self.config.is_rgbd() {
            (ns + 500) / 1000 * 1000
        } else {
            ns
        }
    }

    /// Stamp of frame `index` in seconds since the epoch.
    pub fn timestamp(&self, index: usize) -> f64 {
        let ns = self.stamp_ns(index);
        (ns / 1000) as f64 * 1e-6 + (ns % 1000) as f64 * 1e-9
    }

    /// Seconds since frame 0.
    pub fn time(&self, index: usize) -> f64 {
        (self.stamp_ns(index) - T0_NS) as f64 * 1e-9
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

    fn occluded(&self, index: usize) -> bool {
        self.config
            .occlusion
            .is_some_and(|(s, n)| index >= s && index < s.saturating_add(n))
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
        let left = view.render(Some(shading));
        let sigma = self.config.image.noise_sigma;
        let key_left = NoiseKey::new(self.seed, index, Stream::ImageLeft);
        let colour = left.colour.as_deref().unwrap_or(&[]);
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
            let rgb = noisy_rgb8(colour, sigma, key_left);
            let gray = GrayImage {
                width: w,
                height: h,
                data: rgb_to_gray(&rgb),
            };
            let model = &self.config.depth_noise;
            let measured = match &model.lag {
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
                        cam,
                        &lagged.depth,
                        &lagged.cos_incidence,
                        self.seed,
                        index,
                    )
                }
                _ => sensor_depth(
                    model,
                    cam,
                    &left.depth,
                    &left.cos_incidence,
                    self.seed,
                    index,
                ),
            };
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
            let gray = GrayImage {
                width: w,
                height: h,
                data: noisy_gray8(colour, sigma, key_left),
            };
            let right_view = View {
                scene: &self.scene,
                placed: &placed,
                camera: cam,
                pose_wc: pose_wc * Translation3::new(cam.baseline(), 0.0, 0.0),
                occluded,
            };
            let right = right_view.render(Some(shading));
            let key_right = NoiseKey::new(self.seed, index, Stream::ImageRight);
            let right = GrayImage {
                width: w,
                height: h,
                data: noisy_gray8(right.colour.as_deref().unwrap_or(&[]), sigma, key_right),
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
