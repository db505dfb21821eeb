//! Cross-check against the community tools on the same files: `fixtures/expected.json` holds
//! what evo 1.38 (its Python API behind `evo_ape tum gt.txt est.txt -a [-s] --t_max_diff D`)
//! and a numpy transcription of TUM's evaluate_ate.py compute on `fixtures/gt.txt` and
//! `fixtures/est.txt` (regenerate with `python3 make_fixture.py`). Our statistics must agree
//! to 1e-6 m, with the same number of associated pairs.

use ate_eval::io::read_tum;
use ate_eval::{evaluate_ate, AlignmentMode, AssociationMode, AteOptions};
use std::path::Path;

fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn check(key: &str, opts: AteOptions) {
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("expected.json")).unwrap()).unwrap();
    let e = &expected[key];
    let gt = read_tum(&fixture("gt.txt")).unwrap();
    let est = read_tum(&fixture("est.txt")).unwrap();
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
