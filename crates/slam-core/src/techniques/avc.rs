//! Adaptive Virtual Camera (paper III-B, Eq. 8-12) as a technique: the measurement a keypoint
//! with depth gets when AVC is on. The 4-D residual itself (its geometry, and the documented
//! reading of Eq. 11) is [`crate::optimize::virtual_camera`], beside the residuals the solvers
//! evaluate; it is re-exported here.

use nalgebra::Vector3;

pub use crate::optimize::virtual_camera::{
    virtual_camera_direction, VirtualCameraRef, VirtualCameraResidual, DIRECTION_EPSILON,
};
use crate::optimize::Measurement;
use crate::techniques::params::AvcParams;
use crate::Camera;

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
    use crate::optimize::{AvcAim, CameraResidual};
    use crate::optimize::{PoseOptConfig, MIN_DEPTH};
    use crate::techniques::test_support::{
        assert_jacobian, gaussian, perturb, pose_error, rng, sigma_z,
    };
    use nalgebra::{DMatrix, DVector, Isometry3, Point3, Translation3, UnitQuaternion};
    use nalgebra::{Vector2, Vector4};
    use rand::Rng;
    use std::sync::Arc;

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
