//! `noisefree eval GT EST`: ATE (and optionally RPE) of an estimated trajectory against ground
//! truth, with the association and alignment conventions of evaluate_ate.py / evo_ape.

use anyhow::{bail, Context, Result};
use ate_eval::io::{self, Format};
use ate_eval::{
    evaluate_ate, evaluate_rpe_with, AlignmentMode, AssociationMode, AteOptions, RpeDelta,
    RpePairs, StampPolicy,
};
use serde_json::json;
use std::path::PathBuf;

/// Trajectory file format on the command line.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FormatArg {
    /// Guess from the extension: `.csv` = EuRoC, anything else = TUM.
    Auto,
    /// TUM `timestamp tx ty tz qx qy qz qw` (seconds).
    Tum,
    /// EuRoC ground-truth CSV (`#timestamp [ns], p_RS_R_x, ..., q_RS_w, ...`).
    Euroc,
    /// KITTI poses (12 numbers a line); stamps from --gt-times / --est-times or the line index.
    Kitti,
}

/// Association convention on the command line.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AssocArg {
    /// evaluate_ate.py: greedy by |dt| < max-diff, each stamp once.
    Tum,
    /// evo_ape: nearest stamp from the shorter trajectory, |dt| <= max-diff.
    Evo,
}

/// Arguments of `noisefree eval`.
#[derive(clap::Args, Debug)]
pub struct EvalArgs {
    /// Ground-truth trajectory file.
    pub gt: PathBuf,
    /// Estimated trajectory file.
    pub est: PathBuf,
    /// Largest timestamp difference of an associated pair, in seconds.
    #[arg(long = "max-diff", default_value_t = 0.02, value_name = "S")]
    pub max_diff: f64,
    /// Time offset in seconds added to every estimate stamp before association.
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "S",
        allow_negative_numbers = true
    )]
    pub offset: f64,
    /// Fit a Sim3 alignment (rotation, translation and scale) instead of SE3.
    #[arg(long, conflicts_with = "no_align")]
    pub scale: bool,
    /// Do not align at all: compare the trajectories in their own frames.
    #[arg(long = "no-align")]
    pub no_align: bool,
    /// Format of both files (overridden per file by --gt-format / --est-format).
    #[arg(long, value_enum, default_value_t = FormatArg::Auto)]
    pub format: FormatArg,
    /// Format of the ground-truth file [default: --format].
    #[arg(long = "gt-format", value_enum)]
    pub gt_format: Option<FormatArg>,
    /// Format of the estimate file [default: --format].
    #[arg(long = "est-format", value_enum)]
    pub est_format: Option<FormatArg>,
    /// KITTI timestamps file (one number a line, seconds) for the ground truth.
    #[arg(long = "gt-times", value_name = "FILE")]
    pub gt_times: Option<PathBuf>,
    /// KITTI timestamps file (one number a line, seconds) for the estimate.
    #[arg(long = "est-times", value_name = "FILE")]
    pub est_times: Option<PathBuf>,
    /// Association convention.
    #[arg(long, value_enum, default_value_t = AssocArg::Tum)]
    pub assoc: AssocArg,
    /// EuRoC cam0 `sensor.yaml`: convert the estimate from cam0 to the body frame with its T_BS
    /// before comparing with body-frame ground truth.
    #[arg(long = "body-from", value_name = "SENSOR_YAML")]
    pub body_from: Option<PathBuf>,
    /// Also compute the RPE over this many associated frames.
    #[arg(long = "rpe-frames", value_name = "N", conflicts_with = "rpe_seconds")]
    pub rpe_frames: Option<usize>,
    /// Also compute the RPE over this time delta, in seconds.
    #[arg(long = "rpe-seconds", value_name = "S")]
    pub rpe_seconds: Option<f64>,
    /// The RPE's samples: `all` (one from every pose, overlapping: TUM's evaluate_rpe.py and
    /// evo's --all_pairs) or `consecutive` (back to back, each starting where the previous
    /// ended: evo_rpe's default).
    #[arg(long = "rpe-pairs", value_name = "all|consecutive", default_value = "all", value_parser = ["all", "consecutive"])]
    pub rpe_pairs: String,
    /// Write the aligned estimate (TUM format) to this file.
    #[arg(long = "save-aligned", value_name = "FILE")]
    pub save_aligned: Option<PathBuf>,
    /// Print every statistic (and per-pose errors) as JSON instead of the human summary.
    #[arg(long)]
    pub json: bool,
    /// Refuse files whose stamps repeat or go back in time (by default they are read as the
    /// tool of --assoc reads them: evaluate_ate.py keeps the last line of a repeated stamp, evo
    /// keeps every line; both sort by time), with a warning line per repaired file.
    #[arg(long)]
    pub strict: bool,
}

