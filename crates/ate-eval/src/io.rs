//! Readers and writers of the trajectory formats the community uses:
//! - TUM: `timestamp tx ty tz qx qy qz qw`, seconds, `#` comments, any whitespace;
//! - EuRoC ground truth CSV: `#timestamp [ns], p_RS_R_x, p_RS_R_y, p_RS_R_z, q_RS_w, q_RS_x,
//!   q_RS_y, q_RS_z, ...` (nanoseconds, quaternion w first, extra columns ignored);
//! - KITTI: 12 numbers a line (row-major 3x4 [R | t]), stamps from a times file or the index.
//!
//! Readers check every line: field count, finite numbers, rotation validity (a quaternion off
//! unit length is normalised with a warning, one near zero is rejected). Repeated and
//! out-of-order stamps are resolved as the community tools resolve them, with one warning per
//! file, or refused under [`StampPolicy::Strict`] (see [`crate::stamps`]). Writers go through a temporary file and a rename, so a crash never leaves a file that
//! looks complete.

use crate::error::{Error, Result, Warning};
use crate::stamps::{self, Row, StampPolicy};
use crate::trajectory::Trajectory;
use nalgebra::{Isometry3, Matrix3, Quaternion, Rotation3, Translation3, UnitQuaternion};
use std::fmt::Write as _;
use std::path::Path;

/// The trajectory file formats understood by [`read_trajectory`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// TUM RGB-D `timestamp tx ty tz qx qy qz qw`.
    Tum,
    /// EuRoC ASL ground-truth CSV (ns, w-first quaternion).
    Euroc,
    /// KITTI odometry poses (12 numbers a line).
    Kitti,
}

impl Format {
    /// Guesses the format from a file name: `.csv` is EuRoC, anything else TUM.
    /// KITTI files cannot be told from their name; ask for them explicitly.
    pub fn guess(path: &Path) -> Format {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("csv") => Format::Euroc,
            _ => Format::Tum,
        }
    }
}

/// A trajectory read from a file, with the repairs made on the way.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The poses.
    pub trajectory: Trajectory,
    /// Repairs (normalised quaternions...), to show the user.
    pub warnings: Vec<Warning>,
}

/// Relative deviation from unit norm beyond which a quaternion is reported as repaired.
const QUAT_NORM_TOLERANCE: f64 = 1e-3;
/// Largest `|R^T R - I|` of a rotation block that is re-orthonormalised (with a warning
/// beyond 1e-3); beyond it the block is refused. Besides meaning the block is no rotation, a
/// block far from one can make nalgebra's `from_matrix_eps` loop forever (a fuzzed KITTI
/// line with an entry of 7e61: its search cannot see a rotation's entries beside it).
const MAX_ORTHONORMALITY_ERROR: f64 = 0.5;
/// Norm below which a quaternion carries no rotation and the line is rejected.
const QUAT_MIN_NORM: f64 = 1e-6;

/// The file's text; a file that is not UTF-8 text (binary junk, an image passed by mistake) is
/// a parse error naming the line where the text stops being text.
fn read_text(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|cause| Error::Io {
        path: path.to_path_buf(),
        cause,
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let good = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..good].iter().filter(|&&b| b == b'\n').count() + 1;
        Error::Parse {
            path: path.to_path_buf(),
            line,
            message: format!("not a text file (invalid UTF-8 at byte {good})"),
        }
    })
}

struct LineCtx<'a> {
    path: &'a Path,
    line: usize,
}

