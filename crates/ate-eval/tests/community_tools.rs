//! Cross-check against the community tools on the same files. Each `fixtures/expected*.json`
//! holds what evo 1.38 (its Python API behind `evo_ape tum GT EST -a [-s] --t_max_diff D`) and
//! a numpy transcription of TUM's evaluate_ate.py compute on a pair of files:
//! - `gt.txt` / `est.txt` (`make_fixture.py`): clean files, dropped frames, jittered stamps;
//! - `rep_gt.txt` / `rep_est.txt` (`make_repeats.py`): repeated stamps in both files (the
//!   repeats 4-5 cm away from their twins, so the line kept matters) and an estimate partly
//!   out of time order; evo's figures are on sorted copies (its search assumes time order);
//! - the real TUM fr2_desk ground truth (one repeated stamp) and ORB-SLAM2 estimate of
//!   `../shared/data/tum_fr2_desk` (`expected_fr2_desk.json`, also from `make_repeats.py`).
//!
//! Files are read with the stamp policy of the tool reproduced. Our statistics must agree to
//! 1e-6 m, with the same number of associated pairs.

use ate_eval::io::{read_tum, read_tum_loaded};
use ate_eval::{evaluate_ate, AlignmentMode, AssociationMode, AteOptions, StampPolicy};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn fr2_desk() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/tum_fr2_desk");
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("skipping: {} not present", dir.display());
        None
    }
}

fn check(key: &str, opts: AteOptions) {
    check_files(
        "expected.json",
        &fixture("gt.txt"),
        &fixture("est.txt"),
        key,
        opts,
    );
}

fn check_files(expected: &str, gt: &Path, est: &Path, key: &str, opts: AteOptions) {
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture(expected)).unwrap()).unwrap();
    let e = &expected[key];
    let policy = StampPolicy::for_association(opts.association);
    let gt = read_tum_loaded(gt, policy).unwrap().trajectory;
    let est = read_tum_loaded(est, policy).unwrap().trajectory;
    let r = evaluate_ate(&gt, &est, &opts).unwrap();
    assert_eq!(
        r.stats.count as u64,
        e["pairs"].as_u64().unwrap(),
        "{key}: pair count"
    );
    let s = &r.stats;
    for (name, ours) in [
        ("rmse", s.rmse),
        ("mean", s.mean),
        ("median", s.median),
        ("std", s.std),
        ("min", s.min),
        ("max", s.max),
    ] {
        let theirs = e[name].as_f64().unwrap();
        assert!(
            (ours - theirs).abs() < 1e-6,
            "{key}.{name}: ours {ours} vs {theirs}"
        );
    }
}

#[test]
fn agrees_with_evaluate_ate_py() {
    check("tum_0.02", AteOptions::default());
}

#[test]
fn agrees_with_evo_ape_se3() {
    let evo = |d| AteOptions {
        max_difference: d,
        association: AssociationMode::Evo,
        ..Default::default()
    };
    check("evo_0.01", evo(0.01));
    check("evo_0.02", evo(0.02));
}

#[test]
fn agrees_with_evo_ape_sim3() {
    check(
        "evo_0.02_scale",
        AteOptions {
            max_difference: 0.02,
            association: AssociationMode::Evo,
            alignment: AlignmentMode::Sim3,
            ..Default::default()
        },
    );
}

fn evo(max_difference: f64) -> AteOptions {
    AteOptions {
        max_difference,
        association: AssociationMode::Evo,
        ..Default::default()
    }
}

#[test]
fn repeated_and_unsorted_stamps_resolve_as_each_tool_does() {
    let (gt, est) = (fixture("rep_gt.txt"), fixture("rep_est.txt"));
    let json = "expected_repeats.json";
    check_files(json, &gt, &est, "tum_0.02", AteOptions::default());
    check_files(json, &gt, &est, "evo_0.01", evo(0.01));
    check_files(json, &gt, &est, "evo_0.02", evo(0.02));
    // Reading with the other tool's policy gives another figure: the policy is what matters.
    let last = read_tum(&gt).unwrap();
    let all = read_tum_loaded(&gt, StampPolicy::KeepAll)
        .unwrap()
        .trajectory;
    assert_eq!(all.len(), last.len() + 4);
}

#[test]
fn real_fr2_desk_agrees_with_evaluate_ate_py_and_evo_ape() {
    let Some(dir) = fr2_desk() else { return };
    let (gt, est) = (dir.join("groundtruth.txt"), dir.join("orbslam2_rgbd.txt"));
    let json = "expected_fr2_desk.json";
    check_files(json, &gt, &est, "tum_0.02", AteOptions::default());
    check_files(json, &gt, &est, "evo_0.01", evo(0.01));
    check_files(json, &gt, &est, "evo_0.02", evo(0.02));
    let l = read_tum_loaded(&gt, StampPolicy::LastWins).unwrap();
    assert_eq!(l.trajectory.len(), 20_956);
    let w: Vec<String> = l.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].ends_with("groundtruth.txt: 1 repeated stamp (first at line 10863), kept the last of each (as evaluate_ate.py)"),
        "{}",
        w[0]
    );
}

#[test]
fn shuffled_estimate_scores_as_the_sorted_one() {
    let Some(dir) = fr2_desk() else { return };
    let gt = dir.join("groundtruth.txt");
    let text = std::fs::read_to_string(dir.join("orbslam2_rgbd.txt")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    // A fixed permutation (multiplicative stride co-prime with the length).
    let n = lines.len();
    let stride = (1..n)
        .rev()
        .find(|s| gcd(*s, n) == 1 && *s < n / 2 + 7)
        .unwrap();
    let shuffled: Vec<&str> = (0..n).map(|k| lines[(k * stride) % n]).collect();
    assert_ne!(shuffled, lines);
    let tmp = std::env::temp_dir().join(format!("ate-eval-shuffle-{}.txt", std::process::id()));
    std::fs::write(&tmp, shuffled.join("\n")).unwrap();
    for assoc in [AssociationMode::Tum, AssociationMode::Evo] {
        let opts = AteOptions {
            association: assoc,
            ..Default::default()
        };
        let policy = StampPolicy::for_association(assoc);
        let gt = read_tum_loaded(&gt, policy).unwrap().trajectory;
        let est_sorted = read_tum_loaded(&dir.join("orbslam2_rgbd.txt"), policy).unwrap();
        let est_shuffled = read_tum_loaded(&tmp, policy).unwrap();
        assert!(est_sorted.warnings.is_empty());
        assert_eq!(est_shuffled.warnings.len(), 1);
        assert!(est_shuffled.warnings[0]
            .message
            .contains("not in time order"));
        let a = evaluate_ate(&gt, &est_sorted.trajectory, &opts).unwrap();
        let b = evaluate_ate(&gt, &est_shuffled.trajectory, &opts).unwrap();
        assert_eq!(a.stats.count, b.stats.count);
        assert_eq!(a.stats.rmse, b.stats.rmse, "{assoc:?}");
    }
    let _ = std::fs::remove_file(&tmp);
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}
