//! Summary statistics of a list of errors, with numpy's conventions (population std, median of
//! an even count = mean of the middle two), as evaluate_ate.py and evo print them.

use serde::Serialize;

/// RMSE, mean, median, std, min, max and count of a list of non-negative errors.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ErrorStats {
    /// Root mean square.
    pub rmse: f64,
    /// Arithmetic mean.
    pub mean: f64,
    /// Median.
    pub median: f64,
    /// Population standard deviation (numpy's default, ddof = 0).
    pub std: f64,
    /// Smallest error.
    pub min: f64,
    /// Largest error.
    pub max: f64,
    /// Number of errors.
    pub count: usize,
}

impl ErrorStats {
    /// Statistics of `errors`; all zero when empty.
    pub fn from_errors(errors: &[f64]) -> Self {
        let n = errors.len();
        if n == 0 {
            return ErrorStats {
                rmse: 0.0,
                mean: 0.0,
                median: 0.0,
                std: 0.0,
                min: 0.0,
                max: 0.0,
                count: 0,
            };
        }
        let nf = n as f64;
        let mean = errors.iter().sum::<f64>() / nf;
        let sq = errors.iter().map(|e| e * e).sum::<f64>() / nf;
        let var = errors.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / nf;
        let mut sorted = errors.to_vec();
        sorted.sort_by(f64::total_cmp);
        let median = if n % 2 == 1 {
            sorted[n / 2]
        } else {
            0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
        };
        ErrorStats {
            rmse: sq.sqrt(),
            mean,
            median,
            std: var.sqrt(),
            min: sorted[0],
            max: sorted[n - 1],
            count: n,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numpy_conventions() {
        let s = ErrorStats::from_errors(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(s.median, 2.5);
        assert!((s.mean - 2.5).abs() < 1e-15);
        assert!((s.rmse - (7.5f64).sqrt()).abs() < 1e-15);
        assert!((s.std - (1.25f64).sqrt()).abs() < 1e-15);
        assert_eq!((s.min, s.max, s.count), (1.0, 4.0, 4));
        assert_eq!(ErrorStats::from_errors(&[3.0, 1.0, 2.0]).median, 2.0);
    }
}
