//! `noisefree match`: the level of a camera chain (or one family) at which the baseline's
//! median ATE on a sequence equals a target, by bisection, each step printed; `match.json`
//! and `match.csv` (every run of every step) written to `--out`.

use crate::config_file::{base_config, overlay_file};
use crate::difficulty::{bisect, LevelOutcome, MatchSetup, MatchStatus};
use crate::runner::remembering;
use crate::select::{open, LoadOptions, Source};
use anyhow::{bail, Context, Result};
use ate_eval::io::write_atomic;
use perturb::{NamedChain, Subject};
use std::path::PathBuf;

/// Arguments of `noisefree match`.
#[derive(clap::Args, Debug)]
pub struct MatchArgs {
    /// Catalogued sequence or synthetic preset (a twin: `twin_fr1_desk`).
    #[arg(long, value_name = "NAME", conflicts_with = "path")]
    pub seq: Option<String>,
    /// Any TUM RGB-D or EuRoC ASL folder.
    #[arg(long, value_name = "DIR")]
    pub path: Option<PathBuf>,
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
    /// Synthetic sequences: number of frames; real ones: only the first N frames.
    #[arg(long, value_name = "N")]
    pub frames: Option<usize>,
    /// Seed of a synthetic sequence's scene and noise.
    #[arg(long = "synth-seed", default_value_t = 0, value_name = "S")]
    pub synth_seed: u64,
    /// TOML configuration overlaid on the baseline's defaults (MC-OR and AVC stay as it says).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Parallel runs at once [default: all cores].
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Data root for catalogued real sequences [default: $NOISEFREE_DATA, else ./data].
    #[arg(long = "data-dir", value_name = "DIR")]
    pub data_dir: Option<PathBuf>,
    /// Where `match.json` and `match.csv` go [default: noisefree-out/match-<sequence>].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print only the result.
    #[arg(long)]
    pub quiet: bool,
}

/// The chain a twin's camera has, from the name of the sequence it imitates.
fn chain_of(imitates: &str) -> Option<NamedChain> {
    let s = imitates.to_ascii_lowercase();
    if s.starts_with("fr1") {
        Some(NamedChain::KinectFr1)
    } else if s.starts_with("fr2") {
        Some(NamedChain::KinectFr2)
    } else if s.starts_with("fr3") {
        Some(NamedChain::KinectFr3)
    } else if s.starts_with('v') || s.starts_with("mh") {
        Some(NamedChain::Euroc)
    } else {
        None
    }
}

/// Parses `0.023`, `23mm`, `0.023m` into metres.
fn parse_metres(text: &str) -> Result<f64> {
    let t = text.trim();
    let (num, scale) = match t.strip_suffix("mm") {
        Some(n) => (n, 1e-3),
        None => (t.strip_suffix('m').unwrap_or(t), 1.0),
    };
    let v: f64 = num.trim().parse().map_err(|_| {
        anyhow::anyhow!("--target {t:?}: expected metres (0.023), millimetres (23mm) or `paper`")
    })?;
    if !(v.is_finite() && v > 0.0) {
        bail!("--target {t:?}: must be a positive ATE");
    }
    Ok(v * scale)
}