impl LineCtx<'_> {
    fn err(&self, message: impl Into<String>) -> Error {
        Error::Parse {
            path: self.path.to_path_buf(),
            line: self.line,
            message: message.into(),
        }
    }

    fn numbers(&self, fields: &[&str]) -> Result<Vec<f64>> {
        fields
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let v: f64 = f
                    .trim()
                    .parse()
                    .map_err(|_| self.err(format!("field {} ({f:?}) is not a number", i + 1)))?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(self.err(format!("field {} is not finite ({f})", i + 1)))
                }
            })
            .collect()
    }

    /// Builds a unit quaternion from (w, x, y, z), normalising with a warning or rejecting.
    fn quaternion(
        &self,
        w: f64,
        x: f64,
        y: f64,
        z: f64,
        warnings: &mut Vec<Warning>,
    ) -> Result<UnitQuaternion<f64>> {
        let q = Quaternion::new(w, x, y, z);
        let n = q.norm();
        // Components of 1e155 and more overflow the norm: normalising by it gave a zero
        // "unit" quaternion, accepted (found by fuzzing, `0 4 4 1 7 9e201 3 0`).
        if !n.is_finite() {
            return Err(self.err(format!(
                "quaternion ({x}, {y}, {z}, {w}) has no finite norm; not a rotation"
            )));
        }
        if n < QUAT_MIN_NORM {
            return Err(self.err(format!("quaternion has near-zero norm ({n:.3e})")));
        }
        if (n - 1.0).abs() > QUAT_NORM_TOLERANCE {
            warnings.push(Warning {
                path: self.path.to_path_buf(),
                line: Some(self.line),
                message: format!("quaternion norm {n:.6} is not 1; normalised"),
            });
        }
        Ok(UnitQuaternion::from_quaternion(q))
    }
}

/// The result of a reader: an error for a file without any pose, else the rows ordered under
/// `policy` (stamps of `stamp_path`) with the repairs made.
fn loaded(
    path: &Path,
    stamp_path: &Path,
    rows: Vec<Row>,
    mut warnings: Vec<Warning>,
    policy: StampPolicy,
) -> Result<Loaded> {
    if rows.is_empty() {
        return Err(Error::Empty {
            path: path.to_path_buf(),
        });
    }
    let (trajectory, note) = stamps::arrange(stamp_path, rows, policy)?;
    warnings.extend(note);
    Ok(Loaded {
        trajectory,
        warnings,
    })
}

/// Reads a TUM trajectory, ordering its stamps under `policy` and returning the repairs made
/// as warnings.
pub fn read_tum_loaded(path: &Path, policy: StampPolicy) -> Result<Loaded> {
    let text = read_text(path)?;
    let mut rows = Vec::new();
    let mut warnings = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let ctx = LineCtx { path, line: i + 1 };
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let mut all = content
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty());
        // At most 9 fields are kept (the rest only counted): a line of a million separators
        // must not cost 16 bytes a field.
        let fields: Vec<&str> = all.by_ref().take(9).collect();
        if fields.len() != 8 {
            return Err(ctx.err(format!(
                "expected 8 fields (timestamp tx ty tz qx qy qz qw), found {}",
                fields.len() + all.count()
            )));
        }
        let v = ctx.numbers(&fields)?;
        let q = ctx.quaternion(v[7], v[4], v[5], v[6], &mut warnings)?;
        rows.push(Row {
            line: i + 1,
            stamp: v[0],
            pose: Isometry3::from_parts(Translation3::new(v[1], v[2], v[3]), q),
        });
    }
    loaded(path, path, rows, warnings, policy)
}

/// Reads a TUM trajectory (`timestamp tx ty tz qx qy qz qw`) as `evaluate_ate.py` does
/// ([`StampPolicy::LastWins`]).
pub fn read_tum(path: &Path) -> Result<Trajectory> {
    read_tum_loaded(path, StampPolicy::default()).map(|l| l.trajectory)
}

