//! Map-point Consensus based Outlier Rejection (paper III-A, Eq. 1-6, Algorithm 1).
//!
//! Every map point M keeps its *cluster*: the 3-D features X_i = T_wc,i * backproject(x_i, d_i)
//! of its observations, each back-projected with its measured depth and placed in the world with
//! its observer's pose. G is their running centroid (Eq. 1). Feature-level (FL) metrics score one
//! feature, |M - X_i| and |G - X_i| (Eq. 2, 3); cluster-level (CL) metrics score the landmark,
//! the means of the FL metrics (Eq. 4, 5) and |M - G| (Eq. 6). Algorithm 1 first drops clusters
//! whose CL metrics exceed (tau_MF, tau_GF, tau_MG), then, within the remaining clusters, single
//! features whose FL metrics exceed (tau_MF, tau_GF). Comparisons are strict (`>` rejects), as
//! in Algorithm 1.
//!
//! # Interpretations (documented choices)
//! - **Bounded memory.** A cluster keeps the [`MCOR_CLUSTER_CAPACITY`] = 32 most recent features
//!   in a ring; older ones are folded into a running sum and count. G (Eq. 1) uses *all*
//!   features (ring + folded sum); the FL / CL means (Eq. 4, 5) run over the ring (plus the
//!   current frame's feature), i.e. over the 32 most recent sightings. ORB-SLAM2 map points
//!   rarely have more than a few dozen keyframe observations, so for almost every point the
//!   ring *is* the whole cluster and Eq. 1-6 hold exactly. Memory per cluster: at most
//!   32 x 56 bytes + 64 bytes. (The system does not even store clusters: it derives each one
//!   from the map point's keyframe observations when a frame is gated, see
//!   [`crate::module::pose_estimation`].)
//! - **Observer poses move.** Ring features keep their camera-frame back-projection and a
//!   `source` tag (the observing keyframe id), so [`McorCluster::relocate`] can re-place them
//!   with the current poses after bundle adjustment moved keyframes. Folded features stay where
//!   they were when folded, and cannot be removed individually.
//! - **The current frame joins the cluster.** When a frame is gated, its own feature X_cur,
//!   placed with the frame's *current* pose estimate, is included in G and in the CL means
//!   ("G updated after every camera viewpoint"). Re-running the gate between pose-optimization
//!   rounds with the moved pose refreshes X_cur, G and every metric (paper: "even between
//!   multiple runs of the optimization for a frame, MC-OR ensures the centroid to be dynamically
//!   updated").
//! - **What a frame's gate rejects.** For pose-only optimization each cluster contributes a
//!   single edge, the current frame's keypoint, so Algorithm 1's `selected_features` reduces to:
//!   the match is kept iff its cluster passes the CL test and X_cur passes the FL test.
//!   [`McorCluster::select`] runs Algorithm 1 over all features of a cluster, which is what
//!   gating bundle-adjustment observations needs: by default the system does not gate local BA
//!   (it keeps ORB-SLAM2's chi2 erasure there); under `scope = "tracking+mapping"` local mapping
//!   applies [`McorCluster::judge_sightings`] to every local point before BA.
//! - **Matches without depth.** A keypoint without measured depth has no 3-D feature: it is not
//!   FL-tested, but it is still subject to its landmark's CL test (the paper: when the CL metrics
//!   are high "the landmark is bad to consider as an interest point"), computed over the cluster
//!   without a current feature. A cluster with no feature at all (never seen with depth) cannot
//!   be judged and passes.
//! - **Depth-normalised variant** (`McorParams::depth_normalised`, not used by the paper): each
//!   FL distance is divided by its feature's measured depth d_i (the z of its back-projection in
//!   its own camera), CL1 / CL2 are the means of those ratios, and CL3 = |M - G| is divided by the
//!   mean measured depth of the features in the means. Thresholds are then dimensionless
//!   (fractions of depth; e.g. 0.1 = 10 % of the depth), since depth noise grows with depth.

use std::collections::VecDeque;

use nalgebra::{Isometry3, Point3, Vector3};

use crate::techniques::params::McorParams;

/// Most recent features a cluster keeps individually; older ones only count in G's running sum
/// (the bound of a map point's stored frame views too, where it is defined).
pub use crate::data::MCOR_CLUSTER_CAPACITY;

/// The `source` tag of the current frame's feature while it is gated (never stored).
pub const CURRENT_FRAME_SOURCE: u64 = u64::MAX;

/// One 3-D feature X_i of a cluster: an observation back-projected with its measured depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterFeature {
    source: u64,
    point_camera: Vector3<f64>,
    point_world: Vector3<f64>,
}

