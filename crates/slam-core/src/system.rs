//! The synchronous SLAM system: one call to [`System::track`] per frame runs feature extraction,
//! tracking, the keyframe decision and, when a keyframe is inserted, local mapping to completion
//! (the paper synchronises ORB-SLAM2's threads the same way). Every random choice draws from
//! one ChaCha RNG seeded by `Config::seed`, and every container iterates in id order, so the
//! same frames, configuration and seed give a bit-identical trajectory. In this synchronous mode
//! the seed only reaches the relocalization RANSAC. `Config::mapping_lag` emulates ORB-SLAM2's
//! concurrent local mapping instead: each keyframe's mapping completes a seeded number of frames
//! later, which gives seeded runs the spread of ORB-SLAM2's threads while staying reproducible.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;

use nalgebra::Isometry3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::camera::Camera;
use crate::data::{Features, KeyFrameId, Map, MapPointId, ScaleLevels, TrackedFrame};
use crate::feature::{OrbConfig, OrbExtractor};
use crate::frame::extract_features;
use crate::image::FrameInput;
use crate::module::global_ba::{apply_global_ba, global_bundle_adjustment, GlobalBaResult};
use crate::module::keyframe_decision::{need_new_keyframe, KeyFrameDecisionInput, KeyFrameParams};
use crate::module::keyframe_insertion::create_keyframe;
use crate::module::local_mapping::{LocalMapper, MappingContext, MappingParams, MappingReport};
use crate::module::loop_closing::{LoopCloser, LoopClosingParams, LoopContext, LoopEvent};
use crate::module::pose_estimation::{renormalized, NoiseHooks};
use crate::module::relocalization::{relocalize, RelocalizationContext, RelocalizationParams};
use crate::module::tracking::{Tracker, TrackingContext, TrackingParams};
use crate::optimize::{BaConfig, PoseOptConfig};
use crate::place::{PlaceRecognition, Vocabulary};
use crate::techniques::mcor::{frame_sightings, mcor_frame_gate_with, ClusterCache};

pub use crate::techniques::params::{
    AvcGate, AvcParams, BaselineRole, ClusterViews, McorParams, Scope, Sightings, Verdict,
};
pub use crate::techniques::RigidConsensusParams;

/// serde mirror of [`OrbConfig`] (which does not derive serde itself).
#[derive(Serialize, Deserialize)]
#[serde(remote = "OrbConfig", default)]
struct OrbConfigDef {
    n_features: usize,
    scale_factor: f64,
    n_levels: usize,
    ini_th_fast: u8,
    min_th_fast: u8,
}

impl Default for OrbConfigDef {
    fn default() -> Self {
        let c = OrbConfig::default();
        OrbConfigDef {
            n_features: c.n_features,
            scale_factor: c.scale_factor,
            n_levels: c.n_levels,
            ini_th_fast: c.ini_th_fast,
            min_th_fast: c.min_th_fast,
        }
    }
}

/// Everything that configures a run. Defaults are ORB-SLAM2's TUM RGB-D settings with both of
/// the paper's techniques off (the "ORB-SLAM2" column of Table III). Read from TOML by the CLI;
/// missing fields take their defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Config {
    /// ORB extractor (1000 features, 8 levels, scale 1.2, FAST 20 / 7).
    #[serde(with = "OrbConfigDef")]
    pub orb: OrbConfig,
    /// Seed of the run's single RNG (relocalization RANSAC).
    pub seed: u64,
    /// Tracking thresholds.
    pub tracking: TrackingParams,
    /// Keyframe decision.
    pub keyframes: KeyFrameParams,
    /// Local mapping.
    pub mapping: MappingParams,
    /// Relocalization.
    pub relocalization: RelocalizationParams,
    /// Loop closing (on by default, as in ORB-SLAM2; needs a vocabulary, see
    /// [`System::with_vocabulary`]).
    pub loop_closing: LoopClosingParams,
    /// Keypoints the first frame needs to initialise the map (ORB-SLAM2: more than 500).
    pub init_min_keypoints: usize,
    /// Keypoints with depth the first frame needs (ours: 50; ORB-SLAM2 does not check, and
    /// would initialise on a frame without depth).
    pub init_min_depths: usize,
    /// MC-OR (paper III-A) when set.
    pub mcor: Option<McorParams>,
    /// AVC (paper III-B) when set.
    pub avc: Option<AvcParams>,
    /// Rigid consensus (noisefree's own, beyond the paper; see
    /// [`crate::techniques::rigid_consensus`](mod@crate::techniques::rigid_consensus)) when set.
    pub rc: Option<RigidConsensusParams>,
    /// Emulated local-mapping latency, frames (0 = synchronous, the paper's protocol). With
    /// N > 0 each new keyframe is mapped (triangulation, fusion, culling, local BA) only after
    /// a number of frames drawn uniformly from 0..=N with the run's RNG, in keyframe order;
    /// meanwhile tracking goes on with the map as it is, and the keyframe decision sees a busy
    /// mapper (no c1b, at most 3 keyframes waiting), as with ORB-SLAM2's threads. Gives
    /// seeded runs of one sequence ORB-SLAM2's run-to-run spread, reproducibly.
    pub mapping_lag: u32,
    /// The RGB-D camera's baseline b in metres (ORB-SLAM2's `bf / fx`), replacing the
    /// sequence camera's: the virtual right coordinate `u - b fx / d` and the close/far depth
    /// threshold ThDepth x b. `None` (default): the sequence's (TUM: bf 40). What AVC's
    /// `b_role = "camera"` sets to its b; given alone it moves the baseline's row of the
    /// paper's Table I. RGB-D only: a stereo rig's baseline is physical and stays.
    pub rgbd_baseline: Option<f64>,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            orb: OrbConfig::default(),
            seed: 0,
            tracking: TrackingParams::default(),
            keyframes: KeyFrameParams::default(),
            mapping: MappingParams::default(),
            relocalization: RelocalizationParams::default(),
            loop_closing: LoopClosingParams::default(),
            init_min_keypoints: 500,
            init_min_depths: 50,
            mcor: None,
            avc: None,
            rc: None,
            mapping_lag: 0,
            rgbd_baseline: None,
        }
    }
}

