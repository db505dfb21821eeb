//! TUM RGB-D reader: `rgb.txt` and `depth.txt` associated by nearest timestamp (as TUM's
//! `associate.py`: all pairs closer than 0.02 s, taken greedily by |dt|, each stamp used once),
//! or `associations.txt` (ORB-SLAM2's format) when present; `groundtruth.txt` when present.
//! Images are decoded in parallel with rayon; frame order is the rgb time order.

use crate::cameras::CameraId;
use crate::decode::{read_depth, read_gray, read_gray_and_colour};
use crate::{DatasetError, Format, FrameReader, Sequence};
use slam_core::{Camera, FrameInput};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Options of the TUM reader. `Default` gives the paper's (ORB-SLAM2's) settings.
#[derive(Clone, Debug, Default)]
pub struct TumOptions {
    /// Camera to use; `None`: chosen by the freiburg id in the folder name, fr3 when none.
    pub camera: Option<Camera>,
    /// Depth PNG value per metre; `None`: ORB-SLAM2's factor for the detected camera
    /// (5208 for fr2, 5000 otherwise; the TUM site says 5000 for all).
    pub depth_factor: Option<f64>,
    /// Maximum |t_rgb - t_depth| in seconds for association; `None`: 0.02 s (associate.py).
    pub max_difference: Option<f64>,
    /// Read at most this many frames (after association); `None`: all.
    pub max_frames: Option<usize>,
}

/// Default association window of TUM's `associate.py`, seconds.
pub const MAX_DIFFERENCE: f64 = 0.02;

/// Most rgb/depth candidate pairs inside the association window a folder may give per stamp
/// of its lists: a camera of up to 200 Hz gives at most 4 in associate.py's 0.02 s window.
const MAX_CANDIDATES_PER_STAMP: usize = 8;

/// One line of a TUM list file: timestamp, file (relative to the sequence folder), line number.
#[derive(Clone, Debug, PartialEq)]
pub struct ListEntry {
    /// Timestamp in seconds.
    pub stamp: f64,
    /// File path relative to the sequence folder.
    pub file: String,
    /// 1-based line in the list file.
    pub line: usize,
}

fn read_text(path: &Path, what: &str) -> Result<String, DatasetError> {
    if !path.is_file() {
        return Err(DatasetError::Missing {
            path: path.to_path_buf(),
            what: what.into(),
        });
    }
    std::fs::read_to_string(path).map_err(|e| DatasetError::io(path, e))
}

fn parse_stamp(path: &Path, line: usize, s: &str) -> Result<f64, DatasetError> {
    match s.parse::<f64>() {
        Ok(t) if t.is_finite() => Ok(t),
        _ => Err(DatasetError::parse(
            path,
            line,
            format!("bad timestamp `{s}`"),
        )),
    }
}

/// Parses a TUM `rgb.txt` / `depth.txt` (`timestamp filename`, `#` comments). Timestamps must
/// not decrease.
pub fn read_list(path: &Path) -> Result<Vec<ListEntry>, DatasetError> {
    let text = read_text(path, "a TUM RGB-D image list (timestamp filename per line)")?;
    let mut out: Vec<ListEntry> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let mut it = l.split_whitespace();
        let (Some(ts), Some(file)) = (it.next(), it.next()) else {
            return Err(DatasetError::parse(
                path,
                line,
                "expected `timestamp filename`",
            ));
        };
        let stamp = parse_stamp(path, line, ts)?;
        if let Some(prev) = out.last() {
            if stamp < prev.stamp {
                return Err(DatasetError::parse(
                    path,
                    line,
                    format!(
                        "timestamp {stamp} goes back in time (previous {} on line {})",
                        prev.stamp, prev.line
                    ),
                ));
            }
        }
        out.push(ListEntry {
            stamp,
            file: file.to_string(),
            line,
        });
    }
    Ok(out)
}

/// Parses ORB-SLAM2's `associations.txt`: `t_rgb rgb_file t_depth depth_file` per line.
pub fn read_associations(path: &Path) -> Result<Vec<(ListEntry, ListEntry)>, DatasetError> {
    let text = read_text(path, "an association file")?;
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        // Four fields; more are ignored, and never collected.
        let f: Vec<&str> = l.split_whitespace().take(4).collect();
        if f.len() < 4 {
            return Err(DatasetError::parse(
                path,
                line,
                "expected `t_rgb rgb_file t_depth depth_file`",
            ));
        }
        out.push((
            ListEntry {
                stamp: parse_stamp(path, line, f[0])?,
                file: f[1].into(),
                line,
            },
            ListEntry {
                stamp: parse_stamp(path, line, f[2])?,
                file: f[3].into(),
                line,
            },
        ));
    }
    Ok(out)
}

/// Associates two time-sorted stamp lists like TUM's `associate.py`: every pair with
/// |a - b| < `max_difference` is a candidate, candidates are taken greedily by increasing |dt|
/// (ties by index), each stamp at most once. Returns index pairs sorted by the first list.
pub fn associate(a: &[f64], b: &[f64], max_difference: f64) -> Vec<(usize, usize)> {
    // evaluate_ate.py's association is associate.py's: the same greedy pairing.
    ate_eval::associate(a, b, max_difference, 0.0, ate_eval::AssociationMode::Tum)
}

