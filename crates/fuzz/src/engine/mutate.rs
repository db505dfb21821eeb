//! The mutator: turns real files (the seeds) into malformed ones, byte-wise (flipped bits,
//! inserted, deleted and repeated ranges, truncation), token-wise (a number or word replaced by
//! an out-of-range number, NaN, inf, a huge count, a quote or a bracket; lines duplicated,
//! dropped, swapped, repeated) and as whole-input cases a parser meets in the wild (empty
//! files, a byte-order mark, CRLF or CR line ends, invalid UTF-8, a line of a million
//! characters, a file many times its usual length). Every input is drawn from the seeded
//! [`Rng`], so a run is reproduced exactly from its seed.

use super::rng::Rng;

/// Tokens that break parsers: numbers at and beyond the limits of every integer and float
/// type, the spellings of NaN and infinity, and the punctuation of the formats read.
pub const INTERESTING: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "-2",
    "0.5",
    "-0.5",
    "1.0000000000000002",
    "255",
    "256",
    "-129",
    "65535",
    "65536",
    "2147483647",
    "2147483648",
    "-2147483649",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "9223372036854775808",
    "-9223372036854775809",
    "18446744073709551615",
    "18446744073709551616",
    "340282366920938463463374607431768211456",
    "1000000000000",
    "1e12",
    "1e18",
    "1e308",
    "1e309",
    "-1e309",
    "1e-320",
    "4.9e-324",
    "1.7976931348623157e308",
    "nan",
    "NaN",
    "-nan",
    "inf",
    "-inf",
    "Infinity",
    "-Infinity",
    ".inf",
    "1e",
    "1e400",
    "+1",
    "0x10",
    "1_000",
    ".",
    "-",
    "",
    " ",
    "#",
    ",",
    ":",
    "=",
    ";",
    "[",
    "]",
    "[[",
    "]]",
    "{",
    "}",
    "\"",
    "'",
    "\\",
    "\t",
    "\r",
    "\r\n",
    "\n",
    "\u{feff}",
    "\0",
    "true",
    "false",
    "null",
    "none",
    "%YAML:1.0",
    "!!opencv-matrix",
];

/// Bytes worth writing over a byte: line ends, separators, digits, the sign, and the bytes
/// that make UTF-8 invalid.
const INTERESTING_BYTES: &[u8] = &[
    0, 0xff, 0x7f, 0x80, 0xc0, 0xed, 0xfe, b'\n', b'\r', b' ', b'\t', b',', b'#', b'-', b'+', b'.',
    b'e', b'0', b'9', b':', b'[', b']', b'"', b'=',
];

fn is_token_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || matches!(b, b'_' | b'.' | b'+' | b'-')
}

/// Input generator over a set of seed files.
#[derive(Clone, Debug)]
pub struct Mutator {
    seeds: Vec<Vec<u8>>,
    /// Extra tokens of the format (its keys, its magic), used beside [`INTERESTING`].
    dictionary: Vec<Vec<u8>>,
    /// Longest input generated, bytes.
    pub max_len: usize,
}

impl Mutator {
    /// A mutator over `seeds` (at least one; an empty list mutates the empty file) with the
    /// format's own `dictionary` of tokens.
    pub fn new(seeds: Vec<Vec<u8>>, dictionary: Vec<Vec<u8>>) -> Mutator {
        let seeds = if seeds.is_empty() {
            vec![Vec::new()]
        } else {
            seeds
        };
        Mutator {
            seeds,
            dictionary,
            max_len: 2 << 20,
        }
    }

    /// The seeds.
    pub fn seeds(&self) -> &[Vec<u8>] {
        &self.seeds
    }

    /// One input: a whole-input case now and then, else a seed under 1 to 16 mutations.
    pub fn input(&self, rng: &mut Rng) -> Vec<u8> {
        let seed = rng.pick(&self.seeds).cloned().unwrap_or_default();
        if rng.one_in(100) {
            return self.whole(rng, seed);
        }
        let mut data = seed;
        let n = rng.small_len(16);
        for _ in 0..n {
            self.mutate_once(rng, &mut data);
        }
        data.truncate(self.max_len);
        data
    }

