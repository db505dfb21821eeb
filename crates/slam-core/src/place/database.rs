//! The keyframe database: an inverted index from each vocabulary word to the keyframes whose
//! BoW vector holds it, and the candidate queries of place recognition (ORB-SLAM2's
//! `KeyFrameDatabase`). Deterministic: keyframes are kept and visited in id order, never in
//! hash order.

use super::bow::{score_l1, BowVector};
use crate::data::KeyFrameId;

/// Share of the most shared words a keyframe needs to be scored (ORB-SLAM2: 0.8).
pub const MIN_COMMON_WORDS_RATIO: f64 = 0.8;
/// Share of the best accumulated score a covisibility group needs to be kept (ORB-SLAM2: 0.75).
pub const MIN_ACC_SCORE_RATIO: f64 = 0.75;
/// Covisible keyframes a candidate's score is accumulated over (ORB-SLAM2: 10).
pub const ACC_NEIGHBOURS: usize = 10;

/// Inverted index word -> keyframes (ids ascending).
#[derive(Clone, Debug, Default)]
pub struct KeyFrameDatabase {
    inverted: Vec<Vec<KeyFrameId>>,
}

/// A keyframe that shares words with a query, and its score.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// The keyframe.
    pub keyframe: KeyFrameId,
    /// Words it shares with the query.
    pub common_words: usize,
    /// L1 score of its BoW vector against the query's.
    pub score: f64,
}

impl KeyFrameDatabase {
    /// An empty database for a vocabulary of `words` words.
    pub fn new(words: usize) -> KeyFrameDatabase {
        KeyFrameDatabase {
            inverted: vec![Vec::new(); words],
        }
    }

    /// Indexes `kf` under every word of `bow`.
    pub fn add(&mut self, kf: KeyFrameId, bow: &BowVector) {
        for &(w, _) in bow.entries() {
            let list = &mut self.inverted[w as usize];
            if let Err(pos) = list.binary_search(&kf) {
                list.insert(pos, kf);
            }
        }
    }

    /// Removes `kf` (indexed with `bow`) from the database.
    pub fn erase(&mut self, kf: KeyFrameId, bow: &BowVector) {
        for &(w, _) in bow.entries() {
            let list = &mut self.inverted[w as usize];
            if let Ok(pos) = list.binary_search(&kf) {
                list.remove(pos);
            }
        }
    }

    /// Keyframes indexed under `word`.
    pub fn keyframes_with(&self, word: u32) -> &[KeyFrameId] {
        &self.inverted[word as usize]
    }

    /// Every keyframe sharing at least one word with `bow` and how many words it shares, by id.
    pub fn shared_words(&self, bow: &BowVector) -> Vec<(KeyFrameId, usize)> {
        let mut counts: Vec<u32> = Vec::new();
        for &(w, _) in bow.entries() {
            for kf in &self.inverted[w as usize] {
                let i = kf.index();
                if i >= counts.len() {
                    counts.resize(i + 1, 0);
                }
                counts[i] += 1;
            }
        }
        counts
            .iter()
            .enumerate()
            .filter(|(_, &c)| c > 0)
            .map(|(i, &c)| (KeyFrameId(i as u32), c as usize))
            .collect()
    }

