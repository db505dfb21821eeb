//! End-to-end test of `noisefree sweep` + `noisefree table` on small synthetic sequences:
//! the CSV rows, resumption after an interruption (no duplicates, same table), shard merging
//! (N shards = one unsharded sweep) and the Markdown table.

mod common;

use common::{assert_clean_failure, assert_ok, noisefree, noisefree_ok, tmpdir};
use std::path::Path;

const FRAMES: &str = "25";

fn sweep(out: &Path, extra: &[&str]) {
    let mut args = vec![
        "sweep",
        "--seq",
        "clean,kinect",
        "--configs",
        "orb,mcor",
        "--runs",
        "3",
        "--frames",
        FRAMES,
        "--quiet",
        "--jobs",
        "2",
        "--out",
    ];
    let o = out.to_str().unwrap();
    args.push(o);
    args.extend_from_slice(extra);
    noisefree_ok(&args);
}

/// Rows without the timing columns (fps, wall_s), sorted: what must not depend on the machine.
fn rows(dir: &Path, file: &str) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join(file)).unwrap();
    let mut v: Vec<String> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').take(15).collect::<Vec<_>>().join(","))
        .collect();
    v.sort();
    v
}

fn all_rows(dir: &Path) -> Vec<String> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let n = e.unwrap().file_name().to_string_lossy().into_owned();
        if n.starts_with("runs") && n.ends_with(".csv") {
            v.extend(rows(dir, &n));
        }
    }
    v.sort();
    v
}

