//! A frame as tracking sees it: ORB keypoints (raw and undistorted), descriptors, and per
//! keypoint a depth and a right-image coordinate — measured by the depth sensor (RGB-D, with
//! the virtual right coordinate `uR = u - bf / d`) or by stereo matching — plus a cell grid
//! for "keypoints near this pixel" queries.

pub mod grid;
pub mod stereo;

use std::sync::Arc;

use nalgebra::Vector3;

pub use grid::{CellGrid, ImageBounds, FRAME_GRID_COLS, FRAME_GRID_ROWS};
pub use stereo::{compute_stereo_matches, StereoInput, StereoParams};

use crate::camera::{Camera, SensorKind};
use crate::data::Features;
use crate::feature::{Descriptor, KeyPoint, OrbExtractor, ScaleInfo};
use crate::image::{DepthImage, FrameInput};

/// One frame: keypoints, descriptors, per-keypoint depth and right coordinate, the pyramid's
/// scale tables and a cell grid. All per-keypoint vectors have the same length and order.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Frame id, given by the caller (the tracker counts frames).
    pub id: u64,
    /// Capture time in seconds.
    pub timestamp: f64,
    /// Keypoints as detected on the raw (distorted) image.
    pub keypoints_raw: Vec<KeyPoint>,
    /// Keypoints with the lens distortion removed; what projections are compared with.
    pub keypoints: Vec<KeyPoint>,
    /// ORB descriptor of each keypoint.
    pub descriptors: Vec<Descriptor>,
    /// Depth of each keypoint in metres; <= 0 when unknown (no depth reading, no stereo match).
    pub depth: Vec<f32>,
    /// Right-image x coordinate of each keypoint (stereo match, or `u - bf / depth` for RGB-D)
    /// in pixels; < 0 when unknown. Like ORB-SLAM2, an RGB-D point so close to the left border
    /// that `u - bf / depth` goes negative is treated as unknown here but keeps its depth.
    pub u_right: Vec<f32>,
    /// Scale tables of the pyramid the keypoints come from.
    pub scale: Arc<ScaleInfo>,
    bounds: ImageBounds,
    grid: CellGrid,
}

/// The features tracking works on, extracted from one frame's images: the first step of
/// [`crate::system::System::track`]. They depend only on the images, the camera and the ORB
/// settings (not on the configuration of MC-OR or AVC, the seed or the mapping lag), so a sweep
/// extracts them once per frame and shares them read-only between its runs.
pub fn extract_features(
    input: &FrameInput,
    camera: &Camera,
    extractor: &mut OrbExtractor,
) -> Features {
    let frame = Frame::new(0, input, camera, extractor);
    Features::new(
        frame.keypoints,
        frame.descriptors,
        frame.depth,
        frame.u_right,
        camera,
    )
}

/// A frame's features with its depth measured from `depth` instead of the image it was
/// extracted with: `frame` extracted without depth (RGB-D), then any number of depth images
/// attached, each giving the same bits as [`extract_features`] on the frame with that depth.
/// A sweep over depth-only perturbations extracts ORB once and attaches each level's depth.
/// Stereo frames (and `depth = None`) keep the depth the frame has.
pub fn features_with_depth(frame: &Frame, depth: Option<&DepthImage>, camera: &Camera) -> Features {
    let mut f = Frame {
        id: frame.id,
        timestamp: frame.timestamp,
        keypoints_raw: frame.keypoints_raw.clone(),
        keypoints: frame.keypoints.clone(),
        descriptors: frame.descriptors.clone(),
        depth: frame.depth.clone(),
        u_right: frame.u_right.clone(),
        scale: frame.scale.clone(),
        bounds: frame.bounds,
        grid: CellGrid::default(),
    };
    if camera.sensor == SensorKind::Rgbd {
        if let Some(d) = depth {
            f.assign_rgbd_depth(d, camera.bf);
        }
    }
    Features::new(f.keypoints, f.descriptors, f.depth, f.u_right, camera)
}

