//! Synthetic scenes for the optimizer tests: a seeded point cloud seen by a row of cameras,
//! noisy keypoint measurements with ORB-SLAM2's octave sigmas, and pose perturbations of a
//! given size.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::residual::Measurement;
use crate::geometry::exp_so3;
use crate::Camera;

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

/// `n` keyframe poses on a 1 m line along x, each looking roughly along +z with a small
/// seeded wobble, all facing the cloud of [`cloud`].
pub(crate) fn trajectory(n: usize, rng: &mut ChaCha8Rng) -> Vec<Isometry3<f64>> {
    (0..n)
        .map(|i| {
            let s = if n > 1 {
                i as f64 / (n - 1) as f64
            } else {
                0.5
            };
            let centre = Vector3::new(-0.5 + s, 0.05 * gaussian(rng), 0.1 * gaussian(rng));
            let rot = UnitQuaternion::from_euler_angles(
                0.03 * gaussian(rng),
                0.1 * (s - 0.5) + 0.03 * gaussian(rng),
                0.03 * gaussian(rng),
            );
            Isometry3::from_parts(Translation3::from(centre), rot).inverse()
        })
        .collect()
}

/// `n` points uniformly in the box x in [-2, 2], y in [-1.5, 1.5], z in [2, 6] metres.
pub(crate) fn cloud(n: usize, rng: &mut ChaCha8Rng) -> Vec<Vector3<f64>> {
    (0..n)
        .map(|_| {
            Vector3::new(
                rng.random_range(-2.0..2.0),
                rng.random_range(-1.5..1.5),
                rng.random_range(2.0..6.0),
            )
        })
        .collect()
}

/// A keypoint measurement of world point `pw` from `tcw` at `octave`, stereo / RGB-D or
/// monocular, with its information weight `1 / 1.2^(2 octave)`; Gaussian noise of standard
/// deviation `noise * 1.2^octave` pixels on u, v and uR (`noise` 0 gives exact measurements).
/// `None` when the point is behind the camera or outside the image.
pub(crate) fn observe(
    camera: &Camera,
    tcw: &Isometry3<f64>,
    pw: &Vector3<f64>,
    octave: i32,
    stereo: bool,
    noise: f64,
    rng: &mut ChaCha8Rng,
) -> Option<(Measurement, f64)> {
    let p = (tcw * Point3::from(*pw)).coords;
    if p.z <= 0.1 {
        return None;
    }
    let uv = camera.project(&p);
    if !camera.in_image(uv.x, uv.y) {
        return None;
    }
    let sigma = 1.2f64.powi(octave);
    let u = uv.x + noise * sigma * gaussian(rng);
    let v = uv.y + noise * sigma * gaussian(rng);
    let m = if stereo {
        let ur = uv.x - camera.bf / p.z + noise * sigma * gaussian(rng);
        Measurement::Stereo { u, v, ur }
    } else {
        Measurement::Mono { u, v }
    };
    Some((m, 1.0 / (sigma * sigma)))
}

/// A grossly wrong measurement (a mismatch): (u, v) 15 to 60 px away from the projection of
/// `pw` in a random direction and, for stereo, a random disparity.
pub(crate) fn gross_outlier(
    camera: &Camera,
    tcw: &Isometry3<f64>,
    pw: &Vector3<f64>,
    stereo: bool,
    rng: &mut ChaCha8Rng,
) -> Measurement {
    let p = (tcw * Point3::from(*pw)).coords;
    let uv = camera.project(&p);
    let angle = rng.random_range(0.0..std::f64::consts::TAU);
    let dist = rng.random_range(15.0..60.0);
    let u = uv.x + dist * angle.cos();
    let v = uv.y + dist * angle.sin();
    if stereo {
        Measurement::Stereo {
            u,
            v,
            ur: u - rng.random_range(5.0..40.0),
        }
    } else {
        Measurement::Mono { u, v }
    }
}
