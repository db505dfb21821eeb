//! Recorded camera paths: a TUM-format trajectory file (`stamp tx ty tz qx qy qz qw`,
//! camera-to-world, camera x right, y down, z forward) read, levelled and placed inside the
//! synthetic room, then sampled at any time by interpolation — so a sequence can be rendered
//! along a real hand-held motion (e.g. TUM fr2_desk's ground truth) instead of a built-in curve.
//!
//! The fit, in order (never a scale: a path that does not fit is refused with its extents):
//! 1. *Level*: the world "down" direction is estimated from the cameras' axes, assuming a
//!    hand-held camera is held roughly upright: the mean of the camera y axes gives "down" and
//!    its sign, and because an upright camera's x axis is horizontal however it pitches, the
//!    components of that mean along the plane the x axes span are removed (a camera looking
//!    down at a desk from one side tilts the plain mean y by its pitch: 13 degrees on TUM
//!    fr2_desk, against under 4 degrees after the correction). The smallest rotation taking
//!    "down" to -z (the room's z is up) is applied to the whole path.
//! 2. *Heading*: the yaw about the vertical (in [`YAW_STEP_DEG`] steps) is chosen among those
//!    whose bounding box fits the square room with [`ROOM_MARGIN`] to the walls, as the one
//!    that keeps the camera farthest from the room's furniture
//!    ([`crate::world::layout::furniture_clearance`]).
//! 3. *Place*: a translation puts the centre of the path's bounding box at the room's centre
//!    in x, y and at [`TARGET_HEIGHT`] in z (shifted within the room if the height range needs
//!    it). Every camera position lies at least [`ROOM_MARGIN`] from the walls, floor and
//!    ceiling.
//!
//! Time is the recording's own: seconds since its first stamp. Between two stamps the
//! translation is interpolated linearly and the rotation by slerp; at a stamp the pose is the
//! file's (after the fit) exactly. Reading follows TUM's `evaluate_ate.py`: `#` lines and blank
//! lines are skipped, commas and tabs separate fields like spaces, lines are sorted by stamp and
//! a repeated stamp keeps its last line. Anything else that is not a finite pose (wrong field
//! count, NaN, a zero quaternion) is an error naming the file and line.

use std::path::Path;

use nalgebra::{Isometry3, Matrix3, Quaternion, Translation3, UnitQuaternion, Vector3};

use crate::error::SynthError;
use crate::world::layout::{furniture_clearance, ROOM_HALF, ROOM_HEIGHT};

/// Height of the centre of a recorded path's bounding box after the fit, metres (hand-held).
pub const TARGET_HEIGHT: f64 = 1.3;
/// Minimum distance of every camera position from the walls, floor and ceiling, metres.
pub const ROOM_MARGIN: f64 = 0.45;
/// Below this length of the mean camera y axis (or of its part off the cameras' x axes) the
/// path has no usable "down" direction.
pub const MIN_DOWN_AGREEMENT: f64 = 0.25;
/// Step of the headings tried when placing a path, degrees.
pub const YAW_STEP_DEG: f64 = 2.0;
/// At most this many camera positions (evenly spaced) are tested for furniture clearance per
/// heading; the chosen heading's clearance is then measured on all of them.
const CLEARANCE_SAMPLES: usize = 1000;

/// A recorded camera path fitted into the synthetic room (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct RecordedPath {
    label: String,
    times: Vec<f64>,
    poses: Vec<Isometry3<f64>>,
    fit: Isometry3<f64>,
    repeated: usize,
    unsorted: bool,
    down_agreement: f64,
    yaw: f64,
    clearance: f64,
}

/// One parsed line: stamp, pose, 1-based line number.
struct Entry {
    stamp: f64,
    pose: Isometry3<f64>,
    line: usize,
}

fn parse_err(path: &Path, line: usize, message: impl Into<String>) -> SynthError {
    SynthError::Parse {
        path: path.to_path_buf(),
        line,
        message: message.into(),
    }
}

