//! Cholesky factorisation and solves of dense symmetric positive-definite matrices written out,
//! with exactly the floating-point operations of nalgebra's `Cholesky::new`, `solve` and
//! `inverse` per entry and in the same order, so the results are the same bits (no fused
//! multiply-add, nothing reassociated).
//!
//! nalgebra factorises column by column (`L[i, j] = (A[i, j] - sum_k L[j, k] L[i, k]) / L[j, j]`,
//! the terms subtracted one by one in increasing `k`) through strided `axpy` calls on matrix
//! views. Here each entry is computed with the same subtractions in the same order, but a
//! chunk of a column is kept in registers over all `k`, which the compiler vectorises; the
//! generic views cost several times the arithmetic in the reduced camera system of bundle
//! adjustment and in the 3 x 3 point blocks.

use nalgebra::Matrix3;

/// Rows of a column updated together in [`cholesky_in_place`] (kept in registers over `k`).
const CHUNK: usize = 8;

/// Columns factored together in [`cholesky_in_place`] (a `CHUNK x GROUP` tile in registers).
const GROUP: usize = 8;

/// nalgebra's pivot test: a zero pivot fails, and so does one without a real square root
/// (negative or NaN).
#[inline(always)]
fn positive_pivot(diag: f64) -> bool {
    diag > 0.0
}

/// Replaces the lower triangle of the `n x n` column-major matrix `a` (`a[j * n + i]` is entry
/// `(i, j)`; the strict upper triangle is neither read nor written) by its Cholesky factor `L`,
/// bit for bit as nalgebra's `Cholesky::new` computes it. False when nalgebra would fail (a
/// pivot that is not positive, or NaN); the contents are then unusable.
///
/// # Panics
/// When `a.len() != n * n` (a caller bug).
pub(crate) fn cholesky_in_place(a: &mut [f64], n: usize) -> bool {
    assert_eq!(a.len(), n * n, "cholesky_in_place: not an n x n matrix");
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the function only enables AVX-512 code generation for safe code; the CPU
        // supports AVX-512F, checked on the line above.
        return unsafe { cholesky_in_place_avx512(a, n) };
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: as above, for AVX2.
        return unsafe { cholesky_in_place_avx2(a, n) };
    }
    cholesky_in_place_impl(a, n)
}

/// [`cholesky_in_place`] built for AVX-512 (a chunk of a column in one register). Call only on
/// a CPU with AVX-512F.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn cholesky_in_place_avx512(a: &mut [f64], n: usize) -> bool {
    cholesky_in_place_impl(a, n)
}

/// [`cholesky_in_place`] built for AVX2. Call only on a CPU with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn cholesky_in_place_avx2(a: &mut [f64], n: usize) -> bool {
    cholesky_in_place_impl(a, n)
}

/// The body of [`cholesky_in_place`] (IEEE arithmetic without fused multiply-add on every
/// build: the same bits).
///
/// Columns are factored in groups of [`GROUP`]. The rows below a group's diagonal block first
/// take the terms of all finished columns in one pass that keeps a `CHUNK x GROUP` tile in
/// registers, so each finished column is read once per group rather than once per column; the
/// group's own columns are then finished one by one. Every entry still subtracts its terms one
/// by one in increasing `k`, as nalgebra does: the order, and so the bits, are unchanged.
#[inline(always)]
fn cholesky_in_place_impl(a: &mut [f64], n: usize) -> bool {
    let mut j0 = 0;
    while j0 < n {
        let width = GROUP.min(n - j0);
        let below = j0 + width;
        // Rows `below..tiled` of the group's columns hold the terms k < j0 after this pass.
        let mut tiled = below;
        if width == GROUP && j0 > 0 {
            let (done, rest) = a.split_at_mut(j0 * n);
            while tiled + CHUNK <= n {
                let i0 = tiled;
                let mut acc = [[0.0f64; CHUNK]; GROUP];
                for (c, acc_c) in acc.iter_mut().enumerate() {
                    acc_c.copy_from_slice(&rest[c * n + i0..c * n + i0 + CHUNK]);
                }
                for k in 0..j0 {
                    let col_k = &done[k * n..k * n + n];
                    let f: &[f64; GROUP] = col_k[j0..j0 + GROUP].try_into().expect("group");
                    let x: &[f64; CHUNK] = col_k[i0..i0 + CHUNK].try_into().expect("chunk");
                    for c in 0..GROUP {
                        for l in 0..CHUNK {
                            acc[c][l] -= f[c] * x[l];
                        }
                    }
                }
                for (c, acc_c) in acc.iter().enumerate() {
                    rest[c * n + i0..c * n + i0 + CHUNK].copy_from_slice(acc_c);
                }
                tiled += CHUNK;
            }
        }
        for j in j0..below {
            let (done, rest) = a.split_at_mut(j * n);
            let col_j = &mut rest[..n];
            // Entries (i, j) minus sum_k L[j, k] L[i, k], k ascending: nalgebra's
            // `col_j.axpy(-L[j, k], col_k, 1)`, i.e. `(-L[j, k]) L[i, k] + a`, equals
            // `a - L[j, k] L[i, k]` exactly (negation is exact and addition commutes). Rows
            // `below..tiled` already hold the terms k < j0.
            subtract_in_chunks(col_j, done, n, j, below..tiled, j0);
            let i0 = subtract_in_chunks(col_j, done, n, j, tiled..n, 0);
            for i in (j..below).chain(i0..n) {
                let mut acc = col_j[i];
                for k in 0..j {
                    let col_k = &done[k * n..k * n + n];
                    acc -= col_k[j] * col_k[i];
                }
                col_j[i] = acc;
            }
            let diag = col_j[j];
            if !positive_pivot(diag) {
                return false;
            }
            let denom = diag.sqrt();
            col_j[j] = denom;
            for x in &mut col_j[j + 1..] {
                *x /= denom;
            }
        }
        j0 = below;
    }
    true
}