#[test]
fn sweep_resume_shards_and_table() {
    // A whole sweep in one go.
    let full = tmpdir("full");
    sweep(&full, &[]);
    let full_rows = rows(&full, "runs.csv");
    assert_eq!(full_rows.len(), 2 * 2 * 3, "{full_rows:#?}");
    let header = std::fs::read_to_string(full.join("runs.csv")).unwrap();
    assert!(
        header.starts_with("sequence,config,tau_mf,tau_gf,tau_mg,baseline,seed,ate_rmse,failed")
    );
    for r in &full_rows {
        let f: Vec<&str> = r.split(',').collect();
        assert!(["clean", "kinect"].contains(&f[0]));
        assert!(["orb", "mcor"].contains(&f[1]));
        assert_eq!(
            f[2].is_empty(),
            f[1] == "orb",
            "thresholds only for mcor: {r}"
        );
        let ate: f64 = f[7].parse().expect("ATE recorded");
        assert!(ate.is_finite() && ate >= 0.0);
        assert_eq!(f[9], FRAMES);
    }

    // Interrupted after 5 runs, then resumed: the same rows, none twice.
    let resumed = tmpdir("resumed");
    sweep(&resumed, &["--max-runs", "5"]);
    assert_eq!(rows(&resumed, "runs.csv").len(), 5);
    // Its tables say the folder is incomplete, and the findings leave it out, naming it.
    noisefree_ok(&["table", resumed.to_str().unwrap()]);
    let index = std::fs::read_to_string(resumed.join("README.md")).unwrap();
    assert!(
        index.contains("**Incomplete:** 5 of 12 planned runs recorded (missing: "),
        "{index}"
    );
    let o = noisefree_ok(&["report", resumed.to_str().unwrap()]);
    let findings = String::from_utf8_lossy(&o.stdout);
    assert!(
        findings.contains("Left out until their sweeps finish: ")
            && findings.contains("5 of 12 planned runs recorded"),
        "{findings}"
    );
    sweep(&resumed, &[]);
    assert_eq!(rows(&resumed, "runs.csv"), full_rows);
    // A third invocation has nothing left to do.
    sweep(&resumed, &[]);
    assert_eq!(rows(&resumed, "runs.csv").len(), 12);

    // Three shards in one folder = the unsharded sweep.
    let sharded = tmpdir("sharded");
    for k in 1..=3 {
        sweep(&sharded, &["--shard", &format!("{k}/3")]);
    }
    assert_eq!(all_rows(&sharded), full_rows);

    // Tables: identical Table III from all three folders, in Markdown with both configurations.
    for d in [&full, &resumed, &sharded] {
        noisefree_ok(&["table", d.to_str().unwrap()]);
        let index = std::fs::read_to_string(d.join("README.md")).unwrap();
        assert!(!index.contains("Incomplete"), "{index}");
    }
    // What the sweeps cost: every run once in the folders' cost records (the resumed folder's
    // over the two invocations that ran something, the sharded one's over its three shards),
    // and the index sums them.
    for (d, invocations) in [(&full, 1), (&resumed, 2), (&sharded, 3)] {
        let mut runs = 0;
        let mut frames = 0;
        let mut cpu = 0.0;
        let mut stamps = std::collections::BTreeSet::new();
        for e in std::fs::read_dir(d).unwrap() {
            let n = e.unwrap().file_name().to_string_lossy().into_owned();
            if !(n.starts_with("cost") && n.ends_with(".csv")) {
                continue;
            }
            let text = std::fs::read_to_string(d.join(&n)).unwrap();
            let mut lines = text.lines();
            assert_eq!(
                lines.next(),
                Some("invocation,point,runs,frames,cpu_s,wall_s")
            );
            for l in lines {
                let f: Vec<&str> = l.split(',').collect();
                stamps.insert((n.clone(), f[0].to_string()));
                assert!(["clean", "kinect"].contains(&f[1]), "{l}");
                runs += f[2].parse::<usize>().unwrap();
                frames += f[3].parse::<usize>().unwrap();
                let c: f64 = f[4].parse().unwrap();
                assert!(c > 0.0 && f[5].parse::<f64>().unwrap() > 0.0, "{l}");
                cpu += c;
            }
        }
        assert_eq!((runs, frames), (12, 12 * 25), "{}", d.display());
        assert_eq!(stamps.len(), invocations, "{stamps:?}");
        let index = std::fs::read_to_string(d.join("README.md")).unwrap();
        assert!(
            index.contains("Cost (`cost.csv`): every recorded run, 300 frames run in "),
            "{index}"
        );
        let per_core: f64 = index
            .split(" frames/s per core")
            .next()
            .and_then(|h| h.rsplit(' ').next())
            .and_then(|x| x.parse().ok())
            .unwrap_or_else(|| panic!("no frames/s per core in {index}"));
        assert!((per_core - 300.0 / cpu).abs() <= 0.051, "{per_core} {cpu}");
    }
    let t_full = std::fs::read_to_string(full.join("table3.md")).unwrap();
    assert_eq!(
        t_full,
        std::fs::read_to_string(resumed.join("table3.md"))
            .unwrap()
            .replace(&*resumed.to_string_lossy(), &full.to_string_lossy())
    );
    assert_eq!(
        t_full,
        std::fs::read_to_string(sharded.join("table3.md")).unwrap()
    );
    assert!(
        t_full.contains("| sequence | class | ORB-SLAM2 (ours) | w/ MC-OR (ours) |"),
        "{t_full}"
    );
    assert!(
        t_full.contains("| clean | synthetic |") && t_full.contains("| kinect | synthetic |"),
        "{t_full}"
    );
    assert!(full.join("table3.csv").exists() && full.join("table4.md").exists());
    // No revisit in 25 frames: the loops table says no run closed a loop.
    let loops = std::fs::read_to_string(full.join("loops.md")).unwrap();
    assert!(
        loops.contains("| clean | 0 (0/3 runs) | 0 (0/3 runs) |")
            && loops.contains("| kinect | 0 (0/3 runs) | 0 (0/3 runs) |"),
        "{loops}"
    );
}