/// Runs `noisefree match`.
pub fn run(args: MatchArgs) -> Result<()> {
    if args.runs == 0 {
        bail!("--runs must be at least 1");
    }
    if !(args.tolerance > 0.0 && args.tolerance < 1.0) {
        bail!("--tolerance must be between 0 and 1 (a share of the target)");
    }
    let catalog = datasets::Catalog::embedded();
    let source = Source::from_flags(args.seq.as_deref(), args.path.as_deref());
    let label = source.label();
    let entry = args.seq.as_deref().and_then(|s| catalog.get(s).ok());
    let imitated = entry
        .and_then(|e| e.imitates.as_deref())
        .and_then(|name| catalog.get(name).ok());
    let subject = match &args.chain {
        Some(c) => Subject::parse(c).context("--chain")?,
        None => {
            let named = imitated.and_then(|e| chain_of(&e.name)).with_context(|| {
                format!("--chain: {label} imitates no TUM or EuRoC sequence; name a chain")
            })?;
            Subject::Named(named)
        }
    };
    let target = if args.target.trim() == "paper" {
        let e = imitated.with_context(|| {
            format!("--target paper: {label} is not a twin of a sequence of the paper")
        })?;
        match e.paper.as_ref().and_then(|p| p.orb_slam2) {
            Some(datasets::catalog::Ate::Metres(m)) => m,
            Some(datasets::catalog::Ate::Failure) => bail!(
                "--target paper: the paper's ORB-SLAM2 failed on {} ('F'); give a target",
                e.name
            ),
            None => bail!(
                "--target paper: the paper gives no ORB-SLAM2 figure for {}",
                e.name
            ),
        }
    } else {
        parse_metres(&args.target)?
    };
    let max_valid = match subject {
        Subject::Named(c) | Subject::Without(c, _) => (c.max_level() * 1000.0).floor() / 1000.0,
        Subject::Family(f) => f.range().1,
    };
    let high = args.max_level.unwrap_or(max_valid.min(8.0));
    subject.check_level(high).context("--max-level")?;
    let opts = LoadOptions {
        data_dir: datasets::data_root(args.data_dir.as_deref()),
        frames: args.frames,
        synth_seed: args.synth_seed,
        synth_without: Vec::new(),
        camera: None,
    };
    let (seq, frames) = open(&source, &catalog, &opts)?;
    // Refused before anything runs: a family that does not fit the sequence.
    perturb::perturb_sequence(&seq, frames.clone(), &perturb::Chain(subject.at(high)), 0)
        .with_context(|| format!("--chain {subject} on {label}"))?;
    if seq.groundtruth.is_none() {
        bail!("{label} has no ground truth: there is no ATE to match");
    }
    let (w, h) = (seq.camera.width as usize, seq.camera.height as usize);
    let frames = remembering(frames, w * h * 8, 3 << 30);
    let mut config = base_config(seq.camera.sensor);
    if let Some(p) = &args.config {
        config = overlay_file(&config, p)?;
    }
    let vocabulary = crate::vocab_file::choose(None)?;
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
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.jobs.unwrap_or(0))
        .build()
        .context("starting the worker pool")?;
    let started = std::time::Instant::now();
    let quiet = args.quiet;
    let result = pool.install(|| {
        bisect(
            &setup,
            target,
            (0.0, high),
            args.max_steps,
            args.tolerance,
            |o: &LevelOutcome| {
                if !quiet {
                    eprintln!(
                        "  {subject}:{:<8} median {} ({} of {} runs failed; {:.0} s)",
                        o.level,
                        mm(o.median),
                        o.failed(),
                        o.ates.len(),
                        started.elapsed().as_secs_f64()
                    );
                }
            },
        )
    })?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("noisefree-out").join(format!("match-{label}")));
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
    write_atomic(
        &out.join("match.json"),
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    let mut csv = csv::Writer::from_writer(Vec::new());
    csv.write_record([
        "step",
        "level",
        "run",
        "perturb_seed",
        "seed",
        "ate_m",
        "failed",
    ])?;
    for (k, s) in result.steps.iter().enumerate() {
        for (i, a) in s.ates.iter().enumerate() {
            csv.write_record([
                k.to_string(),
                s.level.to_string(),
                i.to_string(),
                (args.perturb_seed + i as u64).to_string(),
                i.to_string(),
                a.map(|v| v.to_string()).unwrap_or_default(),
                a.is_none().to_string(),
            ])?;
        }
    }
    write_atomic(&out.join("match.csv"), &csv.into_inner()?)?;
    match result.status {
        MatchStatus::Matched {
            level,
            median,
            within_tolerance,
        } => {
            println!(
                "{label}: {subject}:{level} gives the baseline a median ATE of {} (target {}{}) after {} levels",
                mm(median),
                mm(target),
                if within_tolerance {
                    String::new()
                } else {
                    format!(", not within {} %: the closest level measured", args.tolerance * 100.0)
                },
                result.steps.len()
            );
        }
        MatchStatus::BelowRange { at_low, at_high } => bail!(
            "{label}: the target {} lies below what {subject} reaches: median ATE {} at level 0, {} at {high} (the twin is already harder)",
            mm(target),
            mm(at_low),
            mm(at_high)
        ),
        MatchStatus::AboveRange { at_low, at_high } => bail!(
            "{label}: the target {} lies above what {subject} reaches: median ATE {} at level 0, {} at {high} (raise --max-level, or the chain cannot make it that hard)",
            mm(target),
            mm(at_low),
            mm(at_high)
        ),
    }
    Ok(())
}

/// An ATE in millimetres, or "failed" for an infinite median.
fn mm(m: f64) -> String {
    if m.is_finite() {
        format!("{:.1} mm", m * 1e3)
    } else {
        "failed (more than half the runs)".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_and_chains_are_read() {
        assert_eq!(parse_metres("0.023").unwrap(), 0.023);
        assert!((parse_metres("23mm").unwrap() - 0.023).abs() < 1e-15);
        assert_eq!(parse_metres("0.5m").unwrap(), 0.5);
        assert!(parse_metres("-1").is_err() && parse_metres("abc").is_err());
        assert_eq!(chain_of("fr1_desk"), Some(NamedChain::KinectFr1));
        assert_eq!(chain_of("fr3_w_rpy"), Some(NamedChain::KinectFr3));
        assert_eq!(chain_of("mh01"), Some(NamedChain::Euroc));
        assert_eq!(chain_of("kinect"), None);
    }
}
