//! Adaptive Virtual Camera (paper III-B, Eq. 8-12): the 4-D residual of an observation with
//! measured depth, projecting only the depth-axis part of the 3-D error onto a virtual camera
//! placed, per observation, at baseline `b` along the in-image component of that error.
//!
//! # Geometry (camera coordinates, camera centre C at the origin)
//! - D: the keypoint (u, v) back-projected with its measured depth (so D projects to (u, v)).
//! - M: the map point in camera coordinates (the point the solver moves).
//! - D' = |CD| unit(CM) (Eq. 8): D rotated onto the ray CM, so D'M (Eq. 9) is the error along
//!   the depth axis CM and DD' has the same image projection as the 3-D error DM.
//! - The virtual camera C' = (t_x, t_y, 0) = b * unit(DD' - (DD'.z) z) (Eq. 10, 11), falling back
//!   to (b, 0, 0) (ORB-SLAM2's static right camera) when that in-plane component vanishes.
//! - Residual (Eq. 12): (x_M - x_D, y_M - y_D, f_x t_x (1/Z_D' - 1/Z_M), f_y t_y (1/Z_D' - 1/Z_M)),
//!   with 1/Z_D' = |M| / (|D| Z_M), so rows 3 and 4 vanish exactly when |M| = |D|.
//!
//! # Interpretations (documented choices)
//! - Eq. 11 writes `C' = b DD'_proj`. Read literally, |C'| would be b times a length in metres,
//!   which contradicts the text right above it ("the locus of C' is a circle of radius b centred
//!   at C"). We therefore use b times the **unit** vector of DD'_proj: |C'| = b always.
//! - The virtual-camera direction is **held fixed while differentiating**: it is part of the
//!   linearisation point, like a measurement or a robust weight, and is stored in the residual.
//!   It is chosen from an estimate of M when the residual is built and can be re-chosen with
//!   [`VirtualCameraResidual::aim_at`] between optimization rounds (the pose-estimation hook does
//!   so with the current pose before every round; local BA keeps the direction chosen from the
//!   map before the BA, as it has no between-rounds hook). [`CameraResidual::evaluate`] is then a smooth function of M whose
//!   analytic Jacobian is exact. Differentiating through the direction was rejected: the
//!   direction is undefined (and its derivative unbounded, ~1/|DD'_xy|) exactly where the solver
//!   converges (M on the ray CD), while the cost barely depends on it (|r_3|^2 + |r_4|^2 =
//!   (|M|-|D|)^2/(|D| Z_M)^2 (f_x^2 t_x^2 + f_y^2 t_y^2), direction-independent when f_x = f_y),
//!   so Gauss-Newton's J^T J would gain a spurious stiff term the true Hessian cancels.
//! - Rows 3 and 4 use the keypoint's octave information `1 / sigma^2`, like ORB-SLAM2's uR row.
//! - The residual is defined for M in front of the camera (the solvers check `Z_M > MIN_DEPTH`).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use nalgebra::{Matrix4x3, Vector2, Vector3, Vector4};

use crate::module::noise::{AvcAim, AvcParams};
use crate::optimize::{CameraResidual, Measurement, ResidualBlock};
use crate::Camera;

/// An in-image component of DD' at or below this length (metres) counts as vanished: the
/// virtual camera falls back to +x. (One millionth of a pixel at 2 m is ~4e-9 m.)
pub const DIRECTION_EPSILON: f64 = 1e-9;

/// The unit direction, in the image plane, of the virtual camera for measured point `d` and map
/// point `m` (both camera coordinates): unit(component of DD' parallel to the image plane),
/// with D' = |d| unit(m) (Eq. 8, 10). Falls back to +x `(1, 0)` when that component is at or
/// below [`DIRECTION_EPSILON`] or `m` is the camera centre.
pub fn virtual_camera_direction(d: &Vector3<f64>, m: &Vector3<f64>) -> Vector2<f64> {
    direction_with_range(d, d.norm(), m)
}

/// [`virtual_camera_direction`] given `d_norm = |d|` (a residual keeps it).
fn direction_with_range(d: &Vector3<f64>, d_norm: f64, m: &Vector3<f64>) -> Vector2<f64> {
    let m_norm = m.norm();
    if m_norm.is_nan() || m_norm <= 0.0 || !m_norm.is_finite() {
        return Vector2::new(1.0, 0.0);
    }
    let d_prime = m * (d_norm / m_norm);
    let in_plane = Vector2::new(d_prime.x - d.x, d_prime.y - d.y);
    let len = in_plane.norm();
    if len > DIRECTION_EPSILON && len.is_finite() {
        in_plane / len
    } else {
        Vector2::new(1.0, 0.0)
    }
}

