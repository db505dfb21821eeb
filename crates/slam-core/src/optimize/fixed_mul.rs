//! Products of small fixed-size matrices written out so that the compiler inlines and unrolls
//! them. nalgebra's generic product is the same arithmetic behind a call the optimiser keeps out
//! of line; in the inner loops of bundle adjustment (one 6 x 3 by 3 x 6 product per pair of
//! observations of a point) that call costs more than the arithmetic.
//!
//! Every entry is computed with the operations of nalgebra's product in the same order
//! (`((a_i0 b_0j + a_i1 b_1j) + a_i2 b_2j) + ...`, no fused multiply-add), so the results are the
//! same bits: swapping these in for nalgebra's operator leaves every trajectory unchanged.

use nalgebra::{Matrix3, Matrix3x6, Matrix6, SMatrix, Vector3};

/// `a * b`, bit for bit as nalgebra computes it.
#[inline(always)]
pub(crate) fn mul<const R: usize, const K: usize, const C: usize>(
    a: &SMatrix<f64, R, K>,
    b: &SMatrix<f64, K, C>,
) -> SMatrix<f64, R, C> {
    let mut out = SMatrix::<f64, R, C>::zeros();
    for j in 0..C {
        for i in 0..R {
            out[(i, j)] = dot_row_col(a, i, b, j);
        }
    }
    out
}

/// `a * b^T`, bit for bit as nalgebra computes `a * b.transpose()`.
#[inline(always)]
pub(crate) fn mul_transpose<const R: usize, const K: usize, const C: usize>(
    a: &SMatrix<f64, R, K>,
    b: &SMatrix<f64, C, K>,
) -> SMatrix<f64, R, C> {
    let mut out = SMatrix::<f64, R, C>::zeros();
    for j in 0..C {
        for i in 0..R {
            let mut s = a[(i, 0)] * b[(j, 0)];
            for k in 1..K {
                s += a[(i, k)] * b[(j, k)];
            }
            out[(i, j)] = s;
        }
    }
    out
}

/// `a^T * b`, bit for bit as nalgebra computes `a.transpose() * b`.
#[inline(always)]
pub(crate) fn transpose_mul<const K: usize, const R: usize, const C: usize>(
    a: &SMatrix<f64, K, R>,
    b: &SMatrix<f64, K, C>,
) -> SMatrix<f64, R, C> {
    let mut out = SMatrix::<f64, R, C>::zeros();
    for j in 0..C {
        for i in 0..R {
            let mut s = a[(0, i)] * b[(0, j)];
            for k in 1..K {
                s += a[(k, i)] * b[(k, j)];
            }
            out[(i, j)] = s;
        }
    }
    out
}

/// `A^T b` for the Jacobian `A = [-[p]x | I]` of the camera-frame point `p` by a left pose
/// perturbation ([`crate::geometry::d_point_d_left_perturbation`]): nalgebra's
/// `A.transpose() * b` without the products with `A`'s structural zeros and ones. The values
/// are those of the full product (adding a zero or multiplying by one is exact) up to the sign
/// of a result that is exactly zero.
#[inline(always)]
pub(crate) fn left_jacobian_transpose_mul<const C: usize>(
    p: &Vector3<f64>,
    b: &SMatrix<f64, 3, C>,
) -> SMatrix<f64, 6, C> {
    let s = skew_entries(p);
    let mut out = SMatrix::<f64, 6, C>::zeros();
    for j in 0..C {
        // Rows 0-2: column i of -[p]x has its zero on the diagonal, row k = i.
        out[(0, j)] = s[1][0] * b[(1, j)] + s[2][0] * b[(2, j)];
        out[(1, j)] = s[0][1] * b[(0, j)] + s[2][1] * b[(2, j)];
        out[(2, j)] = s[0][2] * b[(0, j)] + s[1][2] * b[(1, j)];
        // Rows 3-5: the identity.
        out[(3, j)] = b[(0, j)];
        out[(4, j)] = b[(1, j)];
        out[(5, j)] = b[(2, j)];
    }
    out
}

