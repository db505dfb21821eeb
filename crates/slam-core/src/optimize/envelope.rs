//! A symmetric positive-definite matrix stored by its envelope (profile) and its in-place
//! Cholesky factor. The factor `L` has exactly the envelope of the matrix, so the work depends
//! on how far each row reaches back: pose graphs and global bundle adjustment number their
//! keyframes with [`super::ordering`] first, which turns a circuit into a narrow band.

use nalgebra::Matrix6;

/// Lower triangle of a symmetric matrix, row `i` stored from column `first[i]` to `i`.
#[derive(Clone, Debug)]
pub(crate) struct EnvelopeMatrix {
    first: Vec<usize>,
    start: Vec<usize>,
    data: Vec<f64>,
}

impl EnvelopeMatrix {
    /// A zero matrix whose row `i` may hold entries in columns `first[i]..=i`.
    ///
    /// # Panics
    /// When `first[i] > i` (a caller bug).
    pub(crate) fn zeros(first: Vec<usize>) -> Self {
        let mut start = Vec::with_capacity(first.len() + 1);
        let mut len = 0;
        for (i, &f) in first.iter().enumerate() {
            assert!(f <= i, "envelope row {i} starts at column {f}");
            start.push(len);
            len += i - f + 1;
        }
        start.push(len);
        EnvelopeMatrix {
            first,
            start,
            data: vec![0.0; len],
        }
    }

    /// Dimension.
    pub(crate) fn dim(&self) -> usize {
        self.first.len()
    }

    /// Stored entries (the cost of a factorisation grows with their spread per row).
    #[cfg(test)]
    pub(crate) fn stored(&self) -> usize {
        self.data.len()
    }

    fn index(&self, i: usize, j: usize) -> usize {
        debug_assert!(
            j <= i && j >= self.first[i],
            "({i}, {j}) outside the envelope"
        );
        self.start[i] + (j - self.first[i])
    }

    /// Adds `v` to entry `(i, j)`, `j <= i`, inside the envelope.
    pub(crate) fn add(&mut self, i: usize, j: usize, v: f64) {
        let k = self.index(i, j);
        self.data[k] += v;
    }

    /// Entry `(i, j)` of the lower triangle (0 outside the envelope).
    pub(crate) fn get(&self, i: usize, j: usize) -> f64 {
        let (i, j) = if j > i { (j, i) } else { (i, j) };
        if j < self.first[i] {
            0.0
        } else {
            self.data[self.index(i, j)]
        }
    }

    /// Subtracts the 6 x 6 `block` at rows `6 * bi..`, columns `6 * bj..` (`bj <= bi`; of a
    /// diagonal block only the lower triangle is stored).
    pub(crate) fn sub_block6(&mut self, bi: usize, bj: usize, block: &Matrix6<f64>) {
        debug_assert!(bj <= bi);
        for r in 0..6 {
            let row = 6 * bi + r;
            let cols = if bi == bj { r + 1 } else { 6 };
            let k = self.index(row, 6 * bj);
            for (c, x) in self.data[k..k + cols].iter_mut().enumerate() {
                *x -= block[(r, c)];
            }
        }
    }

    /// Adds the 6 x 6 diagonal block `bi` (its lower triangle) of `block`.
    pub(crate) fn add_diagonal_block6(&mut self, bi: usize, block: &Matrix6<f64>) {
        self.sub_block6(bi, bi, &(-block));
    }

    /// Replaces the matrix by its Cholesky factor `L` (`A = L L^T`); false when the matrix is
    /// not positive definite (the contents are then unusable).
    pub(crate) fn cholesky(&mut self) -> bool {
        let n = self.dim();
        for i in 0..n {
            let fi = self.first[i];
            let ri = self.start[i];
            for j in fi..i {
                let fj = self.first[j];
                let rj = self.start[j];
                let k0 = fi.max(fj);
                let (head, tail) = self.data.split_at_mut(ri);
                let row_j = &head[rj + (k0 - fj)..rj + (j - fj)];
                let row_i = &tail[k0 - fi..j - fi];
                let s = tail[j - fi] - dot(row_i, row_j);
                tail[j - fi] = s / head[rj + (j - fj)];
            }
            let row_i = &self.data[ri..ri + (i - fi)];
            let s = self.data[ri + (i - fi)] - dot(row_i, row_i);
            if !s.is_finite() || s <= 0.0 {
                return false;
            }
            self.data[ri + (i - fi)] = s.sqrt();
        }
        true
    }

