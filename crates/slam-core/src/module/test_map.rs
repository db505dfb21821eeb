//! A small map for the tests of the modules: three keyframes observing 120 points and the
//! current frame matched to all of them, with depth errors where a test needs them.

use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::camera::Camera;
use crate::data::{Features, Map, TrackedFrame};
use crate::feature::KeyPoint;

/// Camera-to-world pose of camera `k`: 10 cm steps along x, looking along +z.
pub(crate) fn twc(k: usize) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.1 * k as f64, 0.0, 0.0),
        UnitQuaternion::from_euler_angles(0.0, 0.02 * k as f64, 0.0),
    )
}

/// Features of `points` (world) seen from `twc`, with `depth_error(k)` metres added to the
/// depth of point `k` and `pixel_noise` px of uniform keypoint noise.
pub(crate) fn features(
    camera: &Camera,
    points: &[Vector3<f64>],
    twc: &Isometry3<f64>,
    depth_error: impl Fn(usize) -> f64,
    pixel_noise: f64,
    rng: &mut ChaCha8Rng,
) -> Arc<Features> {
    let (mut kps, mut depth, mut ur) = (Vec::new(), Vec::new(), Vec::new());
    for (k, pw) in points.iter().enumerate() {
        let p = twc.inverse_transform_point(&Point3::from(*pw)).coords;
        let uv = camera.project(&p);
        let (u, v) = (
            uv.x + rng.random_range(-pixel_noise..=pixel_noise),
            uv.y + rng.random_range(-pixel_noise..=pixel_noise),
        );
        let z = p.z + depth_error(k);
        kps.push(KeyPoint {
            x: u as f32,
            y: v as f32,
            octave: 0,
            angle: 0.0,
            response: 1.0,
        });
        depth.push(z as f32);
        ur.push((u - camera.bf / z) as f32);
    }
    let n = points.len();
    Arc::new(Features::new(
        kps,
        (0..n).map(|i| [i as u64, 0, 0, 0]).collect(),
        depth,
        ur,
        camera,
    ))
}

/// A map of 3 keyframes observing 120 points, and the current frame (camera 3) matched to
/// all of them; points `gross` have a depth reading 1.5 m too far in the current frame.
pub(crate) fn scene(gross: &[usize]) -> (Camera, Map, TrackedFrame, Vec<Vector3<f64>>) {
    let gross = gross.to_vec();
    scene_with(move |k| if gross.contains(&k) { 1.5 } else { 0.0 })
}

/// [`scene`] with `depth_error(k)` metres on the current frame's depth of point `k`.
pub(crate) fn scene_with(
    depth_error: impl Fn(usize) -> f64,
) -> (Camera, Map, TrackedFrame, Vec<Vector3<f64>>) {
    let camera = Camera::tum_fr3();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let points: Vec<Vector3<f64>> = (0..120)
        .map(|_| {
            let p = camera.unproject(
                rng.random_range(40.0..600.0),
                rng.random_range(40.0..440.0),
                rng.random_range(1.5..4.0),
            );
            twc(1) * p
        })
        .collect();
    let mut map = Map::new();
    let kfs: Vec<_> = (0..3)
        .map(|k| {
            let f = features(&camera, &points, &twc(k), |_| 0.0, 0.3, &mut rng);
            map.create_keyframe(k as u64, k as f64, twc(k).inverse(), f)
        })
        .collect();
    for (i, p) in points.iter().enumerate() {
        let mp = map.create_map_point(*p, [i as u64, 0, 0, 0], kfs[0]);
        for &kf in &kfs {
            map.add_observation(mp, kf, i);
        }
    }
    let f = features(&camera, &points, &twc(3), depth_error, 0.3, &mut rng);
    let mut frame = TrackedFrame::new(3, 3.0, f);
    for i in 0..points.len() {
        frame.map_points[i] = map.map_points().nth(i).map(|m| m.id);
    }
    (camera, map, frame, points)
}

/// `frame` with keypoints `moved` shifted `dx` pixels along the row, their depth as measured
/// and their right coordinate following: a reprojection error the chi2 test rejects with a
/// back-projection a few centimetres off at the scene's depths.
pub(crate) fn shifted(
    frame: &TrackedFrame,
    camera: &Camera,
    moved: &[usize],
    dx: f64,
) -> TrackedFrame {
    let mut f = (*frame.features).clone();
    for &k in moved {
        f.keypoints[k].x += dx as f32;
        f.u_right[k] = (f.keypoints[k].x as f64 - camera.bf / f.depth[k] as f64) as f32;
    }
    let mut out = TrackedFrame::new(frame.id, frame.timestamp, Arc::new(f));
    out.map_points = frame.map_points.clone();
    out
}
