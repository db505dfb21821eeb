//! One Levenberg-Marquardt driver with g2o's damping schedule, shared by the pose-only and the
//! bundle-adjustment solvers (which only say how to build, solve and try a step).
//!
//! Schedule (g2o `OptimizationAlgorithmLevenberg`, as ORB-SLAM2 runs it): `lambda0 = 1e-5 *
//! max diag(H)` at the first iteration of a call; a step is accepted only when the cost strictly
//! decreases (`rho > 0`), then `lambda *= max(1/3, 1 - (2 rho - 1)^3)`; a rejected step does
//! `lambda *= nu, nu *= 2`, up to 10 tries per iteration, after which the call stops. Hence the
//! cost sequence of a call is strictly decreasing. One addition: a call also stops once an
//! accepted step lowers the cost by less than 1e-12 of its value (nothing left to gain).

/// Initial damping relative to the largest diagonal entry of the normal matrix.
const TAU: f64 = 1e-5;
/// Rejected steps tolerated within one iteration.
const MAX_TRIALS: usize = 10;
/// Relative cost decrease below which the problem counts as converged.
const CONVERGED_RELATIVE_DECREASE: f64 = 1e-12;

/// A least-squares problem as the LM driver sees it. The implementation owns the current
/// estimate, the normal equations `H dx = g` (with `g = -J^T Omega r`) and one pending step.
pub(crate) trait LmProblem {
    /// The cost at the current estimate.
    fn cost(&self) -> f64;
    /// Builds the normal equations at the current estimate and returns the largest diagonal
    /// entry of `H`, or `None` when there is nothing to optimize.
    fn linearize(&mut self) -> Option<f64>;
    /// Solves the damped system for a step (damping `lambda` on every variable, possibly plus
    /// a problem-specific floor) and returns the model's predicted decrease `dx^T (D dx + g)`,
    /// or `None` when the damped system could not be solved.
    fn solve(&mut self, lambda: f64) -> Option<f64>;
    /// The cost after applying the pending step, or `None` when the step is not admissible
    /// (e.g. it moves an observed point behind a camera).
    fn trial_cost(&mut self) -> Option<f64>;
    /// Makes the estimate evaluated by the last [`LmProblem::trial_cost`] current.
    fn accept(&mut self);
}

/// What one LM call did.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct LmSummary {
    /// Iterations run (linearizations), at most the requested number.
    pub iterations: usize,
    /// Cost before the first iteration and after every accepted step (strictly decreasing).
    pub costs: Vec<f64>,
}

/// Runs up to `max_iterations` LM iterations on `problem`.
pub(crate) fn levenberg_marquardt<P: LmProblem>(
    problem: &mut P,
    max_iterations: usize,
) -> LmSummary {
    let mut cost = problem.cost();
    let mut summary = LmSummary {
        iterations: 0,
        costs: vec![cost],
    };
    let mut lambda = 0.0;
    let mut nu = 2.0;
    for iteration in 0..max_iterations {
        let Some(max_diag) = problem.linearize() else {
            break;
        };
        summary.iterations += 1;
        if iteration == 0 {
            lambda = TAU * max_diag;
            if lambda.is_nan() || lambda <= 0.0 || !lambda.is_finite() {
                lambda = TAU;
            }
        }
        let mut accepted = None;
        for _ in 0..MAX_TRIALS {
            if let Some(predicted) = problem.solve(lambda) {
                if let Some(new_cost) = problem.trial_cost() {
                    let rho = (cost - new_cost) / (predicted + 1e-3);
                    if rho > 0.0 && new_cost.is_finite() {
                        problem.accept();
                        let a = 2.0 * rho - 1.0;
                        lambda *= (1.0 - a * a * a).max(1.0 / 3.0);
                        nu = 2.0;
                        accepted = Some(new_cost);
                        break;
                    }
                }
            }
            lambda *= nu;
            nu *= 2.0;
        }
        let Some(new_cost) = accepted else {
            break;
        };
        let decrease = cost - new_cost;
        cost = new_cost;
        summary.costs.push(cost);
        if decrease <= CONVERGED_RELATIVE_DECREASE * (cost + decrease) {
            break;
        }
    }
    summary
}

#[cfg(test)]
mod tests {
    use super::*;

    /// f(x) = sum_i (x_i^2 - c_i)^2 -- a small nonlinear least-squares problem.
    struct Quartic {
        c: Vec<f64>,
        x: Vec<f64>,
        trial: Vec<f64>,
        h: Vec<f64>,
        g: Vec<f64>,
    }

    impl Quartic {
        fn cost_at(&self, x: &[f64]) -> f64 {
            x.iter()
                .zip(&self.c)
                .map(|(x, c)| (x * x - c).powi(2))
                .sum()
        }
    }

    impl LmProblem for Quartic {
        fn cost(&self) -> f64 {
            self.cost_at(&self.x)
        }
        fn linearize(&mut self) -> Option<f64> {
            for i in 0..self.x.len() {
                let j = 2.0 * self.x[i];
                let r = self.x[i] * self.x[i] - self.c[i];
                self.h[i] = j * j;
                self.g[i] = -j * r;
            }
            self.h.iter().cloned().reduce(f64::max)
        }
        fn solve(&mut self, lambda: f64) -> Option<f64> {
            let mut predicted = 0.0;
            for i in 0..self.x.len() {
                let dx = self.g[i] / (self.h[i] + lambda);
                self.trial[i] = self.x[i] + dx;
                predicted += dx * (lambda * dx + self.g[i]);
            }
            Some(predicted)
        }
        fn trial_cost(&mut self) -> Option<f64> {
            Some(self.cost_at(&self.trial))
        }
        fn accept(&mut self) {
            self.x.clone_from(&self.trial);
        }
    }

    #[test]
    fn converges_with_strictly_decreasing_cost() {
        let mut p = Quartic {
            c: vec![4.0, 9.0, 0.25],
            x: vec![5.0, 0.5, 3.0],
            trial: vec![0.0; 3],
            h: vec![0.0; 3],
            g: vec![0.0; 3],
        };
        let s = levenberg_marquardt(&mut p, 50);
        assert!(s.costs.windows(2).all(|w| w[1] < w[0]), "{:?}", s.costs);
        assert!(p.cost() < 1e-12, "cost {}", p.cost());
        assert!((p.x[0] - 2.0).abs() < 1e-6 && (p.x[1] - 3.0).abs() < 1e-6);
        assert!(s.iterations <= 50);
    }

    #[test]
    fn respects_the_iteration_budget() {
        let mut p = Quartic {
            c: vec![4.0],
            x: vec![100.0],
            trial: vec![0.0],
            h: vec![0.0],
            g: vec![0.0],
        };
        let s = levenberg_marquardt(&mut p, 3);
        assert_eq!(s.iterations, 3);
        assert!(s.costs.len() <= 4);
    }
}
