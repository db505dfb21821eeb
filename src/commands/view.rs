//! `noisefree view GT EST[=LABEL]... --out FILE.rrd`: trajectory files, each aligned to the
//! ground truth as `eval` aligns it, as one Rerun recording (the real ORB-SLAM2's and
//! ORB-SLAM3's runs of a sweep folder beside ours, scrubbable in the viewer).

use crate::commands::plot::{read_inputs, Inputs};
use crate::recording;
use anyhow::{bail, Result};
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
    recording::output::check(&args.out)?;
    let inputs = read_inputs(&args.gt, &args.estimates, args.max_diff, args.scale)?;
    write(&inputs, &args)?;
    println!(
        "wrote {} ({} trajectories beside the ground truth); open it with `rerun {}`",
        args.out.display(),
        inputs.estimates.len(),
        args.out.display()
    );
    Ok(())
}

#[cfg(feature = "rerun")]
fn write(inputs: &Inputs, args: &ViewArgs) -> Result<()> {
    recording::view(&inputs.gt, &inputs.estimates, &inputs.options, &args.out)
}

#[cfg(not(feature = "rerun"))]
fn write(_: &Inputs, _: &ViewArgs) -> Result<()> {
    bail!("{}", recording::HOW_TO_GET_IT)
}
