//! MC-OR's gate (Algorithm 1, [`mcor_gate`](super::cluster::mcor_gate)) over prepared clusters:
//! the same verdicts, bit for bit, at a fraction of the cost.
//!
//! While the map stands still (a frame's tracking, and the frames between two keyframes) the
//! map points and their clusters do not move; only the frame's pose does, between
//! pose-optimization rounds, and a tracked frame appends its views. So everything of a cluster
//! that does not involve the current feature X_cur is summed once, in the order
//! [`McorCluster::metrics`](super::cluster::McorCluster::metrics) sums it (floating-point sums are
//! not associative, so the order is part of the result): G's numerator over the folded sum and
//! the ring, and the sum of |M - X_i| over the ring. A round then adds X_cur to those sums
//! and needs the ring only for CL2 = mean |G - X_i|, which depends on G and so on the pose.
//! That one is bounded first by the triangle inequality, |G - X_i| <= |G - M| + |M - X_i|:
//! when even the bound is under tau_GF with a margin far beyond rounding, the exact mean is
//! too and the ring is not visited. Only clusters near the threshold, and the depth-normalised
//! variant, are summed exactly, by the operations of `metrics`.
//!
//! A [`PreparedCluster`] keeps every feature it was given (placed, with |M - X_i|), so that a
//! new frame view is one more feature and a re-sum, not a rebuild: the ring, the folds and
//! the sums are replayed from the features in the order a `McorCluster` built by
//! `push_distinct` / `add_folded` would have made them.

use nalgebra::{Isometry3, Matrix3, Point3, Vector3};

use super::cluster::{ClusterFeature, McorVerdict, MCOR_CLUSTER_CAPACITY};
use super::cluster::{ClusterMetrics, FeatureMetrics, McorMetrics};
use crate::ids::MapPointId;
use crate::techniques::params::{ClusterViews, McorParams};

/// Relative margin of the CL2 bound: a bound within this fraction of tau_GF is not trusted and
/// the exact mean is computed (rounding of a sum of at most a few dozen norms is ~1e-14).
const BOUND_MARGIN: f64 = 1e-6;

/// A keypoint's back-projection as [`PreparedCluster::verdict`] takes it: kept only when it
/// makes a 3-D feature (finite, positive depth: the test of `ClusterFeature::new`), so that a
/// frame tests it once and not once per round.
pub fn gate_point(point_camera: Option<Vector3<f64>>) -> Option<Vector3<f64>> {
    point_camera.filter(|p| p.iter().all(|x| x.is_finite()) && p.z > 0.0)
}

/// One feature as the gate reads it: its world position, measured depth and |M - X_i|.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RingFeature {
    point_world: Vector3<f64>,
    depth: f64,
    to_map_point: f64,
}

/// The cluster of one map point M, reduced for the gate (see the module doc). Built as a
/// `McorCluster` is: [`new`](Self::new), the keyframe features with [`push`](Self::push), the
/// frame views' folded sum with [`add_folded`](Self::add_folded), then the views with `push`,
/// and [`seal`](Self::seal); later views with [`push_view`](Self::push_view).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PreparedCluster {
    /// M, world frame.
    map_point: Vector3<f64>,
    /// Every feature given, keyframe features first (the ring is the last
    /// [`MCOR_CLUSTER_CAPACITY`] of them, the others were folded).
    features: Vec<RingFeature>,
    /// How many of `features` are keyframe features (pushed before `add_folded`).
    n_keyframe: usize,
    /// What `add_folded` added.
    added_sum: Vector3<f64>,
    added_count: u64,
    /// Whether `add_folded` was called (later pushes are views).
    views_started: bool,
    /// Sealed: the folded sum, then each ring feature in ring order (G's numerator without
    /// X_cur).
    ring_sum: Vector3<f64>,
    /// Sealed: N of Eq. 1 without X_cur.
    total: u64,
    /// Sealed: the sum of |M - X_i| over the ring, in ring order.
    ring_to_map_point: f64,
    /// Sealed: where the ring starts in `features`.
    ring_start: usize,
    /// Sealed: N of Eq. 1 as f64 without / with X_cur.
    total_f64: [f64; 2],
    /// Sealed: the number of features in the means as f64 without / with X_cur, and the
    /// ring's length.
    n_f64: [f64; 2],
    ring_len_f64: f64,
}

impl PreparedCluster {
    /// An empty cluster of map point `map_point` (world), keeping its buffer.
    pub fn reset(&mut self, map_point: Vector3<f64>) {
        self.map_point = map_point;
        self.features.clear();
        self.n_keyframe = 0;
        self.added_sum = Vector3::zeros();
        self.added_count = 0;
        self.views_started = false;
        self.seal();
    }

    /// An empty cluster of map point `map_point`.
    pub fn new(map_point: Vector3<f64>) -> Self {
        let mut c = Self::default();
        c.reset(map_point);
        c
    }

