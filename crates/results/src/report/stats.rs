//! The statistics the tables state. A group of runs is summarised by n, mean, standard
//! deviation, median and the 95 % interval of its mean (Student's t, n - 1 degrees of freedom);
//! a system is compared with the baseline by the difference of their mean ATEs, as a share of
//! the baseline's mean, with the 95 % interval of that difference and a two-sided p-value. The
//! test is the **paired t-test** where run i of both systems shares its SLAM seed and its
//! perturbation draw (the runs are then matched pairs and their differences carry no draw-to-draw
//! spread), **Welch's t-test** otherwise. The p-values of one table are corrected together
//! with **Holm's** step-down procedure, so a difference a table marks survives the number of
//! comparisons that table made.
//!
//! Relative differences: the other system's mean as a share of the baseline's, with **Fieller's**
//! 95 % interval of that ratio (Fieller 1954): the ratios `r` for which `other - r baseline`
//! passes the same t-test (same pairing, same degrees of freedom). The baseline mean's own
//! uncertainty enters (the difference's interval over the baseline's mean, used before, passed
//! -100 % wherever the baseline's runs spread widely; Fieller's does only where the other
//! system's mean is itself not told from zero), and a bounded one excludes 0 % exactly when
//! the difference's interval excludes 0. When the baseline's mean is not told from zero at that
//! level the set of ratios reaches both infinities; the tables say `[unbounded]` and the
//! p-value alone gives the verdict. Distributions come from
//! statrs; the values are tested against scipy's and statsmodels' (the numbers committed in the
//! tests).

use statrs::distribution::{ContinuousCDF, StudentsT};

/// The quantile of Student's t with `df` degrees of freedom at `p`.
fn t_quantile(df: f64, p: f64) -> f64 {
    StudentsT::new(0.0, 1.0, df)
        .expect("positive degrees of freedom")
        .inverse_cdf(p)
}

/// The two-sided p-value of a t statistic with `df` degrees of freedom.
fn two_sided_p(t: f64, df: f64) -> f64 {
    if t.is_nan() {
        return 1.0;
    }
    if t.is_infinite() {
        return 0.0;
    }
    let dist = StudentsT::new(0.0, 1.0, df).expect("positive degrees of freedom");
    (2.0 * dist.cdf(-t.abs())).min(1.0)
}

/// Mean, and the half-width of its 95 % interval (Student's t with n - 1 degrees of freedom,
/// sample standard deviation), of `x`; the half-width is `None` for fewer than two values.
pub fn mean_ci95(x: &[f64]) -> Option<(f64, Option<f64>)> {
    let n = x.len();
    if n == 0 {
        return None;
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    if n < 2 {
        return Some((mean, None));
    }
    let var = variance(x, mean);
    Some((
        mean,
        Some(t_quantile((n - 1) as f64, 0.975) * (var / n as f64).sqrt()),
    ))
}

/// Sample variance (n - 1 in the denominator) of `x` about `mean`.
fn variance(x: &[f64], mean: f64) -> f64 {
    x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (x.len() - 1) as f64
}

/// The median of `x` (the mean of the two middle values for an even count).
pub fn median(x: &[f64]) -> Option<f64> {
    if x.is_empty() {
        return None;
    }
    let mut v = x.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    })
}

/// One group of runs as every table summarises it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    /// Values summarised (runs that did not fail).
    pub n: usize,
    /// Their mean.
    pub mean: f64,
    /// Sample standard deviation (`None` below two values).
    pub std: Option<f64>,
    /// Median.
    pub median: f64,
    /// The 95 % interval of the mean, Student's t (`None` below two values).
    pub ci95: Option<(f64, f64)>,
}

/// Summarises `x`; `None` when it is empty.
pub fn summarize(x: &[f64]) -> Option<Summary> {
    let (mean, half) = mean_ci95(x)?;
    Some(Summary {
        n: x.len(),
        mean,
        std: (x.len() >= 2).then(|| variance(x, mean).sqrt()),
        median: median(x)?,
        ci95: half.map(|h| (mean - h, mean + h)),
    })
}