/// The paper's 4-D AVC residual of one keypoint with measured depth (Eq. 12), for pose-only
/// optimization and bundle adjustment through [`Measurement::Custom`]. See the module doc for
/// the geometry and for why the virtual-camera direction is stored rather than differentiated.
///
/// Cloning a [`Measurement`] shares this residual (it sits behind an `Arc`), so
/// [`aim_at`](Self::aim_at) on one clone aims all of them; build one residual per observation.
#[derive(Debug)]
pub struct VirtualCameraResidual {
    /// Measured keypoint column (undistorted pixels).
    u: f64,
    /// Measured keypoint row (undistorted pixels).
    v: f64,
    /// D: the keypoint back-projected with its measured depth, camera coordinates (metres).
    measured_point: Vector3<f64>,
    /// |CD|, metres.
    range: f64,
    /// 1 / |CD|, computed once.
    inv_range: f64,
    /// How [`aim_at`](Self::aim_at) places the virtual camera.
    aim: AvcAim,
    /// Virtual camera baseline b, metres.
    baseline: f64,
    /// The virtual camera centre (t_x, t_y) = b (cos a, sin a), a = `atan2` of the chosen
    /// direction, as f64 bits; atomic so the direction can be re-chosen between rounds through a
    /// shared `Arc`. Kept as the centre rather than the angle: the residual is evaluated some
    /// twenty times per aim, and its sine and cosine were a third of AVC's cost.
    centre_bits: [AtomicU64; 2],
}

impl VirtualCameraResidual {
    /// The residual of keypoint (u, v) (undistorted pixels) with measured depth `depth`
    /// (metres), virtual baseline `baseline` (metres), its virtual camera aimed from the current
    /// estimate `estimate` of the map point in camera coordinates. `None` unless `depth` and
    /// `baseline` are finite and positive.
    pub fn new(
        camera: &Camera,
        u: f64,
        v: f64,
        depth: f64,
        baseline: f64,
        estimate: &Vector3<f64>,
    ) -> Option<Self> {
        Self::with_aim_from(camera, u, v, depth, baseline, AvcAim::Angle, estimate)
    }

    /// [`new`](Self::new) with the virtual camera placed by `aim` from the start (aimed once,
    /// not first by the angle and then again).
    pub fn with_aim_from(
        camera: &Camera,
        u: f64,
        v: f64,
        depth: f64,
        baseline: f64,
        aim: AvcAim,
        estimate: &Vector3<f64>,
    ) -> Option<Self> {
        if !Self::is_defined(depth, baseline) {
            return None;
        }
        let measured_point = camera.unproject(u, v, depth);
        let residual = VirtualCameraResidual {
            u,
            v,
            measured_point,
            range: measured_point.norm(),
            inv_range: 1.0 / measured_point.norm(),
            aim,
            baseline,
            centre_bits: [AtomicU64::new(0), AtomicU64::new(0)],
        };
        residual.aim_at(estimate);
        Some(residual)
    }

    /// Whether a residual exists for measured depth `depth` and baseline `baseline` (metres):
    /// both finite and positive. [`with_aim_from`](Self::with_aim_from) builds one exactly then.
    pub fn is_defined(depth: f64, baseline: f64) -> bool {
        depth > 0.0 && depth.is_finite() && baseline > 0.0 && baseline.is_finite()
    }

    /// The residual placing its virtual camera by `aim` (re-aimed from `estimate`).
    pub fn with_aim(mut self, aim: AvcAim, estimate: &Vector3<f64>) -> Self {
        self.aim = aim;
        self.aim_at(estimate);
        self
    }

    /// Re-chooses the virtual camera from the estimate `p_c` of the map point in camera
    /// coordinates (Eq. 8-11). The solvers treat the direction as fixed until the next call.
    pub fn aim_at(&self, p_c: &Vector3<f64>) {
        let dir = direction_with_range(&self.measured_point, self.range, p_c);
        let t = match self.aim {
            AvcAim::Angle => {
                let angle = dir.y.atan2(dir.x);
                Vector2::new(angle.cos(), angle.sin()) * self.baseline
            }
            AvcAim::Direct => dir * self.baseline,
        };
        self.centre_bits[0].store(t.x.to_bits(), Ordering::Relaxed);
        self.centre_bits[1].store(t.y.to_bits(), Ordering::Relaxed);
    }