impl ClusterFeature {
    /// The feature observed by `source` (e.g. a keyframe id) at `point_camera` (the keypoint
    /// back-projected with its measured depth, metres, observer's camera frame), placed in the
    /// world with the observer's pose `twc` (camera to world). `None` unless the depth
    /// (`point_camera.z`) is finite and positive.
    pub fn new(source: u64, point_camera: Vector3<f64>, twc: &Isometry3<f64>) -> Option<Self> {
        let finite = point_camera.iter().all(|x| x.is_finite());
        (finite && point_camera.z > 0.0).then(|| ClusterFeature {
            source,
            point_camera,
            point_world: (twc * Point3::from(point_camera)).coords,
        })
    }

    /// A feature already placed in the world at `point_world` (e.g. a stored frame view moved
    /// with its reference keyframe); `point_camera` is its observer's back-projection.
    pub fn placed(source: u64, point_camera: Vector3<f64>, point_world: Vector3<f64>) -> Self {
        ClusterFeature {
            source,
            point_camera,
            point_world,
        }
    }

    /// Who observed it (keyframe id, or [`CURRENT_FRAME_SOURCE`]).
    pub fn source(&self) -> u64 {
        self.source
    }

    /// The back-projection in the observer's camera frame (metres).
    pub fn point_camera(&self) -> Vector3<f64> {
        self.point_camera
    }

    /// X_i: the feature in the world frame (metres).
    pub fn point_world(&self) -> Vector3<f64> {
        self.point_world
    }

    /// The measured depth d_i (metres).
    pub fn depth(&self) -> f64 {
        self.point_camera.z
    }
}

/// FL metrics of one feature (Eq. 2, 3); metres, or fractions of its depth when normalised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeatureMetrics {
    /// MCE_FL,1 = |M - X_i|.
    pub to_map_point: f64,
    /// MCE_FL,2 = |G - X_i|.
    pub to_centroid: f64,
}

/// CL metrics of a cluster (Eq. 4-6) and the centroid they were computed with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterMetrics {
    /// MCE_CL,1: mean of |M - X_i| over the features in the means.
    pub mean_to_map_point: f64,
    /// MCE_CL,2: mean of |G - X_i| over the features in the means.
    pub mean_to_centroid: f64,
    /// MCE_CL,3 = |M - G|.
    pub map_point_to_centroid: f64,
    /// G (Eq. 1), world frame, over all features (folded ones included) and the current one.
    pub centroid: Vector3<f64>,
    /// Features in the means (ring + current).
    pub n_features: usize,
}

/// CL metrics of a cluster and the FL metrics of the current frame's feature, if any.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McorMetrics {
    /// The cluster-level metrics.
    pub cluster: ClusterMetrics,
    /// FL metrics of the current frame's feature (`None` when the keypoint has no depth).
    pub current: Option<FeatureMetrics>,
}

/// Algorithm 1 over one cluster: whether the cluster survived, and which features did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct McorSelection {
    /// The cluster failed the CL test (then nothing is selected).
    pub cluster_rejected: bool,
    /// Per ring feature (in [`McorCluster::features`] order): selected.
    pub features: Vec<bool>,
    /// The current frame's feature: selected (`None` when there was none).
    pub current: Option<bool>,
}

/// The cluster of 3-D features of one map point, with bounded memory (see the module doc).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct McorCluster {
    /// The most recent features, oldest first, at most [`MCOR_CLUSTER_CAPACITY`].
    recent: VecDeque<ClusterFeature>,
    /// Sum of the world positions of features folded out of the ring.
    folded_sum: Vector3<f64>,
    /// Number of folded features.
    folded_count: u64,
}

impl McorCluster {
    /// An empty cluster.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a feature. A feature with the same `source` already in the ring is replaced (one
    /// observation per observer); otherwise, when the ring is full, its oldest feature is folded
    /// into the running sum.
    pub fn push(&mut self, feature: ClusterFeature) {
        if let Some(f) = self.recent.iter_mut().find(|f| f.source == feature.source) {
            *f = feature;
            return;
        }
        self.push_distinct(feature);
    }

    /// Adds a feature whose `source` the caller knows is not in the ring (no search); when the
    /// ring is full, its oldest feature is folded into the running sum.
    pub fn push_distinct(&mut self, feature: ClusterFeature) {
        if self.recent.len() == MCOR_CLUSTER_CAPACITY {
            if let Some(old) = self.recent.pop_front() {
                self.folded_sum += old.point_world;
                self.folded_count += 1;
            }
        }
        self.recent.push_back(feature);
    }