/// `m A` for the left-perturbation Jacobian `A = [-[p]x | I]` of the point `p`: nalgebra's
/// `m * A` without the products with structural zeros and ones (same values up to the sign of
/// an exact zero).
#[inline(always)]
pub(crate) fn mul_left_jacobian(m: &Matrix3<f64>, p: &Vector3<f64>) -> Matrix3x6<f64> {
    let s = skew_entries(p);
    let mut out = Matrix3x6::zeros();
    for i in 0..3 {
        out[(i, 0)] = m[(i, 1)] * s[1][0] + m[(i, 2)] * s[2][0];
        out[(i, 1)] = m[(i, 0)] * s[0][1] + m[(i, 2)] * s[2][1];
        out[(i, 2)] = m[(i, 0)] * s[0][2] + m[(i, 1)] * s[1][2];
        out[(i, 3)] = m[(i, 0)];
        out[(i, 4)] = m[(i, 1)];
        out[(i, 5)] = m[(i, 2)];
    }
    out
}

/// `u += A^T m A` on and below the diagonal only, for the left-perturbation Jacobian
/// `A = [-[p]x | I]` of the point `p`: each entry as `u + left_jacobian_transpose_mul(p,
/// &mul_left_jacobian(m, p))` computes it; the strict upper triangle of `u` is left as it was
/// (for a matrix of which only the lower triangle is read).
#[inline(always)]
pub(crate) fn add_left_jacobian_quadratic_lower(
    u: &mut Matrix6<f64>,
    m: &Matrix3<f64>,
    p: &Vector3<f64>,
) {
    let mm = mul_left_jacobian(m, p);
    let s = skew_entries(p);
    for c in 0..6 {
        let col = [
            s[1][0] * mm[(1, c)] + s[2][0] * mm[(2, c)],
            s[0][1] * mm[(0, c)] + s[2][1] * mm[(2, c)],
            s[0][2] * mm[(0, c)] + s[1][2] * mm[(1, c)],
            mm[(0, c)],
            mm[(1, c)],
            mm[(2, c)],
        ];
        for r in c..6 {
            u[(r, c)] += col[r];
        }
    }
}

/// `v += a^T b` on and below the diagonal only, each entry as `v + transpose_mul(a, b)`
/// computes it; the strict upper triangle of `v` is left as it was.
#[inline(always)]
pub(crate) fn add_transpose_mul_lower(v: &mut Matrix3<f64>, a: &Matrix3<f64>, b: &Matrix3<f64>) {
    for c in 0..3 {
        for r in c..3 {
            let mut s = a[(0, r)] * b[(0, c)];
            for k in 1..3 {
                s += a[(k, r)] * b[(k, c)];
            }
            v[(r, c)] += s;
        }
    }
}

/// The entries `[row][column]` of `-[p]x` as [`crate::geometry::d_point_d_left_perturbation`]
/// computes them (negation is exact); the diagonal is zero and not read.
#[inline(always)]
fn skew_entries(p: &Vector3<f64>) -> [[f64; 3]; 3] {
    [[0.0, p.z, -p.y], [-p.z, 0.0, p.x], [p.y, -p.x, 0.0]]
}

