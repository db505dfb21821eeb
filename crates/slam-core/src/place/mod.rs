//! Place recognition (DBoW2's model, as ORB-SLAM2 uses it): a vocabulary tree of binary ORB
//! words, bag-of-words vectors with a direct index, and the keyframe database that finds
//! relocalization (and loop) candidates.
//!
//! - [`vocabulary`]: the tree, quantisation, DBoW2's text form and our binary form;
//! - [`bow`]: BoW vectors, the L1 score, the direct index (`FeatureVector`);
//! - [`database`]: the inverted index over keyframes and its candidate queries;
//! - [`train`]: hierarchical k-majority training, seeded and parallel.
//!
//! Nothing here reads files: the CLI hands in the bytes of a vocabulary file.

pub mod bow;
pub mod database;
pub mod train;
pub mod vocabulary;

pub use bow::{score_l1, BowVector, FeatureVector, NodeId, WordId};
pub use database::KeyFrameDatabase;
pub use train::{train, TrainParams};
pub use vocabulary::{Vocabulary, VocabularyError, Weighting, DIRECT_INDEX_LEVELS_UP};

#[cfg(test)]
mod tests;
