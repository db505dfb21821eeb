//! Fuzz targets of the formats this binary reads itself (issue 45): `runs.csv`,
//! `sweep-settings.toml`, the config TOML (with its range checks), the `[systems.*]` TOML and a
//! sweep folder's `systems.toml`, the regression golden file, and a vocabulary file. Their
//! readers live in this crate, which no other crate can depend on, so the targets are here and
//! the fuzz crate's engine (a dev-dependency) drives them, with its counting allocator as this
//! test binary's global allocator.
//!
//! `cargo test --bin noisefree fuzz_cli` runs the CI pass (a few thousand fixed-seed inputs a
//! target); `make fuzz` runs the long pass (`fuzz_cli_long`, ignored by default) for
//! `FUZZ_SECS` seconds a target, appending to the tally `FUZZ_TALLY`. A saved input (a
//! finding in `target/fuzz`) is read again by `fuzz_cli_replay`, the `fuzz --replay` of these
//! targets:
//!
//! ```text
//! FUZZ_TARGET=config-toml FUZZ_REPLAY=target/fuzz/config-toml-slow-1.bin \
//!   cargo test -p noisefree --bin noisefree fuzz_cli_replay -- --ignored --nocapture
//! ```

use fuzz::engine;
use fuzz::engine::driver::{run, scratch_dir, Limits, Reader, Report, Target};
use std::path::Path;

#[global_allocator]
static ALLOC: engine::alloc::Counting = engine::alloc::Counting;

/// A reader of the file `name` in a scratch folder; `read` gets the folder and the file.
fn on_file(
    name: &'static str,
    read: impl Fn(&Path, &Path) -> anyhow::Result<()> + Send + Sync + 'static,
) -> Reader {
    // A folder per target: the targets run side by side, and a reader that looks at its
    // folder (a sweep's) must see only its own file.
    let dir = scratch_dir("cli").join(name.replace('.', "-"));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join(name);
    engine::driver::on_file(path, move |p| read(&dir, p).map_err(|e| format!("{e:#}")))
}

/// Bytes the TOML and CSV readers may hold per input byte. The `toml` and `csv` crates keep
/// state per token (a field's end offset, a span, an event), for a token that may be one byte
/// long: a file of a million commas takes 50 times its size, one of a million dots 112 times
/// (found by the first long run, held to 64 then), in time and memory linear in it. No count
/// of the file's is believed: there is no header to lie.
const TOKEN_ALLOC_FACTOR: f64 = 128.0;

fn target(
    name: &'static str,
    about: &'static str,
    file: &'static str,
    seeds: Vec<Vec<u8>>,
    dictionary: &[&str],
    read: Reader,
) -> Target {
    Target::new(
        name,
        about,
        file,
        seeds,
        dictionary,
        TOKEN_ALLOC_FACTOR,
        read,
    )
}

/// The first `n` lines of `text`.
fn head(text: &str, n: usize) -> Vec<u8> {
    text.lines()
        .take(n)
        .flat_map(|l| l.bytes().chain(std::iter::once(b'\n')))
        .collect()
}