    /// The virtual camera centre (t_x, t_y) in the image plane of the real camera (metres);
    /// its norm is the baseline b.
    pub fn virtual_camera(&self) -> Vector2<f64> {
        Vector2::new(
            f64::from_bits(self.centre_bits[0].load(Ordering::Relaxed)),
            f64::from_bits(self.centre_bits[1].load(Ordering::Relaxed)),
        )
    }

    /// D: the measured point in camera coordinates (metres).
    pub fn measured_point(&self) -> Vector3<f64> {
        self.measured_point
    }

    /// The residual and its Jacobian at the camera-frame point `p_c` (what
    /// [`CameraResidual::evaluate`] returns; `None` where the residual is undefined).
    #[inline]
    pub fn block(&self, camera: &Camera, p_c: &Vector3<f64>) -> Option<ResidualBlock> {
        let (x, y, z) = (p_c.x, p_c.y, p_c.z);
        let n = p_c.norm();
        if z.is_nan() || z <= 0.0 || n.is_nan() || n <= 0.0 || !n.is_finite() {
            return None;
        }
        let t = self.virtual_camera();
        let inv_z = 1.0 / z;
        let inv_rho = self.inv_range;
        // g = 1/Z_D' - 1/Z_M with Z_D' = |D| Z_M / |M|.
        let g = (n * inv_rho - 1.0) * inv_z;
        // dg/dM = M / (|M| |D| Z_M) - (|M|/|D| - 1) / Z_M^2 * e_z.
        let k = inv_rho / n * inv_z;
        let dg = Vector3::new(x * k, y * k, z * k - g * inv_z);
        let (ax, ay) = (camera.fx * t.x, camera.fy * t.y);
        let residual = Vector4::new(
            camera.fx * x * inv_z + camera.cx - self.u,
            camera.fy * y * inv_z + camera.cy - self.v,
            ax * g,
            ay * g,
        );
        #[rustfmt::skip]
        let d_residual_d_point = Matrix4x3::new(
            camera.fx * inv_z, 0.0, -camera.fx * x * inv_z * inv_z,
            0.0, camera.fy * inv_z, -camera.fy * y * inv_z * inv_z,
            ax * dg.x, ax * dg.y, ax * dg.z,
            ay * dg.x, ay * dg.y, ay * dg.z,
        );
        Some(ResidualBlock {
            residual,
            d_residual_d_point,
        })
    }

    /// The residual rows of [`block`](Self::block), the same operations without the
    /// Jacobian: what the solvers' cost and chi2 tests need, most of their evaluations.
    #[inline]
    pub fn residual_rows(&self, camera: &Camera, p_c: &Vector3<f64>) -> Option<Vector4<f64>> {
        let (x, y, z) = (p_c.x, p_c.y, p_c.z);
        let n = p_c.norm();
        if z.is_nan() || z <= 0.0 || n.is_nan() || n <= 0.0 || !n.is_finite() {
            return None;
        }
        let t = self.virtual_camera();
        let inv_z = 1.0 / z;
        let inv_rho = self.inv_range;
        let g = (n * inv_rho - 1.0) * inv_z;
        let (ax, ay) = (camera.fx * t.x, camera.fy * t.y);
        Some(Vector4::new(
            camera.fx * x * inv_z + camera.cx - self.u,
            camera.fy * y * inv_z + camera.cy - self.v,
            ax * g,
            ay * g,
        ))
    }

    /// The virtual baseline b (metres).
    pub fn baseline(&self) -> f64 {
        self.baseline
    }
}

impl CameraResidual for VirtualCameraResidual {
    fn dof(&self) -> usize {
        4
    }

    fn evaluate(&self, camera: &Camera, p_c: &Vector3<f64>) -> Option<ResidualBlock> {
        self.block(camera, p_c)
    }

    fn residual(&self, camera: &Camera, p_c: &Vector3<f64>) -> Option<Vector4<f64>> {
        self.residual_rows(camera, p_c)
    }
}