/// Reads an EuRoC ground-truth CSV, ordering its stamps under `policy` and returning repairs
/// as warnings. Stamps become seconds.
pub fn read_euroc_loaded(path: &Path, policy: StampPolicy) -> Result<Loaded> {
    let text = read_text(path)?;
    let mut rows = Vec::new();
    let mut warnings = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let ctx = LineCtx { path, line: i + 1 };
        let content = raw.trim();
        if content.is_empty() || content.starts_with('#') {
            continue;
        }
        // The first 8 fields; further columns are ignored, and never collected (a line of a
        // million commas must not cost 16 bytes a field).
        let fields: Vec<&str> = content.split(',').map(str::trim).take(8).collect();
        if fields.len() < 8 {
            return Err(ctx.err(format!(
                "expected at least 8 comma-separated fields (timestamp [ns], p xyz, q wxyz), found {}",
                fields.len()
            )));
        }
        let ns: i128 = fields[0].parse().map_err(|_| {
            ctx.err(format!(
                "timestamp {:?} is not an integer of nanoseconds",
                fields[0]
            ))
        })?;
        let v = ctx.numbers(&fields[1..8])?;
        let q = ctx.quaternion(v[3], v[4], v[5], v[6], &mut warnings)?;
        let stamp = ns_to_seconds(ns);
        rows.push(Row {
            line: i + 1,
            stamp,
            pose: Isometry3::from_parts(Translation3::new(v[0], v[1], v[2]), q),
        });
    }
    loaded(path, path, rows, warnings, policy)
}

/// Reads an EuRoC ground-truth CSV (`state_groundtruth_estimate0/data.csv`) as
/// `evaluate_ate.py` would ([`StampPolicy::LastWins`]).
pub fn read_euroc(path: &Path) -> Result<Trajectory> {
    read_euroc_loaded(path, StampPolicy::default()).map(|l| l.trajectory)
}

/// Nanoseconds to seconds without losing the sub-microsecond digits of 1e18-scale stamps
/// more than f64 must.
fn ns_to_seconds(ns: i128) -> f64 {
    let secs = ns.div_euclid(1_000_000_000);
    let rem = ns.rem_euclid(1_000_000_000);
    secs as f64 + rem as f64 * 1e-9
}

/// Reads a KITTI pose file (12 numbers a line, row-major [R | t]). Stamps come from `times`
/// (one number a line, KITTI's `times.txt`; ordered under `policy`, warnings name that file)
/// or, without it, are the frame indices 0, 1, 2...
pub fn read_kitti_loaded(path: &Path, times: Option<&Path>, policy: StampPolicy) -> Result<Loaded> {
    let text = read_text(path)?;
    let mut poses = Vec::new();
    let mut warnings = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let ctx = LineCtx { path, line: i + 1 };
        let content = raw.trim();
        if content.is_empty() || content.starts_with('#') {
            continue;
        }
        let mut all = content.split_whitespace();
        let fields: Vec<&str> = all.by_ref().take(13).collect();
        if fields.len() != 12 {
            return Err(ctx.err(format!(
                "expected 12 numbers (row-major 3x4 pose), found {}",
                fields.len() + all.count()
            )));
        }
        let v = ctx.numbers(&fields)?;
        let m = Matrix3::new(v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10]);
        let det = m.determinant();
        if det <= 1e-6 {
            return Err(ctx.err(format!(
                "rotation block has determinant {det:.3e}; not a rotation"
            )));
        }
        let orth_err = (m.transpose() * m - Matrix3::identity()).abs().max();
        if orth_err.is_nan() || orth_err > MAX_ORTHONORMALITY_ERROR {
            return Err(ctx.err(format!(
                "rotation block is far from a rotation (|R^T R - I| = {orth_err:.2e})"
            )));
        }
        if orth_err > 1e-3 {
            warnings.push(Warning {
                path: path.to_path_buf(),
                line: Some(i + 1),
                message: format!(
                    "rotation block is not orthonormal (error {orth_err:.2e}); re-orthonormalised"
                ),
            });
        }
        let rot = Rotation3::from_matrix_eps(&m, 1e-12, 100, Rotation3::identity());
        poses.push((
            i + 1,
            Isometry3::from_parts(Translation3::new(v[3], v[7], v[11]), rot.into()),
        ));
    }
    if poses.is_empty() {
        return Err(Error::Empty {
            path: path.to_path_buf(),
        });
    }
    let stamps: Vec<(usize, f64)> = match times {
        None => (0..poses.len()).map(|i| (poses[i].0, i as f64)).collect(),
        Some(tp) => {
            let t = read_text(tp)?;
            let mut out = Vec::new();
            for (i, raw) in t.lines().enumerate() {
                let content = raw.trim();
                if content.is_empty() || content.starts_with('#') {
                    continue;
                }
                let ctx = LineCtx {
                    path: tp,
                    line: i + 1,
                };
                let mut all = content.split_whitespace();
                let fields: Vec<&str> = all.by_ref().take(2).collect();
                if fields.len() != 1 {
                    return Err(ctx.err(format!(
                        "expected one timestamp, found {} fields",
                        fields.len() + all.count()
                    )));
                }
                out.push((i + 1, ctx.numbers(&fields)?[0]));
            }
            if out.len() != poses.len() {
                return Err(Error::LengthMismatch {
                    path: tp.to_path_buf(),
                    times: out.len(),
                    poses: poses.len(),
                });
            }
            out
        }
    };
    let rows = stamps
        .into_iter()
        .zip(poses)
        .map(|((line, stamp), (_, pose))| Row { line, stamp, pose })
        .collect();
    loaded(path, times.unwrap_or(path), rows, warnings, policy)
}