    /// Adds a feature whose source is distinct from those already in (as
    /// `McorCluster::push_distinct`).
    pub fn push(&mut self, feature: &ClusterFeature) {
        let point_world = feature.point_world();
        self.features.push(RingFeature {
            point_world,
            depth: feature.depth(),
            to_map_point: (self.map_point - point_world).norm() * 1.0,
        });
        if !self.views_started {
            self.n_keyframe += 1;
        }
    }

    /// N of Eq. 1 without the current frame's feature: every sighting the cluster holds or
    /// folded (sealed).
    pub fn sightings(&self) -> u64 {
        self.total
    }

    /// Adds features folded elsewhere whose world positions sum to `sum` (as
    /// `McorCluster::add_folded`); called once, between the keyframe features and the views.
    pub fn add_folded(&mut self, sum: Vector3<f64>, count: u64) {
        self.added_sum += sum;
        self.added_count += count;
        self.views_started = true;
    }

    /// Replays the ring and the folds, and sums what the gate needs.
    pub fn seal(&mut self) {
        let n = self.features.len();
        let cap = MCOR_CLUSTER_CAPACITY;
        // A push folds the feature `cap` places before it once the ring is full: the keyframe
        // features' folds come before `add_folded`, the views' after.
        let keyframe_folds = self.n_keyframe.saturating_sub(cap);
        let all_folds = n.saturating_sub(cap);
        let mut folded = Vector3::zeros();
        let mut count = 0u64;
        for f in &self.features[..keyframe_folds] {
            folded += f.point_world;
            count += 1;
        }
        folded += self.added_sum;
        count += self.added_count;
        for f in &self.features[keyframe_folds..all_folds] {
            folded += f.point_world;
            count += 1;
        }
        let mut ring_sum = folded;
        let mut ring_to_map_point = 0.0;
        for f in &self.features[all_folds..] {
            ring_sum += f.point_world;
            ring_to_map_point += f.to_map_point;
        }
        self.ring_sum = ring_sum;
        self.total = count + (n - all_folds) as u64;
        self.ring_to_map_point = ring_to_map_point;
        self.ring_start = all_folds;
        let ring = (n - all_folds) as u64;
        self.total_f64 = [self.total as f64, (self.total + 1) as f64];
        self.n_f64 = [ring as f64, (ring + 1) as f64];
        self.ring_len_f64 = (n - all_folds) as f64;
    }

    /// Appends a frame view to a sealed cluster and re-seals it, as a cluster rebuilt from a
    /// map point whose [`FrameViews`](crate::data::FrameViews) just took `feature` would be:
    /// `views_folded` is the views' folded sum and count after the push, and `views_kept`
    /// how many views they hold individually (their oldest ones beyond it are dropped here,
    /// since the views folded them).
    pub fn push_view(
        &mut self,
        feature: &ClusterFeature,
        views_folded: (Vector3<f64>, u64),
        views_kept: usize,
    ) {
        self.push(feature);
        let views = self.features.len() - self.n_keyframe;
        if views > views_kept {
            self.features
                .drain(self.n_keyframe..self.n_keyframe + (views - views_kept));
        }
        self.added_sum = views_folded.0;
        self.added_count = views_folded.1;
        self.views_started = true;
        self.seal();
    }

    /// Algorithm 1's verdict for a match of this cluster whose keypoint back-projects to
    /// `point_camera` (camera frame; `None` without depth; passed through [`gate_point`] once
    /// per match), with the frame at `twc` (camera to world): the verdict
    /// [`mcor_gate`](super::cluster::mcor_gate) gives for the same cluster, bit for bit.
    pub fn verdict(
        &self,
        params: &McorParams,
        twc: &Isometry3<f64>,
        point_camera: Option<&Vector3<f64>>,
    ) -> McorVerdict {
        self.judge::<false>(params, twc, point_camera).0
    }

    /// [`verdict`](Self::verdict), and its *reach*: how far (metres, world frame) the current
    /// feature X_cur may move, by a change of the frame's pose, before any comparison of
    /// Algorithm 1 that decides the verdict could turn (each metric's distance to its threshold,
    /// less a rounding allowance, over how fast the metric can follow X_cur). A gate that moves
    /// the pose by less than the reach between two rounds has the same verdict without
    /// computing it. Infinite without a current feature (nothing then depends on the pose);
    /// zero for the depth-normalised variant (not bounded here: always recomputed).
    pub fn verdict_with_reach(
        &self,
        params: &McorParams,
        twc: &Isometry3<f64>,
        point_camera: Option<&Vector3<f64>>,
    ) -> (McorVerdict, f64) {
        self.judge::<true>(params, twc, point_camera)
    }

