//! Pose-graph optimization over SE(3) (ORB-SLAM2's `OptimizeEssentialGraph` with the scale of
//! its Sim3 vertices fixed to 1, as for stereo and RGB-D): keyframe poses are the vertices, each
//! edge says what the relative pose of two keyframes was before a loop correction, and the
//! optimizer spreads the loop's correction along the graph.
//!
//! Edge `(i, j)` measures `M = T_i T_j^-1` (both `Tcw`). Its residual is the 6-vector
//! `[log_so3(R_E); t_E]` of `E = M^-1 T_i T_j^-1`, zero when the two poses keep the measured
//! relative pose; every edge has identity information (as ORB-SLAM2's essential graph). The
//! Jacobians are exact (checked against finite differences); the free vertices are numbered in
//! reverse Cuthill-McKee order ([`super::ordering`]), the normal equations stored by their
//! envelope ([`super::envelope`]) and solved by Levenberg-Marquardt with the damping schedule of
//! [`super::lm`].

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector3};

use super::envelope::EnvelopeMatrix;
use super::lm::{levenberg_marquardt, LmProblem};
use super::ordering::{inverse_permutation, Adjacency};
use crate::geometry::{exp_se3, log_so3, skew, so3_left_jacobian_inverse, Vector6};

/// A relative-pose constraint between vertices `i` and `j`.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseGraphEdge {
    /// First vertex (index into [`PoseGraph::poses`]).
    pub i: usize,
    /// Second vertex.
    pub j: usize,
    /// Measured relative pose `T_i T_j^-1` (`Tcw` poses).
    pub t_ij: Isometry3<f64>,
}

/// A pose graph; the free poses are optimized in place.
#[derive(Clone, Debug, Default)]
pub struct PoseGraph {
    /// Vertex poses `Tcw`.
    pub poses: Vec<Isometry3<f64>>,
    /// Held constant (at least one vertex must be, or the graph floats).
    pub fixed: Vec<bool>,
    /// Constraints.
    pub edges: Vec<PoseGraphEdge>,
}

/// What [`optimize_pose_graph`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseGraphReport {
    /// Sum of squared residuals before.
    pub initial_cost: f64,
    /// Sum of squared residuals after.
    pub final_cost: f64,
    /// LM iterations run.
    pub iterations: usize,
}

/// Residual of an edge measuring `t_ij` at poses `ti`, `tj`.
pub(crate) fn edge_residual(
    t_ij: &Isometry3<f64>,
    ti: &Isometry3<f64>,
    tj: &Isometry3<f64>,
) -> Vector6 {
    let e = t_ij.inverse() * ti * tj.inverse();
    let w = log_so3(&e.rotation);
    let t = e.translation.vector;
    Vector6::new(w.x, w.y, w.z, t.x, t.y, t.z)
}

/// Jacobians of [`edge_residual`] with respect to left perturbations `T <- exp(xi) T` of `ti`
/// and of `tj`.
pub(crate) fn edge_jacobians(
    t_ij: &Isometry3<f64>,
    ti: &Isometry3<f64>,
    tj: &Isometry3<f64>,
) -> (Matrix6<f64>, Matrix6<f64>) {
    let m_inv = t_ij.inverse();
    let p = ti * tj.inverse();
    let e = m_inv * p;
    let a: Matrix3<f64> = m_inv.rotation.to_rotation_matrix().into_inner();
    let r_e: Matrix3<f64> = e.rotation.to_rotation_matrix().into_inner();
    let phi: Vector3<f64> = log_so3(&e.rotation);
    let mut ji = Matrix6::zeros();
    ji.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(so3_left_jacobian_inverse(&phi) * a));
    ji.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&(-a * skew(&p.translation.vector)));
    ji.fixed_view_mut::<3, 3>(3, 3).copy_from(&a);
    let mut jj = Matrix6::zeros();
    jj.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(-so3_left_jacobian_inverse(&(-phi))));
    jj.fixed_view_mut::<3, 3>(3, 3).copy_from(&(-r_e));
    (ji, jj)
}

/// Optimizes the free poses of `graph` in place with up to `iterations` LM iterations
/// (ORB-SLAM2: 20).
///
/// # Panics
/// When an edge refers to a vertex outside the graph or `fixed` has the wrong length (a
/// caller bug).
pub fn optimize_pose_graph(graph: &mut PoseGraph, iterations: usize) -> PoseGraphReport {
    assert_eq!(
        graph.fixed.len(),
        graph.poses.len(),
        "one fixed flag per pose"
    );
    for (k, e) in graph.edges.iter().enumerate() {
        assert!(
            e.i < graph.poses.len() && e.j < graph.poses.len(),
            "pose-graph edge {k} refers to a vertex outside the graph"
        );
    }
    let mut solver = PoseGraphSolver::new(graph);
    let initial_cost = solver.cost;
    let summary = levenberg_marquardt(&mut solver, iterations);
    let final_cost = solver.cost;
    let poses = solver.poses;
    for (k, pose) in poses.into_iter().enumerate() {
        if !graph.fixed[k] {
            graph.poses[k] = pose;
        }
    }
    PoseGraphReport {
        initial_cost,
        final_cost,
        iterations: summary.iterations,
    }
}

