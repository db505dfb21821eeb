//! FAST-9 corner detection (Rosten & Drummond 2006) with its score and 3x3 non-maximum
//! suppression, written for speed: a branch-free pre-test on the four cardinal circle pixels
//! (1, 5, 9, 13 in the usual 1-based numbering) over whole row slices, then the full 16-pixel
//! arc test and score only on the survivors.
//!
//! Definitions (the brute-force reference in the tests spells them out): a pixel `p` is a corner
//! at threshold `t` when 9 contiguous pixels of the radius-3 Bresenham circle are all brighter
//! than `p + t` or all darker than `p - t`. Its score is the largest `t` for which it is still a
//! corner, so "corner at `t`" is "score >= `t`". A corner survives non-maximum suppression when
//! its score is strictly above the score of every 8-neighbour that is itself a corner at `t`
//! inside the searched rectangle (as OpenCV's FAST, which ORB-SLAM2 calls).

use crate::image::GrayImage;

/// The 16 offsets (dx, dy) of the radius-3 Bresenham circle, clockwise from the top.
pub const CIRCLE: [(i32, i32); 16] = [
    (0, -3),
    (1, -3),
    (2, -2),
    (3, -1),
    (3, 0),
    (3, 1),
    (2, 2),
    (1, 3),
    (0, 3),
    (-1, 3),
    (-2, 2),
    (-3, 1),
    (-3, 0),
    (-3, -1),
    (-2, -2),
    (-1, -3),
];

/// A detected corner: pixel position on its level and FAST score.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Corner {
    /// Row (first so that sorting gives raster order).
    pub y: u32,
    /// Column.
    pub x: u32,
    /// FAST score (see the module doc).
    pub score: u8,
}

/// A half-open pixel rectangle `[x0, x1) x [y0, y1)` of candidate corner centres.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    /// First column.
    pub x0: usize,
    /// First row.
    pub y0: usize,
    /// One past the last column.
    pub x1: usize,
    /// One past the last row.
    pub y1: usize,
}

/// Reusable buffers of [`detect`], so detection allocates nothing once warmed up.
#[derive(Clone, Debug, Default)]
pub struct FastScratch {
    scores: Vec<u8>,
    cand: Vec<u8>,
    raw: Vec<Corner>,
    /// Pixels that passed the cardinal pre-test in the last call (a diagnostic).
    pub candidates: usize,
}

/// Detects FAST-9 corners at `threshold` (clamped to >= 1) with centres inside `rect`, applies
/// non-maximum suppression within `rect`, and appends the survivors to `out` in raster order.
/// `rect` is clipped so the circle stays inside the image (3 px from every border).
pub fn detect(
    img: &GrayImage,
    rect: Rect,
    threshold: u8,
    scratch: &mut FastScratch,
    out: &mut Vec<Corner>,
) {
    let t = threshold.max(1);
    let (w, h) = (img.width, img.height);
    if w < 7 || h < 7 {
        return;
    }
    let x0 = rect.x0.max(3);
    let y0 = rect.y0.max(3);
    let x1 = rect.x1.min(w - 3);
    let y1 = rect.y1.min(h - 3);
    if x0 >= x1 || y0 >= y1 {
        return;
    }
    let rw = x1 - x0;
    let rh = y1 - y0;
    scratch.scores.clear();
    scratch.scores.resize(rw * rh, 0);
    scratch.cand.clear();
    scratch.cand.resize(rw.next_multiple_of(8), 0);
    scratch.raw.clear();
    scratch.candidates = 0;
    let offsets: [isize; 16] = CIRCLE.map(|(dx, dy)| dy as isize * w as isize + dx as isize);
    let data = &img.data;
    for y in y0..y1 {
        let row = &data[y * w..(y + 1) * w];
        let up = &data[(y - 3) * w..(y - 2) * w];
        let down = &data[(y + 3) * w..(y + 4) * w];
        let up2 = &data[(y - 2) * w..(y - 1) * w];
        let down2 = &data[(y + 2) * w..(y + 3) * w];
        let up1 = &data[(y - 1) * w..y * w];
        let down1 = &data[(y + 1) * w..(y + 2) * w];
        // Circle pixels 0..16 as row slices aligned with the centre slice.
        let ring: [&[u8]; 16] = [
            &up[x0..x1],
            &up[x0 + 1..x1 + 1],
            &up2[x0 + 2..x1 + 2],
            &up1[x0 + 3..x1 + 3],
            &row[x0 + 3..x1 + 3],
            &down1[x0 + 3..x1 + 3],
            &down2[x0 + 2..x1 + 2],
            &down[x0 + 1..x1 + 1],
            &down[x0..x1],
            &down[x0 - 1..x1 - 1],
            &down2[x0 - 2..x1 - 2],
            &down1[x0 - 3..x1 - 3],
            &row[x0 - 3..x1 - 3],
            &up1[x0 - 3..x1 - 3],
            &up2[x0 - 2..x1 - 2],
            &up[x0 - 1..x1 - 1],
        ];
        pretest(&row[x0..x1], &ring, t, &mut scratch.cand[..rw]);
        let score_row = &mut scratch.scores[(y - y0) * rw..(y - y0 + 1) * rw];
        for (chunk_i, chunk) in scratch.cand.chunks_exact(8).enumerate() {
            // Bytes are 0 or 1: visit the set ones by their lowest bit.
            let mut word = u64::from_le_bytes(chunk.try_into().expect("8 bytes"));
            while word != 0 {
                let i = chunk_i * 8 + (word.trailing_zeros() / 8) as usize;
                word &= word - 1;
                scratch.candidates += 1;
                let x = x0 + i;
                let centre = y * w + x;
                if let Some(s) = corner_score(data, centre, &offsets, t) {
                    score_row[i] = s;
                    scratch.raw.push(Corner {
                        y: y as u32,
                        x: x as u32,
                        score: s,
                    });
                }
            }
        }
    }
    // Non-maximum suppression on the score buffer (0 = not a corner at `t`).
    let scores = &scratch.scores;
    for c in &scratch.raw {
        let i = c.x as usize - x0;
        let j = c.y as usize - y0;
        let s = c.score;
        let ia = i.saturating_sub(1);
        let ib = (i + 1).min(rw - 1);
        let ja = j.saturating_sub(1);
        let jb = (j + 1).min(rh - 1);
        let mut is_max = true;
        'n: for jj in ja..=jb {
            let r = &scores[jj * rw..(jj + 1) * rw];
            for (ii, &v) in r.iter().enumerate().take(ib + 1).skip(ia) {
                if (ii != i || jj != j) && v >= s {
                    is_max = false;
                    break 'n;
                }
            }
        }
        if is_max {
            out.push(*c);
        }
    }
}

