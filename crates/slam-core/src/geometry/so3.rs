//! SO(3): the hat operator and the exponential / logarithm maps between axis-angle vectors and
//! unit quaternions, accurate down to zero angle (Taylor expansions near the identity).

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

/// Below this rotation angle (radians) the maps switch to their Taylor expansions.
const SMALL_ANGLE: f64 = 1e-4;

/// The skew-symmetric ("hat") matrix of `v`: `skew(v) * w == v.cross(w)`.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Exponential map of so(3): the rotation by angle `|w|` about axis `w / |w|`.
/// Exact to machine precision at every angle, including `w == 0`.
pub fn exp_so3(w: &Vector3<f64>) -> UnitQuaternion<f64> {
    let theta2 = w.norm_squared();
    let theta = theta2.sqrt();
    // q = (cos(theta/2), sin(theta/2)/theta * w)
    let (real, k) = if theta < SMALL_ANGLE {
        (
            1.0 - theta2 / 8.0 + theta2 * theta2 / 384.0,
            0.5 - theta2 / 48.0 + theta2 * theta2 / 3840.0,
        )
    } else {
        let half = 0.5 * theta;
        (half.cos(), half.sin() / theta)
    };
    UnitQuaternion::new_normalize(Quaternion::new(real, k * w.x, k * w.y, k * w.z))
}

/// Logarithm map of SO(3): the axis-angle vector with angle in `[0, pi]` whose [`exp_so3`] is `q`.
/// At exactly `pi` either of the two equivalent axes may come back.
pub fn log_so3(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    // Use the representative with non-negative real part, so the angle is in [0, pi].
    let (w, v) = if q.w < 0.0 {
        (-q.w, -q.imag())
    } else {
        (q.w, q.imag())
    };
    let n = v.norm();
    // theta = 2 atan2(n, w); omega = theta / n * v.
    let k = if n < SMALL_ANGLE * 0.5 {
        // 2 atan(n/w) / n = 2/w (1 - n^2 / (3 w^2) + ...), w ~ 1 here.
        let r2 = (n / w) * (n / w);
        2.0 / w * (1.0 - r2 / 3.0 + r2 * r2 / 5.0)
    } else {
        2.0 * n.atan2(w) / n
    };
    v * k
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skew_is_cross_product() {
        let a = Vector3::new(0.3, -1.2, 2.0);
        let b = Vector3::new(-0.7, 0.4, 1.1);
        assert!((skew(&a) * b - a.cross(&b)).norm() < 1e-15);
        assert!((skew(&a) + skew(&a).transpose()).norm() == 0.0);
    }

    #[test]
    fn exp_matches_nalgebra_axis_angle() {
        for w in [
            Vector3::new(0.1, -0.2, 0.3),
            Vector3::new(2.0, 1.0, -0.5),
            Vector3::new(0.0, 0.0, 3.1),
        ] {
            let reference = UnitQuaternion::from_scaled_axis(w);
            assert!(exp_so3(&w).angle_to(&reference) < 1e-12);
        }
    }

    #[test]
    fn exp_log_round_trip_over_angle_range() {
        let axis = Vector3::new(0.48, -0.6, 0.64).normalize();
        for &theta in &[
            0.0,
            1e-12,
            1e-8,
            1e-5,
            9.9e-5,
            1e-4,
            1e-3,
            0.5,
            2.0,
            3.1,
            std::f64::consts::PI - 1e-6,
        ] {
            let w = axis * theta;
            let back = log_so3(&exp_so3(&w));
            assert!(
                (back - w).norm() <= 1e-12 * (1.0 + theta),
                "theta {theta}: {back:?} vs {w:?}"
            );
        }
    }

    #[test]
    fn log_of_negated_quaternion_is_the_same_rotation() {
        let q = exp_so3(&Vector3::new(0.2, 0.4, -0.1));
        let neg = UnitQuaternion::new_unchecked(-q.into_inner());
        assert!((log_so3(&q) - log_so3(&neg)).norm() < 1e-14);
    }

    #[test]
    fn small_angle_exp_is_first_order_accurate() {
        // exp(w) p = p + w x p + O(|w|^2): the derivative the optimizers rely on.
        let p = Vector3::new(1.0, 2.0, 3.0);
        let w = Vector3::new(1e-7, -2e-7, 3e-7);
        let moved = exp_so3(&w) * p;
        assert!((moved - p - w.cross(&p)).norm() < 1e-12);
    }
}
