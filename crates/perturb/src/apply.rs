//! A perturbed sequence: [`perturb_sequence`] wraps a sequence's [`FrameReader`] so that every
//! consumer reads perturbed frames through the same function.
//!
//! Order: the time families choose frames first (`frame-drop`: output frame i is input frame
//! n i; `depth-lag` and `rgb-depth-offset`: the depth image comes from another input frame,
//! at the camera's nominal rate), then the content families apply in the order the chain
//! names them, then `stamp-jitter` moves the stamp. Random draws are keyed by the *input*
//! frame, so frame 30's noise is the same whether or not frames were dropped before it.

use crate::calibration::given_camera;
use crate::family::{Domain, Family, Perturbation};
use crate::groundtruth::perturb_groundtruth;
use crate::spec::Chain;
use crate::{depth, image, occluders, stereo, PerturbError};
use datasets::{FrameReader, Sequence};
use slam_core::{Camera, FrameInput, SensorKind};
use std::sync::Arc;
use synth::hash::{NoiseKey, Stream};

/// Depth PNG units of a sequence without a recorded depth factor (TUM's 5000 per metre), the
/// ones the folder writer uses.
pub use datasets::write::DEFAULT_DEPTH_UNITS;

/// Applies a chain to the frames of one sequence.
#[derive(Clone, Debug)]
pub struct Perturber {
    chain: Chain,
    camera: Camera,
    units: f64,
    seed: u64,
    input_len: usize,
    keep_every: usize,
    depth_shift: i64,
}

impl Perturber {
    /// The perturber of `chain` (checked against the camera's sensor) for a sequence of
    /// `input_len` frames seen by `camera`, depth on a PNG grid of `units` per metre, with
    /// perturbation seed `seed`.
    pub fn new(
        chain: &Chain,
        camera: &Camera,
        units: f64,
        seed: u64,
        input_len: usize,
        sequence: &str,
    ) -> Result<Perturber, PerturbError> {
        chain.check_sensor(camera.sensor, sequence)?;
        let chain = chain.effective();
        let fps = if camera.fps > 0.0 { camera.fps } else { 30.0 };
        let mut keep_every = 1usize;
        let mut depth_shift = 0i64;
        for p in &chain.0 {
            match p.family {
                Family::FrameDrop => keep_every *= p.level as usize,
                Family::DepthLag => depth_shift -= p.level as i64,
                Family::RgbDepthOffset => depth_shift += (p.level / 1000.0 * fps).round() as i64,
                _ => {}
            }
        }
        Ok(Perturber {
            chain,
            camera: camera.clone(),
            units,
            seed,
            input_len,
            keep_every: keep_every.max(1),
            depth_shift,
        })
    }

    /// Frames after the time families (`frame-drop` keeps ceil(n / k)).
    pub fn len(&self) -> usize {
        self.input_len.div_ceil(self.keep_every)
    }

    /// Whether no frame is left.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The input frame output frame `i` shows.
    pub fn source(&self, i: usize) -> usize {
        i * self.keep_every
    }

    /// The chain actually applied (identity members dropped).
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// Output frame `i`, its input frames read by `read`.
    pub fn frame(
        &self,
        i: usize,
        read: &dyn Fn(usize) -> Result<FrameInput, datasets::DatasetError>,
    ) -> Result<FrameInput, PerturbError> {
        let s = self.source(i);
        let mut f = read(s)?;
        if self.chain.0.is_empty() {
            return Ok(f);
        }
        if self.depth_shift != 0 && f.depth.is_some() {
            let d = (s as i64 + self.depth_shift).clamp(0, self.input_len as i64 - 1) as usize;
            if d != s {
                f.depth = read(d)?.depth;
            }
        }
        let t = s as f64
            / if self.camera.fps > 0.0 {
                self.camera.fps
            } else {
                30.0
            };
        for (pos, p) in self.chain.0.iter().enumerate() {
            let seed = member_seed(self.seed, p.family, pos);
            let key = |stream: Stream| NoiseKey::new(seed, s, stream);
            match p.family.domain() {
                Domain::Depth => {
                    if let Some(d) = &f.depth {
                        let out =
                            depth::apply(p.family, p.level, d, &self.camera, self.units, seed, s);
                        f.depth = Some(Arc::new(out));
                    }
                }
                Domain::Image => {
                    let one = |img: &slam_core::GrayImage, stream: Stream, channel: u64| match p
                        .family
                    {
                        Family::ImageNoise => {
                            image::noise(img, p.level, channel_key(key(stream), channel))
                        }
                        Family::MotionBlur => {
                            // One direction per frame, shared by both cameras of a rig.
                            let angle = key(Stream::Mocap).uniform(0) * std::f64::consts::PI;
                            image::motion_blur(img, p.level, angle)
                        }
                        Family::Exposure => {
                            image::exposure(img, image::flicker_gain(p.level, key(Stream::Mocap)))
                        }
                        Family::Jpeg => image::jpeg(img, p.level as u8),
                        _ => img.clone(),
                    };
                    match &f.colour {
                        // A colour camera: each channel (JPEG: the colour image), then grey
                        // as a reader makes it.
                        Some(c) => {
                            let c = if p.family == Family::Jpeg {
                                image::jpeg_colour(c, p.level as u8)
                            } else {
                                let [r, g, b] = image::planes(c);
                                image::interleave(&[
                                    one(&r, Stream::ImageLeft, 1),
                                    one(&g, Stream::ImageLeft, 2),
                                    one(&b, Stream::ImageLeft, 3),
                                ])
                            };
                            f.image = Arc::new(c.to_gray());
                            f.colour = Some(Arc::new(c));
                        }
                        None => f.image = Arc::new(one(&f.image, Stream::ImageLeft, 0)),
                    }
                    if let Some(r) = &f.right {
                        f.right = Some(Arc::new(one(r, Stream::ImageRight, 0)));
                    }
                }
                Domain::Time => {
                    if p.family == Family::StampJitter {
                        let dt = p.level / 1000.0 * key(Stream::Stamps).normal(0);
                        f.timestamp = stamp_on_grid(f.timestamp + dt);
                    }
                }
                Domain::Dynamic => {
                    let objects =
                        occluders::Occluder::objects(p.level as usize, seed, &self.camera);
                    let mut img = (*f.image).clone();
                    let mut dep = f.depth.as_deref().cloned();
                    let mut right = f.right.as_deref().cloned();
                    let mut colour = f.colour.as_deref().cloned();
                    occluders::draw(
                        &objects,
                        t,
                        &self.camera,
                        self.units,
                        occluders::Canvas {
                            image: &mut img,
                            depth: dep.as_mut(),
                            right: if self.camera.sensor == SensorKind::Stereo {
                                right.as_mut()
                            } else {
                                None
                            },
                            colour: colour.as_mut(),
                        },
                    );
                    f.image = Arc::new(img);
                    f.depth = dep.map(Arc::new);
                    f.right = right.map(Arc::new);
                    f.colour = colour.map(Arc::new);
                }
                Domain::Stereo => {
                    if let Some(r) = &f.right {
                        f.right = Some(Arc::new(stereo::rotate_right(r, &self.camera, p.level)));
                    }
                }
                // The camera given to the system and the ground truth: the sequence's, not
                // a frame's (`perturb_sequence`).
                Domain::Calibration | Domain::GroundTruth => {}
            }
        }
        Ok(f)
    }
}

