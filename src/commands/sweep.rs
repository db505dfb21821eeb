//! `noisefree sweep`: sequences x configurations x parameter grids x n seeds, run in parallel
//! (one thread per run), each finished run appended to `<out>/runs.csv` at once, resumable,
//! and shardable over a cluster's job array.

use crate::config_file::{base_config, overlay_file};
use crate::external::system::{systems_in_file, SystemDef};
use crate::runner::{remembering, run_extracted, ExtractedSequence, ImageFrames};
use crate::select::{open, LoadOptions, Source};
use crate::sweep::plan::{
    expand, parse_values, perturbation_points, with_perturbations, ConfigKind, Grids, Job,
    RunConfig, Shard,
};
use crate::sweep::store::{pin_settings, FolderSettings, RunRecord, RunStore};
use anyhow::{bail, Context, Result};
use ate_eval::io::{write_atomic, write_tum};
use datasets::{Catalog, Class, EntryFormat};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use slam_core::feature::OrbConfig;
use slam_core::place::Vocabulary;
use slam_core::system::Config;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Instant;

/// Arguments of `noisefree sweep`.
// The help texts name placeholders like <out>, which rustdoc would read as HTML tags.
#[allow(rustdoc::invalid_html_tags)]
#[derive(clap::Args, Debug)]
pub struct SweepArgs {
    /// Catalogued sequences or synthetic presets, comma-separated or repeated (`fr3_w_rpy,walking`).
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    pub seq: Vec<String>,
    /// TUM RGB-D / EuRoC folders (repeatable).
    #[arg(long, value_name = "DIR")]
    pub path: Vec<PathBuf>,
    /// Every catalogued real sequence of the paper's class `easy` or `hard`.
    #[arg(long, value_name = "easy|hard")]
    pub class: Option<String>,
    /// Every TUM RGB-D sequence of Table III.
    #[arg(long = "all-tum")]
    pub all_tum: bool,
    /// Every EuRoC sequence of Table III.
    #[arg(long = "all-euroc")]
    pub all_euroc: bool,
    /// Every synthetic preset of the catalog.
    #[arg(long = "all-synthetic")]
    pub all_synthetic: bool,
    /// Configurations, comma-separated: the paper's orb, mcor, avc, mcor+avc; MC-OR with
    /// every-frame clusters, mcor-frames and mcor-frames+avc; noisefree's rigid consensus, rc;
    /// and any external SLAM system the --config file declares under [systems.NAME] (e.g. the
    /// real ORB-SLAM2, see the README).
    #[arg(long, default_value = "orb,mcor,avc,mcor+avc", value_name = "LIST")]
    pub configs: String,
    /// Where synthetic sequences are written for external systems, with their settings files
    /// and associations [default: <out>/cache, ignored by git].
    #[arg(long = "cache-dir", value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// MC-OR tau_MF values in metres: a list `0.1,0.3` or a range `start:stop:step`.
    #[arg(long = "tau-mf", default_value = "0.7", value_name = "VALUES")]
    pub tau_mf: String,
    /// MC-OR tau_GF values in metres.
    #[arg(long = "tau-gf", default_value = "0.7", value_name = "VALUES")]
    pub tau_gf: String,
    /// MC-OR tau_MG values in metres.
    #[arg(long = "tau-mg", default_value = "0.5", value_name = "VALUES")]
    pub tau_mg: String,
    /// AVC virtual-camera baselines in metres (e.g. `0.01:0.13:0.02` for Table I).
    #[arg(long, default_value = "0.09", value_name = "VALUES")]
    pub baseline: String,
    /// Seeded runs per sequence and parameter set (seeds 0..n-1).
    #[arg(long, default_value_t = 10)]
    pub runs: u64,
    /// Parallel runs at once [default: all cores].
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Output folder (runs.csv, trajectories).
    #[arg(long, default_value = "results/sweep", value_name = "DIR")]
    pub out: PathBuf,
    /// Run only slice K of N (1-based) of the runs; default: from SLURM_ARRAY_TASK_ID /
    /// SLURM_ARRAY_TASK_COUNT when set, else everything.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// TOML configuration overlaid on the defaults of every run.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Place-recognition vocabulary: a DBoW2 text file (ORB-SLAM2's ORBvoc.txt) or a noisefree
    /// binary one, or `none` for brute-force relocalization and matching [default: the config
    /// file's `vocabulary`, else the built-in assets/vocabulary/noisefree-k10L5.voc].
    #[arg(long, value_name = "FILE|none")]
    pub vocabulary: Option<PathBuf>,
    /// Emulate ORB-SLAM2's concurrent local mapping: each keyframe is mapped up to N frames
    /// late (seeded), so runs with different --seed spread as ORB-SLAM2's do [default: 0,
    /// synchronous as in the paper's protocol: runs of one sequence differ only where
    /// relocalization's RANSAC draws].
    #[arg(long = "mapping-lag", value_name = "N")]
    pub mapping_lag: Option<u32>,
    /// Turn loop closing off in every run (an ablation; the folder records it).
    #[arg(long = "no-loop-closing")]
    pub no_loop_closing: bool,
    /// Synthetic sequences: number of frames (default 300); real ones: only the first N frames.
    #[arg(long, value_name = "N")]
    pub frames: Option<usize>,
    /// Seed of synthetic sequences' scene and noise.
    #[arg(long = "synth-seed", default_value_t = 0, value_name = "S")]
    pub synth_seed: u64,
    /// Synthetic sequences: effects to switch off, comma-separated (an ablation): lens, blur,
    /// rolling_shutter, vignetting, auto_exposure, sensor_noise, image_noise, tremor, depth_lag,
    /// axial, quantisation, lateral, holes, misregistration, depth_distortion, mocap_noise,
    /// layout, stamp_jitter, mocap_clock.
    #[arg(long = "synth-without", value_name = "EFFECTS", value_delimiter = ',')]
    pub synth_without: Vec<String>,
    /// Data root for real sequences [default: $NOISEFREE_DATA, else ./data].
    #[arg(long = "data-dir", value_name = "DIR")]
    pub data_dir: Option<PathBuf>,
    /// Synthetic sequences: run k uses its own realization of the sequence (synth seed
    /// --synth-seed + k: other textures and noise draws), so the spread over runs measures the
    /// sensitivity to the noise rather than only to RANSAC.
    #[arg(long = "vary-sequence")]
    pub vary_sequence: bool,
    /// Run again the runs an external system failed (those with a `reason` in runs.csv: a
    /// non-zero exit, a timeout, no trajectory...), e.g. after fixing its definition; without
    /// it a resumed sweep keeps every recorded run, failed ones included.
    #[arg(long = "retry-failed")]
    pub retry_failed: bool,
    /// A perturbation axis, repeatable: `family:LEVELS` with LEVELS a list (`depth-axial:0,1,2,4,8`)
    /// or a range (`image-noise:0:20:5`). Each axis is swept with the others at level 0 (one
    /// resilience curve per family); every axis' level 0 is one shared, unperturbed point.
    /// Families, units and ranges: `noisefree perturb --list`.
    #[arg(long = "perturb", value_name = "FAMILY:LEVELS")]
    pub perturb: Vec<String>,
    /// An ablation of a named camera chain at a level (`kinect-fr1:1`): the chain, each member
    /// alone at its level in the chain, and the chain without each member (axes
    /// `kinect-fr1~ir-shadow:0,1`, ...), added to the --perturb axes: which member accounts for
    /// what the chain does.
    #[arg(long = "ablate", value_name = "CHAIN:LEVEL")]
    pub ablate: Option<String>,
    /// A perturbation applied under every point of the sweep (`occluders:2`, or a chain
    /// `depth-axial:1+exposure:5`), the axes' members added after it.
    #[arg(long = "perturb-with", value_name = "CHAIN")]
    pub perturb_with: Option<String>,
    /// Seed of the perturbations' random draws (every run of a point sees one perturbed copy).
    #[arg(long = "perturb-seed", default_value_t = 0, value_name = "S")]
    pub perturb_seed: u64,
    /// Every run of a point sees one and the same perturbation draw (seed --perturb-seed).
    /// Without it, run k of every point and every system draws perturbation k (seed
    /// --perturb-seed + k): runs differ in their noise and systems are compared on the same
    /// draws (a paired design). Features are extracted per draw where the images change.
    #[arg(long = "perturb-shared")]
    pub perturb_shared: bool,
    /// The default since paired draws became it (kept so older scripts run unchanged).
    #[arg(
        long = "perturb-per-run",
        hide = true,
        conflicts_with = "perturb_shared"
    )]
    pub perturb_per_run: bool,
    /// Stop after this many runs have finished in this invocation (for testing resumption).
    #[arg(long = "max-runs", value_name = "N", hide = true)]
    pub max_runs: Option<usize>,
    /// No progress bars.
    #[arg(long)]
    pub quiet: bool,
}

