//! One run of an external system, scored as a run of ours: ATE with the sequence's association
//! and alignment (EuRoC: in the body frame), frames tracked, wall time and frames per second,
//! peak memory and CPU time of its process. A crash, a non-zero exit, a timeout, a missing,
//! empty or unreadable trajectory is a failed run with its reason; the last lines of the
//! program's output stay in the run folder.

use crate::external::export::OnDisk;
use crate::external::process;
use crate::external::system::SystemDef;
use crate::external::system::{fill, Resolved, TrajectoryFormat};
use crate::runner::MIN_TRACKED_FRACTION;
use crate::select::{LoadOptions, Source};
use crate::sweep::plan::Job;
use crate::sweep::progress::Progress;
use crate::sweep::store::RunRecord;
use crate::sweep::store::RunStore;
use anyhow::{Context, Result};
use ate_eval::{evaluate_ate, AteOptions, StampPolicy, Trajectory};
use datasets::Catalog;
use datasets::Sequence;
use rayon::prelude::*;
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
    let launched = launch(system, disk, vocabulary, job, out)?;
    score(system, disk, seq, job, out, &launched)
}

/// What a finished external process left: its run folder, the trajectory file it was told to
/// write, its stderr log, and how it ended.
struct Launched {
    dir: PathBuf,
    trajectory: PathBuf,
    stderr: PathBuf,
    finished: process::Finished,
}

/// Fills the system's command, working directory and environment for `job`, writes the
/// command to `command.txt` (to re-run by hand), runs it and trims its logs.
fn launch(
    system: &Resolved,
    disk: &OnDisk,
    vocabulary: &Path,
    job: &Job,
    out: &Path,
) -> Result<Launched> {
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
    atomic_file::write(
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
    Ok(Launched {
        dir,
        trajectory,
        stderr,
        finished,
    })
}

/// Scores a finished run: the reason it failed (exit, timeout, trajectory missing, empty or
/// unreadable), its ATE against the ground truth, its trajectory beside ours and its record.
fn score(
    system: &Resolved,
    disk: &OnDisk,
    seq: &Sequence,
    job: &Job,
    out: &Path,
    launched: &Launched,
) -> Result<RunRecord> {
    let Launched {
        dir,
        trajectory,
        stderr,
        finished,
    } = launched;
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
        } else if no_poses(trajectory) {
            reason = Some("empty trajectory".into());
        } else {
            match read_estimate(trajectory, system.format, disk.times_s.as_deref()) {
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
        let tail = process::tail(stderr, 5);
        atomic_file::write(
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

/// What the runs of external systems on one sequence share.
pub struct ExternalContext<'a> {
    /// The sequence's source (a perturbed one: its folder in the cache).
    pub source: &'a Source,
    /// The sequence (perturbed).
    pub seq: &'a datasets::Sequence,
    /// Its frames.
    pub frames: usize,
    /// The catalog.
    pub catalog: &'a Catalog,
    /// How it was read.
    pub opts: &'a LoadOptions,
    /// Cache of sequences on disk.
    pub cache: &'a Path,
    /// The sweep's folder.
    pub out: &'a Path,
    /// The record of runs.
    pub store: &'a RunStore,
}

/// Runs the jobs of external systems on one sequence in parallel, each recorded as it ends.
/// Systems without a command for the sequence's sensor are skipped with a note.
pub fn run_external_jobs(
    jobs: &[&Job],
    systems: &BTreeMap<String, SystemDef>,
    cx: ExternalContext<'_>,
    pool: &rayon::ThreadPool,
    progress: &Progress,
) -> Result<()> {
    let sensor = cx.seq.camera.sensor;
    let mut runnable: Vec<(&Job, Resolved)> = Vec::new();
    let mut skipped = std::collections::BTreeSet::new();
    for job in jobs {
        let name = job.config.name();
        match systems[name].resolve(name, sensor)? {
            Some(r) => runnable.push((job, r)),
            None => {
                skipped.insert(name.to_string());
            }
        }
    }
    for name in skipped {
        progress.note(&format!(
            "note: system {name} has no {} command; not run on {}",
            match sensor {
                slam_core::SensorKind::Rgbd => "rgbd",
                slam_core::SensorKind::Stereo => "stereo",
            },
            cx.source.label()
        ));
    }
    if runnable.is_empty() {
        return Ok(());
    }
    let disk = progress.multi.suspend(|| {
        crate::external::export::prepare(
            cx.source, cx.seq, cx.frames, cx.catalog, cx.opts, cx.cache,
        )
    })?;
    let mut vocabularies = std::collections::BTreeMap::new();
    for (_, r) in &runnable {
        let v = match &r.vocabulary {
            Some(v) => v.clone(),
            None => crate::external::export::vocabulary_text(cx.cache)?,
        };
        vocabularies.insert(r.name.clone(), v);
    }
    let bar = progress.bar(runnable.len(), cx.source.label(), "external runs {msg}");
    let results: Vec<Result<()>> = pool.install(|| {
        runnable
            .par_iter()
            .map(|(job, system)| {
                if !progress.reserve() {
                    return Ok(());
                }
                let rec = run_job(
                    system,
                    &disk,
                    &vocabularies[&system.name],
                    cx.seq,
                    job,
                    cx.out,
                )
                .with_context(|| {
                    format!("{} seed {} on {}", system.name, job.seed, job.sequence)
                })?;
                if let Some(r) = &rec.reason {
                    bar.set_message(format!("({} seed {}: {r})", system.name, job.seed));
                }
                cx.store.append(&rec)?;
                progress.done(rec.frames);
                bar.inc(1);
                Ok(())
            })
            .collect()
    });
    bar.finish_and_clear();
    results.into_iter().collect()
}

/// Writes a perturbed sequence once into the cache (TUM or EuRoC layout) for external systems,
/// and returns its folder; another shard may have written it first.
#[allow(clippy::too_many_arguments)]
pub fn perturbed_folder(
    cache: &Path,
    src: &Source,
    catalog: &Catalog,
    opts: &LoadOptions,
    seq: &datasets::Sequence,
    frames: &datasets::FrameReader,
    chain: &perturb::Chain,
    seed: u64,
    progress: &Progress,
) -> Result<PathBuf> {
    let realization = match src {
        Source::Catalog(name) if catalog.get(name).is_ok_and(|e| e.preset.is_some()) => {
            format!("-seed{}", opts.synth_seed)
        }
        _ => String::new(),
    };
    let folder = cache.join("sequences").join(format!(
        "{}{realization}-{}f-{}-ps{seed}",
        crate::file_name::safe(&src.label()),
        frames.len(),
        crate::file_name::safe(&chain.to_string())
    ));
    if !folder.is_dir() {
        // A perturbed ground truth is written from memory, not copied from the source.
        let source_dir = if chain.touches_groundtruth() {
            None
        } else {
            crate::external::export::source_folder(src, catalog, opts)?
        };
        let note = format!(
            "source {}\nperturbation {chain}\nperturbation_seed {seed}\nframes {}",
            src.label(),
            frames.len()
        );
        progress.note(&format!(
            "writing {} perturbed by {chain} for external systems to {}",
            src.label(),
            folder.display()
        ));
        let written =
            perturb::write_folder(seq, frames, &folder, &note, source_dir.as_deref(), |_| {});
        if !folder.is_dir() {
            written.with_context(|| format!("writing {}", folder.display()))?;
        }
    }
    Ok(folder)
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
