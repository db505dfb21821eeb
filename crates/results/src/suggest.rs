//! "Did you mean": the known name closest to a mistyped one, for the messages that refuse an
//! unknown configuration, setting or reading.

/// The edit distance (insertions, deletions, substitutions) between `a` and `b`.
fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let above = row[j + 1];
            row[j + 1] = (above + 1)
                .min(row[j] + 1)
                .min(diagonal + usize::from(ca != *cb));
            diagonal = above;
        }
    }
    row[b.len()]
}

/// The candidate closest to `word` when it is close enough to be what was meant (at most a
/// third of its letters wrong, at least one allowed); the first of equals.
pub fn closest<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let allowed = (word.chars().count() / 3).max(1);
    candidates
        .into_iter()
        .map(|c| (distance(word, c), c))
        .filter(|(d, _)| *d <= allowed)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

/// `" (did you mean `NAME`?)"` for the closest candidate, or nothing.
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    closest(word, candidates).map_or_else(String::new, |c| format!(" (did you mean `{c}`?)"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_typo_finds_the_name_meant_and_a_stranger_finds_none() {
        assert_eq!(distance("mcorr", "mcor"), 1);
        assert_eq!(distance("", "abc"), 3);
        assert_eq!(closest("mcorr", ["orb", "mcor", "avc"]), Some("mcor"));
        assert_eq!(closest("tau_mff", ["tau_mf", "tau_gf"]), Some("tau_mf"));
        assert_eq!(closest("banana", ["orb", "mcor", "avc"]), None);
        assert_eq!(did_you_mean("avcc", ["avc"]), " (did you mean `avc`?)");
        assert_eq!(did_you_mean("zzz", ["avc"]), "");
    }
}