    /// Every metric of Algorithm 1 for a match of this cluster (as [`verdict`](Self::verdict)
    /// takes it), computed in full: the verdict's fast path stops at the first metric that
    /// decides, so this is what tells which thresholds a rejection exceeded
    /// ([`Exceeded`](super::cluster::Exceeded)). For analysis (a tapped run), not the gate.
    pub fn metrics(
        &self,
        params: &McorParams,
        twc: &Isometry3<f64>,
        point_camera: Option<&Vector3<f64>>,
    ) -> McorMetrics {
        let ring = &self.features[self.ring_start..];
        let cur = point_camera.map(|p| RingFeature {
            point_world: (twc * Point3::from(*p)).coords,
            depth: p.z,
            to_map_point: 0.0,
        });
        let with_current = usize::from(cur.is_some());
        let mut sum = self.ring_sum;
        if let Some(f) = &cur {
            sum += f.point_world;
        }
        let g = sum / self.total_f64[with_current];
        let m = &self.map_point;
        let (cl1, cl2, cl3) = exact_metrics(m, &g, ring, cur.as_ref(), params.depth_normalised);
        McorMetrics {
            cluster: ClusterMetrics {
                mean_to_map_point: cl1,
                mean_to_centroid: cl2,
                map_point_to_centroid: cl3,
                centroid: g,
                n_features: ring.len() + with_current,
            },
            current: cur.map(|f| {
                let scale = if params.depth_normalised {
                    1.0 / f.depth
                } else {
                    1.0
                };
                FeatureMetrics {
                    to_map_point: (m - f.point_world).norm() * scale,
                    to_centroid: (g - f.point_world).norm() * scale,
                }
            }),
        }
    }

    /// The verdict, and with `REACH` its reach (else 0): one body, so that both give the same
    /// verdict by the same operations.
    fn judge<const REACH: bool>(
        &self,
        params: &McorParams,
        twc: &Isometry3<f64>,
        point_camera: Option<&Vector3<f64>>,
    ) -> (McorVerdict, f64) {
        let ring = &self.features[self.ring_start..];
        // X_cur as `ClusterFeature::new` places it.
        let cur = point_camera.map(|p| {
            let point_world = (twc * Point3::from(*p)).coords;
            RingFeature {
                point_world,
                depth: p.z,
                to_map_point: 0.0,
            }
        });
        let n_features = ring.len() + usize::from(cur.is_some());
        if n_features == 0 {
            return (McorVerdict::Kept, f64::INFINITY);
        }
        // G (Eq. 1): the sums of `McorCluster::centroid_with`.
        let mut sum = self.ring_sum;
        if let Some(f) = &cur {
            sum += f.point_world;
        }
        let with_current = usize::from(cur.is_some());
        let g = sum / self.total_f64[with_current];
        let m = &self.map_point;
        let n = self.n_f64[with_current];
        if params.depth_normalised {
            let (cl1, cl2, cl3) = exact_metrics(m, &g, ring, cur.as_ref(), true);
            if cl1 > params.tau_mf || cl2 > params.tau_gf || cl3 > params.tau_mg {
                return (McorVerdict::RejectedCluster, 0.0);
            }
            let verdict = match &cur {
                Some(f) => {
                    let scale = 1.0 / f.depth;
                    let to_m = (m - f.point_world).norm() * scale;
                    let to_g = (g - f.point_world).norm() * scale;
                    if to_m > params.tau_mf || to_g > params.tau_gf {
                        McorVerdict::RejectedFeature
                    } else {
                        McorVerdict::Kept
                    }
                }
                None => McorVerdict::Kept,
            };
            return (verdict, 0.0);
        }
        // How fast each metric follows X_cur (metres per metre; see `Reach`).
        let reach = Reach::<REACH>::new(
            m,
            &g,
            cur.as_ref(),
            self.ring_to_map_point,
            self.total_f64[1],
            n,
            self.ring_len_f64,
        );
        // FL1 and FL2 of X_cur (Eq. 2, 3), which CL1 and the CL2 bound use too.
        let fl = cur.as_ref().map(|f| {
            (
                (m - f.point_world).norm() * 1.0,
                (g - f.point_world).norm() * 1.0,
            )
        });
        let mut sum_m = self.ring_to_map_point;
        if let Some((to_m, _)) = fl {
            sum_m += to_m;
        }
        let cl1 = sum_m / n;
        let cl3 = (m - g).norm();
        if cl1 > params.tau_mf || cl3 > params.tau_mg {
            // Rejected while either stays above its threshold.
            let r = reach
                .above(cl1, params.tau_mf, reach.per_cl1)
                .max(reach.above(cl3, params.tau_mg, reach.per_cl3));
            return (McorVerdict::RejectedCluster, r);
        }
        let mut r = reach
            .below(cl1, params.tau_mf, reach.per_cl1)
            .min(reach.below(cl3, params.tau_mg, reach.per_cl3));
        // CL2 <= (len |G - M| + sum |M - X_i| + |G - X_cur|) / n.
        let bound = self.ring_len_f64 * cl3 + self.ring_to_map_point + fl.map_or(0.0, |f| f.1);
        let certain = bound * (1.0 + BOUND_MARGIN) < params.tau_gf * n * (1.0 - BOUND_MARGIN);
        if certain {
            // The exact CL2 is at most the bound, and stays under tau_GF while the bound would.
            r = r.min(reach.below(bound / n, params.tau_gf, reach.per_cl2));
        } else {
            let (_, cl2, _) = exact_metrics(m, &g, ring, cur.as_ref(), false);
            if cl2 > params.tau_gf {
                return (
                    McorVerdict::RejectedCluster,
                    reach.above(cl2, params.tau_gf, reach.per_cl2),
                );
            }
            r = r.min(reach.below(cl2, params.tau_gf, reach.per_cl2));
        }
        match fl {
            Some((to_m, to_g)) if to_m > params.tau_mf || to_g > params.tau_gf => {
                // Rejected while the cluster passes and either FL metric stays above.
                let fl_reach = reach.above(to_m, params.tau_mf, 1.0).max(reach.above(
                    to_g,
                    params.tau_gf,
                    1.0,
                ));
                (McorVerdict::RejectedFeature, r.min(fl_reach))
            }
            Some((to_m, to_g)) => (
                McorVerdict::Kept,
                r.min(reach.below(to_m, params.tau_mf, 1.0))
                    .min(reach.below(to_g, params.tau_gf, 1.0)),
            ),
            None => (McorVerdict::Kept, f64::INFINITY),
        }
    }
}

