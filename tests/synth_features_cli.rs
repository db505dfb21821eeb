//! End-to-end: `noisefree synth` writes a TUM RGB-D folder, `noisefree features` draws the ORB
//! keypoints of one of its frames, `noisefree run --path` tracks the folder, and
//! `noisefree eval` scores the written trajectory against the folder's ground truth — the same
//! files and formats a user would hand to outside tools.

mod common;

use common::{noisefree_ok, tmpdir};

#[test]
fn synth_features_run_eval_round_trip() {
    let seq = tmpdir("seq");
    let s = seq.to_str().unwrap();
    noisefree_ok(&[
        "synth", "--preset", "kinect", "--frames", "40", "--seed", "3", "--out", s,
    ]);
    for f in [
        "rgb.txt",
        "depth.txt",
        "groundtruth.txt",
        "associations.txt",
    ] {
        assert!(seq.join(f).is_file(), "{f} missing");
    }
    // The first colour / depth pair listed in associations.txt.
    let assoc = std::fs::read_to_string(seq.join("associations.txt")).unwrap();
    let first: Vec<&str> = assoc
        .lines()
        .find(|l| !l.starts_with('#'))
        .unwrap()
        .split_whitespace()
        .collect();
    let png = tmpdir("features").with_extension("png");
    let out = noisefree_ok(&[
        "features",
        seq.join(first[1]).to_str().unwrap(),
        "--depth",
        seq.join(first[3]).to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
    ]);
    let drawn = image::open(&png).expect("a readable PNG");
    assert_eq!((drawn.width(), drawn.height()), (640, 480));
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(text.contains("1000"), "1000 keypoints expected: {text}");

    let run_dir = tmpdir("run");
    let out = noisefree_ok(&[
        "run",
        "--path",
        s,
        "--quiet",
        "--out",
        run_dir.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("tracked 40/40 frames"));
    let out = noisefree_ok(&[
        "eval",
        seq.join("groundtruth.txt").to_str().unwrap(),
        run_dir.join("trajectory.txt").to_str().unwrap(),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["ate"]["count"].as_u64(), Some(40));
    assert!(v["ate"]["rmse"].as_f64().unwrap() < 0.01, "{}", v["ate"]);
}
