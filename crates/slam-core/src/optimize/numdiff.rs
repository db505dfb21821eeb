//! The shared finite-difference Jacobian checker: every analytic Jacobian in slam-core's
//! optimizers (and later residuals such as AVC) is compared with central differences here.

use nalgebra::{DMatrix, DVector};

/// Central-difference step (the functions checked are smooth at the metre / radian scale).
pub(crate) const STEP: f64 = 1e-6;
/// Largest accepted relative error `|J_analytic - J_numeric|_F / max(|J_analytic|_F, 1)`.
pub(crate) const MAX_RELATIVE_ERROR: f64 = 1e-6;

/// Central-difference Jacobian of `f` at `x0`.
pub(crate) fn numeric_jacobian(
    f: impl Fn(&DVector<f64>) -> DVector<f64>,
    x0: &DVector<f64>,
) -> DMatrix<f64> {
    let rows = f(x0).len();
    let mut j = DMatrix::zeros(rows, x0.len());
    for k in 0..x0.len() {
        let mut plus = x0.clone();
        let mut minus = x0.clone();
        plus[k] += STEP;
        minus[k] -= STEP;
        let column = (f(&plus) - f(&minus)) / (2.0 * STEP);
        j.set_column(k, &column);
    }
    j
}

/// Relative error between an analytic and a numeric Jacobian, as [`MAX_RELATIVE_ERROR`] defines.
pub(crate) fn relative_error(analytic: &DMatrix<f64>, numeric: &DMatrix<f64>) -> f64 {
    (analytic - numeric).norm() / analytic.norm().max(1.0)
}

/// Asserts that `analytic` is the Jacobian of `f` at `x0` to [`MAX_RELATIVE_ERROR`].
pub(crate) fn assert_jacobian(
    what: &str,
    f: impl Fn(&DVector<f64>) -> DVector<f64>,
    x0: &DVector<f64>,
    analytic: &DMatrix<f64>,
) {
    let numeric = numeric_jacobian(f, x0);
    let err = relative_error(analytic, &numeric);
    assert!(
        err < MAX_RELATIVE_ERROR,
        "{what}: relative error {err:e}\nanalytic {analytic}\nnumeric {numeric}"
    );
}

#[test]
fn checker_rejects_a_wrong_jacobian() {
    let f = |x: &DVector<f64>| DVector::from_vec(vec![x[0] * x[1], x[0].sin()]);
    let x0 = DVector::from_vec(vec![0.7, -1.3]);
    let right = DMatrix::from_row_slice(2, 2, &[-1.3, 0.7, 0.7f64.cos(), 0.0]);
    assert!(relative_error(&right, &numeric_jacobian(f, &x0)) < MAX_RELATIVE_ERROR);
    let wrong = DMatrix::from_row_slice(2, 2, &[-1.3, 0.7, 0.7f64.cos() * 1.0001, 0.0]);
    assert!(relative_error(&wrong, &numeric_jacobian(f, &x0)) > MAX_RELATIVE_ERROR);
}
