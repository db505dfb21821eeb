//! One pass of the regression suite: the cases chosen, each sequence rendered and its features
//! extracted once, every case (and its perturbed reruns) run in parallel, and the figures and
//! spreads that the comparison with the golden file ([`super::golden`]) reads.

use crate::config_file::base_config;
use crate::regress::cases::{all_cases, Case, Figures, SuiteSequence, SUITE, SUITE_SEED};
use crate::regress::golden::{Golden, GoldenCase, Spread};
use crate::runner::{run_extracted, run_sequence, ExtractedSequence};
use anyhow::{bail, Context, Result};
use datasets::Sequence;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use slam_core::system::{AvcParams, Config, McorParams, RigidConsensusParams};
use std::fmt::Write as _;
use std::path::Path;

/// Default relative change of the focal length per perturbed rerun: a change in the 12th
/// significant digit, the size of the roundings another machine's libm or a reordered sum
/// flips (see [`crate::regress::golden`]).
pub const DEFAULT_PERTURBATION: f64 = 1e-12;
/// Perturbed reruns per case when `--update` is given without `--spread`.
pub const DEFAULT_SPREAD_RUNS: usize = 6;

/// The cases whose name contains `only` (every case without it); refused when none is left,
/// or when `update` (which writes the whole golden file) is asked for a part of the suite.
pub fn select_cases(only: Option<&str>, update: bool) -> Result<Vec<Case>> {
    let cases: Vec<Case> = all_cases()
        .into_iter()
        .filter(|c| only.is_none_or(|o| c.name().contains(o)))
        .collect();
    if cases.is_empty() {
        bail!("--only {:?} matches no case", only.unwrap_or_default());
    }
    if update && only.is_some() {
        bail!("--update writes the whole golden file; it cannot be combined with --only");
    }
    Ok(cases)
}

/// The golden file at `path`; with `update` it may not exist yet (`None`), without it a
/// missing file is an error that says how to make one.
pub fn read_golden(path: &Path, update: bool) -> Result<Option<Golden>> {
    if path.is_file() {
        Ok(Some(Golden::read(path)?))
    } else if update {
        Ok(None)
    } else {
        bail!(
            "golden file {} not found (run from the repository root, pass --golden, or create it with `make golden`)",
            path.display()
        );
    }
}

/// A suite sequence rendered, with its features extracted for the sensor's default ORB.
pub struct Prepared {
    /// Which suite sequence.
    pub sequence: SuiteSequence,
    /// Its rendering (frames dropped when no perturbed rerun needs them).
    pub seq: Sequence,
    /// Every frame's features.
    pub extracted: ExtractedSequence,
}

