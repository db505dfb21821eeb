//! Rigid-body geometry: the SO(3) / SE(3) exponential and logarithm maps on nalgebra types, and
//! the one perturbation convention every optimizer in slam-core uses.
//!
//! # Conventions (the only place they are written down)
//!
//! - A pose is an [`nalgebra::Isometry3<f64>`]. `Tcw` maps world coordinates into the camera
//!   frame: `p_c = Tcw * p_w`.
//! - A tangent vector is `xi = [omega; upsilon]` ([`Vector6`]): rotation (axis-angle, radians)
//!   first, translation (metres) second, as in g2o's `SE3Quat` and ORB-SLAM2.
//! - Increments are applied by **left** multiplication: `T <- exp(xi) * T`. For a world point the
//!   camera-frame point then moves by `d p_c / d xi = [ -[p_c]_x , I ]` (see
//!   [`d_point_d_left_perturbation`]); for `Tcw` the increment is expressed in the camera frame.
//! - `exp_se3(xi) = (exp_so3(omega), V(omega) upsilon)` with the SO(3) left Jacobian `V`, so
//!   [`log_se3`] inverts [`exp_se3`] exactly (not just to first order).

mod se3;
mod so3;

pub use se3::{d_point_d_left_perturbation, exp_se3, log_se3, so3_left_jacobian_inverse};
pub use so3::{exp_so3, log_so3, skew};

/// A 6-vector of f64: an element of se(3) as `[omega; upsilon]` (rotation first).
pub type Vector6 = nalgebra::Vector6<f64>;
