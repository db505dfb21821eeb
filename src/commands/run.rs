//! `noisefree run`: SLAM over one sequence (a catalogued name, any folder, or the embedded
//! synthetic default), n seeded runs in parallel, writing each run's TUM trajectory, per-frame
//! CSV and a JSON summary, and printing the ATE where ground truth exists.

use crate::config_file::{apply_switches, base_config, config_name, overlay_file, Switches};
use crate::runner::{run_extracted, run_sequence, ExtractedSequence, RunOutcome};
use crate::select::{open, LoadOptions, Source};
use anyhow::{bail, Context, Result};
use ate_eval::io::{write_atomic, write_tum};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use serde_json::json;
use slam_core::system::ClusterViews;
use std::path::{Path, PathBuf};

/// Arguments of `noisefree run`.
// The help texts name placeholders like <sequence>, which rustdoc would read as HTML tags.
#[allow(rustdoc::invalid_html_tags)]
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// Catalogued sequence (datasets.toml): a TUM / EuRoC name such as `fr2_coke` or `mh04`, or
    /// a synthetic preset (`clean`, `kinect`, `boundary`, `walking`, `stereo`, ...).
    /// Without --seq and --path: the embedded synthetic default (`kinect`, 300 frames).
    #[arg(long, value_name = "NAME", conflicts_with = "path")]
    pub seq: Option<String>,
    /// Any TUM RGB-D or EuRoC ASL folder.
    #[arg(long, value_name = "DIR")]
    pub path: Option<PathBuf>,
    /// The folder's camera from an ORB-SLAM2 or ORB-SLAM3 settings file (YAML: intrinsics,
    /// distortion, bf, ThDepth, DepthMapFactor, a stereo pair's rectification) instead of the
    /// one its name (TUM) or sensor.yaml files (EuRoC) imply; `noisefree settings` writes one.
    #[arg(long, value_name = "FILE.yaml", requires = "path")]
    pub camera: Option<PathBuf>,
    /// TOML configuration overlaid on the sensor's defaults (any subset of the fields).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Place-recognition vocabulary: a DBoW2 text file (ORB-SLAM2's ORBvoc.txt) or a noisefree
    /// binary one, or `none` for brute-force relocalization and matching [default: the config
    /// file's `vocabulary`, else the built-in assets/vocabulary/noisefree-k10L5.voc].
    #[arg(long, value_name = "FILE|none")]
    pub vocabulary: Option<PathBuf>,
    /// Emulate ORB-SLAM2's concurrent local mapping: each keyframe is mapped up to N frames
    /// late (seeded), so runs with different --seed spread as ORB-SLAM2's do [default: 0,
    /// synchronous as in the paper's protocol: runs of one sequence differ only where
    /// relocalization's RANSAC draws].
    #[arg(long = "mapping-lag", value_name = "N")]
    pub mapping_lag: Option<u32>,
    /// Seed of the first run; run k uses seed + k.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Number of seeded runs (in parallel, one thread each).
    #[arg(long, default_value_t = 1)]
    pub runs: u64,
    /// Parallel runs at once [default: all cores].
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Turn on MC-OR (paper III-A) with its default thresholds (0.7, 0.7, 0.5 m).
    #[arg(long)]
    pub mcor: bool,
    /// MC-OR's cluster (implies --mcor): `every-frame` (the default: every tracked frame that
    /// kept the point as an inlier adds its feature, the paper's "tracked across N camera
    /// views") or `keyframes` (one feature per observing keyframe, the default before issue 18).
    #[arg(long = "mcor-cluster", value_name = "READING", value_parser = parse_cluster_views)]
    pub mcor_cluster: Option<ClusterViews>,
    /// Turn on noisefree's rigid consensus (beyond the paper): only the matches one rigid camera
    /// motion explains enter pose optimization, and keypoints beside rejected ones on the same
    /// body create no map points.
    #[arg(long)]
    pub rc: bool,
    /// Turn on AVC (paper III-B) with its default baseline (0.09 m).
    #[arg(long)]
    pub avc: bool,
    /// Turn loop closing off (an ablation: ORB-SLAM2, and so the baseline, closes loops).
    /// Loop closing needs a vocabulary; with --vocabulary none it is off anyway.
    #[arg(long = "no-loop-closing")]
    pub no_loop_closing: bool,
    /// Output folder [default: noisefree-out/<sequence>].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Synthetic sequences: number of frames (default 300); real ones: only the first N frames.
    #[arg(long, value_name = "N")]
    pub frames: Option<usize>,
    /// Seed of a synthetic sequence's scene and noise (independent of --seed).
    #[arg(long = "synth-seed", default_value_t = 0, value_name = "S")]
    pub synth_seed: u64,
    /// Synthetic sequences: effects to switch off, comma-separated (an ablation): lens, blur,
    /// rolling_shutter, vignetting, auto_exposure, sensor_noise, image_noise, tremor, depth_lag,
    /// axial, quantisation, lateral, holes, misregistration, depth_distortion, mocap_noise,
    /// layout, stamp_jitter, mocap_clock.
    #[arg(long = "synth-without", value_name = "EFFECTS", value_delimiter = ',')]
    pub synth_without: Vec<String>,
    /// Data root for catalogued real sequences [default: $NOISEFREE_DATA, else ./data].
    #[arg(long = "data-dir", value_name = "DIR")]
    pub data_dir: Option<PathBuf>,
    /// Catalog file [default: the datasets.toml compiled into the binary].
    #[arg(long, value_name = "FILE")]
    pub catalog: Option<PathBuf>,
    /// Perturb the sequence before anything reads it: `family:level[+family:level...]`, e.g.
    /// `depth-axial:2+depth-lateral:2` (families and units: `noisefree perturb --list`).
    #[arg(long, value_name = "CHAIN")]
    pub perturb: Option<String>,
    /// Seed of the perturbation's random draws (independent of --seed: every run sees the same
    /// perturbed copy).
    #[arg(long = "perturb-seed", default_value_t = 0, value_name = "S")]
    pub perturb_seed: u64,
    /// No progress bars.
    #[arg(long)]
    pub quiet: bool,
}

