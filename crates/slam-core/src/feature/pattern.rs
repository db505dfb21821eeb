//! The BRIEF sampling pattern: 256 point pairs around the keypoint, each test comparing the
//! (blurred) intensities at its two points.
//!
//! The pattern is ours, not OpenCV's learned table: [`generate_pattern`] draws both points of
//! every pair independently from an isotropic Gaussian with sigma = [`PATTERN_SIGMA`] px
//! (PATCH_SIZE / 5, the "G II" arrangement of Calonder et al.'s BRIEF paper), rounds them to
//! integer offsets, and rejects a draw when a point falls outside the radius-[`PATTERN_RADIUS`]
//! disk (so that a rotated point, rounded, still lies within the 15 px descriptor patch), when
//! the two points coincide, or when the pair repeats an earlier one. It is run once with
//! [`PATTERN_SEED`] (ChaCha8) and stored below as [`PATTERN`]; a test regenerates it and checks
//! the two agree.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Seed of [`generate_pattern`] that produced [`PATTERN`] (the bytes of "ORBPATT1").
pub const PATTERN_SEED: u64 = 0x4f52_4250_4154_5431;
/// Standard deviation of the point offsets in pixels: 31 / 5.
pub const PATTERN_SIGMA: f64 = 6.2;
/// Largest distance of a pattern point from the keypoint in pixels.
pub const PATTERN_RADIUS: i32 = 13;

/// Draws 256 test pairs `[x1, y1, x2, y2]` as described in the module doc.
pub fn generate_pattern(seed: u64) -> Vec<[i8; 4]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out: Vec<[i8; 4]> = Vec::with_capacity(256);
    let point = |rng: &mut ChaCha8Rng| -> (i32, i32) {
        loop {
            // Box-Muller: two independent N(0, sigma^2) coordinates.
            let u1: f64 = 1.0 - rng.random::<f64>();
            let u2: f64 = rng.random::<f64>();
            let r = (-2.0 * u1.ln()).sqrt() * PATTERN_SIGMA;
            let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
            let (x, y) = ((r * c).round() as i32, (r * s).round() as i32);
            if x * x + y * y <= PATTERN_RADIUS * PATTERN_RADIUS {
                return (x, y);
            }
        }
    };
    while out.len() < 256 {
        let (x1, y1) = point(&mut rng);
        let (x2, y2) = point(&mut rng);
        if (x1, y1) == (x2, y2) {
            continue;
        }
        let pair = [x1 as i8, y1 as i8, x2 as i8, y2 as i8];
        let swapped = [pair[2], pair[3], pair[0], pair[1]];
        if out.iter().any(|p| *p == pair || *p == swapped) {
            continue;
        }
        out.push(pair);
    }
    out
}

