//! Association of estimated poses with ground-truth poses by timestamp.
//!
//! Two conventions exist in the community and give different pair sets on the same files, so
//! every table names the one it used:
//! - [`AssociationMode::Tum`] (TUM's `associate.py` / `evaluate_ate.py`): every (gt, est) pair
//!   with |t_gt - (t_est + offset)| < max_difference is a candidate; candidates are taken
//!   greedily by increasing |dt|, each stamp used at most once. Default max_difference 0.02 s.
//! - [`AssociationMode::Evo`] (`evo_ape`): for each stamp of the shorter trajectory, the nearest
//!   stamp of the other with |dt| <= max_difference (evo's default 0.01 s).

/// Which association convention to reproduce.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum AssociationMode {
    /// Greedy by |dt|, one use per stamp, strict `<` (evaluate_ate.py).
    #[default]
    Tum,
    /// Nearest neighbour from the shorter trajectory, `<=` (evo).
    Evo,
}

/// Pairs `(gt_index, est_index)`, sorted by ground-truth index, of stamps that belong together.
/// `offset` (seconds) is added to every estimate stamp before comparison. Both stamp lists must
/// be in non-decreasing order (the readers guarantee it); repeated stamps are paired as the
/// reproduced tool pairs them.
pub fn associate(
    gt: &[f64],
    est: &[f64],
    max_difference: f64,
    offset: f64,
    mode: AssociationMode,
) -> Vec<(usize, usize)> {
    match mode {
        AssociationMode::Tum => associate_tum(gt, est, max_difference, offset),
        AssociationMode::Evo => associate_evo(gt, est, max_difference, offset),
    }
}

fn associate_tum(gt: &[f64], est: &[f64], max_difference: f64, offset: f64) -> Vec<(usize, usize)> {
    // Candidates: for each estimate, the ground-truth stamps inside the open window.
    let mut candidates: Vec<(f64, usize, usize)> = Vec::new();
    for (j, &t) in est.iter().enumerate() {
        let te = t + offset;
        let lo = gt.partition_point(|&g| g <= te - max_difference);
        for (i, &g) in gt.iter().enumerate().skip(lo) {
            let d = (g - te).abs();
            if g - te >= max_difference {
                break;
            }
            if d < max_difference {
                candidates.push((d, i, j));
            }
        }
    }
    // evaluate_ate.py sorts (diff, a, b) tuples: ties broken by the stamps, i.e. the indices.
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut gt_used = vec![false; gt.len()];
    let mut est_used = vec![false; est.len()];
    let mut pairs = Vec::new();
    for (_, i, j) in candidates {
        if !gt_used[i] && !est_used[j] {
            gt_used[i] = true;
            est_used[j] = true;
            pairs.push((i, j));
        }
    }
    pairs.sort_unstable();
    pairs
}

/// The nearest stamp of `sorted` to `t` within `max_difference`, chosen as evo's
/// `matching_time_indices` chooses on sorted stamps: the candidate after every stamp <= t wins
/// only when strictly closer than the one before it, so of a repeated stamp the last copy is
/// taken when approached from above (or hit exactly) and the first when approached from below.
fn evo_nearest(sorted: &[f64], t: f64, max_difference: f64) -> Option<usize> {
    let n = sorted.len();
    if n == 0 || t < sorted[0] - max_difference || t > sorted[n - 1] + max_difference {
        return None;
    }
    let idx = sorted.partition_point(|&s| s <= t).min(n - 1);
    let above = sorted[idx] - t;
    let below = if idx > 0 {
        t - sorted[idx - 1]
    } else {
        f64::INFINITY
    };
    if above <= max_difference && above < below {
        Some(idx)
    } else if below <= max_difference && below <= above {
        Some(idx - 1)
    } else {
        None
    }
}

