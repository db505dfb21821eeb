//! Test helpers of the techniques: the optimizer's seeded scene helpers and its shared
//! finite-difference Jacobian checker (one checker for every residual, AVC's included), plus the
//! Nguyen et al. axial depth-noise model.

pub(crate) use crate::optimize::numdiff::assert_jacobian;
pub(crate) use crate::optimize::test_scene::{gaussian, perturb, pose_error, rng};

/// Axial depth noise of a Kinect at depth `z` metres (Nguyen et al. 2012): standard deviation
/// `0.0012 + 0.0019 (z - 0.4)^2` metres.
pub(crate) fn sigma_z(z: f64) -> f64 {
    0.0012 + 0.0019 * (z - 0.4).powi(2)
}