/// The LM problem: current and trial poses, and the normal equations in envelope form.
struct PoseGraphSolver<'a> {
    edges: &'a [PoseGraphEdge],
    /// Vertex -> index of its 6-DoF block, `None` when fixed.
    var: Vec<Option<usize>>,
    /// Envelope of the block rows (first block column per block row).
    first_block: Vec<usize>,
    poses: Vec<Isometry3<f64>>,
    trial: Vec<Isometry3<f64>>,
    cost: f64,
    trial_cost: f64,
    h: Option<EnvelopeMatrix>,
    g: Vec<f64>,
    step: Vec<f64>,
}

impl<'a> PoseGraphSolver<'a> {
    fn new(graph: &'a PoseGraph) -> Self {
        // Free vertices in id order, then renumbered by reverse Cuthill-McKee over the edges
        // that couple two of them.
        let free: Vec<usize> = (0..graph.poses.len())
            .filter(|&k| !graph.fixed[k])
            .collect();
        let mut free_index = vec![None; graph.poses.len()];
        for (f, &k) in free.iter().enumerate() {
            free_index[k] = Some(f);
        }
        let coupling = Adjacency::from_edges(
            free.len(),
            graph
                .edges
                .iter()
                .filter_map(|e| Some((free_index[e.i]?, free_index[e.j]?))),
        );
        let position = inverse_permutation(&coupling.reverse_cuthill_mckee());
        let var: Vec<Option<usize>> = free_index.iter().map(|f| f.map(|f| position[f])).collect();
        let first_block = coupling.envelope_first(&position);
        let n = first_block.len();
        let poses = graph.poses.clone();
        let cost = cost_at(&graph.edges, &poses);
        PoseGraphSolver {
            edges: &graph.edges,
            var,
            first_block,
            trial: poses.clone(),
            poses,
            cost,
            trial_cost: f64::INFINITY,
            h: None,
            g: vec![0.0; 6 * n],
            step: vec![0.0; 6 * n],
        }
    }

    fn n_var(&self) -> usize {
        self.first_block.len()
    }

    fn envelope(&self) -> EnvelopeMatrix {
        let first = (0..6 * self.n_var())
            .map(|row| 6 * self.first_block[row / 6])
            .collect();
        EnvelopeMatrix::zeros(first)
    }
}

fn cost_at(edges: &[PoseGraphEdge], poses: &[Isometry3<f64>]) -> f64 {
    edges
        .iter()
        .map(|e| edge_residual(&e.t_ij, &poses[e.i], &poses[e.j]).norm_squared())
        .sum()
}

