//! FAST-9 corner detection (Rosten & Drummond 2006) with its score and 3x3 non-maximum
//! suppression, written for speed: the score of every pixel of the searched area is computed
//! at once, branch-free, over whole row slices (16 or 32 pixels per vector instruction), into a
//! score map; detection at any threshold is then a scan of the map and a 3x3 comparison.
//!
//! Definitions (the brute-force reference in the tests spells them out): a pixel `p` is a corner
//! at threshold `t` when 9 contiguous pixels of the radius-3 Bresenham circle are all brighter
//! than `p + t` or all darker than `p - t`. Its score is the largest `t` for which it is still a
//! corner, so "corner at `t`" is "score >= `t`" (a pixel that is no corner at `t = 0` scores
//! 0, like one that is a corner only at 0; thresholds are at least 1). A corner survives
//! non-maximum suppression when its score is strictly above the score of every 8-neighbour that
//! is itself a corner at `t` inside the searched rectangle (as OpenCV's FAST, which ORB-SLAM2
//! calls). A neighbour scoring below `t` also scores below the corner, so the suppression can
//! compare raw scores without looking at `t`.
//!
//! Why a dense score map: the candidate-driven detector (pre-test, then the full arc test and
//! score pixel by pixel) spent most of its time in scalar gathers of the 16 circle pixels of
//! ~80 000 candidates per 640x480 pyramid and in scanning the empty cells a second time at the
//! low threshold. The map costs about 200 vector operations per 16 pixels, needs no gather, and
//! serves both thresholds of the adaptive detector: the score does not depend on the threshold.

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
    /// Score map of the whole image: the FAST score inside the scored rectangle, 0 elsewhere.
    map: Vec<u8>,
    /// Local-maximum flags of one row (0 or 1 per pixel, padded to a multiple of 8).
    flags: Vec<u8>,
    /// Scores of one cell with a border of zeros, for suppression limited to the cell.
    patch: Vec<u8>,
    /// The corners of both passes merged into raster order.
    merged: Vec<Corner>,
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
    /// ORB-SLAM2's detection area and cells of a `w` x `h` level: corners in
    /// `[edge, dim - edge)`; cells sized over ORB-SLAM2's span `[edge - 3, dim - edge + 3]`,
    /// floor(span / `cell`) of them, each ceil(span / n) wide (detection inside a cell is 3 px
    /// in from its window).
    /// `None` when the level is too small for any corner.
    pub fn orb_slam2(w: usize, h: usize, edge: usize, cell: usize) -> Option<(Rect, CellLayout)> {
        if w <= 2 * edge + 1 || h <= 2 * edge + 1 {
            return None;
        }
        let area = Rect {
            x0: edge,
            y0: edge,
            x1: w - edge,
            y1: h - edge,
        };
        let (aw, ah) = (w - 2 * (edge - 3), h - 2 * (edge - 3));
        let n_cols = (aw / cell).max(1);
        let n_rows = (ah / cell).max(1);
        let cells = CellLayout {
            x0: edge,
            y0: edge,
            cw: aw.div_ceil(n_cols),
            ch: ah.div_ceil(n_rows),
            n_cols,
            n_rows,
            x_end: w - edge,
            y_end: h - edge,
        };
        Some((area, cells))
    }

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
    score_map(img, r, &mut scratch.map);
    // The map is 0 around `r`, as the suppression wants it.
    local_maxima(&scratch.map, w, r, t, &mut scratch.flags, |c| out.push(c));
}

