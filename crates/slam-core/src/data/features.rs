//! The per-image feature set the map and the matchers work on: undistorted keypoints, their
//! descriptors, measured depth and (virtual) right coordinate, plus a cell grid for radius
//! queries (ORB-SLAM2: 64 x 48 cells over the undistorted image bounds). Shared between the
//! tracked frame and the keyframe made from it (`Arc`), never copied.

use crate::camera::Camera;
use crate::feature::{Descriptor, KeyPoint};

/// Grid columns (ORB-SLAM2: FRAME_GRID_COLS).
pub const GRID_COLS: usize = 64;
/// Grid rows (ORB-SLAM2: FRAME_GRID_ROWS).
pub const GRID_ROWS: usize = 48;

/// Keypoint indices bucketed by image cell, stored compactly (one index array and the start of
/// each cell in it: 16 KB for 1000 keypoints, where a vector per cell took 90 KB), because every
/// keyframe keeps its grid and a sweep keeps every frame's.
#[derive(Clone, Debug)]
pub struct FeatureGrid {
    min_x: f64,
    min_y: f64,
    inv_cell_w: f64,
    inv_cell_h: f64,
    /// Keypoints of cell `c` are `indices[cell_start[c]..cell_start[c + 1]]`, ascending.
    cell_start: Vec<u32>,
    indices: Vec<u32>,
}

impl FeatureGrid {
    /// Buckets `keypoints` over the undistorted bounds of `camera`'s image. Keypoints outside the
    /// bounds fall into the nearest border cell.
    pub fn new(keypoints: &[KeyPoint], camera: &Camera) -> Self {
        let (min_x, max_x, min_y, max_y) = undistorted_bounds(camera);
        let inv_cell_w = GRID_COLS as f64 / (max_x - min_x).max(1.0);
        let inv_cell_h = GRID_ROWS as f64 / (max_y - min_y).max(1.0);
        let mut grid = FeatureGrid {
            min_x,
            min_y,
            inv_cell_w,
            inv_cell_h,
            cell_start: Vec::new(),
            indices: Vec::new(),
        };
        let cell: Vec<usize> = keypoints
            .iter()
            .map(|kp| {
                let (cx, cy) = grid.cell_of(kp.x as f64, kp.y as f64);
                cy * GRID_COLS + cx
            })
            .collect();
        let mut start = vec![0u32; GRID_COLS * GRID_ROWS + 1];
        for &c in &cell {
            start[c + 1] += 1;
        }
        for c in 0..GRID_COLS * GRID_ROWS {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut indices = vec![0u32; keypoints.len()];
        for (i, &c) in cell.iter().enumerate() {
            indices[fill[c] as usize] = i as u32;
            fill[c] += 1;
        }
        grid.cell_start = start;
        grid.indices = indices;
        grid
    }

    /// Keypoints in cells `first..=last` (row-major), cell by cell, each cell's ascending.
    fn cells(&self, first: usize, last: usize) -> &[u32] {
        &self.indices[self.cell_start[first] as usize..self.cell_start[last + 1] as usize]
    }

    /// Heap bytes held by the grid.
    pub fn heap_bytes(&self) -> usize {
        4 * (self.cell_start.capacity() + self.indices.capacity())
    }

    fn cell_coord(&self, x: f64, y: f64) -> (i64, i64) {
        (
            ((x - self.min_x) * self.inv_cell_w).floor() as i64,
            ((y - self.min_y) * self.inv_cell_h).floor() as i64,
        )
    }

    fn cell_of(&self, x: f64, y: f64) -> (usize, usize) {
        let (cx, cy) = self.cell_coord(x, y);
        (
            cx.clamp(0, GRID_COLS as i64 - 1) as usize,
            cy.clamp(0, GRID_ROWS as i64 - 1) as usize,
        )
    }
}

/// Bounds (min_x, max_x, min_y, max_y) of the undistorted image: the image itself without
/// distortion, else the box around the undistorted corners (as ORB-SLAM2's ComputeImageBounds).
pub fn undistorted_bounds(camera: &Camera) -> (f64, f64, f64, f64) {
    let (w, h) = (camera.width as f64, camera.height as f64);
    if camera.distortion.is_none() {
        return (0.0, w, 0.0, h);
    }
    let c = [
        camera.undistort_point(0.0, 0.0),
        camera.undistort_point(w, 0.0),
        camera.undistort_point(0.0, h),
        camera.undistort_point(w, h),
    ];
    (
        c[0].0.min(c[2].0),
        c[1].0.max(c[3].0),
        c[0].1.min(c[1].1),
        c[2].1.max(c[3].1),
    )
}

/// Undistorted keypoints with descriptors, depth and right coordinate, and their grid.
#[derive(Clone, Debug)]
pub struct Features {
    /// Undistorted keypoints (pixel coordinates in the ideal pinhole image).
    pub keypoints: Vec<KeyPoint>,
    /// 256-bit ORB descriptors, one per keypoint.
    pub descriptors: Vec<Descriptor>,
    /// Measured depth per keypoint in metres; `<= 0` means none.
    pub depth: Vec<f32>,
    /// Right-image x coordinate per keypoint (stereo match, or `u - bf / depth` for RGB-D);
    /// negative means none.
    pub u_right: Vec<f32>,
    /// Radius-query grid over `keypoints`.
    pub grid: FeatureGrid,
}

impl Features {
    /// Bundles the arrays (all of the same length) and builds the grid.
    pub fn new(
        keypoints: Vec<KeyPoint>,
        descriptors: Vec<Descriptor>,
        depth: Vec<f32>,
        u_right: Vec<f32>,
        camera: &Camera,
    ) -> Self {
        let n = keypoints.len();
        debug_assert!(descriptors.len() == n && depth.len() == n && u_right.len() == n);
        let grid = FeatureGrid::new(&keypoints, camera);
        Features {
            keypoints,
            descriptors,
            depth,
            u_right,
            grid,
        }
    }