/// Which test compared two groups.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Test {
    /// Paired t-test on run-by-run differences (runs share seed and perturbation draw).
    Paired,
    /// Welch's unequal-variance t-test (runs not matched).
    Welch,
}

impl Test {
    /// The name a table prints.
    pub fn name(self) -> &'static str {
        match self {
            Test::Paired => "paired t",
            Test::Welch => "Welch t",
        }
    }
}

/// A system against the baseline: `other - baseline`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    /// The test used.
    pub test: Test,
    /// Runs of the baseline and of the other system the test used (equal when paired).
    pub n: (usize, usize),
    /// The baseline's mean over those runs.
    pub baseline_mean: f64,
    /// Mean difference, other minus baseline (negative: the other is better).
    pub diff: f64,
    /// Its 95 % interval.
    pub diff_ci95: (f64, f64),
    /// Fieller's 95 % interval of the ratio of the means, other over baseline; `None` when it
    /// is unbounded (the baseline's mean not told from zero).
    pub ratio_ci95: Option<(f64, f64)>,
    /// Degrees of freedom of the t distribution used.
    pub df: f64,
    /// The t statistic.
    pub t: f64,
    /// Two-sided p-value, uncorrected.
    pub p: f64,
}

impl Comparison {
    /// The difference as a share of the baseline's mean, in % (negative: a gain).
    pub fn relative_pct(&self) -> f64 {
        100.0 * self.diff / self.baseline_mean
    }

    /// The interval of [`Comparison::relative_pct`], in %: Fieller's interval of the ratio of
    /// the means, less one; `(-inf, +inf)` when that interval is unbounded.
    pub fn relative_ci95_pct(&self) -> (f64, f64) {
        match self.ratio_ci95 {
            Some((lo, hi)) => (100.0 * (lo - 1.0), 100.0 * (hi - 1.0)),
            None => (f64::NEG_INFINITY, f64::INFINITY),
        }
    }
}

/// The means of two groups and the variances of those means (their squared standard errors)
/// and covariance (zero for independent groups): what Fieller's interval needs.
#[derive(Clone, Copy, Debug)]
struct Means {
    baseline: f64,
    other: f64,
    var_baseline: f64,
    var_other: f64,
    cov: f64,
}

impl Means {
    /// The means of `baseline` and `other`, their variances (sample variance over n) and,
    /// when the runs are `paired` (equal lengths, run i of both matched), their covariance.
    fn of(baseline: &[f64], other: &[f64], paired: bool) -> Means {
        let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
        let (mb, mo) = (mean(baseline), mean(other));
        let cov = if paired {
            let n = baseline.len();
            baseline
                .iter()
                .zip(other)
                .map(|(b, o)| (b - mb) * (o - mo))
                .sum::<f64>()
                / (n - 1) as f64
                / n as f64
        } else {
            0.0
        };
        Means {
            baseline: mb,
            other: mo,
            var_baseline: variance(baseline, mb) / baseline.len() as f64,
            var_other: variance(other, mo) / other.len() as f64,
            cov,
        }
    }
}

/// Fieller's interval of `other / baseline` at the t quantile `q`: the ratios `r` with
/// `(other - r baseline)^2 <= q^2 (var_other - 2 r cov + r^2 var_baseline)`. `None` when that
/// set is unbounded (`baseline^2 <= q^2 var_baseline`). Exact groups (no variance) give the
/// ratio itself.
fn fieller(m: Means, q: f64) -> Option<(f64, f64)> {
    let q2 = q * q;
    let a = m.baseline * m.baseline - q2 * m.var_baseline;
    if a.is_nan() || a <= 0.0 {
        return None;
    }
    let b = m.other * m.baseline - q2 * m.cov;
    let c = m.other * m.other - q2 * m.var_other;
    // Non-negative in exact arithmetic when a > 0 (the quadratic is <= 0 at other / baseline).
    let root = (b * b - a * c).max(0.0).sqrt();
    Some(((b - root) / a, (b + root) / a))
}