/// FAST with ORB-SLAM2's adaptive threshold: corners at `ini_th` over `area` (non-maximum
/// suppression across the whole area), then, in every cell of `cells` left without a corner,
/// corners at `min_th` (suppression within the cell). Appends the corners in raster order to
/// `out`; `cell_counts` receives the number of `ini_th` corners per cell.
///
/// The result is exactly that of [`detect`] over `area` at `ini_th` followed by [`detect`] on
/// every empty cell at `min_th` (a test checks it), but every pixel is scored once: both passes
/// read the same score map.
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
    let t_hi = ini_th.max(1);
    let t_lo = min_th.max(1);
    // Score the bounding box of the area and the cells (they coincide in the extractor).
    let scored = Rect {
        x0: area.x0.min(cells.x0),
        y0: area.y0.min(cells.y0),
        x1: area.x1.max(cells.x_end),
        y1: area.y1.max(cells.y_end),
    };
    let Some(scored) = clip(scored, w, h) else {
        return;
    };
    let FastScratch {
        map,
        flags,
        patch,
        merged,
    } = scratch;
    score_map(img, scored, map);
    // Pass 1: the whole area at the high threshold.
    let start = out.len();
    if let Some(a) = clip(area, w, h) {
        let mut emit = |c: Corner| {
            cell_counts[cells.index_of(c.x as usize, c.y as usize)] += 1;
            out.push(c);
        };
        if a == scored {
            // The map is 0 around the area.
            local_maxima(map, w, a, t_hi, flags, &mut emit);
        } else {
            local_maxima_within(map, w, a, t_hi, patch, flags, &mut emit);
        }
    }
    let n_high = out.len();
    // Pass 2: each empty cell at the low threshold, suppression within the cell.
    for j in 0..cells.n_rows {
        for i in 0..cells.n_cols {
            if cell_counts[j * cells.n_cols + i] > 0 {
                continue;
            }
            if let Some(r) = clip(cells.cell(i, j), w, h) {
                local_maxima_within(map, w, r, t_lo, patch, flags, |c| out.push(c));
            }
        }
    }
    // Raster order: sort the low-threshold corners and merge them with the (already sorted)
    // high-threshold ones. They lie in different cells, so no two share a pixel.
    if out.len() > n_high {
        out[n_high..].sort_unstable();
        merged.clear();
        let (high, low) = out[start..].split_at(n_high - start);
        let (mut i, mut j) = (0, 0);
        while i < high.len() && j < low.len() {
            if high[i] < low[j] {
                merged.push(high[i]);
                i += 1;
            } else {
                merged.push(low[j]);
                j += 1;
            }
        }
        merged.extend_from_slice(&high[i..]);
        merged.extend_from_slice(&low[j..]);
        out[start..].copy_from_slice(merged);
    }
}

/// [`local_maxima`] with the suppression blind to everything outside `r`: the scores of `r`
/// are copied into `patch` with a border of zeros, and the corners mapped back.
fn local_maxima_within(
    map: &[u8],
    w: usize,
    r: Rect,
    t: u8,
    patch: &mut Vec<u8>,
    flags: &mut Vec<u8>,
    mut emit: impl FnMut(Corner),
) {
    let (pw, ph) = (r.x1 - r.x0 + 2, r.y1 - r.y0 + 2);
    patch.clear();
    patch.resize(pw * ph, 0);
    for y in r.y0..r.y1 {
        let dst = (y - r.y0 + 1) * pw + 1;
        patch[dst..dst + r.x1 - r.x0].copy_from_slice(&map[y * w + r.x0..y * w + r.x1]);
    }
    let inner = Rect {
        x0: 1,
        y0: 1,
        x1: pw - 1,
        y1: ph - 1,
    };
    local_maxima(patch, pw, inner, t, flags, |c| {
        emit(Corner {
            x: c.x + r.x0 as u32 - 1,
            y: c.y + r.y0 as u32 - 1,
            score: c.score,
        })
    });
}

/// Calls `emit` in raster order for every pixel of `r` in `map` (row stride `w`) scoring at
/// least `t` and strictly above each of its 8-neighbours. `r` must lie at least one pixel
/// inside the map; the pixels around `r` take part in the comparison, so a caller wanting the
/// suppression limited to `r` keeps them 0. `flags` is scratch.
#[inline]
fn local_maxima(
    map: &[u8],
    w: usize,
    r: Rect,
    t: u8,
    flags: &mut Vec<u8>,
    mut emit: impl FnMut(Corner),
) {
    let n = r.x1 - r.x0;
    let padded = n.next_multiple_of(8);
    flags.clear();
    flags.resize(padded, 0);
    for y in r.y0..r.y1 {
        let row = |yy: usize| &map[yy * w + r.x0 - 1..yy * w + r.x1 + 1];
        local_max_flags(row(y - 1), row(y), row(y + 1), t, &mut flags[..n]);
        // 0/1 bytes read as words; most words are 0. Set bytes are visited by their lowest bit.
        for (k, chunk) in flags.chunks_exact(8).enumerate() {
            let mut word = u64::from_le_bytes(chunk.try_into().expect("8 bytes"));
            while word != 0 {
                let x = r.x0 + k * 8 + (word.trailing_zeros() / 8) as usize;
                word &= word - 1;
                emit(Corner {
                    y: y as u32,
                    x: x as u32,
                    score: map[y * w + x],
                });
            }
        }
    }
}

/// Centres per call of [`local_max_chunk`].
const NMS_LANES: usize = 32;

