//! End-to-end tests of `noisefree run`: the embedded synthetic default, its outputs, bit-exact
//! reproducibility from a seed, and clean errors on bad input.

mod common;

use common::{assert_clean_failure, noisefree, noisefree_ok, tmpdir};

#[test]
fn default_run_writes_outputs_and_is_reproducible() {
    let a = tmpdir("a");
    let b = tmpdir("b");
    for d in [&a, &b] {
        let out = noisefree(&[
            "run",
            "--frames",
            "60",
            "--quiet",
            "--out",
            d.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains("kinect [orb] seed 0: ATE RMSE"), "{stdout}");
    }
    let traj_a = std::fs::read(a.join("trajectory.txt")).unwrap();
    assert_eq!(
        traj_a,
        std::fs::read(b.join("trajectory.txt")).unwrap(),
        "same seed, same bytes"
    );
    let t = ate_eval::io::read_tum(&a.join("trajectory.txt")).unwrap();
    assert_eq!(t.len(), 60, "every frame tracked");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("summary.json")).unwrap()).unwrap();
    let ate = summary["ate_rmse_m"].as_f64().unwrap();
    // The kinect preset with an ORB-SLAM2-class baseline: millimetres, well under 3 cm.
    assert!(ate < 0.03, "ATE {ate}");
    let frames = std::fs::read_to_string(a.join("frames.csv")).unwrap();
    assert_eq!(frames.lines().count(), 61);
    assert!(frames.starts_with("timestamp,state,n_keypoints,n_matches,n_inliers,n_outliers"));
}

