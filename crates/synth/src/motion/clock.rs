//! The clocks of a sequence: when each frame is captured, how its colour and depth images are
//! stamped ([`StreamStamps`]: a host's arrival jitter, a free-running depth stream), which
//! depth image TUM's associate.py pairs with which colour image, and the ground truth as a
//! motion-capture system records it ([`MocapClock`]: its own rate and phase; [`MocapNoise`]:
//! its error). Every random number is a hash of (seed, frame, stream): see [`crate::hash`].

use nalgebra::{Isometry3, Translation3};

use crate::hash::{NoiseKey, Stream};

/// Time stamp of frame 0 in nanoseconds since the epoch (an arbitrary date in 2014, like EuRoC's).
pub const T0_NS: u64 = 1_403_636_580_000_000_000;

/// The association window of TUM's associate.py, seconds.
pub const ASSOCIATE_MAX_DIFFERENCE_S: f64 = 0.02;

/// `ns` rounded to the nearest multiple of `unit` nanoseconds (a stamp's resolution).
fn round_to(ns: i128, unit: i128) -> u64 {
    ((ns + unit / 2).div_euclid(unit) * unit) as u64
}

/// Nanoseconds since the epoch as seconds, exact to the microsecond.
fn seconds(ns: u64) -> f64 {
    (ns / 1000) as f64 * 1e-6 + (ns % 1000) as f64 * 1e-9
}

/// A stamp as TUM's files write it (image names, `rgb.txt`, `depth.txt`): seconds with 6
/// decimals.
pub fn stamp_name(timestamp: f64) -> String {
    format!("{timestamp:.6}")
}

/// White noise of a motion-capture system on the ground-truth poses: each written pose is the
/// true one moved by an independent Gaussian displacement (per world axis) and rotated by an
/// independent Gaussian rotation vector (per body axis), drawn from the sequence seed and the
/// frame ([`Clock::measured_pose`]).
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
/// own capture instant (the depth lag, [`Clock::depth_lag_frames`], earlier) with its own
/// jitter (free-running streams: fr1 and fr2's Kinects) ([`Clock::timestamp`],
/// [`Clock::depth_timestamp`]).
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
/// the frame instants ([`Clock::groundtruth`]); evaluation then pairs each frame with
/// the nearest sample, without interpolation, as evaluate_ate.py and evo do on real files.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MocapClock {
    /// Sampling rate, Hz (TUM's MotionAnalysis system: 100).
    pub rate_hz: f64,
}

/// The clocks of one (configuration, seed) sequence. Built by the generator from the
/// configuration: the camera's rate, its stream stamps and depth lag, the motion-capture clock
/// and noise.
#[derive(Clone, Debug)]
pub struct Clock {
    /// Frame rate of the camera, Hz.
    pub fps: f64,
    /// An RGB-D sequence: capture instants are whole microseconds (TUM files carry 6
    /// decimals); a stereo sequence's are nanoseconds.
    pub rgbd: bool,
    /// The sequence seed (stamp jitter, motion-capture phase and noise).
    pub seed: u64,
    /// How the images are stamped; `None`: the exact colour capture instant.
    pub stamps: Option<StreamStamps>,
    /// Lag of the depth image behind the colour image, frames (0 without one).
    pub depth_lag_frames: f64,
    /// The motion-capture system's own clock; `None`: one pose per frame at its instant.
    pub mocap_clock: Option<MocapClock>,
    /// The motion-capture system's error; `None`: exact poses.
    pub mocap_noise: Option<MocapNoise>,
}

impl Clock {
    /// Capture instant of frame `index` (its colour image) in nanoseconds since the epoch.
    /// RGB-D instants are whole microseconds (TUM files carry 6 decimals).
    pub fn capture_ns(&self, index: usize) -> u64 {
        let dt = (index as f64 * 1e9 / self.fps).round() as u64;
        let ns = T0_NS + dt;
        if self.rgbd {
            round_to(ns as i128, 1000)
        } else {
            ns
        }
    }

    /// The arrival jitter of stream `item` (0 colour, 1 depth) of frame `index`, nanoseconds:
    /// Gaussian with standard deviation `sd_s`, clipped at 4 sigma.
    fn jitter_ns(&self, index: usize, item: u64, sd_s: f64) -> i128 {
        let z = NoiseKey::new(self.seed, index, Stream::Stamps).normal(item);
        (z.clamp(-4.0, 4.0) * sd_s * 1e9).round() as i128
    }

    /// Stamp of frame `index` (its colour image) in nanoseconds since the epoch: its capture
    /// instant, plus the arrival jitter with [`StreamStamps`]. RGB-D stamps are
    /// whole microseconds.
    pub fn stamp_ns(&self, index: usize) -> u64 {
        let ns = self.capture_ns(index);
        match &self.stamps {
            Some(s) => round_to(ns as i128 + self.jitter_ns(index, 0, s.rgb_jitter_s), 1000),
            None => ns,
        }
    }

    /// Stamp of frame `index` in seconds since the epoch.
    pub fn timestamp(&self, index: usize) -> f64 {
        seconds(self.stamp_ns(index))
    }