    /// The cases a file meets as a whole: empty, a lone line end, a byte-order mark, other
    /// line ends, invalid UTF-8, a line of a million characters, the file repeated.
    fn whole(&self, rng: &mut Rng, seed: Vec<u8>) -> Vec<u8> {
        match rng.below(10) {
            0 => Vec::new(),
            1 => b"\n".to_vec(),
            2 => {
                let mut v = b"\xef\xbb\xbf".to_vec();
                v.extend_from_slice(&seed);
                v
            }
            3 => {
                let mut v = Vec::with_capacity(seed.len() * 2);
                for &b in &seed {
                    if b == b'\n' {
                        v.push(b'\r');
                    }
                    v.push(b);
                }
                v
            }
            4 => seed
                .iter()
                .map(|&b| if b == b'\n' { b'\r' } else { b })
                .collect(),
            5 => {
                let mut v = seed;
                let at = rng.below(v.len() + 1);
                v.insert(at, 0xff);
                v
            }
            6 => {
                let byte = *rng.pick(b"a0 9,.#\t-").unwrap_or(&b'a');
                let mut v = vec![byte; 1 << 20];
                v.extend_from_slice(&seed);
                v
            }
            7 => {
                // A line of a million characters in the middle of the file.
                let mut v = seed;
                let at = rng.below(v.len() + 1);
                let line: Vec<u8> = b"1 ".iter().copied().cycle().take(1 << 20).collect();
                v.splice(at..at, line);
                v
            }
            8 => {
                let mut v = Vec::new();
                while v.len() < (1 << 20) && !seed.is_empty() {
                    v.extend_from_slice(&seed);
                }
                v.truncate(self.max_len);
                v
            }
            _ => {
                // The seed cut at every kind of place: inside a number, a key, a header.
                let mut v = seed;
                let at = rng.below(v.len() + 1);
                v.truncate(at);
                v
            }
        }
    }

    fn token(&self, rng: &mut Rng) -> Vec<u8> {
        if !self.dictionary.is_empty() && rng.one_in(3) {
            return rng.pick(&self.dictionary).cloned().unwrap_or_default();
        }
        rng.pick(INTERESTING)
            .map(|s| s.as_bytes().to_vec())
            .unwrap_or_default()
    }

    /// The token (a run of letters, digits and `_.+-`) at or after a random position.
    fn find_token(rng: &mut Rng, data: &[u8]) -> Option<(usize, usize)> {
        if data.is_empty() {
            return None;
        }
        let mut i = rng.below(data.len());
        while i < data.len() && !is_token_byte(data[i]) {
            i += 1;
        }
        if i == data.len() {
            return None;
        }
        let mut start = i;
        while start > 0 && is_token_byte(data[start - 1]) {
            start -= 1;
        }
        let mut end = i;
        while end < data.len() && is_token_byte(data[end]) {
            end += 1;
        }
        Some((start, end))
    }

    /// The line (without its end) at a random position.
    fn find_line(rng: &mut Rng, data: &[u8]) -> (usize, usize) {
        if data.is_empty() {
            return (0, 0);
        }
        let i = rng.below(data.len());
        let start = data[..i]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |p| p + 1);
        let end = data[i..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(data.len(), |p| i + p);
        (start, end)
    }

