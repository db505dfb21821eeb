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

/// Reusable buffers of [`detect`] and [`detect_adaptive`], so detection allocates nothing once
/// warmed up.
#[derive(Clone, Debug, Default)]
pub struct FastScratch {
    /// Score map of the whole image (0 = not a corner at the threshold of the pass that
    /// visited the pixel, or not visited).
    map: Vec<u8>,
    /// Pre-test flags of one row segment (0 or 1 per pixel, padded to a multiple of 8).
    cand: Vec<u8>,
    /// Corners found by the current pass, before non-maximum suppression.
    raw: Vec<Corner>,
    /// Pixels that passed the pre-test in the last call (a diagnostic).
    pub candidates: usize,
}

/// The cells of the adaptive threshold: `n_cols x n_rows` cells of `cw x ch` pixels starting
/// at (x0, y0); the last column ends at `x_end` and the last row at `y_end` instead.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CellLayout {
    /// Left edge of the first column.
    pub x0: usize,
    /// Top edge of the first row.
    pub y0: usize,
    /// Cell width.
    pub cw: usize,
    /// Cell height.
    pub ch: usize,
    /// Number of columns (>= 1).
    pub n_cols: usize,
    /// Number of rows (>= 1).
    pub n_rows: usize,
    /// Right edge (exclusive) of the last column.
    pub x_end: usize,
    /// Bottom edge (exclusive) of the last row.
    pub y_end: usize,
}

impl CellLayout {
    /// The rectangle of cell (i, j).
    pub fn cell(&self, i: usize, j: usize) -> Rect {
        Rect {
            x0: self.x0 + i * self.cw,
            y0: self.y0 + j * self.ch,
            x1: if i + 1 == self.n_cols {
                self.x_end
            } else {
                self.x0 + (i + 1) * self.cw
            },
            y1: if j + 1 == self.n_rows {
                self.y_end
            } else {
                self.y0 + (j + 1) * self.ch
            },
        }
    }

    /// Index `j * n_cols + i` of the cell holding pixel (x, y) (x >= x0, y >= y0).
    #[inline]
    pub fn index_of(&self, x: usize, y: usize) -> usize {
        let i = ((x - self.x0) / self.cw).min(self.n_cols - 1);
        let j = ((y - self.y0) / self.ch).min(self.n_rows - 1);
        j * self.n_cols + i
    }
}

/// `rect` clipped so the circle stays inside a `w x h` image, or `None` when empty.
fn clip(rect: Rect, w: usize, h: usize) -> Option<Rect> {
    if w < 7 || h < 7 {
        return None;
    }
    let r = Rect {
        x0: rect.x0.max(3),
        y0: rect.y0.max(3),
        x1: rect.x1.min(w - 3),
        y1: rect.y1.min(h - 3),
    };
    (r.x0 < r.x1 && r.y0 < r.y1).then_some(r)
}

/// Linear offsets of the circle pixels in an image of width `w`.
fn circle_offsets(w: usize) -> [isize; 16] {
    CIRCLE.map(|(dx, dy)| dy as isize * w as isize + dx as isize)
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
    let Some(r) = clip(rect, w, h) else {
        return;
    };
    scratch.map.clear();
    scratch.map.resize(w * h, 0);
    scratch.raw.clear();
    scratch.candidates = 0;
    let offsets = circle_offsets(w);
    for y in r.y0..r.y1 {
        scan_row(img, y, r.x0, r.x1, t, &offsets, scratch);
    }
    for c in &scratch.raw {
        if is_local_max(&scratch.map, w, c, Some(r)) {
            out.push(*c);
        }
    }
}