/// Non-maximum suppression of one row: `out[i]` is 1 when `cur[i + 1]` is at least `t` and
/// strictly above its 8 neighbours in `prev`, `cur` and `next` (each `out.len() + 2` long,
/// starting one pixel left of the first centre). Chunked as [`score_slices`]; AVX2 when the
/// CPU has it, as [`score_slices_dispatch`].
#[inline]
fn local_max_flags(prev: &[u8], cur: &[u8], next: &[u8], t: u8, out: &mut [u8]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: `local_max_flags_avx2` only enables AVX2 code generation for safe code; the
        // CPU supports AVX2, checked on the line above.
        unsafe { local_max_flags_avx2(prev, cur, next, t, out) };
        return;
    }
    local_max_flags_impl(prev, cur, next, t, out);
}

/// [`local_max_flags_impl`] compiled with AVX2 enabled; call only on a CPU that has it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn local_max_flags_avx2(prev: &[u8], cur: &[u8], next: &[u8], t: u8, out: &mut [u8]) {
    local_max_flags_impl(prev, cur, next, t, out);
}

/// The body of [`local_max_flags`].
#[inline(always)]
fn local_max_flags_impl(prev: &[u8], cur: &[u8], next: &[u8], t: u8, out: &mut [u8]) {
    const L: usize = NMS_LANES;
    let n = out.len();
    if n < L {
        let pad = |src: &[u8]| {
            let mut a = [0u8; L + 2];
            a[..n + 2].copy_from_slice(&src[..n + 2]);
            a
        };
        let o = local_max_chunk(&pad(prev), &pad(cur), &pad(next), t);
        out.copy_from_slice(&o[..n]);
        return;
    }
    let mut next_start = 0;
    loop {
        let s = next_start.min(n - L);
        let flags = local_max_chunk(window(prev, s), window(cur, s), window(next, s), t);
        out[s..s + L].copy_from_slice(&flags);
        if s + L == n {
            break;
        }
        next_start += L;
    }
}

/// [`local_max_flags`] of [`NMS_LANES`] centres, branch-free so it vectorizes.
#[inline(always)]
fn local_max_chunk(
    prev: &[u8; NMS_LANES + 2],
    cur: &[u8; NMS_LANES + 2],
    next: &[u8; NMS_LANES + 2],
    t: u8,
) -> [u8; NMS_LANES] {
    let mut out = [0u8; NMS_LANES];
    for (i, o) in out.iter_mut().enumerate() {
        let s = cur[i + 1];
        let m = prev[i]
            .max(prev[i + 1])
            .max(prev[i + 2])
            .max(next[i])
            .max(next[i + 1])
            .max(next[i + 2])
            .max(cur[i])
            .max(cur[i + 2]);
        *o = ((s > m) & (s >= t)) as u8;
    }
    out
}

/// Fills `map` (resized to the image) with the FAST score of every pixel of `r` (which keeps
/// the circle inside the image) and 0 elsewhere.
fn score_map(img: &GrayImage, r: Rect, map: &mut Vec<u8>) {
    let w = img.width;
    map.clear();
    map.resize(w * img.height, 0);
    for y in r.y0..r.y1 {
        score_row(img, y, r.x0, r.x1, &mut map[y * w + r.x0..y * w + r.x1]);
    }
}

/// FAST scores of the pixels `[x0, x1)` of row `y` (3 px inside the image) into `out`.
fn score_row(img: &GrayImage, y: usize, x0: usize, x1: usize, out: &mut [u8]) {
    let (centre, ring) = ring_slices(img, y, x0, x1);
    score_slices_dispatch(centre, &ring, out);
}

/// The centres `[x0, x1)` of row `y` and, for each circle pixel `k`, the row slice holding
/// circle pixel `k` of every centre, aligned with the centres.
fn ring_slices(img: &GrayImage, y: usize, x0: usize, x1: usize) -> (&[u8], [&[u8]; 16]) {
    let w = img.width;
    let data = &img.data;
    let row = |dy: isize| {
        let yy = (y as isize + dy) as usize;
        &data[yy * w..(yy + 1) * w]
    };
    let (up3, up2, up1, mid) = (row(-3), row(-2), row(-1), row(0));
    let (down1, down2, down3) = (row(1), row(2), row(3));
    let ring: [&[u8]; 16] = [
        &up3[x0..x1],
        &up3[x0 + 1..x1 + 1],
        &up2[x0 + 2..x1 + 2],
        &up1[x0 + 3..x1 + 3],
        &mid[x0 + 3..x1 + 3],
        &down1[x0 + 3..x1 + 3],
        &down2[x0 + 2..x1 + 2],
        &down3[x0 + 1..x1 + 1],
        &down3[x0..x1],
        &down3[x0 - 1..x1 - 1],
        &down2[x0 - 2..x1 - 2],
        &down1[x0 - 3..x1 - 3],
        &mid[x0 - 3..x1 - 3],
        &up1[x0 - 3..x1 - 3],
        &up2[x0 - 2..x1 - 2],
        &up3[x0 - 1..x1 - 1],
    ];
    (&mid[x0..x1], ring)
}

