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
fn unsorted_timestamps_rejected() {
    let p = tmp(
        "uns.txt",
        "1.0 0 0 0 0 0 0 1\n3.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n",
    );
    assert_clean_failure(
        &noisefree(&["eval", p.to_str().unwrap(), p.to_str().unwrap()]),
        "uns.txt:3",
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
