//! A hierarchical vocabulary of binary ORB words (DBoW2's model, as ORB-SLAM2 uses it): a tree
//! of k-ary branchings, L levels deep, whose nodes carry a descriptor (the k-majority centroid
//! of the descriptors below it) and whose leaves are the words, each with a weight (its idf for
//! TF-IDF). A descriptor goes down the tree to the child with the smallest Hamming distance.
//!
//! Text form (DBoW2's, the one of ORB-SLAM2's `ORBvoc.txt`): a header line `k L scoring
//! weighting`, then one line per node except the root, in id order: `parent_id is_leaf b0 ...
//! b31 weight` (32 descriptor bytes as integers). Binary form (ours): the same nodes packed
//! little-endian behind a magic and a checksum, loading a 10^6-word vocabulary in a fraction of
//! the text's parse time. Both are parsed from and written to memory here; files are the CLI's.
//!
//! Note on ORBvoc.txt: it was trained on descriptors of OpenCV's learned BRIEF pattern, and our
//! extractor uses a pattern of its own (see `feature::pattern`), so its words partition our
//! descriptor space without the correspondence they had in ORB-SLAM2: it still quantises
//! consistently (nearby descriptors share words), but a vocabulary trained on our own
//! descriptors (`noisefree vocab train`) fits them better.

use super::bow::{BowVector, FeatureVector, NodeId, WordId};
use crate::feature::{hamming, Descriptor};
use crate::hash::fnv1a;
use std::fmt;

/// How word weights are computed (DBoW2's `WeightingType`, same numbering).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weighting {
    /// Term frequency times inverse document frequency (ORB-SLAM2's choice, code 0).
    TfIdf,
    /// Term frequency (code 1).
    Tf,
    /// Inverse document frequency (code 2).
    Idf,
    /// 1 for every word present (code 3).
    Binary,
}

impl Weighting {
    fn from_code(c: i64) -> Option<Weighting> {
        Some(match c {
            0 => Weighting::TfIdf,
            1 => Weighting::Tf,
            2 => Weighting::Idf,
            3 => Weighting::Binary,
            _ => return None,
        })
    }

    /// DBoW2's code.
    pub fn code(self) -> u8 {
        match self {
            Weighting::TfIdf => 0,
            Weighting::Tf => 1,
            Weighting::Idf => 2,
            Weighting::Binary => 3,
        }
    }
}

/// DBoW2's code of the L1-norm score, the only scoring implemented (ORB-SLAM2's).
pub const SCORING_L1: u8 = 0;

/// Why a vocabulary could not be read.
#[derive(Clone, Debug, PartialEq)]
pub struct VocabularyError {
    /// 1-based line of the text form (0 for the binary form or the whole file).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for VocabularyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "line {}: {}", self.line, self.message)
        } else {
            f.write_str(&self.message)
        }
    }
}

impl std::error::Error for VocabularyError {}

fn err(line: usize, message: impl Into<String>) -> VocabularyError {
    VocabularyError {
        line,
        message: message.into(),
    }
}

/// One node as the text and binary forms list it (the root, node 0, is implicit).
#[derive(Clone, Debug, PartialEq)]
pub struct NodeRecord {
    /// Parent node id (0 = root).
    pub parent: NodeId,
    /// Whether the node is a leaf (a word).
    pub is_leaf: bool,
    /// Centroid descriptor.
    pub descriptor: Descriptor,
    /// Word weight (leaves; 0 on inner nodes).
    pub weight: f64,
}

/// A vocabulary tree with its words.
#[derive(Clone, Debug, PartialEq)]
pub struct Vocabulary {
    k: usize,
    levels: usize,
    weighting: Weighting,
    /// Per node (0 = root): parent, centroid, weight, word id (leaves) and children (CSR).
    parent: Vec<NodeId>,
    descriptor: Vec<Descriptor>,
    weight: Vec<f64>,
    word_of_node: Vec<Option<WordId>>,
    node_of_word: Vec<NodeId>,
    child_start: Vec<u32>,
    children: Vec<NodeId>,
    /// Depth of each node (root 0).
    depth: Vec<u8>,
}

