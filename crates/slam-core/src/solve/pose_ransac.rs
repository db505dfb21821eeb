//! Seeded RANSAC for the camera pose from map point -> keypoint correspondences (the role of
//! ORB-SLAM2's PnPsolver in relocalization). Deviation, on purpose: ORB-SLAM2 draws 4
//! correspondences and solves EPnP; our frames are RGB-D or stereo, so a keypoint usually has a
//! measured depth and we draw 3 correspondences with depth and solve the rigid absolute
//! orientation (Horn) between the map points and the back-projected keypoints. Hypotheses are
//! scored as ORB-SLAM2 scores them, by 2-D reprojection error against `chi2_threshold * sigma^2`
//! on every correspondence (with or without depth), and the best one is refined on its inliers.

use nalgebra::{Isometry3, Point3, Vector3};
use rand::Rng;

use super::absolute_orientation;
use crate::camera::Camera;

/// One correspondence: a world point and the keypoint that matched it.
#[derive(Clone, Copy, Debug)]
pub struct PoseCorrespondence {
    /// Map point position, world frame, metres.
    pub point_world: Vector3<f64>,
    /// Keypoint column (undistorted), pixels.
    pub u: f64,
    /// Keypoint row (undistorted), pixels.
    pub v: f64,
    /// Keypoint back-projected with its measured depth (camera frame), when it has one.
    pub point_camera: Option<Vector3<f64>>,
    /// Measurement variance of the keypoint's octave, pixels^2.
    pub sigma2: f64,
}

/// RANSAC settings (ORB-SLAM2's relocalization values: probability 0.99, 10 minimum inliers,
/// 300 maximum iterations, expected inlier ratio 0.5, chi2 5.991).
#[derive(Clone, Copy, Debug)]
pub struct PoseRansacParams {
    /// Confidence that one all-inlier sample is drawn.
    pub probability: f64,
    /// Minimum inliers of an accepted pose.
    pub min_inliers: usize,
    /// Upper bound on the iterations.
    pub max_iterations: usize,
    /// Expected inlier ratio (ORB-SLAM2's epsilon), also a floor: at least `epsilon * N` inliers.
    pub epsilon: f64,
    /// Reprojection gate, chi2 with 2 dof at 95 %.
    pub chi2_threshold: f64,
}

impl Default for PoseRansacParams {
    fn default() -> Self {
        PoseRansacParams {
            probability: 0.99,
            min_inliers: 10,
            max_iterations: 300,
            epsilon: 0.5,
            chi2_threshold: 5.991,
        }
    }
}

/// The accepted pose and its inliers.
#[derive(Clone, Debug)]
pub struct PoseRansacResult {
    /// Camera pose, world -> camera.
    pub tcw: Isometry3<f64>,
    /// Inlier flag per correspondence.
    pub inliers: Vec<bool>,
    /// Number of inliers.
    pub n_inliers: usize,
}

fn score(
    tcw: &Isometry3<f64>,
    corr: &[PoseCorrespondence],
    camera: &Camera,
    chi2: f64,
    inliers: &mut [bool],
) -> usize {
    let mut n = 0;
    for (c, flag) in corr.iter().zip(inliers.iter_mut()) {
        let pc = tcw.transform_point(&Point3::from(c.point_world));
        *flag = false;
        if pc.z <= 0.0 {
            continue;
        }
        let uv = camera.project(&pc.coords);
        let e2 = (uv.x - c.u).powi(2) + (uv.y - c.v).powi(2);
        if e2 < chi2 * c.sigma2 {
            *flag = true;
            n += 1;
        }
    }
    n
}

fn fit(corr: &[PoseCorrespondence], select: impl Iterator<Item = usize>) -> Option<Isometry3<f64>> {
    let (mut from, mut to) = (Vec::new(), Vec::new());
    for i in select {
        if let Some(pc) = corr[i].point_camera {
            from.push(corr[i].point_world);
            to.push(pc);
        }
    }
    absolute_orientation(&from, &to)
}

