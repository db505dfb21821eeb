//! One run of an external system, scored as a run of ours: ATE with the sequence's association
//! and alignment (EuRoC: in the body frame), frames tracked, wall time and frames per second,
//! peak memory and CPU time of its process. A crash, a non-zero exit, a timeout, a missing,
//! empty or unreadable trajectory is a failed run with its reason; the last lines of the
//! program's output stay in the run folder.

use super::export::OnDisk;
use super::process;
use super::system::{fill, Resolved, TrajectoryFormat};
use crate::runner::MIN_TRACKED_FRACTION;
use crate::sweep::plan::Job;
use crate::sweep::store::RunRecord;
use anyhow::{Context, Result};
use ate_eval::{evaluate_ate, AteOptions, StampPolicy, Trajectory};
use datasets::Sequence;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Lines of the program's stdout and stderr kept in the run folder.
pub const LOG_LINES: usize = 200;

/// The folder of a run of `system` on `sequence` with `seed` in sweep folder `out`.
pub fn run_dir(out: &Path, sequence: &str, system: &str, seed: u64) -> PathBuf {
    out.join("external")
        .join(sequence)
        .join(system)
        .join(format!("seed{seed}"))
}

/// Reads an external system's trajectory.
pub fn read_estimate(
    path: &Path,
    format: TrajectoryFormat,
    times_s: Option<&Path>,
) -> Result<Trajectory> {
    use ate_eval::io::{read_trajectory, Format};
    let (f, times) = match format {
        TrajectoryFormat::Tum | TrajectoryFormat::TumNs => (Format::Tum, None),
        TrajectoryFormat::Euroc => (Format::Euroc, None),
        TrajectoryFormat::Kitti => (Format::Kitti, times_s),
    };
    let mut t = read_trajectory(path, f, times, StampPolicy::LastWins)?.trajectory;
    if format == TrajectoryFormat::TumNs {
        for s in &mut t.stamps {
            *s *= 1e-9;
        }
    }
    Ok(t)
}

/// Whether a trajectory file holds no pose line (only blanks and `#` comments): a system that
/// tracked nothing, which is a failed run of its own kind, not an unreadable file.
fn no_poses(path: &Path) -> bool {
    std::fs::read(path).is_ok_and(|b| {
        String::from_utf8_lossy(&b)
            .lines()
            .map(str::trim)
            .all(|l| l.is_empty() || l.starts_with('#'))
    })
}

/// Keeps the last [`LOG_LINES`] lines of a log, saying how many were dropped.
fn trim_log(path: &Path) {
    let Ok(bytes) = std::fs::read(path) else {
        return;
    };
    let text = String::from_utf8_lossy(&bytes);
    let n = text.lines().count();
    if n > LOG_LINES {
        let kept = process::tail(path, LOG_LINES);
        let _ = std::fs::write(
            path,
            format!(
                "[noisefree: {} earlier lines dropped]\n{kept}\n",
                n - LOG_LINES
            ),
        );
    }
}

