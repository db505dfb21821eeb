//! `noisefree match`: the level of a camera chain (or one family) at which the baseline's
//! median ATE on a sequence equals a target, by bisection, each step printed; `match.json`
//! and `match.csv` (every run of every step) written to `--out`, and `levels.jsonl` there as
//! each level ends, so a stopped match resumes where it stopped.

use super::shared_args::{Resolved, SequenceArgs, SourceArgs, SystemArgs};
use crate::config_file::Switches;
use crate::difficulty::level_log::{self, Found, LevelLog};
use crate::difficulty::request::{self, mm};
use crate::difficulty::{bisect, LevelOutcome, MatchSetup};
use crate::runner::remembering;
use crate::select::open;
use anyhow::{bail, Context, Result};
use perturb::Subject;
use std::path::PathBuf;

/// Arguments of `noisefree match`.
#[derive(clap::Args, Debug)]
pub struct MatchArgs {
    /// The sequence: --seq NAME or --path DIR.
    #[command(flatten)]
    pub source: SourceArgs,
    /// The named chain (`kinect-fr1`, `kinect-fr2`, `kinect-fr3`, `euroc`) or family whose level
    /// is sought [default: a twin's camera chain, from the sequence it imitates].
    #[arg(long, value_name = "CHAIN")]
    pub chain: Option<String>,
    /// The median ATE to reach: metres (`0.023`), millimetres (`23mm`), or `paper` (the paper's
    /// ORB-SLAM2 figure for the sequence a twin imitates).
    #[arg(long, value_name = "ATE")]
    pub target: String,
    /// Runs per level (run i: perturbation seed --perturb-seed + i, SLAM seed i).
    #[arg(long, default_value_t = 10)]
    pub runs: usize,
    /// Perturbation seed of run 0.
    #[arg(long = "perturb-seed", default_value_t = 0, value_name = "S")]
    pub perturb_seed: u64,
    /// The highest level tried [default: the chain's highest valid level, at most 8].
    #[arg(long = "max-level", value_name = "L")]
    pub max_level: Option<f64>,
    /// Levels measured between the two ends at most.
    #[arg(long = "max-steps", default_value_t = 8, value_name = "N")]
    pub max_steps: usize,
    /// Stop when the median is within this share of the target.
    #[arg(long, default_value_t = 0.05, value_name = "SHARE")]
    pub tolerance: f64,
    /// The baseline's settings file (MC-OR and AVC stay as it says), vocabulary, mapping lag and
    /// loop closing.
    #[command(flatten)]
    pub system: SystemArgs,
    /// Parallel runs at once [default: all cores].
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// The sequence's length, synthetic seed and ablated effects, and the data root.
    #[command(flatten)]
    pub sequence: SequenceArgs,
    /// Where `match.json`, `match.csv` and `levels.jsonl` go (a match into a folder that holds
    /// the levels of the same setup reuses them) [default: noisefree-out/match-<sequence>].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print only the result.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs `noisefree match`: resolves the chain, target and range, opens the sequence (checked
/// against the chain before anything runs), bisects with a line per level, writes `match.json`
/// and `match.csv`, and prints the verdict.
pub fn run(args: MatchArgs) -> Result<()> {
    if args.runs == 0 {
        bail!("--runs must be at least 1");
    }
    if !(args.tolerance > 0.0 && args.tolerance < 1.0) {
        bail!("--tolerance must be between 0 and 1 (a share of the target)");
    }
    let catalog = datasets::Catalog::embedded();
    let source = args.source.source();
    let label = source.label();
    let entry = args.source.seq.as_deref().and_then(|s| catalog.get(s).ok());
    let imitated = entry
        .and_then(|e| e.imitates.as_deref())
        .and_then(|name| catalog.get(name).ok());
    let subject = request::subject_of(args.chain.as_deref(), imitated, &label)?;
    let target = request::target_of(&args.target, imitated, &label)?;
    let high = request::highest_level(subject, args.max_level)?;
    let opts = args.sequence.load_options(None);
    let (seq, frames) = open(&source, &catalog, &opts)?;
    // Refused before anything runs: a family that does not fit the sequence.
    perturb::perturb_sequence(&seq, frames.clone(), &perturb::Chain(subject.at(high)), 0)
        .with_context(|| format!("--chain {subject} on {label}"))?;
    if seq.groundtruth.is_none() {
        bail!("{label} has no ground truth: there is no ATE to match");
    }
    let (w, h) = (seq.camera.width as usize, seq.camera.height as usize);
    let frames = remembering(frames, w * h * 8, 3 << 30);
    let Resolved { config, vocabulary } = args
        .system
        .resolve(seq.camera.sensor, Switches::default())?;
    let setup = MatchSetup {
        seq: &seq,
        frames: &frames,
        subject,
        config: &config,
        vocabulary: vocabulary.vocabulary.as_ref(),
        runs: args.runs,
        perturb_seed: args.perturb_seed,
    };
    if !args.quiet {
        eprintln!(
            "{label}: the level of {subject} at which the baseline's median ATE over {} runs is {:.1} mm (levels 0 to {high}, tolerance {} %)",
            args.runs,
            target * 1e3,
            args.tolerance * 100.0
        );
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("noisefree-out").join(format!("match-{label}")));
    // What a level's runs depend on: the log's levels are reused only under the same.
    let log_setup = serde_json::json!({
        "sequence": label,
        "frames": frames.len(),
        "synth_seed": args.sequence.synth_seed,
        "synth_without": args.sequence.synth_without,
        "chain": subject.name(),
        "runs": args.runs,
        "perturb_seed": args.perturb_seed,
        "config": config,
        "vocabulary": vocabulary.identity,
        "noisefree": env!("CARGO_PKG_VERSION"),
    });
    let (mut log, found) = LevelLog::open(&out, &log_setup)?;
    if !args.quiet {
        let file = out.join(level_log::FILE_NAME);
        match found {
            Found::Levels(n) if n > 0 => {
                eprintln!(
                    "  {n} level(s) measured before, reused from {}",
                    file.display()
                )
            }
            Found::OtherSetup => eprintln!(
                "  {} was written for another setup: its levels are not reused",
                file.display()
            ),
            _ => {}
        }
    }
    let started = std::time::Instant::now();
    let result = bisect_in_pool(&args, &setup, target, high, &mut log, started)?;
    let json = serde_json::json!({
        "sequence": label,
        "chain": subject.name(),
        "target_m": target,
        "runs": args.runs,
        "perturb_seed": args.perturb_seed,
        "frames": frames.len(),
        "range": [0.0, high],
        "tolerance": args.tolerance,
        "wall_s": started.elapsed().as_secs_f64(),
        "result": result,
    });
    request::write_files(&out, &json, &result, args.perturb_seed)?;
    let line = request::verdict(&label, subject, target, high, args.tolerance, &result)?;
    println!("{line}");
    Ok(())
}

/// The bisection on `--jobs` threads, each level printed (unless `--quiet`) with the time
/// since `started`, or `recorded` when it came from the log.
fn bisect_in_pool(
    args: &MatchArgs,
    setup: &MatchSetup<'_>,
    target: f64,
    high: f64,
    log: &mut LevelLog,
    started: std::time::Instant,
) -> Result<crate::difficulty::MatchResult> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.jobs.unwrap_or(0))
        .build()
        .context("starting the worker pool")?;
    let subject: Subject = setup.subject;
    let quiet = args.quiet;
    pool.install(|| {
        bisect(
            setup,
            target,
            (0.0, high),
            args.max_steps,
            args.tolerance,
            log,
            |o: &LevelOutcome, recorded: bool| {
                if !quiet {
                    let when = if recorded {
                        "recorded".to_string()
                    } else {
                        format!("{:.0} s", started.elapsed().as_secs_f64())
                    };
                    eprintln!(
                        "  {subject}:{:<8} median {} ({} of {} runs failed; {when})",
                        o.level,
                        mm(o.median),
                        o.failed(),
                        o.ates.len(),
                    );
                }
            },
        )
    })
}
