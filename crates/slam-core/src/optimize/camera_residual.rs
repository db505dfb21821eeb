//! The contract every residual the solvers evaluate fulfils: a function of the point in camera
//! coordinates with its Jacobian ([`CameraResidual`], [`ResidualBlock`]), the dimension bound,
//! the depth below which a point cannot be projected, and the chi2 gates of each dimension.

use std::fmt;

use nalgebra::{Matrix4x3, Vector3, Vector4};

use crate::Camera;

/// Largest residual dimension the solvers support (the AVC residual is 4-D).
pub const MAX_RESIDUAL_DOF: usize = 4;

/// Points with a camera-frame depth at or below this (metres) cannot be projected: their
/// observation counts as an outlier (ORB-SLAM2's `isDepthPositive` test in bundle adjustment).
pub const MIN_DEPTH: f64 = 1e-6;

/// The 95 % quantile of the chi2 distribution for 1..=4 degrees of freedom
/// (3.841, 5.991, 7.815, 9.488): ORB-SLAM2's inlier gates and squared Huber thresholds.
pub fn chi2_95(dof: usize) -> f64 {
    match dof {
        1 => 3.841,
        2 => 5.991,
        3 => 7.815,
        _ => 9.488,
    }
}

/// A residual and its Jacobian with respect to the point in camera coordinates, padded to
/// [`MAX_RESIDUAL_DOF`] rows. Rows at and past the residual's dof must be zero in both.
/// Residuals are "predicted minus measured", in pixels for the built-in measurements.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResidualBlock {
    /// The residual vector (unused rows zero).
    pub residual: Vector4<f64>,
    /// `d residual / d p_c`, 4x3 (unused rows zero).
    pub d_residual_d_point: Matrix4x3<f64>,
}

/// A user-defined residual of a point in camera coordinates, e.g. the paper's AVC residual.
///
/// The solvers weight it with the observation's scalar information `inv_sigma2` on every row
/// (a residual whose rows have different variances can whiten them itself), gate it with
/// [`chi2_95`] of its [`dof`](CameraResidual::dof) and robustify it with Huber at the square
/// root of that gate. The solvers have already checked `p_c.z > MIN_DEPTH`.
pub trait CameraResidual: Send + Sync + fmt::Debug {
    /// Residual dimension, 1..=[`MAX_RESIDUAL_DOF`].
    fn dof(&self) -> usize;
    /// The residual and `d r / d p_c` at the camera-frame point `p_c`, or `None` when the
    /// residual is undefined there (the observation then counts as an outlier). Whether it is
    /// defined must depend on `p_c` alone, not on state changed between rounds (pose-only
    /// optimization tests it once per start pose).
    fn evaluate(&self, camera: &Camera, p_c: &Vector3<f64>) -> Option<ResidualBlock>;
    /// The residual alone at `p_c` (what chi2 tests and cost evaluations need): must be the
    /// bits of [`evaluate`](CameraResidual::evaluate)'s `residual`. The default evaluates the
    /// whole block; a residual whose Jacobian costs more than its value overrides it.
    fn residual(&self, camera: &Camera, p_c: &Vector3<f64>) -> Option<Vector4<f64>> {
        self.evaluate(camera, p_c).map(|b| b.residual)
    }
}