/// Runs RANSAC; `None` when no hypothesis reaches `max(min_inliers, epsilon * N)` inliers.
pub fn pose_ransac<R: Rng>(
    corr: &[PoseCorrespondence],
    camera: &Camera,
    params: &PoseRansacParams,
    rng: &mut R,
) -> Option<PoseRansacResult> {
    let with_depth: Vec<usize> = (0..corr.len())
        .filter(|&i| corr[i].point_camera.is_some())
        .collect();
    let needed = params
        .min_inliers
        .max((params.epsilon * corr.len() as f64).floor() as usize);
    if with_depth.len() < 3 || corr.len() < needed {
        return None;
    }
    const SAMPLE: usize = 3;
    let iterations = {
        let p_good = params.epsilon.powi(SAMPLE as i32);
        let k = ((1.0 - params.probability).ln() / (1.0 - p_good).ln()).ceil();
        if k.is_finite() && k > 0.0 {
            (k as usize).clamp(1, params.max_iterations)
        } else {
            params.max_iterations
        }
    };
    let mut best: Option<(usize, Isometry3<f64>)> = None;
    let mut flags = vec![false; corr.len()];
    for _ in 0..iterations {
        let sample = rand::seq::index::sample(rng, with_depth.len(), SAMPLE);
        let Some(t) = fit(corr, sample.iter().map(|s| with_depth[s])) else {
            continue;
        };
        let n = score(&t, corr, camera, params.chi2_threshold, &mut flags);
        if best.is_none_or(|(b, _)| n > b) {
            best = Some((n, t));
        }
    }
    let (n_best, mut tcw) = best?;
    if n_best < needed {
        return None;
    }
    // Refine on the inliers (twice: the inlier set may grow).
    for _ in 0..2 {
        score(&tcw, corr, camera, params.chi2_threshold, &mut flags);
        if let Some(t) = fit(corr, (0..corr.len()).filter(|&i| flags[i])) {
            let mut f2 = vec![false; corr.len()];
            if score(&t, corr, camera, params.chi2_threshold, &mut f2)
                >= score(&tcw, corr, camera, params.chi2_threshold, &mut flags)
            {
                tcw = t;
            }
        }
    }
    let n_inliers = score(&tcw, corr, camera, params.chi2_threshold, &mut flags);
    (n_inliers >= needed).then_some(PoseRansacResult {
        tcw,
        inliers: flags,
        n_inliers,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn finds_pose_with_forty_percent_outliers_deterministically() {
        let camera = Camera::tum_fr3();
        let truth = Isometry3::from_parts(
            Translation3::new(0.1, -0.2, 0.3),
            UnitQuaternion::from_euler_angles(0.1, 0.2, -0.05),
        );
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut corr = Vec::new();
        for i in 0..100 {
            let pc = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-0.8..0.8),
                rng.random_range(1.0..4.0),
            );
            let pw = truth.inverse_transform_point(&Point3::from(pc)).coords;
            let uv = camera.project(&pc);
            let mut c = PoseCorrespondence {
                point_world: pw,
                u: uv.x,
                v: uv.y,
                point_camera: Some(pc),
                sigma2: 1.0,
            };
            if i % 5 < 2 {
                c.u += rng.random_range(20.0..80.0);
                c.point_camera = Some(pc + Vector3::new(0.3, 0.0, 0.0));
            }
            corr.push(c);
        }
        let params = PoseRansacParams::default();
        let run = |seed| {
            let mut r = ChaCha8Rng::seed_from_u64(seed);
            pose_ransac(&corr, &camera, &params, &mut r).unwrap()
        };
        let a = run(1);
        assert_eq!(a.n_inliers, 60);
        assert!((a.tcw.translation.vector - truth.translation.vector).norm() < 1e-6);
        let b = run(1);
        assert_eq!(a.tcw, b.tcw);
    }
}