fn resolve(arg: FormatArg, path: &std::path::Path) -> Format {
    match arg {
        FormatArg::Auto => Format::guess(path),
        FormatArg::Tum => Format::Tum,
        FormatArg::Euroc => Format::Euroc,
        FormatArg::Kitti => Format::Kitti,
    }
}

/// Warns when an estimate scored against EuRoC's body-frame ground truth looks like a camera
/// (cam0) trajectory, as ORB-SLAM2 and ORB-SLAM3 write: converted with the cam0 `sensor.yaml`
/// beside the ground truth (`mav0/cam0/sensor.yaml`) its ATE is under half and at least a
/// millimetre lower. Nothing is said where no such file is found, or where the two frames
/// cannot be told apart (a vehicle that does not turn).
fn warn_camera_frame(
    args: &EvalArgs,
    gt: &ate_eval::Trajectory,
    est: &ate_eval::Trajectory,
    opts: &AteOptions,
    rmse: f64,
) -> Result<()> {
    let Some(yaml) = args
        .gt
        .parent()
        .and_then(|d| d.parent())
        .map(|mav0| mav0.join("cam0").join("sensor.yaml"))
        .filter(|p| p.is_file())
    else {
        return Ok(());
    };
    let t_bs = io::read_euroc_t_bs(&yaml)?;
    let Ok(body) = evaluate_ate(gt, &est.cam_to_body(&t_bs), opts) else {
        return Ok(());
    };
    if body.stats.rmse < 0.5 * rmse && rmse - body.stats.rmse > 1e-3 {
        eprintln!(
            "warning: {} looks like a camera (cam0) trajectory scored against EuRoC's body-frame \
             ground truth: converted with --body-from {} its ATE RMSE is {:.4} m, not {:.4} m",
            args.est.display(),
            yaml.display(),
            body.stats.rmse,
            rmse
        );
    }
    Ok(())
}