/// Runs `job` (an external system's) on the sequence `disk` puts on disk, scores it against
/// `seq`'s ground truth, and returns its record; its trajectory goes beside ours (body frame
/// for EuRoC) for the figures.
pub fn run_job(
    system: &Resolved,
    disk: &OnDisk,
    vocabulary: &Path,
    seq: &Sequence,
    job: &Job,
    out: &Path,
) -> Result<RunRecord> {
    let dir = run_dir(out, &job.sequence_folder(), &system.name, job.seed);
    if dir.exists() {
        std::fs::remove_dir_all(&dir).with_context(|| format!("clearing {}", dir.display()))?;
    }
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let dir = std::fs::canonicalize(&dir).unwrap_or(dir);
    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let text = |p: &Path| abs(p).display().to_string();
    let mut values: BTreeMap<&str, String> = BTreeMap::new();
    values.insert("sequence", text(&disk.folder));
    values.insert("vocabulary", text(vocabulary));
    values.insert("run_dir", dir.display().to_string());
    values.insert("seed", job.seed.to_string());
    values.insert("frames", disk.frames.to_string());
    if let Ok(exe) = std::env::current_exe() {
        values.insert("noisefree", exe.display().to_string());
    }
    if let Some(f) = system.settings {
        values.insert("settings", text(&disk.settings_file(f)));
    }
    for (key, path) in [
        ("associations", &disk.associations),
        ("times", &disk.times_ns),
        ("times_s", &disk.times_s),
        ("cam0", &disk.cam0),
        ("cam1", &disk.cam1),
    ] {
        if let Some(p) = path {
            values.insert(key, text(p));
        }
    }
    let workdir = PathBuf::from(fill(&system.workdir, &values)?);
    std::fs::create_dir_all(&workdir)
        .with_context(|| format!("creating the working directory {}", workdir.display()))?;
    let trajectory = workdir.join(fill(&system.trajectory, &values)?);
    values.insert("trajectory", trajectory.display().to_string());
    let argv: Vec<String> = system
        .command
        .iter()
        .map(|a| fill(a, &values))
        .collect::<Result<_>>()
        .with_context(|| format!("the command of system {}", system.name))?;
    // A trajectory left by an earlier attempt must not pass for this run's.
    if trajectory.exists() {
        std::fs::remove_file(&trajectory)
            .with_context(|| format!("removing the old {}", trajectory.display()))?;
    }
    let env: BTreeMap<String, String> = system
        .env
        .iter()
        .map(|(k, v)| Ok((k.clone(), fill(v, &values)?)))
        .collect::<Result<_>>()
        .with_context(|| format!("the env of system {}", system.name))?;
    let quoted: Vec<String> = env
        .iter()
        .map(|(k, v)| format!("{k}={}", shell_quote(v)))
        .chain(argv.iter().map(|a| shell_quote(a)))
        .collect();
    ate_eval::io::write_atomic(
        &dir.join("command.txt"),
        format!(
            "cd {} && {}\n",
            shell_quote(&workdir.display().to_string()),
            quoted.join(" ")
        )
        .as_bytes(),
    )?;
    let (stdout, stderr) = (dir.join("stdout.log"), dir.join("stderr.log"));
    let finished = process::run(&argv, &workdir, &env, &stdout, &stderr, system.timeout)?;
    trim_log(&stdout);
    trim_log(&stderr);

    let frames = disk.frames;
    let mut reason = finished.failure(system.timeout);
    let mut estimate: Option<Trajectory> = None;
    if reason.is_none() {
        if !trajectory.is_file() {
            reason = Some(format!(
                "no trajectory ({} not written)",
                trajectory.file_name().map_or_else(
                    || trajectory.display().to_string(),
                    |n| n.to_string_lossy().into_owned()
                )
            ));
        } else if no_poses(&trajectory) {
            reason = Some("empty trajectory".into());
        } else {
            match read_estimate(&trajectory, system.format, disk.times_s.as_deref()) {
                Ok(t) if t.is_empty() => reason = Some("empty trajectory".into()),
                Ok(t) => estimate = Some(t),
                Err(e) => reason = Some(format!("unreadable trajectory: {e}")),
            }
        }
    }
    let tracked = estimate.as_ref().map_or(0, |t| t.len().min(frames));
    let est = estimate.map(|t| match &seq.t_bs {
        Some(t_bs) => t.cam_to_body(t_bs),
        None => t,
    });
    let ate = match (&est, &seq.groundtruth) {
        (Some(e), Some(gt)) => match evaluate_ate(gt, e, &AteOptions::default()) {
            Ok(a) => Some(a.stats.rmse),
            Err(err) => {
                reason.get_or_insert_with(|| format!("no ATE: {err}"));
                None
            }
        },
        _ => None,
    };
    if let Some(e) = &est {
        let tag = system.name.replace('+', "-");
        ate_eval::io::write_tum(
            &out.join("trajectories")
                .join(&job.sequence)
                .join(tag)
                .join(format!("seed{}.txt", job.seed)),
            e,
        )?;
    }
    if let Some(r) = &reason {
        let tail = process::tail(&stderr, 5);
        ate_eval::io::write_atomic(
            &dir.join("failure.txt"),
            format!("{r}\n\nlast lines of stderr:\n{tail}\n").as_bytes(),
        )?;
    }
    let failed = reason.is_some()
        || (ate.is_none() && seq.groundtruth.is_some())
        || (tracked as f64) < MIN_TRACKED_FRACTION * frames as f64;
    let (perturbation, perturb_family, perturb_level, perturb_seed) = job.perturbation_columns();
    Ok(RunRecord {
        sequence: job.sequence.clone(),
        config: system.name.clone(),
        tau_mf: None,
        tau_gf: None,
        tau_mg: None,
        baseline: None,
        seed: job.seed,
        ate_rmse: ate,
        failed,
        frames,
        tracked,
        keyframes: None,
        map_points: None,
        mean_inliers: None,
        mean_outliers: None,
        fps: if finished.wall_s > 0.0 {
            frames as f64 / finished.wall_s
        } else {
            0.0
        },
        wall_s: finished.wall_s,
        synth_seed: job.synth_seed,
        loops: None,
        reason,
        peak_rss_mb: Some(finished.peak_rss_bytes as f64 / 1e6),
        cpu_s: Some(finished.cpu_s),
        perturbation,
        perturb_family,
        perturb_level,
        perturb_seed,
    })
}

/// `s` quoted for a POSIX shell when it needs it (for `command.txt`, to re-run by hand).
fn shell_quote(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}
