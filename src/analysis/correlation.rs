//! Table II on a synthetic sequence: for every tracked frame, the error terms of each
//! observation with measured depth (slam-core's [`error_terms`]) at the pose and map points the
//! system estimated, correlated with the z-normalised 3-D error and the 2-D projective errors as
//! the paper does, and — what only a synthetic sequence allows — with the true depth error.
//!
//! # Definitions
//! For an observation of frame k (keypoint (u, v), measured depth Z_D, map point X_w matched to
//! it in the frame's final pose optimization, estimated pose T_cw of that optimization):
//! - M = T_cw X_w (the map point in the estimated camera frame), D = the keypoint back-projected
//!   with Z_D. `e_ORB,z`, `e_AVC,zx`, `e_AVC,zy`, `e_BASE,z` = |M - D| / Z_D and (dx, dy) are
//!   those of [`slam_core::techniques::correlation`] with virtual baseline b (`--baseline`).
//! - True depth error: Z_D - Z_true, with Z_true the generator's noiseless depth at the pixel
//!   the system read Z_D from (the raw keypoint rounded to the nearest pixel). It contains every
//!   component of the sensor model (axial and lateral noise, quantisation, holes' edges,
//!   misregistration, lag, distortion), not only the axial noise.
//! - True z-normalised depth error: |Z_D - Z_true| / Z_D.
//!
//! Correlations are Pearson's r of **magnitudes** (absolute values), as slam-core's
//! [`slam_core::techniques::correlation_analysis`] explains; Spearman's rank correlation of the same magnitudes is
//! reported next to it because depth errors are heavy-tailed (a few edge pixels metres off
//! dominate Pearson's r). Subsets: the observations the final optimization kept as inliers
//! (what the pose estimate rests on) and all its matches (inliers and outliers).

use crate::analysis::stream::{for_each_frame, frame_input};
use anyhow::{bail, Result};
use slam_core::module::pose_estimation::tap_pose_optimizations;
use slam_core::system::{Config, System};
use slam_core::techniques::{error_terms, pearson, ErrorTerms};
use slam_core::{Camera, DepthImage};
use synth::Generator;

/// One observation: the error terms, the true depth error and whether it was an inlier.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observation {
    /// Frame index.
    pub frame: usize,
    /// Error terms at the estimated pose and map point.
    pub terms: ErrorTerms,
    /// Measured depth Z_D, metres.
    pub depth: f64,
    /// True depth error Z_D - Z_true, metres.
    pub true_depth_error: f64,
    /// Inlier of the frame's final pose optimization.
    pub inlier: bool,
}

/// What a correlation run collected.
#[derive(Clone, Debug)]
pub struct CorrelationData {
    /// Every observation with measured and true depth, over all tracked frames.
    pub observations: Vec<Observation>,
    /// Frames fed to the system.
    pub frames: usize,
    /// Frames with a pose optimization record (tracked).
    pub tracked_frames: usize,
}

/// Runs `config` over frames 0..n of `generator` and collects the observations (see the module
/// doc), with virtual baseline `baseline` (metres).
pub fn collect(
    generator: &Generator,
    n: usize,
    config: &Config,
    baseline: f64,
    mut progress: impl FnMut(usize),
) -> Result<CorrelationData> {
    if !(baseline > 0.0 && baseline.is_finite()) {
        bail!("--baseline must be a positive number of metres, got {baseline}");
    }
    let camera = generator.camera();
    let mut system = System::with_vocabulary(
        camera.clone(),
        config.clone(),
        crate::vocab_file::default_vocabulary(),
    );
    let mut observations = Vec::new();
    let mut tracked_frames = 0;
    for_each_frame(generator, n, |frame| {
        let input = frame_input(&frame);
        let (result, records) = tap_pose_optimizations(|| system.track(&input));
        progress(frame.index + 1);
        if !result.state.is_tracked() {
            return;
        }
        let (Some(record), Some(last), Some(truth)) = (
            records
                .iter()
                .rev()
                .find(|r| r.frame_id == frame.index as u64),
            system.last_frame(),
            frame.depth_true.as_ref(),
        ) else {
            return;
        };
        tracked_frames += 1;
        for m in &record.matches {
            let Some(depth) = last.features.depth_of(m.keypoint) else {
                continue;
            };
            let kp = &last.features.keypoints[m.keypoint];
            let (u, v) = (kp.x as f64, kp.y as f64);
            let Some(z_true) = depth_at_raw_pixel(&camera, truth, u, v) else {
                continue;
            };
            let point = (record.tcw * nalgebra::Point3::from(m.point_world)).coords;
            if let Some(terms) = error_terms(&camera, u, v, depth, &point, baseline) {
                observations.push(Observation {
                    frame: frame.index,
                    terms,
                    depth,
                    true_depth_error: depth - z_true,
                    inlier: m.inlier,
                });
            }
        }
    });
    Ok(CorrelationData {
        observations,
        frames: n,
        tracked_frames,
    })
}