    /// Adds `count` features already folded elsewhere, whose world positions sum to `sum`: they
    /// count in G (Eq. 1) but not in the FL / CL means.
    pub fn add_folded(&mut self, sum: Vector3<f64>, count: u64) {
        self.folded_sum += sum;
        self.folded_count += count;
    }

    /// Removes the ring feature of `source` (an observation erased from the map); `false` when
    /// it is not in the ring (absent, or already folded into the running sum).
    pub fn remove(&mut self, source: u64) -> bool {
        match self.recent.iter().position(|f| f.source == source) {
            Some(k) => {
                self.recent.remove(k);
                true
            }
            None => false,
        }
    }

    /// Re-places every ring feature with its observer's current pose `pose_of(source)` (camera
    /// to world); features whose observer is unknown (`None`) keep their position.
    pub fn relocate(&mut self, mut pose_of: impl FnMut(u64) -> Option<Isometry3<f64>>) {
        for f in &mut self.recent {
            if let Some(twc) = pose_of(f.source) {
                f.point_world = (twc * Point3::from(f.point_camera)).coords;
            }
        }
    }

    /// Absorbs `other` (map-point fusion): its folded sum, then its ring features (sources
    /// already present keep this cluster's feature).
    pub fn merge(&mut self, other: &McorCluster) {
        self.folded_sum += other.folded_sum;
        self.folded_count += other.folded_count;
        for f in &other.recent {
            if !self.recent.iter().any(|g| g.source == f.source) {
                self.push(*f);
            }
        }
    }

    /// The ring features, oldest first.
    pub fn features(&self) -> impl ExactSizeIterator<Item = &ClusterFeature> + '_ {
        self.recent.iter()
    }

    /// Features held individually (at most [`MCOR_CLUSTER_CAPACITY`]).
    pub fn len(&self) -> usize {
        self.recent.len()
    }

    /// Whether the ring holds no feature.
    pub fn is_empty(&self) -> bool {
        self.recent.is_empty()
    }

    /// N of Eq. 1: every feature ever kept, folded ones included.
    pub fn total_count(&self) -> u64 {
        self.folded_count + self.recent.len() as u64
    }

    /// G of Eq. 1 over the stored features (`None` for an empty cluster).
    pub fn centroid(&self) -> Option<Vector3<f64>> {
        self.centroid_with(None)
    }

    /// G over the stored features and `current`.
    fn centroid_with(&self, current: Option<&ClusterFeature>) -> Option<Vector3<f64>> {
        let mut sum = self.folded_sum;
        let mut n = self.folded_count;
        for f in self.recent.iter().chain(current) {
            sum += f.point_world;
            n += 1;
        }
        (n > 0).then(|| sum / n as f64)
    }

    /// CL metrics of the cluster with the current frame's feature `current` included, and that
    /// feature's FL metrics, for map point `map_point` (world). `None` when there is no feature
    /// to average over (empty ring and no current feature).
    pub fn metrics(
        &self,
        map_point: &Vector3<f64>,
        current: Option<&ClusterFeature>,
        depth_normalised: bool,
    ) -> Option<McorMetrics> {
        let n_features = self.recent.len() + usize::from(current.is_some());
        if n_features == 0 {
            return None;
        }
        let g = self.centroid_with(current)?;
        let (mut sum_m, mut sum_g, mut sum_depth) = (0.0, 0.0, 0.0);
        for f in self.recent.iter().chain(current) {
            let fl = feature_metrics(map_point, &g, f, depth_normalised);
            sum_m += fl.to_map_point;
            sum_g += fl.to_centroid;
            sum_depth += f.depth();
        }
        let n = n_features as f64;
        let mut map_point_to_centroid = (map_point - g).norm();
        if depth_normalised {
            map_point_to_centroid /= sum_depth / n;
        }
        Some(McorMetrics {
            cluster: ClusterMetrics {
                mean_to_map_point: sum_m / n,
                mean_to_centroid: sum_g / n,
                map_point_to_centroid,
                centroid: g,
                n_features,
            },
            current: current.map(|f| feature_metrics(map_point, &g, f, depth_normalised)),
        })
    }

    /// Algorithm 1 over this cluster: the CL test, then the FL test of every ring feature and of
    /// `current`. `None` when the cluster holds no feature to judge.
    pub fn select(
        &self,
        params: &McorParams,
        map_point: &Vector3<f64>,
        current: Option<&ClusterFeature>,
    ) -> Option<McorSelection> {
        let m = self.metrics(map_point, current, params.depth_normalised)?;
        if !cluster_passes(params, &m.cluster) {
            return Some(McorSelection {
                cluster_rejected: true,
                features: vec![false; self.recent.len()],
                current: current.map(|_| false),
            });
        }
        let g = m.cluster.centroid;
        let pass = |f: &ClusterFeature| {
            feature_passes(
                params,
                &feature_metrics(map_point, &g, f, params.depth_normalised),
            )
        };
        Some(McorSelection {
            cluster_rejected: false,
            features: self.recent.iter().map(pass).collect(),
            current: current.map(pass),
        })
    }
}