fn associate_evo(gt: &[f64], est: &[f64], max_difference: f64, offset: f64) -> Vec<(usize, usize)> {
    // evo searches from the trajectory with fewer poses (the estimate on a tie) into the other,
    // and applies the offset to the one searched into.
    let mut pairs = Vec::new();
    if est.len() <= gt.len() {
        let gt_shifted: Vec<f64> = gt.iter().map(|t| t - offset).collect();
        for (j, &t) in est.iter().enumerate() {
            if let Some(i) = evo_nearest(&gt_shifted, t, max_difference) {
                pairs.push((i, j));
            }
        }
    } else {
        let est_shifted: Vec<f64> = est.iter().map(|t| t + offset).collect();
        for (i, &t) in gt.iter().enumerate() {
            if let Some(j) = evo_nearest(&est_shifted, t, max_difference) {
                pairs.push((i, j));
            }
        }
    }
    pairs.sort_unstable();
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jitter_within_and_beyond_window() {
        let gt: Vec<f64> = (0..10).map(|i| i as f64 * 0.1).collect();
        let est: Vec<f64> = gt
            .iter()
            .enumerate()
            .map(|(i, t)| t + if i % 2 == 0 { 0.015 } else { 0.025 })
            .collect();
        let pairs = associate(&gt, &est, 0.02, 0.0, AssociationMode::Tum);
        assert_eq!(
            pairs,
            (0..10).step_by(2).map(|i| (i, i)).collect::<Vec<_>>()
        );
    }

    #[test]
    fn each_stamp_used_once_greedy_by_dt() {
        // Two estimates compete for one gt stamp: the closer one wins, the other stays unpaired.
        let gt = [1.0];
        let est = [0.99, 1.005];
        assert_eq!(
            associate(&gt, &est, 0.02, 0.0, AssociationMode::Tum),
            vec![(0, 1)]
        );
        // evo: nearest from the shorter (gt) side.
        assert_eq!(
            associate(&gt, &est, 0.02, 0.0, AssociationMode::Evo),
            vec![(0, 1)]
        );
    }

    #[test]
    fn strict_window_in_tum_inclusive_in_evo() {
        let gt = [1.0];
        let est = [1.5];
        assert!(associate(&gt, &est, 0.5, 0.0, AssociationMode::Tum).is_empty());
        assert_eq!(
            associate(&gt, &est, 0.5, 0.0, AssociationMode::Evo),
            vec![(0, 0)]
        );
    }

    #[test]
    fn offset_shifts_estimate() {
        let gt: Vec<f64> = (0..5).map(|i| i as f64).collect();
        let est: Vec<f64> = gt.iter().map(|t| t + 100.0).collect();
        assert!(associate(&gt, &est, 0.02, 0.0, AssociationMode::Tum).is_empty());
        let p = associate(&gt, &est, 0.02, -100.0, AssociationMode::Tum);
        assert_eq!(p.len(), 5);
    }

    #[test]
    fn greedy_matches_brute_force_reference() {
        // Reference: evaluate_ate.py's quadratic algorithm, written naively.
        let mut state = 12345u64;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..20 {
            let mut gt: Vec<f64> = Vec::new();
            let mut est: Vec<f64> = Vec::new();
            let (mut a, mut b) = (0.0, 0.0);
            for _ in 0..60 {
                a += 0.005 + 0.03 * rnd();
                b += 0.005 + 0.03 * rnd();
                gt.push(a);
                est.push(b);
            }
            let mut cand = Vec::new();
            for (i, g) in gt.iter().enumerate() {
                for (j, e) in est.iter().enumerate() {
                    let d = (g - e).abs();
                    if d < 0.02 {
                        cand.push((d, i, j));
                    }
                }
            }
            cand.sort_by(|x, y| x.partial_cmp(y).unwrap());
            let (mut ug, mut ue) = (vec![false; 60], vec![false; 60]);
            let mut expected = Vec::new();
            for (_, i, j) in cand {
                if !ug[i] && !ue[j] {
                    ug[i] = true;
                    ue[j] = true;
                    expected.push((i, j));
                }
            }
            expected.sort();
            assert_eq!(
                associate(&gt, &est, 0.02, 0.0, AssociationMode::Tum),
                expected
            );
        }
    }

    #[test]
    fn evo_resolves_repeated_stamps_as_evo_does() {
        // gt (longer, searched into) repeats 1.0 at indices 1 and 2. From above or exactly, evo's
        // binary search lands on the last copy; from below on the first.
        let gt = [0.0, 1.0, 1.0, 2.0, 3.0];
        assert_eq!(
            associate(&gt, &[1.0, 2.5], 0.6, 0.0, AssociationMode::Evo),
            vec![(2, 0), (3, 1)]
        );
        assert_eq!(
            associate(&gt, &[1.004], 0.01, 0.0, AssociationMode::Evo),
            vec![(2, 0)]
        );
        assert_eq!(
            associate(&gt, &[0.996], 0.01, 0.0, AssociationMode::Evo),
            vec![(1, 0)]
        );
        // A repeat in the shorter trajectory is kept: both of its lines are paired.
        assert_eq!(
            associate(
                &[0.0, 1.0, 2.0],
                &[1.0, 1.0],
                0.01,
                0.0,
                AssociationMode::Evo
            ),
            vec![(1, 0), (1, 1)]
        );
    }
}