/// Every target of the binary's own readers.
fn targets() -> Vec<Target> {
    use slam_core::system::{AvcParams, Config, McorParams, RigidConsensusParams};
    let full = Config {
        mcor: Some(McorParams::default()),
        avc: Some(AvcParams::default()),
        rc: Some(RigidConsensusParams::default()),
        ..Config::default()
    };
    let config_seeds = vec![
        toml::to_string(&full).unwrap_or_default().into_bytes(),
        b"vocabulary = \"none\"\nmapping_lag = 2\n[loop_closing]\nenabled = false\n".to_vec(),
        b"[orb]\nscale_factor = 1.2\nn_levels = 8\n[mcor]\ncluster_views = \"keyframes\"\n"
            .to_vec(),
    ];
    let systems = include_str!("../systems/orbslam.toml");
    vec![
        target(
            "runs-csv",
            "a sweep's runs.csv (sweep::store::read_records)",
            "runs.csv",
            vec![
                include_bytes!("../results/orbslam2-beside/runs.csv").to_vec(),
                head(include_str!("../results/synthetic/runs.csv"), 12),
                head(include_str!("../results/rc-stereo/runs.csv"), 12),
            ],
            &["false", "true", "mcor+avc", "kinect", "timeout after 600 s"],
            on_file("runs.csv", |_, p| {
                crate::sweep::store::read_records(p).map(|_| ())
            }),
        ),
        target(
            "sweep-settings",
            "a sweep folder's sweep-settings.toml (sweep::store::settings_of)",
            "sweep-settings.toml",
            vec![
                include_bytes!("../results/orbslam2-beside/sweep-settings.toml").to_vec(),
                include_bytes!("../results/synthetic-lag3/sweep-settings.toml").to_vec(),
                b"mcor_cluster = \"keyframes\"\nsynth_without = [\"blur\", \"exposure\"]\n"
                    .to_vec(),
                b"approximations = [\"avc.aim = \\\"direct\\\"\", \"mcor.view_stride = 2\"]\n"
                    .to_vec(),
            ],
            &[
                "mapping_lag",
                "vocabulary",
                "loop_closing",
                "mcor_cluster",
                "every-frame",
                "approximations",
            ],
            on_file("sweep-settings.toml", |dir, _| {
                crate::sweep::store::settings_of(dir).map(|_| ())
            }),
        ),
        target(
            "config-toml",
            "the config TOML, every value range-checked (config_file::overlay_file, vocabulary_in_file)",
            "config.toml",
            config_seeds,
            &[
                "[orb]",
                "scale_factor",
                "n_levels",
                "n_features",
                "[mcor]",
                "[avc]",
                "[rc]",
                "[tracking]",
                "[relocalization]",
                "ransac_iterations",
                "[loop_closing]",
                "[systems.x]",
            ],
            on_file("config.toml", |_, p| {
                let c = crate::config_file::overlay_file(&Config::default(), p)?;
                // An accepted configuration is one the system can run with.
                if let Err(e) = c.check() {
                    panic!("accepted out of range: {e}");
                }
                crate::config_file::vocabulary_in_file(p).map(|_| ())
            }),
        ),
        target(
            "systems-toml",
            "[systems.*] definitions of external programs (external::system::systems_in_file, systems_of, resolve)",
            "systems.toml",
            vec![
                systems.as_bytes().to_vec(),
                include_bytes!("../results/orbslam2-beside/systems.toml").to_vec(),
            ],
            &["timeout_s", "[systems.", ".rgbd]", ".stereo]", "command", "{sequence}", "tum-ns"],
            on_file("systems.toml", |dir, p| {
                use crate::external::system::{systems_in_file, systems_of};
                for (name, def) in systems_in_file(p)? {
                    for sensor in [slam_core::SensorKind::Rgbd, slam_core::SensorKind::Stereo] {
                        def.resolve(&name, sensor)?;
                    }
                }
                for (name, def) in systems_of(dir)? {
                    for sensor in [slam_core::SensorKind::Rgbd, slam_core::SensorKind::Stereo] {
                        // A recorded definition was validated when written; resolving one
                        // edited by hand must fail cleanly, never panic.
                        let _ = def.resolve(&name, sensor);
                    }
                }
                Ok(())
            }),
        ),
        target(
            "golden",
            "the regression suite's golden file (regress::golden::Golden::read)",
            "regression.toml",
            // Its header and first three cases: every field of the format, in a ninth of the
            // file's bytes (each mutated input is read whole; the whole file took 2 ms an input).
            vec![head(include_str!("../tests/golden/regression.toml"), 83)],
            &["[[case]]", "ate_tol_m", "spread_runs", "hash"],
            on_file("regression.toml", |_, p| {
                crate::regress::golden::Golden::read(p).map(|_| ())
            }),
        ),
        {
            // A k = 3, L = 1 vocabulary of two words, in both forms.
            let line = |w: f64, b: u8| {
                let bytes: Vec<String> = (0..32u8).map(|i| (i ^ b).to_string()).collect();
                format!("0 1 {} {w}\n", bytes.join(" "))
            };
            let text = format!("3 1 0 0\n{}{}", line(0.5, 0), line(0.25, 0xff));
            let mut seeds = vec![text.clone().into_bytes()];
            if let Ok(v) = slam_core::place::Vocabulary::from_text(&text) {
                seeds.push(v.to_binary());
            }
            target(
                "vocab-file",
                "a vocabulary file in either form (vocab_file::read)",
                "vocab.voc",
                seeds,
                &["NFVOCAB1"],
                on_file("vocab.voc", |_, p| crate::vocab_file::read(p).map(|_| ())),
            )
        },
    ]
}