/// Reads a KITTI pose file as `evaluate_ate.py` would; see [`read_kitti_loaded`].
pub fn read_kitti(path: &Path, times: Option<&Path>) -> Result<Trajectory> {
    read_kitti_loaded(path, times, StampPolicy::default()).map(|l| l.trajectory)
}

/// Reads a trajectory in the given format (KITTI stamps from `kitti_times` when given),
/// ordering its stamps under `policy`.
pub fn read_trajectory(
    path: &Path,
    format: Format,
    kitti_times: Option<&Path>,
    policy: StampPolicy,
) -> Result<Loaded> {
    match format {
        Format::Tum => read_tum_loaded(path, policy),
        Format::Euroc => read_euroc_loaded(path, policy),
        Format::Kitti => read_kitti_loaded(path, kitti_times, policy),
    }
}

/// Formats a trajectory as TUM text, every number with the fewest digits that read back to the
/// same `f64`: a trajectory written and read again is the same trajectory, bit for bit (so an
/// estimate scored from its file scores as it did in memory).
pub fn format_tum(traj: &Trajectory) -> String {
    let mut s = String::with_capacity(traj.len() * 160);
    s.push_str("# timestamp tx ty tz qx qy qz qw\n");
    for (t, p) in traj.stamps.iter().zip(&traj.poses) {
        let q = p.rotation.coords; // (x, y, z, w)
        let v = p.translation.vector;
        let _ = writeln!(
            s,
            "{t} {} {} {} {} {} {} {}",
            v.x, v.y, v.z, q.x, q.y, q.z, q.w
        );
    }
    s
}

/// Formats a trajectory as an EuRoC ground-truth CSV (pose columns only).
pub fn format_euroc(traj: &Trajectory) -> String {
    let mut s = String::with_capacity(traj.len() * 128);
    s.push_str("#timestamp [ns], p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n");
    for (t, p) in traj.stamps.iter().zip(&traj.poses) {
        let q = p.rotation.coords;
        let v = p.translation.vector;
        let ns = (t * 1e9).round() as i128;
        let _ = writeln!(
            s,
            "{ns},{:.9},{:.9},{:.9},{:.9},{:.9},{:.9},{:.9}",
            v.x, v.y, v.z, q.w, q.x, q.y, q.z
        );
    }
    s
}

/// Formats a trajectory as KITTI poses (stamps are not part of the format).
pub fn format_kitti(traj: &Trajectory) -> String {
    let mut s = String::with_capacity(traj.len() * 160);
    for p in &traj.poses {
        let m = p.to_homogeneous();
        let vals: Vec<String> = (0..3)
            .flat_map(|r| (0..4).map(move |c| (r, c)))
            .map(|(r, c)| format!("{:.9e}", m[(r, c)]))
            .collect();
        s.push_str(&vals.join(" "));
        s.push('\n');
    }
    s
}

