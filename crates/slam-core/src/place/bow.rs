//! Bag-of-words vectors (DBoW2's `BowVector`) and their similarity, and the direct index
//! (`FeatureVector`): a frame's features grouped by vocabulary node a few levels above the
//! leaves, so that BoW-guided matching compares only features that fell under the same node.

/// Id of a vocabulary word (a leaf), dense from 0.
pub type WordId = u32;
/// Id of a vocabulary node (0 is the root).
pub type NodeId = u32;

/// The place-recognition view of one frame: its BoW vector and its direct index, computed once
/// (when a frame first needs it) and shared with the keyframe made from it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameBow {
    /// The L1-normalised BoW vector.
    pub bow: BowVector,
    /// Features grouped by their node at the direct-index level.
    pub features: FeatureVector,
}

/// A sparse bag-of-words vector: (word, weight) pairs sorted by word, without repeats.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BowVector {
    entries: Vec<(WordId, f64)>,
}

impl BowVector {
    /// Builds a vector from (word, weight) contributions in any order: weights of the same word
    /// add up (TF-IDF: one idf per occurrence), zero weights are dropped.
    pub fn from_contributions(mut c: Vec<(WordId, f64)>) -> BowVector {
        c.sort_by_key(|&(w, _)| w);
        let mut entries: Vec<(WordId, f64)> = Vec::with_capacity(c.len());
        for (w, x) in c {
            if x == 0.0 {
                continue;
            }
            match entries.last_mut() {
                Some((lw, lx)) if *lw == w => *lx += x,
                _ => entries.push((w, x)),
            }
        }
        BowVector { entries }
    }

    /// The (word, weight) pairs, sorted by word.
    pub fn entries(&self) -> &[(WordId, f64)] {
        &self.entries
    }

    /// Number of distinct words.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether no word has weight.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Scales the vector to unit L1 norm (DBoW2's normalisation for the L1 score).
    pub fn normalize_l1(&mut self) {
        let n: f64 = self.entries.iter().map(|(_, x)| x.abs()).sum();
        if n > 0.0 {
            for (_, x) in &mut self.entries {
                *x /= n;
            }
        }
    }

    /// Divides every weight by `d` (DBoW2's TF: weights over the number of features).
    pub fn scale(&mut self, d: f64) {
        for (_, x) in &mut self.entries {
            *x /= d;
        }
    }

    /// Words shared with `other`, counted by a merge of the two sorted lists.
    pub fn common_words(&self, other: &BowVector) -> usize {
        let (mut i, mut j, mut n) = (0, 0, 0);
        while i < self.entries.len() && j < other.entries.len() {
            match self.entries[i].0.cmp(&other.entries[j].0) {
                std::cmp::Ordering::Less => i += 1,
                std::cmp::Ordering::Greater => j += 1,
                std::cmp::Ordering::Equal => {
                    n += 1;
                    i += 1;
                    j += 1;
                }
            }
        }
        n
    }
}

/// DBoW2's L1 score of two L1-normalised vectors: 1 - |a - b|_1 / 2, in [0, 1] (1: the same
/// distribution of words). Only shared words need visiting: for unit-L1 vectors,
/// |a - b|_1 = 2 + sum over shared words of (|a_i - b_i| - |a_i| - |b_i|).
pub fn score_l1(a: &BowVector, b: &BowVector) -> f64 {
    let (a, b) = (&a.entries, &b.entries);
    let (mut i, mut j) = (0, 0);
    let mut s = 0.0;
    while i < a.len() && j < b.len() {
        match a[i].0.cmp(&b[j].0) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                let (x, y) = (a[i].1, b[j].1);
                s += (x - y).abs() - x.abs() - y.abs();
                i += 1;
                j += 1;
            }
        }
    }
    -s / 2.0
}

/// The direct index of a frame: for each vocabulary node at the direct-index level that any
/// feature fell under, the indices of those features (ascending), nodes sorted by id.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FeatureVector {
    nodes: Vec<(NodeId, Vec<usize>)>,
}

impl FeatureVector {
    /// Builds the index from (node, feature index) pairs in any order.
    pub fn from_pairs(mut pairs: Vec<(NodeId, usize)>) -> FeatureVector {
        pairs.sort_unstable();
        let mut nodes: Vec<(NodeId, Vec<usize>)> = Vec::new();
        for (n, f) in pairs {
            match nodes.last_mut() {
                Some((ln, fs)) if *ln == n => fs.push(f),
                _ => nodes.push((n, vec![f])),
            }
        }
        FeatureVector { nodes }
    }

    /// The (node, features) groups, sorted by node.
    pub fn nodes(&self) -> &[(NodeId, Vec<usize>)] {
        &self.nodes
    }

    /// Pairs of feature groups of `self` and `other` under the same node: the only features
    /// BoW-guided matching compares.
    pub fn common_nodes<'a>(
        &'a self,
        other: &'a FeatureVector,
    ) -> impl Iterator<Item = (&'a [usize], &'a [usize])> + 'a {
        let (a, b) = (&self.nodes, &other.nodes);
        let (mut i, mut j) = (0, 0);
        std::iter::from_fn(move || {
            while i < a.len() && j < b.len() {
                match a[i].0.cmp(&b[j].0) {
                    std::cmp::Ordering::Less => i += 1,
                    std::cmp::Ordering::Greater => j += 1,
                    std::cmp::Ordering::Equal => {
                        let r = (a[i].1.as_slice(), b[j].1.as_slice());
                        i += 1;
                        j += 1;
                        return Some(r);
                    }
                }
            }
            None
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(e: &[(WordId, f64)]) -> BowVector {
        let mut b = BowVector::from_contributions(e.to_vec());
        b.normalize_l1();
        b
    }

    #[test]
    fn contributions_add_up_and_sort() {
        let b = BowVector::from_contributions(vec![(5, 1.0), (2, 0.5), (5, 2.0), (9, 0.0)]);
        assert_eq!(b.entries(), &[(2, 0.5), (5, 3.0)]);
    }

    #[test]
    fn l1_score_is_one_for_itself_zero_for_disjoint_and_matches_the_definition() {
        let a = v(&[(1, 1.0), (2, 2.0), (7, 1.0)]);
        let b = v(&[(2, 1.0), (7, 3.0), (8, 1.0)]);
        let c = v(&[(3, 1.0)]);
        assert!((score_l1(&a, &a) - 1.0).abs() < 1e-12);
        assert_eq!(score_l1(&a, &c), 0.0);
        // Direct: 1 - 0.5 * sum |a_i - b_i| over the union of words.
        let dense = |x: &BowVector| {
            let mut d = [0.0; 10];
            for &(w, y) in x.entries() {
                d[w as usize] = y;
            }
            d
        };
        let (da, db) = (dense(&a), dense(&b));
        let l1: f64 = da.iter().zip(&db).map(|(x, y)| (x - y).abs()).sum();
        assert!((score_l1(&a, &b) - (1.0 - 0.5 * l1)).abs() < 1e-12);
        assert_eq!(a.common_words(&b), 2);
    }

    #[test]
    fn feature_vector_groups_and_pairs_common_nodes() {
        let a = FeatureVector::from_pairs(vec![(3, 4), (1, 0), (3, 2), (8, 1)]);
        let b = FeatureVector::from_pairs(vec![(3, 7), (8, 5), (9, 6)]);
        assert_eq!(a.nodes()[1], (3, vec![2, 4]));
        let common: Vec<_> = a.common_nodes(&b).collect();
        assert_eq!(
            common,
            vec![(&[2usize, 4][..], &[7usize][..]), (&[1][..], &[5][..])]
        );
    }
}