    /// Number of keypoints.
    pub fn len(&self) -> usize {
        self.keypoints.len()
    }

    /// The RGB-D feature set with every right coordinate that depth gives recomputed for
    /// baseline `bf` (metres x pixels), as extraction with a camera of that `bf` computes it
    /// (`u - bf / depth`): what a run whose configuration moves the RGB-D baseline
    /// ([`crate::system::Config::camera_baseline`]) tracks on features extracted beforehand.
    pub fn with_rgbd_bf(&self, bf: f64) -> Features {
        let mut f = self.clone();
        for ((ur, &d), kp) in f.u_right.iter_mut().zip(&f.depth).zip(&f.keypoints) {
            if d > 0.0 {
                *ur = (kp.x as f64 - bf / d as f64) as f32;
            }
        }
        f
    }

    /// Heap bytes held by the feature set (what a sweep keeps per frame).
    pub fn heap_bytes(&self) -> usize {
        self.keypoints.capacity() * std::mem::size_of::<KeyPoint>()
            + self.descriptors.capacity() * std::mem::size_of::<Descriptor>()
            + 4 * (self.depth.capacity() + self.u_right.capacity())
            + self.grid.heap_bytes()
    }

    /// Whether there are no keypoints.
    pub fn is_empty(&self) -> bool {
        self.keypoints.is_empty()
    }

    /// Depth of keypoint `i` in metres when it has one.
    #[inline]
    pub fn depth_of(&self, i: usize) -> Option<f64> {
        let d = self.depth[i];
        (d > 0.0 && d.is_finite()).then_some(d as f64)
    }

    /// Right coordinate of keypoint `i` when it has one.
    #[inline]
    pub fn u_right_of(&self, i: usize) -> Option<f64> {
        let u = self.u_right[i];
        (u >= 0.0).then_some(u as f64)
    }

