//! Recorded trajectories on real data: TUM fr2_desk's ground truth (`shared/data/tum_fr2_desk`,
//! beside the repository; 20,957 poses over 99 s, one repeated stamp) read, fitted into the
//! room and replayed. Checks that the fitted path stays in the room, that the poses at the
//! file's stamps reproduce the file's relative motions to 1e-9, that the generator refuses
//! frames beyond the recording, and that bad files fail with file:line.

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use synth::motion::recorded::ROOM_MARGIN;
use synth::world::layout::{ROOM_HALF, ROOM_HEIGHT};
use synth::{Generator, RecordedPath, SynthConfig, SynthError, Trajectory};

fn fr2_desk() -> PathBuf {
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let candidates = [
        std::env::var_os("NOISEFREE_FR2_DESK").map(PathBuf::from),
        Some(here.join("../../../shared/data/tum_fr2_desk")),
        Some(PathBuf::from("/work/shared/data/tum_fr2_desk")),
    ];
    candidates
        .into_iter()
        .flatten()
        .map(|d| d.join("groundtruth.txt"))
        .find(|p| p.is_file())
        .expect(
            "fr2_desk ground truth not found: set NOISEFREE_FR2_DESK to shared/data/tum_fr2_desk",
        )
}

/// The file read independently of the crate: stamp -> pose, the last line of a repeated stamp
/// winning, sorted by stamp (as evaluate_ate.py reads it).
fn read_plain(path: &Path) -> Vec<(f64, Isometry3<f64>)> {
    let text = std::fs::read_to_string(path).unwrap();
    // Keyed by the stamp's bits: for positive stamps their order is the numeric order.
    let mut rows = std::collections::BTreeMap::new();
    for line in text.lines() {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let v: Vec<f64> = line
            .split_whitespace()
            .map(|f| f.parse().unwrap())
            .collect();
        let q = UnitQuaternion::new_normalize(Quaternion::new(v[7], v[4], v[5], v[6]));
        let p = Isometry3::from_parts(Translation3::new(v[1], v[2], v[3]), q);
        rows.insert(v[0].to_bits(), p);
    }
    rows.into_iter()
        .map(|(s, p)| (f64::from_bits(s), p))
        .collect()
}

fn recorded(path: &Path) -> std::sync::Arc<RecordedPath> {
    match Trajectory::from_arg(path.to_str().unwrap()).unwrap() {
        Trajectory::Recorded(r) => r,
        other => panic!("{other:?}"),
    }
}

#[test]
fn fr2_desk_is_read_like_evaluate_ate_and_fits_the_room() {
    let file = fr2_desk();
    let path = recorded(&file);
    assert_eq!(path.len(), 20_956, "20,957 lines, one repeated stamp");
    assert_eq!(path.repeated_stamps(), 1);
    assert!(path.warning().unwrap().contains("1 repeated stamp"));
    assert!(
        (path.duration() - 99.4).abs() < 0.5,
        "{} s",
        path.duration()
    );
    assert!(path.down_agreement() > 0.5, "{}", path.down_agreement());
    eprintln!("{}", path.summary());
    let lim = ROOM_HALF - ROOM_MARGIN;
    for p in path.poses() {
        let e = p.translation.vector;
        assert!(e.x.abs() <= lim + 1e-9 && e.y.abs() <= lim + 1e-9, "{e}");
        assert!(e.z >= ROOM_MARGIN - 1e-9 && e.z <= ROOM_HEIGHT - ROOM_MARGIN + 1e-9);
    }
    // Sampled between stamps as well: still inside (lerp of inside points).
    for k in 0..2000 {
        let e = path
            .pose_at(path.duration() * k as f64 / 1999.0)
            .translation
            .vector;
        assert!(e.x.abs() <= lim + 1e-9 && e.y.abs() <= lim + 1e-9, "{e}");
    }
}

