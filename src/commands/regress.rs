//! `noisefree regress`: the regression suite (short synthetic sequences x the four
//! configurations) against the golden figures of `tests/golden/regression.toml`, with the
//! old-vs-new table; `--update` rewrites the golden file and measures the tolerances.

use crate::config_file::base_config;
use crate::regress::cases::{all_cases, Case, Figures, SuiteSequence, SUITE, SUITE_SEED};
use crate::regress::golden::{self, Golden, GoldenCase, Spread};
use crate::runner::{run_extracted, run_sequence, ExtractedSequence};
use anyhow::{bail, Context, Result};
use datasets::Sequence;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use slam_core::system::{AvcParams, Config, McorParams, RigidConsensusParams};
use std::path::PathBuf;

/// Default relative change of the focal length per perturbed rerun: a change in the 12th
/// significant digit, the size of the roundings another machine's libm or a reordered sum
/// flips (see [`crate::regress::golden`]).
const DEFAULT_PERTURBATION: f64 = 1e-12;
/// Perturbed reruns per case when `--update` is given without `--spread`.
const DEFAULT_SPREAD_RUNS: usize = 6;

/// Arguments of `noisefree regress`.
#[derive(clap::Args, Debug)]
pub struct RegressArgs {
    /// The golden file.
    #[arg(
        long,
        value_name = "FILE",
        default_value = "tests/golden/regression.toml"
    )]
    pub golden: PathBuf,
    /// Write the golden file from this run (with tolerances measured over --spread perturbed
    /// reruns per case) instead of comparing. Only for an intended change; see the README.
    #[arg(long)]
    pub update: bool,
    /// Perturbed reruns per case (focal length changed by k x --perturbation) to measure the
    /// spread of every figure [default with --update: 6]; without --update the spread is
    /// printed beside the comparison.
    #[arg(long, value_name = "K")]
    pub spread: Option<usize>,
    /// Relative change of the focal length in perturbed rerun k is k times this (1e-12: the
    /// roundings of another machine; 1e-4: decisions flipping at their margins, as any change
    /// of behaviour makes them).
    #[arg(long, value_name = "REL", default_value_t = DEFAULT_PERTURBATION)]
    pub perturbation: f64,
    /// Only the cases whose name (`preset/config`) contains this text.
    #[arg(long, value_name = "TEXT")]
    pub only: Option<String>,
    /// Parallel runs at once [default: all cores].
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// The configuration of a case: the sensor's defaults with the switches of its column.
fn case_config(seq: &Sequence, case: &Case) -> Config {
    let mut c = base_config(seq.camera.sensor);
    c.seed = SUITE_SEED;
    c.mcor = case.kind.mcor().then(|| McorParams {
        cluster_views: case.kind.cluster_views().unwrap_or_default(),
        ..McorParams::default()
    });
    c.avc = case.kind.avc().then(AvcParams::default);
    c.rc = case.kind.rc().then(RigidConsensusParams::default);
    c
}

/// `seq` with its focal length changed by `k * rel` (k = 0: unchanged).
fn perturbed(seq: &Sequence, k: usize, rel: f64) -> Sequence {
    let mut s = seq.clone();
    s.camera.fx *= 1.0 + rel * k as f64;
    s
}