/// Levels above the leaves at which ORB-SLAM2 groups features for its direct index.
pub const DIRECT_INDEX_LEVELS_UP: usize = 4;

impl Vocabulary {
    /// Builds a vocabulary from its node list (node ids 1.. in order), checking the tree. An
    /// error about node `id` names line `id + 1`, where DBoW2's text form has it.
    pub fn from_nodes(
        k: usize,
        levels: usize,
        weighting: Weighting,
        nodes: &[NodeRecord],
    ) -> Result<Vocabulary, VocabularyError> {
        Self::build(k, levels, weighting, nodes)
            .map_err(|(id, m)| err(id.map_or(0, |id| id as usize + 1), m))
    }

    /// [`Vocabulary::from_nodes`], its errors naming the node id they are about.
    fn build(
        k: usize,
        levels: usize,
        weighting: Weighting,
        nodes: &[NodeRecord],
    ) -> Result<Vocabulary, (Option<NodeId>, String)> {
        let err = |id: Option<usize>, m: String| (id.map(|i| i as NodeId), m);
        if k < 2 || levels < 1 {
            return Err(err(
                None,
                format!("k = {k}, L = {levels}: need k >= 2 and L >= 1"),
            ));
        }
        let n = nodes.len() + 1;
        if n > u32::MAX as usize {
            return Err(err(None, "too many nodes".into()));
        }
        let mut parent = vec![0; n];
        let mut descriptor = vec![[0u64; 4]; n];
        let mut weight = vec![0.0; n];
        let mut is_leaf = vec![false; n];
        let mut depth = vec![0u8; n];
        let mut n_children = vec![0u32; n];
        for (i, r) in nodes.iter().enumerate() {
            let id = i + 1;
            let p = r.parent as usize;
            // A parent comes before its children (DBoW2 writes nodes as it creates them).
            if p >= id {
                return Err(err(
                    Some(id),
                    format!("node {id} has parent {p}, which is not an earlier node"),
                ));
            }
            if is_leaf[p] {
                return Err(err(
                    Some(id),
                    format!("node {id} has a leaf ({p}) as parent"),
                ));
            }
            if !r.weight.is_finite() || r.weight < 0.0 {
                return Err(err(
                    Some(id),
                    format!("weight {} is not a finite number >= 0", r.weight),
                ));
            }
            let d = depth[p] as usize + 1;
            if d > levels {
                return Err(err(
                    Some(id),
                    format!("node {id} is deeper ({d}) than L = {levels}"),
                ));
            }
            parent[id] = r.parent;
            descriptor[id] = r.descriptor;
            weight[id] = r.weight;
            is_leaf[id] = r.is_leaf;
            depth[id] = d as u8;
            n_children[p] += 1;
        }
        if n == 1 {
            return Err(err(None, "the vocabulary has no node".into()));
        }
        let mut child_start = vec![0u32; n + 1];
        for i in 0..n {
            child_start[i + 1] = child_start[i] + n_children[i];
        }
        let mut fill = child_start.clone();
        let mut children = vec![0; n - 1];
        for (id, &p) in parent.iter().enumerate().skip(1) {
            let p = p as usize;
            children[fill[p] as usize] = id as NodeId;
            fill[p] += 1;
        }
        let mut word_of_node = vec![None; n];
        let mut node_of_word = Vec::new();
        for id in 1..n {
            let has_children = child_start[id + 1] > child_start[id];
            if is_leaf[id] && has_children {
                return Err(err(
                    Some(id),
                    format!("node {id} is marked a leaf but has children"),
                ));
            }
            if !is_leaf[id] && !has_children {
                return Err(err(
                    Some(id),
                    format!("node {id} is not a leaf but has no children"),
                ));
            }
            if is_leaf[id] {
                word_of_node[id] = Some(node_of_word.len() as WordId);
                node_of_word.push(id as NodeId);
            }
        }
        Ok(Vocabulary {
            k,
            levels,
            weighting,
            parent,
            descriptor,
            weight,
            word_of_node,
            node_of_word,
            child_start,
            children,
            depth,
        })
    }

    /// Branching factor k.
    pub fn k(&self) -> usize {
        self.k
    }

    /// Depth L.
    pub fn levels(&self) -> usize {
        self.levels
    }