/// What local mapping does with a map point under MC-OR's `scope = "tracking+mapping"`
/// reading: Algorithm 1 over the point's whole cluster.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SightingsJudgement {
    /// The cluster failed the CL test: the landmark is culled.
    Cull,
    /// The cluster passed (or holds no feature): the sources of the ring features that failed
    /// the FL test, ascending (a keyframe's id, or a frame view's tagged id).
    Keep {
        /// Sources of the rejected features.
        rejected: Vec<u64>,
    },
}

impl McorCluster {
    /// Algorithm 1 over this cluster's features for map point `map_point` (world), with no
    /// current frame: what local mapping applies under `scope = "tracking+mapping"`. A feature
    /// folded out of the ring is not judged alone (it only counts in G).
    pub fn judge_sightings(
        &self,
        params: &McorParams,
        map_point: &Vector3<f64>,
    ) -> SightingsJudgement {
        match self.select(params, map_point, None) {
            None => SightingsJudgement::Keep {
                rejected: Vec::new(),
            },
            Some(s) if s.cluster_rejected => SightingsJudgement::Cull,
            Some(s) => {
                let mut rejected: Vec<u64> = self
                    .recent
                    .iter()
                    .zip(&s.features)
                    .filter(|(_, &kept)| !kept)
                    .map(|(f, _)| f.source)
                    .collect();
                rejected.sort_unstable();
                SightingsJudgement::Keep { rejected }
            }
        }
    }
}

/// FL metrics (Eq. 2, 3) of feature `f` for map point `m` and centroid `g`, divided by the
/// feature's depth when `depth_normalised`.
pub fn feature_metrics(
    m: &Vector3<f64>,
    g: &Vector3<f64>,
    f: &ClusterFeature,
    depth_normalised: bool,
) -> FeatureMetrics {
    let scale = if depth_normalised {
        1.0 / f.depth()
    } else {
        1.0
    };
    FeatureMetrics {
        to_map_point: (m - f.point_world).norm() * scale,
        to_centroid: (g - f.point_world).norm() * scale,
    }
}

/// The CL test of Algorithm 1: no CL metric exceeds its threshold
/// (CL1 <= tau_MF, CL2 <= tau_GF, CL3 <= tau_MG).
pub fn cluster_passes(params: &McorParams, c: &ClusterMetrics) -> bool {
    !(c.mean_to_map_point > params.tau_mf
        || c.mean_to_centroid > params.tau_gf
        || c.map_point_to_centroid > params.tau_mg)
}

/// The FL test of Algorithm 1: FL1 <= tau_MF and FL2 <= tau_GF.
pub fn feature_passes(params: &McorParams, f: &FeatureMetrics) -> bool {
    !(f.to_map_point > params.tau_mf || f.to_centroid > params.tau_gf)
}

/// Which of Algorithm 1's thresholds a rejected match exceeded: what a recording of the run
/// shows beside the rejection (`run --rerun`). For a cluster rejection the CL metrics against
/// tau_MF, tau_GF and tau_MG; for a feature rejection the FL metrics against tau_MF and tau_GF.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Exceeded {
    /// CL1 (or FL1) above tau_MF.
    pub tau_mf: bool,
    /// CL2 (or FL2) above tau_GF.
    pub tau_gf: bool,
    /// CL3 above tau_MG (cluster rejections only).
    pub tau_mg: bool,
}

impl Exceeded {
    /// The thresholds `metrics` exceed for a match whose verdict was `verdict` (none when kept,
    /// or for a feature rejection without a current feature).
    pub fn of(params: &McorParams, metrics: &McorMetrics, verdict: McorVerdict) -> Self {
        match verdict {
            McorVerdict::Kept => Self::default(),
            McorVerdict::RejectedCluster => {
                let c = &metrics.cluster;
                Self {
                    tau_mf: c.mean_to_map_point > params.tau_mf,
                    tau_gf: c.mean_to_centroid > params.tau_gf,
                    tau_mg: c.map_point_to_centroid > params.tau_mg,
                }
            }
            McorVerdict::RejectedFeature => metrics.current.map_or(Self::default(), |f| Self {
                tau_mf: f.to_map_point > params.tau_mf,
                tau_gf: f.to_centroid > params.tau_gf,
                tau_mg: false,
            }),
        }
    }