    /// Keypoint `i` back-projected with its measured depth, in camera coordinates.
    pub fn unproject_camera(&self, i: usize, camera: &Camera) -> Option<nalgebra::Vector3<f64>> {
        let z = self.depth_of(i)?;
        let kp = &self.keypoints[i];
        Some(camera.unproject(kp.x as f64, kp.y as f64, z))
    }

    /// Indices of keypoints within the square of half-side `r` around (x, y), with the level
    /// filter of ORB-SLAM2's GetFeaturesInArea: levels are checked when `min_level > 0` or
    /// `max_level >= 0`; a negative `max_level` means no upper bound. Ascending index order.
    pub fn features_in_area(
        &self,
        x: f64,
        y: f64,
        r: f64,
        min_level: i32,
        max_level: i32,
    ) -> Vec<usize> {
        let g = &self.grid;
        let (x0, y0) = g.cell_coord(x - r, y - r);
        let (x1, y1) = g.cell_coord(x + r, y + r);
        if x1 < 0 || y1 < 0 || x0 >= GRID_COLS as i64 || y0 >= GRID_ROWS as i64 {
            return Vec::new();
        }
        let (x0, y0) = (x0.max(0) as usize, y0.max(0) as usize);
        let (x1, y1) = (
            x1.min(GRID_COLS as i64 - 1) as usize,
            y1.min(GRID_ROWS as i64 - 1) as usize,
        );
        let check_levels = min_level > 0 || max_level >= 0;
        let mut out = Vec::new();
        for cy in y0..=y1 {
            // Cells x0..=x1 of a row are consecutive, so their keypoints are one run of the
            // index array (visited in the same order as cell by cell).
            for &i in g.cells(cy * GRID_COLS + x0, cy * GRID_COLS + x1) {
                let kp = &self.keypoints[i as usize];
                if check_levels {
                    let o = kp.octave as i32;
                    if o < min_level || (max_level >= 0 && o > max_level) {
                        continue;
                    }
                }
                if (kp.x as f64 - x).abs() < r && (kp.y as f64 - y).abs() < r {
                    out.push(i as usize);
                }
            }
        }
        out.sort_unstable();
        out
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn kp(x: f32, y: f32, octave: usize) -> KeyPoint {
        KeyPoint {
            x,
            y,
            octave,
            angle: 0.0,
            response: 1.0,
        }
    }

    #[test]
    fn area_query_matches_brute_force() {
        let cam = Camera::tum_fr3();
        let mut kps = Vec::new();
        let mut s = 12345u64;
        for _ in 0..3000 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let x = ((s >> 33) % 6400) as f32 / 10.0;
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let y = ((s >> 33) % 4800) as f32 / 10.0;
            kps.push(kp(x, y, (s >> 20) as usize % 8));
        }
        let n = kps.len();
        let f = Features::new(kps, vec![[0; 4]; n], vec![0.0; n], vec![-1.0; n], &cam);
        let mut total = 0;
        for &(x, y, r, lo, hi) in &[
            (100.0, 100.0, 30.0, 0, -1),
            (320.0, 240.0, 50.0, 2, 3),
            (5.0, 470.0, 40.0, 0, 0),
            (639.0, 0.0, 15.0, -1, -1),
        ] {
            let got = f.features_in_area(x, y, r, lo, hi);
            let want: Vec<usize> = (0..n)
                .filter(|&i| {
                    let k = &f.keypoints[i];
                    let lv = k.octave as i32;
                    let lv_ok = !(lo > 0 || hi >= 0) || (lv >= lo && (hi < 0 || lv <= hi));
                    lv_ok && (k.x as f64 - x).abs() < r && (k.y as f64 - y).abs() < r
                })
                .collect();
            assert_eq!(got, want);
            total += want.len();
        }
        // The queries are not vacuous.
        assert!(total > 50, "{total}");
    }
}
