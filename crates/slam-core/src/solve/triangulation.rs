//! Linear (DLT) triangulation of one point from two views, as ORB-SLAM2's
//! LocalMapping::CreateNewMapPoints does it: the null vector of the 4x4 system.

use nalgebra::{Isometry3, Matrix3x4, Matrix4, RowVector4, Vector3};

/// Triangulates the world point seen at normalised image coordinates `xn1` in camera 1 and `xn2`
/// in camera 2 (poses world -> camera). `None` when the solution is at infinity.
pub fn triangulate_linear(
    xn1: &Vector3<f64>,
    xn2: &Vector3<f64>,
    tcw1: &Isometry3<f64>,
    tcw2: &Isometry3<f64>,
) -> Option<Vector3<f64>> {
    let p1: Matrix3x4<f64> = tcw1.to_homogeneous().fixed_view::<3, 4>(0, 0).into_owned();
    let p2: Matrix3x4<f64> = tcw2.to_homogeneous().fixed_view::<3, 4>(0, 0).into_owned();
    let row = |p: &Matrix3x4<f64>, c: f64, r: usize| -> RowVector4<f64> { c * p.row(2) - p.row(r) };
    let a = Matrix4::from_rows(&[
        row(&p1, xn1.x, 0),
        row(&p1, xn1.y, 1),
        row(&p2, xn2.x, 0),
        row(&p2, xn2.y, 1),
    ]);
    let svd = a.svd(false, true);
    let v_t = svd.v_t?;
    let (mut imin, mut smin) = (0, f64::INFINITY);
    for (i, &s) in svd.singular_values.iter().enumerate() {
        if s < smin {
            smin = s;
            imin = i;
        }
    }
    let x = v_t.row(imin);
    if x[3].abs() < 1e-12 {
        return None;
    }
    Some(Vector3::new(x[0] / x[3], x[1] / x[3], x[2] / x[3]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Point3, Translation3, UnitQuaternion};

    #[test]
    fn recovers_point_from_two_views() {
        let p = Vector3::new(0.3, -0.2, 3.0);
        let t1 = Isometry3::identity();
        let t2 = Isometry3::from_parts(
            Translation3::new(-0.2, 0.05, 0.1),
            UnitQuaternion::from_euler_angles(0.02, -0.05, 0.01),
        );
        let n = |t: &Isometry3<f64>| {
            let c = t.transform_point(&Point3::from(p));
            Vector3::new(c.x / c.z, c.y / c.z, 1.0)
        };
        let x = triangulate_linear(&n(&t1), &n(&t2), &t1, &t2).unwrap();
        assert!((x - p).norm() < 1e-9, "{x}");
    }
}