/// Row `i` of `a` times column `j` of `b`, accumulated from the first term on.
#[inline(always)]
fn dot_row_col<const R: usize, const K: usize, const C: usize>(
    a: &SMatrix<f64, R, K>,
    i: usize,
    b: &SMatrix<f64, K, C>,
    j: usize,
) -> f64 {
    let mut s = a[(i, 0)] * b[(0, j)];
    for k in 1..K {
        s += a[(i, k)] * b[(k, j)];
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::d_point_d_left_perturbation;
    use nalgebra::{Matrix4x3, Matrix6x3, Vector4, Vector6};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Entries over many magnitudes and both signs, with exact zeros, negative zeros and ones
    /// (as in the structured Jacobians), so rounding and signed zeros are exercised.
    fn random<const R: usize, const C: usize>(rng: &mut ChaCha8Rng) -> SMatrix<f64, R, C> {
        SMatrix::from_fn(|_, _| match rng.random_range(0..10) {
            0 => 0.0,
            1 => -0.0,
            2 => 1.0,
            _ => {
                let m: f64 = rng.random_range(-1.0..1.0);
                m * 10f64.powi(rng.random_range(-8..8))
            }
        })
    }

    fn same_bits<const R: usize, const C: usize>(
        a: &SMatrix<f64, R, C>,
        b: &SMatrix<f64, R, C>,
    ) -> bool {
        a.iter()
            .zip(b.iter())
            .all(|(x, y)| x.to_bits() == y.to_bits())
    }

    #[test]
    fn products_are_nalgebra_s_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..2000 {
            let a6x3: Matrix6x3<f64> = random(&mut rng);
            let b6x3: Matrix6x3<f64> = random(&mut rng);
            let m3: Matrix3<f64> = random(&mut rng);
            let n3: Matrix3<f64> = random(&mut rng);
            let a3x6: Matrix3x6<f64> = random(&mut rng);
            let j4x3: Matrix4x3<f64> = random(&mut rng);
            let r4: Vector4<f64> = random(&mut rng);
            let v3: Vector3<f64> = random(&mut rng);
            let v6: Vector6<f64> = random(&mut rng);
            let y: Matrix6<f64> = mul_transpose(&a6x3, &b6x3);
            assert!(same_bits(&y, &(a6x3 * b6x3.transpose())));
            assert!(same_bits(&mul(&a6x3, &m3), &(a6x3 * m3)));
            assert!(same_bits(&mul(&m3, &n3), &(m3 * n3)));
            assert!(same_bits(&mul(&a6x3, &v3), &(a6x3 * v3)));
            assert!(same_bits(&mul(&m3, &a3x6), &(m3 * a3x6)));
            assert!(same_bits(
                &mul(&a3x6.transpose(), &a3x6),
                &(a3x6.transpose() * a3x6)
            ));
            assert!(same_bits(&transpose_mul(&m3, &n3), &(m3.transpose() * n3)));
            assert!(same_bits(&transpose_mul(&m3, &v3), &(m3.transpose() * v3)));
            assert!(same_bits(
                &transpose_mul(&j4x3, &j4x3),
                &(j4x3.transpose() * j4x3)
            ));
            assert!(same_bits(
                &transpose_mul(&j4x3, &r4),
                &(j4x3.transpose() * r4)
            ));
            assert!(same_bits(
                &transpose_mul(&a6x3, &v6),
                &(a6x3.transpose() * v6)
            ));
        }
    }

    #[test]
    fn structured_products_equal_the_full_products() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        for _ in 0..2000 {
            let p: Vector3<f64> = random(&mut rng);
            let a = d_point_d_left_perturbation(&p);
            let m: Matrix3<f64> = random(&mut rng);
            let v: Vector3<f64> = random(&mut rng);
            // `==` on f64: equal values, a zero of either sign equal to the other.
            assert_eq!(mul_left_jacobian(&m, &p), m * a);
            assert_eq!(left_jacobian_transpose_mul(&p, &m), a.transpose() * m);
            assert_eq!(left_jacobian_transpose_mul(&p, &v), a.transpose() * v);
            let ma = m * a;
            assert_eq!(left_jacobian_transpose_mul(&p, &ma), a.transpose() * ma);
            // The lower-triangle accumulations: the same bits as the full update there.
            let mut u: Matrix6<f64> = random(&mut rng);
            let mut want = u + left_jacobian_transpose_mul(&p, &mul_left_jacobian(&m, &p));
            let before = u;
            add_left_jacobian_quadratic_lower(&mut u, &m, &p);
            for c in 0..6 {
                for r in 0..6 {
                    if r < c {
                        want[(r, c)] = before[(r, c)];
                    }
                }
            }
            assert!(same_bits(&u, &want));
            let (mut v, a3, b3): (Matrix3<f64>, Matrix3<f64>, Matrix3<f64>) =
                (random(&mut rng), random(&mut rng), random(&mut rng));
            let mut want = v + transpose_mul(&a3, &b3);
            let before = v;
            add_transpose_mul_lower(&mut v, &a3, &b3);
            for (r, c) in [(0, 1), (0, 2), (1, 2)] {
                want[(r, c)] = before[(r, c)];
            }
            assert!(same_bits(&v, &want));
            // Away from exact zeros, the same bits.
            let dense: Matrix3<f64> = Matrix3::from_fn(|_, _| rng.random_range(0.5..2.0));
            let full = a.transpose() * (dense * a);
            let structured = left_jacobian_transpose_mul(&p, &mul_left_jacobian(&dense, &p));
            if structured.iter().all(|x| *x != 0.0) {
                assert!(same_bits(&structured, &full));
            }
        }
    }
}
