//! One SLAM run over a decoded sequence: feed every frame to `slam_core::System`, collect the
//! trajectory and per-frame statistics, and score it against ground truth with ate-eval in the
//! frame the ground truth is expressed in (EuRoC: body frame via T_BS).

use crate::cpu_time::thread_cpu_s;
use ate_eval::{evaluate_ate, AteOptions, AteResult, Trajectory};
use datasets::{DatasetError, FrameReader, Sequence};
use rayon::prelude::*;
use slam_core::data::Features;
use slam_core::feature::{OrbConfig, OrbExtractor};
use slam_core::frame::extract_features;
use slam_core::module::loop_closing::LoopEvent;
use slam_core::module::pose_estimation::{tap_pose_optimizations, PoseOptRecord};
use slam_core::place::Vocabulary;
use slam_core::system::{Config, FrameStats, System, TrackResult};
use slam_core::{Camera, FrameInput};
use std::sync::Arc;
use std::time::Instant;

/// A run fails ('F' in the paper's tables) when fewer than this fraction of the frames have a
/// pose, or when no ATE can be computed at all.
pub const MIN_TRACKED_FRACTION: f64 = 0.8;

/// Everything a run produces.
#[derive(Clone, Debug)]
pub struct RunOutcome {
    /// Estimated camera trajectory (T_world_camera, TUM convention), tracked frames only.
    pub trajectory: Trajectory,
    /// Per-frame statistics, one per input frame.
    pub stats: Vec<FrameStats>,
    /// ATE against ground truth, when the sequence has ground truth and enough poses associate.
    pub ate: Option<AteResult>,
    /// Frames fed to the system.
    pub frames: usize,
    /// Frames with a pose.
    pub tracked: usize,
    /// Keyframes in the final map.
    pub keyframes: usize,
    /// Map points in the final map.
    pub map_points: usize,
    /// Whether loop closing ran (on in the configuration and a vocabulary loaded).
    pub loop_closing: bool,
    /// Loops closed, in order.
    pub loops: Vec<ClosedLoop>,
    /// Wall time of the run, seconds (single thread), including its features' extraction
    /// (when they were extracted once for several runs: the time that extraction took).
    pub wall_s: f64,
    /// CPU time of the run, seconds: its thread's (user + system), plus its features'
    /// extraction when they were extracted once for several runs, as `wall_s` charges it.
    /// Equal to `wall_s` on a core of its own; below it when the run shared its core.
    pub cpu_s: f64,
    /// The failure verdict ('F').
    pub failed: bool,
}

/// A loop the run closed.
#[derive(Clone, Debug, PartialEq)]
pub struct ClosedLoop {
    /// Index of the frame on which it closed (0-based).
    pub frame: usize,
    /// That frame's timestamp, seconds.
    pub timestamp: f64,
    /// The keyframes involved and the size of the correction.
    pub event: LoopEvent,
    /// Capture times of the closing keyframe and of the keyframe it was matched to, seconds.
    pub keyframe_stamps: (f64, f64),
    /// With ground truth: how far apart the two keyframes' true poses are (metres, degrees;
    /// body frame for EuRoC). A true loop joins views of one place; a false one, far apart
    /// or looking elsewhere.
    pub truth: Option<(f64, f64)>,
}

/// The ground-truth pose nearest to `stamp` (within 0.02 s, evaluate_ate.py's window).
fn truth_at(gt: &Trajectory, stamp: f64) -> Option<nalgebra::Isometry3<f64>> {
    let i = gt.stamps.partition_point(|&s| s < stamp);
    [i.checked_sub(1), Some(i)]
        .into_iter()
        .flatten()
        .filter(|&k| k < gt.stamps.len())
        .min_by(|&a, &b| {
            (gt.stamps[a] - stamp)
                .abs()
                .total_cmp(&(gt.stamps[b] - stamp).abs())
        })
        .filter(|&k| (gt.stamps[k] - stamp).abs() < 0.02)
        .map(|k| gt.poses[k])
}