fn sources(args: &SweepArgs, catalog: &Catalog) -> Result<Vec<Source>> {
    let mut out: Vec<Source> = Vec::new();
    let mut push = |s: Source| {
        if !out.contains(&s) {
            out.push(s);
        }
    };
    for name in &args.seq {
        catalog.get(name)?;
        push(Source::Catalog(name.clone()));
    }
    for p in &args.path {
        push(Source::Path(p.clone()));
    }
    if let Some(c) = &args.class {
        let class = match c.as_str() {
            "easy" => Class::Easy,
            "hard" => Class::Hard,
            other => bail!("--class {other:?}: expected easy or hard"),
        };
        for e in catalog.by_class(class) {
            push(Source::Catalog(e.name.clone()));
        }
    }
    if args.all_tum {
        for e in catalog.by_format(EntryFormat::Tum) {
            push(Source::Catalog(e.name.clone()));
        }
    }
    if args.all_euroc {
        for e in catalog.by_format(EntryFormat::Euroc) {
            push(Source::Catalog(e.name.clone()));
        }
    }
    if args.all_synthetic {
        for e in catalog.by_format(EntryFormat::Synthetic) {
            push(Source::Catalog(e.name.clone()));
        }
    }
    if out.is_empty() {
        bail!("no sequence given: use --seq, --path, --class, --all-tum, --all-euroc or --all-synthetic");
    }
    Ok(out)
}