    /// Solves `L L^T x = b` in place with the factor from [`EnvelopeMatrix::cholesky`].
    pub(crate) fn solve_in_place(&self, b: &mut [f64]) {
        let n = self.dim();
        for i in 0..n {
            let (fi, ri) = (self.first[i], self.start[i]);
            let s = dot(&self.data[ri..ri + (i - fi)], &b[fi..i]);
            b[i] = (b[i] - s) / self.data[ri + (i - fi)];
        }
        for i in (0..n).rev() {
            let (fi, ri) = (self.first[i], self.start[i]);
            b[i] /= self.data[ri + (i - fi)];
            let xi = b[i];
            let row = &self.data[ri..ri + (i - fi)];
            for (x, l) in b[fi..i].iter_mut().zip(row) {
                *x -= l * xi;
            }
        }
    }
}

/// Dot product of two equally long slices in four independent sums (which the compiler can keep
/// in vector registers; one running sum would serialise every addition).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    let mut acc = [0.0f64; 4];
    let (a4, a_rest) = a.split_at(a.len() - a.len() % 4);
    let (b4, b_rest) = b.split_at(a4.len());
    for (x, y) in a4.chunks_exact(4).zip(b4.chunks_exact(4)) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let mut s = (acc[0] + acc[2]) + (acc[1] + acc[3]);
    for (x, y) in a_rest.iter().zip(b_rest) {
        s += x * y;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimize::test_scene::{gaussian, rng};
    use nalgebra::{DMatrix, DVector};

    #[test]
    fn block_updates_land_in_the_lower_triangle() {
        let mut env = EnvelopeMatrix::zeros(vec![0; 12]);
        let block = Matrix6::from_fn(|r, c| (10 * r + c) as f64);
        env.add_diagonal_block6(1, &block);
        env.sub_block6(1, 0, &block);
        assert_eq!(env.get(8, 7), 21.0);
        assert_eq!(env.get(7, 8), 21.0, "symmetric read of the lower entry");
        assert_eq!(env.get(8, 1), -21.0);
        assert_eq!(env.get(1, 8), -21.0);
        assert_eq!(env.get(0, 0), 0.0);
    }

    #[test]
    fn solves_a_banded_system_with_a_long_row_like_the_dense_solver() {
        let n = 40;
        let mut r = rng(3);
        // Band of half-width 5 plus a "loop" coupling the last rows to the first ones.
        let first: Vec<usize> = (0..n)
            .map(|i: usize| if i >= n - 3 { 0 } else { i.saturating_sub(5) })
            .collect();
        let mut dense = DMatrix::<f64>::zeros(n, n);
        for i in 0..n {
            for j in first[i]..i {
                let v = 0.3 * gaussian(&mut r);
                dense[(i, j)] = v;
                dense[(j, i)] = v;
            }
        }
        for i in 0..n {
            dense[(i, i)] = 10.0 + gaussian(&mut r).abs();
        }
        let mut env = EnvelopeMatrix::zeros(first.clone());
        for i in 0..n {
            for j in first[i]..=i {
                env.add(i, j, dense[(i, j)]);
            }
        }
        assert_eq!(env.get(3, 20), dense[(20, 3)]);
        assert!(env.stored() < n * (n + 1) / 2);
        let b = DVector::from_fn(n, |_, _| gaussian(&mut r));
        let want = dense.clone().cholesky().unwrap().solve(&b);
        assert!(env.cholesky());
        let mut x: Vec<f64> = b.iter().copied().collect();
        env.solve_in_place(&mut x);
        let got = DVector::from_vec(x);
        assert!(
            (got - &want).norm() < 1e-12 * want.norm(),
            "envelope solve differs"
        );
    }

    #[test]
    fn rejects_an_indefinite_matrix() {
        let mut env = EnvelopeMatrix::zeros(vec![0, 0]);
        env.add(0, 0, 1.0);
        env.add(1, 0, 2.0);
        env.add(1, 1, 1.0);
        assert!(!env.cholesky());
    }
}