/// Subtracts `L[j, k] L[i, k]` for `k` in `k_from..j`, one term at a time in increasing `k`,
/// from the entries of column `col_j` in the whole chunks of `rows` (a chunk kept in registers
/// over all `k`); returns where the whole chunks end (the rest of `rows` is left untouched).
#[inline(always)]
fn subtract_in_chunks(
    col_j: &mut [f64],
    done: &[f64],
    n: usize,
    j: usize,
    rows: std::ops::Range<usize>,
    k_from: usize,
) -> usize {
    let mut i0 = rows.start;
    while i0 + CHUNK <= rows.end {
        let mut acc: [f64; CHUNK] = col_j[i0..i0 + CHUNK].try_into().expect("chunk");
        for k in k_from..j {
            let col_k = &done[k * n..k * n + n];
            let f = col_k[j];
            let x: &[f64; CHUNK] = col_k[i0..i0 + CHUNK].try_into().expect("chunk");
            for l in 0..CHUNK {
                acc[l] -= f * x[l];
            }
        }
        col_j[i0..i0 + CHUNK].copy_from_slice(&acc);
        i0 += CHUNK;
    }
    i0
}

/// Solves `L L^T x = b` in place with the factor of [`cholesky_in_place`], bit for bit as
/// nalgebra's `Cholesky::solve_mut` (forward substitution by columns, then the transposed
/// system by nalgebra's eight-way unrolled dot products).
///
/// # Panics
/// When the sizes disagree (a caller bug).
pub(crate) fn cholesky_solve_in_place(l: &[f64], n: usize, b: &mut [f64]) {
    assert_eq!(
        l.len(),
        n * n,
        "cholesky_solve_in_place: not an n x n factor"
    );
    assert_eq!(
        b.len(),
        n,
        "cholesky_solve_in_place: right-hand side of the wrong size"
    );
    for i in 0..n {
        let col = &l[i * n..i * n + n];
        let coeff = b[i] / col[i];
        b[i] = coeff;
        // nalgebra's `axpy(-coeff, L[i + 1.., i], 1)`: `(-coeff) L + b`, i.e. `b - coeff L`.
        for (x, li) in b[i + 1..].iter_mut().zip(&col[i + 1..]) {
            *x -= coeff * li;
        }
    }
    for i in (0..n).rev() {
        let col = &l[i * n..i * n + n];
        let dot = nalgebra_dot(&col[i + 1..], &b[i + 1..]);
        b[i] = (b[i] - dot) / col[i];
    }
}

/// The dot product of two equally long slices as nalgebra's `dot` accumulates it for a
/// dynamically sized vector: eight partial sums over whole chunks of eight, combined as
/// `((((0 + (s0 + s4)) + (s1 + s5)) + (s2 + s6)) + (s3 + s7))`, then the remaining products one
/// by one.
#[inline(always)]
fn nalgebra_dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let mut acc = [0.0f64; 8];
    let whole = a.len() - a.len() % 8;
    for (x, y) in a[..whole].chunks_exact(8).zip(b[..whole].chunks_exact(8)) {
        for l in 0..8 {
            acc[l] += x[l] * y[l];
        }
    }
    let mut res = 0.0;
    res += acc[0] + acc[4];
    res += acc[1] + acc[5];
    res += acc[2] + acc[6];
    res += acc[3] + acc[7];
    for (x, y) in a[whole..].iter().zip(&b[whole..]) {
        res += x * y;
    }
    res
}