/// The configuration of one job of ours.
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
    c
}

/// A file-name-safe tag of a job's configuration and parameters.
pub fn job_tag(job: &Job) -> String {
    let mut tag = job.config.name().replace('+', "-");
    let p = &job.params;
    if let (Some(a), Some(b), Some(c)) = (p.tau_mf, p.tau_gf, p.tau_mg) {
        tag.push_str(&format!("_t{a}-{b}-{c}"));
    }
    if let Some(b) = p.baseline {
        tag.push_str(&format!("_b{b}"));
    }
    tag
}

/// Runs `noisefree sweep`.
pub fn run(args: SweepArgs) -> Result<()> {
    let catalog = Catalog::embedded();
    let srcs = sources(&args, &catalog)?;
    let systems: std::collections::BTreeMap<String, SystemDef> = match &args.config {
        Some(p) => systems_in_file(p)?,
        None => Default::default(),
    };
    let kinds: Vec<RunConfig> = args
        .configs
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| match ConfigKind::parse(s) {
            Ok(k) => Ok(RunConfig::Ours(k)),
            Err(_) if systems.contains_key(s) => Ok(RunConfig::System(s.to_string())),
            Err(e) => Err(if systems.is_empty() {
                e.context("an external system would be declared under [systems.NAME] in --config")
            } else {
                e.context(format!(
                    "nor one of the systems of the config file ({})",
                    systems.keys().cloned().collect::<Vec<_>>().join(", ")
                ))
            }),
        })
        .collect::<Result<_>>()?;
    if kinds.is_empty() {
        bail!("--configs is empty");
    }
    if args.runs == 0 {
        bail!("--runs must be at least 1");
    }
    let grids = Grids {
        tau_mf: parse_values(&args.tau_mf).context("--tau-mf")?,
        tau_gf: parse_values(&args.tau_gf).context("--tau-gf")?,
        tau_mg: parse_values(&args.tau_mg).context("--tau-mg")?,
        baseline: parse_values(&args.baseline).context("--baseline")?,
    };
    let shard = match &args.shard {
        Some(s) => Some(Shard::parse(s)?),
        None => Shard::from_slurm(|k| std::env::var(k).ok())?,
    };
    let labels: Vec<String> = srcs.iter().map(Source::label).collect();
    // Perturbation axes, checked before anything runs.
    let axes: Vec<perturb::Axis> = args
        .perturb
        .iter()
        .map(|a| perturb::Axis::parse(a).with_context(|| format!("--perturb {a}")))
        .collect::<Result<_>>()?;
    let mut axes = axes;
    if let Some(a) = &args.ablate {
        axes.extend(ablation(a).with_context(|| format!("--ablate {a}"))?);
    }
    let with = perturb::Chain::parse(args.perturb_with.as_deref().unwrap_or(""))
        .context("--perturb-with")?;
    let points = perturbation_points(&axes, &with, args.perturb_seed);
    let mut all_jobs = with_perturbations(
        expand(&labels, &kinds, &grids, args.runs),
        &points,
        !args.perturb_shared,
    );
    for job in &mut all_jobs {
        let synthetic = catalog
            .get(&job.sequence)
            .map(|e| e.preset.is_some())
            .unwrap_or(false)
            && srcs
                .iter()
                .any(|s| *s == Source::Catalog(job.sequence.clone()));
        if synthetic {
            job.synth_seed = Some(if args.vary_sequence {
                args.synth_seed + job.seed
            } else {
                args.synth_seed
            });
        }
    }
    // Every configuration the flags make, checked against its valid ranges before anything
    // runs (a config file's values are checked where it is read).
    {
        let mut flags = Config::default();
        if let Some(n) = args.mapping_lag {
            flags.mapping_lag = n;
        }
        let mut seen: Vec<(ConfigKind, crate::sweep::plan::Params)> = Vec::new();
        for job in &all_jobs {
            let Some(kind) = job.config.kind() else {
                continue;
            };
            if seen.contains(&(kind, job.params)) {
                continue;
            }
            seen.push((kind, job.params));
            job_config(&flags, job).check().map_err(|e| {
                anyhow::anyhow!(
                    "{e} (from --tau-mf, --tau-gf, --tau-mg, --baseline or --mapping-lag)"
                )
            })?;
        }
    }
    // --retry-failed: this sweep's runs that an external program failed (a reason recorded)
    // run again.
    let keys: std::collections::BTreeSet<String> = all_jobs.iter().map(Job::key).collect();
    let store = RunStore::open_dropping(&args.out, shard, |r| {
        args.retry_failed && r.reason.is_some() && keys.contains(&r.key())
    })?;
    // The config file over the defaults, read once for the folder's settings.
    let file_config = args
        .config
        .as_ref()
        .map(|p| overlay_file(&Config::default(), p))
        .transpose()?;
    let mapping_lag = match (args.mapping_lag, &file_config) {
        (Some(n), _) => n,
        (None, Some(c)) => c.mapping_lag,
        (None, None) => 0,
    };
    let vocab_flag = match (&args.vocabulary, &args.config) {
        (Some(v), _) => Some(v.clone()),
        (None, Some(c)) => crate::config_file::vocabulary_in_file(c)?,
        (None, None) => None,
    };
    let vocabulary = crate::vocab_file::choose(vocab_flag.as_deref())?;
    let loop_closing_on = match &file_config {
        _ if args.no_loop_closing => false,
        Some(c) => c.loop_closing.enabled,
        None => true,
    } && vocabulary.vocabulary.is_some();
    let approximations = file_config
        .as_ref()
        .map(crate::config_file::approximations)
        .unwrap_or_default();
    // The reading of the `mcor` and `mcor+avc` columns: the config file's, else the default.
    let mcor_cluster = file_config
        .and_then(|c| c.mcor)
        .unwrap_or_default()
        .cluster_views;
    pin_settings(
        &args.out,
        &FolderSettings {
            mapping_lag,
            vocabulary: vocabulary.identity.clone(),
            loop_closing: loop_closing_on,
            mcor_cluster,
            approximations,
            synth_without: {
                let mut w = args.synth_without.clone();
                w.sort();
                w.dedup();
                w
            },
        },
    )?;
    let used: std::collections::BTreeMap<String, SystemDef> = kinds
        .iter()
        .filter_map(|k| match k {
            RunConfig::System(name) => Some((name.clone(), systems[name].clone())),
            RunConfig::Ours(_) => None,
        })
        .collect();
    {
        let recorded = crate::sweep::store::load_dir(&args.out)?;
        crate::external::system::pin_systems(&args.out, &used, |name| {
            recorded.iter().any(|r| r.config == name)
        })?;
    }
    let cache = crate::external::export::cache_root(
        &args
            .cache_dir
            .clone()
            .unwrap_or_else(|| args.out.join("cache")),
    )?;
    let mine: Vec<&Job> = all_jobs
        .iter()
        .enumerate()
        .filter(|(i, _)| shard.is_none_or(|s| s.contains(*i)))
        .map(|(_, j)| j)
        .collect();
    let todo: usize = mine.iter().filter(|j| !store.is_done(&j.key())).count();
    let multi = MultiProgress::with_draw_target(if args.quiet {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    });
    let overall = multi.add(ProgressBar::new(mine.len() as u64));
    overall.set_style(
        ProgressStyle::with_template(
            "{prefix:>12} [{bar:40}] {pos}/{len} runs, elapsed {elapsed}, eta {eta}",
        )
        .expect("static template")
        .progress_chars("=> "),
    );
    overall.set_prefix("sweep");
    overall.set_position((mine.len() - todo) as u64);
    if !args.quiet {
        let shard_txt = shard
            .map(|s| format!(" (shard {}/{})", s.index, s.count))
            .unwrap_or_default();
        multi.println(format!(
            "{} runs in the sweep{shard_txt}, {} already recorded in {}, {todo} to run",
            mine.len(),
            mine.len() - todo,
            store.path().display()
        ))?;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.jobs.unwrap_or(0))
        .build()
        .context("starting the worker pool")?;
    let load_opts = LoadOptions {
        data_dir: datasets::data_root(args.data_dir.as_deref()),
        frames: args.frames,
        synth_seed: args.synth_seed,
        synth_without: args.synth_without.clone(),
        camera: None,
    };
    // A perturbation that does not fit a sequence (its sensor, its camera, its ground truth)
    // is refused before any run: applying a chain reads no frame.
    if !points.is_empty() {
        for (src, label) in srcs.iter().zip(&labels) {
            let (seq, frames) = open(src, &catalog, &load_opts)?;
            for p in &points {
                let chain = perturb::Chain::parse(&p.chain)?;
                chain
                    .check_sensor(seq.camera.sensor, label)
                    .context("--perturb")?;
                perturb::perturb_sequence(&seq, frames.clone(), &chain, p.seed)
                    .with_context(|| format!("--perturb {chain} on {label}"))?;
            }
        }
    }
    let started = Instant::now();
    let finished = std::sync::atomic::AtomicUsize::new(0);
    let started_runs = std::sync::atomic::AtomicUsize::new(0);
    let max_runs = args.max_runs.unwrap_or(usize::MAX);
    for (src, label) in srcs.iter().zip(&labels) {
        let jobs: Vec<&Job> = mine
            .iter()
            .copied()
            .filter(|j| &j.sequence == label && !store.is_done(&j.key()))
            .collect();
        // One decoded sequence per realization (synthetic with --vary-sequence: one per seed).
        let mut groups: std::collections::BTreeMap<Option<u64>, Vec<&Job>> = Default::default();
        for j in jobs {
            groups.entry(j.synth_seed).or_default().push(j);
        }
        for (synth_seed, jobs) in groups {
            if started_runs.load(Ordering::SeqCst) >= max_runs {
                break;
            }
            let opts = LoadOptions {
                synth_seed: synth_seed.unwrap_or(args.synth_seed),
                ..load_opts.clone()
            };
            let (seq, base_frames) = open(src, &catalog, &opts)?;
            if let Some(gt) = &seq.groundtruth {
                // The figures draw seed 0; its realization's ground truth goes beside it.
                if jobs.iter().any(|j| j.seed == 0) {
                    write_tum(
                        &args
                            .out
                            .join("trajectories")
                            .join(label)
                            .join("groundtruth.txt"),
                        gt,
                    )?;
                }
            }
            // The perturbation points of this realization, in job order (one point, `None`,
            // in a sweep without perturbations).
            let mut by_point: Vec<(PointKey, Vec<&Job>)> = Vec::new();
            for j in jobs {
                let key = j.perturbation.as_ref().map(|p| (p.chain.clone(), p.seed));
                match by_point.iter_mut().find(|(k, _)| *k == key) {
                    Some((_, v)) => v.push(j),
                    None => by_point.push((key, vec![j])),
                }
            }
            let perturbed_sweep = by_point.iter().any(|(k, _)| k.is_some());
            // Several points read the same input frames: decode (or render) each once.
            let base_frames = if by_point.len() > 1 {
                let (w, h) = (seq.camera.width as usize, seq.camera.height as usize);
                remembering(base_frames, w * h * 8, FRAME_MEMORY_BUDGET)
            } else {
                base_frames
            };
            let mut base = base_config(seq.camera.sensor);
            if let Some(p) = &args.config {
                base = overlay_file(&base, p)?;
            }
            if let Some(n) = args.mapping_lag {
                base.mapping_lag = n;
            }
            if args.no_loop_closing {
                base.loop_closing.enabled = false;
            }
            // Every ORB setting our runs of this realization use, over all its points.
            let mut all_orbs: Vec<OrbConfig> = Vec::new();
            for (_, js) in &by_point {
                for job in js.iter().filter(|j| j.config.kind().is_some()) {
                    let orb = job_config(&base, job).orb;
                    if !all_orbs.contains(&orb) {
                        all_orbs.push(orb);
                    }
                }
            }
            // ORB of the unperturbed frames, extracted once on first use by a depth-only or
            // time point and shared by all of them.
            let mut image_frames: Option<Vec<ImageFrames>> = None;
            for (point, jobs) in by_point {
                if started_runs.load(Ordering::SeqCst) >= max_runs {
                    break;
                }
                let (chain, pseed) = match &point {
                    Some((c, s)) => (perturb::Chain::parse(c)?, *s),
                    None => (perturb::Chain::default(), 0),
                };
                let (pseq, frames) =
                    perturb::perturb_sequence(&seq, base_frames.clone(), &chain, pseed)
                        .with_context(|| format!("perturbing {label} by {chain}"))?;
                let what = if perturbed_sweep {
                    format!("{label} [{chain}]")
                } else {
                    label.clone()
                };
                // External systems' runs first: each a child process on the sequence on disk
                // (a perturbed sequence written once to the cache).
                let (jobs, theirs): (Vec<&Job>, Vec<&Job>) =
                    jobs.into_iter().partition(|j| j.config.kind().is_some());
                if !theirs.is_empty() {
                    let perturbed_src;
                    let source = if chain.is_identity() {
                        src
                    } else {
                        let folder = perturbed_folder(
                            &cache, src, &catalog, &opts, &pseq, &frames, &chain, pseed, &multi,
                        )?;
                        perturbed_src = Source::Path(folder);
                        &perturbed_src
                    };
                    run_external_jobs(
                        &theirs,
                        &systems,
                        ExternalContext {
                            source,
                            seq: &pseq,
                            frames: frames.len(),
                            catalog: &catalog,
                            opts: &opts,
                            cache: &cache,
                            out: &args.out,
                            store: &store,
                        },
                        &pool,
                        &multi,
                        || {
                            // Reserve a slot first, so parallel runs never overshoot --max-runs.
                            started_runs.fetch_add(1, Ordering::SeqCst) < max_runs
                        },
                        || {
                            finished.fetch_add(1, Ordering::SeqCst);
                            overall.inc(1);
                        },
                    )?;
                }
                if jobs.is_empty() {
                    continue;
                }
                // Every frame's features once for each set of ORB settings the runs use,
                // shared read-only by the runs; frames are read (or rendered) and extracted as
                // they go, so the decoded sequence never sits in memory.
                let mut orbs: Vec<OrbConfig> = Vec::new();
                for job in &jobs {
                    let orb = job_config(&base, job).orb;
                    if !orbs.contains(&orb) {
                        orbs.push(orb);
                    }
                }
                let t_extract = Instant::now();
                let fbar = multi.add(ProgressBar::new(frames.len() as u64));
                fbar.set_style(
                    ProgressStyle::with_template("{prefix:>16} [{bar:40}] {pos}/{len} frames")
                        .expect("static template")
                        .progress_chars("=> "),
                );
                fbar.set_prefix(format!("{label} features"));
                // Depth-only and time perturbations keep the images: their ORB is that of the
                // unperturbed frames, attached to each point's depth and stamps.
                let reuse = perturbed_sweep && chain.keeps_images();
                let mut how = "extracted";
                let extracted = if reuse {
                    if image_frames.is_none() {
                        let ibar = multi.add(ProgressBar::new(base_frames.len() as u64));
                        ibar.set_style(fbar.style());
                        ibar.set_prefix(format!("{label} ORB"));
                        image_frames = Some(
                            pool.install(|| {
                                ImageFrames::extract_all(
                                    &base_frames,
                                    &seq.camera,
                                    &all_orbs,
                                    || ibar.inc(1),
                                )
                            })
                            .with_context(|| format!("reading the frames of {label}"))?,
                        );
                        ibar.finish_and_clear();
                    } else {
                        how = "reused";
                    }
                    let perturber = perturb::Perturber::new(
                        &chain,
                        &seq.camera,
                        seq.depth_factor
                            .unwrap_or(perturb::apply::DEFAULT_DEPTH_UNITS),
                        pseed,
                        base_frames.len(),
                        label,
                    )?;
                    let image = image_frames.as_ref().expect("extracted above");
                    pool.install(|| {
                        orbs.iter()
                            .map(|orb| {
                                let imf = image
                                    .iter()
                                    .find(|f| &f.orb == orb)
                                    .expect("every ORB setting of the realization");
                                imf.attach(
                                    &frames,
                                    |i| perturber.source(i),
                                    &pseq.camera,
                                    || fbar.inc(1),
                                )
                            })
                            .collect::<Result<Vec<_>, _>>()
                    })
                    .with_context(|| format!("reading the frames of {what}"))?
                } else {
                    pool.install(|| {
                        ExtractedSequence::extract_all(&frames, &pseq.camera, &orbs, || fbar.inc(1))
                    })
                    .with_context(|| format!("reading the frames of {what}"))?
                };
                fbar.finish_and_clear();
                drop(frames);
                if !args.quiet {
                    let n: usize = extracted.iter().map(|e| e.frames.len()).sum();
                    let bytes: usize = extracted.iter().map(ExtractedSequence::heap_bytes).sum();
                    let cpu: f64 = extracted.iter().map(ExtractedSequence::extraction_s).sum();
                    let note = if reuse {
                        format!(
                            "ORB of the unperturbed frames {how} ({cpu:.1} s of one core once per sequence), depth and stamps attached"
                        )
                    } else {
                        format!("{cpu:.1} s of one core")
                    };
                    // Printed even when stderr is not a terminal (indicatif then hides its own lines).
                    multi.suspend(|| {
                        eprintln!(
                            "{what}: features of {n} frames in {:.1} s ({note}, {:.0} KB per frame, shared by {} runs)",
                            t_extract.elapsed().as_secs_f64(),
                            bytes as f64 / 1024.0 / n.max(1) as f64,
                            jobs.len()
                        )
                    });
                }
                let bar = multi.add(ProgressBar::new(jobs.len() as u64));
                bar.set_style(
                    ProgressStyle::with_template("{prefix:>16} [{bar:40}] {pos}/{len} runs")
                        .expect("static template")
                        .progress_chars("=> "),
                );
                bar.set_prefix(match synth_seed {
                    Some(s) if args.vary_sequence => format!("{what} s{s}"),
                    _ => what.clone(),
                });
                let results: Vec<Result<()>> = pool.install(|| {
                    jobs.par_iter()
                        .map(|job| {
                            // Reserve a slot first, so parallel runs never overshoot --max-runs.
                            if started_runs.fetch_add(1, Ordering::SeqCst) >= max_runs {
                                return Ok(());
                            }
                            let rec = run_job(
                                &pseq,
                                &extracted,
                                &base,
                                vocabulary.vocabulary.as_ref(),
                                job,
                                &args.out,
                            )?;
                            store.append(&rec)?;
                            finished.fetch_add(1, Ordering::SeqCst);
                            bar.inc(1);
                            overall.inc(1);
                            Ok(())
                        })
                        .collect()
                });
                bar.finish_and_clear();
                for r in results {
                    r?;
                }
            }
        }
    }
    overall.finish_and_clear();
    if !args.quiet {
        eprintln!(
            "{} runs finished in {:.1} s; records in {}",
            finished.load(Ordering::SeqCst),
            started.elapsed().as_secs_f64(),
            store.path().display()
        );
    }
    Ok(())
}

