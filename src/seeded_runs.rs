//! The work of `noisefree run`: one sequence (perturbed if asked) run with n SLAM seeds in
//! parallel under one configuration, with progress bars, each run's TUM trajectory, per-frame
//! CSV and JSON summary written, a line per run printed, and over several runs their mean.
//!
//! Phases: [`load`] (open, perturb, read) -> [`system_config`] -> [`run_seeds`] (features
//! extracted once when several runs share them) -> [`record`] (files and lines) ->
//! [`summarise`] (several runs' mean and spread).

use crate::runner::{run_extracted, run_sequence, ExtractedSequence, RunOutcome};
use crate::select::{open, LoadOptions, Source};
use anyhow::{Context, Result};
use ate_eval::io::write_tum;
use atomic_file::write as write_atomic;
use datasets::{Catalog, FrameReader, Sequence};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use serde_json::json;
use slam_core::place::Vocabulary;
use slam_core::system::Config;
use std::path::{Path, PathBuf};
use std::sync::Arc;

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

/// A sequence ready to run: its frames in memory (one run decodes and extracts as it tracks),
/// or a reader that [`run_seeds`] extracts from once for several runs.
pub struct Loaded {
    /// The sequence's label (tables, file names, messages).
    pub label: String,
    /// The sequence (its frames read when `reader` is `None`).
    pub seq: Sequence,
    /// The frames still to read, when several runs share their features.
    pub reader: Option<FrameReader>,
    /// Every frame's images as read (colour included, perturbed where the run is): what a
    /// recording of the run shows (`run --rerun`).
    #[cfg_attr(not(feature = "rerun"), allow(dead_code))]
    pub images: FrameReader,
}

impl Loaded {
    /// Frames of the sequence.
    pub fn frames(&self) -> usize {
        self.reader.as_ref().map_or(self.seq.len(), |r| r.len())
    }
}

/// Opens `source`, perturbs it by `chain` (seeded by `perturb_seed`, said on standard error
/// unless `quiet`), and reads its frames now unless `several` runs will share their features.
pub fn load(
    source: &Source,
    catalog: &Catalog,
    opts: &LoadOptions,
    chain: &perturb::Chain,
    perturb_seed: u64,
    several: bool,
    quiet: bool,
) -> Result<Loaded> {
    let label = source.label();
    if !quiet {
        eprintln!("loading {label} ...");
    }
    let (seq, frames) = open(source, catalog, opts)?;
    let (mut seq, frames) = perturb::perturb_sequence(&seq, frames, chain, perturb_seed)
        .with_context(|| format!("--perturb {chain}"))?;
    if !chain.is_identity() && !quiet {
        eprintln!(
            "{label}: perturbed by {} (perturbation seed {})",
            chain.effective(),
            perturb_seed
        );
    }
    let images = frames.clone();
    let reader = if several {
        Some(frames)
    } else {
        seq.frames = frames
            .without_colour()
            .read_all()
            .with_context(|| format!("loading {label}"))?;
        None
    };
    Ok(Loaded {
        label,
        seq,
        reader,
        images,
    })
}