#[test]
fn vary_sequence_gives_each_run_its_own_realization() {
    let d = tmpdir("vary");
    let o = d.to_str().unwrap();
    noisefree_ok(&[
        "sweep",
        "--seq",
        "kinect",
        "--configs",
        "orb",
        "--runs",
        "2",
        "--frames",
        "30",
        "--quiet",
        "--out",
        o,
        "--vary-sequence",
        "--synth-seed",
        "5",
    ]);
    let text = std::fs::read_to_string(d.join("runs.csv")).unwrap();
    let mut rows: Vec<Vec<String>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    rows.sort_by(|a, b| a[6].cmp(&b[6]));
    assert_eq!(rows.len(), 2);
    assert_eq!(
        (rows[0][17].as_str(), rows[1][17].as_str()),
        ("5", "6"),
        "synth_seed = 5 + seed"
    );
    assert_ne!(
        rows[0][7], rows[1][7],
        "different noise realizations give different ATEs"
    );
}

#[test]
fn mapping_lag_is_pinned_per_folder() {
    let tiny = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "sweep",
            "--seq",
            "kinect",
            "--configs",
            "orb",
            "--runs",
            "1",
            "--frames",
            "20",
            "--quiet",
            "--jobs",
            "1",
            "--out",
        ];
        args.push(out.to_str().unwrap());
        args.extend_from_slice(extra);
        noisefree(&args)
    };
    // A synchronous folder refuses lagged runs (they would be resumed as the recorded ones).
    let sync = tmpdir("lag-sync");
    assert_ok(&tiny(&sync, &[]));
    let settings = std::fs::read_to_string(sync.join("sweep-settings.toml")).unwrap();
    assert!(settings.contains("mapping_lag = 0"), "{settings}");
    assert!(
        settings.contains("vocabulary = \"built-in noisefree-k10L5.voc"),
        "{settings}"
    );
    // Runs of another vocabulary are refused too.
    assert_clean_failure(
        &tiny(&sync, &["--vocabulary", "none"]),
        "vocabulary built-in",
    );
    assert_clean_failure(&tiny(&sync, &["--mapping-lag", "2"]), "--mapping-lag 0");
    // A fresh folder takes the lag, records it, resumes with it and refuses another.
    let lagged = tmpdir("lag-2");
    assert_ok(&tiny(&lagged, &["--mapping-lag", "2"]));
    let settings = std::fs::read_to_string(lagged.join("sweep-settings.toml")).unwrap();
    assert!(settings.contains("mapping_lag = 2"), "{settings}");
    assert_ok(&tiny(&lagged, &["--mapping-lag", "2"]));
    assert_clean_failure(&tiny(&lagged, &[]), "--mapping-lag 2");
    // The tables say how the runs were made.
    noisefree_ok(&["table", lagged.to_str().unwrap()]);
    noisefree_ok(&["table", sync.to_str().unwrap()]);
    let t3 = std::fs::read_to_string(lagged.join("table3.md")).unwrap();
    assert!(t3.contains("--mapping-lag 2"), "{t3}");
    let t3 = std::fs::read_to_string(sync.join("table3.md")).unwrap();
    assert!(t3.contains("Runs are synchronous"), "{t3}");
    for d in [sync, lagged] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn table_draws_rc_against_the_baseline_where_both_ran() {
    let dir = tmpdir("rc-figure");
    let d = dir.to_str().unwrap();
    noisefree_ok(&[
        "sweep",
        "--seq",
        "kinect",
        "--configs",
        "orb,rc",
        "--runs",
        "2",
        "--frames",
        FRAMES,
        "--quiet",
        "--jobs",
        "2",
        "--out",
        d,
    ]);
    noisefree_ok(&["table", d]);
    for f in ["ate_spread.png", "rc_vs_baseline.png", "rc_vs_baseline.svg"] {
        let p = dir.join("figures").join(f);
        let len = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
        assert!(len > 1000, "{} missing or empty", p.display());
    }
    // A folder without rc has no such figure.
    let plain = tmpdir("no-rc-figure");
    let p = plain.to_str().unwrap();
    noisefree_ok(&[
        "sweep",
        "--seq",
        "kinect",
        "--configs",
        "orb",
        "--runs",
        "1",
        "--frames",
        FRAMES,
        "--quiet",
        "--out",
        p,
    ]);
    noisefree_ok(&["table", p]);
    assert!(plain.join("figures/ate_spread.png").exists());
    assert!(!plain.join("figures/rc_vs_baseline.png").exists());
}

