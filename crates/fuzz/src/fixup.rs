//! Repairs applied to mutated inputs so that mutations reach the parser behind a checksum: the
//! binary vocabulary's trailing FNV-1a 64, and every PNG chunk's CRC-32. Without them nearly
//! every mutation of these formats would stop at the checksum test, which is worth fuzzing once
//! and not a million times.

use datasets::decode::png_crc32;
use slam_core::hash::fnv1a;

/// Rewrites the last 8 bytes of a binary vocabulary as the checksum of the bytes before them.
pub fn vocabulary_checksum(b: &mut [u8]) {
    if b.len() >= 8 {
        let n = b.len() - 8;
        let sum = fnv1a(&b[..n]);
        b[n..].copy_from_slice(&sum.to_le_bytes());
    }
}

/// Recomputes the CRC of every whole chunk of a PNG (signature, then length, type, data, CRC),
/// stopping at the first chunk that runs past the end.
pub fn png_crcs(b: &mut [u8]) {
    let mut at = 8;
    while at + 12 <= b.len() {
        let len = u32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as usize;
        let Some(end) = (at + 8).checked_add(len) else {
            return;
        };
        if end + 4 > b.len() {
            return;
        }
        let crc = png_crc32(&b[at + 4..end]);
        b[end..end + 4].copy_from_slice(&crc.to_be_bytes());
        at = end + 4;
    }
}

/// [`png_crcs`] for an input that begins as a PNG does (a reader of PNG and JPEG alike): other
/// inputs are left as they are.
pub fn png_crcs_if_png(b: &mut [u8]) {
    if b.starts_with(b"\x89PNG") {
        png_crcs(b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_of_the_png_iend_chunk() {
        // Every PNG ends with the same IEND chunk: type `IEND`, no data, CRC ae426082.
        assert_eq!(png_crc32(b"IEND"), 0xae42_6082);
        let mut png = b"\x89PNG\r\n\x1a\n\0\0\0\0IEND\0\0\0\0".to_vec();
        png_crcs(&mut png);
        assert_eq!(&png[16..], &[0xae, 0x42, 0x60, 0x82]);
        let mut jpeg = b"\xff\xd8\xff\xe0\0\0\0\0IEND\0\0\0\0".to_vec();
        let before = jpeg.clone();
        png_crcs_if_png(&mut jpeg);
        assert_eq!(jpeg, before);
        png[12] = b'X';
        png_crcs_if_png(&mut png);
        assert_eq!(&png[16..], &png_crc32(b"XEND").to_be_bytes());
    }
}
