//! Reprojection residuals as plain data: what was measured for one observation of a point, how
//! to evaluate the residual and its Jacobian with respect to the point in camera coordinates, and
//! the chi2 gates of their dimension.
//!
//! Every residual here is a function `r(p_c)` of the point in camera coordinates only; the
//! solvers chain `d r / d p_c` to the pose (left perturbation, see [`crate::geometry`]) and to the
//! world point themselves. That is the extension point for the paper's 4-D AVC residual
//! (Eq. 12): implement [`CameraResidual`] and wrap it in [`Measurement::Custom`]; no solver
//! changes. Residuals are stored in a fixed 4-vector whose rows past [`Measurement::dof`] are zero.

use std::sync::Arc;

use nalgebra::{Matrix3, Matrix4x3, Vector3, Vector4};

use super::camera_residual::{chi2_95, CameraResidual, ResidualBlock, MIN_DEPTH};
use super::fixed_mul::transpose_mul;
use super::virtual_camera::VirtualCameraRef;
use crate::Camera;

/// What one keypoint measured of a map point.
#[derive(Clone, Debug)]
pub enum Measurement {
    /// Monocular keypoint at undistorted pixel (u, v): a 2-D reprojection residual.
    Mono {
        /// Undistorted pixel column.
        u: f64,
        /// Undistorted pixel row.
        v: f64,
    },
    /// Stereo or RGB-D keypoint: (u, v) plus the right-image column `ur = u - bf / z`
    /// (for RGB-D the virtual right column from the measured depth; see [`Measurement::rgbd`]).
    /// A 3-D residual, as ORB-SLAM2's stereo edges.
    Stereo {
        /// Undistorted pixel column.
        u: f64,
        /// Undistorted pixel row.
        v: f64,
        /// Column in the (real or virtual) right image.
        ur: f64,
    },
    /// Any other residual of the camera-frame point (the extension point).
    Custom(Arc<dyn CameraResidual>),
    /// The paper's 4-D AVC residual: what [`Measurement::Custom`] would do with it, the same
    /// operations, called directly rather than through a trait object so that the solvers'
    /// loops inline it (AVC's residuals are evaluated millions of times a sequence).
    VirtualCamera(VirtualCameraRef),
}

impl Measurement {
    /// An RGB-D keypoint at (u, v) with measured depth `depth` (metres, > 0): a
    /// [`Measurement::Stereo`] with the virtual right column `ur = u - bf / depth`.
    pub fn rgbd(camera: &Camera, u: f64, v: f64, depth: f64) -> Self {
        Measurement::Stereo {
            u,
            v,
            ur: u - camera.bf / depth,
        }
    }

    /// Residual dimension: 2 (mono), 3 (stereo / RGB-D), or the custom residual's.
    pub fn dof(&self) -> usize {
        match self {
            Measurement::Mono { .. } => 2,
            Measurement::Stereo { .. } => 3,
            Measurement::Custom(c) => c.dof(),
            Measurement::VirtualCamera(_) => 4,
        }
    }

    /// The 95 % chi2 gate for this residual's dimension (5.991 / 7.815 / 9.488); an AVC
    /// residual's own gate (9.488 unless AVC's `gate` reading set 7.815).
    pub fn chi2_threshold(&self) -> f64 {
        match self {
            Measurement::VirtualCamera(c) => c.chi2_gate(),
            _ => chi2_95(self.dof()),
        }
    }

    /// The Huber threshold on the whitened residual norm, `sqrt(chi2_threshold())`.
    pub fn huber_delta(&self) -> f64 {
        self.chi2_threshold().sqrt()
    }

    /// Evaluates the residual and its Jacobian at the camera-frame point `p_c`; `None` when the
    /// point is not in front of the camera (`z <= MIN_DEPTH`) or the custom residual is undefined.
    #[inline]
    pub fn evaluate(&self, camera: &Camera, p_c: &Vector3<f64>) -> Option<ResidualBlock> {
        if p_c.z.is_nan() || p_c.z <= MIN_DEPTH {
            return None;
        }
        let (r, j) = match self {
            Measurement::Mono { u, v } => builtin_residual(camera, *u, *v, None, p_c),
            Measurement::Stereo { u, v, ur } => builtin_residual(camera, *u, *v, Some(*ur), p_c),
            Measurement::Custom(c) => return c.evaluate(camera, p_c),
            Measurement::VirtualCamera(c) => return c.block(camera, p_c),
        };
        Some(ResidualBlock {
            residual: Vector4::from(r),
            d_residual_d_point: Matrix4x3::from_fn(|row, c| j[row][c]),
        })
    }
}