    /// Whether any threshold is exceeded.
    pub fn any(&self) -> bool {
        self.tau_mf || self.tau_gf || self.tau_mg
    }

    /// The exceeded thresholds by the paper's names, e.g. `"tau_MF tau_MG"` (empty when none).
    pub fn names(&self) -> String {
        [
            (self.tau_mf, "tau_MF"),
            (self.tau_gf, "tau_GF"),
            (self.tau_mg, "tau_MG"),
        ]
        .iter()
        .filter(|(on, _)| *on)
        .map(|(_, n)| *n)
        .collect::<Vec<_>>()
        .join(" ")
    }
}

/// One match of the frame being tracked: its map point's cluster and position, and the
/// keypoint back-projected with its measured depth in the frame's camera (`None` without depth).
#[derive(Clone, Copy, Debug)]
pub struct McorMatch<'a> {
    /// The matched map point's cluster.
    pub cluster: &'a McorCluster,
    /// M: the map point, world frame (metres).
    pub map_point: Vector3<f64>,
    /// The keypoint back-projected with its measured depth, camera frame (metres).
    pub point_camera: Option<Vector3<f64>>,
}

/// What the gate decided for one match.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum McorVerdict {
    /// Enters the pose optimization.
    Kept,
    /// Its cluster failed the CL test (the landmark is rejected as a whole).
    RejectedCluster,
    /// Its cluster passed but the current frame's feature failed the FL test.
    RejectedFeature,
}

/// The gate's decision for every match of a frame, with the counts of paper Fig. 8.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct McorOutcome {
    /// One verdict per match, in input order.
    pub verdicts: Vec<McorVerdict>,
    /// Matches rejected by the cluster-level test.
    pub n_rejected_clusters: usize,
    /// Matches rejected by the feature-level test.
    pub n_rejected_features: usize,
}

impl McorOutcome {
    /// Whether match `i` enters the optimization.
    pub fn kept(&self, i: usize) -> bool {
        self.verdicts[i] == McorVerdict::Kept
    }

    /// Appends the verdict of the next match and counts it.
    pub fn push(&mut self, verdict: McorVerdict) {
        match verdict {
            McorVerdict::RejectedCluster => self.n_rejected_clusters += 1,
            McorVerdict::RejectedFeature => self.n_rejected_features += 1,
            McorVerdict::Kept => {}
        }
        self.verdicts.push(verdict);
    }

    /// Number of kept matches.
    pub fn n_kept(&self) -> usize {
        self.verdicts.len() - self.n_rejected_clusters - self.n_rejected_features
    }
}

