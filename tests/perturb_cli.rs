//! `noisefree perturb` and `run --perturb`: a perturbed folder written by `perturb` and run as
//! any folder gives the same trajectory, bit for bit, as the internal run under the same
//! perturbation (RGB-D synthetic, stereo synthetic, and the real EuRoC frames of ../shared);
//! bad perturbations are refused before anything runs.

mod common;

use common::{assert_clean_failure, noisefree, noisefree_ok, tmpdir};
use std::path::Path;

/// `exact_ate`: the ATE too is the same to the bit (synthetic sequences); a real EuRoC folder's
/// body-camera extrinsic passes through sensor.yaml's 4x4 matrix text, whose rotation reads back
/// within an ulp or so, so its ATE (body frame) agrees to 1e-12 relative.
fn same_trajectory(src: &[&str], chain: &str, frames: &str, name: &str, exact_ate: bool) {
    let dir = tmpdir(name);
    let folder = dir.join("perturbed");
    let f = folder.to_str().unwrap();
    let mut args = vec![
        "perturb",
        "--perturb",
        chain,
        "--frames",
        frames,
        "-o",
        f,
        "--quiet",
    ];
    args.extend_from_slice(src);
    let sheet = dir.join("sheet.png");
    args.extend_from_slice(&["--contact-sheet", sheet.to_str().unwrap()]);
    noisefree_ok(&args);
    assert!(sheet.is_file());
    let note = std::fs::read_to_string(folder.join("perturbation.txt")).unwrap();
    assert!(note.contains(&format!("perturbation {chain}")), "{note}");
    let (a, b) = (dir.join("internal"), dir.join("external"));
    let mut run = vec![
        "run",
        "--perturb",
        chain,
        "--frames",
        frames,
        "--quiet",
        "--out",
        a.to_str().unwrap(),
    ];
    run.extend_from_slice(src);
    noisefree_ok(&run);
    let camera = folder.join("camera-orbslam2.yaml");
    noisefree_ok(&[
        "run",
        "--path",
        f,
        "--camera",
        camera.to_str().unwrap(),
        "--quiet",
        "--out",
        b.to_str().unwrap(),
    ]);
    let read = |d: &Path| std::fs::read_to_string(d.join("trajectory.txt")).unwrap();
    assert_eq!(read(&a), read(&b), "{chain} on {src:?}");
    let ate = |d: &Path| {
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap())
                .unwrap();
        s["ate_rmse_m"].as_f64().unwrap()
    };
    if exact_ate {
        assert_eq!(ate(&a).to_bits(), ate(&b).to_bits());
    } else {
        assert!(
            (ate(&a) / ate(&b) - 1.0).abs() < 1e-12,
            "{} {}",
            ate(&a),
            ate(&b)
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_perturbed_rgbd_folder_runs_bit_for_bit_as_the_internal_perturbation() {
    same_trajectory(
        &["--seq", "kinect"],
        "depth-axial:2+depth-lateral:1+depth-holes:5+occluders:1",
        "40",
        "perturb-rgbd",
        true,
    );
}

#[test]
fn a_perturbed_stereo_folder_runs_bit_for_bit_as_the_internal_perturbation() {
    same_trajectory(
        &["--seq", "stereo"],
        "image-noise:4+stereo-misalignment:0.1+stamp-jitter:2",
        "30",
        "perturb-stereo",
        true,
    );
}

#[test]
fn a_named_camera_chain_exports_its_camera_and_ground_truth_bit_for_bit() {
    // Depth families, the given camera and the scored ground truth all travel through the
    // folder: its settings carry the perturbed camera, its groundtruth.txt the perturbed truth.
    same_trajectory(
        &["--seq", "kinect"],
        "kinect-fr3:1",
        "40",
        "perturb-chain-rgbd",
        true,
    );
    same_trajectory(
        &["--seq", "stereo"],
        "euroc:2",
        "30",
        "perturb-chain-stereo",
        true,
    );
}

/// `Camera.NAME: value` of an ORB-SLAM2 settings file.
fn setting(yaml: &Path, name: &str) -> f64 {
    let text = std::fs::read_to_string(yaml).unwrap();
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with(&format!("{name}:")))
        .unwrap_or_else(|| panic!("{name} in {text}"));
    line.split(':').nth(1).unwrap().trim().parse().unwrap()
}

#[test]
fn focal_error_changes_the_settings_and_not_one_image_byte() {
    let dir = tmpdir("perturb-focal");
    let write = |chain: &str, name: &str| {
        let out = dir.join(name);
        noisefree_ok(&[
            "perturb",
            "--seq",
            "kinect",
            "--frames",
            "3",
            "--perturb",
            chain,
            "-o",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        out
    };
    let (clean, focal) = (
        write("focal-error:0", "clean"),
        write("focal-error:1", "focal"),
    );
    for sub in ["rgb", "depth"] {
        for i in 0..3 {
            let f = format!("{sub}/{i:06}.png");
            assert_eq!(
                std::fs::read(clean.join(&f)).unwrap(),
                std::fs::read(focal.join(&f)).unwrap(),
                "{f}"
            );
        }
    }
    let (a, b) = (
        clean.join("camera-orbslam2.yaml"),
        focal.join("camera-orbslam2.yaml"),
    );
    for key in ["Camera.fx", "Camera.fy"] {
        assert!(
            (setting(&b, key) / setting(&a, key) - 1.01).abs() < 1e-12,
            "{key}"
        );
    }
    for key in ["Camera.cx", "Camera.cy", "Camera.bf"] {
        assert_eq!(setting(&b, key), setting(&a, key), "{key}");
    }
    // A ground-truth family on a folder without ground truth is refused before anything runs.
    std::fs::remove_file(clean.join("groundtruth.txt")).unwrap();
    let o = dir.join("o");
    assert_clean_failure(
        &noisefree(&[
            "run",
            "--path",
            clean.to_str().unwrap(),
            "--perturb",
            "gt-offset:10",
            "--out",
            o.to_str().unwrap(),
        ]),
        "gt-offset does not apply to clean: it has no ground truth",
    );
    assert!(!o.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn real_euroc_frames_perturbed_run_bit_for_bit_as_the_internal_perturbation() {
    let euroc = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/data/euroc_v101_head"
    );
    if !Path::new(euroc).is_dir() {
        eprintln!("skipped: {euroc} is not on this machine");
        return;
    }
    same_trajectory(
        &["--path", euroc],
        "occluders:1+exposure:5",
        "30",
        "perturb-euroc",
        false,
    );
}

#[test]
fn bad_perturbations_are_refused_before_anything_runs() {
    let dir = tmpdir("perturb-bad");
    let out = dir.join("o");
    let o = out.to_str().unwrap();
    for (chain, needle) in [
        ("depth-nois:2", "unknown perturbation \"depth-nois\""),
        (
            "depth-axial:2000",
            "depth-axial:2000: the level must be 0 to 1000",
        ),
        ("frame-drop:1.5", "whole number"),
        ("depth-axial", "expected family:level"),
        (
            "kinect-fr9:1",
            "chains: kinect-fr1, kinect-fr2, kinect-fr3, euroc",
        ),
        ("kinect-fr1:100", "kinect-fr1:100: the level must be 0 to"),
        (
            "focal-error:25",
            "focal-error:25: the level must be -20 to 20",
        ),
    ] {
        assert_clean_failure(
            &noisefree(&["perturb", "--perturb", chain, "-o", o]),
            needle,
        );
        assert_clean_failure(&noisefree(&["run", "--perturb", chain, "--out", o]), needle);
        assert!(!out.exists(), "nothing written for {chain}");
    }
    assert_clean_failure(
        &noisefree(&[
            "run",
            "--seq",
            "stereo",
            "--perturb",
            "depth-holes:10",
            "--out",
            o,
        ]),
        "depth-holes does not apply to stereo, a stereo sequence",
    );
    assert!(!out.exists());
    let list = noisefree_ok(&["perturb", "--list"]);
    let text = String::from_utf8_lossy(&list.stdout);
    for f in [
        "depth-axial",
        "occluders",
        "stereo-misalignment",
        "x Nguyen sigma",
        "focal-error",
        "principal-point-error",
        "distortion-error",
        "depth-distortion",
        "depth-registration",
        "ir-shadow",
        "disparity-quantization",
        "gt-offset",
        "gt-jitter",
        "gt-hand-eye",
        "kinect-fr1: TUM freiburg1",
        "kinect-fr2",
        "kinect-fr3",
        "euroc: EuRoC",
        "Teichman",
    ] {
        assert!(text.contains(f), "{text}");
    }
}

/// (sequence, config, perturbation, seed) -> column -> value of a sweep's runs.csv.
fn records(dir: &Path) -> Vec<std::collections::BTreeMap<String, String>> {
    let mut rdr = csv::Reader::from_path(dir.join("runs.csv")).expect("runs.csv");
    let header: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
    rdr.records()
        .map(|r| {
            header
                .iter()
                .cloned()
                .zip(r.unwrap().iter().map(String::from))
                .collect()
        })
        .collect()
}

const SELF_COMMAND: &str = r#"["{noisefree}", "run", "--path", "{sequence}", "--camera", "{settings}", "--seed", "{seed}", "--frames", "{frames}", "--out", "{run_dir}/out", "--quiet"]"#;

#[test]
fn a_perturbation_sweep_records_every_point_and_external_systems_get_the_perturbed_folder() {
    let dir = tmpdir("perturb-sweep");
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = dir.join("systems.toml");
    std::fs::write(
        &cfg,
        format!(
            "[systems.self]\nlabel = \"noisefree (external)\"\nsettings = \"orbslam2\"\n\
             timeout_s = 600\n[systems.self.rgbd]\ncommand = {SELF_COMMAND}\n\
             trajectory = \"out/trajectory.txt\"\n"
        ),
    )
    .unwrap();
    let out = dir.join("sweep");
    let (out_s, cfg_s) = (out.to_str().unwrap(), cfg.to_str().unwrap());
    let sweep = [
        "sweep",
        "--seq",
        "kinect",
        "--frames",
        "40",
        "--runs",
        "1",
        "--configs",
        "orb,self",
        "--config",
        cfg_s,
        "--perturb",
        "depth-axial:0,4",
        "--perturb",
        "image-noise:0,6",
        "--perturb",
        "frame-drop:2",
        "--out",
        out_s,
    ];
    let first = noisefree_ok(&sweep);
    let err = String::from_utf8_lossy(&first.stderr);
    assert!(
        err.contains("ORB of the unperturbed frames reused"),
        "depth-only and time points reuse the unperturbed ORB: {err}"
    );
    let recs = records(&out);
    // 4 points (none, depth-axial:4, image-noise:6, frame-drop:2) x 2 systems.
    assert_eq!(recs.len(), 8, "{recs:?}");
    for point in ["none", "depth-axial:4", "image-noise:6", "frame-drop:2"] {
        let at = |c: &str| {
            recs.iter()
                .find(|r| r["config"] == c && r["perturbation"] == point)
                .unwrap_or_else(|| panic!("{c} at {point}"))
        };
        let (ours, theirs) = (at("orb"), at("self"));
        assert!(!ours["ate_rmse"].is_empty());
        assert_eq!(ours["ate_rmse"], theirs["ate_rmse"], "{point}: bit for bit");
        assert_eq!(
            ours["frames"],
            if point == "frame-drop:2" { "20" } else { "40" }
        );
    }
    let axial = recs
        .iter()
        .find(|r| r["perturbation"] == "depth-axial:4")
        .unwrap();
    assert_eq!(axial["perturb_family"], "depth-axial");
    assert_eq!(axial["perturb_level"], "4.0");
    // The internal run of a point equals `run --perturb` of it.
    let r = dir.join("run");
    noisefree_ok(&[
        "run",
        "--seq",
        "kinect",
        "--frames",
        "40",
        "--perturb",
        "depth-axial:4",
        "--quiet",
        "--out",
        r.to_str().unwrap(),
    ]);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(r.join("summary.json")).unwrap()).unwrap();
    let ours = recs
        .iter()
        .find(|r| r["config"] == "orb" && r["perturbation"] == "depth-axial:4")
        .unwrap();
    assert_eq!(
        ours["ate_rmse"].parse::<f64>().unwrap(),
        s["ate_rmse_m"].as_f64().unwrap()
    );
    // Resumed: nothing runs again.
    let again = noisefree_ok(&sweep);
    assert!(String::from_utf8_lossy(&again.stderr).contains("0 runs finished"));
    assert_eq!(records(&out).len(), 8);
    // Tables: one resilience table (Markdown + tidy CSV) and figure per family.
    noisefree_ok(&["table", out_s]);
    for f in ["depth-axial", "image-noise", "frame-drop"] {
        let md = std::fs::read_to_string(out.join(format!("resilience-{f}.md"))).unwrap();
        assert!(
            md.contains("noisefree (external)") && md.contains("breaking level"),
            "{md}"
        );
        assert!(out
            .join(format!("figures/resilience_{f}_kinect.png"))
            .is_file());
    }
    let t3 = std::fs::read_to_string(out.join("table3.md")).unwrap();
    assert!(t3.contains("kinect"), "{t3}");
    // A depth axis over a stereo sequence is refused before any run.
    let bad = dir.join("bad");
    assert_clean_failure(
        &noisefree(&[
            "sweep",
            "--seq",
            "kinect,stereo",
            "--frames",
            "20",
            "--runs",
            "1",
            "--perturb",
            "depth-lateral:0,2",
            "--out",
            bad.to_str().unwrap(),
        ]),
        "depth-lateral does not apply to stereo, a stereo sequence",
    );
    assert!(!bad.join("runs.csv").exists() || records(&bad).is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Values that parse but make no sense, given on the command line, are refused with their
/// range before anything runs (issue 45: the config file's were already).
#[test]
fn out_of_range_sweep_flags_are_refused_with_their_range() {
    let dir = tmpdir("flags-range");
    let o = dir.join("o");
    let o = o.to_str().unwrap();
    for (flag, value, needle) in [
        ("--tau-mf", "-0.5", "tau_mf = -0.5: must be > 0"),
        ("--baseline", "0", "baseline = 0: must be"),
    ] {
        let arg = format!("{flag}={value}");
        let out = noisefree(&[
            "sweep",
            "--seq",
            "kinect",
            "--frames",
            "10",
            "--runs",
            "1",
            "--configs",
            "mcor+avc",
            &arg,
            "--out",
            o,
        ]);
        assert_clean_failure(&out, needle);
        assert!(
            !Path::new(o).join("runs.csv").exists(),
            "nothing ran for {flag} {value}"
        );
    }
}

#[test]
fn match_bisects_to_a_target_and_says_when_it_is_out_of_reach() {
    let dir = tmpdir("perturb-match");
    let out = dir.join("m");
    let o = out.to_str().unwrap();
    let base = [
        "match",
        "--seq",
        "kinect",
        "--frames",
        "40",
        "--chain",
        "depth-scale",
        "--runs",
        "2",
        "--max-level",
        "20",
        "--out",
        o,
    ];
    let mut args = base.to_vec();
    args.extend(["--target", "5000mm"]);
    let far = noisefree(&args);
    assert_clean_failure(&far, "lies above what depth-scale reaches: median ATE");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("match.json")).unwrap()).unwrap();
    let (low, high) = (
        json["result"]["status"]["at_low"].as_f64().unwrap(),
        json["result"]["status"]["at_high"].as_f64().unwrap(),
    );
    assert!(high > low, "{low} {high}");
    let far_csv = std::fs::read_to_string(out.join("match.csv")).unwrap();
    let target = format!("{}", (low + high) / 2.0);
    let mut args = base.to_vec();
    args.extend(["--target", &target, "--tolerance", "0.2"]);
    let ok = noisefree_ok(&args);
    let text = String::from_utf8_lossy(&ok.stdout);
    assert!(
        text.contains("gives the baseline a median ATE of"),
        "{text}"
    );
    let steps = String::from_utf8_lossy(&ok.stderr);
    assert!(steps.matches("median").count() >= 3, "{steps}");
    // The two ends were measured by the first match into this folder: reused, not run again,
    // and their runs' ATEs are the same to the last digit.
    assert!(
        steps.contains("2 level(s) measured before, reused"),
        "{steps}"
    );
    assert_eq!(steps.matches("; recorded)").count(), 2, "{steps}");
    let csv = std::fs::read_to_string(out.join("match.csv")).unwrap();
    let ends = |text: &str| -> Vec<String> {
        text.lines()
            .filter(|l| l.starts_with("0,") || l.starts_with("1,"))
            .map(str::to_string)
            .collect()
    };
    assert_eq!(ends(&csv), ends(&far_csv));
    assert_eq!(ends(&csv).len(), 4, "{csv}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("match.json")).unwrap()).unwrap();
    assert_eq!(json["result"]["status"]["status"], "matched");
    let level = json["result"]["status"]["level"].as_f64().unwrap();
    assert!(level > 0.0 && level < 20.0, "{level}");
    assert!(csv.lines().count() > 2 * 3, "{csv}");
    // A twin's chain and target come from the sequence it imitates; a non-twin needs both.
    assert_clean_failure(
        &noisefree(&["match", "--seq", "kinect", "--target", "paper", "--out", o]),
        "imitates no TUM or EuRoC sequence",
    );
    // `match` honours --vocabulary as `run` does: a missing file is refused, named.
    let mut missing = base.to_vec();
    missing.extend(["--target", "0.01", "--vocabulary", "nothere.voc"]);
    assert_clean_failure(&noisefree(&missing), "nothere.voc");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_perturbed_copy_of_a_colour_folder_stays_in_colour_and_level_zero_is_the_input() {
    let dir = tmpdir("perturb-colour");
    let src = dir.join("src");
    noisefree_ok(&[
        "synth",
        "--preset",
        "kinect",
        "--frames",
        "3",
        "--seed",
        "0",
        "--out",
        src.to_str().unwrap(),
    ]);
    let first_rgb = |d: &Path| -> image::RgbImage {
        let list = datasets::tum::read_list(&d.join("rgb.txt")).unwrap();
        let img = image::open(d.join(&list[0].file)).unwrap();
        assert!(img.color().has_color(), "{}", d.display());
        img.into_rgb8()
    };
    for (chain, name) in [("depth-axial:0", "zero"), ("kinect-fr3:1", "chain")] {
        let out = dir.join(name);
        noisefree_ok(&[
            "perturb",
            "--path",
            src.to_str().unwrap(),
            "--perturb",
            chain,
            "-o",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        // Neither a depth, a calibration nor a ground-truth family touches a colour byte.
        assert_eq!(first_rgb(&src), first_rgb(&out), "{chain}");
        let list = std::fs::read_to_string(out.join("rgb.txt")).unwrap();
        assert!(list.starts_with("# color images"), "{list}");
    }
    let noisy = dir.join("noisy");
    noisefree_ok(&[
        "perturb",
        "--path",
        src.to_str().unwrap(),
        "--perturb",
        "image-noise:4",
        "-o",
        noisy.to_str().unwrap(),
        "--quiet",
    ]);
    assert_ne!(first_rgb(&src), first_rgb(&noisy));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The ATE `noisefree run` gives on kinect's first 30 frames under `chain` with one
/// perturbation seed and one SLAM seed.
fn run_ate(dir: &Path, chain: &str, perturb_seed: u64, seed: u64) -> f64 {
    let out = dir.join(format!("run-{perturb_seed}-{seed}"));
    noisefree_ok(&[
        "run",
        "--seq",
        "kinect",
        "--frames",
        "30",
        "--perturb",
        chain,
        "--perturb-seed",
        &perturb_seed.to_string(),
        "--seed",
        &seed.to_string(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    s["ate_rmse_m"].as_f64().unwrap()
}

/// Issue 55: run i of every system sees perturbation draw i (a paired design), different
/// draws for different i; `--perturb-shared` gives every run one draw. Each run's draw is
/// checked against `noisefree run` with that perturbation seed and SLAM seed.
#[test]
fn a_perturbation_sweep_pairs_its_draws_by_run_unless_shared() {
    let dir = tmpdir("paired-draws");
    std::fs::create_dir_all(&dir).unwrap();
    let chain = "depth-axial:8";
    for (name, shared) in [("paired", false), ("shared", true)] {
        let out = dir.join(name);
        let mut args = vec![
            "sweep",
            "--seq",
            "kinect",
            "--frames",
            "30",
            "--runs",
            "2",
            "--configs",
            "orb,rc",
            "--perturb",
            "depth-axial:8",
            "--perturb-seed",
            "5",
            "--quiet",
            "--out",
        ];
        args.push(out.to_str().unwrap());
        if shared {
            args.push("--perturb-shared");
        }
        noisefree_ok(&args);
        let recs = records(&out);
        let at = |config: &str, seed: &str| {
            recs.iter()
                .find(|r| r["config"] == config && r["seed"] == seed && r["perturbation"] == chain)
                .unwrap_or_else(|| panic!("{config} seed {seed}: {recs:?}"))
        };
        for seed in ["0", "1"] {
            let draw = if shared || seed == "0" { "5" } else { "6" };
            assert_eq!(at("orb", seed)["perturb_seed"], draw, "{name}, run {seed}");
            assert_eq!(at("rc", seed)["perturb_seed"], draw, "{name}, run {seed}");
        }
        let ate: f64 = at("orb", "1")["ate_rmse"].parse().unwrap();
        let draw = if shared { 5 } else { 6 };
        assert_eq!(
            ate,
            run_ate(&dir, chain, draw, 1),
            "{name}: run 1 on draw {draw}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--frames`, `--synth-seed` and `--synth-without` are one argument group that `synth`'s
/// siblings share: `perturb` at level 0 of an ablated synthetic sequence writes the depth
/// `synth` writes for the same ablation, names the ablation in its note, and refuses an
/// unknown effect as `run` does.
#[test]
fn perturb_takes_the_shared_synthetic_flags_as_synth_and_run_do() {
    let dir = tmpdir("perturb-shared-flags");
    let (synth_out, perturbed) = (dir.join("synth"), dir.join("perturbed"));
    noisefree_ok(&[
        "synth",
        "--preset",
        "kinect",
        "--frames",
        "3",
        "--seed",
        "2",
        "--synth-without",
        "axial,lateral",
        "--out",
        synth_out.to_str().unwrap(),
    ]);
    noisefree_ok(&[
        "perturb",
        "--seq",
        "kinect",
        "--frames",
        "3",
        "--synth-seed",
        "2",
        "--synth-without",
        "axial,lateral",
        "--perturb",
        "depth-axial:0",
        "-o",
        perturbed.to_str().unwrap(),
        "--quiet",
    ]);
    let depth_files = |d: &Path| -> Vec<Vec<u16>> {
        let list = datasets::tum::read_list(&d.join("depth.txt")).unwrap();
        list.iter()
            .map(|e| {
                image::open(d.join(&e.file))
                    .unwrap()
                    .into_luma16()
                    .into_raw()
            })
            .collect()
    };
    let (a, b) = (depth_files(&synth_out), depth_files(&perturbed));
    assert_eq!(a.len(), 3);
    assert!(
        a == b,
        "the ablated depth differs between synth and perturb"
    );
    let note = std::fs::read_to_string(perturbed.join("perturbation.txt")).unwrap();
    assert!(note.contains("synth_without axial,lateral\n"), "{note}");
    for command in ["perturb", "run"] {
        let out = noisefree(&[
            command,
            "--seq",
            "kinect",
            "--frames",
            "2",
            "--synth-without",
            "no-such-effect",
            "--perturb",
            "depth-axial:0",
            "--out",
            dir.join(command).to_str().unwrap(),
        ]);
        assert_clean_failure(&out, "no-such-effect");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// An output folder that holds anything is refused with the writer's own error, and what it
/// holds is left as it was.
#[test]
fn perturb_refuses_an_occupied_output_folder_and_leaves_it_as_it_was() {
    let dir = tmpdir("perturb-occupied");
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("keep.txt"), "mine").unwrap();
    let o = out.to_str().unwrap();
    assert_clean_failure(
        &noisefree(&["perturb", "--perturb", "depth-axial:1", "-o", o, "--quiet"]),
        "the output folder exists and is not empty",
    );
    let left: Vec<_> = std::fs::read_dir(&out).unwrap().flatten().collect();
    assert_eq!(left.len(), 1);
    assert_eq!(
        std::fs::read_to_string(out.join("keep.txt")).unwrap(),
        "mine"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