/// The residual of a monocular (`ur` `None`) or stereo keypoint at `p_c` (in front of the
/// camera) and its Jacobian by rows, padded with zeros to four rows, as plain arrays: the values
/// of [`Measurement::evaluate`], which the linearization keeps in registers.
#[inline(always)]
fn builtin_residual(
    camera: &Camera,
    u: f64,
    v: f64,
    ur: Option<f64>,
    p_c: &Vector3<f64>,
) -> ([f64; 4], [[f64; 3]; 4]) {
    let inv_z = 1.0 / p_c.z;
    let x_z = p_c.x * inv_z;
    let y_z = p_c.y * inv_z;
    let pu = camera.fx * x_z + camera.cx;
    let pv = camera.fy * y_z + camera.cy;
    // d(u, v) / d p_c.
    let du = [camera.fx * inv_z, 0.0, -camera.fx * x_z * inv_z];
    let dv = [0.0, camera.fy * inv_z, -camera.fy * y_z * inv_z];
    let (r2, dur) = match ur {
        None => (0.0, [0.0; 3]),
        Some(ur) => (
            pu - camera.bf * inv_z - ur,
            [du[0], 0.0, du[2] + camera.bf * inv_z * inv_z],
        ),
    };
    ([pu - u, pv - v, r2, 0.0], [du, dv, dur, [0.0; 3]])
}

/// One observation reduced to what the normal equations need, in camera-point coordinates:
/// `jtj = w J^T J` and `jtr = w J^T r` (3x3 and 3-vector, `w` = information x robust weight).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointLinearization {
    /// Weighted `J^T J` with respect to the camera-frame point.
    pub jtj: Matrix3<f64>,
    /// Weighted `J^T r` with respect to the camera-frame point.
    pub jtr: Vector3<f64>,
}

/// The observation's raw chi2 at `p_c`, or `None` when the residual is undefined there.
#[inline]
pub(crate) fn observation_chi2(
    camera: &Camera,
    measurement: &Measurement,
    inv_sigma2: f64,
    p_c: &Vector3<f64>,
) -> Option<f64> {
    if p_c.z.is_nan() || p_c.z <= MIN_DEPTH {
        return None;
    }
    let r = match measurement {
        Measurement::Mono { u, v } => builtin_residual(camera, *u, *v, None, p_c).0,
        Measurement::Stereo { u, v, ur } => builtin_residual(camera, *u, *v, Some(*ur), p_c).0,
        Measurement::Custom(c) => c.residual(camera, p_c)?.into(),
        Measurement::VirtualCamera(c) => c.residual_rows(camera, p_c)?.into(),
    };
    Some(inv_sigma2 * Vector4::from(r).norm_squared())
}