/// FAST with ORB-SLAM2's adaptive threshold, in one sweep: corners at `ini_th` over `area`
/// (non-maximum suppression across the whole area), then, in every cell of `cells` left
/// without a corner, corners at `min_th` (suppression within the cell). Appends the corners in
/// raster order to `out`; `cell_counts` receives the number of `ini_th` corners per cell.
///
/// The result is exactly that of [`detect`] over `area` at `ini_th` followed by [`detect`] on
/// every empty cell at `min_th` (a test checks it), but it shares one score map between the
/// two passes (a corner's score does not depend on the threshold), so no pixel is scored twice,
/// and the low-threshold pass runs over whole runs of adjacent empty cells in a row.
#[allow(clippy::too_many_arguments)]
pub fn detect_adaptive(
    img: &GrayImage,
    area: Rect,
    cells: &CellLayout,
    ini_th: u8,
    min_th: u8,
    scratch: &mut FastScratch,
    cell_counts: &mut Vec<u32>,
    out: &mut Vec<Corner>,
) {
    let (w, h) = (img.width, img.height);
    cell_counts.clear();
    cell_counts.resize(cells.n_cols * cells.n_rows, 0);
    if w < 7 || h < 7 {
        return;
    }
    let t_hi = ini_th.max(1);
    let t_lo = min_th.max(1);
    scratch.map.clear();
    scratch.map.resize(w * h, 0);
    scratch.raw.clear();
    scratch.candidates = 0;
    let offsets = circle_offsets(w);
    // Pass 1: the whole area at the high threshold. The map is zero outside the area, so the
    // suppression needs no bounds test.
    let start = out.len();
    if let Some(r) = clip(area, w, h) {
        for y in r.y0..r.y1 {
            scan_row(img, y, r.x0, r.x1, t_hi, &offsets, scratch);
        }
        for c in &scratch.raw {
            if is_local_max(&scratch.map, w, c, None) {
                out.push(*c);
                cell_counts[cells.index_of(c.x as usize, c.y as usize)] += 1;
            }
        }
    }
    let n_high = out.len();
    // Pass 2: empty cells at the low threshold, row by row over runs of adjacent empty cells.
    // A pixel already scored in pass 1 keeps its score (it is the same at any threshold).
    scratch.raw.clear();
    for j in 0..cells.n_rows {
        let counts = &cell_counts[j * cells.n_cols..(j + 1) * cells.n_cols];
        let mut i = 0;
        while i < cells.n_cols {
            if counts[i] > 0 {
                i += 1;
                continue;
            }
            let mut i2 = i + 1;
            while i2 < cells.n_cols && counts[i2] == 0 {
                i2 += 1;
            }
            let run = Rect {
                x0: cells.cell(i, j).x0,
                x1: cells.cell(i2 - 1, j).x1,
                ..cells.cell(i, j)
            };
            if let Some(r) = clip(run, w, h) {
                for y in r.y0..r.y1 {
                    scan_row(img, y, r.x0, r.x1, t_lo, &offsets, scratch);
                }
            }
            i = i2;
        }
    }
    for c in &scratch.raw {
        let k = cells.index_of(c.x as usize, c.y as usize);
        let cell = cells.cell(k % cells.n_cols, k / cells.n_cols);
        if let Some(r) = clip(cell, w, h) {
            if is_local_max(&scratch.map, w, c, Some(r)) {
                out.push(*c);
            }
        }
    }
    if out.len() > n_high {
        out[start..].sort_unstable();
    }
}

/// Pre-tests row `y` over columns `[x0, x1)` at threshold `t` and scores every candidate not
/// scored before: corners get their score written to the map and are appended to the raw list.
#[inline]
fn scan_row(
    img: &GrayImage,
    y: usize,
    x0: usize,
    x1: usize,
    t: u8,
    offsets: &[isize; 16],
    scratch: &mut FastScratch,
) {
    let w = img.width;
    let data = &img.data;
    let rw = x1 - x0;
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
    let padded = rw.next_multiple_of(8);
    if scratch.cand.len() < padded {
        scratch.cand.resize(padded, 0);
    }
    pretest(&row[x0..x1], &ring, t, &mut scratch.cand[..rw]);
    scratch.cand[rw..padded].fill(0);
    let map_row = &mut scratch.map[y * w..(y + 1) * w];
    for (chunk_i, chunk) in scratch.cand[..padded].chunks_exact(8).enumerate() {
        // Bytes are 0 or 1: visit the set ones by their lowest bit.
        let mut word = u64::from_le_bytes(chunk.try_into().expect("8 bytes"));
        while word != 0 {
            let i = chunk_i * 8 + (word.trailing_zeros() / 8) as usize;
            word &= word - 1;
            scratch.candidates += 1;
            let x = x0 + i;
            let known = map_row[x];
            let score = if known != 0 {
                (known >= t).then_some(known)
            } else {
                corner_score(data, y * w + x, offsets, t)
            };
            if let Some(s) = score {
                map_row[x] = s;
                scratch.raw.push(Corner {
                    y: y as u32,
                    x: x as u32,
                    score: s,
                });
            }
        }
    }
}