/// A t-based comparison from its difference, standard error and degrees of freedom; a zero
/// standard error (identical runs, or differences that do not vary) gives p = 1 for no
/// difference and p = 0 for one, with an interval of width zero.
fn from_t(test: Test, n: (usize, usize), means: Means, diff: f64, se: f64, df: f64) -> Comparison {
    let (t, q) = if se > 0.0 && df.is_finite() && df > 0.0 {
        (diff / se, t_quantile(df, 0.975))
    } else if diff == 0.0 {
        (f64::NAN, 0.0)
    } else {
        (diff.signum() * f64::INFINITY, 0.0)
    };
    let half = q * se;
    Comparison {
        test,
        n,
        baseline_mean: means.baseline,
        diff,
        diff_ci95: (diff - half, diff + half),
        ratio_ci95: fieller(means, q),
        df,
        t,
        p: two_sided_p(t, df),
    }
}

/// Paired t-test of `other` against `baseline`, pair i being `(baseline[i], other[i])`;
/// `None` for fewer than two pairs or unequal lengths.
pub fn paired(baseline: &[f64], other: &[f64]) -> Option<Comparison> {
    let n = baseline.len();
    if n < 2 || other.len() != n {
        return None;
    }
    let d: Vec<f64> = other.iter().zip(baseline).map(|(o, b)| o - b).collect();
    let mean_d = d.iter().sum::<f64>() / n as f64;
    let se = (variance(&d, mean_d) / n as f64).sqrt();
    Some(from_t(
        Test::Paired,
        (n, n),
        Means::of(baseline, other, true),
        mean_d,
        se,
        (n - 1) as f64,
    ))
}

/// Welch's t-test of `other` against `baseline`; `None` when either has fewer than two runs.
pub fn welch(baseline: &[f64], other: &[f64]) -> Option<Comparison> {
    let (nb, no) = (baseline.len(), other.len());
    if nb < 2 || no < 2 {
        return None;
    }
    let means = Means::of(baseline, other, false);
    let (vb, vo) = (means.var_baseline, means.var_other);
    let se2 = vb + vo;
    let df = se2 * se2 / (vb * vb / (nb - 1) as f64 + vo * vo / (no - 1) as f64);
    Some(from_t(
        Test::Welch,
        (nb, no),
        means,
        means.other - means.baseline,
        se2.sqrt(),
        df,
    ))
}