/// The 256 BRIEF test pairs `[x1, y1, x2, y2]` in pixels relative to the keypoint, as produced
/// by `generate_pattern(PATTERN_SEED)`. Bit `i` of a descriptor is `I(p1) < I(p2)` for pair `i`
/// rotated by the keypoint angle.
#[rustfmt::skip]
pub const PATTERN: [[i8; 4]; 256] = [
    [5, -3, 4, -4], [-5, -1, -4, 4], [-1, 8, -3, -2], [3, -5, -2, -3],
    [1, 1, 3, 6], [-2, -10, -3, -3], [-7, 10, 2, 7], [0, 1, -1, -10],
    [6, 0, -1, 10], [2, -1, 1, 6], [3, 4, 8, -5], [7, -1, -6, -5],
    [-3, 1, -1, -8], [2, -1, 5, -3], [2, -6, -3, 1], [9, -1, -4, -1],
    [-2, -5, 10, -3], [6, -11, -2, -1], [9, 2, -6, -7], [2, -5, -2, 9],
    [-2, 1, -4, -1], [7, -10, 7, 0], [1, -1, -6, 1], [-1, -1, 3, 1],
    [5, -7, 8, -6], [9, 3, -8, 4], [10, 1, 6, -7], [1, -3, -1, 11],
    [2, 8, -3, -4], [4, 10, -5, -3], [9, 1, 1, -4], [0, -4, -5, 0],
    [1, 10, 1, -8], [2, -1, -12, -3], [-2, -4, 3, 5], [3, -2, 5, -2],
    [-2, 4, -9, -9], [0, 2, 2, 0], [2, -9, 3, 0], [1, 1, 3, -8],
    [3, -6, -4, -10], [-8, 2, -3, 3], [-5, 3, -2, 4], [1, -1, 0, 1],
    [-4, -8, -3, -5], [-8, -6, 9, -3], [-5, 0, 2, 3], [1, 0, 11, -1],
    [2, -8, -4, -1], [-7, 2, 1, -9], [-3, 6, 4, 3], [4, 6, 5, 1],
    [11, 2, -4, -4], [7, 4, -1, -1], [4, 4, -4, 3], [0, 7, 6, 6],
    [-1, 1, -8, -4], [-2, 6, 7, 2], [3, -2, 5, 0], [5, 2, 1, 0],
    [8, -7, -3, -8], [-8, 0, 6, 0], [-6, 4, -10, -2], [-2, 6, -8, -2],
    [8, -3, 4, -9], [9, -1, 0, -12], [0, 6, -4, 3], [2, -9, 4, 1],
    [10, 8, 3, 4], [-9, 6, 12, 0], [4, 7, 0, -8], [-7, 5, 0, 0],
    [-10, 1, -4, 5], [1, 1, -1, -2], [-7, 7, 1, -2], [1, -1, -8, -9],
    [-7, -4, 5, 3], [3, -6, -5, -9], [7, 7, -1, -5], [2, 3, -3, 0],
    [-5, 0, -6, -3], [-2, -12, -1, -4], [2, -4, -5, -1], [-6, -1, 1, 2],
    [-5, 0, 5, 10], [6, -9, 3, 6], [-9, 5, 0, -3], [-8, -8, -5, 3],
    [2, -7, -4, -7], [-1, 3, 1, 7], [3, 4, -6, -5], [-2, -4, -5, 2],
    [1, 11, 3, -8], [8, 8, 5, 0], [2, 7, 1, 2], [-1, 9, 4, -7],
    [-9, 5, 4, 0], [4, -1, -3, 6], [-7, -6, 5, 8], [3, 6, 0, 8],
    [-1, 2, 4, -3], [-9, -4, 7, 10], [-8, 3, 2, -1], [0, -1, -5, -1],
    [-5, -2, -8, 5], [-4, -5, -4, 0], [-7, -9, 1, -4], [-7, -2, -3, -5],
    [-1, -7, 2, 3], [-4, 10, 5, -2], [-1, -4, 0, 10], [2, 4, -3, -4],
    [2, 1, -4, 0], [-4, 4, 5, 2], [2, 1, 4, -7], [-1, -7, -6, -4],
    [4, -5, 6, 2], [0, 1, 1, -5], [6, -5, 1, -12], [4, 7, -1, 6],
    [12, 3, 7, 1], [8, 4, 3, 2], [0, 0, 2, -7], [0, 2, -6, 8],
    [-6, 10, -8, 2], [4, 4, 4, 3], [-11, 3, 9, -3], [-11, -2, 2, 4],
    [10, -3, -1, -1], [-2, -4, 0, -11], [-7, -10, -4, -1], [-4, 4, 3, -7],
    [-7, -1, 4, -3], [3, 4, 0, -11], [-3, 2, 1, -11], [-6, 6, -5, 2],
    [-8, -9, -1, -3], [3, 3, 4, 0], [-6, 9, 3, -9], [0, 10, 0, 5],
    [-7, -5, 7, 0], [-3, 2, -9, -7], [-6, -2, 2, 6], [-4, -2, -3, -2],
    [11, 4, -5, -4], [2, 0, -3, -8], [3, -1, 9, 4], [5, 0, 4, -2],
    [3, -8, 0, -6], [8, -6, 7, 2], [-6, 0, -3, 0], [-8, -2, -4, 0],
    [1, 2, 7, -5], [-4, 7, -4, -2], [-10, -1, 4, -1], [1, 9, -8, 1],
    [5, 1, -3, -10], [-2, 0, -10, 8], [3, 9, -2, 4], [5, 5, -7, -4],
    [-10, 2, -6, 2], [-1, 0, -5, 1], [-1, 1, 9, 1], [-8, 0, 4, -4],
    [7, 3, -6, 1], [7, 1, -9, 2], [7, 8, -4, -9], [0, -8, 2, 0],
    [-12, -5, -10, 1], [1, 0, -4, 5], [-3, -1, -2, -2], [-2, -4, 2, -5],
    [2, 3, -2, -4], [1, -9, -11, 0], [-6, -1, -4, 2], [1, 5, 1, 4],
    [4, -2, -3, -7], [2, -5, 4, -8], [1, 5, 6, -5], [-9, 3, 4, -2],
    [-4, -4, 10, -2], [8, -6, -5, -1], [-7, -1, 9, 4], [1, 6, 0, -2],
    [-8, 8, -4, 1], [6, -2, -8, -4], [-7, 0, 4, 5], [8, -8, 2, 0],
    [1, 4, -1, -2], [5, -3, -9, -2], [-9, 1, 5, -5], [4, -1, -8, -2],
    [-6, 0, -7, -4], [1, -1, -1, 2], [11, 5, 0, -4], [4, 2, 3, -5],
    [-1, -9, -10, 2], [-2, 8, -4, 3], [-3, -9, -4, -2], [5, -4, -9, 4],
    [-2, -1, 0, 7], [-12, 5, 2, -1], [-3, -1, -2, -9], [-1, -9, 3, 0],
    [5, 9, -1, 1], [2, -9, -7, -4], [1, 8, 7, -5], [6, -2, -9, -1],
    [4, 0, -9, -1], [-9, 7, -7, 8], [8, 4, 5, 4], [1, 8, -2, 5],
    [3, 5, 2, 11], [3, -6, 8, -1], [-1, 0, 1, 8], [4, -6, 7, -6],
    [-9, -4, 0, -2], [2, -11, 0, 3], [9, 9, -1, -2], [4, 10, 1, -2],
    [-8, -1, 3, -2], [8, -3, -6, 5], [4, -4, -9, -1], [2, 4, 3, -2],
    [4, -3, -3, 1], [1, -2, 5, -7], [-3, 2, -9, 7], [-2, -4, -5, 4],
    [-5, -2, 3, 4], [1, 0, -4, -10], [0, 6, 3, -4], [11, 3, 4, -7],
    [7, 0, 3, -6], [-2, -6, -5, 0], [2, -6, -4, -3], [7, 0, 0, -7],
    [-1, 1, -4, 5], [-2, 2, 7, 7], [4, -12, 4, 7], [-6, -2, -1, -4],
    [1, 1, -5, 4], [-1, 3, -7, 0], [-3, -1, -4, -4], [0, -4, 9, 3],
    [4, -3, 6, -6], [2, 4, -2, 0], [-8, 6, 8, -1], [-6, -2, -6, 10],
    [-1, -6, 5, 10], [11, 0, -7, -5], [-3, 2, 1, 5], [-4, 1, 0, -4],
    [-2, 4, -7, 1], [-2, 1, 4, -1], [1, -6, -1, -10], [2, -3, 0, 2],
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[ignore = "prints the table; run with `cargo test -p slam-core print_pattern -- --ignored --nocapture`"]
    fn print_pattern() {
        for p in generate_pattern(PATTERN_SEED) {
            println!("    [{}, {}, {}, {}],", p[0], p[1], p[2], p[3]);
        }
    }

    #[test]
    fn table_matches_seeded_generator() {
        assert_eq!(PATTERN.to_vec(), generate_pattern(PATTERN_SEED));
    }

    #[test]
    fn pattern_stays_inside_patch_and_is_spread() {
        let mut sx = 0.0;
        let mut sxx = 0.0;
        for p in PATTERN {
            for (x, y) in [(p[0], p[1]), (p[2], p[3])] {
                let (x, y) = (x as i32, y as i32);
                assert!(x * x + y * y <= PATTERN_RADIUS * PATTERN_RADIUS);
                sx += x as f64;
                sxx += (x * x) as f64;
            }
        }
        let mean = sx / 512.0;
        let sd = (sxx / 512.0 - mean * mean).sqrt();
        assert!(mean.abs() < 1.0, "mean {mean}");
        assert!((4.5..6.5).contains(&sd), "sd {sd}");
    }
}
