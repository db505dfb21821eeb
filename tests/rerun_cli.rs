//! End-to-end tests of the Rerun recording: `noisefree run --rerun FILE.rrd` and `noisefree
//! view`, read back with Rerun's own decoder (the `rerun-sdk` Python package, through
//! tools/rrd_summary.py, in the venv `.ci/run` makes: `NOISEFREE_RERUN_PYTHON` names its
//! interpreter). Without the `rerun` feature, the commands must say how to get it.

mod common;

use common::{assert_clean_failure, noisefree, tmpdir};

/// A bad recording path is refused before the run starts, naming it, with or without the
/// recording built in.
#[test]
fn a_recording_path_that_cannot_be_written_is_refused_before_the_run() {
    let dir = tmpdir("rerun-bad");
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("nothere").join("run.rrd");
    let out = noisefree(&[
        "run",
        "--frames",
        "5",
        "--quiet",
        "--rerun",
        missing.to_str().unwrap(),
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert_clean_failure(&out, "nothere");
    assert!(
        !dir.join("out").exists(),
        "refused before anything ran or was written"
    );
    let out = noisefree(&["run", "--frames", "5", "--quiet", "--rerun", "run.txt"]);
    assert_clean_failure(&out, ".rrd");
    let _ = std::fs::remove_dir_all(dir);
}

#[cfg(not(feature = "rerun"))]
#[test]
fn without_the_feature_the_recording_says_how_to_get_it() {
    let dir = tmpdir("rerun-absent");
    std::fs::create_dir_all(&dir).unwrap();
    let rrd = dir.join("run.rrd");
    let out = noisefree(&[
        "run",
        "--frames",
        "5",
        "--quiet",
        "--rerun",
        rrd.to_str().unwrap(),
    ]);
    assert_clean_failure(&out, "--features rerun");
    let gt = dir.join("gt.txt");
    std::fs::write(&gt, "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n2 2 0 0 0 0 0 1\n").unwrap();
    let out = noisefree(&[
        "view",
        gt.to_str().unwrap(),
        gt.to_str().unwrap(),
        "-o",
        rrd.to_str().unwrap(),
    ]);
    assert_clean_failure(&out, "--features rerun");
    let _ = std::fs::remove_dir_all(dir);
}

#[cfg(feature = "rerun")]
mod recorded {
    use super::common::{noisefree_ok, tmpdir};
    use serde_json::Value;
    use std::path::Path;

    /// The summary tools/rrd_summary.py prints of `rrd`, read with Rerun's own decoder.
    fn summary(rrd: &Path) -> Value {
        let python = std::env::var("NOISEFREE_RERUN_PYTHON").unwrap_or_else(|_| {
            panic!(
                "NOISEFREE_RERUN_PYTHON must name a Python with rerun-sdk 0.36 (.ci/run makes \
                 one: python3 -m venv target/rerun-venv && target/rerun-venv/bin/pip install \
                 rerun-sdk==0.36.3)"
            )
        });
        let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tools/rrd_summary.py");
        let out = std::process::Command::new(python)
            .args([script, rrd.to_str().unwrap()])
            .output()
            .expect("python runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).expect("JSON")
    }

    /// Per frame index, the instances logged at `entity` (summed over its rows at that frame).
    fn per_frame(s: &Value, entity: &str) -> std::collections::BTreeMap<i64, i64> {
        let e = &s[format!("/{entity}")];
        assert!(e.is_object(), "no entity {entity}");
        let mut out = std::collections::BTreeMap::new();
        for (f, n) in e["frames"]
            .as_array()
            .unwrap()
            .iter()
            .zip(e["instances"].as_array().unwrap())
        {
            if let (Some(f), Some(n)) = (f.as_i64(), n.as_i64()) {
                *out.entry(f).or_insert(0) += n;
            }
        }
        out
    }

    /// 30 frames of the walking preset under MC-OR, recorded and read back: every entity path is
    /// there, one camera pose per tracked frame and one image per frame, the keypoint classes add
    /// up to each frame's keypoints, MC-OR rejects some, and the trajectory is the unrecorded
    /// run's, bit for bit.
    #[test]
    fn a_recorded_walking_run_reads_back_with_every_keypoint_and_its_fate() {
        let dir = tmpdir("rerun-walking");
        std::fs::create_dir_all(&dir).unwrap();
        let rrd = dir.join("walking.rrd");
        let run = |out: &str, extra: &[&str]| {
            let mut args = vec![
                "run", "--seq", "walking", "--frames", "30", "--mcor", "--quiet", "--out",
            ];
            let out = dir.join(out);
            let out_s = out.to_str().unwrap().to_string();
            args.push(&out_s);
            args.extend_from_slice(extra);
            noisefree_ok(&args);
            out
        };
        let recorded = run("recorded", &["--rerun", rrd.to_str().unwrap()]);
        let plain = run("plain", &[]);
        let traj = |d: &Path| std::fs::read(d.join("trajectory.txt")).unwrap();
        assert_eq!(traj(&recorded), traj(&plain), "recording changes nothing");
        assert!(!dir.join("walking.rrd.partial").exists());
        let s = summary(&rrd);
        for entity in [
            "world/groundtruth",
            "world/slam",
            "world/slam/estimate",
            "world/slam/camera",
            "world/slam/camera/image",
            "world/slam/camera/image/colour",
            "world/slam/camera/image/depth",
            "world/slam/map/points",
            "world/slam/map/keyframes",
            "stats/inliers",
            "stats/mcor_rejected",
            "stats/error_m",
            "events",
        ] {
            assert!(s[format!("/{entity}")].is_object(), "no {entity}: {s}");
        }
        let images = per_frame(&s, "world/slam/camera/image/colour");
        assert_eq!(images.len(), 30, "one image per frame");
        assert!(images.values().all(|&n| n == 1));
        let tracked = String::from_utf8(traj(&recorded))
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#'))
            .count();
        let poses = per_frame(&s, "world/slam/camera");
        assert_eq!(poses.len(), tracked, "one pose per tracked frame");
        // The fates of every frame add up to its keypoints (frames.csv's n_keypoints).
        let mut fates = std::collections::BTreeMap::new();
        for fate in [
            "kept",
            "chi2",
            "mcor_cluster",
            "mcor_feature",
            "rc",
            "no_depth",
            "unmatched",
        ] {
            for (f, n) in per_frame(&s, &format!("world/slam/camera/image/keypoints/{fate}")) {
                *fates.entry(f).or_insert(0) += n;
            }
        }
        let frames = std::fs::read_to_string(recorded.join("frames.csv")).unwrap();
        let mut lines = frames.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = header.iter().position(|h| *h == "n_keypoints").unwrap();
        for (i, line) in lines.enumerate() {
            let n: i64 = line.split(',').nth(col).unwrap().parse().unwrap();
            assert_eq!(fates[&(i as i64)], n, "frame {i}: fates against keypoints");
        }
        let mcor: i64 = ["mcor_cluster", "mcor_feature"]
            .iter()
            .flat_map(|f| per_frame(&s, &format!("world/slam/camera/image/keypoints/{f}")))
            .map(|(_, n)| n)
            .sum();
        assert!(mcor > 0, "at least one MC-OR rejection");
        // Each MC-OR rejection is labelled with the thresholds it exceeded.
        let mut labels = Vec::new();
        for f in ["mcor_cluster", "mcor_feature"] {
            let e = &s[format!("/world/slam/camera/image/keypoints/{f}")];
            labels.extend(e["labels"].as_array().unwrap().iter().cloned());
        }
        assert!(!labels.is_empty(), "MC-OR rejections carry labels");
        for l in &labels {
            let l = l.as_str().unwrap();
            let names = ["tau_MF", "tau_GF", "tau_MG"];
            assert!(
                !l.is_empty() && l.split(' ').all(|t| names.contains(&t)),
                "label {l:?}"
            );
        }
        let _ = std::fs::remove_dir_all(dir);
    }

    /// A run under AVC and a depth perturbation records what the system read: every depth image
    /// differs from the unperturbed run's and every colour image is the same; and AVC's virtual
    /// cameras of a few matches per tracked frame, two rays each.
    #[test]
    fn a_perturbed_avc_run_records_the_perturbed_images_and_the_virtual_cameras() {
        let dir = tmpdir("rerun-perturbed");
        std::fs::create_dir_all(&dir).unwrap();
        let record = |name: &str, extra: &[&str]| {
            let rrd = dir.join(format!("{name}.rrd"));
            let out = dir.join(name);
            let (rrd_s, out_s) = (rrd.to_str().unwrap(), out.to_str().unwrap());
            let mut args = vec![
                "run", "--seq", "walking", "--frames", "12", "--avc", "--quiet", "--out", out_s,
                "--rerun", rrd_s,
            ];
            args.extend_from_slice(extra);
            noisefree_ok(&args);
            summary(&rrd)
        };
        let plain = record("plain", &[]);
        let perturbed = record("perturbed", &["--perturb", "depth-axial:8"]);
        let digests = |s: &Value, image: &str| -> Vec<String> {
            let e = &s[format!("/world/slam/camera/image/{image}")];
            let d: Vec<String> = e["digests"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_str().unwrap().to_string())
                .collect();
            assert_eq!(d.len(), 12, "{image}: one image per frame");
            d
        };
        assert_eq!(digests(&plain, "colour"), digests(&perturbed, "colour"));
        let (a, b) = (digests(&plain, "depth"), digests(&perturbed, "depth"));
        for (i, (a, b)) in a.iter().zip(&b).enumerate() {
            assert_ne!(a, b, "frame {i}: the perturbed depth is recorded");
        }
        let cameras = per_frame(&perturbed, "world/slam/camera/avc/virtual_cameras");
        assert!(cameras.len() >= 10, "virtual cameras on tracked frames");
        assert!(
            cameras.values().all(|&n| (1..=8).contains(&n)),
            "{cameras:?}"
        );
        let rays = per_frame(&perturbed, "world/slam/camera/avc/rays");
        for (f, n) in &cameras {
            assert_eq!(
                rays.get(f),
                Some(&(2 * n)),
                "frame {f}: two rays per camera"
            );
        }
        let _ = std::fs::remove_dir_all(dir);
    }

    /// `view` puts any trajectory files beside the ground truth, one entity each.
    #[test]
    fn view_records_each_estimate_beside_the_ground_truth() {
        let dir = tmpdir("rerun-view");
        std::fs::create_dir_all(&dir).unwrap();
        let gt = dir.join("gt.txt");
        let est = dir.join("est.txt");
        let (mut g, mut e) = (String::new(), String::new());
        for i in 0..20 {
            let t = i as f64 * 0.1;
            g.push_str(&format!("{t} {} {} 0 0 0 0 1\n", t, (t * 3.0).sin()));
            e.push_str(&format!(
                "{t} {} {} 0.01 0 0 0 1\n",
                t + 0.5,
                (t * 3.0).sin()
            ));
        }
        std::fs::write(&gt, g).unwrap();
        std::fs::write(&est, e).unwrap();
        let rrd = dir.join("view.rrd");
        noisefree_ok(&[
            "view",
            gt.to_str().unwrap(),
            &format!("{}=ours", est.display()),
            &format!("{}=again", est.display()),
            "-o",
            rrd.to_str().unwrap(),
        ]);
        let s = summary(&rrd);
        for entity in [
            "world/groundtruth",
            "world/estimates/ours",
            "world/estimates/again",
            "stats/ours/error_m",
        ] {
            assert!(s[format!("/{entity}")].is_object(), "no {entity}: {s}");
        }
        assert_eq!(per_frame(&s, "stats/ours/error_m").len(), 20);
        let _ = std::fs::remove_dir_all(dir);
    }
}
