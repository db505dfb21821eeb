//! SE(3): exponential and logarithm maps with the `[omega; upsilon]` ordering, and the derivative
//! of a transformed point under a left perturbation (the building block of every pose Jacobian).

use nalgebra::{Isometry3, Matrix3, Matrix3x6, Translation3, Vector3};

use super::so3::{exp_so3, log_so3, skew};
use super::Vector6;

/// Below this rotation angle (radians) the `V` matrices use their Taylor expansions.
const SMALL_ANGLE: f64 = 1e-4;

/// The left Jacobian of SO(3), `V(w) = I + (1 - cos t)/t^2 W + (t - sin t)/t^3 W^2` with
/// `W = skew(w)`, `t = |w|`: it maps `upsilon` to the translation of `exp_se3([w; upsilon])`.
fn so3_left_jacobian(w: &Vector3<f64>) -> Matrix3<f64> {
    let t2 = w.norm_squared();
    let (a, b) = if t2.sqrt() < SMALL_ANGLE {
        (0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0)
    } else {
        let t = t2.sqrt();
        ((1.0 - t.cos()) / t2, (t - t.sin()) / (t2 * t))
    };
    let wx = skew(w);
    Matrix3::identity() + wx * a + wx * wx * b
}

/// Inverse of the SO(3) left Jacobian `V(w)`:
/// `V^-1 = I - W/2 + (1 - (t/2) cot(t/2)) / t^2 W^2`. Besides inverting [`exp_se3`]'s
/// translation, it is the derivative of `log_so3(exp(d) R)` with respect to `d` at `d = 0`
/// (and `V^-1(-w)` that of `log_so3(R exp(d))`), which pose-graph Jacobians need.
pub fn so3_left_jacobian_inverse(w: &Vector3<f64>) -> Matrix3<f64> {
    let t2 = w.norm_squared();
    let c = if t2.sqrt() < SMALL_ANGLE {
        1.0 / 12.0 + t2 / 720.0
    } else {
        let t = t2.sqrt();
        let half = 0.5 * t;
        (1.0 - half * half.cos() / half.sin()) / t2
    };
    let wx = skew(w);
    Matrix3::identity() - wx * 0.5 + wx * wx * c
}

/// Exponential map of se(3): `xi = [omega; upsilon]` to the rigid motion
/// `(exp_so3(omega), V(omega) upsilon)`. See the module-level convention in [`crate::geometry`].
pub fn exp_se3(xi: &Vector6) -> Isometry3<f64> {
    let w = xi.fixed_rows::<3>(0).into_owned();
    let v = xi.fixed_rows::<3>(3).into_owned();
    let t = so3_left_jacobian(&w) * v;
    Isometry3::from_parts(Translation3::from(t), exp_so3(&w))
}

/// Logarithm map of SE(3), the exact inverse of [`exp_se3`] (rotation angle in `[0, pi]`).
pub fn log_se3(t: &Isometry3<f64>) -> Vector6 {
    let w = log_so3(&t.rotation);
    let v = so3_left_jacobian_inverse(&w) * t.translation.vector;
    Vector6::new(w.x, w.y, w.z, v.x, v.y, v.z)
}

/// Derivative of a transformed point `p = T * p_w` with respect to a left perturbation
/// `T <- exp(xi) * T`, evaluated at `xi = 0`: `[ -skew(p) , I ]` (3x6). Chain it after a
/// residual's Jacobian with respect to the camera-frame point to get the pose Jacobian.
pub fn d_point_d_left_perturbation(p: &Vector3<f64>) -> Matrix3x6<f64> {
    let mut j = Matrix3x6::zeros();
    j.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-skew(p)));
    j.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&Matrix3::identity());
    j
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    fn xi(w: [f64; 3], v: [f64; 3]) -> Vector6 {
        Vector6::new(w[0], w[1], w[2], v[0], v[1], v[2])
    }

    #[test]
    fn exp_log_round_trip() {
        for x in [
            xi([0.0, 0.0, 0.0], [0.1, -0.2, 0.3]),
            xi([1e-9, -2e-9, 0.0], [1.0, 2.0, 3.0]),
            xi([5e-5, 0.0, 5e-5], [-1.0, 0.5, 0.2]),
            xi([0.3, -0.4, 0.5], [1.0, -2.0, 0.5]),
            xi([2.0, 1.0, -1.5], [0.0, 0.0, 4.0]),
            xi([0.0, 3.1, 0.0], [0.2, 0.2, 0.2]),
        ] {
            let back = log_se3(&exp_se3(&x));
            assert!(
                (back - x).norm() < 1e-11 * (1.0 + x.norm()),
                "{x:?} -> {back:?}"
            );
        }
    }

    #[test]
    fn log_exp_round_trip_on_poses() {
        let t = Isometry3::from_parts(
            Translation3::new(0.4, -1.0, 2.5),
            UnitQuaternion::from_euler_angles(0.3, -1.1, 2.0),
        );
        let back = exp_se3(&log_se3(&t));
        assert!((back.to_homogeneous() - t.to_homogeneous()).norm() < 1e-12);
    }

    #[test]
    fn pure_translation_and_pure_rotation() {
        let t = exp_se3(&xi([0.0, 0.0, 0.0], [1.0, 2.0, 3.0]));
        assert!((t.translation.vector - Vector3::new(1.0, 2.0, 3.0)).norm() < 1e-15);
        assert!(t.rotation.angle() < 1e-15);
        let r = exp_se3(&xi([0.0, 0.0, 0.5], [0.0, 0.0, 0.0]));
        assert!((r.rotation.angle() - 0.5).abs() < 1e-15);
        assert!(r.translation.vector.norm() < 1e-15);
    }

    #[test]
    fn v_times_v_inverse_is_identity() {
        for w in [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(3e-5, 1e-5, -2e-5),
            Vector3::new(0.7, -0.2, 1.9),
        ] {
            let e = so3_left_jacobian(&w) * so3_left_jacobian_inverse(&w) - Matrix3::identity();
            assert!(e.norm() < 1e-13, "{w:?}");
        }
    }

    #[test]
    fn left_perturbation_derivative_matches_central_differences() {
        let t = Isometry3::from_parts(
            Translation3::new(0.1, 0.2, -0.3),
            UnitQuaternion::from_euler_angles(0.2, 0.1, -0.4),
        );
        let pw = Vector3::new(0.5, -0.4, 3.0);
        let p = t * nalgebra::Point3::from(pw);
        let analytic = d_point_d_left_perturbation(&p.coords);
        let h = 1e-6;
        for k in 0..6 {
            let mut d = Vector6::zeros();
            d[k] = h;
            let plus = (exp_se3(&d) * t) * nalgebra::Point3::from(pw);
            let minus = (exp_se3(&(-d)) * t) * nalgebra::Point3::from(pw);
            let numeric = (plus - minus) / (2.0 * h);
            let err = (numeric - analytic.column(k)).norm();
            assert!(err < 1e-8, "column {k}: {err}");
        }
    }
}