#[test]
fn fr2_desk_relative_motions_are_the_files() {
    let file = fr2_desk();
    let path = recorded(&file);
    let rows = read_plain(&file);
    assert_eq!(rows.len(), path.len());
    let t0 = rows[0].0;
    let at = |i: usize| path.pose_at(rows[i].0 - t0);
    let n = rows.len();
    let mut pairs: Vec<(usize, usize)> = (0..n - 1).step_by(37).map(|i| (i, i + 1)).collect();
    pairs.extend((0..n - 300).step_by(997).map(|i| (i, i + 300)));
    pairs.extend([(0, n - 1), (0, n / 2), (n / 3, n - 2), (10_859, 10_862)]);
    let mut worst = (0.0f64, 0.0f64);
    for (i, j) in pairs {
        let ours = at(i).inverse() * at(j);
        let file = rows[i].1.inverse() * rows[j].1;
        let d = file.inverse() * ours;
        worst.0 = worst.0.max(d.translation.vector.norm());
        worst.1 = worst.1.max(d.rotation.angle());
    }
    assert!(
        worst.0 < 1e-9 && worst.1 < 1e-9,
        "relative pose off by {} m, {} rad",
        worst.0,
        worst.1
    );
    // Half-way between two stamps: half-way in translation and rotation.
    let (a, b) = (at(5000), at(5001));
    let mid = path.pose_at(((rows[5000].0 - t0) + (rows[5001].0 - t0)) / 2.0);
    let tm = (a.translation.vector + b.translation.vector) / 2.0;
    assert!((mid.translation.vector - tm).norm() < 1e-9);
    let half = a.rotation.angle_to(&b.rotation) / 2.0;
    assert!((a.rotation.angle_to(&mid.rotation) - half).abs() < 1e-9);
}

#[test]
fn generator_replays_the_recording_and_refuses_frames_beyond_it() {
    let file = fr2_desk();
    let mut cfg = SynthConfig::preset("kinect").unwrap();
    cfg.trajectory = Trajectory::from_arg(file.to_str().unwrap()).unwrap();
    let Trajectory::Recorded(path) = cfg.trajectory.clone() else {
        unreachable!()
    };
    let gen = Generator::try_new(cfg.clone(), 1).unwrap();
    for i in [0usize, 1, 599, 2000] {
        assert_eq!(gen.pose(i), path.pose_at(gen.time(i)));
    }
    gen.check_frames(600).unwrap();
    let max = match gen.check_frames(4000) {
        Err(e @ SynthError::TrajectoryTooShort { max_frames, .. }) => {
            let msg = e.to_string();
            assert!(
                msg.contains("groundtruth.txt") && msg.contains("lasts 99."),
                "{msg}"
            );
            max_frames
        }
        other => panic!("{other:?}"),
    };
    gen.check_frames(max).unwrap();
    assert!(gen.check_frames(max + 1).is_err());
    assert!((max as f64 - path.duration() * 30.0).abs() <= 2.0, "{max}");
    // Motion scale 2: half the frames.
    cfg.motion_scale = 2.0;
    let fast = Generator::try_new(cfg, 1).unwrap();
    assert!(fast.check_frames(max / 2).is_ok() && fast.check_frames(max / 2 + 2).is_err());
    assert_eq!(fast.pose(300), path.pose_at(fast.time(300) * 2.0));
}

#[test]
fn bad_files_fail_with_file_and_line() {
    let file = fr2_desk();
    let text = std::fs::read_to_string(&file).unwrap();
    let dir = std::env::temp_dir().join(format!("synth-recorded-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let corrupt = |line: usize, with: &str, name: &str| -> String {
        let mut lines: Vec<&str> = text.lines().collect();
        lines[line - 1] = with;
        let p = dir.join(name);
        std::fs::write(&p, lines.join("\n")).unwrap();
        Trajectory::from_arg(p.to_str().unwrap())
            .unwrap_err()
            .to_string()
    };
    let e = corrupt(500, "1311868180.2 0.1 nan 1.4 0.6 -0.5 0.3 -0.4", "nan.txt");
    assert!(e.contains("nan.txt:500:") && e.contains("finite"), "{e}");
    let e = corrupt(777, "1311868180.2 0.1 0.2 1.4 0.6 -0.5 0.3", "short.txt");
    assert!(e.contains("short.txt:777:") && e.contains("found 7"), "{e}");
    let e = corrupt(20_000, "1311868180.2 0.1 0.2 1.4 0 0 0 0", "zero.txt");
    assert!(
        e.contains("zero.txt:20000:") && e.contains("zero length"),
        "{e}"
    );
    // Not a file, not a name: the valid names.
    let e = Trajectory::from_arg(dir.join("missing.txt").to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("xyz") && e.contains("loop") && e.contains("TUM"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
