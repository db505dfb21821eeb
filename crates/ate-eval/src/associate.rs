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

/// evaluate_ate.py's pairing: every (gt, est) pair with |t_gt - (t_est + offset)| <
/// max_difference is a candidate, candidates are taken in the order of `(|dt|, gt index, est
/// index)` (the order of evaluate_ate.py's sorted `(diff, a, b)` tuples on time-sorted stamps),
/// each stamp at most once.
///
/// Taking the candidates one by one is quadratic when many stamps share a window (n^2 pairs
/// for n stamps within max_difference of each other). This takes the same pairs in
/// O(n log n): with distinct keys the greedy matching is also what one gets by repeatedly
/// pairing two stamps that are each other's best free partner (an edge lighter than every
/// other edge at both of its ends is taken by the greedy, whatever is taken before it); such
/// pairs are found by following best partners from stamp to stamp until two point at each
/// other (at most one step per stamp and one per pair), and on a line a stamp's best free
/// partner is found by binary search among the free stamps nearest it on either side.
///
/// Identical to the quadratic original in every case (tested against it): the window's lower
/// edge is its `g > t_est + offset - max_difference` (as rounded), rounding ties of |dt|
/// included. Ground-truth stamps out of time order, which the original read with a binary
/// search meant for sorted stamps, are taken as evaluate_ate.py takes them: every pair inside
/// the window is a candidate. Non-finite stamps are never paired.
fn associate_tum(gt: &[f64], est: &[f64], max_difference: f64, offset: f64) -> Vec<(usize, usize)> {
    // |dt| < max_difference holds for no pair unless max_difference > 0 (a NaN neither).
    if max_difference.is_nan() || max_difference <= 0.0 {
        return Vec::new();
    }
    let te: Vec<f64> = est.iter().map(|&t| t + offset).collect();
    let (gt_t, gt_id) = in_time_order(gt);
    let (est_t, est_id) = in_time_order(&te);
    let window = Window {
        max_difference,
        gt: &gt_t,
        est: &est_t,
    };
    let mut sides = [Side::new(gt_id, gt.len()), Side::new(est_id, te.len())];
    // The chain of best partners: stamps alternately of either side, each the best free
    // partner of the one before it, with strictly decreasing keys; it never holds a stamp
    // twice, and ends in a pair when the last two point at each other.
    let mut chain: Vec<(usize, usize)> = Vec::new();
    let mut on_chain = [vec![false; sides[GT].len()], vec![false; sides[EST].len()]];
    let mut dead = on_chain.clone();
    let mut pairs = Vec::new();
    for start_side in [GT, EST] {
        for start in 0..sides[start_side].len() {
            if !sides[start_side].is_free(start) || dead[start_side][start] {
                continue;
            }
            chain.push((start_side, start));
            on_chain[start_side][start] = true;
            while let Some(&(side, pos)) = chain.last() {
                let other = 1 - side;
                let range = window.candidates(side, pos);
                let v = window.stamp(side, pos);
                match sides[other].best(window.stamps(other), v, range) {
                    None => {
                        // No free partner, now or later (stamps are only ever taken). Only the
                        // first stamp of a chain can be so: the others have the one before.
                        dead[side][pos] = true;
                        on_chain[side][pos] = false;
                        chain.pop();
                        assert!(chain.is_empty(), "association: inconsistent windows");
                    }
                    Some(b) => {
                        let n = chain.len();
                        if n >= 2 && chain[n - 2] == (other, b) {
                            let (g, e) = if side == GT { (pos, b) } else { (b, pos) };
                            pairs.push((sides[GT].id[g], sides[EST].id[e]));
                            sides[GT].take(g);
                            sides[EST].take(e);
                            (on_chain[GT][g], on_chain[EST][e]) = (false, false);
                            chain.truncate(n - 2);
                        } else {
                            // Keys fall strictly along the chain, so a stamp on it again would
                            // mean the two sides disagree on a window (a bug): never loop.
                            assert!(!on_chain[other][b], "association: inconsistent windows");
                            on_chain[other][b] = true;
                            chain.push((other, b));
                        }
                    }
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs
}

const GT: usize = 0;
const EST: usize = 1;

/// Whether `g` lies past the window's lower edge as the original found it: not among the stamps
/// `g <= te - max_difference` (all are past it when that edge is NaN).
#[inline]
fn past_lower_edge(g: f64, te: f64, max_difference: f64) -> bool {
    let edge = te - max_difference;
    edge.is_nan() || g > edge
}

/// |dt| of a pair, computed as evaluate_ate.py computes it (rounding is symmetric in sign, so
/// `|a - b| == |b - a|` for doubles).
#[inline]
fn gap(a: f64, b: f64) -> f64 {
    (a - b).abs()
}

/// Which stamps of the other side are candidate partners of a stamp: both sides' stamps in
/// time order, the window `-max_difference < g - te < max_difference` (as rounded) and its
/// lower edge `g > te - max_difference` (as rounded), as the quadratic original tests them.
struct Window<'a> {
    max_difference: f64,
    gt: &'a [f64],
    est: &'a [f64],
}

impl Window<'_> {
    fn stamps(&self, side: usize) -> &[f64] {
        if side == GT {
            self.gt
        } else {
            self.est
        }
    }

    fn stamp(&self, side: usize, pos: usize) -> f64 {
        self.stamps(side)[pos]
    }

    /// The positions of the other side that are candidates of `pos` of `side`: a range, since
    /// each condition holds on a range of the other side's sorted stamps.
    fn candidates(&self, side: usize, pos: usize) -> std::ops::Range<usize> {
        let d = self.max_difference;
        let v = self.stamp(side, pos);
        let inside = |p: f64| gap(p, v) < d;
        let (others, lower_edge) = if side == GT {
            // est stamps te with g > te - d: a prefix (te - d grows with te).
            (
                self.est,
                self.est.partition_point(|&te| past_lower_edge(v, te, d)),
            )
        } else {
            (self.gt, self.gt.len())
        };
        // Below v the window holds a suffix of the stamps below, above v a prefix.
        let lo = others.partition_point(|&p| p < v && !inside(p));
        let hi = others
            .partition_point(|&p| p < v || inside(p))
            .min(lower_edge);
        let lo = if side == EST {
            // gt stamps g with g > te - d: a suffix.
            lo.max(self.gt.partition_point(|&g| g <= v - d))
        } else {
            lo
        };
        lo..hi.max(lo)
    }
}

/// The finite stamps of a list in time order, and the index of each in the list (stably
/// sorted: equal stamps keep the list's order; sorted already, as the readers give them, the
/// list is only checked).
fn in_time_order(stamps: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let mut order: Vec<(f64, usize)> = stamps
        .iter()
        .enumerate()
        .filter(|(_, t)| t.is_finite())
        .map(|(i, &t)| (t, i))
        .collect();
    if !order.windows(2).all(|w| w[0].0 <= w[1].0) {
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    order.into_iter().unzip()
}

/// Which stamps of one side (in time order) are free, and the structures that find the best
/// free one near a stamp: the nearest free position before and after any position
/// (path-halving links) and the smallest caller index among the free positions of a range
/// (a segment tree).
struct Side {
    /// The index of each position in the caller's list.
    id: Vec<usize>,
    /// `next[k]`: a position >= k on the way to the first free one (`len` for none).
    next: Vec<usize>,
    /// `prev[k]`: one more than a position < k on the way to the last free one before k (0 for
    /// none).
    prev: Vec<usize>,
    /// Segment tree of caller indices, `usize::MAX` for taken positions; leaves from `leaves`.
    tree: Vec<usize>,
    leaves: usize,
    /// Position of each caller index (for the segment tree's answer).
    pos_of: Vec<usize>,
}

impl Side {
    /// Every position free; `id` as [`in_time_order`] gives it for a list of `n` stamps.
    fn new(id: Vec<usize>, n: usize) -> Side {
        let len = id.len();
        let leaves = len.next_power_of_two();
        let mut tree = vec![usize::MAX; 2 * leaves];
        let mut pos_of = vec![usize::MAX; n];
        for (k, &i) in id.iter().enumerate() {
            tree[leaves + k] = i;
            pos_of[i] = k;
        }
        for k in (1..leaves).rev() {
            tree[k] = tree[2 * k].min(tree[2 * k + 1]);
        }
        let n = len;
        Side {
            id,
            next: (0..=n).collect(),
            prev: (0..=n).collect(),
            tree,
            leaves,
            pos_of,
        }
    }

    fn len(&self) -> usize {
        self.id.len()
    }

    fn is_free(&self, k: usize) -> bool {
        self.tree[self.leaves + k] != usize::MAX
    }

    fn take(&mut self, k: usize) {
        self.next[k] = k + 1;
        self.prev[k + 1] = k;
        let mut node = self.leaves + k;
        self.tree[node] = usize::MAX;
        while node > 1 {
            node /= 2;
            self.tree[node] = self.tree[2 * node].min(self.tree[2 * node + 1]);
        }
    }

    /// The first free position >= k (`len` for none).
    fn next_free(&mut self, mut k: usize) -> usize {
        while self.next[k] != k {
            let up = self.next[self.next[k]];
            self.next[k] = up;
            k = up;
        }
        k
    }

    /// One more than the last free position < k (0 for none).
    fn prev_free(&mut self, mut k: usize) -> usize {
        while self.prev[k] != k {
            let down = self.prev[self.prev[k]];
            self.prev[k] = down;
            k = down;
        }
        k
    }

    /// The position of the smallest caller index among the free positions of `lo..hi`.
    fn min_id(&self, lo: usize, hi: usize) -> Option<usize> {
        let (mut l, mut r) = (lo + self.leaves, hi + self.leaves);
        let mut best = usize::MAX;
        while l < r {
            if l & 1 == 1 {
                best = best.min(self.tree[l]);
                l += 1;
            }
            if r & 1 == 1 {
                r -= 1;
                best = best.min(self.tree[r]);
            }
            l /= 2;
            r /= 2;
        }
        (best != usize::MAX).then(|| self.pos_of[best])
    }

    /// The best free partner among positions `range` of a stamp `v` of the other side: the
    /// smallest `(|dt|, caller index)`. |dt| falls towards `v` and grows away from it, so the
    /// least |dt| on either side of `v` is that of the free stamp nearest it, shared by a run
    /// of stamps found by binary search, of which the segment tree gives the smallest index.
    fn best(&mut self, t: &[f64], v: f64, range: std::ops::Range<usize>) -> Option<usize> {
        let (lo, hi) = (range.start, range.end);
        let split = lo + t[lo..hi].partition_point(|&p| p < v);
        let mut best: Option<(f64, usize, usize)> = None;
        let above = self.next_free(split);
        if above < hi {
            let d = gap(t[above], v);
            let end = above + t[above..hi].partition_point(|&p| gap(p, v) <= d);
            if let Some(k) = self.min_id(above, end) {
                best = Some((d, self.id[k], k));
            }
        }
        let below_end = self.prev_free(split);
        if below_end > lo {
            let below = below_end - 1;
            let d = gap(t[below], v);
            let start = lo + t[lo..below].partition_point(|&p| gap(p, v) > d);
            if let Some(k) = self.min_id(start, below + 1) {
                let id = self.id[k];
                if best.is_none_or(|(bd, bid, _)| d < bd || (d == bd && id < bid)) {
                    best = Some((d, id, k));
                }
            }
        }
        best.map(|b| b.2)
    }
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

    /// The quadratic original (until issue 45), kept as the oracle of the fast pairing: for
    /// each estimate, the ground-truth stamps in the window by binary search and a scan, then
    /// every candidate sorted by (|dt|, gt index, est index) and taken greedily.
    fn associate_tum_quadratic(
        gt: &[f64],
        est: &[f64],
        max_difference: f64,
        offset: f64,
    ) -> Vec<(usize, usize)> {
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

    /// The pairing from its definition, every pair tested: the oracle where the original's
    /// binary search does not apply (ground truth out of time order).
    fn associate_tum_every_pair(
        gt: &[f64],
        est: &[f64],
        max_difference: f64,
        offset: f64,
    ) -> Vec<(usize, usize)> {
        let mut candidates = Vec::new();
        for (j, &t) in est.iter().enumerate() {
            let te = t + offset;
            for (i, &g) in gt.iter().enumerate() {
                let d = (g - te).abs();
                if past_lower_edge(g, te, max_difference) && d < max_difference {
                    candidates.push((d, i, j));
                }
            }
        }
        candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        let (mut gt_used, mut est_used) = (vec![false; gt.len()], vec![false; est.len()]);
        let mut pairs = Vec::new();
        for (_, i, j) in candidates {
            if !gt_used[i] && !est_used[j] {
                (gt_used[i], est_used[j]) = (true, true);
                pairs.push((i, j));
            }
        }
        pairs.sort_unstable();
        pairs
    }

    /// A seeded generator (splitmix64).
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }

        /// Uniform in [0, 1).
        fn unit(&mut self) -> f64 {
            (self.next() >> 11) as f64 / (1u64 << 53) as f64
        }

        fn below(&mut self, n: usize) -> usize {
            (self.next() % n as u64) as usize
        }

        fn pick<T: Copy>(&mut self, list: &[T]) -> T {
            list[self.below(list.len())]
        }

        fn shuffle<T>(&mut self, v: &mut [T]) {
            for i in (1..v.len()).rev() {
                v.swap(i, self.below(i + 1));
            }
        }
    }

    fn sorted(mut v: Vec<f64>) -> Vec<f64> {
        v.sort_by(|a, b| a.total_cmp(b));
        v
    }

    /// One random case of kind `kind`: (gt, est, max_difference, offset), both lists sorted.
    fn case(rng: &mut Rng, kind: usize) -> (Vec<f64>, Vec<f64>, f64, f64) {
        let base = 1_305_031_102.0;
        match kind {
            // Cameras and motion capture: 30 and 100 Hz with jitter, an offset now and then.
            0 => {
                let (n, m) = (50 + rng.below(400), 50 + rng.below(400));
                let jitter = rng.pick(&[0.0, 0.002, 0.01]);
                let mut gt = Vec::new();
                for k in 0..n {
                    gt.push(base + k as f64 / 100.0 + jitter * rng.unit());
                }
                let mut est = Vec::new();
                for k in 0..m {
                    est.push(base + k as f64 / 30.0 + jitter * rng.unit());
                }
                let u = rng.unit();
                let offset = rng.pick(&[0.0, 0.0, -0.013, 0.05 * u]);
                (sorted(gt), sorted(est), 0.02, offset)
            }
            // Dense clusters: hundreds of stamps within one window, some outside it.
            1 => {
                let (n, m) = (1 + rng.below(300), 1 + rng.below(300));
                let width = rng.pick(&[1e-6, 1e-4, 0.005, 0.03]);
                let stamps = |rng: &mut Rng, k: usize| {
                    (0..k)
                        .map(|_| base + width * rng.unit() + rng.pick(&[0.0, 0.0, 0.0, 0.1]))
                        .collect::<Vec<f64>>()
                };
                let (gt, est) = (sorted(stamps(rng, n)), sorted(stamps(rng, m)));
                (gt, est, 0.02, 0.0)
            }
            // Repeated stamps on a grid: ties of |dt| everywhere.
            2 => {
                let step = rng.pick(&[0.005, 0.01, 1.0 / 64.0]);
                let cells = 1 + rng.below(30);
                let grid = |rng: &mut Rng| -> Vec<f64> {
                    let k = 1 + rng.below(120);
                    (0..k).map(|_| rng.below(cells) as f64 * step).collect()
                };
                let (gt, est) = (sorted(grid(rng)), sorted(grid(rng)));
                let d = rng.pick(&[0.005, 0.01, 0.02, 0.0200001, 1.0]);
                let offset = rng.pick(&[0.0, 0.005, -1.0 / 128.0]);
                (gt, est, d, offset)
            }
            // Rounding: stamps of every magnitude against windows much larger or smaller than
            // them, so that |dt| ties by rounding and the window's edges round.
            3 => {
                let scales = [1e-310, 1e-300, 1e-17, 1e-9, 1.0, 1e9, 1.3e9, 1e16, 1e300];
                let one = |rng: &mut Rng| -> f64 {
                    let s = rng.pick(&scales);
                    let sign = if rng.below(4) == 0 { -1.0 } else { 1.0 };
                    let u = rng.unit();
                    let v = sign * s * rng.pick(&[0.0, 1.0, 1.0 + f64::EPSILON, 1.5, u]);
                    if rng.below(3) == 0 {
                        v
                    } else {
                        s + v * 1e-16
                    }
                };
                let n = 1 + rng.below(60);
                let m = 1 + rng.below(60);
                let gt = sorted((0..n).map(|_| one(rng)).collect());
                let est = sorted((0..m).map(|_| one(rng)).collect());
                let d = rng.pick(&[1e-300, 1e-16, 1e-9, 2e-9, 0.02, 1.0, 2.0, 1e9, 1e300]);
                let offset = rng.pick(&[0.0, 0.0, 1e-9, -1e-17, 1.0]);
                (gt, est, d, offset)
            }
            // Values no reader gives: infinities at the ends of the ground truth, NaN and
            // infinities among the estimates, windows of 0, below 0, NaN and infinity.
            _ => {
                let specials = [f64::INFINITY, f64::NEG_INFINITY, f64::NAN, 0.0, -0.0];
                let mut gt: Vec<f64> = (0..1 + rng.below(40)).map(|_| rng.unit() * 0.2).collect();
                let mut est: Vec<f64> = (0..1 + rng.below(40)).map(|_| rng.unit() * 0.2).collect();
                for _ in 0..rng.below(4) {
                    gt.push(rng.pick(&[f64::INFINITY, f64::NEG_INFINITY, 1e308, -1e308]));
                    est.push(rng.pick(&specials));
                }
                let gt = sorted(gt);
                let est = sorted(est);
                let d = rng.pick(&[0.02, 0.0, -0.02, f64::NAN, f64::INFINITY, f64::MIN_POSITIVE]);
                let offset = rng.pick(&[0.0, 1e308, f64::NAN, 0.01]);
                (gt, est, d, offset)
            }
        }
    }

    #[test]
    fn the_fast_pairing_is_the_quadratic_one_on_seeded_random_inputs() {
        let mut rng = Rng(45);
        let mut pairs = 0;
        for n in 0..4000 {
            let kind = n % 5;
            let (gt, mut est, d, offset) = case(&mut rng, kind);
            let want = associate_tum_quadratic(&gt, &est, d, offset);
            let got = associate(&gt, &est, d, offset, AssociationMode::Tum);
            assert_eq!(
                got, want,
                "case {n} (kind {kind}): {gt:?} {est:?} {d} {offset}"
            );
            pairs += got.len();
            // On sorted stamps, the definition (every pair tested) agrees too.
            assert_eq!(
                got,
                associate_tum_every_pair(&gt, &est, d, offset),
                "case {n}"
            );
            // The original takes estimates in any order: so must this.
            rng.shuffle(&mut est);
            assert_eq!(
                associate(&gt, &est, d, offset, AssociationMode::Tum),
                associate_tum_quadratic(&gt, &est, d, offset),
                "case {n} shuffled"
            );
        }
        assert!(pairs > 100_000, "{pairs}");
    }

    #[test]
    fn thousands_of_stamps_in_one_window_pair_as_the_quadratic_original() {
        // 2000 + 2000 stamps within 10 ms of each other: 4 million candidate pairs, which the
        // original sorted; repeats and equal gaps included.
        let mut rng = Rng(46);
        let base = 1_305_031_102.0;
        for (n, m, width) in [(2000, 2000, 0.01), (2000, 1500, 1e-6), (3, 2500, 0.019)] {
            let gt = sorted((0..n).map(|_| base + width * rng.unit()).collect());
            let mut est = sorted((0..m).map(|_| base + width * rng.unit()).collect());
            est.extend_from_within(..m / 4);
            let est = sorted(est);
            let got = associate(&gt, &est, 0.02, 0.0, AssociationMode::Tum);
            assert_eq!(got, associate_tum_quadratic(&gt, &est, 0.02, 0.0));
            assert_eq!(got.len(), n.min(est.len()));
        }
    }

    #[test]
    fn ground_truth_out_of_time_order_is_paired_by_the_definition() {
        let mut rng = Rng(47);
        for n in 0..1000 {
            let kind = n % 4;
            let (mut gt, est, d, offset) = case(&mut rng, kind);
            rng.shuffle(&mut gt);
            assert_eq!(
                associate(&gt, &est, d, offset, AssociationMode::Tum),
                associate_tum_every_pair(&gt, &est, d, offset),
                "case {n}: {gt:?} {est:?} {d} {offset}"
            );
        }
    }

    #[test]
    fn ties_go_to_the_smaller_index_as_in_evaluate_ate_py() {
        // An estimate halfway between two ground-truth stamps: both 0.5 away, the first wins.
        assert_eq!(
            associate(&[0.0, 1.0], &[0.5], 0.6, 0.0, AssociationMode::Tum),
            vec![(0, 0)]
        );
        // Two estimates equally near one ground-truth stamp: the first wins.
        assert_eq!(
            associate(&[1.0], &[0.5, 1.5], 0.6, 0.0, AssociationMode::Tum),
            vec![(0, 0)]
        );
        // Repeated stamps pair in index order.
        assert_eq!(
            associate(
                &[1.0, 1.0, 1.0],
                &[1.0, 1.0],
                0.1,
                0.0,
                AssociationMode::Tum
            ),
            vec![(0, 0), (1, 1)]
        );
        // Rounding ties: 1 - 1e-17 and 1 - 2e-17 are both 1.0 as doubles, so both estimates are
        // 1.0 from the ground truth; the first index wins though the second is nearer.
        assert_eq!(
            associate(&[1.0], &[1e-17, 2e-17], 2.0, 0.0, AssociationMode::Tum),
            vec![(0, 0)]
        );
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
