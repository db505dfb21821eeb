//! Training a vocabulary on binary descriptors (DBoW2's hierarchical k-means, for binary data):
//! at every node the descriptors below it are split into k clusters, seeded by k-means++ (D^2
//! sampling with the Hamming distance, "k-medians++") and refined by k-majority (a centroid is
//! the bitwise majority of its members); each cluster becomes a child, down to L levels. Word
//! weights are then the idf of each word over the training images (TF-IDF), as DBoW2 sets them.
//!
//! Deterministic and parallel: every node draws from its own ChaCha8 stream, seeded from the
//! training seed and the node's path in the tree, so the vocabulary is the same bytes whatever
//! the thread count; subtrees are built in parallel (rayon).
//!
//! Where we differ from DBoW2: a node whose descriptors are all identical (or single) becomes a
//! leaf at once instead of a chain of one-child nodes down to level L, and k-majority stops
//! after [`TrainParams::max_iterations`] rounds if the assignment still changes.

use super::vocabulary::{NodeRecord, Vocabulary, VocabularyError, Weighting};
use crate::feature::{hamming, Descriptor};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Parameters of [`train`].
#[derive(Clone, Debug, PartialEq)]
pub struct TrainParams {
    /// Branching factor (ORB-SLAM2: 10).
    pub k: usize,
    /// Depth (ORB-SLAM2: 6).
    pub levels: usize,
    /// Word weighting (ORB-SLAM2: TF-IDF).
    pub weighting: Weighting,
    /// Seed of the k-means++ draws.
    pub seed: u64,
    /// Most k-majority rounds per node.
    pub max_iterations: usize,
}

impl Default for TrainParams {
    fn default() -> Self {
        TrainParams {
            k: 10,
            levels: 6,
            weighting: Weighting::TfIdf,
            seed: 0,
            max_iterations: 20,
        }
    }
}

struct Subtree {
    descriptor: Descriptor,
    children: Vec<Subtree>,
}