/// Writes `contents` to `path` whole or not at all ([`atomic_file::write`]), as this crate's
/// error.
fn write_whole(path: &Path, contents: &[u8]) -> Result<()> {
    atomic_file::write(path, contents).map_err(|e| match e {
        atomic_file::WriteError::Io { path, cause } => Error::Io { path, cause },
        atomic_file::WriteError::Occupied { path } => Error::Io {
            path,
            cause: std::io::Error::from(std::io::ErrorKind::AlreadyExists),
        },
    })
}

/// Writes a TUM trajectory atomically.
pub fn write_tum(path: &Path, traj: &Trajectory) -> Result<()> {
    write_whole(path, format_tum(traj).as_bytes())
}

/// Writes a trajectory in the given format atomically (KITTI drops the stamps).
pub fn write_trajectory(path: &Path, traj: &Trajectory, format: Format) -> Result<()> {
    let text = match format {
        Format::Tum => format_tum(traj),
        Format::Euroc => format_euroc(traj),
        Format::Kitti => format_kitti(traj),
    };
    write_whole(path, text.as_bytes())
}

/// Reads the `T_BS` 4x4 matrix of an EuRoC `sensor.yaml` (row-major `data: [...]`): the pose
/// of the sensor in the body (IMU) frame, needed by [`Trajectory::cam_to_body`].
pub fn read_euroc_t_bs(path: &Path) -> Result<Isometry3<f64>> {
    let text = read_text(path)?;
    let start = text.find("T_BS").ok_or_else(|| Error::Parse {
        path: path.to_path_buf(),
        line: 1,
        message: "no T_BS entry".into(),
    })?;
    let line_of = |offset: usize| text[..offset].matches('\n').count() + 1;
    let rest = &text[start..];
    let open = rest.find('[').ok_or_else(|| Error::Parse {
        path: path.to_path_buf(),
        line: line_of(start),
        message: "T_BS has no `data: [...]` list".into(),
    })?;
    let close = rest[open..].find(']').ok_or_else(|| Error::Parse {
        path: path.to_path_buf(),
        line: line_of(start + open),
        message: "T_BS data list is not closed with ']'".into(),
    })?;
    let ctx = LineCtx {
        path,
        line: line_of(start + open),
    };
    let fields: Vec<&str> = rest[open + 1..open + close]
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect();
    if fields.len() != 16 {
        return Err(ctx.err(format!("T_BS must hold 16 numbers, found {}", fields.len())));
    }
    let v = ctx.numbers(&fields)?;
    let m = Matrix3::new(v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10]);
    let orth_err = (m.transpose() * m - Matrix3::identity()).abs().max();
    if m.determinant() <= 1e-6 || orth_err.is_nan() || orth_err > MAX_ORTHONORMALITY_ERROR {
        return Err(ctx.err("T_BS rotation block is not a rotation"));
    }
    let rot = Rotation3::from_matrix_eps(&m, 1e-12, 100, Rotation3::identity());
    Ok(Isometry3::from_parts(
        Translation3::new(v[3], v[7], v[11]),
        rot.into(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn tmp_file(name: &str, contents: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("ate-eval-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, contents).unwrap();
        p
    }

    fn parse_err(e: Error) -> (usize, String) {
        match e {
            Error::Parse { line, message, .. } => (line, message),
            other => panic!("expected a parse error, got {other:?}"),
        }
    }

    #[test]
    fn tum_comments_and_whitespace() {
        let p = tmp_file(
            "ok.txt",
            "# header\n\n1.0 1 2 3 0 0 0 1\n1.5\t4  5 6 0 0 0.7071067811865476 0.7071067811865476 # trailing\n",
        );
        let t = read_tum(&p).unwrap();
        assert_eq!(t.stamps, vec![1.0, 1.5]);
        assert_eq!(t.poses[1].translation.vector.x, 4.0);
        assert!((t.poses[1].rotation.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn tum_seven_numbers_names_line() {
        let p = tmp_file("seven.txt", "1.0 1 2 3 0 0 0 1\n2.0 1 2 3 0 0 0\n");
        let e = read_tum(&p).unwrap_err();
        assert!(e.to_string().contains("seven.txt:2"), "{e}");
        let (line, msg) = parse_err(e);
        assert_eq!(line, 2);
        assert!(msg.contains("found 7"));
    }

    #[test]
    fn tum_nan_rejected() {
        let p = tmp_file("nan.txt", "1.0 1 2 3 0 0 0 1\n2.0 nan 2 3 0 0 0 1\n");
        let (line, msg) = parse_err(read_tum(&p).unwrap_err());
        assert_eq!(line, 2);
        assert!(msg.contains("not finite"), "{msg}");
    }

    #[test]
    fn tum_quaternion_normalised_with_warning_or_rejected() {
        let p = tmp_file("q.txt", "1.0 0 0 0 0 0 0 2\n2.0 0 0 0 0 0 0 1\n");
        let l = read_tum_loaded(&p, StampPolicy::default()).unwrap();
        assert_eq!(l.warnings.len(), 1);
        assert_eq!(l.warnings[0].line, Some(1));
        assert!((l.trajectory.poses[0].rotation.angle()).abs() < 1e-12);
        let p = tmp_file("q0.txt", "1.0 0 0 0 0 0 0 1e-9\n");
        let (line, msg) = parse_err(read_tum(&p).unwrap_err());
        assert_eq!(line, 1);
        assert!(msg.contains("near-zero"));
    }

    #[test]
    fn tum_unsorted_and_duplicate_rejected_when_strict() {
        let strict = |p: &Path| read_tum_loaded(p, StampPolicy::Strict).unwrap_err();
        let p = tmp_file("uns.txt", "2.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n");
        match strict(&p) {
            Error::Unsorted { line, .. } => assert_eq!(line, 2),
            e => panic!("{e:?}"),
        }
        let p = tmp_file("dup.txt", "1.0 0 0 0 0 0 0 1\n\n1.0 0 0 0 0 0 0 1\n");
        let e = strict(&p);
        assert!(e.to_string().contains("dup.txt:3"), "{e}");
    }

    #[test]
    fn tum_unsorted_and_duplicate_read_as_the_tools_do() {
        let p = tmp_file(
            "tol.txt",
            "2.0 2 0 0 0 0 0 1\n1.0 1 0 0 0 0 0 1\n\n2.0 3 0 0 0 0 0 1\n",
        );
        let l = read_tum_loaded(&p, StampPolicy::LastWins).unwrap();
        assert_eq!(l.trajectory.stamps, vec![1.0, 2.0]);
        assert_eq!(l.trajectory.poses[1].translation.vector.x, 3.0);
        assert_eq!(l.warnings.len(), 1, "one warning line per file");
        let w = l.warnings[0].to_string();
        assert!(w.starts_with(&format!("{}: ", p.display())), "{w}");
        assert!(
            w.contains("not in time order (first at line 2), sorted"),
            "{w}"
        );
        assert!(w.contains("1 repeated stamp (first at line 4)"), "{w}");
        let l = read_tum_loaded(&p, StampPolicy::KeepAll).unwrap();
        assert_eq!(l.trajectory.stamps, vec![1.0, 2.0, 2.0]);
        let x: Vec<f64> = l
            .trajectory
            .poses
            .iter()
            .map(|q| q.translation.vector.x)
            .collect();
        assert_eq!(x, vec![1.0, 2.0, 3.0]);
    }

    #[test]
    fn euroc_and_kitti_times_tolerate_repeats_and_disorder() {
        let p = tmp_file(
            "rep.csv",
            "#timestamp [ns], x, y, z, qw, qx, qy, qz\n\
             2000000000,2,0,0,1,0,0,0\n\
             1000000000,1,0,0,1,0,0,0\n\
             2000000000,3,0,0,1,0,0,0\n",
        );
        let l = read_euroc_loaded(&p, StampPolicy::LastWins).unwrap();
        assert_eq!(l.trajectory.stamps, vec![1.0, 2.0]);
        assert_eq!(l.trajectory.poses[1].translation.vector.x, 3.0);
        assert_eq!(l.warnings.len(), 1);
        match read_euroc_loaded(&p, StampPolicy::Strict).unwrap_err() {
            Error::Unsorted { line, .. } => assert_eq!(line, 3),
            e => panic!("{e:?}"),
        }
        let k = tmp_file(
            "kt.txt",
            "1 0 0 1 0 1 0 0 0 0 1 0\n1 0 0 2 0 1 0 0 0 0 1 0\n1 0 0 3 0 1 0 0 0 0 1 0\n",
        );
        let times = tmp_file("kt_times.txt", "0.2\n0.1\n0.2\n");
        let l = read_kitti_loaded(&k, Some(&times), StampPolicy::LastWins).unwrap();
        assert_eq!(l.trajectory.stamps, vec![0.1, 0.2]);
        assert_eq!(l.trajectory.poses[1].translation.vector.x, 3.0);
        let w = l.warnings[0].to_string();
        assert!(
            w.contains("kt_times.txt"),
            "the warning names the times file: {w}"
        );
        match read_kitti_loaded(&k, Some(&times), StampPolicy::Strict).unwrap_err() {
            Error::Unsorted { path, line, .. } => {
                assert_eq!(line, 2);
                assert!(path.ends_with("kt_times.txt"));
            }
            e => panic!("{e:?}"),
        }
    }

    #[test]
    fn binary_junk_names_file_and_line() {
        let dir = std::env::temp_dir().join(format!("ate-eval-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("junk.txt");
        std::fs::write(&p, b"1.0 0 0 0 0 0 0 1\n\x89PNG\r\n\x1a\n\xff\xfe").unwrap();
        let e = read_tum(&p).unwrap_err();
        assert!(e.to_string().contains("junk.txt:2: not a text file"), "{e}");
    }

    #[test]
    fn missing_file_names_path() {
        let e = read_tum(Path::new("/nonexistent/dir/gt.txt")).unwrap_err();
        assert!(matches!(e, Error::Io { .. }));
        assert!(e.to_string().contains("/nonexistent/dir/gt.txt"));
    }

    #[test]
    fn euroc_reads_ns_and_w_first() {
        let p = tmp_file(
            "gt.csv",
            "#timestamp [ns], p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], v_x\n\
             1403715274312143104,0.8,2.1,0.9,0.7071067811865476,0.7071067811865476,0,0,0.1\n\
             1403715274362142976,0.8,2.1,0.9,1,0,0,0,0.1\n",
        );
        let t = read_euroc(&p).unwrap();
        assert!((t.stamps[0] - 1_403_715_274.312_143).abs() < 1e-6);
        // f64 seconds near 1.4e9 resolve ~2.4e-7 s, as in every tool that stores stamps as doubles.
        assert!((t.stamps[1] - t.stamps[0] - 0.049999872).abs() < 1e-6);
        let axis = t.poses[0].rotation.axis().unwrap();
        assert!((axis.x - 1.0).abs() < 1e-12);
    }

    #[test]
    fn real_euroc_groundtruth_and_tum_agree() {
        let root =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/euroc_v101_head");
        if !root.exists() {
            eprintln!("skipping: {} not present", root.display());
            return;
        }
        let body = read_euroc(&root.join("mav0/state_groundtruth_estimate0/data.csv")).unwrap();
        let cam = read_tum(&root.join("groundtruth_cam0.tum.txt")).unwrap();
        let t_bs = read_euroc_t_bs(&root.join("mav0/cam0/sensor.yaml")).unwrap();
        assert_eq!(body.len(), 76);
        assert_eq!(cam.len(), body.len());
        let conv = cam.cam_to_body(&t_bs);
        for (a, b) in conv.poses.iter().zip(&body.poses) {
            assert!((a.translation.vector - b.translation.vector).norm() < 1e-5);
            assert!(a.rotation.angle_to(&b.rotation) < 1e-5);
        }
    }

    #[test]
    fn kitti_with_and_without_times() {
        let p = tmp_file(
            "k.txt",
            "1 0 0 1 0 1 0 2 0 0 1 3\n1 0 0 4 0 1 0 5 0 0 1 6\n",
        );
        let t = read_kitti(&p, None).unwrap();
        assert_eq!(t.stamps, vec![0.0, 1.0]);
        assert_eq!(t.poses[1].translation.vector.z, 6.0);
        let times = tmp_file("times.txt", "0.0\n0.1\n");
        let t = read_kitti(&p, Some(&times)).unwrap();
        assert_eq!(t.stamps, vec![0.0, 0.1]);
        let bad = tmp_file("times_bad.txt", "0.0\n");
        assert!(matches!(
            read_kitti(&p, Some(&bad)).unwrap_err(),
            Error::LengthMismatch { .. }
        ));
        let p = tmp_file("k11.txt", "1 0 0 1 0 1 0 2 0 0 1\n");
        assert_eq!(parse_err(read_kitti(&p, None).unwrap_err()).0, 1);
    }

    #[test]
    fn a_quaternion_whose_norm_overflows_is_refused() {
        // Found by fuzzing (the target's check that accepted rotations are unit): qy = 9e201
        // squared overflows, the norm is inf, and dividing by it gave (0, 0, 0, 0).
        let p = tmp_file(
            "q9e201.txt",
            "0 4 4 1 7 9e201 3 0
",
        );
        let (line, msg) = parse_err(read_tum(&p).unwrap_err());
        assert_eq!(line, 1);
        assert!(msg.contains("no finite norm"), "{msg}");
        let p = tmp_file(
            "q9e201.csv",
            "1,0,0,0,9e201,0,0,0
",
        );
        let (_, msg) = parse_err(read_euroc(&p).unwrap_err());
        assert!(msg.contains("no finite norm"), "{msg}");
    }

    #[test]
    fn a_rotation_entry_of_7e61_is_refused_not_looped_on() {
        // Found by fuzzing: nalgebra's `from_matrix_eps` never returned for this block (its
        // search cannot see a rotation's entries beside 7e61), whatever its iteration cap.
        let p = tmp_file(
            "k7e61.txt",
            "1 0 0 1 0 1 7e61 2 0 0 1 3
",
        );
        let (line, msg) = parse_err(read_kitti(&p, None).unwrap_err());
        assert_eq!(line, 1);
        assert!(msg.contains("far from a rotation"), "{msg}");
        let p = tmp_file(
            "tbs7e61.yaml",
            "T_BS:\n  data: [1, 0, 0, 0, 0, 1, 7e61, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n",
        );
        let e = read_euroc_t_bs(&p).unwrap_err().to_string();
        assert!(
            e.contains("tbs7e61.yaml:2") && e.contains("not a rotation"),
            "{e}"
        );
    }

    #[test]
    fn writers_round_trip() {
        let mut t = Trajectory::new();
        for i in 0..5 {
            let q = UnitQuaternion::from_euler_angles(0.1 * i as f64, -0.2, 0.3);
            t.push(
                1000.0 + 0.05 * i as f64,
                Isometry3::from_parts(Translation3::new(i as f64, 0.5, -1.0), q),
            );
        }
        for fmt in [Format::Tum, Format::Euroc, Format::Kitti] {
            let p = tmp_file(&format!("rt_{fmt:?}.txt"), "");
            write_trajectory(&p, &t, fmt).unwrap();
            let back = read_trajectory(&p, fmt, None, StampPolicy::Strict)
                .unwrap()
                .trajectory;
            assert_eq!(back.len(), t.len());
            for (a, b) in back.poses.iter().zip(&t.poses) {
                assert!((a.translation.vector - b.translation.vector).norm() < 1e-8);
                assert!(a.rotation.angle_to(&b.rotation) < 1e-8);
            }
            if fmt != Format::Kitti {
                for (a, b) in back.stamps.iter().zip(&t.stamps) {
                    assert!((a - b).abs() < 1e-6);
                }
            }
        }
    }
}
