//! One run of ours in a sweep: its configuration from the sweep's base and the job's
//! parameters, its file-name tag, and the run itself on features extracted once, with its
//! trajectory and record.

use crate::runner::{run_extracted, ExtractedSequence};
use crate::sweep::plan::Job;
use crate::sweep::store::RunRecord;
use anyhow::{Context, Result};
use ate_eval::io::write_tum;
use atomic_file::write as write_atomic;
use slam_core::place::Vocabulary;
use slam_core::system::Config;
use std::path::Path;
use std::sync::Arc;

/// The configuration of one job of ours: `base` with the job's seed, and the techniques of its
/// column switched on with the job's parameters.
///
/// # Panics
/// When the job is an external system's (a caller bug).
pub fn job_config(base: &Config, job: &Job) -> Config {
    let kind = job
        .config
        .kind()
        .expect("noisefree's configuration of an external system's job");
    let mut c = base.clone();
    c.seed = job.seed;
    c.mcor = kind.mcor().then(|| {
        let mut m = base.mcor.clone().unwrap_or_default();
        m.tau_mf = job.params.tau_mf.unwrap_or(m.tau_mf);
        m.tau_gf = job.params.tau_gf.unwrap_or(m.tau_gf);
        m.tau_mg = job.params.tau_mg.unwrap_or(m.tau_mg);
        if let Some(views) = kind.cluster_views() {
            m.cluster_views = views;
        }
        m
    });
    c.rc = kind.rc().then(|| base.rc.clone().unwrap_or_default());
    c.avc = kind.avc().then(|| {
        let mut a = base.avc.clone().unwrap_or_default();
        a.baseline = job.params.baseline.unwrap_or(a.baseline);
        a
    });
    if let Some(reading) = crate::readings::of(&job.config) {
        reading.apply(&mut c, job.params.baseline);
    }
    c
}

/// A file-name-safe tag of a job's configuration and parameters (its trajectories' folder).
pub fn job_tag(job: &Job) -> String {
    let mut tag = job
        .config
        .name()
        .replace('+', "-")
        .replace(':', "_")
        .replace(['=', '/'], "-");
    let p = &job.params;
    if let (Some(a), Some(b), Some(c)) = (p.tau_mf, p.tau_gf, p.tau_mg) {
        tag.push_str(&format!("_t{a}-{b}-{c}"));
    }
    if let Some(b) = p.baseline {
        tag.push_str(&format!("_b{b}"));
    }
    tag
}

/// Runs one job on a sequence's extracted features (those with the job's ORB settings), writes
/// its trajectory (in the ground truth's frame, for the figures) and, for seed 0, its
/// per-frame statistics; returns its record.
pub fn run_job(
    seq: &datasets::Sequence,
    extracted: &[ExtractedSequence],
    base: &Config,
    vocabulary: Option<&Arc<Vocabulary>>,
    job: &Job,
    out: &Path,
) -> Result<RunRecord> {
    let cfg = job_config(base, job);
    let features = extracted
        .iter()
        .find(|e| e.orb == cfg.orb)
        .context("no features extracted with the run's ORB settings")?;
    let o = run_extracted(seq, features, &cfg, vocabulary, |_| {});
    let dir = out
        .join("trajectories")
        .join(job.sequence_folder())
        .join(job_tag(job));
    let est = match &seq.t_bs {
        Some(t_bs) => o.trajectory.cam_to_body(t_bs),
        None => o.trajectory.clone(),
    };
    write_tum(&dir.join(format!("seed{}.txt", job.seed)), &est)?;
    if job.seed == 0 {
        let mut w = csv::Writer::from_writer(Vec::new());
        for s in &o.stats {
            w.serialize(s)?;
        }
        write_atomic(&dir.join("frames_seed0.csv"), &w.into_inner()?)?;
    }
    let (mean_inliers, mean_outliers) = o.mean_inliers_outliers();
    let (perturbation, perturb_family, perturb_level, perturb_seed) = job.perturbation_columns();
    Ok(RunRecord {
        sequence: job.sequence.clone(),
        config: job.config.name().to_string(),
        tau_mf: job.params.tau_mf,
        tau_gf: job.params.tau_gf,
        tau_mg: job.params.tau_mg,
        baseline: job.params.baseline,
        seed: job.seed,
        ate_rmse: o.ate_rmse(),
        failed: o.failed,
        frames: o.frames,
        tracked: o.tracked,
        keyframes: Some(o.keyframes),
        map_points: Some(o.map_points),
        mean_inliers: Some(mean_inliers),
        mean_outliers: Some(mean_outliers),
        fps: o.fps(),
        wall_s: o.wall_s,
        synth_seed: job.synth_seed,
        loops: Some(o.loops.len()),
        reason: None,
        peak_rss_mb: None,
        cpu_s: Some(o.cpu_s),
        perturbation,
        perturb_family,
        perturb_level,
        perturb_seed,
    })
}
