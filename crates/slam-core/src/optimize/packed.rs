//! The point elimination of bundle adjustment on padded, vector-friendly storage.
//!
//! Every 6-row quantity of the Schur complement (a column of a camera-point block `W`, of
//! `Y = W V^-1`, a row of a 6 x 6 block of the reduced camera system, a camera's right-hand side)
//! is kept as one [`Lanes`]: eight doubles, 64-byte aligned, the last two zero or unused. A pair
//! update `S_ab -= Y_a W_b^T` is then six statements `line -= (v0 s0 + v1 s1) + v2 s2` over
//! whole lanes, which the compiler turns into one vector operation per term (a 512-bit register
//! holds a line, two 256-bit or four 128-bit ones otherwise).
//!
//! Each entry is computed with the operations of nalgebra's products in the same order
//! (`(a_0 b_0 + a_1 b_1) + a_2 b_2`, no fused multiply-add) and the contributions of the points
//! reach an entry in the same order as before, so the results are the same bits.

use nalgebra::{DMatrix, Matrix3, Matrix6, Matrix6x3, Vector3};

use crate::geometry::Vector6;

/// Eight doubles aligned to a cache line: a 6-vector padded with two unused entries.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct Lanes(pub [f64; 8]);

impl Lanes {
    /// The zero vector.
    pub(crate) const ZERO: Lanes = Lanes([0.0; 8]);

    /// `self -= (v0 s0 + v1 s1) + v2 s2` entry by entry.
    #[inline(always)]
    fn sub_combination(&mut self, v: &[Lanes; 3], s: [f64; 3]) {
        for l in 0..8 {
            self.0[l] -= v[0].0[l] * s[0] + v[1].0[l] * s[1] + v[2].0[l] * s[2];
        }
    }

    /// `(v0 s0 + v1 s1) + v2 s2` entry by entry.
    #[inline(always)]
    fn combination(v: &[Lanes; 3], s: [f64; 3]) -> Lanes {
        let mut out = Lanes::ZERO;
        for l in 0..8 {
            out.0[l] = v[0].0[l] * s[0] + v[1].0[l] * s[1] + v[2].0[l] * s[2];
        }
        out
    }
}

/// A 6 x 3 matrix by columns, each padded to eight rows with zeros.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Padded6x3(pub [Lanes; 3]);

impl Padded6x3 {
    /// The zero matrix.
    pub(crate) const ZERO: Padded6x3 = Padded6x3([Lanes::ZERO; 3]);

    /// Entry `(r, k)`.
    #[inline(always)]
    pub(crate) fn at(&self, r: usize, k: usize) -> f64 {
        self.0[k].0[r]
    }

    /// Row `r`.
    #[inline(always)]
    fn row(&self, r: usize) -> [f64; 3] {
        [self.0[0].0[r], self.0[1].0[r], self.0[2].0[r]]
    }

    /// The padded copy of `m`.
    #[inline(always)]
    pub(crate) fn from_matrix(m: &Matrix6x3<f64>) -> Self {
        let mut out = Padded6x3::ZERO;
        for k in 0..3 {
            for r in 0..6 {
                out.0[k].0[r] = m[(r, k)];
            }
        }
        out
    }

    /// The unpadded matrix.
    pub(crate) fn to_matrix(self) -> Matrix6x3<f64> {
        Matrix6x3::from_fn(|r, k| self.at(r, k))
    }

    /// `self * m`, bit for bit as nalgebra computes it.
    #[inline(always)]
    pub(crate) fn mul3(&self, m: &Matrix3<f64>) -> Padded6x3 {
        let mut out = Padded6x3::ZERO;
        for k in 0..3 {
            out.0[k] = Lanes::combination(&self.0, [m[(0, k)], m[(1, k)], m[(2, k)]]);
        }
        out
    }

    /// `self^T * d`, bit for bit as nalgebra computes `self.transpose() * d`.
    #[inline(always)]
    pub(crate) fn transpose_mul(&self, d: &Vector6) -> Vector3<f64> {
        Vector3::from_fn(|k, _| {
            let col = &self.0[k].0;
            let mut s = col[0] * d[0];
            for r in 1..6 {
                s += col[r] * d[r];
            }
            s
        })
    }
}