/// Loads a TUM RGB-D folder with the paper's defaults; `camera` overrides the camera detected
/// from the folder name (fr1/fr2/fr3; fr3 when the name has no freiburg id).
pub fn load_tum(dir: &Path, camera: Option<Camera>) -> Result<Sequence, DatasetError> {
    load_tum_with(
        dir,
        &TumOptions {
            camera,
            ..TumOptions::default()
        },
    )
}

/// The folder's own name (resolving `.` and trailing separators).
pub(crate) fn folder_name(dir: &Path) -> String {
    let abs = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
    abs.file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| dir.display().to_string())
}

/// The colour-depth pairs of a TUM folder, in colour order: its `associations.txt` when it has
/// one, else `rgb.txt` and `depth.txt` associated as associate.py does within `max_difference`.
pub fn pairs(dir: &Path, max_difference: f64) -> Result<Vec<(ListEntry, ListEntry)>, DatasetError> {
    let assoc_path = dir.join("associations.txt");
    if assoc_path.is_file() {
        return read_associations(&assoc_path);
    }
    let rgb = read_list(&dir.join("rgb.txt"))?;
    let depth = read_list(&dir.join("depth.txt"))?;
    let ta: Vec<f64> = rgb.iter().map(|e| e.stamp).collect();
    let tb: Vec<f64> = depth.iter().map(|e| e.stamp).collect();
    // associate.py's pairing weighs every pair inside the window: a camera's stamps give a
    // few per frame, but lists whose stamps repeat (or lie nanoseconds apart) give n_rgb x
    // n_depth of them, time and memory quadratic in the files. Counted first, in n log n.
    let candidates: usize = ta
        .iter()
        .map(|&t| {
            let lo = tb.partition_point(|&g| g <= t - max_difference);
            let hi = tb.partition_point(|&g| g < t + max_difference);
            hi.saturating_sub(lo)
        })
        .sum();
    if candidates > MAX_CANDIDATES_PER_STAMP * (ta.len() + tb.len()) + 1024 {
        return Err(DatasetError::invalid(
            dir.join("rgb.txt"),
            format!(
                "{candidates} rgb/depth pairs lie within the {max_difference} s association \
                 window ({} and {} stamps): the stamps are denser than a camera's (repeated, \
                 or nanoseconds apart)",
                ta.len(),
                tb.len()
            ),
        ));
    }
    Ok(associate(&ta, &tb, max_difference)
        .into_iter()
        .map(|(i, j)| (rgb[i].clone(), depth[j].clone()))
        .collect())
}

/// Loads a TUM RGB-D folder with explicit options.
pub fn load_tum_with(dir: &Path, opts: &TumOptions) -> Result<Sequence, DatasetError> {
    let (mut seq, frames) = open_tum_with(dir, opts)?;
    seq.frames = frames.without_colour().read_all()?;
    Ok(seq)
}

/// Opens a TUM RGB-D folder: lists, association and ground truth are read now, the images when
/// the returned reader reads them (the sequence's `frames` stay empty).
pub fn open_tum_with(
    dir: &Path,
    opts: &TumOptions,
) -> Result<(Sequence, FrameReader), DatasetError> {
    if !dir.is_dir() {
        return Err(DatasetError::Missing {
            path: dir.to_path_buf(),
            what: "a TUM RGB-D sequence folder".into(),
        });
    }
    let name = folder_name(dir);
    let id = CameraId::detect_tum(&name).unwrap_or(CameraId::Fr3);
    let camera = match &opts.camera {
        Some(c) => c.clone(),
        None => id.tum_camera().unwrap_or_else(Camera::tum_fr3),
    };
    let depth_factor = opts
        .depth_factor
        .unwrap_or_else(|| id.orbslam2_depth_factor());
    if !(depth_factor.is_finite() && depth_factor > 0.0) {
        return Err(DatasetError::invalid(
            dir,
            format!("depth factor must be positive, got {depth_factor}"),
        ));
    }
    let max_dt = opts.max_difference.unwrap_or(MAX_DIFFERENCE);

    let mut pairs = pairs(dir, max_dt)?;
    if let Some(n) = opts.max_frames {
        pairs.truncate(n);
    }
    if pairs.is_empty() {
        return Err(DatasetError::invalid(
            dir,
            "no rgb/depth pairs (empty lists, or no depth within the association window)",
        ));
    }

    // A settings file without the image size (ORB-SLAM2's TUM files have none): the images say.
    let mut camera = camera;
    if camera.width == 0 || camera.height == 0 {
        let first = read_gray(&dir.join(&pairs[0].0.file))?;
        (camera.width, camera.height) = (first.width as u32, first.height as u32);
    }
    let (w, h) = (camera.width as usize, camera.height as usize);
    let folder = dir.to_path_buf();
    let n_pairs = pairs.len();
    let frames = FrameReader::new(n_pairs, move |i| {
        let (rgb, depth) = &pairs[i];
        let rgb_path = folder.join(&rgb.file);
        let depth_path = folder.join(&depth.file);
        let (image, colour) = read_gray_and_colour(&rgb_path)?;
        check_size(&rgb_path, image.width, image.height, w, h, "the camera")?;
        let d = read_depth(&depth_path, depth_factor)?;
        check_size(
            &depth_path,
            d.width,
            d.height,
            image.width,
            image.height,
            "its rgb image",
        )?;
        Ok(FrameInput {
            timestamp: rgb.stamp,
            image: Arc::new(image),
            depth: Some(Arc::new(d)),
            right: None,
            colour: colour.map(Arc::new),
        })
    });

    let gt_path = dir.join("groundtruth.txt");
    let mut notes = Vec::new();
    let groundtruth = if gt_path.is_file() {
        Some(read_groundtruth(
            &gt_path,
            ate_eval::io::Format::Tum,
            &mut notes,
        )?)
    } else {
        None
    };
    let seq = Sequence {
        name,
        camera,
        frames: Vec::new(),
        groundtruth,
        t_bs: None,
        format: Format::TumRgbd,
        notes,
        depth_factor: Some(depth_factor),
        rectification: None,
    };
    Ok((seq, frames))
}