fn check(reports: &[Report]) {
    let bad: Vec<String> = reports
        .iter()
        .filter(|r| !r.clean())
        .map(|r| r.details(300))
        .collect();
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// Each target on a thread of its own (the allocator counts per thread, the time bounds of
/// [`Limits::ci`] are seconds against readers' milliseconds), its report in the targets' order.
#[test]
fn fuzz_cli_readers_survive_a_fixed_seed_pass() {
    let targets = targets();
    let reports: Vec<Report> = std::thread::scope(|s| {
        let handles: Vec<_> = targets
            .iter()
            .map(|t| s.spawn(move || run(t, 45, &Limits::ci(3000))))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a fuzz target's thread"))
            .collect()
    });
    for r in &reports {
        println!("{}", r.summary());
        assert!(r.counted, "the counting allocator is not installed");
        assert!(r.accepted > 0 && r.refused > 0, "{}", r.summary());
    }
    check(&reports);
    let _ = std::fs::remove_dir_all(scratch_dir("cli"));
}

/// The long pass of `make fuzz`: `FUZZ_SECS` seconds a target (default 10) from `FUZZ_SEED`
/// (default 0), `FUZZ_TARGET` (a comma list; default all), appending to `FUZZ_TALLY`.
#[test]
#[ignore = "the long pass of `make fuzz`"]
fn fuzz_cli_long() {
    let var = |k: &str| std::env::var(k).ok();
    let secs: f64 = var("FUZZ_SECS")
        .and_then(|s| s.parse().ok())
        .unwrap_or(10.0);
    let seed: u64 = var("FUZZ_SEED").and_then(|s| s.parse().ok()).unwrap_or(0);
    let only = var("FUZZ_TARGET").unwrap_or_else(|| "all".into());
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/fuzz");
    let mut reports = Vec::new();
    for t in targets() {
        if only != "all" && !only.split(',').any(|n| n == t.name) {
            continue;
        }
        let r = run(&t, seed, &Limits::long(secs, out.clone()));
        println!("{}", r.summary());
        reports.push(r);
    }
    if let Some(p) = var("FUZZ_TALLY") {
        engine::driver::append_tally(Path::new(&p), seed, &reports).expect("writing the tally");
    }
    let _ = std::fs::remove_dir_all(scratch_dir("cli"));
    check(&reports);
}

/// `fuzz --replay` for the binary's targets: reads the file `FUZZ_REPLAY` with the target
/// `FUZZ_TARGET` once, prints the outcome, time and memory, and fails when the input breaks a
/// rule of the long pass (a panic is the reader's own: run with `RUST_BACKTRACE=1`).
#[test]
#[ignore = "replays the input FUZZ_REPLAY with the target FUZZ_TARGET"]
fn fuzz_cli_replay() {
    let (Ok(name), Ok(file)) = (std::env::var("FUZZ_TARGET"), std::env::var("FUZZ_REPLAY")) else {
        panic!("set FUZZ_TARGET (a target name) and FUZZ_REPLAY (the input's file)");
    };
    let all = targets();
    let Some(t) = all.iter().find(|t| t.name == name) else {
        let names: Vec<_> = all.iter().map(|t| t.name).collect();
        panic!("no target {name:?}; targets: {}", names.join(", "));
    };
    let input = std::fs::read(&file).unwrap_or_else(|e| panic!("{file}: {e}"));
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/fuzz");
    let r = engine::driver::replay(t, &input, &Limits::long(0.0, out));
    println!("{}", r.summary());
    let _ = std::fs::remove_dir_all(scratch_dir("cli"));
    assert!(r.broken.is_empty(), "{}", r.summary());
}

#[test]
fn a_saved_input_is_replayed_with_its_memory_counted() {
    // What fuzz_cli_replay does, on a config file that sets a value out of its range.
    let all = targets();
    let t = all.iter().find(|t| t.name == "config-toml").unwrap();
    let r = engine::driver::replay(
        t,
        b"[orb]\nscale_factor = 0.5\n",
        &Limits::long(0.0, std::env::temp_dir()),
    );
    let e = r.outcome.as_ref().unwrap_err();
    assert!(
        e.contains("config.toml") && e.contains("scale_factor = 0.5"),
        "{e}"
    );
    assert!(
        r.peak_bytes.is_some() && r.broken.is_empty(),
        "{}",
        r.summary()
    );
}

#[test]
fn a_systems_timeout_too_large_for_a_duration_is_refused() {
    // Found while writing this target (reading `resolve` for what a value can break):
    // `timeout_s = 1e300` passed the positive check, then panicked in Duration::from_secs_f64.
    let dir = scratch_dir("cli-timeout");
    let p = dir.join("systems.toml");
    std::fs::write(
        &p,
        "[systems.s]\ntimeout_s = 1e300\n[systems.s.rgbd]\ncommand = [\"x\"]\n",
    )
    .unwrap();
    let e = format!(
        "{:#}",
        crate::external::system::systems_in_file(&p).unwrap_err()
    );
    assert!(
        e.contains("systems.toml") && e.contains("timeout_s = 1000000") && e.contains("a year"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(dir);
}