/// The lower triangle of the reduced camera system by 6 x 6 blocks, block `(p, q)` (`q <= p`)
/// as six [`Lanes`], line `r` holding row `r` of the block, block columns one after the other. Of a diagonal block only the
/// entries on and below the diagonal are meaningful (the others collect unused values).
#[derive(Clone, Debug, Default)]
pub(crate) struct PackedBlocks {
    n: usize,
    lines: Vec<Lanes>,
}

impl PackedBlocks {
    /// Resets to the zero matrix of `n` block rows, keeping the storage.
    pub(crate) fn reset(&mut self, n: usize) {
        self.n = n;
        self.lines.clear();
        self.lines.resize(3 * n * (n + 1), Lanes::ZERO);
    }

    /// The first line of block `(p, q)`, `q <= p`. The blocks are stored by block columns
    /// (`(q, q), (q + 1, q), ...`): the pair updates of one observation run down a column.
    #[inline(always)]
    fn block_at(&self, p: usize, q: usize) -> usize {
        6 * (q * self.n - q * q.saturating_sub(1) / 2 + (p - q))
    }

    /// The six lines of block `(p, q)`, `q <= p`.
    #[inline(always)]
    fn block_mut(&mut self, p: usize, q: usize) -> &mut [Lanes; 6] {
        debug_assert!(q <= p && p < self.n);
        let at = self.block_at(p, q);
        (&mut self.lines[at..at + 6]).try_into().expect("six lines")
    }

    /// Sets diagonal block `p` to `m`.
    pub(crate) fn set_diagonal_block(&mut self, p: usize, m: &Matrix6<f64>) {
        for (r, line) in self.block_mut(p, p).iter_mut().enumerate() {
            for c in 0..6 {
                line.0[c] = m[(r, c)];
            }
        }
    }

    /// Subtracts one point's contribution `Y_a W_b^T` coupling the cameras `ia` and `ib` (and,
    /// unless it is the same observation, its transpose) from the lower triangle: the entries
    /// of [`super::local_ba`]'s dense update, each `sum_k Y_a[r, k] W_b[c, k]` in nalgebra's
    /// order.
    #[inline(always)]
    pub(crate) fn subtract_pair(
        &mut self,
        ia: usize,
        ib: usize,
        same: bool,
        y_a: &Padded6x3,
        w_b: &Padded6x3,
    ) {
        if ia < ib {
            // Block (ib, ia): row c, column r gets sum_k Y_a[r, k] W_b[c, k].
            for (c, line) in self.block_mut(ib, ia).iter_mut().enumerate() {
                line.sub_combination(&y_a.0, w_b.row(c));
            }
        } else if ia > ib || same {
            // Block (ia, ib): row r, column c gets sum_k Y_a[r, k] W_b[c, k] (of a diagonal
            // block, the entries above the diagonal are not used).
            for (r, line) in self.block_mut(ia, ib).iter_mut().enumerate() {
                line.sub_combination(&w_b.0, y_a.row(r));
            }
        } else {
            // Two observations of one point by one keyframe: the block plus its transpose.
            let blk = |r: usize, c: usize| {
                let (y, w) = (y_a.row(r), w_b.row(c));
                y[0] * w[0] + y[1] * w[1] + y[2] * w[2]
            };
            for (r, line) in self.block_mut(ia, ia).iter_mut().enumerate() {
                for c in 0..=r {
                    line.0[c] -= blk(r, c) + blk(c, r);
                }
            }
        }
    }

    /// Writes the lower triangle into the `6n x 6n` column-major `dense` (its strict upper
    /// triangle is left as it was).
    pub(crate) fn unpack_lower(&self, dense: &mut DMatrix<f64>) {
        let dim = 6 * self.n;
        assert_eq!(dense.shape(), (dim, dim));
        let data = dense.as_mut_slice();
        for p in 0..self.n {
            for q in 0..=p {
                let at = self.block_at(p, q);
                for (r, line) in self.lines[at..at + 6].iter().enumerate() {
                    let cols = if p == q { r + 1 } else { 6 };
                    for c in 0..cols {
                        data[(6 * q + c) * dim + 6 * p + r] = line.0[c];
                    }
                }
            }
        }
    }
}