#[test]
fn table3_sweeps_every_row_s_twin_under_five_columns() {
    // The rows and their twins as the catalog states them.
    let catalog = datasets::Catalog::embedded();
    let rows: Vec<&str> = catalog
        .entries()
        .iter()
        .filter(|e| !e.is_synthetic() && e.paper.is_some())
        .map(|e| e.name.as_str())
        .collect();
    assert_eq!(rows.len(), 31, "Table III: 20 TUM and 11 EuRoC rows");
    let missing: Vec<&str> = rows
        .iter()
        .copied()
        .filter(|r| catalog.twin_of(r).is_none())
        .collect();
    assert!(missing.is_empty(), "rows without a twin: {missing:?}");
    let twins = rows.len();
    // Planned, nothing run (--max-runs 0): 5 columns x 10 runs per twin.
    let out = tmpdir("sweep-table3");
    let o = noisefree_ok(&[
        "sweep",
        "--table3",
        "--max-runs",
        "0",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!("{} runs in the sweep", twins * 5 * 10)),
        "{err}"
    );
    assert!(!err.contains("without a twin"), "{err}");
    // --configs replaces the five columns.
    let o = noisefree_ok(&[
        "sweep",
        "--table3",
        "--configs",
        "orb",
        "--runs",
        "2",
        "--max-runs",
        "0",
        "--out",
        tmpdir("sweep-table3-orb").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!("{} runs in the sweep", twins * 2)),
        "{err}"
    );
}