/// [`score_slices`] compiled for the best vector width the CPU offers: AVX2 (32 centres per
/// instruction) when present, else the baseline SSE2 build (16). Both compute the same
/// integer results bit for bit; a test compares them.
#[inline]
fn score_slices_dispatch(centre: &[u8], ring: &[&[u8]; 16], out: &mut [u8]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: `score_slices_avx2` only enables AVX2 code generation for safe code; the
        // CPU supports AVX2, checked on the line above.
        unsafe { score_slices_avx2(centre, ring, out) };
        return;
    }
    score_slices(centre, ring, out);
}

/// [`score_slices`] compiled with AVX2 enabled; call only on a CPU that has it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn score_slices_avx2(centre: &[u8], ring: &[&[u8]; 16], out: &mut [u8]) {
    score_slices(centre, ring, out);
}

/// Centres scored per call of [`score_chunk`]: one AVX2 register of bytes, two SSE2 ones.
const SCORE_LANES: usize = 32;

/// The FAST score of every centre pixel, `ring[k][i]` being circle pixel `k` of centre `i`,
/// in chunks of [`SCORE_LANES`] centres. The last chunk overlaps the one before instead of
/// falling back to scalar code (recomputing a score gives the same value); a row shorter than
/// a chunk is zero-padded.
#[inline(always)]
fn score_slices(centre: &[u8], ring: &[&[u8]; 16], out: &mut [u8]) {
    const L: usize = SCORE_LANES;
    let n = centre.len();
    if n < L {
        let pad = |src: &[u8]| {
            let mut a = [0u8; L];
            a[..n].copy_from_slice(&src[..n]);
            a
        };
        let c = pad(centre);
        let r: [[u8; L]; 16] = std::array::from_fn(|k| pad(ring[k]));
        let mut o = [0u8; L];
        score_chunk(&c, &r.each_ref(), &mut o);
        out[..n].copy_from_slice(&o[..n]);
        return;
    }
    let mut next = 0;
    loop {
        let s = next.min(n - L);
        let r: [&[u8; L]; 16] = std::array::from_fn(|k| window(ring[k], s));
        let o: &mut [u8; L] = (&mut out[s..s + L]).try_into().expect("L bytes");
        score_chunk(window(centre, s), &r, o);
        if s + L == n {
            break;
        }
        next += L;
    }
}

/// The `N` bytes of `src` from `start`.
#[inline(always)]
fn window<const N: usize>(src: &[u8], start: usize) -> &[u8; N] {
    src[start..start + N].try_into().expect("N bytes")
}

/// FAST scores of [`SCORE_LANES`] centres: straight-line byte arithmetic the compiler turns
/// into vector instructions over all the centres at once.
///
/// The differences to the centre are taken after the arc extrema: the smallest difference
/// `ring - p` along an arc is `min(ring) - p` (and the largest dark difference is
/// `p - max(ring)`), which saves two subtractions per circle pixel.
#[inline(always)]
fn score_chunk(
    centre: &[u8; SCORE_LANES],
    ring: &[&[u8; SCORE_LANES]; 16],
    out: &mut [u8; SCORE_LANES],
) {
    for i in 0..SCORE_LANES {
        let p = centre[i];
        let v: [u8; 16] = std::array::from_fn(|k| ring[k][i]);
        let bright = best_arc_min(&v).saturating_sub(p);
        let dark = p.saturating_sub(best_arc_max(&v));
        out[i] = bright.max(dark).saturating_sub(1);
    }
}

/// Largest over the 16 arcs of 9 contiguous circle pixels of the smallest value on the arc.
/// With differences `d = ring - p` saturated at 0, the pixel is a bright corner at threshold
/// `t` exactly when this exceeds `t`, so the score is this minus one; dark corners are the
/// mirror image ([`best_arc_max`]). At most one polarity can exceed 0: two arcs of 9 pixels
/// overlap, and no pixel is both brighter and darker than the centre.
#[inline(always)]
fn best_arc_min(d: &[u8; 16]) -> u8 {
    let m2: [u8; 16] = std::array::from_fn(|k| d[k].min(d[(k + 1) % 16]));
    let m4: [u8; 16] = std::array::from_fn(|k| m2[k].min(m2[(k + 2) % 16]));
    let m8: [u8; 16] = std::array::from_fn(|k| m4[k].min(m4[(k + 4) % 16]));
    let mut best = 0;
    for k in 0..16 {
        best = best.max(m8[k].min(d[(k + 8) % 16]));
    }
    best
}