impl Frame {
    /// Extracts features from `input` and measures their depth as `camera.sensor` says:
    /// RGB-D reads `input.depth` at each raw keypoint, stereo matches against `input.right`.
    /// A missing depth or right image leaves every depth unknown (a monocular frame) rather
    /// than failing.
    pub fn new(
        id: u64,
        input: &FrameInput,
        camera: &Camera,
        extractor: &mut OrbExtractor,
    ) -> Frame {
        Self::with_stereo_params(id, input, camera, extractor, &StereoParams::default())
    }

    /// As [`Frame::new`] with explicit stereo matching parameters.
    pub fn with_stereo_params(
        id: u64,
        input: &FrameInput,
        camera: &Camera,
        extractor: &mut OrbExtractor,
        stereo: &StereoParams,
    ) -> Frame {
        let (keypoints_raw, descriptors, depth, u_right) = match (camera.sensor, &input.right) {
            (SensorKind::Stereo, Some(right)) => {
                let f = extractor.extract_pair(&input.image, right);
                let (lp, rp) = extractor.pair_pyramids();
                let si = StereoInput {
                    left: &f.left_keypoints,
                    left_desc: &f.left_descriptors,
                    right: &f.right_keypoints,
                    right_desc: &f.right_descriptors,
                    left_pyr: lp,
                    right_pyr: rp,
                    scale: extractor.scale_info(),
                };
                let (u_right, depth) = compute_stereo_matches(&si, camera.bf, camera.fx, stereo);
                (f.left_keypoints, f.left_descriptors, depth, u_right)
            }
            _ => {
                let (kps, desc) = extractor.extract(&input.image);
                let n = kps.len();
                (kps, desc, vec![-1.0; n], vec![-1.0; n])
            }
        };
        let keypoints = undistort_keypoints(&keypoints_raw, camera);
        let mut frame = Frame {
            id,
            timestamp: input.timestamp,
            keypoints_raw,
            keypoints,
            descriptors,
            depth,
            u_right,
            scale: extractor.scale_info_arc(),
            bounds: image_bounds(camera),
            grid: CellGrid::default(),
        };
        if camera.sensor == SensorKind::Rgbd {
            if let Some(d) = &input.depth {
                frame.assign_rgbd_depth(d, camera.bf);
            }
        }
        frame.grid = CellGrid::new(&frame.keypoints, frame.bounds);
        frame
    }

    /// Builds a frame from already extracted keypoints (raw) and descriptors with the given
    /// per-keypoint depth and right coordinates; for tests and for tools that bring their own
    /// features. Vectors must have equal lengths.
    #[allow(clippy::too_many_arguments)]
    pub fn from_parts(
        id: u64,
        timestamp: f64,
        keypoints_raw: Vec<KeyPoint>,
        descriptors: Vec<Descriptor>,
        depth: Vec<f32>,
        u_right: Vec<f32>,
        scale: Arc<ScaleInfo>,
        camera: &Camera,
    ) -> Frame {
        assert!(
            keypoints_raw.len() == descriptors.len()
                && depth.len() == descriptors.len()
                && u_right.len() == descriptors.len(),
            "per-keypoint vectors must have equal lengths"
        );
        let keypoints = undistort_keypoints(&keypoints_raw, camera);
        let bounds = image_bounds(camera);
        let grid = CellGrid::new(&keypoints, bounds);
        Frame {
            id,
            timestamp,
            keypoints_raw,
            keypoints,
            descriptors,
            depth,
            u_right,
            scale,
            bounds,
            grid,
        }
    }

    /// RGB-D: depth read at the raw keypoint position (nearest pixel; ORB-SLAM2 truncates),
    /// `uR = u_undistorted - bf / d`. Pixels without a valid reading (0, negative, non-finite
    /// or outside the depth image) leave the keypoint without depth.
    fn assign_rgbd_depth(&mut self, depth: &DepthImage, bf: f64) {
        for (i, kp) in self.keypoints_raw.iter().enumerate() {
            let (u, v) = (kp.x.round(), kp.y.round());
            if u < 0.0 || v < 0.0 || u as usize >= depth.width || v as usize >= depth.height {
                continue;
            }
            if let Some(d) = depth.get(u as usize, v as usize) {
                self.depth[i] = d;
                self.u_right[i] = (self.keypoints[i].x as f64 - bf / d as f64) as f32;
            }
        }
    }

    /// Number of keypoints.
    pub fn len(&self) -> usize {
        self.keypoints.len()
    }