    /// The weighting of word weights.
    pub fn weighting(&self) -> Weighting {
        self.weighting
    }

    /// Number of words (leaves).
    pub fn word_count(&self) -> usize {
        self.node_of_word.len()
    }

    /// Number of nodes, the root included.
    pub fn node_count(&self) -> usize {
        self.parent.len()
    }

    /// Weight of a word.
    pub fn word_weight(&self, w: WordId) -> f64 {
        self.weight[self.node_of_word[w as usize] as usize]
    }

    fn children_of(&self, n: usize) -> &[NodeId] {
        &self.children[self.child_start[n] as usize..self.child_start[n + 1] as usize]
    }

    /// The word of a descriptor and the node at depth `direct_level` on its way down (the
    /// deepest node reached when the branch ends earlier; the root for level 0).
    pub fn quantize(&self, d: &Descriptor, direct_level: usize) -> (WordId, NodeId) {
        let mut node = 0usize;
        let mut direct = 0usize;
        loop {
            let ch = self.children_of(node);
            if ch.is_empty() {
                break;
            }
            let mut best = ch[0] as usize;
            let mut best_d = hamming(d, &self.descriptor[best]);
            for &c in &ch[1..] {
                let dist = hamming(d, &self.descriptor[c as usize]);
                if dist < best_d {
                    best_d = dist;
                    best = c as usize;
                }
            }
            node = best;
            if self.depth[node] as usize <= direct_level {
                direct = node;
            }
        }
        let word = self.word_of_node[node].expect("descending ends at a leaf");
        (word, direct as NodeId)
    }

    /// The BoW vector of a frame's descriptors (weighted as the vocabulary says, L1-normalised
    /// for the L1 score) and its direct index at `levels_up` levels above the leaves (ORB-SLAM2:
    /// [`DIRECT_INDEX_LEVELS_UP`]).
    pub fn transform(
        &self,
        descriptors: &[Descriptor],
        levels_up: usize,
    ) -> (BowVector, FeatureVector) {
        let direct_level = self.levels.saturating_sub(levels_up);
        let mut contributions = Vec::with_capacity(descriptors.len());
        let mut pairs = Vec::with_capacity(descriptors.len());
        for (i, d) in descriptors.iter().enumerate() {
            let (w, node) = self.quantize(d, direct_level);
            let weight = self.word_weight(w);
            if weight > 0.0 {
                contributions.push((w, weight));
            }
            pairs.push((node, i));
        }
        let mut bow = match self.weighting {
            Weighting::TfIdf | Weighting::Tf => BowVector::from_contributions(contributions),
            // IDF / binary: a word counts once however often it occurs.
            Weighting::Idf | Weighting::Binary => {
                contributions.sort_by_key(|&(w, _)| w);
                contributions.dedup_by_key(|c| c.0);
                BowVector::from_contributions(contributions)
            }
        };
        bow.normalize_l1();
        (bow, FeatureVector::from_pairs(pairs))
    }

    /// The node list (ids 1..) as the text and binary forms store it.
    pub fn node_records(&self) -> Vec<NodeRecord> {
        (1..self.node_count())
            .map(|id| NodeRecord {
                parent: self.parent[id],
                is_leaf: self.word_of_node[id].is_some(),
                descriptor: self.descriptor[id],
                weight: self.weight[id],
            })
            .collect()
    }

    /// Parses a vocabulary file's bytes in either form: the binary form when they start with
    /// its magic, else DBoW2's text form (which must be UTF-8).
    pub fn from_bytes(bytes: &[u8]) -> Result<Vocabulary, VocabularyError> {
        if bytes.starts_with(BINARY_MAGIC) {
            return Self::from_binary(bytes);
        }
        let text = std::str::from_utf8(bytes).map_err(|e| {
            err(
                0,
                format!(
                    "neither a DBoW2 text vocabulary (not UTF-8 text at byte {}) nor a noisefree \
                     binary one (no {:?} magic)",
                    e.valid_up_to(),
                    String::from_utf8_lossy(BINARY_MAGIC)
                ),
            )
        })?;
        Self::from_text(text)
    }

