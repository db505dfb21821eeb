//! The rigid consensus (`rc`, noisefree's own configuration) pinned where a user would leave it
//! on: it rescues sequences with people walking before the camera (the baseline follows them),
//! with RGB-D depth and with stereo depth, and costs nothing measurable on static sequences,
//! RGB-D and stereo: the ATE within 3 % or 0.1 mm of the baseline's, whichever is larger
//! (issue 33's tolerance).

mod common;

use common::{noisefree_ok, tmpdir};

/// ATE RMSE (m) that `noisefree run` records (summary.json) for `preset` with `extra` flags.
fn ate(preset: &str, frames: &str, extra: &[&str]) -> f64 {
    let out = tmpdir(&format!("rc-{preset}-{}", extra.len()));
    let mut args = vec![
        "run",
        "--seq",
        preset,
        "--frames",
        frames,
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    noisefree_ok(&args);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    summary["ate_rmse_m"].as_f64().expect("an ATE")
}

#[test]
fn rc_rescues_walking_and_costs_nothing_on_static_sequences() {
    // `walking` (RGB-D) is pinned by the regression suite (walking/orb against walking/rc).
    let cases: Vec<(&str, &str)> = vec![
        ("kinect", "100"),
        ("stereo", "80"),
        ("walking-stereo", "110"),
    ];
    let results: Vec<(&str, f64, f64)> = std::thread::scope(|s| {
        let handles: Vec<_> = cases
            .iter()
            .map(|&(p, n)| s.spawn(move || (p, ate(p, n, &[]), ate(p, n, &["--rc"]))))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (preset, orb, rc) in results {
        match preset {
            "walking" | "walking-stereo" => {
                assert!(orb > 0.05, "the baseline follows the walkers: {orb} m");
                assert!(rc < 0.02, "rc holds the room: {rc} m (baseline {orb} m)");
            }
            _ => {
                let tolerance = (0.03 * orb).max(1e-4);
                assert!(
                    (rc - orb).abs() <= tolerance,
                    "{preset}: rc {rc} m against the baseline's {orb} m (tolerance {tolerance} m)"
                );
            }
        }
    }
}
