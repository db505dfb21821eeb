//! MC-OR's gate (Algorithm 1, [`mcor_gate`](super::mcor::mcor_gate)) over clusters prepared
//! once per frame: the same verdicts, bit for bit, at a fraction of the cost.
//!
//! Within one frame's tracking neither the map points nor their clusters move; only the
//! frame's pose does, between pose-optimization rounds. So everything of a cluster that does
//! not involve the current feature X_cur is summed once, in the order
//! [`McorCluster::metrics`](super::mcor::McorCluster::metrics) sums it (floating-point sums are
//! not associative, so the order is part of the result): G's numerator over the folded sum and
//! the ring, and the sum of |M - X_i| over the ring. A round then adds X_cur to those sums
//! and needs the ring only for CL2 = mean |G - X_i|, which depends on G and so on the pose.
//! That one is bounded first by the triangle inequality, |G - X_i| <= |G - M| + |M - X_i|:
//! when even the bound is under tau_GF with a margin far beyond rounding, the exact mean is
//! too and the ring is not visited. Only clusters near the threshold, and the depth-normalised
//! variant, are summed exactly, by the operations of `metrics`.

use nalgebra::{Isometry3, Point3, Vector3};

use super::mcor::{ClusterFeature, McorVerdict, MCOR_CLUSTER_CAPACITY};
use crate::module::noise::McorParams;

/// Relative margin of the CL2 bound: a bound within this fraction of tau_GF is not trusted and
/// the exact mean is computed (rounding of a sum of at most a few dozen norms is ~1e-14).
const BOUND_MARGIN: f64 = 1e-6;

/// A keypoint's back-projection as [`PreparedClusters::verdict`] takes it: kept only when
/// it makes a 3-D feature (finite, positive depth: the test of `ClusterFeature::new`), so
/// that a frame tests it once and not once per round.
pub fn gate_point(point_camera: Option<Vector3<f64>>) -> Option<Vector3<f64>> {
    point_camera.filter(|p| p.iter().all(|x| x.is_finite()) && p.z > 0.0)
}

/// One ring feature as the gate reads it: its world position and measured depth.
#[derive(Clone, Copy, Debug, PartialEq)]
struct RingFeature {
    point_world: Vector3<f64>,
    depth: f64,
}

/// A cluster reduced for its map point M (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Prepared {
    /// M, world frame.
    map_point: Vector3<f64>,
    /// Folded sum, then each ring feature in ring order: G's numerator without X_cur.
    ring_sum: Vector3<f64>,
    /// N of Eq. 1 without X_cur (folded and ring features).
    total: u64,
    /// Sum of |M - X_i| over the ring, in ring order (metres).
    ring_to_map_point: f64,
    /// The ring in the arena: `start..start + len`.
    start: usize,
    len: usize,
}

/// The prepared clusters of one frame's matches (an arena: buffers are reused frame after
/// frame, nothing is allocated once they have grown).
#[derive(Clone, Debug, Default)]
pub struct PreparedClusters {
    features: Vec<RingFeature>,
    clusters: Vec<Prepared>,
    /// The cluster being built: where its ring starts, its folded sum and count.
    open: Option<(usize, Vector3<f64>, u64)>,
}

impl PreparedClusters {
    /// Empty.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets every cluster (keeps the buffers).
    pub fn clear(&mut self) {
        self.features.clear();
        self.clusters.clear();
        self.open = None;
    }

    /// Number of prepared clusters.
    pub fn len(&self) -> usize {
        self.clusters.len()
    }

    /// Whether none is prepared.
    pub fn is_empty(&self) -> bool {
        self.clusters.is_empty()
    }

    /// Starts a cluster; features go in with [`push`](Self::push) and
    /// [`add_folded`](Self::add_folded) exactly as into a [`McorCluster`](super::McorCluster)
    /// built with `push_distinct` / `add_folded`, then [`finish`](Self::finish) seals it.
    pub fn begin(&mut self) {
        self.open = Some((self.features.len(), Vector3::zeros(), 0));
    }

    /// Adds a feature to the open cluster (its source distinct from those in the ring): when
    /// the ring is full its oldest feature is folded into the running sum, as
    /// `McorCluster::push_distinct` does.
    pub fn push(&mut self, feature: &ClusterFeature) {
        let (start, sum, count) = self.open.as_mut().expect("begin() first");
        if self.features.len() - *start == MCOR_CLUSTER_CAPACITY {
            *sum += self.features[*start].point_world;
            *count += 1;
            *start += 1;
        }
        self.features.push(RingFeature {
            point_world: feature.point_world(),
            depth: feature.depth(),
        });
    }

    /// Adds features folded elsewhere (their world positions sum to `sum`), as
    /// `McorCluster::add_folded` does.
    pub fn add_folded(&mut self, sum: Vector3<f64>, count: u64) {
        let (_, s, c) = self.open.as_mut().expect("begin() first");
        *s += sum;
        *c += count;
    }

    /// Seals the open cluster for map point `map_point` (world) and returns its index.
    pub fn finish(&mut self, map_point: Vector3<f64>) -> usize {
        let (start, folded_sum, folded_count) = self.open.take().expect("begin() first");
        let len = self.features.len() - start;
        let mut ring_sum = folded_sum;
        let mut ring_to_map_point = 0.0;
        for f in &self.features[start..] {
            ring_sum += f.point_world;
            ring_to_map_point += (map_point - f.point_world).norm() * 1.0;
        }
        self.clusters.push(Prepared {
            map_point,
            ring_sum,
            total: folded_count + len as u64,
            ring_to_map_point,
            start,
            len,
        });
        self.clusters.len() - 1
    }