    /// Applies one mutation to `data`.
    pub fn mutate_once(&self, rng: &mut Rng, data: &mut Vec<u8>) {
        let len = data.len();
        match rng.below(20) {
            0 if len > 0 => {
                let i = rng.below(len);
                data[i] ^= 1 << rng.below(8);
            }
            1 if len > 0 => {
                let i = rng.below(len);
                data[i] = rng.next_u64() as u8;
            }
            2 if len > 0 => {
                let i = rng.below(len);
                data[i] = *rng.pick(INTERESTING_BYTES).unwrap_or(&0);
            }
            3 if len > 0 => {
                let n = rng.small_len(64).min(len);
                let at = rng.below(len - n + 1);
                data.drain(at..at + n);
            }
            4 => {
                let n = rng.small_len(32);
                let at = rng.below(len + 1);
                let bytes: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
                data.splice(at..at, bytes);
            }
            5 if len > 0 => {
                let n = rng.small_len(256).min(len);
                let from = rng.below(len - n + 1);
                let at = rng.below(len + 1);
                let copy = data[from..from + n].to_vec();
                data.splice(at..at, copy);
            }
            6 if len > 0 => {
                let at = rng.below(len);
                data.truncate(at);
            }
            7..=9 => {
                // A token replaced by an interesting one (or one inserted where there is none).
                let tok = self.token(rng);
                match Self::find_token(rng, data) {
                    Some((s, e)) => {
                        data.splice(s..e, tok);
                    }
                    None => {
                        let at = rng.below(len + 1);
                        data.splice(at..at, tok);
                    }
                }
            }
            10 => {
                // A token replaced by another token of the same input.
                if let (Some((s, e)), Some((s2, e2))) =
                    (Self::find_token(rng, data), Self::find_token(rng, data))
                {
                    let other = data[s2..e2].to_vec();
                    data.splice(s..e, other);
                }
            }
            11 => {
                // A number tweaked: negated, scaled by a power of ten, or given more digits.
                if let Some((s, e)) = Self::find_token(rng, data) {
                    let t = String::from_utf8_lossy(&data[s..e]).into_owned();
                    let new = match rng.below(4) {
                        0 => format!("-{t}"),
                        1 => format!("{t}e{}", rng.range(1, 400)),
                        2 => format!("{t}{}", "9".repeat(rng.small_len(400))),
                        _ => format!("{t}e-{}", rng.range(1, 400)),
                    };
                    data.splice(s..e, new.into_bytes());
                }
            }
            12 => {
                // A line duplicated right after itself (duplicate keys) or elsewhere.
                let (s, e) = Self::find_line(rng, data);
                let mut line = data[s..e].to_vec();
                line.push(b'\n');
                let at = if rng.one_in(2) {
                    (e + 1).min(data.len())
                } else {
                    Self::find_line(rng, data).0
                };
                data.splice(at..at, line);
            }
            13 if len > 0 => {
                let (s, e) = Self::find_line(rng, data);
                let e = (e + 1).min(data.len());
                data.drain(s..e);
            }
            14 if len > 0 => {
                let (s1, e1) = Self::find_line(rng, data);
                let (s2, e2) = Self::find_line(rng, data);
                if e1 <= s2 {
                    let a = data[s1..e1].to_vec();
                    let b = data[s2..e2].to_vec();
                    data.splice(s2..e2, a);
                    data.splice(s1..e1, b);
                }
            }
            15 => {
                // A line repeated many times: inputs of every length, up to megabytes.
                let (s, e) = Self::find_line(rng, data);
                let mut line = data[s..e].to_vec();
                line.push(b'\n');
                let most = if rng.one_in(20) { 20_000 } else { 200 };
                let times = rng.small_len(most).min(self.max_len / line.len().max(1));
                let block: Vec<u8> = line
                    .iter()
                    .copied()
                    .cycle()
                    .take(line.len() * times)
                    .collect();
                data.splice(s..s, block);
            }
            16 if len > 0 => {
                // A run of one digit: a number no integer type holds.
                let at = rng.below(len + 1);
                let digit = b'0' + rng.below(10) as u8;
                data.splice(at..at, std::iter::repeat_n(digit, rng.small_len(1000)));
            }
            17 => {
                // Crossover: the head of this input and the tail of another seed.
                if let Some(other) = rng.pick(&self.seeds) {
                    let cut = rng.below(data.len() + 1);
                    let from = rng.below(other.len() + 1);
                    data.truncate(cut);
                    data.extend_from_slice(&other[from..]);
                }
            }
            18 => {
                let at = rng.below(len + 1);
                let junk: &[u8] = match rng.below(4) {
                    0 => b"\xef\xbb\xbf",
                    1 => b"\r\n",
                    2 => b"\xed\xa0\x80",
                    _ => b"\x00",
                };
                data.splice(at..at, junk.iter().copied());
            }
            _ => {
                let tok = self.token(rng);
                let at = rng.below(len + 1);
                data.splice(at..at, tok);
            }
        }
        data.truncate(self.max_len);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inputs_repeat_with_the_seed_and_vary_and_stay_bounded() {
        let m = Mutator::new(vec![b"1.0 rgb/a.png\n2.0 rgb/b.png\n".to_vec()], vec![]);
        let gen = |seed| {
            let mut r = Rng::new(seed);
            (0..200).map(|_| m.input(&mut r)).collect::<Vec<_>>()
        };
        let a = gen(3);
        assert_eq!(a, gen(3));
        assert_ne!(a, gen(4));
        let distinct: std::collections::BTreeSet<_> = a.iter().collect();
        assert!(distinct.len() > 150, "{}", distinct.len());
        assert!(a.iter().all(|x| x.len() <= m.max_len));
        // Some inputs are empty, some are not UTF-8, some are long.
        let mut r = Rng::new(5);
        let many: Vec<Vec<u8>> = (0..5000).map(|_| m.input(&mut r)).collect();
        assert!(many.iter().any(|x| x.is_empty()));
        assert!(many.iter().any(|x| std::str::from_utf8(x).is_err()));
        assert!(many.iter().any(|x| x.len() > 100_000));
    }
}