/// Whether corner `c` scores strictly above every 8-neighbour in the map (restricted to
/// `rect` when given; the map holds 0 for pixels that are not corners).
#[inline]
fn is_local_max(map: &[u8], w: usize, c: &Corner, rect: Option<Rect>) -> bool {
    let (x, y, s) = (c.x as usize, c.y as usize, c.score);
    match rect {
        None => {
            let above = &map[(y - 1) * w + x - 1..(y - 1) * w + x + 2];
            let here = &map[y * w + x - 1..y * w + x + 2];
            let below = &map[(y + 1) * w + x - 1..(y + 1) * w + x + 2];
            above.iter().chain(below).all(|&v| v < s) && here[0] < s && here[2] < s
        }
        Some(r) => {
            let xa = x.saturating_sub(1).max(r.x0);
            let xb = (x + 1).min(r.x1 - 1);
            let ya = y.saturating_sub(1).max(r.y0);
            let yb = (y + 1).min(r.y1 - 1);
            (ya..=yb).all(|yy| {
                map[yy * w + xa..=yy * w + xb]
                    .iter()
                    .enumerate()
                    .all(|(k, &v)| v < s || (xa + k == x && yy == y))
            })
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

    /// The adaptive detector as the composition of plain detections it replaces: the area at
    /// the high threshold, then each cell without a corner at the low one, merged and sorted.
    fn adaptive_reference(
        img: &GrayImage,
        area: Rect,
        cells: &CellLayout,
        hi: u8,
        lo: u8,
    ) -> Vec<Corner> {
        let mut scratch = FastScratch::default();
        let mut out = Vec::new();
        detect(img, area, hi, &mut scratch, &mut out);
        let mut counts = vec![0; cells.n_cols * cells.n_rows];
        for c in &out {
            counts[cells.index_of(c.x as usize, c.y as usize)] += 1;
        }
        for j in 0..cells.n_rows {
            for i in 0..cells.n_cols {
                if counts[j * cells.n_cols + i] == 0 {
                    detect(img, cells.cell(i, j), lo, &mut scratch, &mut out);
                }
            }
        }
        out.sort_unstable();
        out
    }

    #[test]
    fn adaptive_detection_equals_plain_detections() {
        let mut scratch = FastScratch::default();
        let mut counts = Vec::new();
        let mut n_low_cells = 0;
        // Sizes include a wide image whose cells overhang the detection area.
        for (seed, (w, h)) in [(160usize, 120usize), (333, 211), (1403, 97), (64, 64)]
            .into_iter()
            .enumerate()
        {
            let mut img = random_image(w, h, 50 + seed as u64);
            // Flatten the left third so that cells there need the low threshold.
            for y in 0..h {
                for x in 0..w / 3 {
                    let v = &mut img.data[y * w + x];
                    *v = 100 + *v / 12;
                }
            }
            let e = 19;
            let area = Rect {
                x0: e,
                y0: e,
                x1: w - e,
                y1: h - e,
            };
            let (aw, ah) = (w - 2 * (e - 3), h - 2 * (e - 3));
            let n_cols = (aw / 30).max(1);
            let n_rows = (ah / 30).max(1);
            let cells = CellLayout {
                x0: e,
                y0: e,
                cw: aw.div_ceil(n_cols),
                ch: ah.div_ceil(n_rows),
                n_cols,
                n_rows,
                x_end: w - e,
                y_end: h - e,
            };
            for (hi, lo) in [(20u8, 7u8), (40, 3), (7, 20), (12, 12)] {
                let mut got = vec![Corner {
                    y: 0,
                    x: 0,
                    score: 0,
                }];
                detect_adaptive(
                    &img,
                    area,
                    &cells,
                    hi,
                    lo,
                    &mut scratch,
                    &mut counts,
                    &mut got,
                );
                let want = adaptive_reference(&img, area, &cells, hi, lo);
                assert_eq!(
                    got[0],
                    Corner {
                        y: 0,
                        x: 0,
                        score: 0
                    },
                    "prefix kept"
                );
                assert_eq!(&got[1..], &want[..], "{w}x{h} thresholds {hi}/{lo}");
                n_low_cells += counts.iter().filter(|&&c| c == 0).count();
            }
        }
        assert!(
            n_low_cells > 20,
            "only {n_low_cells} cells used the low threshold"
        );
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