/// The key of colour channel `channel` (1-3; 0: the grey image itself, its key unchanged), so
/// each channel of a colour image draws its own noise.
fn channel_key(key: NoiseKey, channel: u64) -> NoiseKey {
    if channel == 0 {
        return key;
    }
    NoiseKey::new(key.bits(0x4348_414e ^ channel), 0, Stream::ImageLeft)
}

/// The seed of one member of a chain: the perturbation seed, the family and its position mixed,
/// so two members never share random numbers.
fn member_seed(seed: u64, family: Family, position: usize) -> u64 {
    use synth::hash::mix64;
    mix64(seed ^ mix64(0x5045_5254_5552_4221 ^ ((family as u64) << 8) ^ position as u64))
}

/// The member seed of a chain's member at `position` of `family` under perturbation seed
/// `seed` (what its random draws are keyed by; public for tests that redraw them).
pub fn member_seed_of(seed: u64, family: Family, position: usize) -> u64 {
    member_seed(seed, family, position)
}

/// A jittered stamp, moved to the nearest stamp an EuRoC file (whole nanoseconds) or a TUM file
/// (shortest decimal) reads back to the same `f64`: whole microseconds, as TUM's own lists.
fn stamp_on_grid(t: f64) -> f64 {
    (t * 1e6).round() / 1e6
}

/// The sequence of `seq` / `frames` under `chain` with perturbation seed `seed`: the same
/// sequence (name, stamps) with a reader of perturbed frames, the camera the system is given
/// after the calibration families and the ground truth after the ground-truth families. A chain
/// that changes no frame returns the reader as it is (level 0 is bit-identical by
/// construction). A ground-truth family on a sequence without ground truth is refused.
pub fn perturb_sequence(
    seq: &Sequence,
    frames: FrameReader,
    chain: &Chain,
    seed: u64,
) -> Result<(Sequence, FrameReader), PerturbError> {
    let p = Perturber::new(
        chain,
        &seq.camera,
        seq.depth_factor.unwrap_or(DEFAULT_DEPTH_UNITS),
        seed,
        frames.len(),
        &seq.name,
    )?;
    let mut out = seq.clone();
    let members = |domain: Domain| -> Vec<(Perturbation, u64)> {
        p.chain()
            .0
            .iter()
            .enumerate()
            .filter(|(_, m)| m.family.domain() == domain)
            .map(|(pos, m)| (*m, member_seed(seed, m.family, pos)))
            .collect()
    };
    let calibration = members(Domain::Calibration);
    if !calibration.is_empty() {
        out.camera = given_camera(&seq.camera, &calibration, &seq.name)?;
    }
    let truth = members(Domain::GroundTruth);
    if !truth.is_empty() {
        let gt = seq
            .groundtruth
            .as_ref()
            .ok_or_else(|| PerturbError::NotApplicable {
                family: truth[0].0.family.name(),
                sequence: seq.name.clone(),
                why: "it has no ground truth to perturb".into(),
            })?;
        out.groundtruth = Some(perturb_groundtruth(gt, &truth));
    }
    let touches_frames = p
        .chain()
        .0
        .iter()
        .any(|m| !matches!(m.family.domain(), Domain::Calibration | Domain::GroundTruth));
    if !touches_frames {
        return Ok((out, frames));
    }
    let len = p.len();
    let reader = FrameReader::new(len, move |i| {
        p.frame(i, &|k| frames.read(k)).map_err(|e| match e {
            PerturbError::Dataset(d) => d,
            other => datasets::DatasetError::invalid(
                std::path::Path::new("<perturbation>"),
                other.to_string(),
            ),
        })
    });
    Ok((out, reader))
}
