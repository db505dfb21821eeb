//! End-to-end tests of `noisefree eval`: the real binary on real files, good and bad.

mod common;

use common::{assert_clean_failure, noisefree};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("crates/ate-eval/tests/fixtures")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

fn tmp(name: &str, contents: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("noisefree-eval-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, contents).unwrap();
    p
}

#[test]
fn json_has_every_statistic_and_matches_evo() {
    let out = noisefree(&[
        "eval",
        &fixture("gt.txt"),
        &fixture("est.txt"),
        "--json",
        "--assoc",
        "evo",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for k in ["rmse", "mean", "median", "std", "min", "max", "count"] {
        assert!(v["ate"][k].is_number(), "missing ate.{k}");
    }
    // evo_ape -a --t_max_diff 0.02 on these files (fixtures/expected.json).
    assert!((v["ate"]["rmse"].as_f64().unwrap() - 0.038774620551661004).abs() < 1e-6);
    assert_eq!(v["pairs"].as_array().unwrap().len(), 570);
}

#[test]
fn human_summary_and_rpe() {
    let out = noisefree(&[
        "eval",
        &fixture("gt.txt"),
        &fixture("est.txt"),
        "--rpe-frames",
        "10",
    ]);
    assert!(out.status.success());
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(s.contains("rmse   0.038775 m"), "{s}");
    assert!(s.contains("RPE"), "{s}");
}

#[test]
fn rpe_without_a_sample_names_both_files() {
    let out = noisefree(&[
        "eval",
        &fixture("gt.txt"),
        &fixture("est.txt"),
        "--rpe-frames",
        "100000",
    ]);
    assert_clean_failure(&out, "relative pose error of");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("est.txt") && err.contains("gt.txt"), "{err}");
}

#[test]
fn missing_file_is_a_clean_error() {
    let out = noisefree(&["eval", "/no/such/gt.txt", &fixture("est.txt")]);
    assert_clean_failure(&out, "/no/such/gt.txt");
}

#[test]
fn seven_numbers_names_file_and_line() {
    let p = tmp("seven.txt", "# c\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n");
    let out = noisefree(&["eval", p.to_str().unwrap(), &fixture("est.txt")]);
    assert_clean_failure(&out, "seven.txt:3");
}

#[test]
fn nan_and_zero_quaternion_rejected() {
    let p = tmp("nan.txt", "1.0 0 NaN 0 0 0 0 1\n");
    assert_clean_failure(
        &noisefree(&["eval", p.to_str().unwrap(), &fixture("est.txt")]),
        "nan.txt:1",
    );
    let p = tmp("zq.txt", "1.0 0 0 0 0 0 0 0\n");
    assert_clean_failure(
        &noisefree(&["eval", p.to_str().unwrap(), &fixture("est.txt")]),
        "near-zero",
    );
}

#[test]
fn unnormalised_quaternion_warns_but_evaluates() {
    let text: String = (0..10)
        .map(|i| format!("{}.0 {i} {} 0 0 0 0 2\n", i, i * i))
        .collect();
    let p = tmp("q2.txt", &text);
    let out = noisefree(&["eval", p.to_str().unwrap(), p.to_str().unwrap()]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("normalised"));
}

#[test]
fn unsorted_timestamps_refused_with_strict() {
    let p = tmp(
        "uns.txt",
        "1.0 0 0 0 0 0 0 1\n3.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n",
    );
    assert_clean_failure(
        &noisefree(&["eval", p.to_str().unwrap(), p.to_str().unwrap(), "--strict"]),
        "uns.txt:3",
    );
}

fn fr2_desk() -> Option<PathBuf> {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/tum_fr2_desk");
    d.is_dir().then_some(d)
}

/// RPE's two conventions on the real fr2_desk files, under evo's association (nearest stamp
/// within 0.01 s): `--rpe-pairs all` is evo_rpe's `--all_pairs` (and TUM's evaluate_rpe.py's
/// overlapping samples), `--rpe-pairs consecutive` evo_rpe's default. The figures were taken
/// once from evo 1.38.1 (`metrics.RPE(translation_part, delta=30, frames, all_pairs)` after
/// `sync.associate_trajectories(max_diff=0.01)`).
#[test]
fn rpe_pairs_give_evo_rpe_s_two_conventions_on_the_real_fr2_desk_files() {
    let Some(d) = fr2_desk() else {
        eprintln!("skipping: ../shared/data/tum_fr2_desk not present");
        return;
    };
    let gt = d.join("groundtruth.txt");
    let est = d.join("orbslam2_rgbd.txt");
    for (pairs, rmse, samples) in [
        ("all", 0.007701977181680654, 2144),
        ("consecutive", 0.007843758497117352, 72),
    ] {
        let out = noisefree(&[
            "eval",
            gt.to_str().unwrap(),
            est.to_str().unwrap(),
            "--assoc",
            "evo",
            "--max-diff",
            "0.01",
            "--rpe-frames",
            "30",
            "--rpe-pairs",
            pairs,
            "--json",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let t = &v["rpe"]["trans_m"];
        assert!(
            (t["rmse"].as_f64().unwrap() - rmse).abs() < 1e-9,
            "{pairs}: {t}"
        );
        assert_eq!(t["count"].as_u64().unwrap(), samples, "{pairs}");
    }
}

/// The real TUM fr2_desk ground truth as distributed (a repeated stamp at line 10863) and an
/// ORB-SLAM2 estimate: scored as evaluate_ate.py and evo_ape score them (figures from those
/// tools, crates/ate-eval/tests/fixtures/expected_fr2_desk.json), with one warning line.
#[test]
fn real_fr2_desk_ground_truth_is_read_as_the_tools_read_it() {
    let Some(d) = fr2_desk() else {
        eprintln!("skipping: ../shared/data/tum_fr2_desk not present");
        return;
    };
    let gt = d.join("groundtruth.txt");
    let est = d.join("orbslam2_rgbd.txt");
    let (gt, est) = (gt.to_str().unwrap(), est.to_str().unwrap());
    for (extra, rmse, pairs) in [
        (&[][..], 0.008143967169519095, 2223),
        (
            &["--assoc", "evo", "--max-diff", "0.01"][..],
            0.008118977562045396,
            2174,
        ),
    ] {
        let mut args = vec!["eval", gt, est, "--json"];
        args.extend_from_slice(extra);
        let out = noisefree(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert!(
            (v["ate"]["rmse"].as_f64().unwrap() - rmse).abs() < 1e-6,
            "{extra:?}: {v}"
        );
        assert_eq!(v["ate"]["count"].as_u64().unwrap(), pairs, "{extra:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        let warnings: Vec<&str> = stderr.lines().filter(|l| l.contains("warning")).collect();
        assert_eq!(warnings.len(), 1, "one warning line: {stderr}");
        assert!(
            warnings[0].contains("groundtruth.txt: 1 repeated stamp (first at line 10863)"),
            "{stderr}"
        );
    }
    assert_clean_failure(
        &noisefree(&["eval", gt, est, "--strict"]),
        "groundtruth.txt:10863",
    );
}

#[test]
fn shuffled_estimate_gives_the_same_ate_with_a_warning() {
    let lines: Vec<String> = (0..40)
        .map(|i| format!("{}.0 {} {} 0 0 0 0 1", i, i, (i * i) % 7))
        .collect();
    let sorted = tmp("sorted.txt", &lines.join("\n"));
    let mut shuffled_lines = lines.clone();
    shuffled_lines.reverse();
    shuffled_lines.swap(3, 17);
    let shuffled = tmp("shuffled.txt", &shuffled_lines.join("\n"));
    let gt_lines: Vec<String> = (0..40)
        .map(|i| {
            format!(
                "{}.005 {} {} {} 0 0 0 1",
                i,
                i as f64 * 1.01,
                (i * i) % 7,
                (i % 3) as f64 * 0.01
            )
        })
        .collect();
    let gt = tmp("gt40.txt", &gt_lines.join("\n"));
    let rmse = |est: &Path| {
        let out = noisefree(&[
            "eval",
            gt.to_str().unwrap(),
            est.to_str().unwrap(),
            "--json",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (
            v["ate"]["rmse"].as_f64().unwrap(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let (a, wa) = rmse(&sorted);
    let (b, wb) = rmse(&shuffled);
    assert_eq!(a, b);
    assert!(!wa.contains("warning"), "{wa}");
    assert!(
        wb.contains("shuffled.txt: stamps not in time order (first at line 2), sorted"),
        "{wb}"
    );
}

#[test]
fn too_few_pairs_rejected() {
    let a = tmp("a.txt", "1.0 0 0 0 0 0 0 1\n2.0 1 0 0 0 0 0 1\n");
    assert_clean_failure(
        &noisefree(&["eval", a.to_str().unwrap(), a.to_str().unwrap()]),
        "only 2 pose pairs",
    );
}

#[test]
fn plot_draws_aligned_estimates_with_their_ate_and_refuses_missing_files() {
    let eval = noisefree(&["eval", &fixture("gt.txt"), &fixture("est.txt")]);
    let eval_text = String::from_utf8_lossy(&eval.stdout).into_owned();
    let stem = std::env::temp_dir()
        .join(format!("noisefree-plot-cli-{}", std::process::id()))
        .join("fig");
    let labelled = format!("{}=my estimate", fixture("est.txt"));
    let out = noisefree(&[
        "plot",
        &fixture("gt.txt"),
        &labelled,
        "--out",
        stem.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The same alignment and ATE as `eval` prints (its RMSE to 4 decimals).
    let rmse = text
        .split("ATE RMSE ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .unwrap()
        .to_string();
    assert!(text.starts_with("my estimate: ATE RMSE"), "{text}");
    assert!(eval_text.contains(&rmse[..5]), "{eval_text} vs {text}");
    for ext in ["png", "svg"] {
        let p = stem.with_extension(ext);
        assert!(
            std::fs::metadata(&p).unwrap().len() > 1000,
            "{}",
            p.display()
        );
    }
    let o = noisefree(&[
        "plot",
        &fixture("gt.txt"),
        "/no/such/estimate.txt",
        "--out",
        stem.to_str().unwrap(),
    ]);
    assert_clean_failure(&o, "/no/such/estimate.txt");
}

#[test]
fn a_missing_file_is_named_once_with_its_reason() {
    let out = common::noisefree(&["eval", "no/such/gt.txt", "no/such/est.txt"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no/such/gt.txt"), "{err}");
    assert_eq!(err.matches("No such file").count(), 1, "{err}");
}

/// A camera (cam0) trajectory scored against EuRoC's body-frame ground truth is warned about,
/// with the file that converts it and the ATE it would have; converted with `--body-from`, or
/// a body-frame estimate, gets no warning.
#[test]
fn a_camera_frame_estimate_against_euroc_body_ground_truth_is_warned_about() {
    let dir = std::env::temp_dir().join(format!("noisefree-eval-body-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let seq = dir.join("seq");
    let out = noisefree(&[
        "synth",
        "--preset",
        "stereo",
        "--trajectory",
        "rpy",
        "--frames",
        "40",
        "--out",
        seq.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{out:?}");
    let gt = seq.join("mav0/state_groundtruth_estimate0/data.csv");
    let yaml = seq.join("mav0/cam0/sensor.yaml");
    let body = ate_eval::io::read_trajectory(
        &gt,
        ate_eval::io::Format::Euroc,
        None,
        ate_eval::StampPolicy::Strict,
    )
    .unwrap()
    .trajectory;
    let t_bs = ate_eval::io::read_euroc_t_bs(&yaml).unwrap();
    let camera = body.change_sensor_frame(&t_bs);
    let (cam_file, body_file) = (dir.join("cam0.txt"), dir.join("body.txt"));
    ate_eval::io::write_tum(&cam_file, &camera).unwrap();
    ate_eval::io::write_tum(&body_file, &body).unwrap();
    let eval = |est: &Path, extra: &[&str]| {
        let mut args = vec!["eval", gt.to_str().unwrap(), est.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = noisefree(&args);
        assert!(o.status.success(), "{o:?}");
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let warned = eval(&cam_file, &[]);
    assert!(
        warned.contains("looks like a camera (cam0) trajectory")
            && warned.contains(&format!("--body-from {}", yaml.display())),
        "{warned}"
    );
    assert!(
        !eval(&cam_file, &["--body-from", yaml.to_str().unwrap()]).contains("warning"),
        "converted: nothing to say"
    );
    assert!(
        !eval(&body_file, &[]).contains("warning"),
        "a body trajectory"
    );
    let _ = std::fs::remove_dir_all(dir);
}