/// The depth of `image` at the raw (distorted) pixel of undistorted keypoint (u, v), read the
/// way the system reads measured depth (nearest pixel); `None` outside the image or without a
/// positive value.
pub fn depth_at_raw_pixel(camera: &Camera, image: &DepthImage, u: f64, v: f64) -> Option<f64> {
    let (x, y) = camera.distort_point(u, v);
    let (x, y) = (x.round(), y.round());
    if x < 0.0 || y < 0.0 || x as usize >= image.width || y as usize >= image.height {
        return None;
    }
    image
        .get(x as usize, y as usize)
        .map(f64::from)
        .filter(|d| *d > 0.0 && d.is_finite())
}

/// Spearman's rank correlation: Pearson's r of the ranks (ties get their mean rank).
pub fn spearman(a: &[f64], b: &[f64]) -> Option<f64> {
    if a.len() != b.len() {
        return None;
    }
    pearson(&ranks(a), &ranks(b))
}

fn ranks(x: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..x.len()).collect();
    order.sort_by(|&i, &j| x[i].total_cmp(&x[j]));
    let mut r = vec![0.0; x.len()];
    let mut k = 0;
    while k < order.len() {
        let mut end = k + 1;
        while end < order.len() && x[order[end]] == x[order[k]] {
            end += 1;
        }
        let mean_rank = (k + end - 1) as f64 / 2.0;
        for &i in &order[k..end] {
            r[i] = mean_rank;
        }
        k = end;
    }
    r
}

/// Which correlation coefficient a table holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Statistic {
    /// Pearson's r (the paper's).
    Pearson,
    /// Spearman's rank correlation.
    Spearman,
}

impl Statistic {
    /// Lower-case name for files and CSV.
    pub fn name(self) -> &'static str {
        match self {
            Statistic::Pearson => "pearson",
            Statistic::Spearman => "spearman",
        }
    }
}

/// Column identifiers of the table (CSV), in order: e_ORB,z, e_AVC,zx, e_AVC,zy, e_BASE,z.
pub const COLUMNS: [&str; 4] = ["e_orb_z", "e_avc_zx", "e_avc_zy", "e_base_z"];
/// Row identifiers of the table (CSV), in order: the paper's e_BASE,z and (dx, dy), then the
/// true depth error and the true z-normalised depth error.
pub const ROWS: [&str; 5] = [
    "e_base_z",
    "dx",
    "dy",
    "true_depth_error",
    "true_z_normalised_depth_error",
];

/// Markdown labels of the true-error rows (3 and 4 of [`ROWS`]).
const TRUE_ROW_LABELS: [&str; 2] = ["true depth error", "true z-normalised depth error"];

/// One Table II: `cells[row][column]` (see [`ROWS`], [`COLUMNS`]); `None` where a series has
/// no variance or the cell is a series against itself.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// Which coefficient.
    pub statistic: Statistic,
    /// Inliers only, or all matches.
    pub subset: &'static str,
    /// Observations used.
    pub n: usize,
    /// The correlations.
    pub cells: [[Option<f64>; 4]; 5],
}