#[test]
fn several_runs_write_a_folder_each_and_a_summary() {
    let d = tmpdir("multi");
    let out = noisefree(&[
        "run",
        "--seq",
        "clean",
        "--frames",
        "30",
        "--runs",
        "2",
        "--quiet",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(d.join("seed0/trajectory.txt").exists() && d.join("seed1/trajectory.txt").exists());
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["runs"].as_array().unwrap().len(), 2);
}

#[test]
fn unknown_sequence_suggests_names() {
    let out = noisefree(&["run", "--seq", "fr2_cok", "--quiet"]);
    assert_clean_failure(&out, "fr2_coke");
}

#[test]
fn missing_folder_and_missing_dataset_are_clean_errors() {
    let out = noisefree(&["run", "--path", "/no/such/sequence", "--quiet"]);
    assert_clean_failure(&out, "/no/such/sequence");
    let empty = tmpdir("data");
    std::fs::create_dir_all(&empty).unwrap();
    let out = noisefree(&[
        "run",
        "--seq",
        "fr1_desk",
        "--data-dir",
        empty.to_str().unwrap(),
        "--quiet",
    ]);
    assert_clean_failure(&out, "noisefree fetch fr1_desk");
}

#[test]
fn bad_config_file_is_a_clean_error() {
    let d = tmpdir("cfg");
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join("bad.toml");
    std::fs::write(&p, "seed = \"not a number\"\n").unwrap();
    let out = noisefree(&[
        "run",
        "--frames",
        "5",
        "--config",
        p.to_str().unwrap(),
        "--quiet",
    ]);
    assert_clean_failure(&out, "bad.toml");
}

#[test]
fn mapping_lag_makes_seeded_runs_differ() {
    let d = tmpdir("lag");
    let out = noisefree(&[
        "run",
        "--frames",
        "60",
        "--runs",
        "2",
        "--mapping-lag",
        "3",
        "--quiet",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = |seed: &str| std::fs::read_to_string(d.join(seed).join("trajectory.txt")).unwrap();
    let (a, b) = (read("seed0"), read("seed1"));
    assert_eq!(a.lines().filter(|l| !l.starts_with('#')).count(), 60);
    assert_ne!(a, b);
    let _ = std::fs::remove_dir_all(&d);
}

/// `NOISEFREE_SYNTH_CACHE`: the first run renders its frames into the folder, the second reads
/// them, and both write the trajectory of a run without the cache, byte for byte.
#[test]
fn the_frame_cache_gives_the_trajectory_of_rendering() {
    let cache = tmpdir("frame-cache");
    let run = |out: &std::path::Path, cache: Option<&std::path::Path>| {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_noisefree"));
        cmd.args([
            "run",
            "--seq",
            "walking",
            "--frames",
            "12",
            "--synth-seed",
            "7",
        ])
        .args(["--quiet", "--out", out.to_str().unwrap()]);
        match cache {
            Some(c) => cmd.env(synth::CACHE_ENV, c),
            None => cmd.env_remove(synth::CACHE_ENV),
        };
        let o = cmd.output().expect("binary runs");
        common::assert_ok(&o);
        std::fs::read(out.join("trajectory.txt")).unwrap()
    };
    let plain = run(&tmpdir("cache-plain"), None);
    let first = run(&tmpdir("cache-first"), Some(&cache));
    // One build folder holding the 12 frames (and the frame a depth image may borrow).
    let builds: Vec<_> = std::fs::read_dir(&cache).unwrap().flatten().collect();
    assert_eq!(builds.len(), 1, "one build's folder");
    let files: Vec<_> = std::fs::read_dir(builds[0].path())
        .unwrap()
        .flatten()
        .collect();
    assert!(
        (12..=13).contains(&files.len()),
        "{} frames cached",
        files.len()
    );
    let stamps = |files: &[std::fs::DirEntry]| -> Vec<std::time::SystemTime> {
        files
            .iter()
            .map(|f| f.metadata().unwrap().modified().unwrap())
            .collect()
    };
    let written = stamps(&files);
    let second = run(&tmpdir("cache-second"), Some(&cache));
    assert_eq!(stamps(&files), written, "the second run read, not rewrote");
    assert_eq!(first, plain, "rendered through the cache: the same bytes");
    assert_eq!(second, plain, "read from the cache: the same bytes");
    // A frame damaged on disk is rendered again: still the same trajectory.
    let victim = files[0].path();
    let mut bytes = std::fs::read(&victim).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0xff;
    std::fs::write(&victim, &bytes).unwrap();
    assert_eq!(run(&tmpdir("cache-third"), Some(&cache)), plain);
    let _ = std::fs::remove_dir_all(&cache);
}

#[test]
fn fetch_list_lines_up_its_columns_and_names_what_each_twin_imitates() {
    let out = noisefree_ok(&[
        "fetch",
        "--list",
        "--data-dir",
        "/nonexistent-noisefree-data",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines.len() > 20, "{text}");
    // A header names the columns; each column starts where its header does on every line,
    // preceded by two blanks.
    let header = lines[0];
    let starts: Vec<usize> = ["class", "twin", "state"]
        .iter()
        .map(|h| header.find(&format!("  {h}")).unwrap() + 2)
        .collect();
    assert!(header.starts_with("name "), "{header}");
    for l in &lines[1..] {
        for &s in &starts {
            assert_eq!(&l[s - 2..s], "  ", "{l:?}");
            assert_ne!(&l[s..s + 1], " ", "{l:?}");
        }
    }
    let column = |l: &str, i: usize| {
        l[starts[i]..]
            .split_whitespace()
            .next()
            .unwrap()
            .to_string()
    };
    let row = |name: &str| {
        *lines
            .iter()
            .find(|l| l.split_whitespace().next() == Some(name))
            .unwrap()
    };
    let twin = row("twin_fr3_office");
    assert!(twin.ends_with("synthetic, imitates fr3_office"), "{twin}");
    // A real sequence names its twin; a synthetic one has none.
    assert_eq!(column(row("fr1_desk"), 1), "twin_fr1_desk");
    assert_eq!(column(row("fr1_desk"), 0), "easy");
    assert_eq!(column(row("twin_fr1_desk"), 1), "-");
}

#[test]
fn a_frame_cache_cap_that_is_not_a_number_is_refused_before_anything_runs() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_noisefree"))
        .args(["run", "--seq", "kinect", "--frames", "3"])
        .envs([common::synth_cache_env(), (synth::CACHE_LIMIT_ENV, "lots")])
        .output()
        .expect("binary runs");
    assert_clean_failure(&out, "NOISEFREE_SYNTH_CACHE_GB=lots");
    assert!(!String::from_utf8_lossy(&out.stdout).contains("ATE"));
}

#[test]
fn a_missing_ground_truth_is_named_as_such_and_the_ate_has_three_digits() {
    let seq = tmpdir("no-gt-seq");
    noisefree_ok(&[
        "synth",
        "--preset",
        "kinect",
        "--frames",
        "30",
        "--out",
        seq.to_str().unwrap(),
    ]);
    let out = tmpdir("no-gt-out");
    let with = noisefree_ok(&[
        "run",
        "--path",
        seq.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&with.stdout).into_owned();
    // "ATE RMSE 0.00123 m": three significant digits, whatever the size.
    let ate = text
        .split("ATE RMSE ")
        .nth(1)
        .unwrap()
        .split(" m,")
        .next()
        .unwrap();
    let digits: String = ate
        .trim_start_matches(['0', '.'])
        .chars()
        .filter(char::is_ascii_digit)
        .collect();
    assert_eq!(digits.len(), 3, "{text}");
    std::fs::remove_file(seq.join("groundtruth.txt")).unwrap();
    let without = noisefree_ok(&[
        "run",
        "--path",
        seq.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&without.stdout);
    assert!(
        text.contains("ATE RMSE n/a (the sequence has no ground truth)"),
        "{text}"
    );
    // A sweep of it tracks, is not a failure, and its table says n/a, not F.
    let swept = out.join("sweep");
    noisefree_ok(&[
        "sweep",
        "--path",
        seq.to_str().unwrap(),
        "--configs",
        "orb",
        "--quiet",
        "--out",
        swept.to_str().unwrap(),
    ]);
    noisefree_ok(&["table", swept.to_str().unwrap()]);
    let t3 = std::fs::read_to_string(swept.join("table3.md")).unwrap();
    assert!(t3.contains("| n/a |"), "{t3}");
    assert!(t3.contains("'n/a': the runs tracked"), "{t3}");
    for d in [seq, out] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn a_run_that_replaces_an_earlier_runs_files_says_so() {
    let out = tmpdir("replace");
    let run = || {
        noisefree_ok(&[
            "run",
            "--frames",
            "20",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let first = run();
    assert!(!String::from_utf8_lossy(&first.stderr).contains("replaced"));
    let second = run();
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(
        err.contains("note: replaced the files of an earlier run in"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn the_camera_of_a_folder_is_said_and_a_guess_is_a_warning_saying_how_to_give_it() {
    let root = tmpdir("camera-said");
    // A twin of fr1 written under a name that says no camera carries its camera file, and
    // `run --path` reads the folder with it: as with --camera, bit for bit.
    let own = root.join("mine");
    noisefree_ok(&[
        "synth",
        "--preset",
        "twin_fr1_xyz",
        "--frames",
        "12",
        "--out",
        own.to_str().unwrap(),
    ]);
    let run = |dir: &std::path::Path, out: &str, extra: &[&str]| {
        let mut args = vec!["run", "--path", dir.to_str().unwrap(), "--quiet", "--out"];
        let out = root.join(out);
        let out = out.to_str().unwrap().to_string();
        args.push(&out);
        args.extend_from_slice(extra);
        let o = noisefree_ok(&args);
        let traj = std::fs::read_to_string(root.join(&out).join("trajectory.txt")).unwrap();
        (String::from_utf8_lossy(&o.stderr).into_owned(), traj)
    };
    let (said, by_itself) = run(&own, "own", &[]);
    assert!(
        said.contains("from its own camera-orbslam2.yaml") && !said.contains("warning"),
        "{said}"
    );
    let settings = own.join("camera-orbslam2.yaml");
    let (_, given) = run(&own, "given", &["--camera", settings.to_str().unwrap()]);
    assert_eq!(
        by_itself, given,
        "the folder's camera file is the camera it runs with"
    );
    // Without the file, the name decides, and a name that says nothing is a warned guess.
    for f in ["camera-orbslam2.yaml", "camera-orbslam3.yaml"] {
        std::fs::remove_file(own.join(f)).unwrap();
    }
    let named = root.join("rgbd_dataset_freiburg1_mine");
    std::fs::rename(&own, &named).unwrap();
    let (said, by_name) = run(&named, "named", &[]);
    assert!(
        said.contains("TUM Fr1's") && said.contains("from the folder's name"),
        "{said}"
    );
    assert_eq!(
        by_itself, by_name,
        "the folder's own camera file gives the trajectory its TUM name gives"
    );
    let bare = root.join("bare");
    std::fs::rename(&named, &bare).unwrap();
    let (warned, _) = run(&bare, "bare", &[]);
    assert!(
        warned.contains("warning:") && warned.contains("assuming freiburg3's"),
        "{warned}"
    );
    assert!(warned.contains("--camera FILE.yaml"), "{warned}");
    let _ = std::fs::remove_dir_all(root);
}