/// Branch-free necessary condition of a FAST-9 corner, over equal-length row slices (`ring[k]`
/// holds circle pixel k of every centre) so the compiler vectorizes it. An arc of 9 contiguous
/// circle pixels contains two consecutive cardinal pixels (0-4, 4-8, 8-12 or 12-0) and one
/// pixel of every opposite pair (k, k + 8); all of these must be brighter than `p + t` (or all
/// darker than `p - t`).
#[inline]
fn pretest(centre: &[u8], ring: &[&[u8]; 16], t: u8, out: &mut [u8]) {
    let n = centre.len();
    let r: [&[u8]; 16] = std::array::from_fn(|k| &ring[k][..n]);
    let out = &mut out[..n];
    for i in 0..n {
        let p = centre[i];
        let hi = p.saturating_add(t);
        let lo = p.saturating_sub(t);
        let b: [bool; 16] = std::array::from_fn(|k| r[k][i] > hi);
        let d: [bool; 16] = std::array::from_fn(|k| r[k][i] < lo);
        let mut bright = (b[0] & b[4]) | (b[4] & b[8]) | (b[8] & b[12]) | (b[12] & b[0]);
        let mut dark = (d[0] & d[4]) | (d[4] & d[8]) | (d[8] & d[12]) | (d[12] & d[0]);
        for k in [1, 2, 3, 5, 6, 7] {
            bright &= b[k] | b[k + 8];
            dark &= d[k] | d[k + 8];
        }
        out[i] = (bright | dark) as u8;
    }
}

/// Whether a 16-bit circular mask holds 9 contiguous set bits.
#[inline]
fn has_arc9(mask: u32) -> bool {
    let m = mask | (mask << 16);
    let a = m & (m >> 1); // runs of 2
    let b = a & (a >> 2); // runs of 4
    let c = b & (b >> 4); // runs of 8
    (c & (m >> 8)) & 0xffff != 0
}

