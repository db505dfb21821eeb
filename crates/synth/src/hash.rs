//! Counter-based randomness for per-frame and per-pixel noise.
//!
//! Frames must be generated in any order and in parallel with identical bytes, so image and
//! depth noise never come from a sequential RNG: every draw is a pure function of
//! (seed, frame, stream, pixel), mixed with the SplitMix64 finaliser. The world itself (layout
//! and textures) is drawn once from a seeded `rand_chacha` RNG (`world::scene`).

/// Named noise streams, so that two noise components never reuse the same random numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u64)]
pub enum Stream {
    /// Grey-level noise of the left / RGB image.
    ImageLeft = 1,
    /// Grey-level noise of the right image (stereo).
    ImageRight = 2,
    /// Axial depth noise.
    Axial = 3,
    /// Lateral depth noise (neighbour offset).
    Lateral = 4,
    /// Holes at depth boundaries.
    BoundaryHole = 5,
    /// Per-pixel maximum range.
    Range = 6,
    /// Motion-capture noise of the written ground truth (index: the pose component).
    Mocap = 7,
    /// Stamp jitter of the colour and depth streams and the motion-capture clock's phase
    /// (index: 0 colour, 1 depth, 2 phase).
    Stamps = 8,
}

/// SplitMix64 finaliser: a bijective 64-bit mixer with good avalanche.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A key identifying one frame's stream; combine with a pixel index to get random numbers.
#[derive(Clone, Copy, Debug)]
pub struct NoiseKey(u64);

impl NoiseKey {
    /// Key of `stream` in frame `frame` of the sequence seeded with `seed`.
    pub fn new(seed: u64, frame: usize, stream: Stream) -> Self {
        let a = mix64(seed ^ 0xA076_1D64_78BD_642F);
        let b = mix64(a ^ (frame as u64).wrapping_mul(0xE703_7ED1_A0B4_28DB));
        NoiseKey(mix64(
            b ^ (stream as u64).wrapping_mul(0x8EBC_6AF0_9C88_C6E3),
        ))
    }

    /// 64 random bits for item `i` (a pixel index, or pixel * k + channel).
    #[inline]
    pub fn bits(&self, i: u64) -> u64 {
        mix64(self.0 ^ mix64(i))
    }

    /// Uniform in [0, 1) for item `i`.
    #[inline]
    pub fn uniform(&self, i: u64) -> f64 {
        (self.bits(i) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Two independent standard normal draws for item `i` (inverse CDF of 2 x 32 bits).
    #[inline]
    pub fn normal2(&self, i: u64) -> (f64, f64) {
        let r = self.bits(i);
        let p = |b: u64| (b as f64 + 0.5) * (1.0 / 4_294_967_296.0);
        (
            inverse_normal_cdf(p(r >> 32)),
            inverse_normal_cdf(p(r & 0xFFFF_FFFF)),
        )
    }

    /// One standard normal draw for item `i` (the first of [`NoiseKey::normal2`]).
    #[inline]
    pub fn normal(&self, i: u64) -> f64 {
        let r = self.bits(i);
        inverse_normal_cdf(((r >> 32) as f64 + 0.5) * (1.0 / 4_294_967_296.0))
    }
}

/// Inverse of the standard normal CDF for p in (0, 1), Acklam's rational approximation
/// (error below 1e-4, ample for noise): a polynomial ratio in the centre, log + sqrt only in the 5 %
/// tails, so much cheaper than Box-Muller's log + sin + cos per pair.
#[inline]
pub fn inverse_normal_cdf(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_671_010_229_583,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    const P_LOW: f64 = 0.02425;
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < P_LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - P_LOW {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn inverse_normal_cdf_matches_known_quantiles() {
        for (p, z) in [
            (0.5, 0.0),
            (0.975, 1.959_963_985),
            (0.01, -2.326_347_874),
            (0.8413447461, 1.0),
        ] {
            assert!((super::inverse_normal_cdf(p) - z).abs() < 1e-4, "{p}");
        }
    }

    use super::*;

    #[test]
    fn normal_has_unit_moments() {
        let k = NoiseKey::new(7, 3, Stream::Axial);
        let n = 200_000;
        let (mut s, mut s2) = (0.0, 0.0);
        for i in 0..n {
            let (a, b) = k.normal2(i);
            s += a + b;
            s2 += a * a + b * b;
        }
        let m = s / (2 * n) as f64;
        let var = s2 / (2 * n) as f64 - m * m;
        assert!(m.abs() < 0.01, "mean {m}");
        assert!((var - 1.0).abs() < 0.01, "var {var}");
    }

    #[test]
    fn keys_differ_by_frame_and_stream() {
        let a = NoiseKey::new(1, 0, Stream::Axial).bits(5);
        let b = NoiseKey::new(1, 1, Stream::Axial).bits(5);
        let c = NoiseKey::new(1, 0, Stream::Lateral).bits(5);
        let d = NoiseKey::new(2, 0, Stream::Axial).bits(5);
        assert!(a != b && a != c && a != d && b != c);
        assert_eq!(a, NoiseKey::new(1, 0, Stream::Axial).bits(5));
    }
}
