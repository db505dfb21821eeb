//! Quadtree distribution of corners (ORB-SLAM2's `DistributeOctTree`): the detection area is
//! split into nodes, every node holding more than one corner is split in four, until there are
//! as many nodes as wanted corners; each node then keeps its strongest corner. Corners end up
//! spread over the whole image instead of piling up on the most textured part.
//!
//! Differences from ORB-SLAM2, deliberate: nodes are split in a fixed order (most populated
//! first, ties by position in the node list) instead of pointer order, so the result is
//! deterministic; when the last round of splits overshoots the target, the weakest node winners
//! are dropped so a level never returns more than it was asked for.

use super::fast::Corner;

/// A node of the quadtree: a half-open box and the range of its corners in the permutation.
#[derive(Clone, Copy, Debug)]
struct Node {
    x0: f32,
    y0: f32,
    x1: f32,
    y1: f32,
    start: usize,
    end: usize,
}

impl Node {
    fn len(&self) -> usize {
        self.end - self.start
    }

    /// Whether splitting can still separate corners (distinct integer positions cannot share a
    /// box narrower than a pixel in both directions).
    fn splittable(&self) -> bool {
        self.len() > 1 && (self.x1 - self.x0 >= 1.0 || self.y1 - self.y0 >= 1.0)
    }
}

/// A corner as the quadtree moves it around: its position as the box tests read it, its score
/// and its index in the caller's slice. Carrying these instead of the index alone makes every
/// pass over a node a linear scan (no lookup of the corner per visit, which dominated on densely
/// textured images with tens of thousands of corners per frame).
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    x: f32,
    y: f32,
    index: u32,
    score: u8,
}

/// Reusable buffers of [`distribute`].
#[derive(Clone, Debug, Default)]
pub struct QuadScratch {
    perm: Vec<Entry>,
    tmp: Vec<Entry>,
    nodes: Vec<Node>,
    order: Vec<usize>,
}

/// Chooses at most `target` of `corners` (positions inside the box `[x0, x1) x [y0, y1)`)
/// spread evenly by a quadtree, and writes their indices into `out` (sorted ascending).
///
/// # Panics
/// With more than `u32::MAX` corners.
pub fn distribute(
    corners: &[Corner],
    bounds: (f32, f32, f32, f32),
    target: usize,
    scratch: &mut QuadScratch,
    out: &mut Vec<usize>,
) {
    out.clear();
    if corners.is_empty() || target == 0 {
        return;
    }
    assert!(u32::try_from(corners.len()).is_ok(), "too many corners");
    let (bx0, by0, bx1, by1) = bounds;
    let bw = (bx1 - bx0).max(1.0);
    let bh = (by1 - by0).max(1.0);
    // Root nodes: as many square-ish columns as the aspect ratio asks for.
    let n_ini = ((bw / bh).round() as usize).max(1);
    let hx = bw / n_ini as f32;
    // `(v.floor().max(0.0) as usize)` without the floor: the cast truncates toward zero and
    // saturates below at 0 (NaN included), which is the same integer for every `v`.
    let root_of = |e: &Entry| (((e.x - bx0) / hx) as usize).min(n_ini - 1);
    scratch.tmp.clear();
    scratch
        .tmp
        .extend(corners.iter().enumerate().map(|(i, c)| Entry {
            x: c.x as f32,
            y: c.y as f32,
            index: i as u32,
            score: c.score,
        }));
    let mut counts = vec![0usize; n_ini + 1];
    for e in &scratch.tmp {
        counts[root_of(e) + 1] += 1;
    }
    for i in 0..n_ini {
        counts[i + 1] += counts[i];
    }
    scratch.perm.clear();
    scratch.perm.resize(corners.len(), Entry::default());
    let mut fill = counts.clone();
    for e in &scratch.tmp {
        let r = root_of(e);
        scratch.perm[fill[r]] = *e;
        fill[r] += 1;
    }
    scratch.nodes.clear();
    for r in 0..n_ini {
        if counts[r + 1] > counts[r] {
            scratch.nodes.push(Node {
                x0: bx0 + hx * r as f32,
                y0: by0,
                x1: bx0 + hx * (r + 1) as f32,
                y1: by0 + bh,
                start: counts[r],
                end: counts[r + 1],
            });
        }
    }

    while scratch.nodes.len() < target {
        scratch.order.clear();
        scratch
            .order
            .extend((0..scratch.nodes.len()).filter(|&i| scratch.nodes[i].splittable()));
        if scratch.order.is_empty() {
            break;
        }
        let all_fit = scratch.nodes.len() + 3 * scratch.order.len() <= target;
        if !all_fit {
            // Final round: split the most populated nodes first until the target is reached.
            let nodes = &scratch.nodes;
            scratch
                .order
                .sort_by(|&a, &b| nodes[b].len().cmp(&nodes[a].len()).then(a.cmp(&b)));
        }
        for k in 0..scratch.order.len() {
            let i = scratch.order[k];
            split(i, scratch);
            if !all_fit && scratch.nodes.len() >= target {
                break;
            }
        }
    }

    // Each node keeps its strongest corner (the first in raster order on ties).
    for node in &scratch.nodes {
        let entries = &scratch.perm[node.start..node.end];
        let mut best = entries[0];
        for e in &entries[1..] {
            if e.score > best.score || (e.score == best.score && e.index < best.index) {
                best = *e;
            }
        }
        out.push(best.index as usize);
    }
    if out.len() > target {
        out.sort_by(|&a, &b| corners[b].score.cmp(&corners[a].score).then(a.cmp(&b)));
        out.truncate(target);
    }
    out.sort_unstable();
}