/// Runs `seeds` (one thread each, `jobs` at once) on `loaded` under `config`, a progress bar
/// per run (and one for the features, extracted once when several runs share them), hidden
/// when `quiet`. With `rerun`, the first seed's run is recorded into that file
/// ([`crate::recording`]); its trajectory is the same.
pub fn run_seeds(
    loaded: &Loaded,
    config: &Config,
    vocabulary: Option<&Arc<Vocabulary>>,
    seeds: &[u64],
    jobs: Option<usize>,
    quiet: bool,
    rerun: Option<&Path>,
) -> Result<Vec<(u64, RunOutcome)>> {
    let (seq, n_frames) = (&loaded.seq, loaded.frames());
    let multi = MultiProgress::with_draw_target(if quiet {
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
        .num_threads(jobs.unwrap_or(0))
        .build()
        .context("starting the worker pool")?;
    let extracted = match &loaded.reader {
        Some(frames) => {
            let bar = multi.add(ProgressBar::new(n_frames as u64));
            bar.set_style(style.clone());
            bar.set_prefix("features");
            let orbs = std::slice::from_ref(&config.orb);
            let mut e = pool
                .install(|| {
                    ExtractedSequence::extract_all(frames, &seq.camera, orbs, || bar.inc(1))
                })
                .with_context(|| format!("reading the frames of {}", loaded.label))?;
            bar.finish_and_clear();
            Some(e.remove(0))
        }
        None => None,
    };
    pool.install(|| {
        seeds
            .par_iter()
            .enumerate()
            .map(|(k, &seed)| {
                let bar = multi.add(ProgressBar::new(n_frames as u64));
                bar.set_style(style.clone());
                bar.set_prefix(format!("seed {seed}"));
                let mut cfg = config.clone();
                cfg.seed = seed;
                let progress = |i: usize| bar.set_position(i as u64);
                let o = match (rerun.filter(|_| k == 0), &extracted) {
                    (Some(file), e) => {
                        record_run(file, loaded, e.as_ref(), &cfg, vocabulary, progress)?
                    }
                    (None, Some(e)) => run_extracted(seq, e, &cfg, vocabulary, progress),
                    (None, None) => run_sequence(seq, &cfg, vocabulary, progress),
                };
                bar.finish_and_clear();
                Ok((seed, o))
            })
            .collect()
    })
}

/// The run of `config` over `loaded` recorded into `file` (`run --rerun`).
#[cfg(feature = "rerun")]
fn record_run(
    file: &Path,
    loaded: &Loaded,
    extracted: Option<&ExtractedSequence>,
    config: &Config,
    vocabulary: Option<&Arc<Vocabulary>>,
    progress: impl FnMut(usize),
) -> Result<RunOutcome> {
    crate::recording::record_run(
        file,
        &loaded.seq,
        &loaded.images,
        extracted,
        config,
        vocabulary,
        progress,
    )
}

/// Without the recording built in, `--rerun` is refused before the run (see `commands::run`).
#[cfg(not(feature = "rerun"))]
fn record_run(
    _: &Path,
    _: &Loaded,
    _: Option<&ExtractedSequence>,
    _: &Config,
    _: Option<&Arc<Vocabulary>>,
    _: impl FnMut(usize),
) -> Result<RunOutcome> {
    anyhow::bail!("{}", crate::recording::HOW_TO_GET_IT)
}

/// Writes each run's files (into `out`, or `out/seed<k>` for several runs, with the
/// perturbation it ran under) and prints its line; returns the runs' summaries.
pub fn record(
    loaded: &Loaded,
    cname: &str,
    results: &[(u64, RunOutcome)],
    chain: &perturb::Chain,
    perturb_seed: u64,
    out: &Path,
) -> Result<Vec<serde_json::Value>> {
    let label = &loaded.label;
    let mut summaries = Vec::new();
    for (seed, o) in results {
        let dir = if results.len() == 1 {
            out.to_path_buf()
        } else {
            out.join(format!("seed{seed}"))
        };
        let mut summary = run_summary(label, cname, *seed, o);
        summary["perturbation"] = json!(chain.effective().to_string());
        summary["perturbation_seed"] = json!(perturb_seed);
        write_run(&dir, &summary, o)?;
        summaries.push(summary);
        let ate = match (o.ate_rmse(), &loaded.seq.groundtruth) {
            (Some(a), _) => metres_text(a),
            (None, None) => "n/a (the sequence has no ground truth)".into(),
            (None, Some(_)) => "n/a (too few tracked poses matched a ground-truth stamp)".into(),
        };
        println!(
            "{label} [{cname}] seed {seed}: ATE RMSE {ate}, tracked {}/{} frames{}, {}, {}, {}, {:.1} fps",
            o.tracked,
            o.frames,
            if o.failed { " (FAILED)" } else { "" },
            counted(o.keyframes, "keyframe"),
            counted(o.map_points, "map point"),
            loops_text(o),
            o.fps()
        );
    }
    Ok(summaries)
}

/// A length in metres with three significant digits (`0.000912 m`, `0.0231 m`, `1.20 m`): a
/// sub-millimetre ATE keeps its digits.
pub fn metres_text(m: f64) -> String {
    if m == 0.0 || !m.is_finite() {
        return format!("{m} m");
    }
    let decimals = (2 - m.abs().log10().floor() as i64).max(0) as usize;
    format!("{m:.decimals$} m")
}

/// `n` things, in the singular for one: `1 keyframe`, `0 map points`.
pub fn counted(n: usize, thing: &str) -> String {
    if n == 1 {
        format!("1 {thing}")
    } else {
        format!("{n} {thing}s")
    }
}

/// Over several runs: prints their mean ATE, its population std and the failures, and writes
/// them with every run's summary to `out/summary.json`; nothing for a single run.
pub fn summarise(
    label: &str,
    cname: &str,
    results: &[(u64, RunOutcome)],
    summaries: Vec<serde_json::Value>,
    out: &Path,
) -> Result<()> {
    if results.len() <= 1 {
        return Ok(());
    }
    let ates: Vec<f64> = results.iter().filter_map(|(_, o)| o.ate_rmse()).collect();
    let n = ates.len().max(1) as f64;
    let mean = ates.iter().sum::<f64>() / n;
    let std = (ates.iter().map(|a| (a - mean) * (a - mean)).sum::<f64>() / n).sqrt();
    let failures = results.iter().filter(|(_, o)| o.failed).count();
    println!(
        "{label} [{cname}] over {} runs: mean ATE {}, std {}, {failures} failed",
        results.len(),
        metres_text(mean),
        metres_text(std)
    );
    let doc = json!({"sequence": label, "config": cname, "runs": summaries, "mean_ate_m": mean, "std_ate_m": std, "failures": failures});
    write_atomic(
        &out.join("summary.json"),
        serde_json::to_string_pretty(&doc)?.as_bytes(),
    )?;
    Ok(())
}

/// The default output folder of a sequence: `noisefree-out/<label>`.
pub fn default_out(label: &str) -> PathBuf {
    PathBuf::from("noisefree-out").join(label)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_keep_three_significant_digits_and_counts_their_number() {
        assert_eq!(metres_text(0.000_912_4), "0.000912 m");
        assert_eq!(metres_text(0.023_14), "0.0231 m");
        assert_eq!(metres_text(0.4039), "0.404 m");
        assert_eq!(metres_text(1.2), "1.20 m");
        assert_eq!(metres_text(123.4), "123 m");
        assert_eq!(metres_text(0.0), "0 m");
        assert_eq!(counted(1, "keyframe"), "1 keyframe");
        assert_eq!(counted(3, "map point"), "3 map points");
        assert_eq!(counted(0, "keyframe"), "0 keyframes");
    }
}