/// How far X_cur may move with a metric keeping its side of its threshold, for
/// [`PreparedCluster::verdict_with_reach`] (inert without `ON`). When X_cur moves by d,
/// G = (sum + X_cur) / N moves by d / N; FL1 = |M - X_cur| and FL2 = |G - X_cur| by at most d
/// (the latter by d (1 - 1/N)); CL1 = (sum |M - X_i| + FL1) / n by d / n; CL3 = |M - G| by
/// d / N; CL2 = (sum |G - X_i| + FL2) / n by (len d / N + d) / n, as does its bound. The reach
/// of a margin is the margin, less twice the rounding allowance, over that rate.
struct Reach<const ON: bool> {
    /// n, N, and n N / (len + N): the inverse rates of CL1, CL3 and CL2.
    per_cl1: f64,
    per_cl3: f64,
    per_cl2: f64,
    /// Absolute rounding allowance, metres: 1e-9 of the coordinates' magnitude (M, G, X_cur,
    /// and the ring's, at most |M| + sum |M - X_i|). A metric is a sum of at most a few dozen
    /// norms (G's of every feature, relative to their mean), off its exact value by ~1e-14
    /// of that magnitude: the allowance is 1e5 times that, and far under any useful threshold.
    slack: f64,
    /// Without X_cur: nothing depends on the pose.
    fixed: bool,
}

impl<const ON: bool> Reach<ON> {
    fn new(
        m: &Vector3<f64>,
        g: &Vector3<f64>,
        cur: Option<&RingFeature>,
        ring_to_map_point: f64,
        total_with: f64,
        n_with: f64,
        ring_len: f64,
    ) -> Self {
        if !ON {
            return Reach {
                per_cl1: 0.0,
                per_cl3: 0.0,
                per_cl2: 0.0,
                slack: 0.0,
                fixed: true,
            };
        }
        let scale = 1.0
            + 2.0 * m.amax()
            + ring_to_map_point
            + g.amax()
            + cur.map_or(0.0, |f| f.point_world.amax());
        Reach {
            per_cl1: n_with,
            per_cl3: total_with,
            per_cl2: n_with * total_with / (ring_len + total_with),
            slack: 1e-9 * scale,
            fixed: cur.is_none(),
        }
    }

    /// How far X_cur may move with `value` (above `tau`) staying above; `per` is the inverse
    /// of the metric's rate.
    #[inline]
    fn above(&self, value: f64, tau: f64, per: f64) -> f64 {
        self.within(value - tau, per)
    }

    /// How far X_cur may move with `value` (at most `tau`) staying at most `tau`.
    #[inline]
    fn below(&self, value: f64, tau: f64, per: f64) -> f64 {
        self.within(tau - value, per)
    }

    #[inline]
    fn within(&self, margin: f64, per: f64) -> f64 {
        if !ON {
            return 0.0;
        }
        if self.fixed {
            return f64::INFINITY;
        }
        let r = (margin - 2.0 * self.slack) * per;
        // NaN (a non-finite metric) and negative margins: no reach.
        if r > 0.0 {
            r
        } else {
            0.0
        }
    }
}

/// CL1, CL2, CL3 by the operations of `McorCluster::metrics`, in its order.
fn exact_metrics(
    m: &Vector3<f64>,
    g: &Vector3<f64>,
    ring: &[RingFeature],
    current: Option<&RingFeature>,
    depth_normalised: bool,
) -> (f64, f64, f64) {
    let (mut sum_m, mut sum_g, mut sum_depth) = (0.0, 0.0, 0.0);
    for f in ring.iter().chain(current) {
        let scale = if depth_normalised { 1.0 / f.depth } else { 1.0 };
        sum_m += (m - f.point_world).norm() * scale;
        sum_g += (g - f.point_world).norm() * scale;
        sum_depth += f.depth;
    }
    let n = (ring.len() + usize::from(current.is_some())) as f64;
    let mut cl3 = (m - g).norm();
    if depth_normalised {
        cl3 /= sum_depth / n;
    }
    (sum_m / n, sum_g / n, cl3)
}