/// Parses TUM trajectory text into entries in file order.
fn parse_lines(text: &str, origin: &Path) -> Result<Vec<Entry>, SynthError> {
    let mut out = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let s = raw.trim();
        if s.is_empty() || s.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = s
            .split([' ', ',', '\t'])
            .filter(|f| !f.is_empty())
            .collect();
        if fields.len() != 8 {
            return Err(parse_err(
                origin,
                line,
                format!(
                    "expected 8 fields 'stamp tx ty tz qx qy qz qw', found {}",
                    fields.len()
                ),
            ));
        }
        let mut v = [0.0f64; 8];
        for (i, f) in fields.iter().enumerate() {
            let x: f64 = f.parse().map_err(|_| {
                parse_err(
                    origin,
                    line,
                    format!("field {} '{f}' is not a number", i + 1),
                )
            })?;
            if !x.is_finite() {
                return Err(parse_err(
                    origin,
                    line,
                    format!("field {} is {f}: every value must be finite", i + 1),
                ));
            }
            v[i] = x;
        }
        let q = Quaternion::new(v[7], v[4], v[5], v[6]);
        let n = q.norm();
        if n <= 1e-6 {
            return Err(parse_err(
                origin,
                line,
                format!(
                    "quaternion ({} {} {} {}) has zero length",
                    v[4], v[5], v[6], v[7]
                ),
            ));
        }
        let pose = Isometry3::from_parts(
            Translation3::new(v[1], v[2], v[3]),
            UnitQuaternion::new_normalize(q),
        );
        out.push(Entry {
            stamp: v[0],
            pose,
            line,
        });
    }
    Ok(out)
}

/// Linear interpolation of translations and slerp of rotations, `alpha` in [0, 1]. Robust for
/// nearly equal and for opposite rotations (takes the short way; never panics).
pub fn interpolate(a: &Isometry3<f64>, b: &Isometry3<f64>, alpha: f64) -> Isometry3<f64> {
    let t = a.translation.vector + (b.translation.vector - a.translation.vector) * alpha;
    let delta = a.rotation.inverse() * b.rotation;
    let r = a.rotation * UnitQuaternion::from_scaled_axis(delta.scaled_axis() * alpha);
    Isometry3::from_parts(Translation3::from(t), r)
}