    /// Whether the frame has no keypoints.
    pub fn is_empty(&self) -> bool {
        self.keypoints.is_empty()
    }

    /// Indices of the (undistorted) keypoints within the square window |dx| < r, |dy| < r
    /// around (x, y) with octave in `[min_level, max_level]`; a negative bound means no bound
    /// (ORB-SLAM2 `GetFeaturesInArea`). Deterministic order (by grid cell, then index).
    pub fn features_in_area(
        &self,
        x: f64,
        y: f64,
        r: f64,
        min_level: i32,
        max_level: i32,
    ) -> Vec<usize> {
        self.grid
            .query(&self.keypoints, x, y, r, min_level, max_level)
    }

    /// Keypoint `i` back-projected into camera coordinates (metres) with its depth, or `None`
    /// when it has no depth.
    pub fn unproject(&self, i: usize, camera: &Camera) -> Option<Vector3<f64>> {
        let z = *self.depth.get(i)?;
        if !(z > 0.0 && z.is_finite()) {
            return None;
        }
        let kp = &self.keypoints[i];
        Some(camera.unproject(kp.x as f64, kp.y as f64, z as f64))
    }

    /// Whether an undistorted pixel lies inside the undistorted image bounds.
    pub fn is_in_image_bounds(&self, u: f64, v: f64) -> bool {
        self.bounds.contains(u, v)
    }

    /// The undistorted image bounds.
    pub fn bounds(&self) -> ImageBounds {
        self.bounds
    }

    /// Number of keypoints with a valid depth.
    pub fn n_with_depth(&self) -> usize {
        self.depth.iter().filter(|&&d| d > 0.0).count()
    }
}

/// Removes the lens distortion from every keypoint (copies when the camera has none).
pub fn undistort_keypoints(raw: &[KeyPoint], camera: &Camera) -> Vec<KeyPoint> {
    if camera.distortion.is_none() {
        return raw.to_vec();
    }
    raw.iter()
        .map(|kp| {
            let (u, v) = camera.undistort_point(kp.x as f64, kp.y as f64);
            KeyPoint {
                x: u as f32,
                y: v as f32,
                ..*kp
            }
        })
        .collect()
}