impl RunOutcome {
    /// Frames processed per second of wall time.
    pub fn fps(&self) -> f64 {
        if self.wall_s > 0.0 {
            self.frames as f64 / self.wall_s
        } else {
            0.0
        }
    }

    /// ATE RMSE in metres, when computed.
    pub fn ate_rmse(&self) -> Option<f64> {
        self.ate.as_ref().map(|a| a.stats.rmse)
    }

    /// Mean over frames of (inliers, outliers) of the final pose optimization.
    pub fn mean_inliers_outliers(&self) -> (f64, f64) {
        let n = self.stats.len().max(1) as f64;
        let i: usize = self.stats.iter().map(|s| s.n_inliers).sum();
        let o: usize = self.stats.iter().map(|s| s.n_outliers).sum();
        (i as f64 / n, o as f64 / n)
    }
}

/// One frame's features, extracted once and shared read-only by every run that tracks it.
#[derive(Clone, Debug)]
pub struct ExtractedFrame {
    /// Capture time, seconds.
    pub timestamp: f64,
    /// Keypoints, descriptors, depth / right coordinate and grid.
    pub features: Arc<Features>,
    /// What the extraction took on one core, milliseconds (reported as the frame's feature
    /// time by every run, so per-run figures stay comparable with in-run extraction).
    pub extraction_ms: f64,
    /// The CPU time of that extraction, milliseconds (its thread's clock).
    pub extraction_cpu_ms: f64,
}

/// A sequence's frames as features for one set of ORB settings: what a sweep's runs share, so
/// that each frame is extracted once per sequence and not once per run.
#[derive(Clone, Debug)]
pub struct ExtractedSequence {
    /// The ORB settings the features were extracted with.
    pub orb: OrbConfig,
    /// One entry per frame of the sequence, in order.
    pub frames: Vec<ExtractedFrame>,
}

impl ExtractedSequence {
    /// Reads every frame of `frames` and extracts its features once with each of `orbs`, in
    /// parallel over frames on the current rayon pool; a frame's images are dropped as soon as
    /// its features exist, so no more than one decoded frame per worker is ever held. The first
    /// unreadable frame (in frame order) is the error.
    pub fn extract_all(
        frames: &FrameReader,
        camera: &Camera,
        orbs: &[OrbConfig],
        on_frame: impl Fn() + Sync,
    ) -> Result<Vec<Self>, DatasetError> {
        extract_each(frames.len(), |i| frames.read(i), camera, orbs, on_frame)
    }

    /// Extracts the frames of a sequence held in memory (rendered synthetic frames) once with
    /// each of `orbs`, in parallel over frames: [`extract_all`](Self::extract_all) without a
    /// reader, which cannot fail.
    pub fn extract_frames(frames: &[FrameInput], camera: &Camera, orbs: &[OrbConfig]) -> Vec<Self> {
        match extract_each(frames.len(), |i| Ok(frames[i].clone()), camera, orbs, || {}) {
            Ok(extracted) => extracted,
            Err(_) => unreachable!("frames in memory are always readable"),
        }
    }

    /// Heap bytes of all frames' features.
    pub fn heap_bytes(&self) -> usize {
        self.frames.iter().map(|f| f.features.heap_bytes()).sum()
    }

    /// Total extraction time: the frames' wall times summed, seconds (of one core when no other
    /// work shared it; [`Self::extraction_cpu_s`] is the CPU time).
    pub fn extraction_s(&self) -> f64 {
        self.frames.iter().map(|f| f.extraction_ms).sum::<f64>() / 1e3
    }

    /// Total extraction CPU time, seconds (each worker thread's clock).
    pub fn extraction_cpu_s(&self) -> f64 {
        self.frames.iter().map(|f| f.extraction_cpu_ms).sum::<f64>() / 1e3
    }
}