/// `m^-1` through its Cholesky factor, bit for bit as nalgebra's
/// `m.cholesky().map(|c| c.inverse())` (only the lower triangle of `m` is read); `None` when
/// nalgebra's factorisation fails.
#[inline(always)]
pub(crate) fn cholesky_inverse3(m: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    // The factor, column by column.
    let mut l = [[0.0f64; 3]; 3]; // l[column][row]
    for j in 0..3 {
        for (i, x) in l[j].iter_mut().enumerate().skip(j) {
            *x = m[(i, j)];
        }
        let (done, rest) = l.split_at_mut(j);
        for col_k in done.iter() {
            let f = col_k[j];
            for (x, lk) in rest[0][j..].iter_mut().zip(&col_k[j..]) {
                *x -= f * lk;
            }
        }
        let diag = l[j][j];
        if !positive_pivot(diag) {
            return None;
        }
        let denom = diag.sqrt();
        l[j][j] = denom;
        for x in &mut l[j][j + 1..] {
            *x /= denom;
        }
    }
    // nalgebra's `inverse`: `solve_mut` on the identity, column by column.
    let mut out = Matrix3::identity();
    for c in 0..3 {
        let mut b = [out[(0, c)], out[(1, c)], out[(2, c)]];
        for i in 0..3 {
            let coeff = b[i] / l[i][i];
            b[i] = coeff;
            for k in i + 1..3 {
                b[k] -= coeff * l[i][k];
            }
        }
        for i in (0..3).rev() {
            // nalgebra's dynamic-length dot of fewer than eight entries: `0 + ...` term by term.
            let mut dot = 0.0;
            for k in i + 1..3 {
                dot += l[i][k] * b[k];
            }
            b[i] = (b[i] - dot) / l[i][i];
        }
        for (r, x) in b.into_iter().enumerate() {
            out[(r, c)] = x;
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimize::test_scene::{gaussian, rng};
    use nalgebra::{DMatrix, DVector};

    fn same_bits(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
    }

    /// A random SPD matrix `B B^T + eps I` with entries over several magnitudes.
    fn spd(n: usize, seed: u64) -> DMatrix<f64> {
        let mut r = rng(seed);
        let b = DMatrix::from_fn(n, n, |_, _| {
            gaussian(&mut r) * 10f64.powi((seed % 5) as i32 - 2)
        });
        let mut a = &b * b.transpose();
        for i in 0..n {
            a[(i, i)] += 1e-3 * (1 + seed % 3) as f64;
        }
        a
    }

    #[test]
    fn dense_factor_and_solve_are_nalgebra_s_bit_for_bit() {
        for (seed, n) in [
            (1, 1),
            (2, 2),
            (3, 7),
            (4, 8),
            (5, 9),
            (6, 17),
            (7, 54),
            (8, 114),
            (9, 120),
            (10, 203),
            (11, 330),
        ] {
            let a = spd(n, seed);
            let mut r = rng(100 + seed);
            let rhs = DVector::from_fn(n, |_, _| gaussian(&mut r));
            let chol = a.clone().cholesky().expect("SPD");
            let want_x = chol.solve(&rhs);
            let want_l = chol.unpack_dirty();
            // Garbage in the strict upper triangle must not matter.
            let mut got = a.clone();
            for j in 0..n {
                for i in 0..j {
                    got[(i, j)] = f64::NAN;
                }
            }
            assert!(cholesky_in_place(got.as_mut_slice(), n));
            for j in 0..n {
                for i in j..n {
                    assert_eq!(got[(i, j)].to_bits(), want_l[(i, j)].to_bits(), "n {n}");
                }
            }
            let mut x: Vec<f64> = rhs.iter().copied().collect();
            cholesky_solve_in_place(got.as_slice(), n, &mut x);
            assert!(same_bits(&x, want_x.as_slice()), "solve n {n}");
        }
    }

    #[test]
    fn failures_match_nalgebra_s() {
        for a in [
            DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]),
            DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, 1.0]),
            DMatrix::from_row_slice(2, 2, &[f64::NAN, 0.0, 0.0, 1.0]),
            DMatrix::from_row_slice(2, 2, &[-1.0, 0.0, 0.0, 1.0]),
        ] {
            let mut got = a.clone();
            assert_eq!(
                cholesky_in_place(got.as_mut_slice(), 2),
                a.cholesky().is_some()
            );
        }
    }

    #[test]
    fn inverse3_is_nalgebra_s_bit_for_bit() {
        for seed in 0..500 {
            let a = spd(3, seed);
            let m = Matrix3::from_fn(|i, j| a[(i, j)]);
            let want = m.cholesky().map(|c| c.inverse());
            let got = cholesky_inverse3(&m);
            match (want, got) {
                (Some(w), Some(g)) => assert!(same_bits(w.as_slice(), g.as_slice()), "{m}"),
                (w, g) => assert_eq!(w.is_some(), g.is_some()),
            }
        }
        let indefinite = Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert!(cholesky_inverse3(&indefinite).is_none());
        assert!(indefinite.cholesky().is_none());
    }
}
