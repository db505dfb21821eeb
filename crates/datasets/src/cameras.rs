//! The cameras of the datasets: TUM RGB-D's three Kinects (freiburg 1, 2, 3) with the values
//! published on the TUM site and used in ORB-SLAM2's TUM1/2/3.yaml, and the depth-map factors
//! that turn their 16-bit depth PNGs into metres.

use serde::{Deserialize, Serialize};
use slam_core::Camera;

/// Which camera a catalogued sequence uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CameraId {
    /// TUM freiburg1 Kinect (radial-tangential distortion).
    Fr1,
    /// TUM freiburg2 Kinect (radial-tangential distortion, depth factor 5208 in ORB-SLAM2).
    Fr2,
    /// TUM freiburg3 Asus Xtion (factory-undistorted images).
    Fr3,
    /// EuRoC VI-sensor stereo pair; the camera comes from rectifying its `sensor.yaml` files.
    Euroc,
    /// A synthetic preset; the camera comes from the generator.
    Synthetic,
}

impl CameraId {
    /// The TUM camera for fr1/fr2/fr3; `None` for EuRoC and synthetic, whose cameras come
    /// from the data.
    pub fn tum_camera(self) -> Option<Camera> {
        match self {
            CameraId::Fr1 => Some(tum_fr1()),
            CameraId::Fr2 => Some(tum_fr2()),
            CameraId::Fr3 => Some(Camera::tum_fr3()),
            CameraId::Euroc | CameraId::Synthetic => None,
        }
    }

    /// The depth-map factor (PNG value per metre) ORB-SLAM2 uses for this camera:
    /// 5208 for fr2 (its TUM2.yaml), 5000 otherwise (the TUM site says 5000 for all three).
    pub fn orbslam2_depth_factor(self) -> f64 {
        match self {
            CameraId::Fr2 => DEPTH_FACTOR_FR2_ORBSLAM2,
            _ => DEPTH_FACTOR_TUM,
        }
    }

    /// Detects fr1/fr2/fr3 from a TUM folder name such as `rgbd_dataset_freiburg1_xyz`
    /// (also accepts the short `fr1_xyz` spelling). `None` when the name says nothing.
    pub fn detect_tum(folder_name: &str) -> Option<CameraId> {
        let n = folder_name.to_ascii_lowercase();
        for (key, id) in [
            ("freiburg1", CameraId::Fr1),
            ("freiburg2", CameraId::Fr2),
            ("freiburg3", CameraId::Fr3),
        ] {
            if n.contains(key) {
                return Some(id);
            }
        }
        for (key, id) in [
            ("fr1", CameraId::Fr1),
            ("fr2", CameraId::Fr2),
            ("fr3", CameraId::Fr3),
        ] {
            if n.starts_with(key) {
                return Some(id);
            }
        }
        None
    }
}

/// Depth factor of the TUM RGB-D benchmark: a depth PNG value of 5000 is one metre.
pub const DEPTH_FACTOR_TUM: f64 = 5000.0;

/// Depth factor ORB-SLAM2's TUM2.yaml uses for freiburg2 (a calibration correction of the fr2
/// Kinect's depth scale); the TUM site itself says 5000. We default to ORB-SLAM2's value because
/// the paper's baseline is ORB-SLAM2; `TumOptions::depth_factor` overrides it.
pub const DEPTH_FACTOR_FR2_ORBSLAM2: f64 = 5208.0;

/// TUM fr1 (ORB-SLAM2 TUM1.yaml): 640x480, 30 Hz, bf 40, ThDepth 40, radial-tangential distortion.
pub fn tum_fr1() -> Camera {
    Camera::tum_fr1()
}

/// TUM fr2 (ORB-SLAM2 TUM2.yaml): 640x480, 30 Hz, bf 40, ThDepth 40, radial-tangential distortion.
pub fn tum_fr2() -> Camera {
    Camera::tum_fr2()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detects_freiburg_ids() {
        assert_eq!(
            CameraId::detect_tum("rgbd_dataset_freiburg1_xyz"),
            Some(CameraId::Fr1)
        );
        assert_eq!(
            CameraId::detect_tum("rgbd_dataset_freiburg2_coke"),
            Some(CameraId::Fr2)
        );
        assert_eq!(
            CameraId::detect_tum("rgbd_dataset_freiburg3_walking_rpy"),
            Some(CameraId::Fr3)
        );
        assert_eq!(CameraId::detect_tum("fr2_desk"), Some(CameraId::Fr2));
        assert_eq!(CameraId::detect_tum("my_room"), None);
    }

    #[test]
    fn depth_factors_follow_orbslam2() {
        assert_eq!(CameraId::Fr2.orbslam2_depth_factor(), 5208.0);
        assert_eq!(CameraId::Fr1.orbslam2_depth_factor(), 5000.0);
        assert_eq!(CameraId::Fr3.orbslam2_depth_factor(), 5000.0);
    }

    #[test]
    fn tum_cameras_match_orbslam2_settings() {
        let c1 = tum_fr1();
        assert_eq!((c1.fx, c1.cy), (517.306408, 255.313989));
        assert_eq!(c1.distortion.unwrap().k3, 1.163314);
        let c2 = tum_fr2();
        assert_eq!((c2.fy, c2.cx), (521.007327, 325.141442));
        assert_eq!(c2.distortion.unwrap().p2, -0.000105);
        for c in [c1, c2] {
            assert_eq!(
                (c.width, c.height, c.bf, c.th_depth, c.fps),
                (640, 480, 40.0, 40.0, 30.0)
            );
        }
        assert!(CameraId::Fr3.tum_camera().unwrap().distortion.is_none());
    }
}
