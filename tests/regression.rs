//! The regression guard: `noisefree regress` runs the suite (short synthetic sequences through
//! RGB-D, stereo, moving people and relocalization, each under the four configurations) and
//! compares every figure with `tests/golden/regression.toml`. It fails, printing the old-vs-new
//! table, when ATE or a count moves beyond its tolerance; a changed trajectory hash within
//! tolerance is reported, not failed. Regenerate the golden file with `make golden` only for an
//! intended change (docs/development.md, "Regression suite").

mod common;

use common::noisefree;

#[test]
fn regression_suite_matches_golden_figures() {
    let golden = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden/regression.toml");
    let out = noisefree(&["regress", "--golden", golden, "--quiet"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    // The table always reaches the test log, so a reviewer sees moved hashes too.
    eprintln!("{stdout}");
    assert!(
        out.status.success(),
        "regression suite failed:\n{stdout}\n{stderr}"
    );
    assert!(
        stdout.lines().filter(|l| l.contains("/orb ")).count() >= 4,
        "every suite sequence ran: {stdout}"
    );
}

#[test]
fn regress_refuses_a_missing_golden_file_and_an_unknown_case() {
    let out = noisefree(&["regress", "--golden", "/no/such/golden.toml", "--quiet"]);
    common::assert_clean_failure(&out, "/no/such/golden.toml");
    let golden = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden/regression.toml");
    let out = noisefree(&["regress", "--golden", golden, "--only", "no-such-case"]);
    common::assert_clean_failure(&out, "matches no case");
}