/// Runs `noisefree eval`.
pub fn run(args: EvalArgs) -> Result<()> {
    if args.max_diff.is_nan() || args.max_diff <= 0.0 || !args.max_diff.is_finite() {
        bail!(
            "--max-diff must be a positive number of seconds, got {}",
            args.max_diff
        );
    }
    if !args.offset.is_finite() {
        bail!("--offset must be a finite number of seconds");
    }
    let gt_fmt = resolve(args.gt_format.unwrap_or(args.format), &args.gt);
    let est_fmt = resolve(args.est_format.unwrap_or(args.format), &args.est);
    let association = match args.assoc {
        AssocArg::Tum => AssociationMode::Tum,
        AssocArg::Evo => AssociationMode::Evo,
    };
    let policy = if args.strict {
        StampPolicy::Strict
    } else {
        StampPolicy::for_association(association)
    };
    let gt = io::read_trajectory(&args.gt, gt_fmt, args.gt_times.as_deref(), policy)?;
    let est = io::read_trajectory(&args.est, est_fmt, args.est_times.as_deref(), policy)?;
    for w in gt.warnings.iter().chain(&est.warnings) {
        eprintln!("warning: {w}");
    }
    let mut est_traj = est.trajectory;
    if let Some(yaml) = &args.body_from {
        let t_bs = io::read_euroc_t_bs(yaml)?;
        est_traj = est_traj.cam_to_body(&t_bs);
    }
    let opts = AteOptions {
        max_difference: args.max_diff,
        offset: args.offset,
        alignment: if args.no_align {
            AlignmentMode::None
        } else if args.scale {
            AlignmentMode::Sim3
        } else {
            AlignmentMode::Se3
        },
        association,
    };
    let ate = evaluate_ate(&gt.trajectory, &est_traj, &opts).with_context(|| {
        format!(
            "evaluating {} against {}",
            args.est.display(),
            args.gt.display()
        )
    })?;
    if args.body_from.is_none() && gt_fmt == Format::Euroc {
        warn_camera_frame(&args, &gt.trajectory, &est_traj, &opts, ate.stats.rmse)?;
    }
    let delta = match (args.rpe_frames, args.rpe_seconds) {
        (Some(n), _) => Some(RpeDelta::Frames(n)),
        (None, Some(s)) => Some(RpeDelta::Seconds(s)),
        _ => None,
    };
    let rpe = delta
        .map(|d| {
            let pairs = match args.rpe_pairs.as_str() {
                "consecutive" => RpePairs::Consecutive,
                _ => RpePairs::All,
            };
            evaluate_rpe_with(&gt.trajectory, &est_traj, d, pairs, &opts).with_context(|| {
                format!(
                    "relative pose error of {} against {}",
                    args.est.display(),
                    args.gt.display()
                )
            })
        })
        .transpose()?;
    if let Some(out) = &args.save_aligned {
        let aligned = est_traj.transformed(ate.alignment.scale, &ate.alignment.rt);
        io::write_tum(out, &aligned)?;
    }
    let mode_name = match opts.alignment {
        AlignmentMode::Se3 => "se3",
        AlignmentMode::Sim3 => "sim3",
        AlignmentMode::None => "none",
    };
    if args.json {
        let t = ate.alignment.rt.translation.vector;
        let q = ate.alignment.rt.rotation.coords;
        let pairs: Vec<_> = ate
            .pairs
            .iter()
            .zip(&ate.errors)
            .map(|(&(i, j), e)| json!({"gt_stamp": gt.trajectory.stamps[i], "est_stamp": est_traj.stamps[j], "error": e}))
            .collect();
        let mut doc = json!({
            "gt": args.gt, "est": args.est,
            "gt_poses": gt.trajectory.len(), "est_poses": est_traj.len(),
            "association": format!("{:?}", opts.association).to_lowercase(),
            "max_diff": opts.max_difference, "offset": opts.offset, "alignment": mode_name,
            "ate": ate.stats,
            "alignment_transform": {"scale": ate.alignment.scale, "t": [t.x, t.y, t.z], "q_xyzw": [q.x, q.y, q.z, q.w]},
            "pairs": pairs,
        });
        if let Some(r) = &rpe {
            doc["rpe"] = json!({"trans_m": r.trans, "rot_deg": r.rot});
        }
        println!("{}", serde_json::to_string_pretty(&doc)?);
    } else {
        let s = &ate.stats;
        println!(
            "ATE ({} pairs of {} gt / {} est poses, association {:?} max-diff {} s, alignment {}{})",
            s.count,
            gt.trajectory.len(),
            est_traj.len(),
            opts.association,
            opts.max_difference,
            mode_name,
            if opts.alignment == AlignmentMode::Sim3 { format!(", scale {:.6}", ate.alignment.scale) } else { String::new() }
        );
        println!("  rmse   {:.6} m", s.rmse);
        println!(
            "  mean   {:.6} m   median {:.6} m   std {:.6} m",
            s.mean, s.median, s.std
        );
        println!("  min    {:.6} m   max    {:.6} m", s.min, s.max);
        if let Some(r) = &rpe {
            println!("RPE ({} samples)", r.trans.count);
            println!(
                "  trans  rmse {:.6} m   mean {:.6} m   max {:.6} m",
                r.trans.rmse, r.trans.mean, r.trans.max
            );
            println!(
                "  rot    rmse {:.4} deg  mean {:.4} deg  max {:.4} deg",
                r.rot.rmse, r.rot.mean, r.rot.max
            );
        }
    }
    Ok(())
}