/// The table of `statistic` over `obs`, labelled `subset`.
pub fn table(obs: &[Observation], statistic: Statistic, subset: &'static str) -> Table {
    let col = |f: &dyn Fn(&Observation) -> f64| -> Vec<f64> { obs.iter().map(f).collect() };
    let columns = [
        col(&|o| o.terms.e_orb_z.abs()),
        col(&|o| o.terms.e_avc_zx.abs()),
        col(&|o| o.terms.e_avc_zy.abs()),
        col(&|o| o.terms.e_base_z.abs()),
    ];
    let rows = [
        col(&|o| o.terms.e_base_z.abs()),
        col(&|o| o.terms.dx.abs()),
        col(&|o| o.terms.dy.abs()),
        col(&|o| o.true_depth_error.abs()),
        col(&|o| o.true_depth_error.abs() / o.depth),
    ];
    let coefficient = |a: &[f64], b: &[f64]| match statistic {
        Statistic::Pearson => pearson(a, b),
        Statistic::Spearman => spearman(a, b),
    };
    let mut cells = [[None; 4]; 5];
    for (r, row) in rows.iter().enumerate() {
        for (c, column) in columns.iter().enumerate() {
            if !(r == 0 && c == 3) {
                cells[r][c] = coefficient(column, row);
            }
        }
    }
    Table {
        statistic,
        subset,
        n: obs.len(),
        cells,
    }
}

/// The four tables of a run: {inliers, all matches} x {Pearson, Spearman}, inliers + Pearson
/// (the paper's) first.
pub fn tables(data: &CorrelationData) -> Vec<Table> {
    let inliers: Vec<Observation> = data
        .observations
        .iter()
        .copied()
        .filter(|o| o.inlier)
        .collect();
    let mut out = Vec::new();
    for (subset, obs) in [
        ("inliers", &inliers[..]),
        ("all matches", &data.observations),
    ] {
        for s in [Statistic::Pearson, Statistic::Spearman] {
            out.push(table(obs, s, subset));
        }
    }
    out
}

fn cell(x: Option<f64>) -> String {
    x.map_or_else(|| "-".to_string(), |v| format!("{v:.2}"))
}

/// The paper's layout: columns e_ORB,z, e_AVC,zx, e_AVC,zy (and e_BASE,z for the true-error
/// rows); rows e_BASE,z, (dx, dy), then the true depth errors. Markdown.
pub fn markdown_table(t: &Table) -> String {
    let c = &t.cells;
    let mut s = String::new();
    s.push_str("| | e_ORB,z | e_AVC,zx | e_AVC,zy | e_BASE,z |\n|---|---|---|---|---|\n");
    s.push_str(&format!(
        "| e_BASE,z | {} | {} | {} | |\n",
        cell(c[0][0]),
        cell(c[0][1]),
        cell(c[0][2])
    ));
    let pair = |k: usize| format!("({}, {})", cell(c[1][k]), cell(c[2][k]));
    s.push_str(&format!(
        "| (dx, dy) | {} | {} | {} | {} |\n",
        pair(0),
        pair(1),
        pair(2),
        pair(3)
    ));
    for r in 3..5 {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} |\n",
            TRUE_ROW_LABELS[r - 3],
            cell(c[r][0]),
            cell(c[r][1]),
            cell(c[r][2]),
            cell(c[r][3])
        ));
    }
    s
}

/// Long-format CSV of `tables`: subset, statistic, row, column, value (empty when undefined), n.
pub fn csv_bytes(tables: &[Table]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(["subset", "statistic", "row", "column", "value", "n"])?;
    for t in tables {
        for (r, row) in ROWS.iter().enumerate() {
            for (c, column) in COLUMNS.iter().enumerate() {
                if r == 0 && c == 3 {
                    continue;
                }
                let value = t.cells[r][c].map(|v| format!("{v:.6}")).unwrap_or_default();
                w.write_record([
                    t.subset,
                    t.statistic.name(),
                    row,
                    column,
                    &value,
                    &t.n.to_string(),
                ])?;
            }
        }
    }
    Ok(w.into_inner()?)
}

