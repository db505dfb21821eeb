//! End-to-end tests of `noisefree synth --trajectory FILE` (a recorded TUM trajectory replayed
//! in the synthetic room) and of the `loop` preset's registration: the real fr2_desk ground
//! truth renders, its written ground truth moves as the recording does, and bad files, too many
//! frames and unknown names fail cleanly with the file, line or duration in the message.

mod common;

use std::path::{Path, PathBuf};

use common::{assert_clean_failure, noisefree, noisefree_ok, tmpdir};

fn fr2_desk() -> Option<PathBuf> {
    let p =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/tum_fr2_desk/groundtruth.txt");
    if p.is_file() {
        Some(p)
    } else {
        eprintln!("skipping: {} not present", p.display());
        None
    }
}

/// `stamp tx ty tz qx qy qz qw` lines of a TUM trajectory file, comments skipped.
fn poses(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| l.split_whitespace().map(|f| f.parse().unwrap()).collect())
        .collect()
}

#[test]
fn renders_along_a_recorded_trajectory() {
    let Some(gt) = fr2_desk() else { return };
    let out = tmpdir("synth-recorded");
    let o = noisefree_ok(&[
        "synth",
        "--preset",
        "kinect",
        "--trajectory",
        gt.to_str().unwrap(),
        "--frames",
        "12",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    // The repeated stamp of line 10863 is tolerated with one warning line, as evaluate_ate.py.
    assert!(
        stderr.contains("warning:") && stderr.contains("1 repeated stamp"),
        "{stderr}"
    );
    let written = poses(&out.join("groundtruth.txt"));
    assert_eq!(written.len(), 12);
    // 11 frames at 30 Hz = 0.367 s of the recording: the camera moved as the file says (the
    // file's own first-to-nearby-stamp distance is the same up to interpolation, < 1 cm).
    let file = poses(&gt);
    let t0 = file[0][0];
    let near = file
        .iter()
        .min_by(|a, b| {
            ((a[0] - t0) - 11.0 / 30.0)
                .abs()
                .total_cmp(&((b[0] - t0) - 11.0 / 30.0).abs())
        })
        .unwrap();
    let dist = |a: &[f64], b: &[f64]| {
        ((a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2) + (a[3] - b[3]).powi(2)).sqrt()
    };
    let (ours, theirs) = (dist(&written[0], &written[11]), dist(&file[0], near));
    assert!((ours - theirs).abs() < 0.01, "{ours} vs {theirs}");
    assert!(ours > 0.001, "the camera moves");
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn recorded_trajectory_errors_are_clean() {
    let dir = tmpdir("synth-bad-trajectory");
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.txt");
    std::fs::write(
        &bad,
        "# timestamp tx ty tz qx qy qz qw\n1.0 0 0 1 0 0 0 1\n1.1 0 0 1 0 0 0\n",
    )
    .unwrap();
    let out = dir.join("out");
    let o = noisefree(&[
        "synth",
        "--trajectory",
        bad.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_clean_failure(&o, "bad.txt:3:");
    assert!(!out.exists(), "no partial output");
    let o = noisefree(&[
        "synth",
        "--trajectory",
        "figure-of-eight",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_clean_failure(&o, "loop");
    if let Some(gt) = fr2_desk() {
        let o = noisefree(&[
            "synth",
            "--trajectory",
            gt.to_str().unwrap(),
            "--frames",
            "5000",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_clean_failure(&o, "lasts 99.365 s");
        assert!(!out.exists(), "no partial output");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn loop_preset_is_registered() {
    let out = tmpdir("synth-loop");
    noisefree_ok(&[
        "synth",
        "--preset",
        "loop",
        "--frames",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(poses(&out.join("groundtruth.txt")).len(), 3);
    std::fs::remove_dir_all(&out).unwrap();
    // `run --seq loop` finds it in the catalog (a few frames; by default the whole circuit).
    let run = tmpdir("run-loop");
    let o = noisefree_ok(&[
        "run",
        "--seq",
        "loop",
        "--frames",
        "8",
        "--quiet",
        "--out",
        run.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("loop"));
    std::fs::remove_dir_all(&run).unwrap();
    let help = noisefree_ok(&["synth", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains("loop") && help.contains("TUM trajectory file"),
        "{help}"
    );
}