    /// Stamp of frame `index`'s depth image in nanoseconds since the epoch: with
    /// [`StreamStamps`] of a free-running depth stream its own capture instant (the depth lag
    /// earlier than the colour's) plus its own arrival jitter, whole microseconds; otherwise
    /// the colour stamp.
    pub fn depth_stamp_ns(&self, index: usize) -> u64 {
        let Some(sd) = self.stamps.and_then(|s| s.depth_jitter_s) else {
            return self.stamp_ns(index);
        };
        let lag_ns = (self.depth_lag_frames / self.fps * 1e9).round() as i128;
        round_to(
            self.capture_ns(index) as i128 - lag_ns + self.jitter_ns(index, 1, sd),
            1000,
        )
    }

    /// Stamp of frame `index`'s depth image in seconds since the epoch.
    pub fn depth_timestamp(&self, index: usize) -> f64 {
        seconds(self.depth_stamp_ns(index))
    }

    /// Which depth image goes with which colour image among frames `0..n`, as (colour frame,
    /// depth frame) sorted by colour frame: the pairs TUM's associate.py finds in the written
    /// `rgb.txt` and `depth.txt` (stamps closer than 20 ms, nearest first, each once). With a
    /// free-running depth stream ([`StreamStamps::depth_jitter_s`]) a colour
    /// image whose jitter brings the next depth image nearer than its own gets that one, and
    /// a colour image left without depth drops out, as on real fr1 / fr2 recordings;
    /// otherwise every frame is paired with its own depth.
    pub fn stream_pairs(&self, n: usize) -> Vec<(usize, usize)> {
        if self.stamps.and_then(|s| s.depth_jitter_s).is_none() {
            return (0..n).map(|i| (i, i)).collect();
        }
        // The stamps as the files carry them (6 decimals) and a reader parses them.
        let read = |s: f64| stamp_name(s).parse::<f64>().unwrap_or(s);
        let rgb: Vec<f64> = (0..n).map(|i| read(self.timestamp(i))).collect();
        let depth: Vec<f64> = (0..n).map(|i| read(self.depth_timestamp(i))).collect();
        ate_eval::associate(
            &rgb,
            &depth,
            ASSOCIATE_MAX_DIFFERENCE_S,
            0.0,
            ate_eval::AssociationMode::Tum,
        )
    }

    /// Seconds since frame 0 of frame `index`'s capture instant (what is rendered).
    pub fn time(&self, index: usize) -> f64 {
        (self.capture_ns(index) - T0_NS) as f64 * 1e-9
    }

    /// The ground truth of frames `0..n` as the motion-capture system records it: (stamp in
    /// seconds since the epoch, camera-to-world pose with the motion-capture noise). Without a
    /// [`MocapClock`], one pose per frame at its capture instant; with one, a
    /// pose every `1 / rate_hz` from a phase drawn from the seed, stamps rounded to 0.1 ms,
    /// from the last sample at or before frame 0's capture instant to the first at or after
    /// frame `n - 1`'s, so every frame has a sample within half a period (the noise drawn per
    /// sample).
    pub fn groundtruth(
        &self,
        n: usize,
        pose_at_time: impl Fn(f64) -> Isometry3<f64>,
    ) -> Vec<(f64, Isometry3<f64>)> {
        let Some(clock) = &self.mocap_clock else {
            return (0..n)
                .map(|i| {
                    let t = seconds(self.capture_ns(i));
                    (t, self.measured_pose(&pose_at_time(self.time(i)), i))
                })
                .collect();
        };
        if n == 0 {
            return Vec::new();
        }
        const STAMP_NS: i128 = 100_000; // 0.1 ms, the resolution of TUM's ground-truth files
        let period = 1e9 / clock.rate_hz;
        let key = NoiseKey::new(self.seed, 0, Stream::Stamps);
        let phase = key.uniform(2) * period;
        // Instants in nanoseconds since T0, small enough for f64 to hold them exactly to the
        // nanosecond (the epoch's 1.4e18 would not).
        let since_t0 = |i: usize| (self.capture_ns(i) - T0_NS) as f64;
        let k0 = ((since_t0(0) - phase) / period).floor() as i64;
        let k1 = ((since_t0(n - 1) - phase) / period).ceil() as i64;
        (k0..=k1)
            .enumerate()
            .map(|(sample, k)| {
                let instant = T0_NS as i128 + (phase + k as f64 * period).round() as i128;
                let ns = round_to(instant, STAMP_NS);
                let t = (ns as i128 - T0_NS as i128) as f64 * 1e-9;
                (seconds(ns), self.measured_pose(&pose_at_time(t), sample))
            })
            .collect()
    }

    /// `pose` (of frame `index`) as a motion-capture system reports it: with
    /// [`MocapNoise`], the position moved by a Gaussian error per world axis
    /// and the orientation rotated by a Gaussian rotation vector (body axes), drawn from
    /// (seed, frame); without, `pose` itself.
    pub fn measured_pose(&self, pose: &Isometry3<f64>, index: usize) -> Isometry3<f64> {
        let Some(m) = &self.mocap_noise else {
            return *pose;
        };
        let key = NoiseKey::new(self.seed, index, Stream::Mocap);
        let n = |k: u64| key.normal(k);
        let dp = nalgebra::Vector3::new(n(0), n(1), n(2)) * m.position_m;
        let dr = nalgebra::Vector3::new(n(3), n(4), n(5)) * m.angle_rad;
        let rotation = if m.angle_rad > 0.0 {
            pose.rotation * nalgebra::UnitQuaternion::from_scaled_axis(dr)
        } else {
            pose.rotation // a position-only tracker: orientation left exact
        };
        Isometry3::from_parts(Translation3::from(pose.translation.vector + dp), rotation)
    }
}
