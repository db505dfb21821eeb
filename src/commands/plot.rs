//! `noisefree plot GT EST[=LABEL]...`: the top view of one or more estimated trajectories, each
//! aligned to the ground truth as `eval` aligns it (SE3 Umeyama over associated stamps), drawn
//! over the ground truth with its ATE in the legend (like evo_traj --ref ... --align --plot).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use ate_eval::io::{self, Format};
use ate_eval::{evaluate_ate, AlignmentMode, AteOptions, StampPolicy, Trajectory};

/// Arguments of `noisefree plot`.
#[derive(clap::Args, Debug)]
pub struct PlotArgs {
    /// Ground-truth trajectory file (TUM, or EuRoC `.csv`).
    pub gt: PathBuf,
    /// Estimated trajectories, each `FILE` or `FILE=LABEL` (the label names it in the legend;
    /// default: the file name).
    #[arg(required = true, value_name = "EST[=LABEL]")]
    pub estimates: Vec<String>,
    /// Output path without extension: writes `<OUT>.png` and `<OUT>.svg`.
    #[arg(long, value_name = "STEM")]
    pub out: PathBuf,
    /// Figure title [default: the ground-truth file's name].
    #[arg(long)]
    pub title: Option<String>,
    /// Largest timestamp difference of an associated pair, in seconds.
    #[arg(long = "max-diff", default_value_t = 0.02, value_name = "S")]
    pub max_diff: f64,
    /// Fit a Sim3 alignment (rotation, translation and scale) instead of SE3.
    #[arg(long)]
    pub scale: bool,
}

/// Splits `FILE=LABEL` (the last `=` when what follows names no existing file).
fn split_label(arg: &str) -> (PathBuf, String) {
    if let Some((file, label)) = arg.rsplit_once('=') {
        if !file.is_empty() && !label.is_empty() && !Path::new(arg).exists() {
            return (PathBuf::from(file), label.to_string());
        }
    }
    let path = PathBuf::from(arg);
    let label = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| arg.to_string());
    (path, label)
}

/// What `plot` and `view` draw: the ground truth, each estimate (file, label, trajectory) as
/// `eval` reads them (a warning line per repaired file), and the alignment of `--max-diff` and
/// `--scale`.
pub(crate) struct Inputs {
    /// The ground truth.
    pub gt: Trajectory,
    /// Each estimate: its file, its label and its trajectory, in the order given.
    pub estimates: Vec<(PathBuf, String, Trajectory)>,
    /// Association and alignment, as `eval` does them.
    pub options: AteOptions,
}

/// Reads `gt` and every `FILE[=LABEL]` of `estimates`, refusing a `max_diff` that is not a
/// positive number of seconds.
pub(crate) fn read_inputs(
    gt: &Path,
    estimates: &[String],
    max_diff: f64,
    scale: bool,
) -> Result<Inputs> {
    if !(max_diff.is_finite() && max_diff > 0.0) {
        bail!("--max-diff must be a positive number of seconds, got {max_diff}");
    }
    let policy = StampPolicy::for_association(ate_eval::AssociationMode::Tum);
    let read = |p: &Path| -> Result<Trajectory> {
        let t = io::read_trajectory(p, Format::guess(p), None, policy)?;
        for w in &t.warnings {
            eprintln!("warning: {w}");
        }
        Ok(t.trajectory)
    };
    let gt = read(gt)?;
    let estimates = estimates
        .iter()
        .map(|arg| {
            let (path, label) = split_label(arg);
            let est = read(&path)?;
            Ok((path, label, est))
        })
        .collect::<Result<_>>()?;
    let options = AteOptions {
        max_difference: max_diff,
        alignment: if scale {
            AlignmentMode::Sim3
        } else {
            AlignmentMode::Se3
        },
        ..AteOptions::default()
    };
    Ok(Inputs {
        gt,
        estimates,
        options,
    })
}

/// Runs `noisefree plot`.
pub fn run(args: PlotArgs) -> Result<()> {
    let inputs = read_inputs(&args.gt, &args.estimates, args.max_diff, args.scale)?;
    let mut curves = Vec::new();
    for (path, label, est) in &inputs.estimates {
        let ate = evaluate_ate(&inputs.gt, est, &inputs.options)
            .with_context(|| format!("aligning {} to {}", path.display(), args.gt.display()))?;
        println!(
            "{label}: ATE RMSE {:.4} m over {} poses",
            ate.stats.rmse, ate.stats.count
        );
        let aligned = est.transformed(ate.alignment.scale, &ate.alignment.rt);
        curves.push((format!("{label} (ATE {:.3} m)", ate.stats.rmse), aligned));
    }
    let title = args.title.unwrap_or_else(|| {
        args.gt
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    });
    if let Some(parent) = args.out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("creating {}", parent.display()))?;
    }
    crate::report::figures::trajectories(&args.out, &title, &inputs.gt, &curves, &[])?;
    println!("wrote {0}.png and {0}.svg", args.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_split_at_the_last_equals_sign() {
        assert_eq!(
            split_label("a/b.txt=loop on"),
            (PathBuf::from("a/b.txt"), "loop on".to_string())
        );
        assert_eq!(
            split_label("a/b.txt"),
            (PathBuf::from("a/b.txt"), "b.txt".to_string())
        );
        assert_eq!(
            split_label("x=y=z"),
            (PathBuf::from("x=y"), "z".to_string())
        );
    }
}
