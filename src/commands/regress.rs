//! `noisefree regress`: the regression suite (short synthetic sequences x the four
//! configurations) against the golden figures of `tests/golden/regression.toml`, with the
//! old-vs-new table; `--update` rewrites the golden file and measures the tolerances.

use crate::regress::golden;
use crate::regress::suite::{self, DEFAULT_PERTURBATION, DEFAULT_SPREAD_RUNS};
use anyhow::Result;
use std::path::PathBuf;

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
    /// reruns per case) instead of comparing. Only for an intended change; see docs/development.md.
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

/// Runs `noisefree regress`: the chosen cases against the golden file, or with `--update`
/// the golden file rewritten from this pass.
pub fn run(args: RegressArgs) -> Result<()> {
    let cases = suite::select_cases(args.only.as_deref(), args.update)?;
    let reruns = args
        .spread
        .unwrap_or(if args.update { DEFAULT_SPREAD_RUNS } else { 0 });
    let old = suite::read_golden(&args.golden, args.update)?;
    let prepared = suite::prepare_sequences(&cases, reruns > 0, args.quiet)?;
    let measured = suite::run_cases(
        &cases,
        &prepared,
        reruns,
        args.perturbation,
        args.jobs,
        args.quiet,
    )?;
    let rows = old.as_ref().map(|g| golden::compare(g, &measured.results));
    if let Some(rows) = &rows {
        print!("{}", golden::table(rows));
    }
    if reruns > 0 {
        print!("{}", suite::spread_report(&measured, reruns));
    }
    if args.update {
        suite::golden_of(&measured).write(&args.golden)?;
        println!("wrote {}", args.golden.display());
        return Ok(());
    }
    let (Some(rows), Some(old)) = (rows, old) else {
        unreachable!("a comparison has a golden file")
    };
    let stale = if args.only.is_some() {
        Vec::new()
    } else {
        golden::stale_cases(&old, &measured.results)
    };
    golden::verdict(&rows, &stale)
}
