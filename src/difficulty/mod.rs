//! Difficulty matching: the level of a perturbation (a named camera chain, or one family) at
//! which the baseline's median ATE over n runs equals a target, the paper's ORB-SLAM2 figure for
//! the row a twin imitates. Found by bisection, every step measured, nothing else tuned: the
//! techniques are then run at the matched level and only their columns are results.
//!
//! Design: run i of every level uses perturbation seed `perturb_seed + i` and SLAM seed `i`,
//! so the levels are compared on the same draws (common random numbers make the median's
//! curve smooth enough to bisect), and the runs of one level differ in their noise. A failed
//! run (no ATE) counts as worse than any ATE, so a level where more than half fail has an
//! infinite median.
//!
//! [`request`] resolves what `noisefree match` asks (chain, target, range) and writes what it
//! leaves (`match.json`, `match.csv`, the verdict); [`level_log`] keeps every level measured,
//! so a stopped match resumes and a second one reuses them.

pub mod level_log;
pub mod request;

use crate::runner::{run_extracted, ExtractedSequence};
use anyhow::{Context, Result};
use datasets::{FrameReader, Sequence};
use perturb::{Chain, Subject};
use rayon::prelude::*;
use slam_core::place::Vocabulary;
use slam_core::system::Config;
use std::sync::Arc;

/// What one bisection measures with.
pub struct MatchSetup<'a> {
    /// The sequence (camera, ground truth) and its unperturbed frames.
    pub seq: &'a Sequence,
    /// The unperturbed frames (read through a memory when several levels read them).
    pub frames: &'a FrameReader,
    /// The family or chain whose level is sought.
    pub subject: Subject,
    /// The system measured (the baseline: MC-OR and AVC off).
    pub config: &'a Config,
    /// Place-recognition vocabulary.
    pub vocabulary: Option<&'a Arc<Vocabulary>>,
    /// Runs per level.
    pub runs: usize,
    /// Perturbation seed of run 0 (run i: + i).
    pub perturb_seed: u64,
}

/// One level measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LevelOutcome {
    /// The level.
    pub level: f64,
    /// Each run's ATE RMSE in metres (`None`: failed), run i at index i.
    pub ates: Vec<Option<f64>>,
    /// The median ATE, metres (failures counted as infinitely bad; infinite when more than half
    /// fail).
    pub median: f64,
}

impl LevelOutcome {
    /// Runs that failed.
    pub fn failed(&self) -> usize {
        self.ates.iter().filter(|a| a.is_none()).count()
    }
}

/// The median of `ates` with failures counted as +infinity.
pub fn median_with_failures(ates: &[Option<f64>]) -> f64 {
    let mut v: Vec<f64> = ates.iter().map(|a| a.unwrap_or(f64::INFINITY)).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        let (a, b) = (v[n / 2 - 1], v[n / 2]);
        if a.is_infinite() || b.is_infinite() {
            f64::INFINITY
        } else {
            (a + b) / 2.0
        }
    }
}

/// Measures `setup.runs` runs at `level`, in parallel on the current rayon pool.
pub fn measure_level(setup: &MatchSetup<'_>, level: f64) -> Result<LevelOutcome> {
    let chain = Chain(setup.subject.at(level));
    let ates: Vec<Option<f64>> = (0..setup.runs)
        .into_par_iter()
        .map(|i| -> Result<Option<f64>> {
            let pseed = setup.perturb_seed + i as u64;
            let (pseq, frames) =
                perturb::perturb_sequence(setup.seq, setup.frames.clone(), &chain, pseed)
                    .with_context(|| format!("perturbing {} by {chain}", setup.seq.name))?;
            let orbs = std::slice::from_ref(&setup.config.orb);
            let extracted = ExtractedSequence::extract_all(&frames, &pseq.camera, orbs, || {})
                .with_context(|| format!("reading the frames of {}", setup.seq.name))?
                .remove(0);
            let mut cfg = setup.config.clone();
            cfg.seed = i as u64;
            let o = run_extracted(&pseq, &extracted, &cfg, setup.vocabulary, |_| {});
            Ok(o.ate_rmse())
        })
        .collect::<Result<_>>()?;
    let median = median_with_failures(&ates);
    Ok(LevelOutcome {
        level,
        ates,
        median,
    })
}

/// How a bisection ended.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum MatchStatus {
    /// A level whose median is within the tolerance of the target (or the closest one found
    /// when the steps ran out).
    Matched {
        /// The level.
        level: f64,
        /// Its median ATE, metres.
        median: f64,
        /// Whether it is within the tolerance.
        within_tolerance: bool,
    },
    /// The target lies below the median at level 0: the sequence is already harder.
    BelowRange {
        /// Median at the low end, metres.
        at_low: f64,
        /// Median at the high end, metres.
        at_high: f64,
    },
    /// The target lies above the median at the highest level allowed.
    AboveRange {
        /// Median at the low end, metres.
        at_low: f64,
        /// Median at the high end, metres.
        at_high: f64,
    },
}

/// A bisection's every step and its end.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MatchResult {
    /// The target median ATE, metres.
    pub target: f64,
    /// Every level measured, in order.
    pub steps: Vec<LevelOutcome>,
    /// How it ended.
    pub status: MatchStatus,
}

