//! File-name-safe names for what a sweep writes per sequence, chain and system (cache keys, run
//! folders): the planner, the sweep and the external-system export all name folders this way.

/// A file-name-safe version of `s` (cache keys, run folders).
pub fn safe(s: &str) -> String {
    let out: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    // A long chain (a named camera chain expands to a dozen members) keeps a readable head and
    // a hash of the whole, so the name stays well under the file systems' 255 bytes.
    if out.len() > SAFE_MAX {
        let head: String = out.chars().take(SAFE_MAX - 17).collect();
        return format!("{head}-{:016x}", slam_core::hash::fnv1a(s.as_bytes()));
    }
    out
}

/// The longest name [`safe`] returns.
pub const SAFE_MAX: usize = 120;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_file_safe_and_long_ones_capped_apart() {
        assert_eq!(
            safe("kinect-fr1:1.5+gt-offset:3"),
            "kinect-fr1_1.5_gt-offset_3"
        );
        let long_a = "depth-distortion:1.5+".repeat(10);
        let long_b = format!("{long_a}x");
        let (a, b) = (safe(&long_a), safe(&long_b));
        assert_eq!(a.len(), SAFE_MAX);
        assert_eq!(b.len(), SAFE_MAX);
        assert_ne!(a, b, "names that share a head differ by their hash");
        assert!(a
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c)));
    }
}