/// The axes of `--ablate CHAIN:LEVEL`.
fn ablation(text: &str) -> Result<Vec<perturb::Axis>> {
    let (name, level) = text
        .split_once(':')
        .context("expected CHAIN:LEVEL, e.g. kinect-fr1:1")?;
    let chain = perturb::NamedChain::parse(name).with_context(|| {
        format!(
            "unknown chain {name:?}; known: {}",
            perturb::NamedChain::ALL
                .map(perturb::NamedChain::name)
                .join(", ")
        )
    })?;
    let level: f64 = level
        .trim()
        .parse()
        .with_context(|| format!("{level:?}: expected a number"))?;
    perturb::Subject::Named(chain).check_level(level)?;
    Ok(perturb::ablation_axes(chain, level))
}

/// What the runs of external systems on one sequence share.
struct ExternalContext<'a> {
    source: &'a Source,
    seq: &'a datasets::Sequence,
    frames: usize,
    catalog: &'a Catalog,
    opts: &'a LoadOptions,
    cache: &'a Path,
    out: &'a Path,
    store: &'a RunStore,
}

/// Runs the jobs of external systems on one sequence in parallel, each recorded as it ends.
/// Systems without a command for the sequence's sensor are skipped with a note. `reserve`
/// says whether a run may start (`--max-runs`), `done` counts a finished one.
fn run_external_jobs(
    jobs: &[&Job],
    systems: &std::collections::BTreeMap<String, SystemDef>,
    cx: ExternalContext<'_>,
    pool: &rayon::ThreadPool,
    multi: &MultiProgress,
    reserve: impl Fn() -> bool + Sync,
    done: impl Fn() + Sync,
) -> Result<()> {
    let sensor = cx.seq.camera.sensor;
    let mut runnable: Vec<(&Job, crate::external::system::Resolved)> = Vec::new();
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
        multi.suspend(|| {
            eprintln!(
                "note: system {name} has no {} command; not run on {}",
                match sensor {
                    slam_core::SensorKind::Rgbd => "rgbd",
                    slam_core::SensorKind::Stereo => "stereo",
                },
                cx.source.label()
            )
        });
    }
    if runnable.is_empty() {
        return Ok(());
    }
    let disk = multi.suspend(|| {
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
    let bar = multi.add(ProgressBar::new(runnable.len() as u64));
    bar.set_style(
        ProgressStyle::with_template("{prefix:>16} [{bar:40}] {pos}/{len} external runs {msg}")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar.set_prefix(cx.source.label());
    let results: Vec<Result<()>> = pool.install(|| {
        runnable
            .par_iter()
            .map(|(job, system)| {
                if !reserve() {
                    return Ok(());
                }
                let rec = crate::external::run::run_job(
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
                done();
                bar.inc(1);
                Ok(())
            })
            .collect()
    });
    bar.finish_and_clear();
    results.into_iter().collect()
}

/// Runs one job on a sequence's extracted features (those with the job's ORB settings), writes
/// its trajectory (in the ground truth's frame, for the figures) and, for seed 0, its
/// per-frame statistics; returns its record.
fn run_job(
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
        cpu_s: None,
        perturbation,
        perturb_family,
        perturb_level,
        perturb_seed,
    })
}

/// A perturbation point of a realization: (chain, perturbation seed), `None` without one.
type PointKey = Option<(String, u64)>;

/// Decoded frames a sweep may keep in memory to read them once for all its perturbation points.
const FRAME_MEMORY_BUDGET: usize = 3 << 30;

/// Writes a perturbed sequence once into the cache (TUM or EuRoC layout) for external systems,
/// and returns its folder; another shard may have written it first.
#[allow(clippy::too_many_arguments)]
fn perturbed_folder(
    cache: &Path,
    src: &Source,
    catalog: &Catalog,
    opts: &LoadOptions,
    seq: &datasets::Sequence,
    frames: &datasets::FrameReader,
    chain: &perturb::Chain,
    seed: u64,
    multi: &MultiProgress,
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
        multi.suspend(|| {
            eprintln!(
                "writing {} perturbed by {chain} for external systems to {}",
                src.label(),
                folder.display()
            )
        });
        let written =
            perturb::write_folder(seq, frames, &folder, &note, source_dir.as_deref(), |_| {});
        if !folder.is_dir() {
            written.with_context(|| format!("writing {}", folder.display()))?;
        }
    }
    Ok(folder)
}
