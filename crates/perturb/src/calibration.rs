//! The calibration families: the camera a system is *given* (our runs' camera, the ORB-SLAM2 /
//! ORB-SLAM3 settings written beside an exported folder) differs from the one that recorded
//! the images, as a real calibration does; the images are not touched.
//!
//! - `focal-error:L`: fx and fy times 1 + L/100. For stereo, `bf` too (the rig's baseline in
//!   metres is what was calibrated, so depth from disparity scales with the focal length); for
//!   RGB-D `bf` is ORB-SLAM2's virtual baseline (`Camera.bf` of its settings, written on its
//!   own) and stays.
//! - `principal-point-error:L`: (cx, cy) moved L pixels along a direction drawn once from the
//!   perturbation seed.
//! - `distortion-error:L`: each distortion coefficient times 1 - L (L = 1 leaves all of it
//!   out). A camera without distortion (TUM fr3, whose images TUM undistorted; a rectified
//!   stereo pair, which the reader undistorts with its own calibration) is refused.

use crate::family::{Domain, Family, Perturbation};
use crate::PerturbError;
use slam_core::{Camera, SensorKind};
use synth::hash::{NoiseKey, Stream};

/// The direction (radians) in which `principal-point-error` moves the principal point, for a
/// member seed.
pub fn principal_point_direction(seed: u64) -> f64 {
    NoiseKey::new(seed, 0, Stream::Mocap).uniform(0) * std::f64::consts::TAU
}

/// The camera a system is given when `members` (the chain's calibration members with their
/// member seeds) are applied to `camera`, the camera that recorded the images.
pub fn given_camera(
    camera: &Camera,
    members: &[(Perturbation, u64)],
    sequence: &str,
) -> Result<Camera, PerturbError> {
    let mut c = camera.clone();
    for &(p, seed) in members {
        debug_assert_eq!(p.family.domain(), Domain::Calibration);
        match p.family {
            Family::FocalError => {
                let k = 1.0 + p.level / 100.0;
                c.fx *= k;
                c.fy *= k;
                if c.sensor == SensorKind::Stereo {
                    c.bf *= k;
                }
            }
            Family::PrincipalPointError => {
                let a = principal_point_direction(seed);
                c.cx += p.level * a.cos();
                c.cy += p.level * a.sin();
            }
            Family::DistortionError => {
                let Some(d) = c.distortion.as_mut() else {
                    return Err(PerturbError::NotApplicable {
                        family: p.family.name(),
                        sequence: sequence.to_string(),
                        why: "its camera has no lens distortion to leave out (images undistorted \
                              or rectified before the system sees them)"
                            .into(),
                    });
                };
                let k = 1.0 - p.level;
                d.k1 *= k;
                d.k2 *= k;
                d.p1 *= k;
                d.p2 *= k;
                d.k3 *= k;
            }
            _ => {}
        }
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn member(family: Family, level: f64) -> (Perturbation, u64) {
        (Perturbation { family, level }, 7)
    }

    #[test]
    fn focal_error_scales_fx_fy_and_a_stereo_bf_only() {
        let cam = Camera::tum_fr1();
        let c = given_camera(&cam, &[member(Family::FocalError, 1.0)], "s").unwrap();
        assert!((c.fx / cam.fx - 1.01).abs() < 1e-12 && (c.fy / cam.fy - 1.01).abs() < 1e-12);
        assert_eq!(
            (c.cx, c.cy, c.bf, c.distortion),
            (cam.cx, cam.cy, cam.bf, cam.distortion)
        );
        let st = Camera::euroc_rectified();
        let c = given_camera(&st, &[member(Family::FocalError, -2.0)], "s").unwrap();
        assert!((c.bf / st.bf - 0.98).abs() < 1e-12);
        // bf / fx, the baseline in metres, is what the calibration keeps.
        assert!((c.bf / c.fx - st.bf / st.fx).abs() < 1e-12);
    }

    #[test]
    fn principal_point_moves_by_the_level_in_a_seeded_direction() {
        let cam = Camera::tum_fr3();
        let c = given_camera(&cam, &[member(Family::PrincipalPointError, 3.0)], "s").unwrap();
        let moved = ((c.cx - cam.cx).powi(2) + (c.cy - cam.cy).powi(2)).sqrt();
        assert!((moved - 3.0).abs() < 1e-12, "{moved}");
        let other = given_camera(
            &cam,
            &[(
                Perturbation {
                    family: Family::PrincipalPointError,
                    level: 3.0,
                },
                8,
            )],
            "s",
        )
        .unwrap();
        assert_ne!((c.cx, c.cy), (other.cx, other.cy));
        assert_eq!((c.fx, c.fy), (cam.fx, cam.fy));
    }

    #[test]
    fn distortion_error_leaves_out_its_share_and_refuses_a_pinhole() {
        let cam = Camera::tum_fr1();
        let c = given_camera(&cam, &[member(Family::DistortionError, 0.25)], "s").unwrap();
        let (d, t) = (c.distortion.unwrap(), cam.distortion.unwrap());
        for (a, b) in [
            (d.k1, t.k1),
            (d.k2, t.k2),
            (d.p1, t.p1),
            (d.p2, t.p2),
            (d.k3, t.k3),
        ] {
            assert!((a - 0.75 * b).abs() < 1e-15);
        }
        let all = given_camera(&cam, &[member(Family::DistortionError, 1.0)], "s").unwrap();
        assert_eq!(all.distortion.unwrap().k1, 0.0);
        let e = given_camera(
            &Camera::tum_fr3(),
            &[member(Family::DistortionError, 0.5)],
            "fr3",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("distortion-error") && e.contains("fr3"), "{e}");
    }
}