/// Holm's step-down adjustment of `p` (in the input's order): the k-th smallest p times
/// (m - k + 1), made non-decreasing along the sorted order and capped at 1. A comparison
/// survives the correction at level alpha when its adjusted p is at most alpha.
pub fn holm(p: &[f64]) -> Vec<f64> {
    let m = p.len();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| p[a].total_cmp(&p[b]));
    let mut out = vec![0.0; m];
    let mut running: f64 = 0.0;
    for (k, &i) in order.iter().enumerate() {
        running = running.max(((m - k) as f64 * p[i]).min(1.0));
        out[i] = running;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    // Reference values: scipy 1.17.1 and statsmodels 0.15.0 on these numbers:
    //   stats.ttest_rel(o, b), .confidence_interval(0.95)
    //   stats.ttest_ind(w, b, equal_var=False), .confidence_interval(0.95)
    //   multipletests(p, method="holm")
    const B: [f64; 10] = [4.1, 3.9, 4.4, 4.0, 4.2, 3.8, 4.3, 4.1, 4.0, 4.2];
    const O: [f64; 10] = [3.7, 3.8, 4.0, 3.9, 3.9, 3.6, 4.1, 3.8, 3.9, 4.0];
    const W: [f64; 5] = [3.5, 4.6, 3.9, 5.2, 4.4];

    fn close(a: f64, b: f64) {
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }

    #[test]
    fn paired_matches_scipy() {
        let c = paired(&B, &O).unwrap();
        assert_eq!(c.test, Test::Paired);
        close(c.t, -6.27272727273);
        close(c.p, 0.000145632780129);
        close(c.df, 9.0);
        close(c.diff_ci95.0, -0.312945762636);
        close(c.diff_ci95.1, -0.147054237364);
        close(c.relative_pct(), 100.0 * -0.23 / 4.1);
    }

    #[test]
    fn welch_matches_scipy() {
        let c = welch(&B, &W).unwrap();
        close(c.t, 0.738548945876);
        close(c.p, 0.498341940652);
        close(c.df, 4.31542802052);
        close(c.diff_ci95.0, -0.58374733676);
        close(c.diff_ci95.1, 1.02374733676);
    }

    // Fieller's interval, reference values from the formula evaluated in Python with scipy's
    // t quantile (scipy has no Fieller function): the roots of
    // (o - r b)^2 = q^2 (var_o - 2 r cov + r^2 var_b) with the means' variances and covariance.
    #[test]
    fn fieller_ratio_interval_matches_its_reference_values() {
        let c = paired(&B, &O).unwrap();
        let (lo, hi) = c.ratio_ci95.unwrap();
        close(lo, 0.9249512305689327);
        close(hi, 0.9634845841200685);
        let (plo, phi) = c.relative_ci95_pct();
        close(plo, 100.0 * (0.9249512305689327 - 1.0));
        close(phi, 100.0 * (0.9634845841200685 - 1.0));
        let w = welch(&B, &W).unwrap();
        let (lo, hi) = w.ratio_ci95.unwrap();
        close(lo, 0.8585927299318481);
        close(hi, 1.251770979727761);
    }

    /// The Fieller statistic of ratio `r`: `(o - r b)^2 / (var_o - 2 r cov + r^2 var_b)`.
    fn fieller_statistic(m: Means, r: f64) -> f64 {
        (m.other - r * m.baseline).powi(2)
            / (m.var_other - 2.0 * r * m.cov + r * r * m.var_baseline)
    }

    #[test]
    fn fieller_bounds_solve_its_equation_and_agree_with_the_t_test() {
        // A baseline that spreads widely against a steady, much better system (the shape of rc
        // on the walking twins): the difference over the baseline's mean passes -100 %, the
        // ratio's interval does not.
        let wide_b = [0.02, 0.09, 0.15, 0.04, 0.12, 0.03, 0.11, 0.08, 0.16, 0.05];
        let good = [
            0.002, 0.0021, 0.0019, 0.002, 0.0022, 0.0018, 0.002, 0.0021, 0.0019, 0.002,
        ];
        let c = welch(&wide_b, &good).unwrap();
        let old_lo = 100.0 * c.diff_ci95.0 / c.baseline_mean;
        assert!(old_lo < -100.0, "{old_lo}");
        let (lo, hi) = c.relative_ci95_pct();
        assert!((lo - -98.3459783921779).abs() < 1e-6, "{lo}");
        assert!((hi - -95.9492090254223).abs() < 1e-6, "{hi}");
        for (b, o, pairs) in [
            (&wide_b[..], &good[..], false),
            (&B[..], &O[..], true),
            (&B[..], &W[..], false),
        ] {
            let c = if pairs { paired(b, o) } else { welch(b, o) }.unwrap();
            let m = Means::of(b, o, pairs);
            let q = t_quantile(c.df, 0.975);
            let (lo, hi) = c.ratio_ci95.unwrap();
            // Both bounds solve the defining equation, the estimate lies between them.
            for r in [lo, hi] {
                assert!(
                    (fieller_statistic(m, r) - q * q).abs() < 1e-6 * q * q,
                    "{r}"
                );
            }
            assert!(lo < m.other / m.baseline && m.other / m.baseline < hi);
            // Ratio 1 is outside exactly when the difference's interval excludes 0.
            let excludes_one = !(lo..=hi).contains(&1.0);
            let excludes_zero = c.diff_ci95.0 > 0.0 || c.diff_ci95.1 < 0.0;
            assert_eq!(excludes_one, excludes_zero);
        }
    }

    #[test]
    fn fieller_is_unbounded_when_the_baseline_mean_is_not_told_from_zero() {
        // Two baseline runs far apart: t(1 df) = 12.7 swamps their mean.
        let c = welch(&[0.1, 10.0], &[1.0, 1.1, 0.9]).unwrap();
        assert_eq!(c.ratio_ci95, None);
        assert_eq!(c.relative_ci95_pct(), (f64::NEG_INFINITY, f64::INFINITY));
        // Identical runs: no spread, the ratio itself.
        let same = paired(&B, &B).unwrap();
        assert_eq!(same.ratio_ci95, Some((1.0, 1.0)));
    }

    #[test]
    fn holm_matches_statsmodels_and_its_definition() {
        let p = [0.01, 0.04, 0.03, 0.005, 0.2, 0.04];
        let adj = holm(&p);
        let want = [0.05, 0.12, 0.12, 0.03, 0.2, 0.12];
        for (a, w) in adj.iter().zip(want) {
            close(*a, w);
        }
        // Definition: sorted p_(k) compared with alpha / (m - k + 1), stop at the first that
        // fails; the rejected set equals {adjusted <= alpha}.
        let alpha = 0.05;
        let mut sorted: Vec<(f64, usize)> = p.iter().copied().zip(0..).collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut rejected = vec![false; p.len()];
        for (k, (pk, i)) in sorted.iter().enumerate() {
            if *pk <= alpha / (p.len() - k) as f64 {
                rejected[*i] = true;
            } else {
                break;
            }
        }
        for i in 0..p.len() {
            assert_eq!(adj[i] <= alpha + 1e-12, rejected[i], "comparison {i}");
        }
        assert!(holm(&[]).is_empty());
        assert_eq!(holm(&[0.7, 0.9]), vec![1.0, 1.0]);
    }

    #[test]
    fn summary_of_one_sample() {
        let s = summarize(&[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
        assert_eq!(s.n, 5);
        close(s.mean, 3.0);
        close(s.median, 3.0);
        close(s.std.unwrap(), 2.5f64.sqrt());
        // scipy: stats.ttest_1samp([1..5], 0).confidence_interval(0.95)
        let (lo, hi) = s.ci95.unwrap();
        close(lo, 1.0367568385224428);
        close(hi, 4.963243161477557);
        let one = summarize(&[2.0]).unwrap();
        assert_eq!((one.std, one.ci95), (None, None));
        assert!(summarize(&[]).is_none());
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), Some(2.5));
    }

    #[test]
    fn identical_runs_are_no_difference_and_a_constant_shift_is_certain() {
        let same = paired(&B, &B).unwrap();
        assert_eq!((same.diff, same.p), (0.0, 1.0));
        assert_eq!(same.diff_ci95, (0.0, 0.0));
        let shifted: Vec<f64> = B.iter().map(|b| b + 0.5).collect();
        let c = paired(&B, &shifted).unwrap();
        assert!(c.p < 1e-12, "{}", c.p);
        close(c.diff, 0.5);
        assert!(paired(&B[..1], &O[..1]).is_none());
        assert!(paired(&B, &O[..3]).is_none());
        assert!(welch(&B, &[1.0]).is_none());
    }

    #[test]
    fn t_interval_matches_reference_values() {
        // R 4: t.test(c(1, 2, 3, 4, 5))$conf.int -> 1.036757 4.963243
        let (m, h) = mean_ci95(&[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
        assert!((m - 3.0).abs() < 1e-12);
        assert!((m - h.unwrap() - 1.036757).abs() < 1e-6, "{h:?}");
        // qt(0.975, 9) = 2.262157; sd of 0..9 = 3.02765
        let x: Vec<f64> = (0..10).map(f64::from).collect();
        let (_, h) = mean_ci95(&x).unwrap();
        assert!((h.unwrap() - 2.262157 * 3.02765 / 10f64.sqrt()).abs() < 1e-5);
        assert_eq!(mean_ci95(&[2.0]), Some((2.0, None)));
        assert_eq!(mean_ci95(&[]), None);
    }
}
