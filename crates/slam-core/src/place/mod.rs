//! Place recognition (DBoW2's model, as ORB-SLAM2 uses it): a vocabulary tree of binary ORB
//! words, bag-of-words vectors with a direct index, and the keyframe database that finds
//! relocalization (and loop) candidates.
//!
//! - [`vocabulary`]: the tree, quantisation, DBoW2's text form and our binary form;
//! - [`bow`]: BoW vectors, the L1 score, the direct index (`FeatureVector`);
//! - [`database`]: the inverted index over keyframes and its candidate queries;
//! - [`train`](mod@train): hierarchical k-majority training, seeded and parallel.
//!
//! Nothing here reads files: the CLI hands in the bytes of a vocabulary file.

pub mod bow;
pub mod database;
pub mod train;
pub mod vocabulary;

pub use bow::{score_l1, BowVector, FeatureVector, FrameBow, NodeId, WordId};
pub use database::KeyFrameDatabase;
pub use train::{train, TrainParams};
pub use vocabulary::{Vocabulary, VocabularyError, Weighting, DIRECT_INDEX_LEVELS_UP};

use crate::feature::Descriptor;
use std::sync::Arc;

/// What a running system needs for place recognition: the vocabulary (shared by every run of a
/// sweep) and this run's keyframe database.
#[derive(Clone, Debug)]
pub struct PlaceRecognition {
    /// The vocabulary.
    pub vocabulary: Arc<Vocabulary>,
    /// The inverted index over this run's keyframes.
    pub database: KeyFrameDatabase,
}

impl PlaceRecognition {
    /// An empty database over `vocabulary`.
    pub fn new(vocabulary: Arc<Vocabulary>) -> PlaceRecognition {
        let database = KeyFrameDatabase::new(vocabulary.word_count());
        PlaceRecognition {
            vocabulary,
            database,
        }
    }

    /// The BoW vector and direct index of a frame's descriptors (ORB-SLAM2's ComputeBoW,
    /// direct index 4 levels above the leaves).
    pub fn frame_bow(&self, descriptors: &[Descriptor]) -> Arc<FrameBow> {
        let (bow, features) = self
            .vocabulary
            .transform(descriptors, DIRECT_INDEX_LEVELS_UP);
        Arc::new(FrameBow { bow, features })
    }
}

#[cfg(test)]
mod tests;