/// Bisects the level in `[low, high]` at which the median ATE equals `target` (metres), at
/// most `max_steps` levels between the ends, stopping once a median is within `tolerance`
/// (relative) of the target. A level in `log` is taken from it rather than measured again;
/// a level measured is added to it. `on_step` sees each level (and whether it came from the
/// log). Assumes the median grows with the level; where noise breaks that, it still ends at a
/// level whose median crosses the target between two measured neighbours.
pub fn bisect(
    setup: &MatchSetup<'_>,
    target: f64,
    range: (f64, f64),
    max_steps: usize,
    tolerance: f64,
    log: &mut level_log::LevelLog,
    mut on_step: impl FnMut(&LevelOutcome, bool),
) -> Result<MatchResult> {
    bisect_with(
        |level| {
            if let Some(o) = log.recorded(level) {
                let o = o.clone();
                on_step(&o, true);
                return Ok(o);
            }
            let o = measure_level(setup, level)?;
            log.record(&o)?;
            on_step(&o, false);
            Ok(o)
        },
        target,
        range,
        max_steps,
        tolerance,
    )
}

/// [`bisect`] over any measurement of a level (what the tests drive with a known curve).
pub fn bisect_with(
    mut measure_at: impl FnMut(f64) -> Result<LevelOutcome>,
    target: f64,
    (low, high): (f64, f64),
    max_steps: usize,
    tolerance: f64,
) -> Result<MatchResult> {
    let mut steps = Vec::new();
    let mut measure = |level: f64, steps: &mut Vec<LevelOutcome>| -> Result<LevelOutcome> {
        let o = measure_at(level)?;
        steps.push(o.clone());
        Ok(o)
    };
    let lo = measure(low, &mut steps)?;
    let close = |m: f64| (m - target).abs() <= tolerance * target;
    if close(lo.median) {
        let status = MatchStatus::Matched {
            level: low,
            median: lo.median,
            within_tolerance: true,
        };
        return Ok(MatchResult {
            target,
            steps,
            status,
        });
    }
    let hi = measure(high, &mut steps)?;
    if target < lo.median || target > hi.median {
        let ends = (lo.median, hi.median);
        let status = if target < lo.median {
            MatchStatus::BelowRange {
                at_low: ends.0,
                at_high: ends.1,
            }
        } else {
            MatchStatus::AboveRange {
                at_low: ends.0,
                at_high: ends.1,
            }
        };
        return Ok(MatchResult {
            target,
            steps,
            status,
        });
    }
    let (mut a, mut b) = (low, high);
    let mut best = if (lo.median - target).abs() <= (hi.median - target).abs() {
        lo
    } else {
        hi
    };
    for _ in 0..max_steps {
        if close(best.median) {
            break;
        }
        let mid = ((a + b) / 2.0 * 1e6).round() / 1e6;
        if mid <= a || mid >= b {
            break;
        }
        let m = measure(mid, &mut steps)?;
        if m.median < target {
            a = mid;
        } else {
            b = mid;
        }
        if (m.median - target).abs() < (best.median - target).abs() {
            best = m;
        }
    }
    let status = MatchStatus::Matched {
        level: best.level,
        median: best.median,
        within_tolerance: close(best.median),
    };
    Ok(MatchResult {
        target,
        steps,
        status,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_counts_failures_as_worst() {
        assert_eq!(
            median_with_failures(&[Some(3.0), Some(1.0), Some(2.0)]),
            2.0
        );
        assert_eq!(
            median_with_failures(&[Some(3.0), None, Some(1.0), Some(2.0)]),
            2.5
        );
        assert_eq!(
            median_with_failures(&[Some(1.0), None, None, Some(2.0)]),
            f64::INFINITY
        );
        assert_eq!(
            median_with_failures(&[Some(1.0), None, None]),
            f64::INFINITY
        );
        assert!(median_with_failures(&[]).is_nan());
    }

    /// A known curve: median 4 mm + 10 mm per level.
    fn line(level: f64) -> Result<LevelOutcome> {
        let m = 0.004 + 0.010 * level;
        Ok(LevelOutcome {
            level,
            ates: vec![Some(m)],
            median: m,
        })
    }

    #[test]
    fn bisection_finds_the_level_of_a_known_curve() {
        let r = bisect_with(line, 0.023, (0.0, 4.0), 20, 0.01).unwrap();
        let MatchStatus::Matched {
            level,
            within_tolerance,
            ..
        } = r.status
        else {
            panic!("{r:?}")
        };
        assert!(within_tolerance);
        assert!((level - 1.9).abs() < 0.03, "{level}");
        // Both ends first, then halvings: 4 -> 2 -> 1 -> 1.5 -> 1.75 -> 1.875.
        assert_eq!(r.steps[0].level, 0.0);
        assert_eq!(r.steps[1].level, 4.0);
        assert_eq!(r.steps[2].level, 2.0);
        assert!(r.steps.len() <= 10, "{}", r.steps.len());
        // With too few steps it ends at the closest level measured, flagged.
        let r = bisect_with(line, 0.023, (0.0, 4.0), 1, 0.001).unwrap();
        match r.status {
            MatchStatus::Matched {
                level,
                median,
                within_tolerance,
            } => {
                assert_eq!(level, 2.0);
                assert!((median - 0.024).abs() < 1e-12);
                assert!(!within_tolerance);
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_target_outside_the_curve_says_so_with_both_ends() {
        let r = bisect_with(line, 1.0, (0.0, 4.0), 10, 0.01).unwrap();
        match r.status {
            MatchStatus::AboveRange { at_low, at_high } => {
                assert!((at_low - 0.004).abs() < 1e-12 && (at_high - 0.044).abs() < 1e-12);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(r.steps.len(), 2);
        let r = bisect_with(line, 0.001, (0.0, 4.0), 10, 0.01).unwrap();
        assert!(matches!(r.status, MatchStatus::BelowRange { .. }));
    }
}
