//! Pinhole camera with optional radial-tangential distortion, as the TUM and EuRoC settings
//! describe it. Shared by the dataset readers (which build it) and the SLAM system (which
//! projects with it); slam-core only ever sees undistorted (or rectified) geometry through it.

use nalgebra::{Vector2, Vector3};

/// Radial-tangential (Brown-Conrady / OpenCV "plumb_bob") distortion coefficients,
/// in the order TUM and ORB-SLAM2 publish them: k1, k2, p1, p2, k3.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Distortion {
    /// Radial coefficient of r^2.
    pub k1: f64,
    /// Radial coefficient of r^4.
    pub k2: f64,
    /// First tangential coefficient.
    pub p1: f64,
    /// Second tangential coefficient.
    pub p2: f64,
    /// Radial coefficient of r^6.
    pub k3: f64,
}

/// Which kind of sensor produces the frames: it decides how a keypoint gets its depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SensorKind {
    /// Registered colour + depth image (TUM RGB-D, synthetic RGB-D presets).
    Rgbd,
    /// Rectified stereo pair (EuRoC after rectification, synthetic `stereo` preset).
    Stereo,
}

/// Intrinsics, image size, distortion and the stereo / RGB-D settings ORB-SLAM2 keeps next to
/// them (`bf`, `ThDepth`). Units: pixels for intrinsics, metres * pixels for `bf`.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels.
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Lens distortion of the raw images; `None` when images are undistorted or rectified.
    pub distortion: Option<Distortion>,
    /// Stereo baseline times fx (metres * pixels). For RGB-D, a virtual baseline (TUM: 40).
    pub bf: f64,
    /// ORB-SLAM2's `ThDepth`: points closer than `th_depth * baseline` metres are "close".
    pub th_depth: f64,
    /// Frame rate of the sequence in Hz (ORB-SLAM2's keyframe `maxFrames`).
    pub fps: f64,
    /// How a frame's keypoints get depth.
    pub sensor: SensorKind,
}

impl Camera {
    /// The TUM fr3 RGB-D camera (undistorted, 640x480, bf 40, ThDepth 40, 30 Hz), which is also
    /// the default of the synthetic sequences.
    pub fn tum_fr3() -> Self {
        Camera {
            fx: 535.4,
            fy: 539.2,
            cx: 320.1,
            cy: 247.6,
            width: 640,
            height: 480,
            distortion: None,
            bf: 40.0,
            th_depth: 40.0,
            fps: 30.0,
            sensor: SensorKind::Rgbd,
        }
    }

    /// The TUM fr1 Kinect (ORB-SLAM2's TUM1.yaml): 640x480, 30 Hz, bf 40, ThDepth 40, with the
    /// radial-tangential distortion TUM calibrated for its colour camera.
    pub fn tum_fr1() -> Self {
        Camera {
            fx: 517.306408,
            fy: 516.469215,
            cx: 318.643040,
            cy: 255.313989,
            distortion: Some(Distortion {
                k1: 0.262383,
                k2: -0.953104,
                p1: -0.005358,
                p2: 0.002628,
                k3: 1.163314,
            }),
            ..Camera::tum_fr3()
        }
    }

    /// The TUM fr2 Kinect (ORB-SLAM2's TUM2.yaml): 640x480, 30 Hz, bf 40, ThDepth 40, with the
    /// radial-tangential distortion TUM calibrated for its colour camera.
    pub fn tum_fr2() -> Self {
        Camera {
            fx: 520.908620,
            fy: 521.007327,
            cx: 325.141442,
            cy: 249.701764,
            distortion: Some(Distortion {
                k1: 0.231222,
                k2: -0.784899,
                p1: -0.003257,
                p2: -0.000105,
                k3: 0.917205,
            }),
            ..Camera::tum_fr3()
        }
    }

    /// The rectified EuRoC stereo camera of ORB-SLAM2's EuRoC.yaml (752x480, bf 47.9, ThDepth
    /// 35, 20 Hz): the left camera after rectification, as the stereo benchmarks and tests use.
    pub fn euroc_rectified() -> Self {
        Camera {
            fx: 435.2,
            fy: 435.2,
            cx: 367.45,
            cy: 252.2,
            width: 752,
            height: 480,
            distortion: None,
            bf: 47.9,
            th_depth: 35.0,
            fps: 20.0,
            sensor: SensorKind::Stereo,
        }
    }

