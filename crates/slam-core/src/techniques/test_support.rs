//! Test helpers of the techniques: a seeded generator, Gaussian samples, pose perturbations and
//! errors, the Nguyen et al. axial depth-noise model, and a central-difference Jacobian check.
//! (The optimizer's own helpers are private to `optimize`; these are the few we need.)

use nalgebra::{DMatrix, DVector, Isometry3, Translation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::geometry::exp_so3;

/// The seeded generator of every test.
pub(crate) fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// A standard normal sample (Box-Muller).
pub(crate) fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// A uniformly random unit vector.
pub(crate) fn unit_vector(rng: &mut ChaCha8Rng) -> Vector3<f64> {
    loop {
        let v = Vector3::new(gaussian(rng), gaussian(rng), gaussian(rng));
        if v.norm() > 1e-6 {
            return v.normalize();
        }
    }
}

/// Axial depth noise of a Kinect at depth `z` metres (Nguyen et al. 2012): standard deviation
/// `0.0012 + 0.0019 (z - 0.4)^2` metres.
pub(crate) fn sigma_z(z: f64) -> f64 {
    0.0012 + 0.0019 * (z - 0.4).powi(2)
}

/// `tcw` with its camera centre moved by exactly `metres` and its orientation turned by exactly
/// `radians`, both in random directions.
pub(crate) fn perturb(
    tcw: &Isometry3<f64>,
    metres: f64,
    radians: f64,
    rng: &mut ChaCha8Rng,
) -> Isometry3<f64> {
    let twc = tcw.inverse();
    let centre = twc.translation.vector + unit_vector(rng) * metres;
    let rotation = twc.rotation * exp_so3(&(unit_vector(rng) * radians));
    Isometry3::from_parts(Translation3::from(centre), rotation).inverse()
}

/// Camera-centre distance (metres) and rotation angle (degrees) between two `Tcw`.
pub(crate) fn pose_error(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let ca = a.inverse().translation.vector;
    let cb = b.inverse().translation.vector;
    (
        (ca - cb).norm(),
        a.rotation.angle_to(&b.rotation).to_degrees(),
    )
}

/// Asserts that `analytic` is the central-difference Jacobian of `f` at `x0` (step 1e-6) to a
/// relative error `|J_a - J_n|_F / max(|J_a|_F, 1)` below 1e-6.
pub(crate) fn assert_jacobian(
    what: &str,
    f: impl Fn(&DVector<f64>) -> DVector<f64>,
    x0: &DVector<f64>,
    analytic: &DMatrix<f64>,
) {
    const STEP: f64 = 1e-6;
    let rows = f(x0).len();
    let mut numeric = DMatrix::zeros(rows, x0.len());
    for k in 0..x0.len() {
        let mut plus = x0.clone();
        let mut minus = x0.clone();
        plus[k] += STEP;
        minus[k] -= STEP;
        numeric.set_column(k, &((f(&plus) - f(&minus)) / (2.0 * STEP)));
    }
    let err = (analytic - &numeric).norm() / analytic.norm().max(1.0);
    assert!(
        err < 1e-6,
        "{what}: relative error {err:e}\nanalytic {analytic}\nnumeric {numeric}"
    );
}