/// Reads a ground-truth file as evaluate_ate.py does (repeated stamps: the last line wins; out
/// of order: sorted), adding what was repaired to `notes`.
pub(crate) fn read_groundtruth(
    path: &Path,
    format: ate_eval::io::Format,
    notes: &mut Vec<String>,
) -> Result<ate_eval::Trajectory, DatasetError> {
    let loaded = ate_eval::io::read_trajectory(path, format, None, ate_eval::StampPolicy::LastWins)
        .map_err(|e| DatasetError::GroundTruth {
            path: path.to_path_buf(),
            msg: e.to_string(),
        })?;
    notes.extend(loaded.warnings.iter().map(|w| w.to_string()));
    Ok(loaded.trajectory)
}

pub(crate) fn check_size(
    path: &Path,
    found_w: usize,
    found_h: usize,
    expected_w: usize,
    expected_h: usize,
    what: &str,
) -> Result<(), DatasetError> {
    if (found_w, found_h) != (expected_w, expected_h) {
        return Err(DatasetError::SizeMismatch {
            path: PathBuf::from(path),
            found_w,
            found_h,
            expected_w,
            expected_h,
            what: what.into(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn associate_is_greedy_by_dt_and_unique() {
        // a[1] and a[2] both want b[1]; a[2] is closer, a[1] falls back to nothing in range.
        let a = [0.0, 1.0, 1.015, 2.0];
        let b = [0.005, 1.012, 2.03];
        let p = associate(&a, &b, 0.02);
        assert_eq!(p, vec![(0, 0), (2, 1)]);
    }

    #[test]
    fn associate_respects_strict_window() {
        assert!(associate(&[0.0], &[0.02], 0.02).is_empty());
        assert_eq!(associate(&[0.0], &[0.0199], 0.02), vec![(0, 0)]);
    }

    #[test]
    fn lists_of_one_repeated_stamp_are_refused_not_paired_in_quadratic_time() {
        // Found by fuzzing the folder's pairing (target tum-pairs, an allocation of 1.6 GB in
        // its first 30 s): 4000 lines of one stamp in rgb.txt and in depth.txt made 16
        // million candidate pairs (a million lines would make 10^12).
        let dir = tempfile::tempdir().unwrap();
        let list = "1.0 rgb/a.png\n".repeat(4000);
        std::fs::write(dir.path().join("rgb.txt"), &list).unwrap();
        std::fs::write(dir.path().join("depth.txt"), &list).unwrap();
        let e = pairs(dir.path(), MAX_DIFFERENCE).unwrap_err().to_string();
        assert!(e.contains("rgb.txt") && e.contains("16000000"), "{e}");
        // A real camera's lists pair as before.
        let rgb: String = (0..4000)
            .map(|i| format!("{} rgb/{i}.png\n", i as f64 / 30.0))
            .collect();
        std::fs::write(dir.path().join("rgb.txt"), &rgb).unwrap();
        std::fs::write(dir.path().join("depth.txt"), &rgb).unwrap();
        assert_eq!(pairs(dir.path(), MAX_DIFFERENCE).unwrap().len(), 4000);
    }

    #[test]
    fn list_rejects_time_going_back_with_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("rgb.txt");
        std::fs::write(&p, "# c\n1.0 rgb/a.png\n0.5 rgb/b.png\n").unwrap();
        let e = read_list(&p).unwrap_err().to_string();
        assert!(e.contains("rgb.txt:3"), "{e}");
        std::fs::write(&p, "1.0 rgb/a.png\nabc rgb/b.png\n").unwrap();
        let e = read_list(&p).unwrap_err().to_string();
        assert!(e.contains("rgb.txt:2") && e.contains("abc"), "{e}");
    }
}