/// Smallest over the 16 arcs of 9 contiguous circle pixels of the largest value on the arc
/// (the dark counterpart of [`best_arc_min`]).
#[inline(always)]
fn best_arc_max(d: &[u8; 16]) -> u8 {
    let m2: [u8; 16] = std::array::from_fn(|k| d[k].max(d[(k + 1) % 16]));
    let m4: [u8; 16] = std::array::from_fn(|k| m2[k].max(m2[(k + 2) % 16]));
    let m8: [u8; 16] = std::array::from_fn(|k| m4[k].max(m4[(k + 4) % 16]));
    let mut best = u8::MAX;
    for k in 0..16 {
        best = best.min(m8[k].max(d[(k + 8) % 16]));
    }
    best
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
            let (area, cells) = CellLayout::orb_slam2(w, h, 19, 30).expect("large enough");
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
    fn score_map_equals_brute_force_scores() {
        let mut map = Vec::new();
        let mut n_corners = 0;
        for seed in 0..3 {
            let img = random_image(61, 47, 10 + seed);
            let r = Rect {
                x0: 3,
                y0: 4,
                x1: 58,
                y1: 44,
            };
            score_map(&img, r, &mut map);
            for y in 0..47 {
                for x in 0..61 {
                    let inside = x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1;
                    let want = if inside {
                        ref_score(&img, x, y).max(0)
                    } else {
                        0
                    };
                    assert_eq!(map[y * 61 + x] as i32, want, "seed {seed} ({x}, {y})");
                    n_corners += (want >= 7) as usize;
                }
            }
        }
        assert!(n_corners > 300, "test images too flat: {n_corners} corners");
    }

    #[test]
    fn portable_and_dispatched_scores_agree() {
        // Row lengths below, at and above the chunk size, so the padded and the overlapping
        // last chunk both run.
        let img = random_image(140, 30, 21);
        for (x0, x1) in [(3, 137), (3, 20), (10, 42), (5, 70)] {
            for y in 3..27 {
                let (centre, ring) = ring_slices(&img, y, x0, x1);
                let mut a = vec![0u8; x1 - x0];
                let mut b = vec![0u8; x1 - x0];
                score_slices(centre, &ring, &mut a);
                score_slices_dispatch(centre, &ring, &mut b);
                assert_eq!(a, b, "row {y} [{x0}, {x1})");
                for (i, &s) in a.iter().enumerate() {
                    assert_eq!(s as i32, ref_score(&img, x0 + i, y).max(0));
                }
            }
        }
    }

    #[test]
    fn portable_and_dispatched_suppression_agree() {
        let map = random_image(100, 12, 22).data;
        for n in [1usize, 31, 32, 33, 98] {
            for t in [1u8, 60, 120] {
                let row = |y: usize| &map[y * 100..y * 100 + n + 2];
                let mut a = vec![0u8; n];
                let mut b = vec![0u8; n];
                local_max_flags_impl(row(0), row(1), row(2), t, &mut a);
                local_max_flags(row(0), row(1), row(2), t, &mut b);
                assert_eq!(a, b, "n {n} t {t}");
                for (i, &f) in a.iter().enumerate() {
                    let s = row(1)[i + 1];
                    let above = (0..3).all(|k| {
                        row(0)[i + k] < s && row(2)[i + k] < s && (k == 1 || row(1)[i + k] < s)
                    });
                    assert_eq!(f == 1, s >= t && above, "n {n} t {t} i {i}");
                }
            }
        }
    }

    #[test]
    fn arc_score_sees_runs_across_the_wrap() {
        // 9 contiguous pixels through the wrap (11..15, 0..3) at 50, one of them at 30.
        let mut d = [0u8; 16];
        for k in (11..16).chain(0..4) {
            d[k] = 50;
        }
        d[2] = 30;
        assert_eq!(best_arc_min(&d), 30);
        // A tenth pixel (10) lets an arc avoid pixel 3 but not pixel 2.
        d[10] = 40;
        d[3] = 20;
        assert_eq!(best_arc_min(&d), 30);
        // 8 contiguous pixels are not enough.
        let mut e = [0u8; 16];
        e[4..12].fill(90);
        assert_eq!(best_arc_min(&e), 0);
        assert_eq!(best_arc_min(&[255; 16]), 255);
        // The dark side mirrors the bright one.
        assert_eq!(255 - best_arc_max(&d.map(|v| 255 - v)), 30);
        assert_eq!(best_arc_max(&e.map(|v| 255 - v)), 255);
    }
}