/// Median of |x| (0 for an empty series).
pub fn median_abs(x: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = x.map(f64::abs).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The paper's Table II (Pearson), quoted in the Markdown report for comparison.
pub const PAPER_TABLE: &str = "| | e_ORB,z | e_AVC,zx | e_AVC,zy |\n|---|---|---|---|\n\
| e_BASE,z | 0.25 | 0.72 | 0.76 |\n| (dx, dy) | (0.96, 0.03) | (0.10, 0.12) | (0.12, 0.12) |\n";

/// Whether every defined cell of `t` is finite and in [-1, 1].
pub fn cells_valid(t: &Table) -> bool {
    t.cells
        .iter()
        .flatten()
        .flatten()
        .all(|v| v.is_finite() && (-1.0 - 1e-12..=1.0 + 1e-12).contains(v))
}

/// Summary figures of the observations: (count, median |Z_D - Z_true| in metres, median
/// e_BASE,z, median |dx|) over `obs`.
pub fn summary(obs: &[Observation]) -> (usize, f64, f64, f64) {
    (
        obs.len(),
        median_abs(obs.iter().map(|o| o.true_depth_error)),
        median_abs(obs.iter().map(|o| o.terms.e_base_z)),
        median_abs(obs.iter().map(|o| o.terms.dx)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obs(e: f64, dx: f64, err: f64, inlier: bool) -> Observation {
        Observation {
            frame: 0,
            terms: ErrorTerms {
                e_orb_z: dx + 0.1 * e,
                e_avc_zx: -e,
                e_avc_zy: 2.0 * e,
                e_base_z: e,
                dx,
                dy: 0.5,
            },
            depth: 2.0,
            true_depth_error: err,
            inlier,
        }
    }

    #[test]
    fn spearman_uses_ranks_with_ties() {
        let a = [1.0, 2.0, 3.0, 4.0];
        // Monotone but not linear: Spearman 1, Pearson < 1.
        let b = [1.0, 10.0, 100.0, 1000.0];
        assert!((spearman(&a, &b).unwrap() - 1.0).abs() < 1e-12);
        assert!(pearson(&a, &b).unwrap() < 0.99);
        assert_eq!(ranks(&[3.0, 1.0, 3.0, 2.0]), vec![2.5, 0.0, 2.5, 1.0]);
        assert_eq!(spearman(&a, &[1.0; 4]), None);
    }

    #[test]
    fn table_correlates_magnitudes_in_the_papers_layout() {
        let data: Vec<Observation> = (0..40)
            .map(|k| {
                let e = 0.01 * (k % 7) as f64;
                let dx = if k % 2 == 0 { 1.0 } else { -3.0 } * (k % 5) as f64;
                obs(e, dx, 2.0 * e, k % 3 != 0)
            })
            .collect();
        let t = table(&data, Statistic::Pearson, "all matches");
        assert_eq!(t.n, 40);
        // AVC columns are multiples of e_BASE,z in magnitude; the true error is 2 e_BASE,z.
        for c in 1..4 {
            if c != 3 {
                assert!((t.cells[0][c].unwrap() - 1.0).abs() < 1e-12);
            }
            assert!((t.cells[3][c].unwrap() - 1.0).abs() < 1e-12);
        }
        assert_eq!(t.cells[0][3], None, "e_BASE,z against itself is left out");
        assert_eq!(t.cells[2][0], None, "constant dy has no correlation");
        assert!(t.cells[1][0].unwrap() > 0.9, "ORB row follows |dx|");
        assert!(cells_valid(&t));
        let md = markdown_table(&t);
        assert!(md.contains("| e_BASE,z | "), "{md}");
        assert!(md.contains("| (dx, dy) | ("), "{md}");
        let all = tables(&CorrelationData {
            observations: data.clone(),
            frames: 1,
            tracked_frames: 1,
        });
        assert_eq!(all.len(), 4);
        assert_eq!(all[0].n, data.iter().filter(|o| o.inlier).count());
        let csv = String::from_utf8(csv_bytes(&all).unwrap()).unwrap();
        assert_eq!(csv.lines().count(), 1 + 4 * 19);
    }

    #[test]
    fn depth_is_read_at_the_nearest_raw_pixel() {
        let camera = Camera::tum_fr3();
        let mut image = DepthImage::new(4, 3);
        image.data[4 + 2] = 1.5;
        assert_eq!(depth_at_raw_pixel(&camera, &image, 2.4, 1.4), Some(1.5));
        assert_eq!(depth_at_raw_pixel(&camera, &image, 0.0, 0.0), None);
        assert_eq!(depth_at_raw_pixel(&camera, &image, 9.0, 1.0), None);
    }
}