impl Config {
    /// The RGB-D baseline b this configuration gives the camera (metres), if any:
    /// [`rgbd_baseline`](Self::rgbd_baseline), else AVC's b under `b_role = "camera"`.
    pub fn camera_baseline(&self) -> Option<f64> {
        self.rgbd_baseline.or_else(|| {
            self.avc
                .as_ref()
                .filter(|a| a.b_role == BaselineRole::Camera)
                .map(|a| a.baseline)
        })
    }

    /// The camera a run of this configuration uses on a sequence with camera `camera`: the
    /// same, except that an RGB-D camera's `bf` is `b fx` when
    /// [`camera_baseline`](Self::camera_baseline) gives b. Features extracted for such a run
    /// must be extracted with this camera (or [`System::track_features`] recomputes their
    /// right coordinates).
    pub fn run_camera(&self, camera: &Camera) -> Camera {
        let mut c = camera.clone();
        if let (Some(b), crate::SensorKind::Rgbd) = (self.camera_baseline(), camera.sensor) {
            c.bf = b * c.fx;
        }
        c
    }

    /// ORB-SLAM2's EuRoC stereo settings (1200 features), otherwise as the default.
    pub fn stereo() -> Self {
        Config {
            orb: OrbConfig::stereo(),
            ..Config::default()
        }
    }
}

/// Tracking state after a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum TrackingState {
    /// No map yet (first frames without enough features / depth).
    NotInitialized,
    /// Tracked.
    Ok,
    /// Not tracked; relocalization is tried on the next frames.
    Lost,
    /// Tracked again by relocalization on this frame.
    Relocalized,
}

impl TrackingState {
    /// Whether the frame has a pose.
    pub fn is_tracked(self) -> bool {
        matches!(self, TrackingState::Ok | TrackingState::Relocalized)
    }
}

/// Per-frame statistics (one CSV row in the CLI's output).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameStats {
    /// Capture time, seconds.
    pub timestamp: f64,
    /// State after the frame.
    pub state: TrackingState,
    /// Keypoints extracted.
    pub n_keypoints: usize,
    /// Matches entering the last pose optimization (local map).
    pub n_matches: usize,
    /// Of those, inliers at the final pose.
    pub n_inliers: usize,
    /// Of those, outliers at the final pose.
    pub n_outliers: usize,
    /// Inliers whose map point has observations (ORB-SLAM2's mnMatchesInliers).
    pub n_tracked_map_points: usize,
    /// MC-OR (paper Fig. 8): matches whose map-point cluster fails the cluster-level test at the
    /// frame's final pose (0 when MC-OR is off).
    pub n_mcor_rejected_clusters: usize,
    /// MC-OR: matches whose own 3-D feature fails the feature-level test at the final pose.
    pub n_mcor_rejected_features: usize,
    /// A keyframe was inserted from this frame.
    pub keyframe_inserted: bool,
    /// Tracking was recovered by relocalization on this frame.
    pub relocalized: bool,
    /// Loop closing found a consistent loop candidate at a keyframe mapped on this frame.
    pub loop_detected: bool,
    /// A loop was closed (verified and corrected) on this frame.
    pub loop_closed: bool,
    /// Loops closed so far.
    pub n_loops: usize,
    /// Keyframes in the map after the frame.
    pub n_keyframes: usize,
    /// Map points in the map after the frame.
    pub n_map_points: usize,
    /// ORB extraction and frame construction, milliseconds.
    pub time_features_ms: f64,
    /// Tracking (motion model / reference / relocalization, local map, keyframe decision), ms.
    pub time_tracking_ms: f64,
    /// Local mapping without BA, milliseconds.
    pub time_mapping_ms: f64,
    /// Local bundle adjustment, milliseconds.
    pub time_ba_ms: f64,
    /// Loop closing (detection, verification, correction, essential graph, global BA), ms.
    pub time_loop_ms: f64,
}