    /// Algorithm 1's verdict for the match of prepared cluster `k` whose keypoint
    /// back-projects to `point_camera` (camera frame; `None` without depth; passed through
    /// [`gate_point`] once per match), with the frame at `twc` (camera to world): the verdict
    /// [`mcor_gate`](super::mcor::mcor_gate) gives for the same cluster, bit for bit.
    pub fn verdict(
        &self,
        k: usize,
        params: &McorParams,
        twc: &Isometry3<f64>,
        point_camera: Option<&Vector3<f64>>,
    ) -> McorVerdict {
        let c = &self.clusters[k];
        // X_cur as `ClusterFeature::new` places it.
        let cur = point_camera.map(|p| RingFeature {
            point_world: (twc * Point3::from(*p)).coords,
            depth: p.z,
        });
        let n_features = c.len + usize::from(cur.is_some());
        if n_features == 0 {
            return McorVerdict::Kept;
        }
        // G (Eq. 1): the sums of `McorCluster::centroid_with`.
        let mut sum = c.ring_sum;
        let mut total = c.total;
        if let Some(f) = &cur {
            sum += f.point_world;
            total += 1;
        }
        let g = sum / total as f64;
        let m = &c.map_point;
        let n = n_features as f64;
        let ring = &self.features[c.start..c.start + c.len];
        let (cl1, cl2, cl3) = if params.depth_normalised {
            exact_metrics(m, &g, ring, cur.as_ref(), true)
        } else {
            let cur_to_m = cur.as_ref().map(|f| (m - f.point_world).norm() * 1.0);
            let mut sum_m = c.ring_to_map_point;
            if let Some(d) = cur_to_m {
                sum_m += d;
            }
            let cl1 = sum_m / n;
            let cl3 = (m - g).norm();
            if cl1 > params.tau_mf || cl3 > params.tau_mg {
                return McorVerdict::RejectedCluster;
            }
            // CL2 <= (len |G - M| + sum |M - X_i| + |G - X_cur|) / n.
            let cur_to_g = cur.as_ref().map_or(0.0, |f| (g - f.point_world).norm());
            let bound = c.len as f64 * cl3 + c.ring_to_map_point + cur_to_g;
            if bound * (1.0 + BOUND_MARGIN) < params.tau_gf * n * (1.0 - BOUND_MARGIN) {
                (cl1, 0.0, cl3)
            } else {
                exact_metrics(m, &g, ring, cur.as_ref(), false)
            }
        };
        if cl1 > params.tau_mf || cl2 > params.tau_gf || cl3 > params.tau_mg {
            return McorVerdict::RejectedCluster;
        }
        match &cur {
            Some(f) => {
                let scale = if params.depth_normalised {
                    1.0 / f.depth
                } else {
                    1.0
                };
                let to_m = (m - f.point_world).norm() * scale;
                let to_g = (g - f.point_world).norm() * scale;
                if to_m > params.tau_mf || to_g > params.tau_gf {
                    McorVerdict::RejectedFeature
                } else {
                    McorVerdict::Kept
                }
            }
            None => McorVerdict::Kept,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::techniques::mcor::{mcor_gate, McorCluster, McorMatch};
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
        arena: &mut PreparedClusters,
    ) -> (McorCluster, usize) {
        let mut cluster = McorCluster::new();
        arena.begin();
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
        let k = arena.finish(centre + Vector3::new(0.01, -0.02, 0.015));
        (cluster, k)
    }

    #[test]
    fn verdicts_are_those_of_the_gate_over_whole_clusters() {
        let mut g = rng(5);
        let mut arena = PreparedClusters::new();
        let mut near_threshold = 0;
        let mut rejected = [0usize; 3];
        for trial in 0..3000 {
            arena.clear();
            let centre = Vector3::new(
                g.random_range(-1.0..1.0),
                g.random_range(-1.0..1.0),
                g.random_range(0.5..3.0),
            );
            let spread = [0.002, 0.02, 0.2, 0.6][trial % 4];
            let n = g.random_range(0..45);
            let split = g.random_range(0..=n);
            let folded = [0, 0, 3, 40][trial % 4 / 2 + trial % 2];
            let (cluster, k) = both(&mut g, centre, spread, n, split, folded, &mut arena);
            let twc = Isometry3::from_parts(
                Translation3::new(gaussian(&mut g) * 0.1, 0.1, -2.0),
                UnitQuaternion::from_euler_angles(0.02, gaussian(&mut g) * 0.1, 0.0),
            );
            let current = (trial % 5 != 0).then(|| {
                let w = centre + Vector3::new(gaussian(&mut g), gaussian(&mut g), 0.0) * spread;
                (twc.inverse() * Point3::from(w)).coords
            });
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
            let got = arena.verdict(k, &params, &twc, gate_point(current).as_ref());
            assert_eq!(
                got, expected,
                "trial {trial}: n {n}, split {split}, folded {folded}"
            );
            rejected[match got {
                McorVerdict::Kept => 0,
                McorVerdict::RejectedCluster => 1,
                McorVerdict::RejectedFeature => 2,
            }] += 1;
        }
        assert!(near_threshold > 500);
        assert!(rejected.iter().all(|&r| r > 100), "{rejected:?}");
    }
}
