//! Rigid absolute orientation (Horn 1987 / Kabsch): the rotation and translation that best map
//! one 3-D point set onto another in the least-squares sense, via the SVD of the 3x3
//! cross-covariance with the reflection fix.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// `T` minimising `sum |T * from_i - to_i|^2`. `None` with fewer than 3 pairs or a degenerate
/// configuration.
pub fn absolute_orientation(from: &[Vector3<f64>], to: &[Vector3<f64>]) -> Option<Isometry3<f64>> {
    let n = from.len();
    if n < 3 || to.len() != n {
        return None;
    }
    let cf = from.iter().sum::<Vector3<f64>>() / n as f64;
    let ct = to.iter().sum::<Vector3<f64>>() / n as f64;
    let mut h = Matrix3::zeros();
    for (a, b) in from.iter().zip(to) {
        h += (b - ct) * (a - cf).transpose();
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let mut d = Matrix3::identity();
    if (u * v_t).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = u * d * v_t;
    if !r.iter().all(|x| x.is_finite()) {
        return None;
    }
    let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let t = ct - rot * cf;
    Some(Isometry3::from_parts(Translation3::from(t), rot))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    #[test]
    fn recovers_rigid_transform() {
        let t = Isometry3::from_parts(
            Translation3::new(0.5, -1.0, 2.0),
            UnitQuaternion::from_euler_angles(0.3, -0.2, 1.1),
        );
        let from = vec![
            Vector3::new(0.0, 0.0, 1.0),
            Vector3::new(1.0, 0.0, 2.0),
            Vector3::new(0.0, 1.0, 3.0),
            Vector3::new(-1.0, 0.5, 1.5),
        ];
        let to: Vec<_> = from
            .iter()
            .map(|p| t.transform_point(&Point3::from(*p)).coords)
            .collect();
        let est = absolute_orientation(&from, &to).unwrap();
        assert!((est.translation.vector - t.translation.vector).norm() < 1e-9);
        assert!(est.rotation.angle_to(&t.rotation) < 1e-9);
    }
}