impl RecordedPath {
    /// Reads a TUM trajectory file and fits it into the room. Errors name the file (and the
    /// line, for malformed lines).
    pub fn load(path: &Path) -> Result<RecordedPath, SynthError> {
        let text = std::fs::read_to_string(path).map_err(|source| SynthError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        RecordedPath::parse(&text, path)
    }

    /// Parses TUM trajectory text (`origin` names it in errors and becomes the label) and fits
    /// it into the room.
    pub fn parse(text: &str, origin: &Path) -> Result<RecordedPath, SynthError> {
        let mut entries = parse_lines(text, origin)?;
        let unsorted = entries.windows(2).any(|w| w[1].stamp < w[0].stamp);
        // Stable: among equal stamps the file order is kept, so the last line wins below.
        entries.sort_by(|a, b| a.stamp.total_cmp(&b.stamp));
        let mut kept: Vec<Entry> = Vec::with_capacity(entries.len());
        let mut repeated = 0;
        for e in entries {
            match kept.last_mut() {
                Some(last) if last.stamp == e.stamp => {
                    *last = e;
                    repeated += 1;
                }
                _ => kept.push(e),
            }
        }
        if kept.len() < 2 {
            return Err(SynthError::TrajectoryFit {
                path: origin.to_path_buf(),
                message: format!(
                    "needs at least 2 poses with distinct stamps, found {}",
                    kept.len()
                ),
            });
        }
        let t0 = kept[0].stamp;
        let mut times = Vec::with_capacity(kept.len());
        for (i, e) in kept.iter().enumerate() {
            let t = e.stamp - t0;
            if i > 0 && t <= times[i - 1] {
                return Err(parse_err(
                    origin,
                    e.line,
                    format!(
                        "stamp {} is not after the previous one ({}) at f64 precision",
                        e.stamp,
                        kept[i - 1].stamp
                    ),
                ));
            }
            times.push(t);
        }
        let raw: Vec<Isometry3<f64>> = kept.iter().map(|e| e.pose).collect();
        let placement = fit_into_room(&raw, origin)?;
        let fit = placement.fit;
        let poses: Vec<Isometry3<f64>> = raw.iter().map(|p| fit * p).collect();
        let clearance = poses
            .iter()
            .map(|p| furniture_clearance(&p.translation.vector))
            .fold(f64::INFINITY, f64::min);
        Ok(RecordedPath {
            label: origin.display().to_string(),
            times,
            poses,
            fit,
            repeated,
            unsorted,
            down_agreement: placement.down_agreement,
            yaw: placement.yaw,
            clearance,
        })
    }

    /// Where the path came from (the file name as given), for headers and messages.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// Number of poses kept (after dropping repeated stamps).
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// Always false: a path has at least two poses.
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// Seconds from the first to the last stamp.
    pub fn duration(&self) -> f64 {
        self.times.last().copied().unwrap_or(0.0)
    }

    /// Time of each kept pose, seconds since the first stamp (strictly increasing).
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// The kept poses after the fit (camera-to-room), one per entry of [`RecordedPath::times`].
    pub fn poses(&self) -> &[Isometry3<f64>] {
        &self.poses
    }

    /// The rigid transform applied to the file's poses: room_from_recording (levelling
    /// rotation, then placement); fitted pose = `fit * file pose`.
    pub fn fit(&self) -> Isometry3<f64> {
        self.fit
    }

    /// Length of the mean camera y axis, 0..1: how well the cameras agree on "down" (about 1
    /// for a camera held upright).
    pub fn down_agreement(&self) -> f64 {
        self.down_agreement
    }

    /// The heading (yaw about the vertical, radians) chosen when placing the path.
    pub fn yaw(&self) -> f64 {
        self.yaw
    }

    /// Smallest distance of a camera position from the room's furniture, metres (negative:
    /// the camera passes through a piece of furniture at every heading that fits).
    pub fn clearance(&self) -> f64 {
        self.clearance
    }

    /// One line describing the fit: poses, duration, extents, heading, clearance.
    pub fn summary(&self) -> String {
        let (lo, hi) = self.bounds();
        let e = hi - lo;
        format!(
            "{}: {} poses over {:.2} s, levelled (down agreement {:.2}) and turned {:.0} deg, \
             spans {:.2} x {:.2} x {:.2} m at heights {:.2}..{:.2} m, {:.2} m from the nearest \
             furniture",
            self.label,
            self.len(),
            self.duration(),
            self.down_agreement,
            self.yaw.to_degrees(),
            e.x,
            e.y,
            e.z,
            lo.z,
            hi.z,
            self.clearance
        )
    }

    /// Lines dropped because their stamp repeated an earlier one (the last one is kept).
    pub fn repeated_stamps(&self) -> usize {
        self.repeated
    }

    /// Whether the file's stamps were out of order (they were sorted).
    pub fn was_unsorted(&self) -> bool {
        self.unsorted
    }

    /// One line saying what reading tolerated (repeated or unsorted stamps), if anything.
    pub fn warning(&self) -> Option<String> {
        let mut parts = Vec::new();
        if self.repeated > 0 {
            parts.push(format!(
                "{} repeated stamp(s), kept the last line of each",
                self.repeated
            ));
        }
        if self.unsorted {
            parts.push("stamps out of order, sorted".to_string());
        }
        (!parts.is_empty()).then(|| {
            format!(
                "{}: {} (as TUM's evaluate_ate.py reads it)",
                self.label,
                parts.join("; ")
            )
        })
    }

    /// Axis-aligned bounding box (min, max) of the fitted camera positions, metres.
    pub fn bounds(&self) -> (Vector3<f64>, Vector3<f64>) {
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for p in &self.poses {
            lo = lo.inf(&p.translation.vector);
            hi = hi.sup(&p.translation.vector);
        }
        (lo, hi)
    }

    /// Camera-to-room pose at `t` seconds since the first stamp: the fitted pose of a stamp
    /// exactly at a stamp, else interpolated between the two bracketing stamps. Outside the
    /// recording `t` is clamped to it (callers check the duration first: the generator's
    /// `check_frames`).
    pub fn pose_at(&self, t: f64) -> Isometry3<f64> {
        let last = self.poses.len() - 1;
        if t.is_nan() || t <= 0.0 {
            return self.poses[0];
        }
        if t >= self.times[last] {
            return self.poses[last];
        }
        // times[i] <= t < times[i + 1]
        let i = self.times.partition_point(|&x| x <= t) - 1;
        if self.times[i] == t {
            return self.poses[i];
        }
        let alpha = (t - self.times[i]) / (self.times[i + 1] - self.times[i]);
        interpolate(&self.poses[i], &self.poses[i + 1], alpha)
    }
}

/// The result of [`fit_into_room`].
struct Placement {
    fit: Isometry3<f64>,
    down_agreement: f64,
    yaw: f64,
}

/// The world's down direction from camera-to-world rotations (see the module documentation):
/// the mean camera y axis without its components in the span of the camera x axes. `None`
/// when nothing usable is left.
fn estimate_down(rotations: &[UnitQuaternion<f64>]) -> (Option<Vector3<f64>>, f64) {
    let n = rotations.len() as f64;
    let mean_y = rotations
        .iter()
        .map(|r| r * Vector3::y())
        .sum::<Vector3<f64>>()
        / n;
    let scatter = rotations
        .iter()
        .map(|r| {
            let x = r * Vector3::x();
            x * x.transpose()
        })
        .sum::<Matrix3<f64>>()
        / n;
    let eig = scatter.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let [l1, l2, l3] = order.map(|k| eig.eigenvalues[k]);
    let v = |k: usize| eig.eigenvectors.column(order[k]).into_owned();
    // The x axes span a plane (normal: down) or, for a camera that hardly turns, a line.
    let spanned: Vec<Vector3<f64>> = if l2 > 5.0 * l3 {
        vec![v(0), v(1)]
    } else if l1 > 5.0 * l2 {
        vec![v(0)]
    } else {
        Vec::new()
    };
    let down = spanned.iter().fold(mean_y, |d, a| d - a * a.dot(&mean_y));
    let agreement = mean_y.norm();
    let usable = agreement >= MIN_DOWN_AGREEMENT && down.norm() >= MIN_DOWN_AGREEMENT;
    (usable.then(|| down.normalize()), agreement)
}

/// The levelling + heading + placement transform of `poses` (see the module documentation);
/// refuses paths without a down direction or too large for the room at every heading.
fn fit_into_room(poses: &[Isometry3<f64>], origin: &Path) -> Result<Placement, SynthError> {
    let fit_err = |message: String| SynthError::TrajectoryFit {
        path: origin.to_path_buf(),
        message,
    };
    let rotations: Vec<UnitQuaternion<f64>> = poses.iter().map(|p| p.rotation).collect();
    let (down, agreement) = estimate_down(&rotations);
    let Some(down) = down else {
        return Err(fit_err(format!(
            "the cameras' y axes do not agree on a down direction (mean length {agreement:.2}, \
             need {MIN_DOWN_AGREEMENT}): not a camera held roughly upright, cannot level the path"
        )));
    };
    let level = UnitQuaternion::rotation_between(&down, &-Vector3::z()).unwrap_or_else(|| {
        // `down` is +z: any half turn about a horizontal axis.
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    });
    let levelled: Vec<Vector3<f64>> = poses.iter().map(|p| level * p.translation.vector).collect();
    let stride = levelled.len().div_ceil(CLEARANCE_SAMPLES).max(1);
    let room = Vector3::new(2.0 * ROOM_HALF, 2.0 * ROOM_HALF, ROOM_HEIGHT);
    let usable = room - Vector3::repeat(2.0 * ROOM_MARGIN);
    // (yaw, shift, min clearance) of the best heading that fits; the smallest extents seen.
    let mut best: Option<(f64, Vector3<f64>, f64)> = None;
    let mut tightest: Option<Vector3<f64>> = None;
    let steps = (360.0 / YAW_STEP_DEG).round() as usize;
    for k in 0..steps {
        let yaw = (k as f64 * YAW_STEP_DEG).to_radians();
        let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw);
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for p in &levelled {
            let q = turn * p;
            lo = lo.inf(&q);
            hi = hi.sup(&q);
        }
        let extent = hi - lo;
        if tightest.is_none_or(|t| extent.x.max(extent.y) < t.x.max(t.y)) {
            tightest = Some(extent);
        }
        if extent.x > usable.x || extent.y > usable.y || extent.z > usable.z {
            continue;
        }
        // Centre height: TARGET_HEIGHT, moved as little as needed to keep the margin.
        let (z_lo, z_hi) = (
            ROOM_MARGIN + extent.z / 2.0,
            ROOM_HEIGHT - ROOM_MARGIN - extent.z / 2.0,
        );
        let target = Vector3::new(0.0, 0.0, TARGET_HEIGHT.clamp(z_lo, z_hi));
        let shift = target - (lo + hi) / 2.0;
        let clearance = levelled
            .iter()
            .step_by(stride)
            .map(|p| furniture_clearance(&(turn * p + shift)))
            .fold(f64::INFINITY, f64::min);
        if best.is_none_or(|(_, _, c)| clearance > c) {
            best = Some((yaw, shift, clearance));
        }
    }
    let Some((yaw, shift, _)) = best else {
        let e = tightest.unwrap_or_default();
        return Err(fit_err(format!(
            "the camera path spans {:.2} x {:.2} x {:.2} m (x, y, z after levelling, at the \
             heading that suits the square room best); the synthetic room holds at most \
             {:.2} x {:.2} x {:.2} m ({:.1} x {:.1} x {:.1} m room, {ROOM_MARGIN} m margin). \
             Paths are never scaled: use a shorter or smaller part of the recording",
            e.x, e.y, e.z, usable.x, usable.y, usable.z, room.x, room.y, room.z
        )));
    };
    let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw);
    Ok(Placement {
        fit: Translation3::from(shift)
            * Isometry3::from_parts(Translation3::identity(), turn * level),
        down_agreement: agreement,
        yaw,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(stamp: f64, p: &Isometry3<f64>) -> String {
        let t = p.translation.vector;
        let q = p.rotation.quaternion();
        format!(
            "{stamp} {} {} {} {} {} {} {}\n",
            t.x, t.y, t.z, q.i, q.j, q.k, q.w
        )
    }

    /// A camera held upright in a world whose up is +y (so the fit must level it).
    fn tilted_world_path() -> String {
        let mut s = String::from("# stamp tx ty tz qx qy qz qw\n");
        for i in 0..50 {
            let a = i as f64 * 0.05;
            // Upright in a y-up world: the half turn about z maps camera y (down) to world
            // -y, and yawing about world y keeps it there.
            let yaw = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), a);
            let flip = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI);
            let p = Isometry3::from_parts(
                Translation3::new(10.0 + a.cos(), 5.0 + 0.1 * a, -3.0 + a.sin()),
                yaw * flip,
            );
            s += &line(100.0 + i as f64 * 0.1, &p);
        }
        s
    }

    #[test]
    fn levels_and_centres_a_path() {
        let p = RecordedPath::parse(&tilted_world_path(), Path::new("t.txt")).unwrap();
        assert_eq!(p.len(), 50);
        assert!((p.duration() - 4.9).abs() < 1e-9);
        assert!(p.down_agreement() > 0.999);
        for q in p.poses() {
            let y = q.rotation * Vector3::y();
            assert!((y + Vector3::z()).norm() < 1e-9, "{y}");
        }
        let (lo, hi) = p.bounds();
        let c = (lo + hi) / 2.0;
        assert!(
            (c - Vector3::new(0.0, 0.0, TARGET_HEIGHT)).norm() < 1e-9,
            "{c}"
        );
    }

    #[test]
    fn interpolates_between_stamps_and_hits_them_exactly() {
        let p = RecordedPath::parse(&tilted_world_path(), Path::new("t.txt")).unwrap();
        assert_eq!(p.pose_at(p.times()[7]), p.poses()[7]);
        let mid = p.pose_at((p.times()[7] + p.times()[8]) / 2.0);
        let (a, b) = (p.poses()[7], p.poses()[8]);
        let tm = (a.translation.vector + b.translation.vector) / 2.0;
        assert!((mid.translation.vector - tm).norm() < 1e-12);
        let ang = a.rotation.angle_to(&b.rotation);
        assert!((a.rotation.angle_to(&mid.rotation) - ang / 2.0).abs() < 1e-12);
        assert!((b.rotation.angle_to(&mid.rotation) - ang / 2.0).abs() < 1e-12);
        // Clamped outside, no panic.
        assert_eq!(p.pose_at(-1.0), p.poses()[0]);
        assert_eq!(p.pose_at(1e9), p.poses()[49]);
        assert_eq!(p.pose_at(f64::NAN), p.poses()[0]);
    }

    #[test]
    fn repeated_and_unsorted_stamps_are_read_like_evaluate_ate() {
        let text = "1.0 0 0 1 0 0 0 1\n\
                    3.0 0.2 0 1 0 0 0 1\n\
                    2.0 0.1 0 1 0 0 0 1\n\
                    2.0 0.15 0 1 0 0 0 1\n";
        let p = RecordedPath::parse(text, Path::new("r.txt")).unwrap();
        assert_eq!(p.times(), &[0.0, 1.0, 2.0]);
        assert_eq!(p.repeated_stamps(), 1);
        assert!(p.was_unsorted());
        let d = p.poses()[1].translation.vector - p.poses()[0].translation.vector;
        assert!((d.norm() - 0.15).abs() < 1e-12, "last of the repeats kept");
        let w = p.warning().unwrap();
        assert!(w.contains("r.txt") && w.contains("1 repeated"), "{w}");
    }

    #[test]
    fn bad_lines_name_file_and_line() {
        let cases = [
            ("1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n", ":2:", "8 fields"),
            ("# c\n1 0 0 0 0 0 0 1\n2 0 nan 0 0 0 0 1\n", ":3:", "finite"),
            ("1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 0\n", ":2:", "zero length"),
            ("1 0 0 0 0 0 0 1\n2 0 x 0 0 0 0 1\n", ":2:", "not a number"),
            ("1 0 0 0 0 0 0 1\ninf 0 0 0 0 0 0 1\n", ":2:", "finite"),
        ];
        for (text, at, what) in cases {
            let e = RecordedPath::parse(text, Path::new("bad.txt"))
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("bad.txt") && e.contains(at) && e.contains(what),
                "{e}"
            );
        }
        let e = RecordedPath::parse("1 0 0 0 0 0 0 1\n", Path::new("one.txt"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("one.txt") && e.contains("at least 2"), "{e}");
    }

    #[test]
    fn refuses_paths_larger_than_the_room_with_extents() {
        let text = "0 0 0 0 0 0 0 1\n1 0 0 6.5 0 0 0 1\n";
        let e = RecordedPath::parse(text, Path::new("big.txt"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("big.txt") && e.contains("spans 4.") && e.contains("never scaled"),
            "{e}"
        );
        // No agreed down direction: half the cameras upside down.
        let text = "0 0 0 0 0 0 0 1\n1 0 0 0.1 0 0 1 0\n";
        let e = RecordedPath::parse(text, Path::new("flip.txt"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("flip.txt") && e.contains("down"), "{e}");
    }

    #[test]
    fn interpolate_survives_opposite_and_equal_rotations() {
        let a = Isometry3::identity();
        let b = Isometry3::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI),
        );
        let m = interpolate(&a, &b, 0.5);
        assert!((m.rotation.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert_eq!(interpolate(&a, &a, 0.3), a);
    }
}
