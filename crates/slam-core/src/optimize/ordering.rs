//! Fill-reducing variable order for the envelope (profile) Cholesky of [`super::envelope`]:
//! reverse Cuthill-McKee (George & Liu, "Computer Solution of Large Sparse Positive Definite
//! Systems", 1981) from a pseudo-peripheral vertex.
//!
//! Why: ordered by keyframe id, a map that comes back to its start couples the last keyframes
//! to the first ones (loop edges, covisibility after the loop's map points were fused), so their
//! rows of the normal equations reach back to column 0 and the envelope holds most of the
//! matrix. Reverse Cuthill-McKee numbers the keyframes level by level from one end of the
//! graph, so a circuit becomes a band about twice as wide as its covisibility window.
//!
//! Everything is deterministic: ties are broken by vertex index.

use std::collections::VecDeque;

/// An undirected graph as sorted, duplicate-free adjacency lists without self loops.
#[derive(Clone, Debug, Default)]
pub(crate) struct Adjacency {
    neighbours: Vec<Vec<usize>>,
}

impl Adjacency {
    /// The graph on `n` vertices with the given edges (either orientation, repeats and self
    /// loops allowed).
    ///
    /// # Panics
    /// When an edge names a vertex `>= n` (a caller bug).
    pub(crate) fn from_edges(n: usize, edges: impl IntoIterator<Item = (usize, usize)>) -> Self {
        let mut neighbours = vec![Vec::new(); n];
        for (a, b) in edges {
            assert!(a < n && b < n, "edge ({a}, {b}) outside a graph of {n}");
            if a != b {
                neighbours[a].push(b);
                neighbours[b].push(a);
            }
        }
        for list in &mut neighbours {
            list.sort_unstable();
            list.dedup();
        }
        Adjacency { neighbours }
    }

    /// Number of vertices.
    pub(crate) fn len(&self) -> usize {
        self.neighbours.len()
    }

    fn degree(&self, v: usize) -> usize {
        self.neighbours[v].len()
    }

    /// The vertex order of reverse Cuthill-McKee: `order[p]` is the vertex numbered `p`.
    /// Connected components are numbered one after the other, each from a pseudo-peripheral
    /// vertex of minimum degree.
    pub(crate) fn reverse_cuthill_mckee(&self) -> Vec<usize> {
        let n = self.len();
        let mut order = Vec::with_capacity(n);
        let mut numbered = vec![false; n];
        let mut level = vec![usize::MAX; n];
        for seed in 0..n {
            if numbered[seed] {
                continue;
            }
            let start = self.pseudo_peripheral(seed, &mut level);
            let first = order.len();
            order.push(start);
            numbered[start] = true;
            let mut next = first;
            while next < order.len() {
                let v = order[next];
                next += 1;
                let mut fresh: Vec<usize> = self.neighbours[v]
                    .iter()
                    .copied()
                    .filter(|&w| !numbered[w])
                    .collect();
                fresh.sort_by_key(|&w| (self.degree(w), w));
                for w in fresh {
                    numbered[w] = true;
                    order.push(w);
                }
            }
        }
        order.reverse();
        order
    }

    /// A vertex of (nearly) maximal eccentricity in `seed`'s component: starting from the
    /// component's minimum-degree vertex, move to the minimum-degree vertex of the last
    /// breadth-first level as long as that makes the level structure deeper.
    fn pseudo_peripheral(&self, seed: usize, level: &mut [usize]) -> usize {
        let component = self.levels(seed, level);
        let mut v = *component
            .iter()
            .min_by_key(|&&w| (self.degree(w), w))
            .expect("the seed is in its component");
        let mut depth = 0;
        loop {
            let reached = self.levels(v, level);
            let last = reached.iter().map(|&w| level[w]).max().unwrap_or(0);
            if last <= depth && depth > 0 {
                return v;
            }
            depth = last;
            let candidate = *reached
                .iter()
                .filter(|&&w| level[w] == last)
                .min_by_key(|&&w| (self.degree(w), w))
                .expect("the last level is not empty");
            if candidate == v {
                return v;
            }
            v = candidate;
        }
    }

    /// Breadth-first levels from `root`: writes `level[w]` for every vertex reached and returns
    /// them in visiting order (other entries of `level` are reset first).
    fn levels(&self, root: usize, level: &mut [usize]) -> Vec<usize> {
        level.iter_mut().for_each(|l| *l = usize::MAX);
        let mut reached = vec![root];
        level[root] = 0;
        let mut queue = VecDeque::from([root]);
        while let Some(v) = queue.pop_front() {
            for &w in &self.neighbours[v] {
                if level[w] == usize::MAX {
                    level[w] = level[v] + 1;
                    reached.push(w);
                    queue.push_back(w);
                }
            }
        }
        reached
    }