/// What [`System::track`] returns for one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackResult {
    /// Tracking state after the frame.
    pub state: TrackingState,
    /// Estimated pose world -> camera when tracked.
    pub tcw: Option<Isometry3<f64>>,
    /// Statistics of the frame.
    pub stats: FrameStats,
}

/// A frame's trajectory entry: its pose relative to its reference keyframe (as ORB-SLAM2 stores
/// it), so later keyframe corrections reach the output.
#[derive(Clone, Copy, Debug)]
struct FrameRecord {
    timestamp: f64,
    reference: Option<KeyFrameId>,
    t_cr: Isometry3<f64>,
    tracked: bool,
}

/// The SLAM system (RGB-D or rectified stereo, as `camera.sensor` says).
#[derive(Debug)]
pub struct System {
    camera: Camera,
    config: Config,
    extractor: OrbExtractor,
    levels: ScaleLevels,
    pose_cfg: PoseOptConfig,
    ba_cfg: BaConfig,
    map: Map,
    tracker: Tracker,
    mapper: LocalMapper,
    rng: ChaCha8Rng,
    state: TrackingState,
    frame_count: u64,
    last_keyframe_frame: u64,
    records: Vec<FrameRecord>,
    stats: Vec<FrameStats>,
    pending: VecDeque<PendingKeyFrame>,
    place: Option<PlaceRecognition>,
    loop_closer: LoopCloser,
    /// A global BA computed after a loop, merged once frame `.0` has been tracked.
    pending_gba: Option<(u64, GlobalBaResult)>,
    /// MC-OR's clusters, shared by every gate while the map stands still (forgotten before a
    /// frame when the map changed since the last one).
    mcor_clusters: RefCell<ClusterCache>,
    /// The map changed (beyond tracking's counters and frame views) since the clusters were
    /// last forgotten: a keyframe was made or mapped, a loop closed, a global BA merged.
    map_touched: bool,
    /// The camera's `bf` when the configuration changed it from the sequence's (an RGB-D
    /// baseline of [`Config::camera_baseline`]): features handed in were extracted with the
    /// sequence's camera, so their right coordinates are recomputed with it.
    rebased_bf: Option<f64>,
}

/// What local mapping needs of the system (a free function, so that the map and the mapper
/// stay mutably borrowable beside it).
fn mapping_context<'a>(
    camera: &'a Camera,
    levels: &'a ScaleLevels,
    config: &'a Config,
    ba: &'a BaConfig,
) -> MappingContext<'a> {
    MappingContext {
        camera,
        levels,
        params: &config.mapping,
        ba,
        hooks: NoiseHooks {
            mcor: config.mcor.as_ref(),
            avc: config.avc.as_ref(),
            rc: None,
            clusters: None,
        },
    }
}

/// A keyframe waiting for local mapping (emulated mapping lag).
#[derive(Clone, Debug)]
struct PendingKeyFrame {
    kf: KeyFrameId,
    created: Vec<MapPointId>,
    /// Frame counter after whose tracking its mapping has completed.
    due: u64,
}

impl System {
    /// A system with an empty map.
    pub fn new(camera: Camera, config: Config) -> Self {
        let run_camera = config.run_camera(&camera);
        let rebased_bf = (run_camera.bf != camera.bf).then_some(run_camera.bf);
        let camera = run_camera;
        let extractor = OrbExtractor::new(config.orb.clone());
        let si = extractor.scale_info();
        let levels = ScaleLevels::new(si.n_levels, si.scale_factor);
        System {
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            camera,
            config,
            extractor,
            levels,
            pose_cfg: PoseOptConfig::default(),
            ba_cfg: BaConfig::default(),
            map: Map::new(),
            tracker: Tracker::default(),
            mapper: LocalMapper::default(),
            state: TrackingState::NotInitialized,
            frame_count: 0,
            last_keyframe_frame: 0,
            records: Vec::new(),
            stats: Vec::new(),
            pending: VecDeque::new(),
            place: None,
            loop_closer: LoopCloser::default(),
            pending_gba: None,
            mcor_clusters: RefCell::new(ClusterCache::new()),
            map_touched: true,
            rebased_bf,
        }
    }

    /// A system with an empty map and place recognition over `vocabulary`, as ORB-SLAM2 runs:
    /// relocalization candidates from the keyframe database and BoW-guided matching for
    /// relocalization and reference-keyframe tracking. ([`System::new`] has no vocabulary and
    /// uses brute-force stand-ins.)
    pub fn with_vocabulary(camera: Camera, config: Config, vocabulary: Arc<Vocabulary>) -> Self {
        let mut s = Self::new(camera, config);
        s.place = Some(PlaceRecognition::new(vocabulary));
        s
    }

