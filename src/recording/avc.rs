//! AVC's virtual camera for a few of a frame's matches: where the adaptive virtual camera
//! (paper III-B, Eq. 8-11) stood when the frame's pose was final, so a recording shows the
//! second view AVC adds to each keypoint with depth.

use slam_core::data::TrackedFrame;
use slam_core::module::pose_estimation::PoseOptRecord;
use slam_core::techniques::virtual_camera_direction;
use slam_core::Camera;

use nalgebra::{Point3, Vector3};

/// How many matches of a frame a recording shows the virtual camera of: enough to see how the
/// cameras turn with the error's direction, few enough to read.
pub const SAMPLES_PER_FRAME: usize = 8;

/// One sampled match's virtual camera, in the frame's camera coordinates (metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VirtualCameraSample {
    /// The keypoint.
    pub keypoint: usize,
    /// C': the virtual camera's centre, b from the real camera's centre in its image plane,
    /// towards the map point's offset from the measured point (Eq. 10, 11).
    pub centre: Vector3<f64>,
    /// D: the keypoint back-projected with its measured depth.
    pub measured: Vector3<f64>,
    /// M: the matched map point at the frame's final pose.
    pub map_point: Vector3<f64>,
}

/// The virtual cameras of up to [`SAMPLES_PER_FRAME`] inlier matches with depth of the frame's
/// final pose optimization `last`, spread evenly over its matches, for virtual baseline
/// `baseline` (metres): each placed as the residual places it when aimed from the final pose
/// (the residual may be aimed once more in bundle adjustment; this is tracking's).
pub fn sample_virtual_cameras(
    frame: &TrackedFrame,
    last: &PoseOptRecord,
    camera: &Camera,
    baseline: f64,
) -> Vec<VirtualCameraSample> {
    let candidates: Vec<_> = last
        .matches
        .iter()
        .filter(|m| m.inlier)
        .filter_map(|m| {
            let measured = frame.features.unproject_camera(m.keypoint, camera)?;
            Some((m, measured))
        })
        .collect();
    let step = candidates.len().div_ceil(SAMPLES_PER_FRAME).max(1);
    candidates
        .iter()
        .step_by(step)
        .map(|(m, measured)| {
            let map_point = (last.tcw * Point3::from(m.point_world)).coords;
            let u = virtual_camera_direction(measured, &map_point);
            VirtualCameraSample {
                keypoint: m.keypoint,
                centre: Vector3::new(baseline * u.x, baseline * u.y, 0.0),
                measured: *measured,
                map_point,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runner::run_observed;
    use crate::select::{load, LoadOptions, Source};
    use datasets::Catalog;
    use slam_core::system::{AvcParams, Config};

    /// On the walking preset under AVC, every sampled virtual camera is b from the real camera's
    /// centre in its image plane, turned towards M's offset from D, and a frame shows at most
    /// the samples it allows.
    #[test]
    fn virtual_cameras_sit_b_away_in_the_image_plane_towards_the_error() {
        let seq = load(
            &Source::Catalog("walking".into()),
            &Catalog::embedded(),
            &LoadOptions::for_tests(20),
        )
        .expect("a preset");
        let avc = AvcParams::default();
        let b = avc.baseline;
        let config = Config {
            avc: Some(avc),
            ..Config::default()
        };
        let mut sampled = 0;
        run_observed(
            &seq,
            None,
            &config,
            None,
            |_| {},
            |o| {
                let (Some(frame), Some(last)) = (o.system.last_frame(), o.final_optimization())
                else {
                    return;
                };
                let samples = sample_virtual_cameras(frame, last, o.system.camera(), b);
                assert!(samples.len() <= SAMPLES_PER_FRAME);
                for s in &samples {
                    assert!((s.centre.norm() - b).abs() < 1e-12, "{:?}", s.centre);
                    assert_eq!(s.centre.z, 0.0);
                    // D' = |D| unit(M); the camera turns towards the in-plane part of D'- D.
                    let d_prime = s.map_point.normalize() * s.measured.norm();
                    let offset = (d_prime - s.measured).xy();
                    if offset.norm() > 1e-6 {
                        assert!(s.centre.xy().dot(&offset) > 0.0, "{s:?}");
                    }
                    sampled += 1;
                }
            },
        );
        assert!(sampled > 50, "{sampled} samples over 20 frames");
    }
}
