//! FNV-1a 64: the checksum of the binary vocabulary and of cached frames, and the fingerprint
//! the tools print for trajectories, files and results. Chosen for being tiny, dependency-free
//! and the same on every platform; it is not a cryptographic hash.

/// The offset basis: the hash of no bytes, where a hash starts.
pub const FNV1A_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// The FNV prime of 64 bits.
const FNV1A_PRIME: u64 = 0x0000_0100_0000_01b3;

/// The hash `h` continued over `bytes`: `fnv1a_continue(fnv1a(a), b) == fnv1a(a ++ b)`, so a
/// fingerprint can be taken piece by piece without building the whole byte string.
#[inline]
pub fn fnv1a_continue(h: u64, bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .fold(h, |h, &b| (h ^ u64::from(b)).wrapping_mul(FNV1A_PRIME))
}

/// FNV-1a 64 of `bytes`.
#[inline]
pub fn fnv1a(bytes: &[u8]) -> u64 {
    fnv1a_continue(FNV1A_OFFSET, bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_vectors() {
        // The FNV authors' test vectors for FNV-1a 64.
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn continuing_is_hashing_the_concatenation() {
        assert_eq!(fnv1a_continue(fnv1a(b"foo"), b"bar"), fnv1a(b"foobar"));
        assert_eq!(fnv1a_continue(FNV1A_OFFSET, b""), fnv1a(b""));
    }
}