/// A frame extracted without its depth, and what its extraction took: wall and CPU, ms.
pub type ImageFrame = (Arc<slam_core::frame::Frame>, f64, f64);

/// A sequence's frames extracted once for one set of ORB settings, *without* their depth
/// (RGB-D; stereo frames keep their own matches), so that each depth-only or time perturbation
/// of the sequence (`sweep --perturb depth-axial:...`, `frame-drop`, `stamp-jitter`) reuses the
/// keypoints and descriptors and only attaches its own depth: the ORB extraction, the bulk of a
/// frame's cost, is paid once per sequence instead of once per level.
#[derive(Clone, Debug)]
pub struct ImageFrames {
    /// The ORB settings.
    pub orb: OrbConfig,
    /// Per input frame: the frame without depth, and what its extraction took (wall and CPU,
    /// ms).
    pub frames: Vec<ImageFrame>,
}

impl ImageFrames {
    /// Reads every frame of `frames` and extracts it once per ORB setting of `orbs` without
    /// its depth, in parallel over frames.
    pub fn extract_all(
        frames: &FrameReader,
        camera: &Camera,
        orbs: &[OrbConfig],
        on_frame: impl Fn() + Sync,
    ) -> Result<Vec<Self>, DatasetError> {
        let per_orb = extract_per_orb(
            frames.len(),
            |i| {
                let mut input = frames.read(i)?;
                input.depth = None;
                Ok(input)
            },
            orbs,
            on_frame,
            |input, extractor| {
                let (f, ms, cpu_ms) =
                    timed(|| slam_core::frame::Frame::new(0, input, camera, extractor));
                (Arc::new(f), ms, cpu_ms)
            },
        )?;
        Ok(orbs
            .iter()
            .zip(per_orb)
            .map(|(orb, frames)| ImageFrames {
                orb: orb.clone(),
                frames,
            })
            .collect())
    }

    /// The features of a perturbed copy of the sequence whose images are these frames'
    /// (depth-only and time perturbations): output frame `i` shows input frame `source(i)`,
    /// with the depth and stamp `frames` reads. The same bits as extracting the perturbed
    /// frames; each frame is charged its original extraction time.
    pub fn attach(
        &self,
        frames: &FrameReader,
        source: impl Fn(usize) -> usize + Sync,
        camera: &Camera,
        on_frame: impl Fn() + Sync,
    ) -> Result<ExtractedSequence, DatasetError> {
        let out: Vec<Result<ExtractedFrame, DatasetError>> = (0..frames.len())
            .into_par_iter()
            .map(|i| {
                let input = frames.read(i)?;
                let (frame, ms, cpu_ms) = &self.frames[source(i)];
                let features =
                    slam_core::frame::features_with_depth(frame, input.depth.as_deref(), camera);
                on_frame();
                Ok(ExtractedFrame {
                    timestamp: input.timestamp,
                    features: Arc::new(features),
                    extraction_ms: *ms,
                    extraction_cpu_ms: *cpu_ms,
                })
            })
            .collect();
        Ok(ExtractedSequence {
            orb: self.orb.clone(),
            frames: out.into_iter().collect::<Result<_, _>>()?,
        })
    }
}

/// `frames` read through a memory of every frame read so far, when the decoded sequence fits
/// in `budget_bytes` (else `frames` as it is): the perturbation points of a sweep read the same
/// input frames once each instead of decoding (or rendering) them again per point.
pub fn remembering(
    frames: FrameReader,
    bytes_per_frame: usize,
    budget_bytes: usize,
) -> FrameReader {
    if frames.len().saturating_mul(bytes_per_frame) > budget_bytes {
        return frames;
    }
    let memory: Arc<Vec<std::sync::OnceLock<FrameInput>>> = Arc::new(
        (0..frames.len())
            .map(|_| std::sync::OnceLock::new())
            .collect(),
    );
    FrameReader::new(frames.len(), move |i| {
        if let Some(f) = memory[i].get() {
            return Ok(f.clone());
        }
        let f = frames.read(i)?;
        Ok(memory[i].get_or_init(|| f).clone())
    })
}