/// Full FAST-9 test at threshold `t` of the pixel at linear index `centre`; `Some(score)` when
/// it is a corner. Branch-free up to the arc test (early exits mispredict more than they save).
#[inline]
fn corner_score(data: &[u8], centre: usize, offsets: &[isize; 16], t: u8) -> Option<u8> {
    let p = data[centre] as i16;
    let ti = t as i16;
    let mut d = [0i16; 25];
    let (mut bright, mut dark) = (0u32, 0u32);
    for (k, (dk, &o)) in d.iter_mut().zip(offsets).enumerate() {
        let x = data[(centre as isize + o) as usize] as i16 - p;
        *dk = x;
        bright |= ((x > ti) as u32) << k;
        dark |= ((x < -ti) as u32) << k;
    }
    let is_bright = has_arc9(bright);
    if !is_bright && !has_arc9(dark) {
        return None;
    }
    for k in 0..9 {
        d[16 + k] = d[k];
    }
    if !is_bright {
        for x in d.iter_mut() {
            *x = -*x;
        }
    }
    // Largest over the 16 arcs of the smallest difference along the arc.
    let mut a2 = [0i16; 24];
    for k in 0..24 {
        a2[k] = d[k].min(d[k + 1]);
    }
    let mut a4 = [0i16; 22];
    for k in 0..22 {
        a4[k] = a2[k].min(a2[k + 2]);
    }
    let mut best = i16::MIN;
    for k in 0..16 {
        best = best.max(a4[k].min(a4[k + 4]).min(d[k + 8]));
    }
    // Corner at threshold s iff every difference on some arc exceeds s: largest s = best - 1.
    Some((best - 1).clamp(0, 255) as u8)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random test image: noise plus bright and dark rectangles, lightly smoothed.
    pub(crate) fn random_image(w: usize, h: usize, seed: u64) -> GrayImage {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut img = GrayImage::new(w, h);
        for v in img.data.iter_mut() {
            *v = rng.random_range(60..140);
        }
        for _ in 0..40 {
            let x0 = rng.random_range(0..w);
            let y0 = rng.random_range(0..h);
            let x1 = (x0 + rng.random_range(3..w / 3)).min(w);
            let y1 = (y0 + rng.random_range(3..h / 3)).min(h);
            let v: u8 = rng.random_range(0..=255);
            for y in y0..y1 {
                for x in x0..x1 {
                    img.data[y * w + x] = v / 2 + img.data[y * w + x] / 4;
                }
            }
        }
        img
    }

    /// Brute-force FAST score straight from the definition, or -1 when not a corner at 0.
    fn ref_score(img: &GrayImage, x: usize, y: usize) -> i32 {
        let p = img.get(x, y) as i32;
        let circ: Vec<i32> = CIRCLE
            .iter()
            .map(|&(dx, dy)| img.get((x as i32 + dx) as usize, (y as i32 + dy) as usize) as i32)
            .collect();
        let mut best = -1;
        for t in 0..=255 {
            let mut corner = false;
            for start in 0..16 {
                let all_b = (0..9).all(|k| circ[(start + k) % 16] > p + t);
                let all_d = (0..9).all(|k| circ[(start + k) % 16] < p - t);
                if all_b || all_d {
                    corner = true;
                    break;
                }
            }
            if corner {
                best = t;
            } else {
                break;
            }
        }
        best
    }

    fn ref_detect(img: &GrayImage, rect: Rect, t: u8) -> Vec<Corner> {
        let t = t as i32;
        let mut s = vec![-1; img.width * img.height];
        for y in rect.y0..rect.y1 {
            for x in rect.x0..rect.x1 {
                s[y * img.width + x] = ref_score(img, x, y);
            }
        }
        let mut out = Vec::new();
        for y in rect.y0..rect.y1 {
            for x in rect.x0..rect.x1 {
                let c = s[y * img.width + x];
                if c < t {
                    continue;
                }
                let mut keep = true;
                for yy in y.saturating_sub(1)..=y + 1 {
                    for xx in x.saturating_sub(1)..=x + 1 {
                        let inside = xx >= rect.x0 && xx < rect.x1 && yy >= rect.y0 && yy < rect.y1;
                        if (xx, yy) != (x, y) && inside && s[yy * img.width + xx] >= t {
                            keep &= c > s[yy * img.width + xx];
                        }
                    }
                }
                if keep {
                    out.push(Corner {
                        y: y as u32,
                        x: x as u32,
                        score: c as u8,
                    });
                }
            }
        }
        out
    }

    #[test]
    fn fast_equals_brute_force_reference() {
        let mut scratch = FastScratch::default();
        let mut total = 0;
        for seed in 0..4 {
            let img = random_image(97, 71, seed);
            let rects = [
                Rect {
                    x0: 3,
                    y0: 3,
                    x1: 94,
                    y1: 68,
                },
                Rect {
                    x0: 20,
                    y0: 11,
                    x1: 57,
                    y1: 40,
                },
            ];
            for rect in rects {
                for t in [1u8, 7, 20, 40] {
                    let mut got = Vec::new();
                    detect(&img, rect, t, &mut scratch, &mut got);
                    let want = ref_detect(&img, rect, t);
                    assert_eq!(got, want, "seed {seed} rect {rect:?} t {t}");
                    total += got.len();
                }
            }
        }
        assert!(total > 500, "test images too flat: {total} corners");
    }

    #[test]
    fn arc_test_detects_runs_across_the_wrap() {
        assert!(has_arc9(0x01ff));
        assert!(has_arc9(0xf81f)); // bits 11..15 and 0..4 = 10 contiguous through the wrap
        assert!(!has_arc9(0x00ff));
        assert!(!has_arc9(0xf00f));
        assert!(has_arc9(0xffff));
    }
}
