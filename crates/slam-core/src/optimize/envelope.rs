//! A symmetric positive-definite matrix stored by its envelope (profile) and its in-place
//! Cholesky factor. Pose graphs and global bundle adjustment ordered by keyframe id have narrow
//! bands plus a few long rows (loop edges), for which the envelope keeps the factor sparse
//! without a fill-reducing ordering: the factor `L` has exactly the envelope of the matrix.

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
                let mut s = self.data[ri + (j - fi)];
                for k in k0..j {
                    s -= self.data[ri + (k - fi)] * self.data[rj + (k - fj)];
                }
                let d = self.data[rj + (j - fj)];
                self.data[ri + (j - fi)] = s / d;
            }
            let mut s = self.data[ri + (i - fi)];
            for k in fi..i {
                let l = self.data[ri + (k - fi)];
                s -= l * l;
            }
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
            let row = &self.data[ri..ri + (i - fi)];
            let s: f64 = row.iter().zip(&b[fi..i]).map(|(l, x)| l * x).sum();
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimize::test_scene::{gaussian, rng};
    use nalgebra::{DMatrix, DVector};

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
