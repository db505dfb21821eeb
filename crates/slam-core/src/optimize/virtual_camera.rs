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
//!
//! It lives here, beside the other residuals, because [`Measurement`](super::Measurement) holds it by value (static
//! dispatch: a pose optimization evaluates it some twenty times per observation); the technique
//! that decides when to use it is [`crate::techniques::avc`].

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use nalgebra::{Matrix4x3, Vector2, Vector3, Vector4};
use serde::{Deserialize, Serialize};

use super::camera_residual::{CameraResidual, ResidualBlock};
use crate::Camera;

/// How [`VirtualCameraResidual::aim_at`]
/// places the virtual camera C' = b u, u the unit in-image direction of DD' (Eq. 10, 11).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AvcAim {
    /// C' = b (cos a, sin a), a = atan2(u): the reference every result was made with.
    #[default]
    Angle,
    /// C' = b u directly: the same point up to an ulp or two, without the atan2, sin and cos
    /// that are 37 % of AVC's remaining cost over the baseline (an approximation of the
    /// reference's bits, not of the paper: trajectories differ in their last digits; tested
    /// within 1e-9 m of the reference on pose optimization). Off by default.
    Direct,
}

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
/// optimization and bundle adjustment through [`Measurement::Custom`](super::Measurement::Custom). See the module doc for
/// the geometry and for why the virtual-camera direction is stored rather than differentiated.
///
/// Cloning a [`Measurement`](super::Measurement) shares this residual (it sits behind an `Arc`), so
/// [`aim_at`](Self::aim_at) on one clone aims all of them; build one residual per observation.
#[derive(Debug)]
pub struct VirtualCameraResidual {
    /// Measured keypoint column (undistorted pixels).
    pub(crate) u: f64,
    /// Measured keypoint row (undistorted pixels).
    pub(crate) v: f64,
    /// D: the keypoint back-projected with its measured depth, camera coordinates (metres).
    pub(crate) measured_point: Vector3<f64>,
    /// |CD|, metres.
    range: f64,
    /// 1 / |CD|, computed once.
    inv_range: f64,
    /// How [`aim_at`](Self::aim_at) places the virtual camera.
    aim: AvcAim,
    /// Virtual camera baseline b, metres.
    baseline: f64,
    /// The chi2 gate (and, square-rooted, the Huber threshold) of this residual: chi2(4 dof)
    /// = 9.488 unless [`with_gate`](Self::with_gate) set another (AVC's `gate` reading).
    gate: f64,
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
            gate: super::chi2_95(4),
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

    /// The residual gated at chi2 `gate` instead of chi2(4 dof) (AVC's `gate` reading: 7.815,
    /// ORB-SLAM2's stereo gate); the Huber threshold follows, as ORB-SLAM2 ties the two.
    pub fn with_gate(mut self, gate: f64) -> Self {
        self.gate = gate;
        self
    }

    /// The chi2 gate of this residual (9.488 unless [`with_gate`](Self::with_gate) set another).
    pub fn chi2_gate(&self) -> f64 {
        self.gate
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
/// [`Measurement::VirtualCamera`](super::Measurement::VirtualCamera) holds. A pose optimization builds the residuals of all its
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