/// Per-frame CSV of a run.
fn frames_csv(outcome: &RunOutcome) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for s in &outcome.stats {
        w.serialize(s)?;
    }
    Ok(w.into_inner()?)
}

/// JSON summary of a run.
pub fn run_summary(label: &str, config: &str, seed: u64, o: &RunOutcome) -> serde_json::Value {
    let (mi, mo) = o.mean_inliers_outliers();
    json!({
        "sequence": label, "config": config, "seed": seed,
        "ate_rmse_m": o.ate_rmse(),
        "ate": o.ate.as_ref().map(|a| a.stats),
        "frames": o.frames, "tracked": o.tracked, "failed": o.failed,
        "keyframes": o.keyframes, "map_points": o.map_points,
        "loop_closing": o.loop_closing,
        "loops_closed": o.loops.len(),
        "loops": o.loops.iter().map(|l| json!({
            "frame": l.frame, "timestamp": l.timestamp,
            "keyframe": l.event.current.0, "loop_keyframe": l.event.loop_kf.0,
            "keyframe_timestamp": l.keyframe_stamps.0,
            "loop_keyframe_timestamp": l.keyframe_stamps.1,
            "matches": l.event.matches,
            "correction_m": l.event.correction_m, "correction_deg": l.event.correction_deg,
            "true_distance_m": l.truth.map(|t| t.0), "true_angle_deg": l.truth.map(|t| t.1),
        })).collect::<Vec<_>>(),
        "mean_inliers": mi, "mean_outliers": mo,
        "wall_s": o.wall_s, "fps": o.fps(),
    })
}

