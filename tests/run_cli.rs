//! End-to-end tests of `noisefree run`: the embedded synthetic default, its outputs, bit-exact
//! reproducibility from a seed, and clean errors on bad input.

mod common;

use common::{assert_clean_failure, noisefree, tmpdir};

#[test]
fn default_run_writes_outputs_and_is_reproducible() {
    let a = tmpdir("a");
    let b = tmpdir("b");
    for d in [&a, &b] {
        let out = noisefree(&[
            "run",
            "--frames",
            "60",
            "--quiet",
            "--out",
            d.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains("kinect [orb] seed 0: ATE RMSE"), "{stdout}");
    }
    let traj_a = std::fs::read(a.join("trajectory.txt")).unwrap();
    assert_eq!(
        traj_a,
        std::fs::read(b.join("trajectory.txt")).unwrap(),
        "same seed, same bytes"
    );
    let t = ate_eval::io::read_tum(&a.join("trajectory.txt")).unwrap();
    assert_eq!(t.len(), 60, "every frame tracked");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("summary.json")).unwrap()).unwrap();
    let ate = summary["ate_rmse_m"].as_f64().unwrap();
    // The kinect preset with an ORB-SLAM2-class baseline: millimetres, well under 3 cm.
    assert!(ate < 0.03, "ATE {ate}");
    let frames = std::fs::read_to_string(a.join("frames.csv")).unwrap();
    assert_eq!(frames.lines().count(), 61);
    assert!(frames.starts_with("timestamp,state,n_keypoints,n_matches,n_inliers,n_outliers"));
}

#[test]
fn several_runs_write_a_folder_each_and_a_summary() {
    let d = tmpdir("multi");
    let out = noisefree(&[
        "run",
        "--seq",
        "clean",
        "--frames",
        "30",
        "--runs",
        "2",
        "--quiet",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(d.join("seed0/trajectory.txt").exists() && d.join("seed1/trajectory.txt").exists());
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["runs"].as_array().unwrap().len(), 2);
}

#[test]
fn unknown_sequence_suggests_names() {
    let out = noisefree(&["run", "--seq", "fr2_cok", "--quiet"]);
    assert_clean_failure(&out, "fr2_coke");
}

#[test]
fn missing_folder_and_missing_dataset_are_clean_errors() {
    let out = noisefree(&["run", "--path", "/no/such/sequence", "--quiet"]);
    assert_clean_failure(&out, "/no/such/sequence");
    let empty = tmpdir("data");
    std::fs::create_dir_all(&empty).unwrap();
    let out = noisefree(&[
        "run",
        "--seq",
        "fr1_desk",
        "--data-dir",
        empty.to_str().unwrap(),
        "--quiet",
    ]);
    assert_clean_failure(&out, "noisefree fetch fr1_desk");
}

#[test]
fn bad_config_file_is_a_clean_error() {
    let d = tmpdir("cfg");
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join("bad.toml");
    std::fs::write(&p, "seed = \"not a number\"\n").unwrap();
    let out = noisefree(&[
        "run",
        "--frames",
        "5",
        "--config",
        p.to_str().unwrap(),
        "--quiet",
    ]);
    assert_clean_failure(&out, "bad.toml");
}

#[test]
fn mapping_lag_makes_seeded_runs_differ() {
    let d = tmpdir("lag");
    let out = noisefree(&[
        "run",
        "--frames",
        "60",
        "--runs",
        "2",
        "--mapping-lag",
        "3",
        "--quiet",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = |seed: &str| std::fs::read_to_string(d.join(seed).join("trajectory.txt")).unwrap();
    let (a, b) = (read("seed0"), read("seed1"));
    assert_eq!(a.lines().filter(|l| !l.starts_with('#')).count(), 60);
    assert_ne!(a, b);
    let _ = std::fs::remove_dir_all(&d);
}
