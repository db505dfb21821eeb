//! The cell grid of a frame (ORB-SLAM2: 64 x 48 cells over the undistorted image bounds): every
//! keypoint is filed in the cell containing it, so "keypoints near (x, y)" only visits the few
//! cells the search window overlaps instead of every keypoint.

use crate::feature::KeyPoint;

/// Number of grid columns (ORB-SLAM2 `FRAME_GRID_COLS`).
pub const FRAME_GRID_COLS: usize = 64;
/// Number of grid rows (ORB-SLAM2 `FRAME_GRID_ROWS`).
pub const FRAME_GRID_ROWS: usize = 48;

/// The undistorted image bounds in pixels: where a keypoint or a projected point can lie.
/// Without distortion they are `[0, width] x [0, height]`; with distortion, the box through the
/// undistorted image corners (as ORB-SLAM2's `ComputeImageBounds`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageBounds {
    /// Smallest x.
    pub min_x: f64,
    /// Largest x.
    pub max_x: f64,
    /// Smallest y.
    pub min_y: f64,
    /// Largest y.
    pub max_y: f64,
}

impl ImageBounds {
    /// Whether (u, v) lies inside `[min_x, max_x) x [min_y, max_y)`.
    pub fn contains(&self, u: f64, v: f64) -> bool {
        u >= self.min_x && u < self.max_x && v >= self.min_y && v < self.max_y
    }
}

/// Keypoint indices filed by cell, in compressed-row form (cell `c` holds
/// `items[start[c]..start[c + 1]]`, ascending), so queries return indices in a fixed order.
#[derive(Clone, Debug, Default)]
pub struct CellGrid {
    bounds: Option<ImageBounds>,
    inv_cell_w: f64,
    inv_cell_h: f64,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl CellGrid {
    /// Files `keypoints` (undistorted) in a grid over `bounds`; keypoints outside the bounds
    /// are left out of the grid (they can never be found by a search).
    pub fn new(keypoints: &[KeyPoint], bounds: ImageBounds) -> Self {
        let inv_cell_w = FRAME_GRID_COLS as f64 / (bounds.max_x - bounds.min_x);
        let inv_cell_h = FRAME_GRID_ROWS as f64 / (bounds.max_y - bounds.min_y);
        let mut grid = CellGrid {
            bounds: Some(bounds),
            inv_cell_w,
            inv_cell_h,
            start: vec![0; FRAME_GRID_COLS * FRAME_GRID_ROWS + 1],
            items: Vec::new(),
        };
        let cells: Vec<Option<usize>> = keypoints
            .iter()
            .map(|kp| grid.cell_of(kp.x as f64, kp.y as f64))
            .collect();
        for c in cells.iter().flatten() {
            grid.start[c + 1] += 1;
        }
        for c in 0..FRAME_GRID_COLS * FRAME_GRID_ROWS {
            grid.start[c + 1] += grid.start[c];
        }
        let mut fill: Vec<u32> = grid.start[..FRAME_GRID_COLS * FRAME_GRID_ROWS].to_vec();
        grid.items = vec![0; *grid.start.last().expect("non-empty") as usize];
        for (i, c) in cells.iter().enumerate() {
            if let Some(c) = c {
                grid.items[fill[*c] as usize] = i as u32;
                fill[*c] += 1;
            }
        }
        grid
    }

    /// The cell holding (x, y), or `None` outside the bounds.
    fn cell_of(&self, x: f64, y: f64) -> Option<usize> {
        let b = self.bounds?;
        let cx = ((x - b.min_x) * self.inv_cell_w).floor();
        let cy = ((y - b.min_y) * self.inv_cell_h).floor();
        if cx < 0.0 || cy < 0.0 || cx >= FRAME_GRID_COLS as f64 || cy >= FRAME_GRID_ROWS as f64 {
            return None;
        }
        Some(cy as usize * FRAME_GRID_COLS + cx as usize)
    }

    /// Indices of the keypoints with |x - kx| < r and |y - ky| < r (a square window, as
    /// ORB-SLAM2's `GetFeaturesInArea`) whose octave lies in `[min_level, max_level]`, a
    /// negative bound meaning "no bound". Order: cell by cell (row-major), ascending within a
    /// cell.
    pub fn query(
        &self,
        keypoints: &[KeyPoint],
        x: f64,
        y: f64,
        r: f64,
        min_level: i32,
        max_level: i32,
    ) -> Vec<usize> {
        let mut out = Vec::new();
        let Some(b) = self.bounds else {
            return out;
        };
        let fx0 = ((x - r - b.min_x) * self.inv_cell_w).floor().max(0.0);
        let fx1 = ((x + r - b.min_x) * self.inv_cell_w).floor();
        let fy0 = ((y - r - b.min_y) * self.inv_cell_h).floor().max(0.0);
        let fy1 = ((y + r - b.min_y) * self.inv_cell_h).floor();
        if !(fx0 < FRAME_GRID_COLS as f64
            && fy0 < FRAME_GRID_ROWS as f64
            && fx1 >= 0.0
            && fy1 >= 0.0)
        {
            return out;
        }
        let (cx0, cy0) = (fx0 as usize, fy0 as usize);
        let cx1 = (fx1 as usize).min(FRAME_GRID_COLS - 1);
        let cy1 = (fy1 as usize).min(FRAME_GRID_ROWS - 1);
        for cy in cy0..=cy1 {
            for cx in cx0..=cx1 {
                let c = cy * FRAME_GRID_COLS + cx;
                for &i in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                    let kp = &keypoints[i as usize];
                    let octave = kp.octave as i32;
                    if (min_level >= 0 && octave < min_level)
                        || (max_level >= 0 && octave > max_level)
                    {
                        continue;
                    }
                    if (kp.x as f64 - x).abs() < r && (kp.y as f64 - y).abs() < r {
                        out.push(i as usize);
                    }
                }
            }
        }
        out
    }
}