/// One residual of a set of [`VirtualCameraResidual`]s built together: what
/// [`Measurement::VirtualCamera`] holds. A pose optimization builds the residuals of all its
/// observations in one allocation (one per observation cost 2.5 % of an AVC run's instructions)
/// and re-aims them through the set; a residual built alone is a set of one. Dereferences to the residual.
#[derive(Clone, Debug)]
pub struct VirtualCameraRef {
    /// The residuals built together.
    set: Arc<[VirtualCameraResidual]>,
    /// Which of them this is.
    index: usize,
}

impl VirtualCameraRef {
    /// A residual on its own (a set of one).
    pub fn single(residual: VirtualCameraResidual) -> Self {
        VirtualCameraRef {
            set: Arc::new([residual]),
            index: 0,
        }
    }

    /// Residual `index` of `set`. `None` when `index` is out of range.
    pub fn new(set: &Arc<[VirtualCameraResidual]>, index: usize) -> Option<Self> {
        (index < set.len()).then(|| VirtualCameraRef {
            set: set.clone(),
            index,
        })
    }
}

impl std::ops::Deref for VirtualCameraRef {
    type Target = VirtualCameraResidual;

    #[inline(always)]
    fn deref(&self) -> &VirtualCameraResidual {
        &self.set[self.index]
    }
}

