//! ORB features (Rublee et al. 2011, as ORB-SLAM2 uses them): an image pyramid, FAST-9 corners
//! on a cell grid with an adaptive threshold, a quadtree that spreads them evenly, an orientation
//! by intensity centroid and a 256-bit steered BRIEF descriptor compared by Hamming distance.
//!
//! The stages live in their own modules so each can be tested and benchmarked alone:
//! [`pyramid`] (scale tables and the resized levels), [`fast`] (corner detection and score),
//! [`distribute`] (quadtree distribution), [`orientation`] (intensity centroid), [`brief`]
//! (blur and steered tests), [`pattern`] (our seeded BRIEF sampling pattern) and [`extractor`]
//! (the whole pipeline). [`test_scene`] renders procedural textures with known geometry for the
//! tests and benchmarks.
//!
//! Speed (single thread, 640x480, 1000 features: about 2.8 ms): every hot loop is written as
//! straight-line arithmetic over fixed-size chunks of pixels that the compiler turns into vector
//! instructions, with no `unsafe` indexing. On x86-64 the hot kernels (FAST scores and
//! suppression, pyramid, blur, descriptor, orientation moments) are also compiled with AVX2
//! enabled and chosen at run time when the CPU has it; that is the only `unsafe` code (a call
//! guarded by `is_x86_feature_detected!`). The kernels are integer arithmetic or the same IEEE
//! float operations in either build, so the output is bit-identical with or without AVX2, and
//! tests compare both builds with plain reference implementations.

pub mod brief;
pub mod distribute;
pub mod extractor;
pub mod fast;
pub mod orientation;
pub mod pattern;
pub mod pyramid;
pub mod test_scene;

pub use extractor::{OrbConfig, OrbExtractor};
pub use pyramid::{Pyramid, ScaleInfo};

/// Side of the square patch a descriptor and an orientation are computed over (ORB: 31 px).
pub const PATCH_SIZE: usize = 31;
/// Radius of the circular orientation patch, `PATCH_SIZE / 2`.
pub const HALF_PATCH_SIZE: usize = 15;
/// Distance from a level's border inside which no keypoint is kept, so that the orientation
/// patch, the rotated descriptor tests and the blur window all stay inside the level
/// (ORB-SLAM2's `EDGE_THRESHOLD`).
pub const EDGE_THRESHOLD: usize = 19;

/// Hamming distance below which a descriptor match is accepted in the wide searches
/// (ORB-SLAM2's `ORBmatcher::TH_HIGH`).
pub const TH_HIGH: u32 = 100;
/// Hamming distance below which a descriptor match counts as good in the strict searches
/// (ORB-SLAM2's `ORBmatcher::TH_LOW`).
pub const TH_LOW: u32 = 50;
/// Number of bins of the rotation-consistency histogram used by the matchers.
pub const HISTO_LENGTH: usize = 30;

/// A keypoint: position in level-0 pixels, the pyramid level (octave) it was detected on, its
/// orientation and its FAST score.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyPoint {
    /// Column in level-0 pixels (the level position times the level's scale factor).
    pub x: f32,
    /// Row in level-0 pixels.
    pub y: f32,
    /// Pyramid level the keypoint was detected on (0 = full resolution).
    pub octave: usize,
    /// Orientation by intensity centroid in degrees, in [0, 360), measured in image
    /// coordinates (x right, y down), so a positive angle turns from +x towards +y.
    pub angle: f32,
    /// FAST score: the largest threshold at which the pixel is still a corner.
    pub response: f32,
}

/// A 256-bit binary descriptor, bit `i` of the BRIEF test `i` stored in word `i / 64`.
pub type Descriptor = [u64; 4];

/// Hamming distance between two descriptors: the number of differing bits (0..=256).
#[inline]
pub fn hamming(a: &Descriptor, b: &Descriptor) -> u32 {
    (a[0] ^ b[0]).count_ones()
        + (a[1] ^ b[1]).count_ones()
        + (a[2] ^ b[2]).count_ones()
        + (a[3] ^ b[3]).count_ones()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hamming_counts_differing_bits() {
        let a: Descriptor = [0, 0, 0, 0];
        let b: Descriptor = [1, 3, u64::MAX, 0x8000_0000_0000_0000];
        assert_eq!(hamming(&a, &a), 0);
        assert_eq!(hamming(&a, &b), 1 + 2 + 64 + 1);
        assert_eq!(hamming(&b, &a), hamming(&a, &b));
        let c: Descriptor = [u64::MAX; 4];
        assert_eq!(hamming(&a, &c), 256);
    }
}