    /// Scored keyframes among `shared` (from [`KeyFrameDatabase::shared_words`]) that share
    /// more than [`MIN_COMMON_WORDS_RATIO`] of the most shared words and pass `keep`.
    /// `bow_of` gives a keyframe's BoW vector, `None` for a keyframe culled since it was
    /// indexed (skipped as if erased).
    pub fn scored_candidates<'a>(
        shared: &[(KeyFrameId, usize)],
        bow: &BowVector,
        bow_of: impl Fn(KeyFrameId) -> Option<&'a BowVector>,
        keep: impl Fn(KeyFrameId) -> bool,
    ) -> Vec<Candidate> {
        let live: Vec<(KeyFrameId, usize, &BowVector)> = shared
            .iter()
            .filter(|(kf, _)| keep(*kf))
            .filter_map(|&(kf, c)| bow_of(kf).map(|b| (kf, c, b)))
            .collect();
        let max_common = live.iter().map(|&(_, c, _)| c).max().unwrap_or(0);
        let min_common = MIN_COMMON_WORDS_RATIO * max_common as f64;
        live.into_iter()
            .filter(|&(_, c, _)| c as f64 > min_common)
            .map(|(kf, c, b)| Candidate {
                keyframe: kf,
                common_words: c,
                score: score_l1(bow, b),
            })
            .collect()
    }

    /// Relocalization candidates for a frame with BoW vector `bow` (ORB-SLAM2's
    /// `DetectRelocalizationCandidates`): keyframes sharing enough words are scored, each score
    /// is accumulated over the candidate's [`ACC_NEIGHBOURS`] best covisible keyframes that are
    /// candidates too, and the best keyframe of every group within [`MIN_ACC_SCORE_RATIO`] of
    /// the best group is returned, best accumulated score first (ties by id).
    pub fn relocalization_candidates<'a>(
        &self,
        bow: &BowVector,
        bow_of: impl Fn(KeyFrameId) -> Option<&'a BowVector>,
        best_covisible: impl Fn(KeyFrameId, usize) -> Vec<KeyFrameId>,
    ) -> Vec<KeyFrameId> {
        let shared = self.shared_words(bow);
        let scored = Self::scored_candidates(&shared, bow, bow_of, |_| true);
        group_best(&scored, best_covisible)
    }

    /// Loop candidates for keyframe `kf` with BoW vector `bow` (ORB-SLAM2's
    /// `DetectLoopCandidates`): keyframes other than `kf` and not `connected` to it that share
    /// enough words are scored; those scoring at least `min_score` seed a group whose score is
    /// accumulated over the seed's best covisible keyframes that share enough words (whatever
    /// their score), and the best keyframe of every group within [`MIN_ACC_SCORE_RATIO`] of the
    /// best group is returned, best first (ties by id).
    pub fn loop_candidates<'a>(
        &self,
        kf: KeyFrameId,
        bow: &BowVector,
        min_score: f64,
        connected: impl Fn(KeyFrameId) -> bool,
        bow_of: impl Fn(KeyFrameId) -> Option<&'a BowVector>,
        best_covisible: impl Fn(KeyFrameId, usize) -> Vec<KeyFrameId>,
    ) -> Vec<KeyFrameId> {
        let shared = self.shared_words(bow);
        let scored = Self::scored_candidates(&shared, bow, bow_of, |k| k != kf && !connected(k));
        let seeds: Vec<Candidate> = scored
            .iter()
            .filter(|c| c.score >= min_score)
            .copied()
            .collect();
        group_best_of(&seeds, &scored, best_covisible)
    }
}

/// Accumulates each candidate's score over its best covisible keyframes that are candidates too
/// and returns the best keyframe of every group within [`MIN_ACC_SCORE_RATIO`] of the best
/// accumulated score, best first (ties by id), each keyframe once.
pub fn group_best(
    scored: &[Candidate],
    best_covisible: impl Fn(KeyFrameId, usize) -> Vec<KeyFrameId>,
) -> Vec<KeyFrameId> {
    group_best_of(scored, scored, best_covisible)
}

/// [`group_best`] where only `seeds` start groups and `scored` (sorted by id, a superset of
/// `seeds`) gives the scores of the neighbours accumulated into them.
pub fn group_best_of(
    seeds: &[Candidate],
    scored: &[Candidate],
    best_covisible: impl Fn(KeyFrameId, usize) -> Vec<KeyFrameId>,
) -> Vec<KeyFrameId> {
    let score_of = |kf: KeyFrameId| {
        scored
            .binary_search_by_key(&kf, |c| c.keyframe)
            .ok()
            .map(|i| scored[i].score)
    };
    debug_assert!(scored.windows(2).all(|w| w[0].keyframe < w[1].keyframe));
    let mut groups: Vec<(f64, KeyFrameId)> = seeds
        .iter()
        .map(|c| {
            let mut acc = c.score;
            let mut best = (c.score, c.keyframe);
            for n in best_covisible(c.keyframe, ACC_NEIGHBOURS) {
                if let Some(s) = score_of(n) {
                    acc += s;
                    if s > best.0 {
                        best = (s, n);
                    }
                }
            }
            (acc, best.1)
        })
        .collect();
    let best_acc = groups.iter().map(|g| g.0).fold(0.0, f64::max);
    groups.retain(|g| g.0 > MIN_ACC_SCORE_RATIO * best_acc);
    groups.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut out: Vec<KeyFrameId> = Vec::new();
    for (_, kf) in groups {
        if !out.contains(&kf) {
            out.push(kf);
        }
    }
    out
}