/// MC-OR's verdicts for the matches of one frame, kept across the rounds of its pose
/// optimizations and its gates (motion model, local map, the statistics at the final pose):
/// a verdict is computed again only when the pose moved the match's current feature by as
/// much as the verdict's reach
/// ([`PreparedCluster::verdict_with_reach`]),
/// so every gate has the verdicts a full gate would give. Poses move features by millimetres
/// between rounds and the thresholds are decimetres: most verdicts of a frame are computed once.
#[derive(Clone, Debug, Default)]
pub struct GateMemo {
    /// The frame, the clusters' generation and reading the verdicts belong to.
    key: Option<(u64, u64, Option<ClusterViews>)>,
    /// The thresholds they were judged with.
    params: Option<McorParams>,
    /// The camera-to-world poses verdicts were computed at: rotation, translation.
    poses: Vec<(Matrix3<f64>, Vector3<f64>)>,
    /// For the current gate (the last pose), per earlier pose: the bounds of [`moves`](Self::moves).
    moved: Vec<(f64, f64)>,
    /// Per keypoint: the map point it was judged with, the verdict, its reach (metres) and the
    /// index of its pose in `poses`.
    kept: Vec<Option<(MapPointId, McorVerdict, f64, usize)>>,
    /// Checking: every kept verdict handed out is compared with one computed (the cluster
    /// cache's `set_check`).
    check: bool,
    /// Kept verdicts checked so far.
    checked: u64,
}

impl GateMemo {
    /// Whether the memo holds the verdicts of `key` (frame, clusters' generation, reading)
    /// under `params`.
    pub fn is_for(&self, key: (u64, u64, Option<ClusterViews>), params: &McorParams) -> bool {
        self.key == Some(key) && self.params.as_ref() == Some(params)
    }

    /// Forgets every verdict (keeping the buffers) and starts the memo of `key` under `params`
    /// for a frame of `n_keypoints` keypoints; `check` compares every kept verdict handed out
    /// with one computed.
    pub fn start(
        &mut self,
        key: (u64, u64, Option<ClusterViews>),
        params: &McorParams,
        n_keypoints: usize,
        check: bool,
    ) {
        self.key = Some(key);
        self.params = Some(params.clone());
        self.poses.clear();
        self.moved.clear();
        self.kept.clear();
        self.kept.resize(n_keypoints, None);
        self.check = check;
    }

    /// Kept verdicts checked against computed ones so far.
    pub fn checked(&self) -> u64 {
        self.checked
    }

    /// Starts a gate at pose `twc`: per earlier pose, the bounds (a, b) of how far the change
    /// moves a camera-frame point p in the world, |dR p + dt| <= a |p| + b (a: the Frobenius
    /// norm of the rotation's change, which bounds its operator norm); the pose is recorded
    /// for the verdicts computed at it.
    pub fn moves(&mut self, twc: &Isometry3<f64>) {
        let r = *twc.rotation.to_rotation_matrix().matrix();
        let t = twc.translation.vector;
        self.moved.clear();
        self.moved.extend(
            self.poses
                .iter()
                .map(|(r0, t0)| ((r - r0).norm(), (t - t0).norm())),
        );
        self.poses.push((r, t));
    }