impl LmProblem for PoseGraphSolver<'_> {
    fn cost(&self) -> f64 {
        self.cost
    }

    fn linearize(&mut self) -> Option<f64> {
        if self.n_var() == 0 || self.edges.is_empty() {
            return None;
        }
        let mut h = self.envelope();
        self.g.iter_mut().for_each(|g| *g = 0.0);
        for e in self.edges {
            let (ti, tj) = (&self.poses[e.i], &self.poses[e.j]);
            let r = edge_residual(&e.t_ij, ti, tj);
            let (ji, jj) = edge_jacobians(&e.t_ij, ti, tj);
            let blocks = [(self.var[e.i], ji), (self.var[e.j], jj)];
            for (va, ja) in &blocks {
                let Some(a) = *va else {
                    continue;
                };
                let ga = ja.transpose() * r;
                for d in 0..6 {
                    self.g[6 * a + d] -= ga[d];
                }
                for (vb, jb) in &blocks {
                    let Some(b) = *vb else {
                        continue;
                    };
                    if b > a {
                        continue;
                    }
                    let hab = ja.transpose() * jb;
                    for r_ in 0..6 {
                        for c in 0..6 {
                            let (row, col) = (6 * a + r_, 6 * b + c);
                            if col <= row {
                                h.add(row, col, hab[(r_, c)]);
                            }
                        }
                    }
                }
            }
        }
        let max_diag = (0..h.dim()).map(|d| h.get(d, d)).fold(0.0, f64::max);
        self.h = Some(h);
        Some(max_diag)
    }

    fn solve(&mut self, lambda: f64) -> Option<f64> {
        let mut a = self.h.clone()?;
        for d in 0..a.dim() {
            a.add(d, d, lambda);
        }
        if !a.cholesky() {
            return None;
        }
        self.step.clone_from(&self.g);
        a.solve_in_place(&mut self.step);
        let predicted = self
            .step
            .iter()
            .zip(&self.g)
            .map(|(dx, g)| dx * (lambda * dx + g))
            .sum();
        Some(predicted)
    }

    fn trial_cost(&mut self) -> Option<f64> {
        for (k, pose) in self.poses.iter().enumerate() {
            self.trial[k] = match self.var[k] {
                Some(v) => {
                    let xi = Vector6::from_column_slice(&self.step[6 * v..6 * v + 6]);
                    exp_se3(&xi) * pose
                }
                None => *pose,
            };
        }
        self.trial_cost = cost_at(self.edges, &self.trial);
        self.trial_cost.is_finite().then_some(self.trial_cost)
    }

    fn accept(&mut self) {
        std::mem::swap(&mut self.poses, &mut self.trial);
        self.cost = self.trial_cost;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimize::numdiff::assert_jacobian;
    use crate::optimize::test_scene::{perturb, pose_error, rng};
    use nalgebra::{DMatrix, DVector, Translation3, UnitQuaternion};

    /// `n` poses on a circle of radius 2 m, each looking outwards: a loop.
    fn circle(n: usize) -> Vec<Isometry3<f64>> {
        (0..n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                let centre = Vector3::new(2.0 * a.cos(), 2.0 * a.sin(), 0.1 * (3.0 * a).sin());
                let rot = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -a);
                Isometry3::from_parts(Translation3::from(centre), rot).inverse()
            })
            .collect()
    }

    #[test]
    fn edge_jacobians_match_finite_differences() {
        let mut r = rng(11);
        let ti = perturb(&Isometry3::identity(), 0.7, 0.4, &mut r);
        let tj = perturb(&Isometry3::identity(), 1.3, 0.9, &mut r);
        // A measurement that the poses do not satisfy, so the residual is far from zero.
        let t_ij = perturb(&(ti * tj.inverse()), 0.2, 0.3, &mut r);
        let f = |x: &DVector<f64>| {
            let xi = Vector6::from_column_slice(&x.as_slice()[0..6]);
            let xj = Vector6::from_column_slice(&x.as_slice()[6..12]);
            let r = edge_residual(&t_ij, &(exp_se3(&xi) * ti), &(exp_se3(&xj) * tj));
            DVector::from_column_slice(r.as_slice())
        };
        let (ji, jj) = edge_jacobians(&t_ij, &ti, &tj);
        let mut analytic = DMatrix::zeros(6, 12);
        analytic.view_mut((0, 0), (6, 6)).copy_from(&ji);
        analytic.view_mut((0, 6), (6, 6)).copy_from(&jj);
        assert_jacobian("pose-graph edge", f, &DVector::zeros(12), &analytic);
        assert!(edge_residual(&t_ij, &ti, &tj).norm() > 0.1);
    }

    #[test]
    fn a_loop_edge_removes_injected_drift() {
        let truth = circle(30);
        let n = truth.len();
        let rel = |a: usize, b: usize| truth[a] * truth[b].inverse();
        let mut edges: Vec<PoseGraphEdge> = (1..n)
            .map(|k| PoseGraphEdge {
                i: k,
                j: k - 1,
                t_ij: rel(k, k - 1),
            })
            .collect();
        // The loop edge and a second-order edge per vertex, all consistent with the truth.
        edges.push(PoseGraphEdge {
            i: n - 1,
            j: 0,
            t_ij: rel(n - 1, 0),
        });
        for k in 2..n {
            edges.push(PoseGraphEdge {
                i: k,
                j: k - 2,
                t_ij: rel(k, k - 2),
            });
        }
        // Drift: every pose after the first one carries a growing error.
        let mut r = rng(5);
        let mut poses = truth.clone();
        for (k, p) in poses.iter_mut().enumerate().skip(1) {
            *p = perturb(p, 0.01 * k as f64, 0.004 * k as f64, &mut r);
        }
        let (drift_m, drift_deg) = pose_error(&poses[n - 1], &truth[n - 1]);
        assert!(
            drift_m > 0.2 && drift_deg > 3.0,
            "{drift_m} m {drift_deg} deg"
        );
        let mut fixed = vec![false; n];
        fixed[0] = true;
        let mut graph = PoseGraph {
            poses,
            fixed,
            edges,
        };
        let report = optimize_pose_graph(&mut graph, 20);
        assert!(report.final_cost < 1e-12 * report.initial_cost.max(1.0));
        for (k, (got, want)) in graph.poses.iter().zip(&truth).enumerate() {
            let (m, deg) = pose_error(got, want);
            assert!(m < 1e-6 && deg < 1e-5, "vertex {k}: {m} m, {deg} deg");
        }
    }

    #[test]
    fn a_fixed_vertex_stays_and_an_empty_graph_is_left_alone() {
        let truth = circle(6);
        let mut graph = PoseGraph {
            poses: truth.clone(),
            fixed: vec![true; 6],
            edges: vec![PoseGraphEdge {
                i: 1,
                j: 0,
                t_ij: Isometry3::identity(),
            }],
        };
        let report = optimize_pose_graph(&mut graph, 20);
        assert_eq!(report.iterations, 0);
        assert_eq!(graph.poses, truth);
    }
}