/// Renders each sequence some case runs on and extracts its features once, shared by all its
/// cases' runs (the same trajectories, bit for bit, as extracting in each run). Perturbed
/// reruns change the camera, so they extract in their runs from the rendered frames: without
/// `keep_frames` the images are dropped (a suite's frames are gigabytes).
pub fn prepare_sequences(cases: &[Case], keep_frames: bool, quiet: bool) -> Result<Vec<Prepared>> {
    let needed = SUITE
        .iter()
        .copied()
        .filter(|s| cases.iter().any(|c| c.sequence == *s));
    let mut prepared = Vec::new();
    for s in needed {
        if !quiet {
            eprintln!("rendering {} ({} frames) ...", s.label(), s.frames);
        }
        let mut seq = s.render()?;
        let orb = base_config(seq.camera.sensor).orb;
        let extracted = ExtractedSequence::extract_frames(&seq.frames, &seq.camera, &[orb])
            .pop()
            .expect("one extraction per ORB setting");
        if !keep_frames {
            seq.frames = Vec::new();
        }
        prepared.push(Prepared {
            sequence: s,
            seq,
            extracted,
        });
    }
    Ok(prepared)
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

/// What a pass of the suite measured: each case's figures and their spread over its reruns.
pub struct Measured {
    /// Each case with the figures of its unperturbed run.
    pub results: Vec<(Case, Figures)>,
    /// Each case's spread over its perturbed reruns (empty spreads without reruns).
    pub spreads: Vec<Spread>,
}

/// Runs every case and its `reruns` perturbed reruns (focal length changed by k x
/// `perturbation`), each a single-threaded deterministic run, `jobs` at once, under one
/// progress bar (hidden when `quiet`), with the built-in vocabulary (a changed vocabulary
/// changes the figures, as it should).
pub fn run_cases(
    cases: &[Case],
    prepared: &[Prepared],
    reruns: usize,
    perturbation: f64,
    jobs: Option<usize>,
    quiet: bool,
) -> Result<Measured> {
    let seq_of = |case: &Case| -> (&Sequence, &ExtractedSequence) {
        let p = prepared
            .iter()
            .find(|p| p.sequence == case.sequence)
            .expect("every case's sequence was loaded");
        (&p.seq, &p.extracted)
    };
    let vocabulary = Some(crate::vocab_file::default_vocabulary());
    let runs: Vec<(usize, usize)> = (0..cases.len())
        .flat_map(|c| (0..=reruns).map(move |k| (c, k)))
        .collect();
    let bar = ProgressBar::with_draw_target(
        Some(runs.len() as u64),
        if quiet {
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
        .num_threads(jobs.unwrap_or(0))
        .build()
        .context("starting the worker pool")?;
    let start = std::time::Instant::now();
    let figures: Vec<Figures> = pool.install(|| {
        runs.par_iter()
            .map(|&(c, k)| {
                let case = &cases[c];
                let (seq, extracted) = seq_of(case);
                let outcome = if k == 0 {
                    let config = case_config(seq, case);
                    run_extracted(seq, extracted, &config, vocabulary.as_ref(), |_| {})
                } else {
                    let seq = perturbed(seq, k, perturbation);
                    run_sequence(&seq, &case_config(&seq, case), vocabulary.as_ref(), |_| {})
                };
                bar.inc(1);
                Figures::of(&outcome)
            })
            .collect()
    });
    bar.finish_and_clear();
    if !quiet {
        eprintln!(
            "{} runs of {} cases in {:.1} s",
            runs.len(),
            cases.len(),
            start.elapsed().as_secs_f64()
        );
    }
    let per_case = |c: usize| &figures[c * (reruns + 1)..(c + 1) * (reruns + 1)];
    Ok(Measured {
        results: cases
            .iter()
            .enumerate()
            .map(|(i, c)| (*c, per_case(i)[0].clone()))
            .collect(),
        spreads: (0..cases.len())
            .map(|i| Spread::measure(&per_case(i)[0], &per_case(i)[1..]))
            .collect(),
    })
}

/// The spread table printed after `reruns` perturbed reruns: per case its largest deviations,
/// the tolerance they imply and how many trajectory hashes changed.
pub fn spread_report(m: &Measured, reruns: usize) -> String {
    let mut s =
        format!("\nspread over {reruns} perturbed reruns (largest deviation; hashes changed):\n");
    for ((case, f), sp) in m.results.iter().zip(&m.spreads) {
        let t = sp.tolerance(f);
        let _ = writeln!(
            s,
            "{:<20} ATE {:.1e} m -> tol {:.3} mm; tracked {} kf {} mp {} reloc {} loops {}; {} of {} hashes changed",
            case.name(),
            sp.spread_ate_m,
            t.ate_tol_m * 1e3,
            sp.spread_tracked,
            sp.spread_keyframes,
            sp.spread_map_points,
            sp.spread_relocalizations,
            sp.spread_loops,
            sp.spread_changed_hashes,
            sp.spread_runs
        );
    }
    s
}

/// The golden file this pass makes: each case's figures with the tolerance its spread implies.
pub fn golden_of(m: &Measured) -> Golden {
    Golden {
        cases: m
            .results
            .iter()
            .zip(&m.spreads)
            .map(|((case, f), s)| GoldenCase {
                name: case.name(),
                frames: case.sequence.frames,
                tolerance: s.tolerance(f),
                figures: f.clone(),
                spread: s.clone(),
            })
            .collect(),
    }
}