/// Algorithm 1 over a frame's matches, hierarchically: each match's current feature
/// X_cur = T_wc * point_camera is placed with the frame's current pose estimate `twc` (camera to
/// world) and joins its cluster's metrics; a match is rejected when its cluster fails the CL test,
/// else when X_cur fails the FL test. Run it before every pose-optimization round with the
/// latest pose. Matches without depth get the CL test only; clusters with no feature pass.
pub fn mcor_gate(params: &McorParams, twc: &Isometry3<f64>, matches: &[McorMatch]) -> McorOutcome {
    let mut outcome = McorOutcome {
        verdicts: Vec::with_capacity(matches.len()),
        n_rejected_clusters: 0,
        n_rejected_features: 0,
    };
    for m in matches {
        let current = m
            .point_camera
            .and_then(|p| ClusterFeature::new(CURRENT_FRAME_SOURCE, p, twc));
        let verdict =
            match m
                .cluster
                .metrics(&m.map_point, current.as_ref(), params.depth_normalised)
            {
                None => McorVerdict::Kept,
                Some(x) if !cluster_passes(params, &x.cluster) => McorVerdict::RejectedCluster,
                Some(x) if x.current.is_some_and(|f| !feature_passes(params, &f)) => {
                    McorVerdict::RejectedFeature
                }
                Some(_) => McorVerdict::Kept,
            };
        outcome.push(verdict);
    }
    outcome
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::techniques::test_support::{gaussian, rng, sigma_z};
    use crate::Camera;
    use nalgebra::{Translation3, UnitQuaternion};
    use rand::Rng;

    /// Camera-to-world pose of observer `k`: on a 1.5 m arc around the origin, looking at it.
    fn observer(k: usize) -> Isometry3<f64> {
        let yaw = -0.4 + 0.1 * k as f64;
        let rot = UnitQuaternion::from_euler_angles(0.0, yaw, 0.0);
        let centre = rot * Vector3::new(0.0, 0.0, -2.0);
        Isometry3::from_parts(Translation3::from(centre), rot)
    }

    /// The map point at the origin seen by observers `0..n` with Nguyen's axial noise on depth.
    fn consistent_cluster(n: usize, seed: u64) -> (McorCluster, Vector3<f64>) {
        let camera = Camera::tum_fr3();
        let m = Vector3::zeros();
        let mut g = rng(seed);
        let mut cluster = McorCluster::new();
        for k in 0..n {
            let twc = observer(k);
            let p = (twc.inverse() * Point3::from(m)).coords;
            let uv = camera.project(&p);
            let depth = p.z + sigma_z(p.z) * gaussian(&mut g);
            let pc = camera.unproject(uv.x + gaussian(&mut g), uv.y + gaussian(&mut g), depth);
            cluster.push(ClusterFeature::new(k as u64, pc, &twc).unwrap());
        }
        (cluster, m)
    }

    /// The current frame (observer 9) seeing the origin with depth `depth`.
    fn current_point(depth: f64) -> Vector3<f64> {
        let p = (observer(9).inverse() * Point3::origin()).coords;
        p * (depth / p.z)
    }

    fn params() -> McorParams {
        McorParams::default()
    }

    #[test]
    fn metrics_follow_equations_1_to_6() {
        let twc = Isometry3::identity();
        let mut c = McorCluster::new();
        for (k, x) in [[0.0, 0.0, 1.0], [0.2, 0.0, 1.0], [0.1, 0.3, 1.0]]
            .iter()
            .enumerate()
        {
            c.push(ClusterFeature::new(k as u64, Vector3::from(*x), &twc).unwrap());
        }
        let m = Vector3::new(0.1, 0.1, 1.2);
        let x = c.metrics(&m, None, false).unwrap();
        let g = Vector3::new(0.1, 0.1, 1.0);
        assert!((x.cluster.centroid - g).norm() < 1e-15);
        let xs: Vec<Vector3<f64>> = c.features().map(|f| f.point_world()).collect();
        let cl1 = xs.iter().map(|xi| (m - xi).norm()).sum::<f64>() / 3.0;
        let cl2 = xs.iter().map(|xi| (g - xi).norm()).sum::<f64>() / 3.0;
        assert!((x.cluster.mean_to_map_point - cl1).abs() < 1e-12);
        assert!((x.cluster.mean_to_centroid - cl2).abs() < 1e-12);
        assert!((x.cluster.map_point_to_centroid - 0.2).abs() < 1e-12);
        assert_eq!(x.cluster.n_features, 3);
        assert_eq!(x.current, None);
        // With the current feature, G and the means include it.
        let cur = ClusterFeature::new(CURRENT_FRAME_SOURCE, Vector3::new(0.1, 0.1, 1.4), &twc);
        let x = c.metrics(&m, cur.as_ref(), false).unwrap();
        assert!((x.cluster.centroid - Vector3::new(0.1, 0.1, 1.1)).norm() < 1e-12);
        assert_eq!(x.cluster.n_features, 4);
        let fl = x.current.unwrap();
        assert!((fl.to_map_point - 0.2).abs() < 1e-12 && (fl.to_centroid - 0.3).abs() < 1e-12);
    }

    #[test]
    fn consistent_observations_pass() {
        let (cluster, m) = consistent_cluster(9, 1);
        let matches = [McorMatch {
            cluster: &cluster,
            map_point: m,
            point_camera: Some(current_point(2.0 + 0.01)),
        }];
        let out = mcor_gate(&params(), &observer(9), &matches);
        assert_eq!(out.verdicts, vec![McorVerdict::Kept]);
        assert_eq!((out.n_rejected_clusters, out.n_rejected_features), (0, 0));
        let sel = cluster.select(&params(), &m, None).unwrap();
        assert!(!sel.cluster_rejected && sel.features.iter().all(|&s| s));
        // A tight depth-normalised threshold (2 % of depth) still passes Kinect-level noise.
        let tight = McorParams {
            tau_mf: 0.02,
            tau_gf: 0.02,
            tau_mg: 0.02,
            depth_normalised: true,
            ..McorParams::default()
        };
        assert_eq!(mcor_gate(&tight, &observer(9), &matches).n_kept(), 1);
    }

    #[test]
    fn a_gross_depth_outlier_loses_its_feature() {
        let (mut cluster, m) = consistent_cluster(9, 2);
        // The current frame reads the background 1.5 m behind (lateral mixing at a boundary).
        let matches = [McorMatch {
            cluster: &cluster,
            map_point: m,
            point_camera: Some(current_point(3.5)),
        }];
        let out = mcor_gate(&params(), &observer(9), &matches);
        assert_eq!(out.verdicts, vec![McorVerdict::RejectedFeature]);
        assert_eq!((out.n_rejected_clusters, out.n_rejected_features), (0, 1));
        // The same outlier stored in the cluster is dropped by Algorithm 1, the others kept.
        let p = (observer(9).inverse() * Point3::origin()).coords;
        cluster.push(ClusterFeature::new(9, p * (3.5 / p.z), &observer(9)).unwrap());
        let sel = cluster.select(&params(), &m, None).unwrap();
        assert!(!sel.cluster_rejected);
        assert_eq!(sel.features.iter().filter(|&&s| !s).count(), 1);
        assert!(!sel.features[9]);
    }

    #[test]
    fn a_map_point_far_from_its_centroid_rejects_the_cluster() {
        let (cluster, m) = consistent_cluster(9, 3);
        // M drifted 0.6 m from where every depth reading puts the landmark: |M - G| > tau_MG.
        let drifted = m + Vector3::new(0.0, 0.6, 0.0);
        let matches = [
            McorMatch {
                cluster: &cluster,
                map_point: drifted,
                point_camera: Some(current_point(2.0)),
            },
            // Without depth the landmark is still judged by its cluster.
            McorMatch {
                cluster: &cluster,
                map_point: drifted,
                point_camera: None,
            },
            McorMatch {
                cluster: &cluster,
                map_point: m,
                point_camera: None,
            },
        ];
        let out = mcor_gate(&params(), &observer(9), &matches);
        assert_eq!(
            out.verdicts,
            vec![
                McorVerdict::RejectedCluster,
                McorVerdict::RejectedCluster,
                McorVerdict::Kept
            ]
        );
        assert_eq!((out.n_rejected_clusters, out.n_rejected_features), (2, 0));
        assert_eq!(out.n_kept(), 1);
        let sel = cluster.select(&params(), &drifted, None).unwrap();
        assert!(sel.cluster_rejected && sel.features.iter().all(|&s| !s));
    }

    #[test]
    fn a_cluster_without_features_passes() {
        let empty = McorCluster::new();
        let out = mcor_gate(
            &params(),
            &Isometry3::identity(),
            &[McorMatch {
                cluster: &empty,
                map_point: Vector3::new(0.0, 0.0, 2.0),
                point_camera: None,
            }],
        );
        assert_eq!(out.verdicts, vec![McorVerdict::Kept]);
        assert_eq!(empty.select(&params(), &Vector3::zeros(), None), None);
    }

    #[test]
    fn memory_is_capped_and_the_centroid_uses_every_feature() {
        let twc = Isometry3::identity();
        let mut c = McorCluster::new();
        let n = 1000u64;
        for k in 0..n {
            // Features spread along x around x = 0.5; their exact mean is 0.5.
            let x = k as f64 / (n - 1) as f64;
            c.push(ClusterFeature::new(k, Vector3::new(x, 0.0, 2.0), &twc).unwrap());
        }
        assert_eq!(c.len(), MCOR_CLUSTER_CAPACITY);
        assert_eq!(c.total_count(), n);
        assert!((c.centroid().unwrap() - Vector3::new(0.5, 0.0, 2.0)).norm() < 1e-12);
        // The ring holds the most recent features, oldest first.
        let sources: Vec<u64> = c.features().map(|f| f.source()).collect();
        assert_eq!(
            sources,
            (n - MCOR_CLUSTER_CAPACITY as u64..n).collect::<Vec<_>>()
        );
        // Re-adding an observer replaces its feature instead of growing the cluster.
        c.push(ClusterFeature::new(n - 1, Vector3::new(1.0, 1.0, 2.0), &twc).unwrap());
        assert_eq!((c.len(), c.total_count()), (MCOR_CLUSTER_CAPACITY, n));
        assert!(c.remove(n - 1));
        assert!(!c.remove(0), "folded features cannot be removed");
        assert_eq!(c.total_count(), n - 1);
    }

    #[test]
    fn relocate_and_merge_follow_observers() {
        let mut c = McorCluster::new();
        let p = Vector3::new(0.0, 0.0, 2.0);
        c.push(ClusterFeature::new(1, p, &Isometry3::identity()).unwrap());
        c.push(ClusterFeature::new(2, p, &Isometry3::identity()).unwrap());
        // BA moved keyframe 2 by 10 cm along x.
        let moved = Isometry3::translation(0.1, 0.0, 0.0);
        c.relocate(|s| (s == 2).then_some(moved));
        assert!((c.centroid().unwrap() - Vector3::new(0.05, 0.0, 2.0)).norm() < 1e-15);
        let mut other = McorCluster::new();
        other.push(ClusterFeature::new(2, p, &Isometry3::identity()).unwrap());
        other.push(ClusterFeature::new(3, p * 1.1, &Isometry3::identity()).unwrap());
        c.merge(&other);
        assert_eq!(c.len(), 3);
        let moved_kept = c.features().find(|f| f.source() == 2).unwrap();
        assert!((moved_kept.point_world().x - 0.1).abs() < 1e-15);
        // Invalid depth never enters a cluster.
        let id = Isometry3::identity();
        assert!(ClusterFeature::new(4, Vector3::new(0.0, 0.0, 0.0), &id).is_none());
        assert!(ClusterFeature::new(4, Vector3::new(0.0, 0.0, f64::NAN), &id).is_none());
    }

    #[test]
    fn regating_with_a_moved_pose_changes_the_outcome() {
        let (cluster, m) = consistent_cluster(9, 4);
        let matches = [McorMatch {
            cluster: &cluster,
            map_point: m,
            point_camera: Some(current_point(2.0)),
        }];
        // The initial pose estimate is 0.8 m off: X_cur lands 0.8 m from M and the match is
        // rejected; after the pose moved to the truth it is readmitted.
        let wrong = Isometry3::translation(0.8, 0.0, 0.0) * observer(9);
        let first = mcor_gate(&params(), &wrong, &matches);
        assert_eq!(first.verdicts, vec![McorVerdict::RejectedFeature]);
        let second = mcor_gate(&params(), &observer(9), &matches);
        assert_eq!(second.verdicts, vec![McorVerdict::Kept]);
        // A small pose error (5 cm) keeps it.
        let near = Isometry3::translation(0.05, 0.0, 0.0) * observer(9);
        assert!(mcor_gate(&params(), &near, &matches).kept(0));
    }

    #[test]
    fn depth_normalised_thresholds_scale_with_depth() {
        // The same 0.3 m depth error, on a point 1 m away and on one 6 m away.
        let camera = Camera::tum_fr3();
        let tau = McorParams {
            tau_mf: 0.1,
            tau_gf: 0.1,
            tau_mg: 0.1,
            depth_normalised: true,
            ..McorParams::default()
        };
        let mut verdicts = Vec::new();
        for z in [1.0, 6.0] {
            let twc = Isometry3::identity();
            let m = camera.unproject(300.0, 200.0, z);
            let mut c = McorCluster::new();
            for k in 0..5 {
                let dz = 0.002 * (k as f64 - 2.0);
                let f = ClusterFeature::new(k, camera.unproject(300.0, 200.0, z + dz), &twc);
                c.push(f.unwrap());
            }
            let matches = [McorMatch {
                cluster: &c,
                map_point: m,
                point_camera: Some(camera.unproject(300.0, 200.0, z + 0.3)),
            }];
            let x = c
                .metrics(
                    &m,
                    ClusterFeature::new(
                        CURRENT_FRAME_SOURCE,
                        matches[0].point_camera.unwrap(),
                        &twc,
                    )
                    .as_ref(),
                    true,
                )
                .unwrap();
            let fl = x.current.unwrap();
            let expected = (m - camera.unproject(300.0, 200.0, z + 0.3)).norm() / (z + 0.3);
            assert!((fl.to_map_point - expected).abs() < 1e-12);
            verdicts.push(mcor_gate(&tau, &twc, &matches).verdicts[0]);
            // In metres the 0.3 m error passes the paper's thresholds at both depths.
            assert!(mcor_gate(&params(), &twc, &matches).kept(0));
        }
        // 0.3 m is 23 % of 1.3 m (rejected) but 4.8 % of 6.3 m (kept).
        assert_eq!(
            verdicts,
            vec![McorVerdict::RejectedFeature, McorVerdict::Kept]
        );
    }

    #[test]
    fn random_consistent_clusters_are_never_rejected() {
        // 50 landmarks seen with Kinect noise from 9 views: no false rejection at the paper's
        // thresholds.
        let mut g = rng(99);
        for seed in 0..50 {
            let (cluster, m) = consistent_cluster(g.random_range(1..10), seed);
            let out = mcor_gate(
                &params(),
                &observer(9),
                &[McorMatch {
                    cluster: &cluster,
                    map_point: m,
                    point_camera: Some(current_point(2.0 + sigma_z(2.0) * gaussian(&mut g))),
                }],
            );
            assert!(out.kept(0), "seed {seed}: {out:?}");
        }
    }
}