/// Trains a vocabulary on the descriptors of `images` (one list per training image: the idf
/// weights count images). `progress` is called (from any thread) with the number of descriptors
/// that just reached a leaf; the calls add up to the total number of descriptors.
pub fn train(
    images: &[Vec<Descriptor>],
    params: &TrainParams,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vocabulary, VocabularyError> {
    if params.k < 2 || params.levels < 1 {
        return Err(VocabularyError {
            line: 0,
            message: format!(
                "k = {}, L = {}: need k >= 2 and L >= 1",
                params.k, params.levels
            ),
        });
    }
    let all: Vec<Descriptor> = images.iter().flatten().copied().collect();
    if all.is_empty() {
        return Err(VocabularyError {
            line: 0,
            message: "no descriptors to train on".into(),
        });
    }
    let members: Vec<u32> = (0..all.len() as u32).collect();
    let root_children = split(&all, members, 1, params, mix(params.seed, 0x5eed), progress);
    // Flatten as DBoW2 numbers nodes: a node's children get consecutive ids, then each child's
    // subtree follows in turn.
    let mut records: Vec<NodeRecord> = Vec::new();
    flatten(&root_children, 0, &mut records);
    let mut voc = Vocabulary::from_nodes(params.k, params.levels, params.weighting, &records)?;
    // Word weights: idf = ln(N / n_i) over the training images (TF-IDF, IDF); 1 otherwise.
    let n_images = images.iter().filter(|i| !i.is_empty()).count() as f64;
    let mut images_with_word = vec![0u32; voc.word_count()];
    let direct = params.levels;
    let per_image: Vec<Vec<u32>> = images
        .par_iter()
        .map(|img| {
            let mut words: Vec<u32> = img.iter().map(|d| voc.quantize(d, direct).0).collect();
            words.sort_unstable();
            words.dedup();
            words
        })
        .collect();
    for words in &per_image {
        for &w in words {
            images_with_word[w as usize] += 1;
        }
    }
    let weights: Vec<f64> = images_with_word
        .iter()
        .map(|&ni| match params.weighting {
            Weighting::TfIdf | Weighting::Idf if ni > 0 => (n_images / f64::from(ni)).ln(),
            Weighting::TfIdf | Weighting::Idf => 0.0,
            Weighting::Tf | Weighting::Binary => 1.0,
        })
        .collect();
    let mut records = voc.node_records();
    let mut word = 0usize;
    for r in &mut records {
        if r.is_leaf {
            r.weight = weights[word];
            word += 1;
        }
    }
    voc = Vocabulary::from_nodes(params.k, params.levels, params.weighting, &records)?;
    Ok(voc)
}

fn flatten(children: &[Subtree], parent: u32, out: &mut Vec<NodeRecord>) {
    let first = out.len() as u32 + 1;
    for c in children {
        out.push(NodeRecord {
            parent,
            is_leaf: c.children.is_empty(),
            descriptor: c.descriptor,
            weight: 0.0,
        });
    }
    for (i, c) in children.iter().enumerate() {
        if !c.children.is_empty() {
            flatten(&c.children, first + i as u32, out);
        }
    }
}

/// SplitMix64 of `a` and `b`: the seed of a child's stream from its parent's and its index.
fn mix(a: u64, b: u64) -> u64 {
    let mut z = a ^ b.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The children of a node holding `members` at depth `level - 1`.
fn split(
    all: &[Descriptor],
    members: Vec<u32>,
    level: usize,
    params: &TrainParams,
    seed: u64,
    progress: &(dyn Fn(usize) + Sync),
) -> Vec<Subtree> {
    let clusters = cluster(all, &members, params, seed);
    clusters
        .into_par_iter()
        .enumerate()
        .map(|(i, (centroid, m))| {
            let distinct = m.iter().any(|&x| all[x as usize] != all[m[0] as usize]);
            let children = if level < params.levels && distinct {
                split(all, m, level + 1, params, mix(seed, i as u64 + 1), progress)
            } else {
                progress(m.len());
                Vec::new()
            };
            Subtree {
                descriptor: centroid,
                children,
            }
        })
        .collect()
}

/// k clusters (fewer when there are fewer distinct descriptors) of `members`: (centroid,
/// members), in seeding order, empty clusters dropped.
fn cluster(
    all: &[Descriptor],
    members: &[u32],
    params: &TrainParams,
    seed: u64,
) -> Vec<(Descriptor, Vec<u32>)> {
    let d = |i: u32| &all[i as usize];
    // Few descriptors: each distinct one is its own cluster (DBoW2 does the same).
    let mut distinct: Vec<Descriptor> = members.iter().map(|&i| *d(i)).collect();
    distinct.sort_unstable();
    distinct.dedup();
    let mut centers: Vec<Descriptor> = if distinct.len() <= params.k {
        distinct
    } else {
        seed_centers(all, members, params.k, seed)
    };
    let mut assign = vec![usize::MAX; members.len()];
    for _ in 0..params.max_iterations.max(1) {
        let mut changed = false;
        for (a, &m) in assign.iter_mut().zip(members) {
            let best = nearest(&centers, d(m));
            if *a != best {
                *a = best;
                changed = true;
            }
        }
        if !changed {
            break;
        }
        centers = (0..centers.len())
            .map(|c| {
                let mut counts = [0u32; 256];
                let mut n = 0u32;
                for (&a, &m) in assign.iter().zip(members) {
                    if a == c {
                        n += 1;
                        let x = d(m);
                        for (w, word) in x.iter().enumerate() {
                            let mut bits = *word;
                            while bits != 0 {
                                counts[w * 64 + bits.trailing_zeros() as usize] += 1;
                                bits &= bits - 1;
                            }
                        }
                    }
                }
                if n == 0 {
                    return centers[c];
                }
                // Majority, ties set (DBoW2: a bit is set when at least half the members have it).
                let half = n.div_ceil(2);
                let mut out = [0u64; 4];
                for (b, &cnt) in counts.iter().enumerate() {
                    if cnt >= half {
                        out[b / 64] |= 1 << (b % 64);
                    }
                }
                out
            })
            .collect();
    }
    let mut out: Vec<(Descriptor, Vec<u32>)> = centers.iter().map(|&c| (c, Vec::new())).collect();
    for (&a, &m) in assign.iter().zip(members) {
        out[a].1.push(m);
    }
    out.retain(|(_, m)| !m.is_empty());
    out
}

fn nearest(centers: &[Descriptor], x: &Descriptor) -> usize {
    let mut best = 0;
    let mut best_d = u32::MAX;
    for (i, c) in centers.iter().enumerate() {
        let dist = hamming(c, x);
        if dist < best_d {
            best_d = dist;
            best = i;
        }
    }
    best
}

/// k-means++ seeding with the Hamming distance: the first center uniformly, each next one with
/// probability proportional to the squared distance to the nearest center chosen so far.
fn seed_centers(all: &[Descriptor], members: &[u32], k: usize, seed: u64) -> Vec<Descriptor> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let d = |i: u32| &all[i as usize];
    let mut centers = vec![*d(members[rng.random_range(0..members.len())])];
    let mut dist2: Vec<f64> = members
        .iter()
        .map(|&m| f64::from(hamming(d(m), &centers[0])).powi(2))
        .collect();
    while centers.len() < k {
        let total: f64 = dist2.iter().sum();
        if total <= 0.0 {
            break;
        }
        let mut r = rng.random::<f64>() * total;
        let mut pick = members.len() - 1;
        for (i, &x) in dist2.iter().enumerate() {
            if r < x {
                pick = i;
                break;
            }
            r -= x;
        }
        let c = *d(members[pick]);
        centers.push(c);
        for (dd, &m) in dist2.iter_mut().zip(members) {
            let e = f64::from(hamming(d(m), &c)).powi(2);
            if e < *dd {
                *dd = e;
            }
        }
    }
    centers
}