    /// Stereo baseline in metres (`bf / fx`).
    pub fn baseline(&self) -> f64 {
        self.bf / self.fx
    }

    /// Depth in metres below which a point counts as "close" (ORB-SLAM2: `bf * ThDepth / fx`).
    pub fn close_depth(&self) -> f64 {
        self.th_depth * self.bf / self.fx
    }

    /// Projects a point in camera coordinates to undistorted pixel coordinates.
    /// The caller checks `p.z > 0`.
    pub fn project(&self, p: &Vector3<f64>) -> Vector2<f64> {
        let inv_z = 1.0 / p.z;
        Vector2::new(
            self.fx * p.x * inv_z + self.cx,
            self.fy * p.y * inv_z + self.cy,
        )
    }

    /// Back-projects undistorted pixel (u, v) at depth `z` (metres) into camera coordinates.
    pub fn unproject(&self, u: f64, v: f64, z: f64) -> Vector3<f64> {
        Vector3::new((u - self.cx) * z / self.fx, (v - self.cy) * z / self.fy, z)
    }

    /// Whether an undistorted pixel lies inside the image bounds.
    pub fn in_image(&self, u: f64, v: f64) -> bool {
        u >= 0.0 && v >= 0.0 && u < self.width as f64 && v < self.height as f64
    }

    /// Applies the lens distortion to an ideal (undistorted) pixel, giving the raw pixel.
    /// Identity when the camera has no distortion.
    pub fn distort_point(&self, u: f64, v: f64) -> (f64, f64) {
        let Some(d) = self.distortion else {
            return (u, v);
        };
        let x = (u - self.cx) / self.fx;
        let y = (v - self.cy) / self.fy;
        let (xd, yd) = distort_normalized(&d, x, y);
        (xd * self.fx + self.cx, yd * self.fy + self.cy)
    }

    /// Removes the lens distortion from a raw pixel (iterative inversion, converged to well
    /// below 1e-6 px for the distortions of TUM fr1/fr2 and EuRoC). Identity without distortion.
    pub fn undistort_point(&self, u: f64, v: f64) -> (f64, f64) {
        let Some(d) = self.distortion else {
            return (u, v);
        };
        let xd = (u - self.cx) / self.fx;
        let yd = (v - self.cy) / self.fy;
        let (mut x, mut y) = (xd, yd);
        for _ in 0..20 {
            let (fx, fy) = distort_normalized(&d, x, y);
            let (ex, ey) = (fx - xd, fy - yd);
            x -= ex;
            y -= ey;
            if ex.abs() < 1e-12 && ey.abs() < 1e-12 {
                break;
            }
        }
        (x * self.fx + self.cx, y * self.fy + self.cy)
    }
}

/// Radial-tangential distortion of normalised image coordinates.
pub fn distort_normalized(d: &Distortion, x: f64, y: f64) -> (f64, f64) {
    let r2 = x * x + y * y;
    let radial = 1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
    let xd = x * radial + 2.0 * d.p1 * x * y + d.p2 * (r2 + 2.0 * x * x);
    let yd = y * radial + d.p1 * (r2 + 2.0 * y * y) + 2.0 * d.p2 * x * y;
    (xd, yd)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_unproject_round_trip() {
        let cam = Camera::tum_fr3();
        let p = Vector3::new(0.3, -0.2, 2.5);
        let uv = cam.project(&p);
        let q = cam.unproject(uv.x, uv.y, p.z);
        assert!((p - q).norm() < 1e-12);
    }

    #[test]
    fn undistort_inverts_distort_fr1() {
        let mut cam = Camera::tum_fr3();
        cam.distortion = Some(Distortion {
            k1: 0.262383,
            k2: -0.953104,
            p1: -0.005358,
            p2: 0.002628,
            k3: 1.163314,
        });
        for &(u, v) in &[(10.0, 10.0), (320.0, 240.0), (600.0, 50.0), (630.0, 470.0)] {
            let (ud, vd) = cam.distort_point(u, v);
            let (uu, vu) = cam.undistort_point(ud, vd);
            assert!(
                (uu - u).abs() < 1e-6 && (vu - v).abs() < 1e-6,
                "{u},{v} -> {uu},{vu}"
            );
        }
    }
}
