//! The Huber robust kernel applied to a chi2 value, as g2o's `RobustKernelHuber` (the kernel
//! ORB-SLAM2 puts on every edge before its outlier passes).

/// Huber kernel on `s = r^T Omega r` with threshold `delta` on the whitened residual norm:
/// `rho(s) = s` for `s <= delta^2`, `2 delta sqrt(s) - delta^2` beyond (linear growth of the
/// cost in the residual norm, so gross outliers cannot dominate).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Huber {
    /// Threshold on the whitened residual norm (`sqrt` of the chi2 gate).
    pub delta: f64,
}

impl Huber {
    /// The robustified cost `rho(s)`.
    pub fn cost(&self, chi2: f64) -> f64 {
        let d2 = self.delta * self.delta;
        if chi2 <= d2 {
            chi2
        } else {
            2.0 * self.delta * chi2.sqrt() - d2
        }
    }

    /// The iteratively-reweighted least-squares weight `rho'(s)` (1 inside, `delta / sqrt(s)`
    /// outside) that multiplies the information in the normal equations.
    pub fn weight(&self, chi2: f64) -> f64 {
        if chi2 <= self.delta * self.delta {
            1.0
        } else {
            self.delta / chi2.sqrt()
        }
    }
}

/// Cost and IRLS weight of an observation with raw chi2 `chi2`: Huber at `delta` when `robust`,
/// plain least squares otherwise.
pub(crate) fn kernel_cost(robust: bool, delta: f64, chi2: f64) -> f64 {
    if robust {
        Huber { delta }.cost(chi2)
    } else {
        chi2
    }
}

/// The IRLS weight matching [`kernel_cost`].
pub(crate) fn kernel_weight(robust: bool, delta: f64, chi2: f64) -> f64 {
    if robust {
        Huber { delta }.weight(chi2)
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huber_is_continuous_and_its_weight_is_the_derivative() {
        let h = Huber {
            delta: 5.991f64.sqrt(),
        };
        let d2 = h.delta * h.delta;
        assert!((h.cost(d2 - 1e-12) - h.cost(d2 + 1e-12)).abs() < 1e-9);
        for s in [0.5, 3.0, 5.0, 7.0, 50.0, 1e4] {
            let eps = 1e-6 * s;
            let numeric = (h.cost(s + eps) - h.cost(s - eps)) / (2.0 * eps);
            assert!((numeric - h.weight(s)).abs() < 1e-7, "s = {s}");
        }
    }

    #[test]
    fn huber_grows_linearly_in_the_residual_norm() {
        let h = Huber { delta: 2.0 };
        // Outside the threshold, doubling the residual norm (4x chi2) adds 2 delta |r|.
        let (r1, r2) = (10.0f64, 20.0f64);
        assert!((h.cost(r2 * r2) - h.cost(r1 * r1) - 2.0 * h.delta * (r2 - r1)).abs() < 1e-9);
        assert!(h.cost(1e6) < 1e6);
        assert_eq!(h.cost(3.0), 3.0);
        assert_eq!(kernel_cost(false, 2.0, 1e6), 1e6);
        assert_eq!(kernel_weight(false, 2.0, 1e6), 1.0);
    }
}