    /// Indexes a new keyframe in the keyframe database (with its frame's BoW, computed now if
    /// tracking did not need it yet).
    fn index_keyframe(&mut self, kf: KeyFrameId, cur: &mut TrackedFrame) {
        let Some(place) = self.place.as_mut() else {
            return;
        };
        let fb = cur.bow(place);
        place.database.add(kf, &fb.bow);
        if let Some(k) = self.map.keyframe_mut(kf) {
            k.bow = Some(fb);
        }
    }

    /// For tests of MC-OR's cluster cache: from now on every cluster it keeps is compared, each
    /// time a gate uses it, with one rebuilt from the map, and every verdict a frame's gates
    /// keep from round to round with one computed at the gate's pose; a difference panics.
    /// Returns how many kept clusters and kept verdicts were checked so far.
    pub fn check_mcor_clusters(&mut self) -> (u64, u64) {
        let cache = self.mcor_clusters.get_mut();
        cache.set_check(true);
        (cache.checked(), cache.checked_verdicts())
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The map (read only).
    pub fn map(&self) -> &Map {
        &self.map
    }

    /// The last frame processed, with its pose and matches (for analyses and tests).
    pub fn last_frame(&self) -> Option<&TrackedFrame> {
        self.tracker.last_frame.as_ref()
    }

    /// Tracking state after the last frame.
    pub fn state(&self) -> TrackingState {
        self.state
    }

    /// Every loop closed so far, in order.
    pub fn loops(&self) -> &[LoopEvent] {
        &self.loop_closer.loops
    }

    /// Statistics of every frame so far.
    pub fn frame_stats(&self) -> &[FrameStats] {
        &self.stats
    }

    /// Keyframes in the map.
    pub fn keyframe_count(&self) -> usize {
        self.map.keyframe_count()
    }

    /// Map points in the map.
    pub fn map_point_count(&self) -> usize {
        self.map.map_point_count()
    }

    /// Pose `T_world_camera` of every tracked frame, recomputed from its reference keyframe's
    /// current pose (ORB-SLAM2's SaveTrajectoryTUM; lost and uninitialised frames skipped).
    pub fn trajectory(&self) -> Vec<(f64, Isometry3<f64>)> {
        self.records
            .iter()
            .filter(|r| r.tracked)
            .filter_map(|r| {
                let trw = self.map.keyframe_pose_any(r.reference?)?;
                Some((r.timestamp, (r.t_cr * trw).inverse()))
            })
            .collect()
    }

    /// Keyframe poses `T_world_camera` with their timestamps, in id order.
    pub fn keyframe_trajectory(&self) -> Vec<(f64, Isometry3<f64>)> {
        self.map
            .keyframes()
            .map(|k| (k.timestamp, k.tcw.inverse()))
            .collect()
    }

    /// Processes one frame: extracts its features, then [`System::track_features`].
    pub fn track(&mut self, input: &FrameInput) -> TrackResult {
        let t0 = Instant::now();
        let features = Arc::new(extract_features(input, &self.camera, &mut self.extractor));
        let time_features_ms = t0.elapsed().as_secs_f64() * 1e3;
        self.track_features(input.timestamp, features, time_features_ms)
    }

    /// Processes one frame whose features were extracted beforehand ([`extract_features`]
    /// with this system's camera and `config().orb`), e.g. once for all runs of a
    /// sweep; `time_features_ms` is what that extraction took, for the frame's statistics.
    /// Gives the same result, bit for bit, as [`System::track`] on the frame's images.
    pub fn track_features(
        &mut self,
        timestamp: f64,
        features: Arc<Features>,
        time_features_ms: f64,
    ) -> TrackResult {
        let id = self.frame_count;
        self.frame_count += 1;
        let features = match self.rebased_bf {
            Some(bf) => Arc::new(features.with_rgbd_bf(bf)),
            None => features,
        };
        let mut cur = TrackedFrame::new(id, timestamp, features);
        let t1 = Instant::now();
        let mut stats = FrameStats {
            timestamp,
            state: self.state,
            n_keypoints: cur.len(),
            n_matches: 0,
            n_inliers: 0,
            n_outliers: 0,
            n_tracked_map_points: 0,
            n_mcor_rejected_clusters: 0,
            n_mcor_rejected_features: 0,
            keyframe_inserted: false,
            relocalized: false,
            loop_detected: false,
            loop_closed: false,
            n_loops: 0,
            n_keyframes: 0,
            n_map_points: 0,
            time_features_ms,
            time_tracking_ms: 0.0,
            time_mapping_ms: 0.0,
            time_ba_ms: 0.0,
            time_loop_ms: 0.0,
        };
        let mut mapping = MappingReport::default();
        if self.state == TrackingState::NotInitialized {
            if let Some(report) = self.initialize(&mut cur) {
                mapping = report;
                self.state = TrackingState::Ok;
                stats.keyframe_inserted = true;
                stats.n_matches = cur.n_matches();
                stats.n_inliers = stats.n_matches;
                stats.n_tracked_map_points = stats.n_matches;
            }
        } else {
            self.track_frame(&mut cur, &mut stats);
            // Local mapping and loop closing of the keyframes due by now (this frame's, when
            // synchronous); the frame then moves with its reference keyframe.
            let reference_before = cur.reference_kf.and_then(|r| self.map.keyframe_pose_any(r));
            mapping = self.map_due_keyframes(cur.id, &mut stats);
            self.move_with_reference(&mut cur, reference_before);
        }
        self.record(&cur);
        let tcw = if self.state.is_tracked() {
            cur.tcw
        } else {
            None
        };
        self.tracker.last_frame = Some(cur);
        stats.state = self.state;
        stats.n_keyframes = self.map.keyframe_count();
        stats.n_map_points = self.map.map_point_count();
        stats.time_mapping_ms = mapping.time_mapping_ms;
        stats.time_ba_ms = mapping.time_ba_ms;
        stats.n_loops = self.loop_closer.loops.len();
        stats.time_tracking_ms = (t1.elapsed().as_secs_f64() * 1e3
            - mapping.time_mapping_ms
            - mapping.time_ba_ms
            - stats.time_loop_ms)
            .max(0.0);
        self.stats.push(stats.clone());
        TrackResult {
            state: self.state,
            tcw,
            stats,
        }
    }

    /// Map initialisation from one frame (ORB-SLAM2's StereoInitialization): identity pose, a
    /// map point for every keypoint with depth.
    fn initialize(&mut self, cur: &mut TrackedFrame) -> Option<MappingReport> {
        self.map_touched = true;
        let n_depth = (0..cur.len())
            .filter(|&i| cur.features.depth_of(i).is_some())
            .count();
        if cur.len() <= self.config.init_min_keypoints || n_depth < self.config.init_min_depths {
            return None;
        }
        cur.tcw = Some(Isometry3::identity());
        let kf = self.map.create_keyframe(
            cur.id,
            cur.timestamp,
            Isometry3::identity(),
            cur.features.clone(),
        );
        let mut created = Vec::new();
        for i in 0..cur.len() {
            let Some(pc) = cur.features.unproject_camera(i, &self.camera) else {
                continue;
            };
            let mp = self
                .map
                .create_map_point(pc, cur.features.descriptors[i], kf);
            self.map.add_observation(mp, kf, i);
            self.map.compute_distinctive_descriptor(mp);
            self.map.update_normal_and_depth(mp, &self.levels);
            cur.map_points[i] = Some(mp);
            created.push(mp);
        }
        self.index_keyframe(kf, cur);
        cur.reference_kf = Some(kf);
        self.tracker.reference_kf = Some(kf);
        self.tracker.local_keyframes = vec![kf];
        self.tracker.local_points = created.clone();
        self.last_keyframe_frame = cur.id;
        let ctx = mapping_context(&self.camera, &self.levels, &self.config, &self.ba_cfg);
        Some(self.mapper.process(kf, created, &mut self.map, &ctx))
    }

    /// Tracking of an initialised system (ORB-SLAM2's Track after initialisation).
    fn track_frame(&mut self, cur: &mut TrackedFrame, stats: &mut FrameStats) {
        let max_frames = self
            .config
            .keyframes
            .max_frames
            .unwrap_or(self.camera.fps.round().max(1.0) as u64);
        if std::mem::take(&mut self.map_touched) {
            self.mcor_clusters.get_mut().invalidate();
        }
        let hooks = NoiseHooks {
            mcor: self.config.mcor.as_ref(),
            avc: self.config.avc.as_ref(),
            rc: self.config.rc.as_ref(),
            clusters: Some(&self.mcor_clusters),
        };
        let ctx = TrackingContext {
            camera: &self.camera,
            levels: &self.levels,
            params: &self.config.tracking,
            pose_cfg: &self.pose_cfg,
            hooks,
            max_frames,
            place: self.place.as_ref(),
        };
        let mut relocalized = false;
        let mut ok = if self.state.is_tracked() {
            self.tracker.check_replaced_in_last_frame(&self.map);
            let last_rel = self
                .records
                .last()
                .filter(|r| r.tracked)
                .and_then(|r| r.reference.map(|k| (k, r.t_cr)));
            self.tracker.update_last_frame(&self.map, last_rel);
            if self.tracker.velocity.is_none() || self.tracker.recently_relocalized(cur.id, 2) {
                self.tracker
                    .track_reference_keyframe(cur, &mut self.map, &ctx)
            } else {
                self.tracker
                    .track_with_motion_model(cur, &mut self.map, &ctx)
                    || self
                        .tracker
                        .track_reference_keyframe(cur, &mut self.map, &ctx)
            }
        } else {
            let rctx = RelocalizationContext {
                camera: &self.camera,
                levels: &self.levels,
                params: &self.config.relocalization,
                pose_cfg: &self.pose_cfg,
                hooks,
                place: self.place.as_ref(),
            };
            match relocalize(cur, &self.map, &rctx, &mut self.rng) {
                Some(kf) => {
                    self.tracker.last_reloc_frame = Some(cur.id);
                    self.tracker.reference_kf = Some(kf);
                    relocalized = true;
                    true
                }
                None => false,
            }
        };
        cur.reference_kf = self.tracker.reference_kf;
        if ok {
            ok = self.tracker.track_local_map(cur, &mut self.map, &ctx);
            stats.n_matches = self.tracker.local_matches;
            stats.n_inliers = cur
                .map_points
                .iter()
                .zip(&cur.outliers)
                .filter(|(m, &o)| m.is_some() && !o)
                .count();
            stats.n_outliers = stats.n_matches.saturating_sub(stats.n_inliers);
            stats.n_tracked_map_points = self.tracker.matches_inliers;
            if let (Some(params), Some(tcw)) = (self.config.mcor.as_ref(), cur.tcw) {
                // The gate the last optimization round ran, re-run at the final pose.
                let (_, gate) = mcor_frame_gate_with(
                    cur,
                    &self.map,
                    &self.camera,
                    params,
                    &tcw,
                    &mut self.mcor_clusters.borrow_mut(),
                );
                stats.n_mcor_rejected_clusters = gate.n_rejected_clusters;
                stats.n_mcor_rejected_features = gate.n_rejected_features;
            }
        }
        if !ok {
            self.state = TrackingState::Lost;
            self.tracker.velocity = None;
            return;
        }
        self.state = if relocalized {
            TrackingState::Relocalized
        } else {
            TrackingState::Ok
        };
        stats.relocalized = relocalized;
        let last_pose = self.tracker.last_frame.as_ref().and_then(|l| l.tcw);
        self.tracker.velocity = match (cur.tcw, last_pose) {
            (Some(c), Some(l)) => Some(renormalized(&(c * l.inverse()))),
            _ => None,
        };
        let decision = KeyFrameDecisionInput {
            frame_id: cur.id,
            last_keyframe_frame: self.last_keyframe_frame,
            last_reloc_frame: self.tracker.last_reloc_frame,
            matches_inliers: self.tracker.matches_inliers,
            reference_kf: self.tracker.reference_kf.unwrap_or(KeyFrameId(0)),
            keyframes_in_queue: self.pending.len(),
        };
        if need_new_keyframe(
            cur,
            &decision,
            &self.map,
            &self.camera,
            &self.config.keyframes,
        ) {
            self.map_touched = true;
            if let Some((kf, created)) =
                create_keyframe(cur, &mut self.map, &self.camera, &self.levels)
            {
                self.index_keyframe(kf, cur);
                self.tracker.reference_kf = Some(kf);
                cur.reference_kf = Some(kf);
                self.last_keyframe_frame = cur.id;
                stats.keyframe_inserted = true;
                let lag = match self.config.mapping_lag {
                    0 => 0,
                    n => self.rng.random_range(0..=u64::from(n)),
                };
                let after_queue = self.pending.back().map_or(0, |p| p.due);
                self.pending.push_back(PendingKeyFrame {
                    kf,
                    created,
                    due: (cur.id + lag).max(after_queue),
                });
            }
        }
        if !stats.keyframe_inserted {
            self.store_mcor_views(cur);
        }

        cur.drop_outliers();
    }

    /// MC-OR's every-frame cluster reading: the tracked frame's sightings
    /// ([`frame_sightings`]) join their map points' clusters as frame views.
    fn store_mcor_views(&mut self, cur: &TrackedFrame) {
        let Some(params) = self.config.mcor.as_ref() else {
            return;
        };
        for (id, view) in frame_sightings(cur, &self.map, &self.camera, params) {
            if let Some(mp) = self.map.map_point_mut(id) {
                mp.views.push(view);
                let views = &self.map.map_point_any(id).expect("just pushed").views;
                self.mcor_clusters
                    .get_mut()
                    .push_view(&self.map, id, &view, views);
            }
        }
    }

    /// Runs local mapping, then loop closing, for the waiting keyframes whose mapping has
    /// completed by the end of frame `frame_id` (all of them in the synchronous run), in
    /// keyframe order; merges a global BA that is due. Returns the summed mapping report and
    /// notes loops in `stats`.
    fn map_due_keyframes(&mut self, frame_id: u64, stats: &mut FrameStats) -> MappingReport {
        let mut total = MappingReport::default();
        if self
            .pending_gba
            .as_ref()
            .is_some_and(|(due, _)| *due <= frame_id)
        {
            let t = Instant::now();
            if let Some((_, result)) = self.pending_gba.take() {
                self.map_touched = true;
                apply_global_ba(&mut self.map, &result, &self.levels);
            }
            stats.time_loop_ms += t.elapsed().as_secs_f64() * 1e3;
        }
        while self.pending.front().is_some_and(|p| p.due <= frame_id) {
            let Some(p) = self.pending.pop_front() else {
                break;
            };
            if self.map.keyframe(p.kf).is_none() {
                continue;
            }
            self.map_touched = true;
            let ctx = mapping_context(&self.camera, &self.levels, &self.config, &self.ba_cfg);
            let r = self.mapper.process(p.kf, p.created, &mut self.map, &ctx);
            total.time_mapping_ms += r.time_mapping_ms;
            total.time_ba_ms += r.time_ba_ms;
            let t = Instant::now();
            self.close_loops(p.kf, frame_id, stats);
            stats.time_loop_ms += t.elapsed().as_secs_f64() * 1e3;
        }
        total
    }

    /// Carries the current frame along with its reference keyframe when local BA, a loop
    /// correction or a global BA moved the keyframe after the frame was tracked: the frame was
    /// tracked in the map as it was, so its pose relative to the reference keyframe is what it
    /// knows. Without this the stored relative pose absorbs the keyframe's move, and the next
    /// frame's motion model starts from a pose in the uncorrected map (under `--mapping-lag`;
    /// synchronously the reference keyframe is the frame itself).
    fn move_with_reference(&self, cur: &mut TrackedFrame, before: Option<Isometry3<f64>>) {
        let after = cur.reference_kf.and_then(|r| self.map.keyframe_pose_any(r));
        if let (Some(tcw), Some(before), Some(after)) = (cur.tcw, before, after) {
            if before == after {
                return;
            }
            cur.tcw = Some(renormalized(&(tcw * before.inverse() * after)));
        }
    }

    /// Loop closing for the freshly mapped keyframe `kf`; after a closed loop, the global BA
    /// is merged at once (synchronous run) or a seeded number of frames later (mapping lag),
    /// replacing one still pending, as ORB-SLAM2 aborts a running global BA for a new loop.
    fn close_loops(&mut self, kf: KeyFrameId, frame_id: u64, stats: &mut FrameStats) {
        let params = &self.config.loop_closing;
        let Some(place) = self.place.as_ref().filter(|_| params.enabled) else {
            return;
        };
        let ctx = LoopContext {
            camera: &self.camera,
            levels: &self.levels,
            params,
            pose_cfg: &self.pose_cfg,
            place,
        };
        let report = self
            .loop_closer
            .process(kf, &mut self.map, &ctx, &mut self.rng);
        stats.loop_detected |= report.detected;
        if report.closed.is_none() {
            return;
        }
        stats.loop_closed = true;
        self.pending_gba = None;
        if !params.global_ba {
            return;
        }
        let hooks = NoiseHooks {
            mcor: self.config.mcor.as_ref(),
            avc: self.config.avc.as_ref(),
            rc: None,
            clusters: None,
        };
        let result = global_bundle_adjustment(
            &self.map,
            &self.camera,
            &self.levels,
            &hooks,
            params.global_ba_iterations,
        );
        match self.config.mapping_lag {
            0 => apply_global_ba(&mut self.map, &result, &self.levels),
            n => {
                let due = frame_id + self.rng.random_range(1..=u64::from(n));
                self.pending_gba = Some((due, result));
            }
        }
    }

    /// Stores the frame's pose relative to its reference keyframe (or repeats the last relative
    /// pose, flagged untracked, as ORB-SLAM2 does for lost frames).
    fn record(&mut self, cur: &TrackedFrame) {
        let tracked = self.state.is_tracked();
        let rec = match (tracked, cur.tcw, cur.reference_kf) {
            (true, Some(tcw), Some(r)) => match self.map.keyframe_pose_any(r) {
                Some(trw) => FrameRecord {
                    timestamp: cur.timestamp,
                    reference: Some(r),
                    // A keyframe made from this frame may have been moved by local BA already;
                    // the frame is that keyframe, so its relative pose is the identity.
                    t_cr: if self
                        .map
                        .keyframe_any(r)
                        .is_some_and(|k| k.frame_id == cur.id)
                    {
                        Isometry3::identity()
                    } else {
                        renormalized(&(tcw * trw.inverse()))
                    },
                    tracked: true,
                },
                None => self.untracked_record(cur.timestamp),
            },
            _ => self.untracked_record(cur.timestamp),
        };
        self.records.push(rec);
    }

    fn untracked_record(&self, timestamp: f64) -> FrameRecord {
        match self.records.last() {
            Some(last) => FrameRecord {
                timestamp,
                tracked: false,
                ..*last
            },
            None => FrameRecord {
                timestamp,
                reference: None,
                t_cr: Isometry3::identity(),
                tracked: false,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partial_toml_config_keeps_defaults_and_switches_techniques() {
        let c: Config = toml::from_str(
            "seed = 5\n[tracking]\nlocal_ratio = 0.7\n[orb]\nn_features = 1200\n[mcor]\ntau_mg = 0.3\n",
        )
        .unwrap();
        assert_eq!(c.seed, 5);
        assert_eq!(c.tracking.local_ratio, 0.7);
        assert_eq!(c.tracking.min_inliers_local_map, 30);
        assert_eq!(c.orb.n_features, 1200);
        assert_eq!(c.orb.n_levels, 8);
        let m = c.mcor.clone().unwrap();
        assert_eq!((m.tau_mf, m.tau_gf, m.tau_mg), (0.7, 0.7, 0.3));
        assert!(c.avc.is_none());
        let back: Config = toml::from_str(&toml::to_string(&c).unwrap()).unwrap();
        assert_eq!(back, c);
        assert_eq!(toml::from_str::<Config>("").unwrap(), Config::default());
    }

    #[test]
    fn the_readings_parse_from_toml_and_an_unknown_value_names_the_allowed_ones() {
        let c: Config = toml::from_str(
            "[mcor]\nsightings = \"all\"\nverdict = \"consensus\"\nscope = \"tracking+mapping\"\n\
             [avc]\ngate = \"3dof\"\nb_role = \"camera\"\n",
        )
        .unwrap();
        let m = c.mcor.unwrap();
        assert_eq!(
            (m.sightings, m.verdict, m.scope),
            (Sightings::All, Verdict::Consensus, Scope::TrackingMapping)
        );
        let a = c.avc.unwrap();
        assert_eq!(
            (a.gate, a.b_role),
            (AvcGate::ThreeDof, BaselineRole::Camera)
        );
        let e = toml::from_str::<Config>("[mcor]\nverdict = \"vote\"\n").unwrap_err();
        let e = e.to_string();
        assert!(
            e.contains("vote") && e.contains("filter") && e.contains("consensus"),
            "{e}"
        );
        let e = toml::from_str::<Config>("[avc]\ngate = \"2dof\"\n").unwrap_err();
        assert!(e.to_string().contains("4dof"), "{e}");
    }

    #[test]
    fn under_the_camera_reading_b_is_the_rgbd_baseline_and_sets_the_close_threshold() {
        let camera = Camera::tum_fr3();
        let b = 0.05;
        let camera_role = Config {
            avc: Some(AvcParams {
                baseline: b,
                b_role: BaselineRole::Camera,
                ..AvcParams::default()
            }),
            ..Config::default()
        };
        let run = camera_role.run_camera(&camera);
        assert_eq!(run.bf, b * camera.fx);
        assert!((run.close_depth() - camera.th_depth * b).abs() < 1e-12);
        let system = System::new(camera.clone(), camera_role.clone());
        assert_eq!(system.camera().close_depth(), run.close_depth());
        // The residual reading leaves the camera as it is; so does a stereo rig.
        let residual_role = Config {
            avc: Some(AvcParams {
                baseline: b,
                ..AvcParams::default()
            }),
            ..Config::default()
        };
        assert_eq!(residual_role.run_camera(&camera), camera);
        let stereo = Camera::euroc_rectified();
        assert_eq!(camera_role.run_camera(&stereo), stereo);
        // The baseline alone (the ORB-SLAM2 row of Table I under this reading).
        let alone = Config {
            rgbd_baseline: Some(b),
            ..Config::default()
        };
        assert_eq!(alone.run_camera(&camera), run);
    }

    #[test]
    fn features_rebased_to_another_baseline_are_those_extracted_with_it() {
        let camera = Camera::tum_fr3();
        let kps: Vec<crate::feature::KeyPoint> = (0..4)
            .map(|i| crate::feature::KeyPoint {
                x: 100.0 + 50.0 * i as f32,
                y: 200.0,
                octave: 0,
                angle: 0.0,
                response: 1.0,
            })
            .collect();
        let depth = vec![1.0f32, 2.5, 0.0, 4.0];
        let ur_of = |bf: f64| -> Vec<f32> {
            kps.iter()
                .zip(&depth)
                .map(|(k, &d)| {
                    if d > 0.0 {
                        (k.x as f64 - bf / d as f64) as f32
                    } else {
                        -1.0
                    }
                })
                .collect()
        };
        let f = Features::new(
            kps.clone(),
            vec![[0; 4]; 4],
            depth.clone(),
            ur_of(camera.bf),
            &camera,
        );
        let rebased = f.with_rgbd_bf(0.05 * camera.fx);
        assert_eq!(rebased.u_right, ur_of(0.05 * camera.fx));
        assert_eq!(rebased.depth, depth);
    }
}