/// Runs `noisefree regress`.
pub fn run(args: RegressArgs) -> Result<()> {
    let cases: Vec<Case> = all_cases()
        .into_iter()
        .filter(|c| args.only.as_ref().is_none_or(|o| c.name().contains(o)))
        .collect();
    if cases.is_empty() {
        bail!("--only {:?} matches no case", args.only.unwrap_or_default());
    }
    if args.update && args.only.is_some() {
        bail!("--update writes the whole golden file; it cannot be combined with --only");
    }
    let reruns = args
        .spread
        .unwrap_or(if args.update { DEFAULT_SPREAD_RUNS } else { 0 });
    let old = if args.golden.is_file() {
        Some(Golden::read(&args.golden)?)
    } else if args.update {
        None
    } else {
        bail!(
            "golden file {} not found (run from the repository root, pass --golden, or create it with `make golden`)",
            args.golden.display()
        );
    };

    let needed: Vec<SuiteSequence> = SUITE
        .iter()
        .copied()
        .filter(|s| cases.iter().any(|c| c.sequence == *s))
        .collect();
    // Each sequence rendered and its features extracted once, shared by all its cases' runs
    // (the same trajectories, bit for bit, as extracting in each run); perturbed reruns change
    // the camera, so they extract in their runs from the rendered frames.
    let mut sequences: Vec<(SuiteSequence, Sequence, ExtractedSequence)> = Vec::new();
    for s in needed {
        if !args.quiet {
            eprintln!("rendering {} ({} frames) ...", s.label(), s.frames);
        }
        let mut seq = s.render()?;
        let orb = base_config(seq.camera.sensor).orb;
        let extracted = ExtractedSequence::extract_frames(&seq.frames, &seq.camera, &[orb])
            .pop()
            .expect("one extraction per ORB setting");
        if reruns == 0 {
            // The images are no longer needed: a suite's frames are gigabytes.
            seq.frames = Vec::new();
        }
        sequences.push((s, seq, extracted));
    }
    let seq_of = |case: &Case| -> (&Sequence, &ExtractedSequence) {
        let (_, seq, extracted) = sequences
            .iter()
            .find(|(s, _, _)| *s == case.sequence)
            .expect("every case's sequence was loaded");
        (seq, extracted)
    };

    // The built-in vocabulary: a changed vocabulary changes the figures, as it should.
    let vocabulary = Some(crate::vocab_file::default_vocabulary());
    // Every (case, rerun) pair is one single-threaded, deterministic run.
    let jobs: Vec<(usize, usize)> = (0..cases.len())
        .flat_map(|c| (0..=reruns).map(move |k| (c, k)))
        .collect();
    let bar = ProgressBar::with_draw_target(
        Some(jobs.len() as u64),
        if args.quiet {
            ProgressDrawTarget::hidden()
        } else {
            ProgressDrawTarget::stderr()
        },
    );
    bar.set_style(
        ProgressStyle::with_template("regress [{bar:40}] {pos}/{len} runs eta {eta}")
            .expect("static template")
            .progress_chars("=> "),
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.jobs.unwrap_or(0))
        .build()
        .context("starting the worker pool")?;
    let start = std::time::Instant::now();
    let figures: Vec<Figures> = pool.install(|| {
        jobs.par_iter()
            .map(|&(c, k)| {
                let case = &cases[c];
                let (seq, extracted) = seq_of(case);
                let outcome = if k == 0 {
                    let config = case_config(seq, case);
                    run_extracted(seq, extracted, &config, vocabulary.as_ref(), |_| {})
                } else {
                    let seq = perturbed(seq, k, args.perturbation);
                    run_sequence(&seq, &case_config(&seq, case), vocabulary.as_ref(), |_| {})
                };
                bar.inc(1);
                Figures::of(&outcome)
            })
            .collect()
    });
    bar.finish_and_clear();
    let per_case = |c: usize| &figures[c * (reruns + 1)..(c + 1) * (reruns + 1)];
    let results: Vec<(Case, Figures)> = cases
        .iter()
        .enumerate()
        .map(|(i, c)| (*c, per_case(i)[0].clone()))
        .collect();
    let spreads: Vec<Spread> = (0..cases.len())
        .map(|i| Spread::measure(&per_case(i)[0], &per_case(i)[1..]))
        .collect();
    if !args.quiet {
        eprintln!(
            "{} runs of {} cases in {:.1} s",
            jobs.len(),
            cases.len(),
            start.elapsed().as_secs_f64()
        );
    }

    let rows = old.as_ref().map(|g| golden::compare(g, &results));
    if let Some(rows) = &rows {
        print!("{}", golden::table(rows));
    }
    if reruns > 0 {
        println!("\nspread over {reruns} perturbed reruns (largest deviation; hashes changed):");
        for ((case, f), s) in results.iter().zip(&spreads) {
            let t = s.tolerance(f);
            println!(
                "{:<20} ATE {:.1e} m -> tol {:.3} mm; tracked {} kf {} mp {} reloc {} loops {}; {} of {} hashes changed",
                case.name(),
                s.spread_ate_m,
                t.ate_tol_m * 1e3,
                s.spread_tracked,
                s.spread_keyframes,
                s.spread_map_points,
                s.spread_relocalizations,
                s.spread_loops,
                s.spread_changed_hashes,
                s.spread_runs
            );
        }
    }
    if args.update {
        let golden = Golden {
            cases: results
                .iter()
                .zip(&spreads)
                .map(|((case, f), s)| GoldenCase {
                    name: case.name(),
                    frames: case.sequence.frames,
                    tolerance: s.tolerance(f),
                    figures: f.clone(),
                    spread: s.clone(),
                })
                .collect(),
        };
        golden.write(&args.golden)?;
        println!("wrote {}", args.golden.display());
        return Ok(());
    }
    let (Some(rows), Some(old)) = (rows, old) else {
        unreachable!("a comparison has a golden file")
    };
    let stale = if args.only.is_some() {
        Vec::new()
    } else {
        golden::stale_cases(&old, &results)
    };
    golden::verdict(&rows, &stale)
}