/// Linearizes one observation at `p_c`; `robust_weight` maps the raw chi2 to the IRLS weight
/// (1 without a kernel).
#[inline(always)]
pub(crate) fn linearize_observation(
    camera: &Camera,
    measurement: &Measurement,
    inv_sigma2: f64,
    p_c: &Vector3<f64>,
    robust_weight: impl Fn(f64) -> f64,
) -> Option<PointLinearization> {
    if p_c.z.is_nan() || p_c.z <= MIN_DEPTH {
        return None;
    }
    // The built-in residuals without the detour through a `ResidualBlock` in memory.
    let (r, j) = match measurement {
        Measurement::Mono { u, v } => builtin_residual(camera, *u, *v, None, p_c),
        Measurement::Stereo { u, v, ur } => builtin_residual(camera, *u, *v, Some(*ur), p_c),
        Measurement::Custom(_) | Measurement::VirtualCamera(_) => {
            let block = measurement.evaluate(camera, p_c)?;
            let chi2 = inv_sigma2 * block.residual.norm_squared();
            let w = inv_sigma2 * robust_weight(chi2);
            let j = &block.d_residual_d_point;
            return Some(PointLinearization {
                jtj: transpose_mul(j, j) * w,
                jtr: transpose_mul(j, &block.residual) * w,
            });
        }
    };
    // The same operations as the custom path: nalgebra's `norm_squared` of a 4-vector is
    // `0 + ((r0^2 + r2^2) + (r1^2 + r3^2))`, and each entry of `J^T J` (symmetric: its two
    // triangles are the same products in the same order) and of `J^T r` sums its four rows in
    // order before the weight.
    let chi2 = inv_sigma2 * Vector4::from(r).norm_squared();
    let w = inv_sigma2 * robust_weight(chi2);
    let mut jtj = Matrix3::zeros();
    let mut jtr = Vector3::zeros();
    for a in 0..3 {
        for b in 0..=a {
            let mut s = j[0][a] * j[0][b];
            for row in &j[1..] {
                s += row[a] * row[b];
            }
            jtj[(a, b)] = s * w;
            jtj[(b, a)] = s * w;
        }
        let mut s = j[0][a] * r[0];
        for (row, ri) in j[1..].iter().zip(&r[1..]) {
            s += row[a] * ri;
        }
        jtr[a] = s * w;
    }
    Some(PointLinearization { jtj, jtr })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimize::camera_residual::MAX_RESIDUAL_DOF;
    use crate::optimize::numdiff::assert_jacobian;
    use nalgebra::DVector;

    #[derive(Debug)]
    struct DepthOnly;

    impl CameraResidual for DepthOnly {
        fn dof(&self) -> usize {
            1
        }
        fn evaluate(&self, _camera: &Camera, p_c: &Vector3<f64>) -> Option<ResidualBlock> {
            let mut block = ResidualBlock {
                residual: Vector4::zeros(),
                d_residual_d_point: Matrix4x3::zeros(),
            };
            block.residual[0] = p_c.z - 2.0;
            block.d_residual_d_point[(0, 2)] = 1.0;
            Some(block)
        }
    }

    fn measurements(camera: &Camera) -> Vec<Measurement> {
        vec![
            Measurement::Mono { u: 300.0, v: 200.0 },
            Measurement::Stereo {
                u: 300.0,
                v: 200.0,
                ur: 290.0,
            },
            Measurement::rgbd(camera, 310.0, 250.0, 2.2),
            Measurement::Custom(Arc::new(DepthOnly)),
        ]
    }

    #[test]
    fn jacobians_match_central_differences() {
        let camera = Camera::tum_fr3();
        for m in measurements(&camera) {
            for p in [
                Vector3::new(0.1, -0.2, 2.0),
                Vector3::new(-1.5, 0.8, 0.7),
                Vector3::new(3.0, 2.0, 9.0),
            ] {
                let block = m.evaluate(&camera, &p).unwrap();
                let f = |x: &DVector<f64>| {
                    let q = Vector3::new(x[0], x[1], x[2]);
                    DVector::from_column_slice(m.evaluate(&camera, &q).unwrap().residual.as_slice())
                };
                let analytic =
                    nalgebra::DMatrix::from_column_slice(4, 3, block.d_residual_d_point.as_slice());
                assert_jacobian(
                    &format!("{m:?} at {p:?}"),
                    f,
                    &DVector::from_column_slice(p.as_slice()),
                    &analytic,
                );
            }
        }
    }

    #[test]
    fn residual_is_zero_at_the_true_projection() {
        let camera = Camera::tum_fr3();
        let p = Vector3::new(0.4, -0.3, 2.5);
        let uv = camera.project(&p);
        let m = Measurement::rgbd(&camera, uv.x, uv.y, p.z);
        let block = m.evaluate(&camera, &p).unwrap();
        assert!(block.residual.norm() < 1e-12);
        // The virtual right column is u - bf/z: one pixel of disparity per bf / z^2 metres.
        let Measurement::Stereo { u, ur, .. } = m else {
            panic!("rgbd must build a stereo measurement")
        };
        assert!((u - ur - camera.bf / p.z).abs() < 1e-12);
    }

    #[test]
    fn unused_rows_are_zero_and_dof_matches() {
        let camera = Camera::tum_fr3();
        let p = Vector3::new(0.5, 0.5, 1.5);
        for m in measurements(&camera) {
            let block = m.evaluate(&camera, &p).unwrap();
            for row in m.dof()..MAX_RESIDUAL_DOF {
                assert_eq!(block.residual[row], 0.0, "{m:?}");
                assert!(block.d_residual_d_point.row(row).iter().all(|&x| x == 0.0));
            }
        }
    }

    #[test]
    fn points_behind_the_camera_have_no_residual() {
        let camera = Camera::tum_fr3();
        for m in measurements(&camera) {
            assert!(m.evaluate(&camera, &Vector3::new(0.1, 0.1, -1.0)).is_none());
            assert!(m.evaluate(&camera, &Vector3::new(0.1, 0.1, 0.0)).is_none());
        }
    }

    #[test]
    fn gates_follow_the_chi2_table() {
        let camera = Camera::tum_fr3();
        let gates: Vec<f64> = measurements(&camera)
            .iter()
            .map(|m| m.chi2_threshold())
            .collect();
        assert_eq!(gates, vec![5.991, 7.815, 7.815, 3.841]);
        assert_eq!(chi2_95(4), 9.488);
        assert!(
            (Measurement::Mono { u: 0.0, v: 0.0 }.huber_delta() - 5.991f64.sqrt()).abs() < 1e-15
        );
    }
}
