//! Helpers shared by the command-line tests: run the `noisefree` binary, check it succeeded,
//! and give each test a fresh scratch folder.

#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// The frame cache the tests' processes share, as the environment variable that names it
/// (`target/tmp/synth-frames`): a synthetic frame is a pure function of the renderer's code, the
/// configuration, the seed and the index, so the many runs of the same few sequences render
/// each frame once (`synth::CachedFrames`; synth's own tests render without it).
pub fn synth_cache_env() -> (&'static str, &'static str) {
    (
        synth::CACHE_ENV,
        concat!(env!("CARGO_TARGET_TMPDIR"), "/synth-frames"),
    )
}

/// Runs the `noisefree` binary built for these tests with `args`.
pub fn noisefree(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_noisefree"))
        .args(args)
        .envs([synth_cache_env()])
        .output()
        .expect("binary runs")
}

/// Runs `noisefree` with `args` and fails the test (showing its stderr) unless it succeeded.
pub fn noisefree_ok(args: &[&str]) -> Output {
    let out = noisefree(args);
    assert_ok(&out);
    out
}

/// Fails the test, showing stderr, unless `out` is a successful exit.
pub fn assert_ok(out: &Output) {
    assert!(
        out.status.success(),
        "noisefree failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A scratch folder path unique to this test process and `name`, removed if a previous run
/// left it behind (not created: commands under test create their output folders).
pub fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nf-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Fails the test unless `out` is a clean failure: a non-zero exit, no panic, and `needle` (a
/// file name, a flag, a suggestion) in the error message.
pub fn assert_clean_failure(out: &Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "expected failure, stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    assert!(stderr.contains(needle), "stderr lacks {needle:?}: {stderr}");
}
