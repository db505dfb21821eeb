//! Closed-form alignment of an estimated trajectory onto ground truth (Umeyama 1991; equal to
//! Horn's method without scale, as in `evaluate_ate.py`): the similarity x -> s R x + t that
//! minimises sum |gt_i - (s R est_i + t)|^2, with the reflection case handled so R is always a
//! proper rotation.

use crate::error::{Error, Result};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// What alignment to fit before measuring errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum AlignmentMode {
    /// Rotation + translation (the default of evaluate_ate.py and `evo_ape -a`).
    #[default]
    Se3,
    /// Rotation + translation + scale (`--scale`; for monocular estimates).
    Sim3,
    /// No alignment at all (`--no-align`).
    None,
}

/// A similarity transform x -> scale * R x + t mapping estimate coordinates into ground truth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Alignment {
    /// Rotation and translation.
    pub rt: Isometry3<f64>,
    /// Scale (1 unless Sim3).
    pub scale: f64,
}

impl Alignment {
    /// The identity alignment.
    pub fn identity() -> Self {
        Alignment {
            rt: Isometry3::identity(),
            scale: 1.0,
        }
    }

    /// Applies the alignment to a point.
    pub fn apply(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rt.rotation * (p * self.scale) + self.rt.translation.vector
    }
}

/// Fits the alignment mapping `est` onto `gt` (corresponding points, equal length >= 3 for
/// SE3 / Sim3). Returns the identity for [`AlignmentMode::None`].
pub fn umeyama(
    est: &[Vector3<f64>],
    gt: &[Vector3<f64>],
    mode: AlignmentMode,
) -> Result<Alignment> {
    assert_eq!(est.len(), gt.len(), "umeyama needs corresponding points");
    if mode == AlignmentMode::None {
        return Ok(Alignment::identity());
    }
    let n = est.len();
    if n < 3 {
        return Err(Error::TooFewPairs {
            pairs: n,
            needed: 3,
        });
    }
    let inv_n = 1.0 / n as f64;
    let mu_e = est.iter().sum::<Vector3<f64>>() * inv_n;
    let mu_g = gt.iter().sum::<Vector3<f64>>() * inv_n;
    let mut cov = Matrix3::zeros();
    let mut var_e = 0.0;
    for (e, g) in est.iter().zip(gt) {
        let de = e - mu_e;
        let dg = g - mu_g;
        cov += dg * de.transpose();
        var_e += de.norm_squared();
    }
    cov *= inv_n;
    var_e *= inv_n;
    // The SVD squares the covariance's entries: beyond 1e150 (positions 1e75 m from their
    // mean) they overflow and the fit is NaN (found by fuzzing `eval`). Refused, as is an SVD
    // that does not converge (bounded iterations, where `svd` loops until it does).
    let spread = cov.amax().max(var_e);
    if !(cov.iter().all(|x| x.is_finite()) && spread <= 1e150) {
        return Err(Error::Degenerate(format!(
            "positions spread over {:.1e} m: too far apart to align",
            spread.sqrt()
        )));
    }
    let svd = cov
        .try_svd(true, true, f64::EPSILON * 5.0, 10_000)
        .ok_or_else(|| Error::Degenerate("the SVD of the covariance did not converge".into()))?;
    let (u, v_t) = (svd.u.expect("u requested"), svd.v_t.expect("v_t requested"));
    let mut s = Matrix3::identity();
    if u.determinant() * v_t.determinant() < 0.0 {
        s[(2, 2)] = -1.0;
    }
    let r = u * s * v_t;
    let scale = match mode {
        AlignmentMode::Sim3 => {
            if var_e <= f64::EPSILON {
                return Err(Error::Degenerate(
                    "all estimated positions coincide; no scale can be fitted".into(),
                ));
            }
            let d = svd.singular_values;
            (d[0] * s[(0, 0)] + d[1] * s[(1, 1)] + d[2] * s[(2, 2)]) / var_e
        }
        _ => 1.0,
    };
    let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let t = mu_g - rot * (mu_e * scale);
    if !(t.iter().all(|x| x.is_finite())
        && scale.is_finite()
        && rot.coords.iter().all(|x| x.is_finite()))
    {
        return Err(Error::Degenerate(format!(
            "the fitted alignment is not finite (scale {scale}, translation {t:?})"
        )));
    }
    Ok(Alignment {
        rt: Isometry3::from_parts(Translation3::from(t), rot),
        scale,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    #[test]
    fn recovers_random_sim3_and_se3() {
        let mut seed = 7;
        for trial in 0..50 {
            let pts: Vec<Vector3<f64>> = (0..30)
                .map(|_| Vector3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)) * 3.0)
                .collect();
            let rot = UnitQuaternion::from_euler_angles(
                lcg(&mut seed) * 3.0,
                lcg(&mut seed) * 1.5,
                lcg(&mut seed) * 3.0,
            );
            let t = Vector3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)) * 10.0;
            let scale = if trial % 2 == 0 {
                1.0
            } else {
                0.2 + 3.0 * (lcg(&mut seed) + 1.0)
            };
            let gt: Vec<Vector3<f64>> = pts.iter().map(|p| rot * (p * scale) + t).collect();
            let mode = if scale == 1.0 {
                AlignmentMode::Se3
            } else {
                AlignmentMode::Sim3
            };
            let a = umeyama(&pts, &gt, mode).unwrap();
            assert!((a.scale - scale).abs() < 1e-9 * scale);
            assert!(a.rt.rotation.angle_to(&rot) < 1e-9);
            for (p, g) in pts.iter().zip(&gt) {
                assert!((a.apply(p) - g).norm() < 1e-9);
            }
        }
    }

    #[test]
    fn reflection_case_gives_proper_rotation() {
        // gt is a mirror image of est: the best proper rotation must still have det +1.
        let est: Vec<Vector3<f64>> = vec![
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(0.0, 0.0, 1.0),
            Vector3::new(1.0, 1.0, 1.0),
            Vector3::new(-1.0, 0.5, 0.2),
        ];
        let gt: Vec<Vector3<f64>> = est.iter().map(|p| Vector3::new(p.x, p.y, -p.z)).collect();
        let a = umeyama(&est, &gt, AlignmentMode::Se3).unwrap();
        let r = a.rt.rotation.to_rotation_matrix();
        assert!((r.matrix().determinant() - 1.0).abs() < 1e-9);
        // A proper rotation cannot map the set onto its mirror image exactly.
        let rss: f64 = est
            .iter()
            .zip(&gt)
            .map(|(p, g)| (a.apply(p) - g).norm_squared())
            .sum();
        assert!(rss > 1e-3);
        // And it is optimal: no small rotation perturbation lowers the residual.
        for k in 0..3 {
            for sgn in [-1.0, 1.0] {
                let mut w = Vector3::zeros();
                w[k] = sgn * 1e-3;
                let pert = UnitQuaternion::from_scaled_axis(w) * a.rt.rotation;
                let mu_e = est.iter().sum::<Vector3<f64>>() / 5.0;
                let mu_g = gt.iter().sum::<Vector3<f64>>() / 5.0;
                let t = mu_g - pert * mu_e;
                let r2: f64 = est
                    .iter()
                    .zip(&gt)
                    .map(|(p, g)| (pert * p + t - g).norm_squared())
                    .sum();
                assert!(r2 >= rss - 1e-12);
            }
        }
    }

    #[test]
    fn too_few_points() {
        let p = vec![Vector3::zeros(), Vector3::x()];
        assert!(matches!(
            umeyama(&p, &p, AlignmentMode::Se3),
            Err(Error::TooFewPairs { pairs: 2, .. })
        ));
        assert_eq!(
            umeyama(&p, &p, AlignmentMode::None).unwrap(),
            Alignment::identity()
        );
    }
}