/// Splits node `i` in four; the first non-empty child replaces it, the others are appended.
/// The corners keep their relative order within each child.
fn split(i: usize, scratch: &mut QuadScratch) {
    let n = scratch.nodes[i];
    let mx = 0.5 * (n.x0 + n.x1);
    let my = 0.5 * (n.y0 + n.y1);
    let quad = |e: &Entry| (e.x >= mx) as usize + 2 * ((e.y >= my) as usize);
    let mut counts = [0usize; 5];
    for e in &scratch.perm[n.start..n.end] {
        counts[quad(e) + 1] += 1;
    }
    for q in 0..4 {
        counts[q + 1] += counts[q];
    }
    scratch.tmp.clear();
    scratch.tmp.resize(n.len(), Entry::default());
    let mut fill = counts;
    for e in &scratch.perm[n.start..n.end] {
        let q = quad(e);
        scratch.tmp[fill[q]] = *e;
        fill[q] += 1;
    }
    scratch.perm[n.start..n.end].copy_from_slice(&scratch.tmp);
    let boxes = [
        (n.x0, n.y0, mx, my),
        (mx, n.y0, n.x1, my),
        (n.x0, my, mx, n.y1),
        (mx, my, n.x1, n.y1),
    ];
    let mut replaced = false;
    for q in 0..4 {
        if counts[q + 1] == counts[q] {
            continue;
        }
        let (x0, y0, x1, y1) = boxes[q];
        let child = Node {
            x0,
            y0,
            x1,
            y1,
            start: n.start + counts[q],
            end: n.start + counts[q + 1],
        };
        if replaced {
            scratch.nodes.push(child);
        } else {
            scratch.nodes[i] = child;
            replaced = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn corners(n: usize, seed: u64) -> Vec<Corner> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut v: Vec<Corner> = (0..n)
            .map(|_| {
                // Dense cluster in the top-left corner plus a sparse spread elsewhere.
                let (x, y) = if rng.random_bool(0.8) {
                    (rng.random_range(20..120), rng.random_range(20..100))
                } else {
                    (rng.random_range(20..620), rng.random_range(20..460))
                };
                Corner {
                    x,
                    y,
                    score: rng.random_range(7..100),
                }
            })
            .collect();
        v.sort();
        v.dedup_by_key(|c| (c.x, c.y));
        v
    }

    #[test]
    fn keeps_target_count_and_spreads_out() {
        let cs = corners(5000, 1);
        let mut out = Vec::new();
        let mut scratch = QuadScratch::default();
        distribute(&cs, (19.0, 19.0, 621.0, 461.0), 200, &mut scratch, &mut out);
        assert_eq!(out.len(), 200);
        assert!(out.windows(2).all(|w| w[0] < w[1]));
        // The dense cluster covers ~4 % of the area and holds 80 % of the corners; after the
        // quadtree it must hold far fewer than 80 % of the kept ones.
        let in_cluster = out
            .iter()
            .filter(|&&i| cs[i].x < 120 && cs[i].y < 100)
            .count();
        assert!(in_cluster < 100, "{in_cluster} of 200 in the cluster");
        // Every quarter of the image is represented.
        for (qx, qy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let n = out
                .iter()
                .filter(|&&i| (cs[i].x >= 320) as i32 == qx && (cs[i].y >= 240) as i32 == qy)
                .count();
            assert!(n > 10, "quarter ({qx},{qy}) has {n}");
        }
        // Deterministic.
        let mut again = Vec::new();
        distribute(
            &cs,
            (19.0, 19.0, 621.0, 461.0),
            200,
            &mut scratch,
            &mut again,
        );
        assert_eq!(out, again);
    }

    #[test]
    fn fewer_corners_than_target_keeps_all() {
        let cs = corners(50, 2);
        let mut out = Vec::new();
        distribute(
            &cs,
            (19.0, 19.0, 621.0, 461.0),
            1000,
            &mut QuadScratch::default(),
            &mut out,
        );
        assert_eq!(out, (0..cs.len()).collect::<Vec<_>>());
    }

    #[test]
    fn keeps_strongest_in_a_node() {
        let cs = vec![
            Corner {
                y: 30,
                x: 30,
                score: 10,
            },
            Corner {
                y: 31,
                x: 31,
                score: 50,
            },
            Corner {
                y: 32,
                x: 30,
                score: 20,
            },
        ];
        let mut out = Vec::new();
        distribute(
            &cs,
            (0.0, 0.0, 100.0, 100.0),
            1,
            &mut QuadScratch::default(),
            &mut out,
        );
        assert_eq!(out, vec![1]);
    }

    /// Buffers of [`distribute_reference`].
    #[derive(Default)]
    struct RefScratch {
        perm: Vec<usize>,
        tmp: Vec<usize>,
        nodes: Vec<Node>,
        order: Vec<usize>,
    }

    /// The implementation before corners were carried by value (per-visit lookups of
    /// `corners[p]`): the reference the faster one must reproduce exactly.
    /// Chooses at most `target` of `corners` (positions inside the box `[x0, x1) x [y0, y1)`)
    /// spread evenly by a quadtree, and writes their indices into `out` (sorted ascending).
    fn distribute_reference(
        corners: &[Corner],
        bounds: (f32, f32, f32, f32),
        target: usize,
        scratch: &mut RefScratch,
        out: &mut Vec<usize>,
    ) {
        out.clear();
        if corners.is_empty() || target == 0 {
            return;
        }
        let (bx0, by0, bx1, by1) = bounds;
        let bw = (bx1 - bx0).max(1.0);
        let bh = (by1 - by0).max(1.0);
        // Root nodes: as many square-ish columns as the aspect ratio asks for.
        let n_ini = ((bw / bh).round() as usize).max(1);
        let hx = bw / n_ini as f32;
        let root_of =
            |c: &Corner| (((c.x as f32 - bx0) / hx).floor().max(0.0) as usize).min(n_ini - 1);
        let mut counts = vec![0usize; n_ini + 1];
        for c in corners {
            counts[root_of(c) + 1] += 1;
        }
        for i in 0..n_ini {
            counts[i + 1] += counts[i];
        }
        scratch.perm.clear();
        scratch.perm.resize(corners.len(), 0);
        let mut fill = counts.clone();
        for (i, c) in corners.iter().enumerate() {
            let r = root_of(c);
            scratch.perm[fill[r]] = i;
            fill[r] += 1;
        }
        scratch.nodes.clear();
        for r in 0..n_ini {
            if counts[r + 1] > counts[r] {
                scratch.nodes.push(Node {
                    x0: bx0 + hx * r as f32,
                    y0: by0,
                    x1: bx0 + hx * (r + 1) as f32,
                    y1: by0 + bh,
                    start: counts[r],
                    end: counts[r + 1],
                });
            }
        }

        while scratch.nodes.len() < target {
            scratch.order.clear();
            scratch
                .order
                .extend((0..scratch.nodes.len()).filter(|&i| scratch.nodes[i].splittable()));
            if scratch.order.is_empty() {
                break;
            }
            let all_fit = scratch.nodes.len() + 3 * scratch.order.len() <= target;
            if !all_fit {
                // Final round: split the most populated nodes first until the target is reached.
                let nodes = &scratch.nodes;
                scratch
                    .order
                    .sort_by(|&a, &b| nodes[b].len().cmp(&nodes[a].len()).then(a.cmp(&b)));
            }
            for k in 0..scratch.order.len() {
                let i = scratch.order[k];
                split_reference(i, corners, scratch);
                if !all_fit && scratch.nodes.len() >= target {
                    break;
                }
            }
        }

        // Each node keeps its strongest corner (the first in raster order on ties).
        for node in &scratch.nodes {
            let mut best = scratch.perm[node.start];
            for &i in &scratch.perm[node.start + 1..node.end] {
                if corners[i].score > corners[best].score
                    || (corners[i].score == corners[best].score && i < best)
                {
                    best = i;
                }
            }
            out.push(best);
        }
        if out.len() > target {
            out.sort_by(|&a, &b| corners[b].score.cmp(&corners[a].score).then(a.cmp(&b)));
            out.truncate(target);
        }
        out.sort_unstable();
    }

    /// Splits node `i` in four; the first non-empty child replaces it, the others are appended.
    fn split_reference(i: usize, corners: &[Corner], scratch: &mut RefScratch) {
        let n = scratch.nodes[i];
        let mx = 0.5 * (n.x0 + n.x1);
        let my = 0.5 * (n.y0 + n.y1);
        let quad = |c: &Corner| (c.x as f32 >= mx) as usize + 2 * ((c.y as f32 >= my) as usize);
        let mut counts = [0usize; 5];
        for &p in &scratch.perm[n.start..n.end] {
            counts[quad(&corners[p]) + 1] += 1;
        }
        for q in 0..4 {
            counts[q + 1] += counts[q];
        }
        scratch.tmp.clear();
        scratch.tmp.resize(n.len(), 0);
        let mut fill = counts;
        for &p in &scratch.perm[n.start..n.end] {
            let q = quad(&corners[p]);
            scratch.tmp[fill[q]] = p;
            fill[q] += 1;
        }
        scratch.perm[n.start..n.end].copy_from_slice(&scratch.tmp);
        let boxes = [
            (n.x0, n.y0, mx, my),
            (mx, n.y0, n.x1, my),
            (n.x0, my, mx, n.y1),
            (mx, my, n.x1, n.y1),
        ];
        let mut replaced = false;
        for q in 0..4 {
            if counts[q + 1] == counts[q] {
                continue;
            }
            let (x0, y0, x1, y1) = boxes[q];
            let child = Node {
                x0,
                y0,
                x1,
                y1,
                start: n.start + counts[q],
                end: n.start + counts[q + 1],
            };
            if replaced {
                scratch.nodes.push(child);
            } else {
                scratch.nodes[i] = child;
                replaced = true;
            }
        }
    }

    #[test]
    fn equals_the_reference_implementation() {
        let mut scratch = QuadScratch::default();
        let mut ref_scratch = RefScratch::default();
        for seed in 0..40u64 {
            let mut rng = ChaCha8Rng::seed_from_u64(1000 + seed);
            // Sparse to very dense (every pixel a corner in places), few to many score levels.
            let n = [10, 300, 3000, 20000][seed as usize % 4];
            let levels = [3, 255][seed as usize % 2];
            let mut cs: Vec<Corner> = (0..n)
                .map(|_| Corner {
                    x: rng.random_range(19..621),
                    y: rng.random_range(19..461),
                    score: rng.random_range(7..7 + levels.min(248)) as u8,
                })
                .collect();
            cs.sort();
            cs.dedup_by_key(|c| (c.x, c.y));
            for (bounds, target) in [
                ((19.0, 19.0, 621.0, 461.0), 217),
                ((16.0, 16.0, 624.0, 464.0), 1000),
                ((19.0, 19.0, 300.0, 461.0), 5),
                ((19.0, 19.0, 621.0, 461.0), 1),
            ] {
                let (mut got, mut want) = (Vec::new(), Vec::new());
                distribute(&cs, bounds, target, &mut scratch, &mut got);
                distribute_reference(&cs, bounds, target, &mut ref_scratch, &mut want);
                assert_eq!(got, want, "seed {seed}, {n} corners, target {target}");
            }
        }
    }
}