/// Frame `i` of `n` read by `read`, extracted once per ORB setting, in parallel over frames.
fn extract_each(
    n: usize,
    read: impl Fn(usize) -> Result<FrameInput, DatasetError> + Sync,
    camera: &Camera,
    orbs: &[OrbConfig],
    on_frame: impl Fn() + Sync,
) -> Result<Vec<ExtractedSequence>, DatasetError> {
    let per_orb = extract_per_orb(n, read, orbs, on_frame, |input, extractor| {
        let (features, ms, cpu_ms) = timed(|| extract_features(input, camera, extractor));
        ExtractedFrame {
            timestamp: input.timestamp,
            features: Arc::new(features),
            extraction_ms: ms,
            extraction_cpu_ms: cpu_ms,
        }
    })?;
    Ok(orbs
        .iter()
        .zip(per_orb)
        .map(|(orb, frames)| ExtractedSequence {
            orb: orb.clone(),
            frames,
        })
        .collect())
}

/// `f`'s result and what it took on the calling thread: wall and CPU time, milliseconds.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let (t, c) = (Instant::now(), thread_cpu_s());
    let out = f();
    let cpu_ms = (thread_cpu_s() - c) * 1e3;
    (out, t.elapsed().as_secs_f64() * 1e3, cpu_ms)
}

/// The skeleton both extractions share: frame `i` of `n` read by `read` and handed to
/// `extract` once per ORB setting of `orbs` (one extractor per setting and worker), in
/// parallel over frames, each frame's images dropped as soon as it is done; the results per
/// ORB setting, in frame order. The first unreadable frame (in frame order) is the error.
fn extract_per_orb<T: Send>(
    n: usize,
    read: impl Fn(usize) -> Result<FrameInput, DatasetError> + Sync,
    orbs: &[OrbConfig],
    on_frame: impl Fn() + Sync,
    extract: impl Fn(&FrameInput, &mut OrbExtractor) -> T + Sync,
) -> Result<Vec<Vec<T>>, DatasetError> {
    let per_frame: Vec<Result<Vec<T>, DatasetError>> = (0..n)
        .into_par_iter()
        .map_init(
            || -> Vec<OrbExtractor> { orbs.iter().cloned().map(OrbExtractor::new).collect() },
            |extractors, i| {
                let input = read(i)?;
                let out = extractors
                    .iter_mut()
                    .map(|extractor| extract(&input, extractor))
                    .collect();
                on_frame();
                Ok(out)
            },
        )
        .collect();
    let mut out: Vec<Vec<T>> = orbs.iter().map(|_| Vec::with_capacity(n)).collect();
    for frame in per_frame {
        for (seq, x) in out.iter_mut().zip(frame?) {
            seq.push(x);
        }
    }
    Ok(out)
}

/// Runs `config` over `seq` with place recognition over `vocabulary` (brute-force stand-ins
/// without one), extracting each frame's features in the run, calling `on_frame` after each
/// frame (for progress bars).
pub fn run_sequence(
    seq: &Sequence,
    config: &Config,
    vocabulary: Option<&Arc<Vocabulary>>,
    on_frame: impl FnMut(usize),
) -> RunOutcome {
    run(seq, None, config, vocabulary, on_frame, None)
}

/// As [`run_sequence`], tracking features extracted beforehand (`seq.frames` may then be empty:
/// the images are no longer needed). The result is the same, bit for bit.
///
/// # Panics
/// When `extracted` was made with other ORB settings than `config`'s (a caller bug).
pub fn run_extracted(
    seq: &Sequence,
    extracted: &ExtractedSequence,
    config: &Config,
    vocabulary: Option<&Arc<Vocabulary>>,
    on_frame: impl FnMut(usize),
) -> RunOutcome {
    assert_eq!(
        extracted.orb, config.orb,
        "features extracted with other ORB settings than the run's"
    );
    run(seq, Some(extracted), config, vocabulary, on_frame, None)
}