    /// The verdict of `match_` (keypoint index, map point) at the pose last given to
    /// [`moves`](Self::moves); `p_norm` is the norm of its current
    /// feature (camera frame, 0 without one). The kept verdict while the pose moved the feature
    /// by less than its reach, else `compute()` (verdict and reach), kept.
    #[inline]
    pub fn verdict(
        &mut self,
        match_: (usize, MapPointId),
        p_norm: f64,
        compute: impl FnOnce() -> (McorVerdict, f64),
    ) -> McorVerdict {
        let (i, id) = match_;
        if let Some(Some((kept_id, verdict, reach, at))) = self.kept.get(i) {
            // `moved` has an entry for every pose before the gate's own.
            if *kept_id == id {
                if let Some((a, b)) = self.moved.get(*at) {
                    if a * p_norm + b < *reach {
                        let kept = *verdict;
                        if self.check {
                            let (computed, _) = compute();
                            assert_eq!(
                                kept, computed,
                                "the kept verdict of {id} is not the gate's"
                            );
                            self.checked += 1;
                        }
                        return kept;
                    }
                }
            }
        }
        let (verdict, reach) = compute();
        // Kept at the gate's pose (none before the first `moves`: then not kept).
        if let (Some(slot), Some(at)) = (self.kept.get_mut(i), self.poses.len().checked_sub(1)) {
            *slot = Some((id, verdict, reach, at));
        }
        verdict
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::FRAME_VIEW_SOURCE_BIT;
    use crate::techniques::mcor::cluster::{mcor_gate, Exceeded, McorCluster, McorMatch};
    use crate::techniques::test_support::{gaussian, rng};
    use nalgebra::{Translation3, UnitQuaternion};
    use rand::Rng;

    /// A random cluster of `n` features scattered by `spread` metres round `centre`, with
    /// `folded` features folded in after the first `split` (as frame views are), built both
    /// ways.
    fn both(
        g: &mut rand_chacha::ChaCha8Rng,
        centre: Vector3<f64>,
        spread: f64,
        n: usize,
        split: usize,
        folded: u64,
    ) -> (McorCluster, PreparedCluster) {
        let m = centre + Vector3::new(0.01, -0.02, 0.015);
        let mut cluster = McorCluster::new();
        let mut arena = PreparedCluster::new(m);
        let folded_sum =
            centre * folded as f64 + Vector3::new(gaussian(g), gaussian(g), gaussian(g)) * spread;
        for k in 0..n {
            if k == split {
                cluster.add_folded(folded_sum, folded);
                arena.add_folded(folded_sum, folded);
            }
            let twc = Isometry3::from_parts(
                Translation3::new(g.random_range(-1.0..1.0), 0.0, -2.0),
                UnitQuaternion::from_euler_angles(0.0, g.random_range(-0.3..0.3), 0.0),
            );
            let world = centre + Vector3::new(gaussian(g), gaussian(g), gaussian(g)) * spread;
            let pc = (twc.inverse() * Point3::from(world)).coords;
            let f = ClusterFeature::new(k as u64, pc, &twc).expect("in front");
            cluster.push_distinct(f);
            arena.push(&f);
        }
        if split >= n {
            cluster.add_folded(folded_sum, folded);
            arena.add_folded(folded_sum, folded);
        }
        arena.seal();
        (cluster, arena)
    }

    /// A cluster that takes 100 frame views one at a time (its views folding past
    /// [`MCOR_CLUSTER_CAPACITY`]) is, after every view, the cluster built afresh from the same
    /// features: the same features, sums and ring bit for bit, and the same verdicts.
    #[test]
    fn views_pushed_one_by_one_give_the_cluster_built_afresh() {
        let mut g = rng(43);
        let twc = Isometry3::from_parts(
            Translation3::new(0.1, -0.05, 0.2),
            UnitQuaternion::from_euler_angles(0.01, 0.03, -0.02),
        );
        let m = Vector3::new(0.2, -0.1, 2.5);
        let feature = |g: &mut rand_chacha::ChaCha8Rng, source: u64| {
            let p = Vector3::new(
                gaussian(g) * 0.05,
                gaussian(g) * 0.05,
                2.0 + gaussian(g) * 0.05,
            );
            ClusterFeature::new(source, p, &twc).expect("in front")
        };
        for n_keyframe in [0usize, 3, 40] {
            let keyframes: Vec<ClusterFeature> =
                (0..n_keyframe as u64).map(|k| feature(&mut g, k)).collect();
            let mut incremental = PreparedCluster::new(m);
            for f in &keyframes {
                incremental.push(f);
            }
            incremental.add_folded(Vector3::zeros(), 0);
            incremental.seal();
            // What `FrameViews` keeps: the recent views and the sum of those folded out.
            let mut recent: std::collections::VecDeque<ClusterFeature> = Default::default();
            let (mut folded_sum, mut folded_count) = (Vector3::zeros(), 0u64);
            for v in 0..100u64 {
                let view = feature(&mut g, FRAME_VIEW_SOURCE_BIT | v);
                if recent.len() == MCOR_CLUSTER_CAPACITY {
                    let old = recent.pop_front().expect("full");
                    folded_sum += old.point_world();
                    folded_count += 1;
                }
                recent.push_back(view);
                incremental.push_view(&view, (folded_sum, folded_count), recent.len());
                let mut afresh = PreparedCluster::new(m);
                for f in &keyframes {
                    afresh.push(f);
                }
                afresh.add_folded(folded_sum, folded_count);
                for f in &recent {
                    afresh.push(f);
                }
                afresh.seal();
                assert_eq!(
                    incremental, afresh,
                    "{n_keyframe} keyframe features, view {v}"
                );
                let params = McorParams {
                    tau_gf: afresh.ring_to_map_point / afresh.ring_len_f64.max(1.0),
                    ..McorParams::default()
                };
                for k in 0..4 {
                    let p = Vector3::new(0.03 * k as f64, -0.02, 2.0 + 0.1 * k as f64);
                    let current = gate_point(Some(p));
                    assert_eq!(
                        incremental.verdict_with_reach(&params, &twc, current.as_ref()),
                        afresh.verdict_with_reach(&params, &twc, current.as_ref()),
                    );
                }
            }
        }
    }

    /// A random gated match, trial `trial`: a cluster of up to `max_n` features (built both
    /// ways, `folded` of them folded), the frame pose, and the current feature (camera frame;
    /// none every fifth trial) near the cluster's centre; with the centre.
    fn random_match(
        g: &mut rand_chacha::ChaCha8Rng,
        trial: usize,
        max_n: usize,
        folded: u64,
    ) -> (
        McorCluster,
        PreparedCluster,
        Isometry3<f64>,
        Option<Vector3<f64>>,
        Vector3<f64>,
    ) {
        let centre = Vector3::new(
            g.random_range(-1.0..1.0),
            g.random_range(-1.0..1.0),
            g.random_range(0.5..3.0),
        );
        let spread = [0.002, 0.02, 0.2, 0.6][trial % 4];
        let n = g.random_range(0..max_n);
        let split = g.random_range(0..=n);
        let (cluster, prepared) = both(g, centre, spread, n, split, folded);
        let twc = Isometry3::from_parts(
            Translation3::new(gaussian(g) * 0.1, 0.1, -2.0),
            UnitQuaternion::from_euler_angles(0.02, gaussian(g) * 0.1, 0.0),
        );
        let current = (!trial.is_multiple_of(5)).then(|| {
            let w = centre + Vector3::new(gaussian(g), gaussian(g), 0.0) * spread;
            (twc.inverse() * Point3::from(w)).coords
        });
        (cluster, prepared, twc, current, centre)
    }

    #[test]
    fn verdicts_are_those_of_the_gate_over_whole_clusters() {
        let mut g = rng(5);
        let mut near_threshold = 0;
        let mut rejected = [0usize; 3];
        for trial in 0..3000 {
            let folded = [0, 0, 3, 40][trial % 4 / 2 + trial % 2];
            let (cluster, prepared, twc, current, centre) = random_match(&mut g, trial, 45, folded);
            let m = centre + Vector3::new(0.01, -0.02, 0.015);
            let mut params = McorParams {
                depth_normalised: trial % 7 == 0,
                ..McorParams::default()
            };
            // Every third trial: thresholds at the cluster's own metrics, nudged by an ulp or
            // so, where the bound is useless and rounding decides.
            let cur = current.and_then(|p| ClusterFeature::new(u64::MAX, p, &twc));
            if let (0, Some(x)) = (
                trial % 3,
                cluster.metrics(&m, cur.as_ref(), params.depth_normalised),
            ) {
                let nudge = |v: f64| match trial % 9 {
                    0 => v,
                    3 => v * (1.0 + 1e-16),
                    _ => v * (1.0 - 1e-16),
                };
                params.tau_mf = nudge(x.cluster.mean_to_map_point).max(1e-9) * 1.5;
                params.tau_gf = nudge(x.cluster.mean_to_centroid);
                params.tau_mg = nudge(x.cluster.map_point_to_centroid).max(1e-9) * 1.5;
                near_threshold += 1;
            }
            let expected = mcor_gate(
                &params,
                &twc,
                &[McorMatch {
                    cluster: &cluster,
                    map_point: m,
                    point_camera: current,
                }],
            )
            .verdicts[0];
            let got = prepared.verdict(&params, &twc, gate_point(current).as_ref());
            assert_eq!(
                got,
                expected,
                "trial {trial}: n {}, split {}, folded {folded}",
                prepared.features.len(),
                prepared.n_keyframe
            );
            // The full metrics are the slow path's, and a rejection names a threshold its
            // metrics exceed (a feature rejection never tau_MG).
            let full = prepared.metrics(&params, &twc, gate_point(current).as_ref());
            if let Some(slow) = cluster.metrics(&m, cur.as_ref(), params.depth_normalised) {
                assert_eq!(full, slow, "trial {trial}");
            }
            let exceeded = Exceeded::of(&params, &full, got);
            assert_eq!(exceeded.any(), got != McorVerdict::Kept, "trial {trial}");
            assert!(!(got == McorVerdict::RejectedFeature && exceeded.tau_mg));
            rejected[match got {
                McorVerdict::Kept => 0,
                McorVerdict::RejectedCluster => 1,
                McorVerdict::RejectedFeature => 2,
            }] += 1;
        }
        assert!(near_threshold > 500);
        assert!(rejected.iter().all(|&r| r > 100), "{rejected:?}");
    }

    /// A gated match: its cluster, current feature, frame pose and thresholds.
    type Trial = (
        PreparedCluster,
        Option<Vector3<f64>>,
        Isometry3<f64>,
        McorParams,
    );

    /// [`random_match`]es with thresholds set near the cluster's own metrics every other trial: (cluster, current
    /// feature, pose, thresholds).
    fn near_threshold_trials(seed: u64, trials: usize) -> Vec<Trial> {
        let mut g = rng(seed);
        (0..trials)
            .map(|trial| {
                let (cluster, prepared, twc, current, centre) =
                    random_match(&mut g, trial, 40, [0, 7][trial % 2]);
                let mut params = McorParams::default();
                let m = centre + Vector3::new(0.01, -0.02, 0.015);
                let cur = current.and_then(|p| ClusterFeature::new(u64::MAX, p, &twc));
                if let (true, Some(x)) = (trial % 2 == 0, cluster.metrics(&m, cur.as_ref(), false))
                {
                    // Each threshold within a few millimetres of its metric, either side.
                    let near = |v: f64, g: &mut rand_chacha::ChaCha8Rng| {
                        (v + g.random_range(-0.004..0.004)).max(1e-6)
                    };
                    params.tau_mf = near(x.cluster.mean_to_map_point, &mut g);
                    params.tau_gf = near(x.cluster.mean_to_centroid, &mut g);
                    params.tau_mg = near(x.cluster.map_point_to_centroid, &mut g);
                }
                (prepared, gate_point(current), twc, params)
            })
            .collect()
    }

    /// A pose `twc` moved so that camera-frame point `p` moves by `d` metres in the world:
    /// a rotation about the camera centre and a translation, in a random mix.
    fn moved_by(
        g: &mut rand_chacha::ChaCha8Rng,
        twc: &Isometry3<f64>,
        p: &Vector3<f64>,
        d: f64,
    ) -> Isometry3<f64> {
        let dir = Vector3::new(gaussian(g), gaussian(g), gaussian(g)).normalize();
        let share: f64 = g.random_range(0.0..1.0);
        // Rotating by a small angle a moves p by at most a |p|.
        let angle = share * d / p.norm().max(1e-9);
        let rotated = Isometry3::from_parts(
            twc.translation,
            UnitQuaternion::from_scaled_axis(dir * angle) * twc.rotation,
        );
        let now = rotated * Point3::from(*p);
        let then = twc * Point3::from(*p);
        // The translation takes up what the rotation left of d, along a random direction.
        let left = (d - (now - then).norm()).max(0.0);
        let dir_t = Vector3::new(gaussian(g), gaussian(g), gaussian(g)).normalize();
        Isometry3::from_parts(
            Translation3::from(rotated.translation.vector + dir_t * left),
            rotated.rotation,
        )
    }

    #[test]
    fn a_verdict_holds_while_the_pose_moves_its_feature_less_than_its_reach() {
        let mut g = rng(11);
        let (mut bounded, mut flipped_beyond) = (0, 0);
        for (k, (cluster, current, twc, params)) in
            near_threshold_trials(21, 4000).into_iter().enumerate()
        {
            let (verdict, reach) = cluster.verdict_with_reach(&params, &twc, current.as_ref());
            assert_eq!(verdict, cluster.verdict(&params, &twc, current.as_ref()));
            let Some(p) = current else {
                assert_eq!(reach, f64::INFINITY, "trial {k}: no feature, nothing moves");
                continue;
            };
            assert!(reach >= 0.0, "trial {k}: reach {reach}");
            if !reach.is_finite() || reach > 1.0 {
                continue;
            }
            bounded += 1;
            // Anywhere within the reach: the same verdict.
            for _ in 0..4 {
                let d = reach * g.random_range(0.0..1.0);
                let moved = moved_by(&mut g, &twc, &p, d);
                assert_eq!(
                    cluster.verdict(&params, &moved, Some(&p)),
                    verdict,
                    "trial {k}: moved {d} m within the reach {reach} m"
                );
            }
            // The reach is not a vacuous bound: a few times beyond it the verdict often turns.
            let moved = moved_by(&mut g, &twc, &p, 3.0 * reach + 1e-4);
            if cluster.verdict(&params, &moved, Some(&p)) != verdict {
                flipped_beyond += 1;
            }
        }
        assert!(bounded > 1000, "{bounded} trials with a finite reach");
        assert!(
            flipped_beyond > 100,
            "{flipped_beyond} verdicts turned beyond the reach"
        );
    }

    #[test]
    fn the_gate_memo_gives_every_pose_the_verdicts_of_a_full_gate() {
        use crate::ids::MapPointId;
        let trials = near_threshold_trials(33, 300);
        let mut g = rng(3);
        let params = McorParams::default();
        let mut memo = GateMemo::default();
        memo.start((7, 0, None), &params, trials.len(), false);
        let mut twc = trials[0].2;
        let mut computed = 0;
        let poses = 12;
        for round in 0..poses {
            // Millimetre steps between rounds, and a decimetre jump now and then.
            let step = if round % 5 == 4 { 0.1 } else { 0.002 };
            twc = moved_by(&mut g, &twc, &Vector3::new(0.3, -0.2, 2.0), step);
            memo.moves(&twc);
            for (k, (cluster, current, _, _)) in trials.iter().enumerate() {
                let full = cluster.verdict(&params, &twc, current.as_ref());
                let p_norm = current.map_or(0.0, |p| p.norm());
                let kept = memo.verdict((k, MapPointId(k as u32)), p_norm, || {
                    computed += 1;
                    cluster.verdict_with_reach(&params, &twc, current.as_ref())
                });
                assert_eq!(kept, full, "round {round}, match {k}");
            }
        }
        // Every match judged at the first pose and after each jump at most; rarely between.
        assert!(computed >= trials.len());
        assert!(
            computed < trials.len() * poses / 3,
            "{computed} verdicts computed for {} matches over {poses} poses",
            trials.len()
        );
    }
}