    /// Parses DBoW2's text form (ORB-SLAM2's `ORBvoc.txt`).
    pub fn from_text(text: &str) -> Result<Vocabulary, VocabularyError> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let (hl, header) = lines
            .next()
            .ok_or_else(|| err(0, "empty vocabulary file"))?;
        let h: Vec<i64> = header
            .split_whitespace()
            .map(|f| f.parse::<i64>())
            .collect::<Result<_, _>>()
            .map_err(|_| {
                err(
                    hl + 1,
                    format!("header {header:?} is not `k L scoring weighting`"),
                )
            })?;
        if h.len() != 4 {
            return Err(err(
                hl + 1,
                format!(
                    "header has {} fields; expected `k L scoring weighting`",
                    h.len()
                ),
            ));
        }
        if h[2] != i64::from(SCORING_L1) {
            return Err(err(
                hl + 1,
                format!(
                    "scoring {} is not supported (only 0, the L1 norm ORB-SLAM2 uses)",
                    h[2]
                ),
            ));
        }
        let weighting = Weighting::from_code(h[3])
            .ok_or_else(|| err(hl + 1, format!("unknown weighting {}", h[3])))?;
        if h[0] < 2 || h[1] < 1 || h[0] > 255 || h[1] > 16 {
            return Err(err(
                hl + 1,
                format!(
                    "k = {}, L = {}: need 2 <= k <= 255 and 1 <= L <= 16",
                    h[0], h[1]
                ),
            ));
        }
        let mut nodes = Vec::new();
        let mut line_of_node = Vec::new();
        for (i, line) in lines {
            let ln = i + 1;
            line_of_node.push(ln);
            let mut f = line.split_whitespace();
            let mut next = |what: &str| {
                f.next().ok_or_else(|| {
                    err(
                        ln,
                        format!("missing {what}; expected `parent is_leaf b0 ... b31 weight`"),
                    )
                })
            };
            let parent: NodeId = next("parent")?
                .parse()
                .map_err(|_| err(ln, "parent id is not a non-negative integer"))?;
            let is_leaf = match next("is_leaf")? {
                "0" => false,
                "1" => true,
                o => return Err(err(ln, format!("is_leaf {o:?} is not 0 or 1"))),
            };
            let mut bytes = [0u8; 32];
            for (b, slot) in bytes.iter_mut().enumerate() {
                let s = next("descriptor byte")?;
                *slot = s.parse().map_err(|_| {
                    err(ln, format!("descriptor byte {b} ({s:?}) is not in 0..=255"))
                })?;
            }
            let ws = next("weight")?;
            let weight: f64 = ws
                .parse()
                .map_err(|_| err(ln, format!("weight {ws:?} is not a number")))?;
            if f.next().is_some() {
                return Err(err(
                    ln,
                    "more than 35 fields; expected `parent is_leaf b0 ... b31 weight`",
                ));
            }
            nodes.push(NodeRecord {
                parent,
                is_leaf,
                descriptor: descriptor_from_bytes(&bytes),
                weight,
            });
        }
        Self::build(h[0] as usize, h[1] as usize, weighting, &nodes).map_err(|(id, m)| {
            let line = id.map_or(0, |id| line_of_node[id as usize - 1]);
            err(line, m)
        })
    }

    /// Writes DBoW2's text form.
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::with_capacity(self.node_count() * 110);
        let _ = writeln!(
            s,
            "{} {} {} {}",
            self.k,
            self.levels,
            SCORING_L1,
            self.weighting.code()
        );
        for r in self.node_records() {
            let _ = write!(s, "{} {}", r.parent, u8::from(r.is_leaf));
            for b in descriptor_to_bytes(&r.descriptor) {
                let _ = write!(s, " {b}");
            }
            let _ = writeln!(s, " {}", r.weight);
        }
        s
    }

    /// Our binary form: `NFVOCAB1`, k, L, scoring, weighting, node count, the nodes (parent u32,
    /// leaf u8, 32 descriptor bytes, weight f64), then an FNV-1a 64 checksum of all before it.
    pub fn to_binary(&self) -> Vec<u8> {
        let records = self.node_records();
        let mut b = Vec::with_capacity(24 + records.len() * 45 + 8);
        b.extend_from_slice(BINARY_MAGIC);
        b.extend_from_slice(&(self.k as u32).to_le_bytes());
        b.extend_from_slice(&(self.levels as u32).to_le_bytes());
        b.push(SCORING_L1);
        b.push(self.weighting.code());
        b.extend_from_slice(&(records.len() as u32).to_le_bytes());
        for r in &records {
            b.extend_from_slice(&r.parent.to_le_bytes());
            b.push(u8::from(r.is_leaf));
            b.extend_from_slice(&descriptor_to_bytes(&r.descriptor));
            b.extend_from_slice(&r.weight.to_le_bytes());
        }
        let sum = fnv1a(&b);
        b.extend_from_slice(&sum.to_le_bytes());
        b
    }

    /// Reads our binary form, checking its magic, length and checksum.
    pub fn from_binary(b: &[u8]) -> Result<Vocabulary, VocabularyError> {
        const HEAD: usize = 8 + 4 + 4 + 1 + 1 + 4;
        const NODE: usize = 4 + 1 + 32 + 8;
        if b.len() < HEAD + 8 || &b[..8] != BINARY_MAGIC {
            return Err(err(0, "not a noisefree binary vocabulary (bad magic)"));
        }
        let (body, tail) = b.split_at(b.len() - 8);
        if fnv1a(body).to_le_bytes() != tail {
            return Err(err(0, "binary vocabulary is corrupt (checksum mismatch)"));
        }
        let u32_at = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().expect("4 bytes"));
        let k = u32_at(8) as usize;
        let levels = u32_at(12) as usize;
        // The text form's ranges: a node's depth is kept in a byte, and 16 levels of even
        // k = 2 are more words than any vocabulary has.
        if !(2..=255).contains(&k) || !(1..=16).contains(&levels) {
            return Err(err(
                0,
                format!("k = {k}, L = {levels}: need 2 <= k <= 255 and 1 <= L <= 16"),
            ));
        }
        if b[16] != SCORING_L1 {
            return Err(err(0, format!("scoring {} is not supported", b[16])));
        }
        let weighting = Weighting::from_code(i64::from(b[17]))
            .ok_or_else(|| err(0, format!("unknown weighting {}", b[17])))?;
        let n = u32_at(18) as usize;
        if body.len() != HEAD + n * NODE {
            return Err(err(
                0,
                format!(
                    "binary vocabulary holds {} bytes of nodes, expected {} for {n} nodes",
                    body.len().saturating_sub(HEAD),
                    n * NODE
                ),
            ));
        }
        let mut nodes = Vec::with_capacity(n);
        for i in 0..n {
            let o = HEAD + i * NODE;
            let is_leaf = match b[o + 4] {
                0 => false,
                1 => true,
                x => return Err(err(0, format!("node {}: leaf flag {x}", i + 1))),
            };
            let bytes: [u8; 32] = b[o + 5..o + 37].try_into().expect("32 bytes");
            nodes.push(NodeRecord {
                parent: u32_at(o),
                is_leaf,
                descriptor: descriptor_from_bytes(&bytes),
                weight: f64::from_le_bytes(b[o + 37..o + 45].try_into().expect("8 bytes")),
            });
        }
        Self::build(k, levels, weighting, &nodes).map_err(|(_, m)| err(0, m))
    }
}

/// Magic of the binary form.
pub const BINARY_MAGIC: &[u8; 8] = b"NFVOCAB1";

/// DBoW2 / OpenCV byte order of a descriptor: byte i holds tests 8i..8i+7, lowest bit first,
/// which is our word i / 8, bits 8 (i % 8) upwards.
pub fn descriptor_from_bytes(bytes: &[u8; 32]) -> Descriptor {
    let mut d = [0u64; 4];
    for (i, &b) in bytes.iter().enumerate() {
        d[i / 8] |= u64::from(b) << (8 * (i % 8));
    }
    d
}

/// Inverse of [`descriptor_from_bytes`].
pub fn descriptor_to_bytes(d: &Descriptor) -> [u8; 32] {
    let mut out = [0u8; 32];
    for (i, o) in out.iter_mut().enumerate() {
        *o = (d[i / 8] >> (8 * (i % 8))) as u8;
    }
    out
}