/// What an observer of a run ([`run_observed`]) sees after each frame: the system as the frame
/// left it, what tracking returned, and every pose optimization the frame made (the last one of
/// a tracked frame is its final pose's, with each match's fate).
#[cfg_attr(not(feature = "rerun"), allow(dead_code))]
pub struct Observation<'a> {
    /// Frame index in the sequence.
    pub index: usize,
    /// The system after the frame.
    pub system: &'a System,
    /// What tracking returned for it.
    pub result: &'a TrackResult,
    /// The frame's pose optimizations, in call order.
    pub optimizations: &'a [PoseOptRecord],
}

#[cfg_attr(not(feature = "rerun"), allow(dead_code))]
impl Observation<'_> {
    /// The frame's final pose optimization (its last), with each match's fate; `None` when
    /// the frame was not tracked.
    pub fn final_optimization(&self) -> Option<&PoseOptRecord> {
        let id = self.system.last_frame()?.id;
        self.optimizations
            .iter()
            .rev()
            .find(|r| r.frame_id == id)
            .filter(|_| self.result.state.is_tracked())
    }
}

/// As [`run_sequence`] (or [`run_extracted`] with `extracted`), calling `observe` after every
/// frame with what the frame did (a recording of the run, `run --rerun`). Observing reads only:
/// the trajectory is the unobserved run's, bit for bit.
#[cfg_attr(not(feature = "rerun"), allow(dead_code))]
pub fn run_observed(
    seq: &Sequence,
    extracted: Option<&ExtractedSequence>,
    config: &Config,
    vocabulary: Option<&Arc<Vocabulary>>,
    on_frame: impl FnMut(usize),
    mut observe: impl FnMut(&Observation<'_>),
) -> RunOutcome {
    run(
        seq,
        extracted,
        config,
        vocabulary,
        on_frame,
        Some(&mut observe),
    )
}

fn run(
    seq: &Sequence,
    extracted: Option<&ExtractedSequence>,
    config: &Config,
    vocabulary: Option<&Arc<Vocabulary>>,
    mut on_frame: impl FnMut(usize),
    mut observe: Option<&mut dyn FnMut(&Observation<'_>)>,
) -> RunOutcome {
    let (start, cpu_start) = (Instant::now(), thread_cpu_s());
    let mut system = match vocabulary {
        Some(v) => System::with_vocabulary(seq.camera.clone(), config.clone(), v.clone()),
        None => System::new(seq.camera.clone(), config.clone()),
    };
    let frames = extracted.map_or(seq.frames.len(), |e| e.frames.len());
    let mut stats = Vec::with_capacity(frames);
    for i in 0..frames {
        let track = |system: &mut System| match extracted {
            None => system.track(&seq.frames[i]),
            Some(e) => {
                let f = &e.frames[i];
                system.track_features(f.timestamp, f.features.clone(), f.extraction_ms)
            }
        };
        let r = match observe.as_mut() {
            None => track(&mut system),
            Some(observe) => {
                let (r, optimizations) = tap_pose_optimizations(|| track(&mut system));
                observe(&Observation {
                    index: i,
                    system: &system,
                    result: &r,
                    optimizations: &optimizations,
                });
                r
            }
        };
        stats.push(r.stats);
        on_frame(i + 1);
    }
    // A run on shared features is charged what their extraction took, so its time and frames
    // per second stay those of a run that extracts for itself.
    let wall_s = start.elapsed().as_secs_f64() + extracted.map_or(0.0, |e| e.extraction_s());
    let cpu_s = thread_cpu_s() - cpu_start + extracted.map_or(0.0, |e| e.extraction_cpu_s());
    let closing_frames = stats.iter().enumerate().filter(|(_, s)| s.loop_closed);
    let loops: Vec<ClosedLoop> = closing_frames
        .zip(system.loops())
        .map(|((frame, s), event)| {
            let stamp = |k| {
                system
                    .map()
                    .keyframe_any(k)
                    .map_or(f64::NAN, |kf| kf.timestamp)
            };
            let keyframe_stamps = (stamp(event.current), stamp(event.loop_kf));
            let truth = seq.groundtruth.as_ref().and_then(|gt| {
                let a = truth_at(gt, keyframe_stamps.0)?;
                let b = truth_at(gt, keyframe_stamps.1)?;
                Some((
                    (a.translation.vector - b.translation.vector).norm(),
                    a.rotation.angle_to(&b.rotation).to_degrees(),
                ))
            });
            ClosedLoop {
                frame,
                timestamp: s.timestamp,
                event: event.clone(),
                keyframe_stamps,
                truth,
            }
        })
        .collect();
    let mut trajectory = Trajectory::new();
    for (t, pose) in system.trajectory() {
        trajectory.push(t, pose);
    }
    let tracked = trajectory.len();
    let ate = seq.groundtruth.as_ref().and_then(|gt| {
        let est = match &seq.t_bs {
            Some(t_bs) => trajectory.cam_to_body(t_bs),
            None => trajectory.clone(),
        };
        evaluate_ate(gt, &est, &AteOptions::default()).ok()
    });
    let failed = ate.is_none() && seq.groundtruth.is_some()
        || (tracked as f64) < MIN_TRACKED_FRACTION * frames as f64;
    RunOutcome {
        trajectory,
        stats,
        ate,
        frames,
        tracked,
        keyframes: system.keyframe_count(),
        map_points: system.map_point_count(),
        loop_closing: config.loop_closing.enabled && vocabulary.is_some(),
        loops,
        wall_s,
        cpu_s,
        failed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config_file::{apply_switches, base_config, Switches};
    use crate::select::{load, open, LoadOptions, Source};
    use crate::vocab_file::choose;
    use datasets::Catalog;

    /// A preset's first frames decoded, the sequence as a sweep opens it (without frames), and
    /// the features extracted with `orb` through a frame reader as a sweep extracts them.
    fn decoded_and_extracted(
        preset: &str,
        frames: usize,
        orb: impl Fn(&Sequence) -> OrbConfig,
    ) -> (Sequence, Sequence, ExtractedSequence) {
        let source = Source::Catalog(preset.into());
        let catalog = Catalog::embedded();
        let seq = load(&source, &catalog, &LoadOptions::for_tests(frames)).expect("a preset");
        let (opened, _) =
            open(&source, &catalog, &LoadOptions::for_tests(frames)).expect("a preset");
        assert!(opened.frames.is_empty());
        let decoded = seq.frames.clone();
        let reader = FrameReader::new(frames, move |i| Ok(decoded[i].clone()));
        let orb = orb(&seq);
        let extracted =
            ExtractedSequence::extract_all(&reader, &opened.camera, &[orb], || {}).expect("frames");
        (
            seq,
            opened,
            extracted.into_iter().next().expect("one ORB setting"),
        )
    }

    #[test]
    fn an_opened_sequence_reads_the_frames_a_loaded_one_holds() {
        for preset in ["kinect", "stereo"] {
            let source = Source::Catalog(preset.into());
            let catalog = Catalog::embedded();
            let seq = load(&source, &catalog, &LoadOptions::for_tests(3)).expect("a preset");
            let (opened, reader) =
                open(&source, &catalog, &LoadOptions::for_tests(3)).expect("a preset");
            assert_eq!(reader.len(), 3);
            assert_eq!(opened.groundtruth, seq.groundtruth);
            assert_eq!(opened.camera, seq.camera);
            for (i, want) in seq.frames.iter().enumerate() {
                let got = reader.read(i).expect("a frame");
                assert_eq!(got.timestamp, want.timestamp);
                assert_eq!(got.image, want.image);
                assert_eq!(got.depth, want.depth);
                assert_eq!(got.right, want.right);
            }
        }
    }

    /// Per-frame statistics without the wall-clock timings.
    fn untimed(stats: &[FrameStats]) -> Vec<FrameStats> {
        stats
            .iter()
            .map(|s| FrameStats {
                time_features_ms: 0.0,
                time_tracking_ms: 0.0,
                time_mapping_ms: 0.0,
                time_ba_ms: 0.0,
                time_loop_ms: 0.0,
                ..s.clone()
            })
            .collect()
    }

    /// Runs `seq` in each configuration `(mcor, avc, mapping lag)`, once extracting in the run
    /// and once on features extracted beforehand, and compares them.
    fn assert_shared_features_change_nothing(
        preset: &str,
        frames: usize,
        runs: &[(bool, bool, u32)],
        vocabulary: Option<&Arc<Vocabulary>>,
    ) {
        let (seq, without_images, extracted) =
            decoded_and_extracted(preset, frames, |s| base_config(s.camera.sensor).orb);
        let base = base_config(seq.camera.sensor);
        assert_eq!(extracted.frames.len(), frames);
        assert_eq!(without_images.groundtruth, seq.groundtruth);
        let per_frame = extracted.heap_bytes() / frames;
        assert!(
            per_frame < 100 * 1024,
            "{preset}: {per_frame} bytes per frame"
        );
        runs.par_iter().for_each(|&(mcor, avc, lag)| {
            let switches = Switches {
                mcor,
                avc,
                mapping_lag: Some(lag),
                no_loop_closing: false,
                mcor_cluster: None,
                rc: false,
            };
            let mut cfg = apply_switches(base.clone(), switches);
            cfg.seed = 7;
            let what = format!("{preset} mcor {mcor} avc {avc} lag {lag}");
            let inline = run_sequence(&seq, &cfg, vocabulary, |_| {});
            let shared = run_extracted(&without_images, &extracted, &cfg, vocabulary, |_| {});
            assert!(inline.tracked > frames / 2, "{what}: tracking lost");
            assert_eq!(inline.trajectory, shared.trajectory, "{what}: trajectory");
            assert_eq!(untimed(&inline.stats), untimed(&shared.stats), "{what}");
            assert_eq!(
                (inline.keyframes, inline.map_points, inline.loops.len()),
                (shared.keyframes, shared.map_points, shared.loops.len()),
                "{what}: map"
            );
            for (s, f) in shared.stats.iter().zip(&extracted.frames) {
                assert_eq!(s.time_features_ms, f.extraction_ms);
            }
        });
    }

    #[test]
    fn runs_on_shared_features_are_bit_identical_to_runs_that_extract() {
        let vocabulary = choose(None).expect("the shipped vocabulary").vocabulary;
        // RGB-D in all four configurations; stereo (whose extraction also matches the right
        // image) in the baseline and with both techniques; each lag (synchronous, 3 frames)
        // under half of them, so that every switch and every lag meets shared features.
        let rgbd = [
            (false, false, 0),
            (true, false, 3),
            (false, true, 0),
            (true, true, 3),
        ];
        assert_shared_features_change_nothing("kinect", 70, &rgbd, vocabulary.as_ref());
        let stereo = [(false, false, 3), (true, true, 0)];
        assert_shared_features_change_nothing("stereo", 50, &stereo, vocabulary.as_ref());
    }

    #[test]
    #[should_panic(expected = "other ORB settings")]
    fn features_of_other_orb_settings_are_refused() {
        let (seq, _, extracted) = decoded_and_extracted("kinect", 2, |s| OrbConfig {
            n_features: 500,
            ..base_config(s.camera.sensor).orb
        });
        let cfg = base_config(seq.camera.sensor);
        run_extracted(&seq, &extracted, &cfg, None, |_| {});
    }
}