/// Writes a run's trajectory, per-frame CSV and summary (with the perturbation it ran under).
fn write_run(dir: &Path, summary: &serde_json::Value, o: &RunOutcome) -> Result<()> {
    write_tum(&dir.join("trajectory.txt"), &o.trajectory)?;
    write_atomic(&dir.join("frames.csv"), &frames_csv(o)?)?;
    let s = serde_json::to_string_pretty(summary)?;
    write_atomic(&dir.join("summary.json"), s.as_bytes())?;
    Ok(())
}

/// "2 loops closed (frames 812, 1240)", "no loop closed", or "loop closing off".
fn loops_text(o: &RunOutcome) -> String {
    if !o.loop_closing {
        return "loop closing off".into();
    }
    match o.loops.len() {
        0 => "no loop closed".into(),
        n => format!(
            "{n} loop{} closed (frame{} {})",
            if n == 1 { "" } else { "s" },
            if n == 1 { "" } else { "s" },
            o.loops
                .iter()
                .map(|l| l.frame.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Runs `noisefree run`.
pub fn run(args: RunArgs) -> Result<()> {
    if args.runs == 0 {
        bail!("--runs must be at least 1");
    }
    let catalog = match &args.catalog {
        Some(p) => datasets::Catalog::load(p)?,
        None => datasets::Catalog::embedded(),
    };
    let source = Source::from_flags(args.seq.as_deref(), args.path.as_deref());
    let label = source.label();
    // Checked before anything is read.
    let chain =
        perturb::Chain::parse(args.perturb.as_deref().unwrap_or("")).context("--perturb")?;
    let opts = LoadOptions {
        data_dir: datasets::data_root(args.data_dir.as_deref()),
        frames: args.frames,
        synth_seed: args.synth_seed,
        synth_without: args.synth_without.clone(),
        camera: args.camera.clone(),
    };
    if !args.quiet {
        eprintln!("loading {label} ...");
    }
    // Several runs share every frame's features, extracted once as the frames are read; a
    // single run decodes the sequence and extracts as it tracks.
    let (seq, frames) = open(&source, &catalog, &opts)?;
    let (mut seq, frames) = perturb::perturb_sequence(&seq, frames, &chain, args.perturb_seed)
        .with_context(|| format!("--perturb {chain}"))?;
    if !chain.is_identity() && !args.quiet {
        eprintln!(
            "{label}: perturbed by {} (perturbation seed {})",
            chain.effective(),
            args.perturb_seed
        );
    }
    let reader = if args.runs > 1 {
        Some(frames)
    } else {
        seq.frames = frames
            .without_colour()
            .read_all()
            .with_context(|| format!("loading {label}"))?;
        None
    };
    let n_frames = reader.as_ref().map_or(seq.len(), |r| r.len());
    let mut config = base_config(seq.camera.sensor);
    if let Some(p) = &args.config {
        config = overlay_file(&config, p)?;
    }
    let config = apply_switches(
        config,
        Switches {
            mcor: args.mcor,
            avc: args.avc,
            mapping_lag: args.mapping_lag,
            no_loop_closing: args.no_loop_closing,
            mcor_cluster: args.mcor_cluster,
            rc: args.rc,
        },
    );
    config
        .check()
        .map_err(|e| anyhow::anyhow!("{e} (from the command line or --config)"))?;
    let vocab_flag = match (&args.vocabulary, &args.config) {
        (Some(v), _) => Some(v.clone()),
        (None, Some(c)) => crate::config_file::vocabulary_in_file(c)?,
        (None, None) => None,
    };
    let vocabulary = crate::vocab_file::choose(vocab_flag.as_deref())?;
    let cname = config_name(&config);
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("noisefree-out").join(&label));
    let seeds: Vec<u64> = (0..args.runs).map(|k| args.seed + k).collect();
    if !args.quiet {
        eprintln!(
            "{label}: {} frames, {} camera, config {cname}, {} run(s), output {}",
            n_frames,
            if seq.camera.sensor == slam_core::SensorKind::Rgbd {
                "RGB-D"
            } else {
                "stereo"
            },
            seeds.len(),
            out.display()
        );
    }
    let multi = MultiProgress::with_draw_target(if args.quiet {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    });
    let style = ProgressStyle::with_template(
        "{prefix:>10} [{bar:40}] {pos}/{len} frames {per_sec} eta {eta}",
    )
    .expect("static template")
    .progress_chars("=> ");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.jobs.unwrap_or(0))
        .build()
        .context("starting the worker pool")?;
    let extracted = match &reader {
        Some(frames) => {
            let bar = multi.add(ProgressBar::new(n_frames as u64));
            bar.set_style(style.clone());
            bar.set_prefix("features");
            let orbs = std::slice::from_ref(&config.orb);
            let mut e = pool
                .install(|| {
                    ExtractedSequence::extract_all(frames, &seq.camera, orbs, || bar.inc(1))
                })
                .with_context(|| format!("reading the frames of {label}"))?;
            bar.finish_and_clear();
            Some(e.remove(0))
        }
        None => None,
    };
    let results: Vec<(u64, RunOutcome)> = pool.install(|| {
        seeds
            .par_iter()
            .map(|&seed| {
                let bar = multi.add(ProgressBar::new(n_frames as u64));
                bar.set_style(style.clone());
                bar.set_prefix(format!("seed {seed}"));
                let mut cfg = config.clone();
                cfg.seed = seed;
                let vocabulary = vocabulary.vocabulary.as_ref();
                let progress = |i: usize| bar.set_position(i as u64);
                let o = match &extracted {
                    Some(e) => run_extracted(&seq, e, &cfg, vocabulary, progress),
                    None => run_sequence(&seq, &cfg, vocabulary, progress),
                };
                bar.finish_and_clear();
                (seed, o)
            })
            .collect()
    });
    let mut summaries = Vec::new();
    for (seed, o) in &results {
        let dir = if results.len() == 1 {
            out.clone()
        } else {
            out.join(format!("seed{seed}"))
        };
        let mut summary = run_summary(&label, cname, *seed, o);
        summary["perturbation"] = json!(chain.effective().to_string());
        summary["perturbation_seed"] = json!(args.perturb_seed);
        write_run(&dir, &summary, o)?;
        summaries.push(summary);
        let ate = o
            .ate_rmse()
            .map(|a| format!("{a:.4} m"))
            .unwrap_or_else(|| "n/a".into());
        println!(
            "{label} [{cname}] seed {seed}: ATE RMSE {ate}, tracked {}/{} frames{}, {} keyframes, {} map points, {}, {:.1} fps",
            o.tracked,
            o.frames,
            if o.failed { " (FAILED)" } else { "" },
            o.keyframes,
            o.map_points,
            loops_text(o),
            o.fps()
        );
    }
    if results.len() > 1 {
        let ates: Vec<f64> = results.iter().filter_map(|(_, o)| o.ate_rmse()).collect();
        let n = ates.len().max(1) as f64;
        let mean = ates.iter().sum::<f64>() / n;
        let std = (ates.iter().map(|a| (a - mean) * (a - mean)).sum::<f64>() / n).sqrt();
        let failures = results.iter().filter(|(_, o)| o.failed).count();
        println!("{label} [{cname}] over {} runs: mean ATE {mean:.4} m, std {std:.4} m, {failures} failed", results.len());
        let doc = json!({"sequence": label, "config": cname, "runs": summaries, "mean_ate_m": mean, "std_ate_m": std, "failures": failures});
        write_atomic(
            &out.join("summary.json"),
            serde_json::to_string_pretty(&doc)?.as_bytes(),
        )?;
    }
    Ok(())
}

/// Parses `--mcor-cluster`.
fn parse_cluster_views(s: &str) -> std::result::Result<ClusterViews, String> {
    match s {
        "keyframes" => Ok(ClusterViews::Keyframes),
        "every-frame" => Ok(ClusterViews::EveryFrame),
        other => Err(format!(
            "unknown cluster reading {other:?}; expected keyframes or every-frame"
        )),
    }
}
