//! `noisefree view GT EST[=LABEL]... --out FILE.rrd`: trajectory files, each aligned to the
//! ground truth as `eval` aligns it, as one Rerun recording (the real ORB-SLAM2's and
//! ORB-SLAM3's runs of a sweep folder beside ours, scrubbable in the viewer).

use crate::commands::plot::split_label;
use crate::recording;
use anyhow::{bail, Result};
use ate_eval::io::{self, Format};
use ate_eval::{AlignmentMode, AteOptions, StampPolicy};
use std::path::PathBuf;

/// Arguments of `noisefree view`.
#[derive(clap::Args, Debug)]
pub struct ViewArgs {
    /// Ground-truth trajectory file (TUM, or EuRoC `.csv`).
    pub gt: PathBuf,
    /// Estimated trajectories, each `FILE` or `FILE=LABEL` (default label: the file name).
    #[arg(required = true, value_name = "EST[=LABEL]")]
    pub estimates: Vec<String>,
    /// The recording to write (`.rrd`); open it with `rerun FILE.rrd`.
    #[arg(long, short = 'o', value_name = "FILE.rrd")]
    pub out: PathBuf,
    /// Largest timestamp difference of an associated pair, in seconds.
    #[arg(long = "max-diff", default_value_t = 0.02, value_name = "S")]
    pub max_diff: f64,
    /// Fit a Sim3 alignment (rotation, translation and scale) instead of SE3.
    #[arg(long)]
    pub scale: bool,
}

/// Runs `noisefree view`.
pub fn run(args: ViewArgs) -> Result<()> {
    if !recording::AVAILABLE {
        bail!("{}", recording::HOW_TO_GET_IT);
    }
    if !(args.max_diff.is_finite() && args.max_diff > 0.0) {
        bail!(
            "--max-diff must be a positive number of seconds, got {}",
            args.max_diff
        );
    }
    recording::output::check(&args.out)?;
    let policy = StampPolicy::for_association(ate_eval::AssociationMode::Tum);
    let read = |p: &std::path::Path| -> Result<ate_eval::Trajectory> {
        let t = io::read_trajectory(p, Format::guess(p), None, policy)?;
        for w in &t.warnings {
            eprintln!("warning: {w}");
        }
        Ok(t.trajectory)
    };
    let gt = read(&args.gt)?;
    let mut estimates = Vec::new();
    for arg in &args.estimates {
        let (path, label) = split_label(arg);
        let est = read(&path)?;
        estimates.push((path, label, est));
    }
    let opts = AteOptions {
        max_difference: args.max_diff,
        alignment: if args.scale {
            AlignmentMode::Sim3
        } else {
            AlignmentMode::Se3
        },
        ..AteOptions::default()
    };
    write(&gt, &estimates, &opts, &args)?;
    println!(
        "wrote {} ({} trajectories beside the ground truth); open it with `rerun {}`",
        args.out.display(),
        estimates.len(),
        args.out.display()
    );
    Ok(())
}

#[cfg(feature = "rerun")]
fn write(
    gt: &ate_eval::Trajectory,
    estimates: &[(PathBuf, String, ate_eval::Trajectory)],
    opts: &AteOptions,
    args: &ViewArgs,
) -> Result<()> {
    recording::view(gt, estimates, opts, &args.out)
}

#[cfg(not(feature = "rerun"))]
fn write(
    _: &ate_eval::Trajectory,
    _: &[(PathBuf, String, ate_eval::Trajectory)],
    _: &AteOptions,
    _: &ViewArgs,
) -> Result<()> {
    bail!("{}", recording::HOW_TO_GET_IT)
}