/// The undistorted image bounds of `camera` (see [`ImageBounds`]).
pub fn image_bounds(camera: &Camera) -> ImageBounds {
    let (w, h) = (camera.width as f64, camera.height as f64);
    if camera.distortion.is_none() {
        return ImageBounds {
            min_x: 0.0,
            max_x: w,
            min_y: 0.0,
            max_y: h,
        };
    }
    let ul = camera.undistort_point(0.0, 0.0);
    let ur = camera.undistort_point(w, 0.0);
    let bl = camera.undistort_point(0.0, h);
    let br = camera.undistort_point(w, h);
    ImageBounds {
        min_x: ul.0.min(bl.0),
        max_x: ur.0.max(br.0),
        min_y: ul.1.min(ur.1),
        max_y: bl.1.max(br.1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Distortion;
    use crate::feature::test_scene::test_frame;
    use crate::feature::OrbConfig;
    use crate::image::DepthImage;

    fn rgbd_input(depth_of: impl Fn(usize, usize) -> f32) -> FrameInput {
        let img = test_frame(4);
        let mut depth = DepthImage::new(img.width, img.height);
        for y in 0..img.height {
            for x in 0..img.width {
                depth.data[y * img.width + x] = depth_of(x, y);
            }
        }
        FrameInput {
            timestamp: 0.25,
            image: Arc::new(img),
            depth: Some(Arc::new(depth)),
            right: None,
            colour: None,
        }
    }

    #[test]
    fn rgbd_depth_and_virtual_right_coordinate() {
        // Depth 1 + x / 640 m on the left half, holes (0) on the right half.
        let input = rgbd_input(|x, _| if x < 320 { 1.0 + x as f32 / 640.0 } else { 0.0 });
        let cam = Camera::tum_fr3();
        let mut ex = OrbExtractor::new(OrbConfig::default());
        let f = Frame::new(7, &input, &cam, &mut ex);
        assert!(f.len() > 900);
        assert_eq!(f.len(), f.descriptors.len());
        let mut with = 0;
        for i in 0..f.len() {
            let kp = f.keypoints[i];
            let px = kp.x.round() as usize;
            if px < 320 {
                let d = 1.0 + px as f32 / 640.0;
                assert_eq!(f.depth[i], d);
                let ur = kp.x - 40.0 / d;
                assert!((f.u_right[i] - ur).abs() < 1e-4);
                let p = f.unproject(i, &cam).expect("has depth");
                assert!((p.z - d as f64).abs() < 1e-6);
                let uv = cam.project(&p);
                assert!((uv.x - kp.x as f64).abs() < 1e-3 && (uv.y - kp.y as f64).abs() < 1e-3);
                with += 1;
            } else {
                assert!(f.depth[i] <= 0.0 && f.u_right[i] < 0.0);
                assert!(f.unproject(i, &cam).is_none());
            }
        }
        assert_eq!(with, f.n_with_depth());
        assert!(with > 300);
    }

    #[test]
    fn missing_depth_gives_a_monocular_frame() {
        let mut input = rgbd_input(|_, _| 2.0);
        input.depth = None;
        let f = Frame::new(
            0,
            &input,
            &Camera::tum_fr3(),
            &mut OrbExtractor::new(OrbConfig::default()),
        );
        assert!(!f.is_empty());
        assert_eq!(f.n_with_depth(), 0);
        assert!(f.u_right.iter().all(|&u| u < 0.0));
    }

    #[test]
    fn features_in_area_equals_brute_force() {
        let input = rgbd_input(|_, _| 2.0);
        let cam = Camera::tum_fr3();
        let f = Frame::new(
            0,
            &input,
            &cam,
            &mut OrbExtractor::new(OrbConfig::default()),
        );
        let queries = [
            (100.0, 100.0, 20.0, -1, -1),
            (320.0, 240.0, 50.0, 1, 3),
            (600.0, 30.0, 35.0, 0, -1),
            (5.0, 470.0, 60.0, -1, 2),
            (-30.0, 240.0, 40.0, -1, -1),
            (700.0, 240.0, 10.0, -1, -1),
        ];
        let mut total = 0;
        for (x, y, r, lo, hi) in queries {
            let mut got = f.features_in_area(x, y, r, lo, hi);
            let want: Vec<usize> = (0..f.len())
                .filter(|&i| {
                    let k = f.keypoints[i];
                    (k.x as f64 - x).abs() < r
                        && (k.y as f64 - y).abs() < r
                        && (lo < 0 || k.octave as i32 >= lo)
                        && (hi < 0 || k.octave as i32 <= hi)
                })
                .collect();
            got.sort_unstable();
            assert_eq!(got, want, "query {x} {y} {r} {lo} {hi}");
            total += want.len();
        }
        assert!(total > 20);
        assert!(f.is_in_image_bounds(0.0, 0.0) && f.is_in_image_bounds(639.9, 479.9));
        assert!(!f.is_in_image_bounds(640.0, 10.0) && !f.is_in_image_bounds(10.0, -0.1));
    }

    #[test]
    fn distorted_keypoints_are_undistorted() {
        let mut cam = Camera::tum_fr3();
        cam.distortion = Some(Distortion {
            k1: 0.262383,
            k2: -0.953104,
            p1: -0.005358,
            p2: 0.002628,
            k3: 1.163314,
        });
        let input = rgbd_input(|_, _| 1.5);
        let f = Frame::new(
            0,
            &input,
            &cam,
            &mut OrbExtractor::new(OrbConfig::default()),
        );
        let mut moved = 0;
        for (raw, un) in f.keypoints_raw.iter().zip(&f.keypoints) {
            let (u, v) = cam.undistort_point(raw.x as f64, raw.y as f64);
            assert!((u - un.x as f64).abs() < 1e-3 && (v - un.y as f64).abs() < 1e-3);
            assert_eq!((raw.octave, raw.angle), (un.octave, un.angle));
            moved += ((un.x - raw.x).abs() > 1.0) as usize;
        }
        assert!(moved > 100);
        // The bounds follow the undistorted image corners.
        let b = f.bounds();
        let ul = cam.undistort_point(0.0, 0.0);
        let br = cam.undistort_point(640.0, 480.0);
        assert!((b.min_x - ul.0.min(cam.undistort_point(0.0, 480.0).0)).abs() < 1e-9);
        assert!((b.max_y - br.1.max(cam.undistort_point(0.0, 480.0).1)).abs() < 1e-9);
        assert!(b.min_x.abs() > 1.0 && (b.max_x - 640.0).abs() > 1.0);
        // Depth comes from the raw position, uR from the undistorted one.
        for i in 0..f.len() {
            assert!((f.u_right[i] - (f.keypoints[i].x - 40.0 / 1.5)).abs() < 1e-3);
        }
    }
}

/// Golden output dump used to prove that speed work leaves the extractor and the frames bit
/// for bit unchanged. Run before and after a change and diff the two files:
/// `ORB_GOLDEN_OUT=/tmp/a.txt cargo test -p slam-core golden_dump -- --ignored`.
#[cfg(test)]
mod golden {
    use std::fmt::Write as _;
    use std::sync::Arc;

    use super::*;
    use crate::feature::fast::tests::random_image;
    use crate::feature::test_scene::{test_frame, TestScene};
    use crate::feature::OrbConfig;
    use crate::image::GrayImage;

    fn dump_features(out: &mut String, kps: &[KeyPoint], desc: &[Descriptor]) {
        for (k, d) in kps.iter().zip(desc) {
            writeln!(
                out,
                "{:08x} {:08x} {} {:08x} {} {:016x}{:016x}{:016x}{:016x}",
                k.x.to_bits(),
                k.y.to_bits(),
                k.octave,
                k.angle.to_bits(),
                k.response,
                d[0],
                d[1],
                d[2],
                d[3]
            )
            .expect("string write");
        }
    }

    #[test]
    #[ignore = "writes a dump for manual before/after comparison"]
    fn golden_dump() {
        let Ok(path) = std::env::var("ORB_GOLDEN_OUT") else {
            return;
        };
        let mut out = String::new();
        let mut images: Vec<(String, GrayImage)> = Vec::new();
        for s in 0..6 {
            images.push((format!("test_frame {s}"), test_frame(s)));
        }
        for s in 0..3 {
            images.push((format!("random 640 {s}"), random_image(640, 480, 100 + s)));
            images.push((format!("random odd {s}"), random_image(333, 211, 200 + s)));
            images.push((format!("random wide {s}"), random_image(1403, 257, 400 + s)));
        }
        for s in 0..3 {
            let scene = TestScene::random(640.0, 480.0, 60 + 100 * s as usize, 300 + s);
            images.push((format!("scene {s}"), scene.render(640, 480, |u, v| (u, v))));
        }
        // Low contrast: most cells need the low threshold.
        let mut dim = test_frame(9);
        for v in dim.data.iter_mut() {
            *v = 100 + *v / 10;
        }
        images.push(("dim".into(), dim));
        images.push(("flat".into(), GrayImage::new(200, 150)));
        for (name, img) in &images {
            for cfg in [OrbConfig::default(), OrbConfig::stereo()] {
                let (kps, desc) = OrbExtractor::new(cfg.clone()).extract(img);
                writeln!(out, "# {name} n={} {}", kps.len(), cfg.n_features).expect("write");
                dump_features(&mut out, &kps, &desc);
            }
        }
        for s in 0..2 {
            let scene = TestScene::random(752.0, 480.0, 450, 3 + s);
            let left = scene.render(752, 480, |u, v| (u, v));
            let right = scene.render(752, 480, |u, v| (u + 20.0 + 0.03 * v, v));
            let input = FrameInput {
                timestamp: 0.0,
                image: Arc::new(left),
                depth: None,
                right: Some(Arc::new(right)),
                colour: None,
            };
            let cam = Camera::euroc_rectified();
            let mut ex = OrbExtractor::new(OrbConfig::stereo());
            let f = Frame::new(0, &input, &cam, &mut ex);
            writeln!(out, "# stereo {s} n={}", f.len()).expect("write");
            dump_features(&mut out, &f.keypoints, &f.descriptors);
            for (d, u) in f.depth.iter().zip(&f.u_right) {
                writeln!(out, "{:08x} {:08x}", d.to_bits(), u.to_bits()).expect("write");
            }
        }
        std::fs::write(path, out).expect("write golden dump");
    }
}