    /// The envelope of the matrix with this sparsity pattern when vertex `v` is numbered
    /// `position[v]`: for each position, the smallest position it is coupled to (itself if
    /// none is smaller).
    pub(crate) fn envelope_first(&self, position: &[usize]) -> Vec<usize> {
        let mut first: Vec<usize> = (0..self.len()).collect();
        for (v, list) in self.neighbours.iter().enumerate() {
            let p = position[v];
            for &w in list {
                first[p] = first[p].min(position[w]);
            }
        }
        first
    }
}

/// The inverse of a permutation: `position[order[p]] == p`.
pub(crate) fn inverse_permutation(order: &[usize]) -> Vec<usize> {
    let mut position = vec![usize::MAX; order.len()];
    for (p, &v) in order.iter().enumerate() {
        position[v] = p;
    }
    position
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimize::test_scene::rng;
    use rand::seq::SliceRandom;

    /// `n` keyframes round a circuit, each coupled to the `w` before it, and the last `revisit`
    /// keyframes also coupled to the first ones they fly over again.
    fn circuit(n: usize, w: usize, revisit: usize) -> Vec<(usize, usize)> {
        let mut edges = Vec::new();
        for i in 0..n {
            for d in 1..=w.min(i) {
                edges.push((i, i - d));
            }
        }
        for k in 0..revisit {
            let i = n - revisit + k;
            for d in 0..w {
                edges.push((i, (k + d) % n));
            }
        }
        edges
    }

    /// Entries of the lower triangle inside an envelope (the storage of an envelope matrix).
    fn profile(first: &[usize]) -> usize {
        first.iter().enumerate().map(|(i, &f)| i - f + 1).sum()
    }

    /// Multiply-adds of the envelope Cholesky: entry `(i, j)` costs the overlap of rows `i`
    /// and `j` left of column `j`.
    fn factor_work(first: &[usize]) -> usize {
        (0..first.len())
            .map(|i| {
                (first[i]..=i)
                    .map(|j| j - first[i].max(first[j]).min(j))
                    .sum::<usize>()
            })
            .sum()
    }

    fn is_permutation(order: &[usize], n: usize) -> bool {
        let mut seen = vec![false; n];
        order.len() == n
            && order
                .iter()
                .all(|&v| v < n && !std::mem::replace(&mut seen[v], true))
    }

    #[test]
    fn a_circuit_that_returns_to_its_start_becomes_a_narrow_band() {
        let n = 400;
        let graph = Adjacency::from_edges(n, circuit(n, 12, 80));
        let identity: Vec<usize> = (0..n).collect();
        let natural = profile(&graph.envelope_first(&identity));
        let order = graph.reverse_cuthill_mckee();
        assert!(is_permutation(&order, n));
        let first = graph.envelope_first(&inverse_permutation(&order));
        let rcm = profile(&first);
        // The natural order stores the revisit's rows back to column 0, and factoring those
        // long rows against each other is most of the work.
        assert!(natural > 80 * 300, "natural profile {natural}");
        assert!(rcm * 2 < natural, "RCM profile {rcm} vs natural {natural}");
        let (work_natural, work_rcm) = (
            factor_work(&graph.envelope_first(&identity)),
            factor_work(&first),
        );
        assert!(
            work_rcm * 5 < work_natural,
            "RCM work {work_rcm} vs natural {work_natural}"
        );
        let bandwidth = first.iter().enumerate().map(|(i, &f)| i - f).max().unwrap();
        assert!(bandwidth <= 4 * 12, "bandwidth {bandwidth}");
    }

    #[test]
    fn recovers_a_band_from_a_shuffled_numbering() {
        let n = 200;
        let mut shuffle: Vec<usize> = (0..n).collect();
        shuffle.shuffle(&mut rng(4));
        let edges = circuit(n, 5, 0)
            .into_iter()
            .map(|(a, b)| (shuffle[a], shuffle[b]));
        let graph = Adjacency::from_edges(n, edges);
        let identity: Vec<usize> = (0..n).collect();
        let shuffled = profile(&graph.envelope_first(&identity));
        let order = graph.reverse_cuthill_mckee();
        let first = graph.envelope_first(&inverse_permutation(&order));
        let bandwidth = first.iter().enumerate().map(|(i, &f)| i - f).max().unwrap();
        assert_eq!(bandwidth, 5, "a path with window 5 has bandwidth 5");
        assert!(profile(&first) * 10 < shuffled);
    }

    #[test]
    fn numbers_every_component_and_isolated_vertices_deterministically() {
        // Two paths and two isolated vertices.
        let edges = [(0, 2), (2, 4), (1, 3), (3, 5), (5, 7)];
        let graph = Adjacency::from_edges(9, edges);
        let order = graph.reverse_cuthill_mckee();
        assert!(is_permutation(&order, 9));
        assert_eq!(order, graph.reverse_cuthill_mckee());
        let first = graph.envelope_first(&inverse_permutation(&order));
        assert!(first.iter().enumerate().all(|(i, &f)| i - f <= 1));
        assert!(Adjacency::from_edges(0, [])
            .reverse_cuthill_mckee()
            .is_empty());
    }
}