/// The AVC measurement of keypoint (u, v) with measured depth `depth` (metres), aimed from the
/// map-point estimate `estimate` (camera coordinates): what `measurement_for` builds for a
/// keypoint with depth when AVC is on. `None` for a keypoint without valid depth (the caller
/// keeps its mono / stereo residual).
pub fn avc_measurement(
    camera: &Camera,
    u: f64,
    v: f64,
    depth: f64,
    params: &AvcParams,
    estimate: &Vector3<f64>,
) -> Option<Measurement> {
    VirtualCameraResidual::with_aim_from(camera, u, v, depth, params.baseline, params.aim, estimate)
        .map(|r| Measurement::VirtualCamera(VirtualCameraRef::single(r)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{exp_se3, Vector6};
    use crate::optimize::{pose_optimization, pose_optimization_with, PoseObservation};
    use crate::optimize::{PoseOptConfig, MIN_DEPTH};
    use crate::techniques::test_support::{
        assert_jacobian, gaussian, perturb, pose_error, rng, sigma_z,
    };
    use nalgebra::{DMatrix, DVector, Isometry3, Point3, Translation3, UnitQuaternion};
    use rand::Rng;

    fn residual_at(r: &VirtualCameraResidual, camera: &Camera, p: &Vector3<f64>) -> Vector4<f64> {
        r.evaluate(camera, p).unwrap().residual
    }

    #[test]
    fn jacobian_matches_central_differences() {
        let camera = Camera::tum_fr3();
        let mut g = rng(1);
        for _ in 0..200 {
            let u = g.random_range(5.0..635.0);
            let v = g.random_range(5.0..475.0);
            let depth = g.random_range(0.5..6.0);
            let d = camera.unproject(u, v, depth);
            // Map points from nearly on the ray to grossly off it.
            let scale = [1e-3, 0.05, 0.5][g.random_range(0..3)];
            let m = d + Vector3::new(gaussian(&mut g), gaussian(&mut g), gaussian(&mut g)) * scale;
            if m.z <= 0.2 {
                continue;
            }
            let r = VirtualCameraResidual::new(&camera, u, v, depth, 0.09, &m).unwrap();
            let block = r.evaluate(&camera, &m).unwrap();
            let f = |x: &DVector<f64>| {
                let q = Vector3::new(x[0], x[1], x[2]);
                DVector::from_column_slice(residual_at(&r, &camera, &q).as_slice())
            };
            assert_jacobian(
                &format!("AVC at {m:?}"),
                f,
                &DVector::from_column_slice(m.as_slice()),
                &DMatrix::from_column_slice(4, 3, block.d_residual_d_point.as_slice()),
            );
        }
    }

    #[test]
    fn rows_follow_equation_12() {
        let camera = Camera::tum_fr3();
        let (u, v, depth) = (400.0, 150.0, 2.5);
        let d = camera.unproject(u, v, depth);
        let m = Vector3::new(d.x + 0.03, d.y - 0.02, d.z + 0.1);
        let r = VirtualCameraResidual::new(&camera, u, v, depth, 0.09, &m).unwrap();
        let e = residual_at(&r, &camera, &m);
        // Eq. 8-11 written out directly.
        let d_prime = m.normalize() * d.norm();
        let dd = d_prime - d;
        let t = Vector2::new(dd.x, dd.y).normalize() * 0.09;
        assert!((r.virtual_camera() - t).norm() < 1e-12);
        assert!((r.virtual_camera().norm() - 0.09).abs() < 1e-12, "|C'| = b");
        let pm = camera.project(&m);
        let expected = Vector4::new(
            pm.x - u,
            pm.y - v,
            camera.fx * t.x / d_prime.z - camera.fx * t.x / m.z,
            camera.fy * t.y / d_prime.z - camera.fy * t.y / m.z,
        );
        assert!((e - expected).norm() < 1e-9, "{e} vs {expected}");
        // The 2-D rows are the ORB-SLAM2 rows.
        let stereo = Measurement::rgbd(&camera, u, v, depth)
            .evaluate(&camera, &m)
            .unwrap();
        assert!((e.fixed_rows::<2>(0) - stereo.residual.fixed_rows::<2>(0)).norm() < 1e-12);
    }

    #[test]
    fn depth_rows_vanish_iff_range_agrees() {
        let camera = Camera::tum_fr3();
        let (u, v, depth) = (250.0, 300.0, 3.0);
        let d = camera.unproject(u, v, depth);
        // Same range, different bearing: only the 2-D rows are non-zero.
        let m = UnitQuaternion::from_euler_angles(0.01, -0.02, 0.0) * d;
        let r = VirtualCameraResidual::new(&camera, u, v, depth, 0.09, &m).unwrap();
        let e = residual_at(&r, &camera, &m);
        assert!(e[2].abs() < 1e-9 && e[3].abs() < 1e-9, "{e}");
        assert!(e[0].abs() > 1.0 || e[1].abs() > 1.0);
        // Same bearing, 10 cm further: only the depth rows, with norm f b dR / (|D| Z_M).
        let m = d * (1.0 + 0.1 / d.norm());
        let r = VirtualCameraResidual::new(&camera, u, v, depth, 0.09, &m).unwrap();
        let e = residual_at(&r, &camera, &m);
        assert!(e[0].abs() < 1e-9 && e[1].abs() < 1e-9);
        let expected = camera.fx * 0.09 * 0.1 / (d.norm() * m.z);
        assert!((e[2] - expected).abs() < 1e-9, "fallback +x: {e}");
        assert_eq!(e[3], 0.0);
    }

    #[test]
    fn residual_alone_is_the_bits_of_the_evaluated_block() {
        let camera = Camera::tum_fr3();
        let mut g = rng(11);
        for _ in 0..500 {
            let (u, v) = (g.random_range(0.0..640.0), g.random_range(0.0..480.0));
            let depth = g.random_range(0.3..8.0);
            let d = camera.unproject(u, v, depth);
            let aim = d + Vector3::new(gaussian(&mut g), gaussian(&mut g), gaussian(&mut g)) * 0.05;
            let r = VirtualCameraResidual::new(&camera, u, v, depth, 0.09, &aim).unwrap();
            let m = d + Vector3::new(gaussian(&mut g), gaussian(&mut g), gaussian(&mut g)) * 0.2;
            let full = r.evaluate(&camera, &m).map(|b| b.residual);
            let alone = r.residual(&camera, &m);
            assert_eq!(
                full.map(|x| x.map(f64::to_bits)),
                alone.map(|x| x.map(f64::to_bits)),
                "at {m}"
            );
        }
    }

    #[test]
    fn residuals_of_a_set_are_its_members() {
        let camera = Camera::tum_fr3();
        let set: Arc<[VirtualCameraResidual]> = (0..3)
            .map(|k| {
                let d = camera.unproject(100.0 + k as f64, 200.0, 2.0);
                VirtualCameraResidual::new(&camera, 100.0 + k as f64, 200.0, 2.0, 0.09, &d).unwrap()
            })
            .collect();
        for k in 0..3 {
            let r = VirtualCameraRef::new(&set, k).unwrap();
            assert_eq!(r.u, 100.0 + k as f64);
            // Aiming through a reference aims the member.
            r.aim_at(&camera.unproject(100.0 + k as f64, 190.0, 2.0));
            assert_eq!(set[k].virtual_camera(), r.virtual_camera());
            assert!(
                set[k].virtual_camera().y < -0.08,
                "{}",
                set[k].virtual_camera()
            );
        }
        assert!(VirtualCameraRef::new(&set, 3).is_none());
    }

    #[test]
    fn direction_falls_back_to_plus_x() {
        let camera = Camera::tum_fr3();
        let d = camera.unproject(100.0, 400.0, 2.0);
        // M on the ray CD: DD' = 0.
        assert_eq!(
            virtual_camera_direction(&d, &(d * 1.3)),
            Vector2::new(1.0, 0.0)
        );
        assert_eq!(virtual_camera_direction(&d, &d), Vector2::new(1.0, 0.0));
        assert_eq!(
            virtual_camera_direction(&d, &Vector3::zeros()),
            Vector2::new(1.0, 0.0)
        );
        // Off the ray: the direction follows the lateral offset, here mostly -y.
        let dir = virtual_camera_direction(&d, &(d + Vector3::new(0.0, -0.05, 0.0)));
        assert!(dir.y < -0.9 && (dir.norm() - 1.0).abs() < 1e-12, "{dir}");
        let r = VirtualCameraResidual::new(&camera, 100.0, 400.0, 2.0, 0.05, &d).unwrap();
        assert!((r.virtual_camera() - Vector2::new(0.05, 0.0)).norm() < 1e-15);
    }

    #[test]
    fn aim_at_moves_the_virtual_camera_only_when_asked() {
        let camera = Camera::tum_fr3();
        let d = camera.unproject(320.0, 240.0, 2.0);
        let r = VirtualCameraResidual::new(&camera, 320.0, 240.0, 2.0, 0.09, &d).unwrap();
        let up = d + Vector3::new(0.0, 0.04, 0.02);
        let before = r.virtual_camera();
        let _ = r.evaluate(&camera, &up);
        assert_eq!(r.virtual_camera(), before, "evaluate must not re-aim");
        r.aim_at(&up);
        assert!(r.virtual_camera().y > 0.08, "{}", r.virtual_camera());
    }

    #[test]
    fn rejects_invalid_depth_and_points_behind() {
        let camera = Camera::tum_fr3();
        let m = Vector3::new(0.0, 0.0, 1.0);
        for depth in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(VirtualCameraResidual::new(&camera, 1.0, 1.0, depth, 0.09, &m).is_none());
        }
        assert!(VirtualCameraResidual::new(&camera, 1.0, 1.0, 1.0, 0.0, &m).is_none());
        let meas = avc_measurement(&camera, 300.0, 200.0, 2.0, &AvcParams::default(), &m).unwrap();
        assert!(meas
            .evaluate(&camera, &Vector3::new(0.1, 0.1, -1.0))
            .is_none());
        assert!(meas
            .evaluate(&camera, &Vector3::new(0.1, 0.1, MIN_DEPTH / 2.0))
            .is_none());
    }

    #[test]
    fn four_dof_gate_and_huber_delta() {
        let camera = Camera::tum_fr3();
        let m = avc_measurement(
            &camera,
            300.0,
            200.0,
            2.0,
            &AvcParams::default(),
            &Vector3::new(0.0, 0.0, 2.0),
        )
        .unwrap();
        assert_eq!(m.dof(), 4);
        assert_eq!(m.chi2_threshold(), 9.488);
        assert!((m.huber_delta() - 9.488f64.sqrt()).abs() < 1e-15);
    }

    fn true_pose() -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(0.1, -0.2, 0.25),
            UnitQuaternion::from_euler_angles(-0.05, 0.1, 0.15),
        )
    }

    /// `n` RGB-D observations seen from `true_pose()`: 1 px keypoint noise, Nguyen's axial depth
    /// noise, and a fraction `gross` of them, closer than 3 m, with a depth 40-100 % too far or
    /// 30-50 % too near (a boundary mix-up; the depth rows scale with f b dZ / Z^2, so smaller
    /// relative errors or larger depths stay within a pixel and cannot be told from noise).
    /// Returns (world point, u, v, measured depth, is gross).
    fn rgbd_scene(n: usize, gross: f64, seed: u64) -> Vec<(Vector3<f64>, f64, f64, f64, bool)> {
        let camera = Camera::tum_fr3();
        let twc = true_pose().inverse();
        let mut g = rng(seed);
        (0..n)
            .map(|i| {
                let is_gross = (i as f64) < gross * n as f64;
                let (u, v) = (g.random_range(10.0..630.0), g.random_range(10.0..470.0));
                let z = g.random_range(0.8..if is_gross { 3.0 } else { 4.5 });
                let pw = (twc * Point3::from(camera.unproject(u, v, z))).coords;
                let depth = if is_gross {
                    if g.random_bool(0.5) {
                        z * g.random_range(1.4..2.0)
                    } else {
                        z * g.random_range(0.5..0.7)
                    }
                } else {
                    z + sigma_z(z) * gaussian(&mut g)
                };
                let (nu, nv) = (u + gaussian(&mut g), v + gaussian(&mut g));
                (pw, nu, nv, depth, is_gross)
            })
            .collect()
    }

    /// Pose observations of `scene` (RGB-D 3-D residuals, or AVC residuals aimed from `start`),
    /// and the AVC residuals themselves (empty for the 3-D residual) so a hook can re-aim them.
    fn observations(
        scene: &[(Vector3<f64>, f64, f64, f64, bool)],
        start: &Isometry3<f64>,
        avc: bool,
    ) -> (Vec<PoseObservation>, Vec<Arc<VirtualCameraResidual>>) {
        let camera = Camera::tum_fr3();
        let mut residuals = Vec::new();
        let obs = scene
            .iter()
            .map(|&(pw, u, v, depth, _)| {
                let estimate = (start * Point3::from(pw)).coords;
                let measurement = if avc {
                    let b = AvcParams::default().baseline;
                    let r = Arc::new(
                        VirtualCameraResidual::new(&camera, u, v, depth, b, &estimate).unwrap(),
                    );
                    residuals.push(r.clone());
                    Measurement::Custom(r)
                } else {
                    Measurement::rgbd(&camera, u, v, depth)
                };
                PoseObservation {
                    point_world: pw,
                    measurement,
                    inv_sigma2: 1.0,
                }
            })
            .collect();
        (obs, residuals)
    }

    #[test]
    fn pose_optimization_recovers_the_pose_like_the_3d_residual() {
        let camera = Camera::tum_fr3();
        let scene = rgbd_scene(250, 0.0, 3);
        let start = perturb(&true_pose(), 0.08, 4f64.to_radians(), &mut rng(4));
        let cfg = PoseOptConfig::default();
        let base = pose_optimization(
            &camera,
            &start,
            &observations(&scene, &start, false).0,
            &cfg,
        );
        let (obs, residuals) = observations(&scene, &start, true);
        let avc = pose_optimization(&camera, &start, &obs, &cfg);
        let (bt, br) = pose_error(&base.pose, &true_pose());
        let (at, ar) = pose_error(&avc.pose, &true_pose());
        assert!(bt < 0.01 && br < 0.2, "3-D residual: {bt} m {br} deg");
        assert!(at < 0.01 && ar < 0.2, "AVC residual: {at} m {ar} deg");
        assert!(at < 2.0 * bt + 0.002, "AVC {at} m vs 3-D {bt} m");
        assert!(avc.n_inliers >= 220, "{} AVC inliers", avc.n_inliers);
        // Re-aiming every virtual camera before each round (the pose-estimation hook) converges
        // to the same pose.
        let aimed = pose_optimization_with(&camera, &start, &obs, &cfg, &mut |_, pose, _| {
            for (o, r) in obs.iter().zip(&residuals) {
                r.aim_at(&(pose * Point3::from(o.point_world)).coords);
            }
        });
        let (dt, dr) = pose_error(&aimed.pose, &avc.pose);
        assert!(
            dt < 1e-4 && dr < 0.01,
            "re-aimed differs by {dt} m {dr} deg"
        );
    }

    #[test]
    fn direct_aim_places_the_camera_where_the_angle_does_and_solves_the_same_pose() {
        let camera = Camera::tum_fr3();
        let mut g = rng(21);
        for _ in 0..500 {
            let (u, v) = (g.random_range(0.0..640.0), g.random_range(0.0..480.0));
            let depth = g.random_range(0.3..8.0);
            let d = camera.unproject(u, v, depth);
            let aim = d + Vector3::new(gaussian(&mut g), gaussian(&mut g), gaussian(&mut g)) * 0.05;
            let angle = VirtualCameraResidual::new(&camera, u, v, depth, 0.09, &aim).unwrap();
            let direct = VirtualCameraResidual::new(&camera, u, v, depth, 0.09, &aim)
                .unwrap()
                .with_aim(AvcAim::Direct, &aim);
            let gap = (angle.virtual_camera() - direct.virtual_camera()).norm();
            assert!(gap < 1e-16, "{gap} m: a few ulps of b");
            // Built with the direct aim from the start: the same centre, bit for bit.
            let built = VirtualCameraResidual::with_aim_from(
                &camera,
                u,
                v,
                depth,
                0.09,
                AvcAim::Direct,
                &aim,
            )
            .unwrap();
            assert_eq!(
                built.virtual_camera().map(f64::to_bits),
                direct.virtual_camera().map(f64::to_bits)
            );
        }
        // Re-aimed before every round, as the pose-estimation hook does, both aims solve the
        // same pose to far below a micrometre (their bits differ).
        let scene = rgbd_scene(250, 0.1, 3);
        let start = perturb(&true_pose(), 0.08, 4f64.to_radians(), &mut rng(4));
        let cfg = PoseOptConfig::default();
        let solve = |aim: AvcAim| {
            let (obs, residuals) = observations(&scene, &start, true);
            let residuals: Arc<[VirtualCameraResidual]> = residuals
                .iter()
                .zip(&obs)
                .map(|(r, o)| {
                    let estimate = (start * Point3::from(o.point_world)).coords;
                    let (u, v) = (r.u, r.v);
                    let depth = r.measured_point.z;
                    VirtualCameraResidual::new(&camera, u, v, depth, 0.09, &estimate)
                        .unwrap()
                        .with_aim(aim, &estimate)
                })
                .collect();
            let obs: Vec<PoseObservation> = obs
                .iter()
                .enumerate()
                .map(|(n, o)| PoseObservation {
                    measurement: Measurement::VirtualCamera(
                        VirtualCameraRef::new(&residuals, n).unwrap(),
                    ),
                    ..o.clone()
                })
                .collect();
            pose_optimization_with(&camera, &start, &obs, &cfg, &mut |_, pose, _| {
                for (o, r) in obs.iter().zip(residuals.iter()) {
                    r.aim_at(&(pose * Point3::from(o.point_world)).coords);
                }
            })
        };
        let (a, d) = (solve(AvcAim::Angle), solve(AvcAim::Direct));
        let (dt, dr) = pose_error(&a.pose, &d.pose);
        assert!(dt < 1e-9 && dr < 1e-7, "aims differ by {dt} m {dr} deg");
        assert_eq!(a.inliers, d.inliers);
    }

    #[test]
    fn gross_depth_errors_fail_the_four_dof_gate() {
        let camera = Camera::tum_fr3();
        let scene = rgbd_scene(200, 0.15, 5);
        let start = perturb(&true_pose(), 0.05, 2f64.to_radians(), &mut rng(6));
        let (obs, _) = observations(&scene, &start, true);
        let r = pose_optimization(&camera, &start, &obs, &PoseOptConfig::default());
        let (dt, dr) = pose_error(&r.pose, &true_pose());
        assert!(dt < 0.01 && dr < 0.2, "{dt} m {dr} deg");
        for (k, s) in scene.iter().enumerate() {
            if s.4 {
                assert!(
                    !r.inliers[k],
                    "gross depth error {k} kept, chi2 {}",
                    r.chi2[k]
                );
            }
            assert_eq!(r.inliers[k], r.chi2[k] <= 9.488);
        }
        // The pose Jacobian the solver chains (d r / d p_c * [-[p]x, I]) matches too.
        let o = &obs[40];
        let f = |x: &DVector<f64>| {
            let xi = Vector6::from_column_slice(x.as_slice());
            let p = (exp_se3(&xi) * r.pose * Point3::from(o.point_world)).coords;
            DVector::from_column_slice(
                o.measurement
                    .evaluate(&camera, &p)
                    .unwrap()
                    .residual
                    .as_slice(),
            )
        };
        let p = (r.pose * Point3::from(o.point_world)).coords;
        let j = o
            .measurement
            .evaluate(&camera, &p)
            .unwrap()
            .d_residual_d_point
            * crate::geometry::d_point_d_left_perturbation(&p);
        assert_jacobian(
            "AVC pose Jacobian",
            f,
            &DVector::zeros(6),
            &DMatrix::from_column_slice(4, 6, j.as_slice()),
        );
    }
}