/// `rhs -= Y_a g_p` on a padded camera right-hand side, `Y_a g_p` bit for bit as nalgebra's.
#[inline(always)]
pub(crate) fn sub_mul_vector(rhs: &mut Lanes, y_a: &Padded6x3, g: &Vector3<f64>) {
    rhs.sub_combination(&y_a.0, [g.x, g.y, g.z]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimize::fixed_mul::{mul, mul_transpose, transpose_mul};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random<const R: usize, const C: usize>(
        rng: &mut ChaCha8Rng,
    ) -> nalgebra::SMatrix<f64, R, C> {
        nalgebra::SMatrix::from_fn(|_, _| {
            let m: f64 = rng.random_range(-1.0..1.0);
            m * 10f64.powi(rng.random_range(-6..6))
        })
    }

    #[test]
    fn padded_products_are_nalgebra_s_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for _ in 0..1000 {
            let w: Matrix6x3<f64> = random(&mut rng);
            let m: Matrix3<f64> = random(&mut rng);
            let v: Vector3<f64> = random(&mut rng);
            let d: Vector6 = random(&mut rng);
            let pw = Padded6x3::from_matrix(&w);
            assert_eq!(pw.to_matrix(), w);
            let y = pw.mul3(&m).to_matrix();
            assert!(y
                .iter()
                .zip(mul(&w, &m).iter())
                .all(|(a, b)| a.to_bits() == b.to_bits()));
            let mut r = Lanes::ZERO;
            sub_mul_vector(&mut r, &pw, &v);
            let want = -mul(&w, &v);
            assert!((0..6).all(|i| r.0[i].to_bits() == want[i].to_bits()));
            let t = pw.transpose_mul(&d);
            let want = transpose_mul(&w, &d);
            assert!((0..3).all(|i| t[i].to_bits() == want[i].to_bits()));
        }
    }

    #[test]
    fn pair_updates_are_the_dense_updates() {
        let mut rng = ChaCha8Rng::seed_from_u64(10);
        let n = 3;
        let mut packed = PackedBlocks::default();
        packed.reset(n);
        let mut want = DMatrix::<f64>::zeros(6 * n, 6 * n);
        for i in 0..n {
            let d: Matrix6<f64> = random(&mut rng);
            packed.set_diagonal_block(i, &d);
            want.fixed_view_mut::<6, 6>(6 * i, 6 * i).copy_from(&d);
        }
        for (ia, ib, same) in [
            (0, 2, false),
            (2, 1, false),
            (1, 1, true),
            (1, 1, false),
            (0, 0, true),
        ] {
            let y: Matrix6x3<f64> = random(&mut rng);
            let w: Matrix6x3<f64> = random(&mut rng);
            packed.subtract_pair(
                ia,
                ib,
                same,
                &Padded6x3::from_matrix(&y),
                &Padded6x3::from_matrix(&w),
            );
            let blk: Matrix6<f64> = mul_transpose(&y, &w);
            for r in 0..6 {
                for c in 0..6 {
                    let (row, col, v) = if ia == ib {
                        if r < c {
                            continue;
                        }
                        (
                            6 * ia + r,
                            6 * ia + c,
                            if same {
                                blk[(r, c)]
                            } else {
                                blk[(r, c)] + blk[(c, r)]
                            },
                        )
                    } else if ia > ib {
                        (6 * ia + r, 6 * ib + c, blk[(r, c)])
                    } else {
                        (6 * ib + c, 6 * ia + r, blk[(r, c)])
                    };
                    want[(row, col)] -= v;
                }
            }
        }
        let mut got = DMatrix::<f64>::from_element(6 * n, 6 * n, f64::NAN);
        packed.unpack_lower(&mut got);
        for c in 0..6 * n {
            for r in c..6 * n {
                assert_eq!(got[(r, c)].to_bits(), want[(r, c)].to_bits(), "({r}, {c})");
            }
        }
    }
}