#[test]
fn readings_stand_side_by_side_as_columns_and_a_folder_pins_its_configs_readings() {
    let tiny = |out: &Path, configs: &str, extra: &[&str]| {
        let mut args = vec![
            "sweep",
            "--seq",
            "kinect",
            "--configs",
            configs,
            "--runs",
            "1",
            "--frames",
            "20",
            "--baseline",
            "0.05",
            "--quiet",
            "--jobs",
            "2",
            "--out",
        ];
        args.push(out.to_str().unwrap());
        args.extend_from_slice(extra);
        noisefree(&args)
    };
    let dir = tmpdir("readings-columns");
    assert_ok(&tiny(
        &dir,
        "orb,mcor,mcor:sightings=all,mcor:paper,orb:b_role=camera",
        &[],
    ));
    let runs = std::fs::read_to_string(dir.join("runs.csv")).unwrap();
    assert!(
        !dir.join("runs.csv.lock").exists(),
        "a finished sweep leaves no lock"
    );
    for key in [
        "kinect,mcor:sightings=all,0.7,0.7,0.5,,0,",
        "kinect,mcor:sightings=all:verdict=consensus:scope=tracking+mapping,0.7,0.7,0.5,,0,",
        // b as the baseline's camera baseline: the --baseline values apply to it.
        "kinect,orb:b_role=camera,,,,0.05,0,",
        "kinect,orb,,,,,0,",
    ] {
        assert!(runs.contains(key), "{key} in {runs}");
    }
    noisefree_ok(&["table", dir.to_str().unwrap()]);
    let t3 = std::fs::read_to_string(dir.join("table3.md")).unwrap();
    assert!(t3.contains("w/ MC-OR [sightings all] (ours)"), "{t3}");
    assert!(
        t3.contains("w/ MC-OR [sightings all, verdict consensus, scope tracking+mapping] (ours)"),
        "{t3}"
    );
    let versus = std::fs::read_to_string(dir.join("versus-baseline.md")).unwrap();
    assert!(
        versus.contains("ORB-SLAM2 [b role camera] (ours)"),
        "{versus}"
    );
    // A reading that is not one is refused naming those that are.
    assert_clean_failure(
        &tiny(&dir, "orb,mcor:verdict=vote", &[]),
        "filter or consensus",
    );
    assert_clean_failure(&tiny(&dir, "avc:sightings=all", &[]), "MC-OR");
    // A typo is answered with the name meant.
    assert_clean_failure(&tiny(&dir, "orb,mcorr", &[]), "did you mean `mcor`?");
    // The folder's configuration file is pinned: a file that sets a reading for every mcor
    // run is refused where runs of the default readings are.
    let file = dir.join("all-sightings.toml");
    std::fs::write(&file, "[mcor]\nsightings = \"all\"\n").unwrap();
    let f = file.to_str().unwrap();
    assert_clean_failure(
        &tiny(&dir, "mcor", &["--config", f]),
        "mcor.sightings = \"all\"",
    );
    let pinned = tmpdir("readings-pinned");
    assert_ok(&tiny(&pinned, "orb,mcor", &["--config", f]));
    let settings = std::fs::read_to_string(pinned.join("sweep-settings.toml")).unwrap();
    assert!(
        settings.contains("readings = [\"mcor.sightings = \\\"all\\\"\"]"),
        "{settings}"
    );
    assert_clean_failure(&tiny(&pinned, "orb,mcor", &[]), "default readings");
    for d in [dir, pinned] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn first_seed_gives_fresh_draws_of_slam_and_perturbation() {
    let dir = tmpdir("first-seed");
    noisefree_ok(&[
        "sweep",
        "--seq",
        "kinect",
        "--configs",
        "orb",
        "--runs",
        "2",
        "--first-seed",
        "10",
        "--frames",
        "20",
        "--perturb",
        "depth-axial:1",
        "--quiet",
        "--jobs",
        "2",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(dir.join("runs.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (seed, pseed) = (col("seed"), col("perturb_seed"));
    let mut pairs: Vec<(String, String)> = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[seed].to_string(), f[pseed].to_string())
        })
        .collect();
    pairs.sort();
    // Run k draws SLAM seed 10 + k and perturbation draw 10 + k: none of seeds 0..9's draws.
    assert_eq!(
        pairs,
        [("10", "10"), ("11", "11")].map(|(a, b)| (a.to_string(), b.to_string()))
    );
    // Table III names the seeds its runs used.
    let plain = tmpdir("first-seed-plain");
    noisefree_ok(&[
        "sweep",
        "--seq",
        "kinect",
        "--configs",
        "orb",
        "--runs",
        "2",
        "--first-seed",
        "10",
        "--frames",
        "20",
        "--quiet",
        "--out",
        plain.to_str().unwrap(),
    ]);
    noisefree_ok(&["table", plain.to_str().unwrap()]);
    let t3 = std::fs::read_to_string(plain.join("table3.md")).unwrap();
    assert!(t3.contains("(seeds 10..11)"), "{t3}");
    for d in [dir, plain] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn a_sweep_whose_runs_are_one_run_says_so_and_how_to_make_them_vary() {
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "sweep",
            "--seq",
            "kinect",
            "--configs",
            "orb,mcor",
            "--runs",
            "2",
            "--frames",
            "20",
            "--quiet",
            "--out",
        ];
        args.push(out.to_str().unwrap());
        args.extend_from_slice(extra);
        noisefree_ok(&args)
    };
    let sync = tmpdir("identical-sync");
    let o = run(&sync, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("in 2 of the 2 cells with several runs every run gave the same result"),
        "{err}"
    );
    assert!(err.contains("--mapping-lag 3"), "{err}");
    noisefree_ok(&["table", sync.to_str().unwrap()]);
    let t3 = std::fs::read_to_string(sync.join("table3.md")).unwrap();
    assert!(t3.contains("In 2 of the 2 cells with several runs"), "{t3}");
    // The findings say why nothing was compared, not "0 reproduce a gain".
    let report = noisefree_ok(&["report", sync.to_str().unwrap()]);
    let md = String::from_utf8_lossy(&report.stdout);
    assert!(
        md.contains("Nothing could be compared: in 1 cell every run"),
        "{md}"
    );
    assert!(md.contains("unperturbed, no comparison"), "{md}");
    let _ = std::fs::remove_dir_all(sync);
}
