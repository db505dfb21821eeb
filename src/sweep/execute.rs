//! A sweep in phases, each a function a reader can name: [`plan`] (every job, its synthetic
//! realization and perturbation, each configuration checked) -> [`settle_folder`] (the run
//! store, the folder's pinned settings, the vocabulary, the external systems) ->
//! [`check_perturbations`] (every chain fits every sequence, before any run) -> per sequence
//! and realization [`prepare_realization`] (read once, the base configuration) -> per
//! perturbation point [`run_point`]: perturb, the external systems' runs, [`extract`] (ORB
//! once per frame and setting, shared by the runs), [`run_ours`] (in parallel, each run
//! recorded as it ends). Values arrive typed ([`SweepRequest`]) and stay typed.

use crate::config_file::{system_config, Switches};
use crate::external::system::SystemDef;
use crate::runner::{remembering, ExtractedSequence, ImageFrames};
use crate::select::{open, LoadOptions, Source};
use crate::sweep::external_run::{perturbed_folder, run_external_jobs, ExternalContext};
use crate::sweep::job::{job_config, run_job};
use crate::sweep::plan::{expand, perturbation_points, with_perturbations, Job, RunConfig};
use crate::sweep::plan::{Grids, Params, PerturbPoint, Shard};
use crate::sweep::progress::{Cost, Progress};
use crate::sweep::store::{pin_settings, FolderSettings, RunStore};
use crate::vocab_file::VocabularyChoice;
use anyhow::{Context, Result};
use ate_eval::io::write_tum;
use datasets::{Catalog, FrameReader, Sequence};
use rayon::prelude::*;
use slam_core::feature::OrbConfig;
use slam_core::system::Config;
use slam_core::SensorKind;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A sweep as the command line asks for it, every value parsed and checked at the edge.
#[derive(Debug)]
pub struct SweepRequest {
    /// The sequences, in order.
    pub sources: Vec<Source>,
    /// The configurations (columns): ours and external systems'.
    pub kinds: Vec<RunConfig>,
    /// External systems declared in the config file, by name.
    pub systems: BTreeMap<String, SystemDef>,
    /// The parameter grids.
    pub grids: Grids,
    /// Seeded runs per sequence, configuration and parameter set.
    pub runs: u64,
    /// The first run's seed (runs use `first_seed..first_seed + runs`).
    pub first_seed: u64,
    /// Parallel runs at once (`None`: every core).
    pub threads: Option<usize>,
    /// Output folder.
    pub out: PathBuf,
    /// This invocation's slice of the runs.
    pub shard: Option<Shard>,
    /// Configuration file overlaid on every run's defaults.
    pub config: Option<PathBuf>,
    /// `--vocabulary` (`None`: the config file's, else the built-in one).
    pub vocabulary: Option<PathBuf>,
    /// `--mapping-lag`.
    pub mapping_lag: Option<u32>,
    /// Loop closing switched off in every run.
    pub no_loop_closing: bool,
    /// Frames per sequence (synthetic: to render; real: the first N).
    pub frames: Option<usize>,
    /// Seed of the synthetic sequences' realization.
    pub synth_seed: u64,
    /// Synthetic effects switched off.
    pub synth_without: Vec<String>,
    /// Data root of real sequences.
    pub data_dir: Option<PathBuf>,
    /// Run k renders its own realization (synth seed + k).
    pub vary_sequence: bool,
    /// External runs that failed run again.
    pub retry_failed: bool,
    /// Perturbation axes (the ablation's included).
    pub axes: Vec<perturb::Axis>,
    /// The chain under every point.
    pub with: perturb::Chain,
    /// Seed of the perturbations' draws.
    pub perturb_seed: u64,
    /// Every run of a point sees one draw instead of its own.
    pub perturb_shared: bool,
    /// Stop after this many runs (tests of resumption).
    pub max_runs: Option<usize>,
    /// Cache of sequences written for external systems (`None`: `<out>/cache`).
    pub cache_dir: Option<PathBuf>,
    /// No progress bars or notes.
    pub quiet: bool,
}

/// What a sweep runs: its sequences' labels, its perturbation points and every job.
pub struct Plan {
    /// One label per source, in the request's order.
    pub labels: Vec<String>,
    /// The perturbation points (empty without perturbations).
    pub points: Vec<PerturbPoint>,
    /// Every job of the sweep, all shards.
    pub jobs: Vec<Job>,
}

/// Phase 1: every job of the sweep (sequences x configurations x grids x seeds, times the
/// perturbation points), each synthetic job with its realization's seed, and every
/// configuration checked against its valid ranges before anything runs.
pub fn plan(req: &SweepRequest, catalog: &Catalog, settings: &SweepSettings) -> Result<Plan> {
    let labels: Vec<String> = req.sources.iter().map(Source::label).collect();
    let points = perturbation_points(&req.axes, &req.with, req.perturb_seed);
    let mut jobs = with_perturbations(
        expand(
            &labels,
            &req.kinds,
            &req.grids,
            req.first_seed..req.first_seed + req.runs,
        ),
        &points,
        !req.perturb_shared,
    );
    for job in &mut jobs {
        let synthetic = catalog
            .get(&job.sequence)
            .map(|e| e.preset.is_some())
            .unwrap_or(false)
            && req
                .sources
                .iter()
                .any(|s| *s == Source::Catalog(job.sequence.clone()));
        if synthetic {
            job.synth_seed = Some(if req.vary_sequence {
                req.synth_seed + job.seed
            } else {
                req.synth_seed
            });
        }
    }
    // The base settings were checked when resolved; these are each column's own values.
    let mut seen: Vec<(crate::sweep::plan::ConfigKind, Params)> = Vec::new();
    for job in &jobs {
        let Some(kind) = job.config.kind() else {
            continue;
        };
        if seen.contains(&(kind, job.params)) {
            continue;
        }
        seen.push((kind, job.params));
        job_config(&settings.rgbd, job).check().map_err(|e| {
            anyhow::anyhow!("{e} (from --tau-mf, --tau-gf, --tau-mg, --baseline or --mapping-lag)")
        })?;
    }
    Ok(Plan {
        labels,
        points,
        jobs,
    })
}

/// The settings every run of ours starts from, resolved once from `--config`, the flags and
/// the vocabulary (as `run` resolves its own): one base configuration per sensor, which each
/// column's kind, readings and parameters then change. The folder pins what it shares.
pub struct SweepSettings {
    /// The base configuration of RGB-D sequences.
    pub rgbd: Config,
    /// The base configuration of stereo sequences.
    pub stereo: Config,
    /// The place-recognition vocabulary.
    pub vocabulary: VocabularyChoice,
}

impl SweepSettings {
    /// Resolves the request's `--config`, `--mapping-lag`, `--no-loop-closing` and
    /// `--vocabulary`.
    pub fn resolve(req: &SweepRequest) -> Result<Self> {
        let switches = Switches {
            mapping_lag: req.mapping_lag,
            no_loop_closing: req.no_loop_closing,
            ..Switches::default()
        };
        let of = |sensor| system_config(sensor, req.config.as_deref(), switches);
        let vocab_flag =
            crate::config_file::vocabulary_asked(req.vocabulary.as_deref(), req.config.as_deref())?;
        Ok(Self {
            rgbd: of(SensorKind::Rgbd)?,
            stereo: of(SensorKind::Stereo)?,
            vocabulary: crate::vocab_file::choose(vocab_flag.as_deref())?,
        })
    }

    /// The base configuration of a sequence of `sensor`.
    pub fn base(&self, sensor: SensorKind) -> &Config {
        match sensor {
            SensorKind::Rgbd => &self.rgbd,
            SensorKind::Stereo => &self.stereo,
        }
    }
}

/// The output folder ready for runs: its store (resumed), the vocabulary every run of ours
/// uses, and the cache for sequences written for external systems.
pub struct Folder {
    /// The record of finished runs.
    pub store: RunStore,
    /// Cache of sequences on disk for external systems.
    pub cache: PathBuf,
    /// The settings every run of ours starts from, and the vocabulary.
    pub settings: SweepSettings,
}

/// Phase 2: opens the run store (dropping, with `--retry-failed`, this sweep's failed external
/// runs), pins the settings every run of the folder shares (a resumed sweep must not mix
/// settings) and the external systems' definitions.
pub fn settle_folder(req: &SweepRequest, plan: &Plan, settings: SweepSettings) -> Result<Folder> {
    let keys: std::collections::BTreeSet<String> = plan.jobs.iter().map(Job::key).collect();
    let store = RunStore::open_dropping(&req.out, req.shard, |r| {
        req.retry_failed && r.reason.is_some() && keys.contains(&r.key())
    })?;
    // What every run shares, from the settings resolved once (the RGB-D base: what the pins
    // read is the same for both sensors).
    let base = &settings.rgbd;
    let mapping_lag = base.mapping_lag;
    let loop_closing_on = base.loop_closing.enabled && settings.vocabulary.vocabulary.is_some();
    let approximations = crate::config_file::approximations(base);
    let readings = crate::config_file::readings(base);
    // The reading of the `mcor` and `mcor+avc` columns: the config file's, else the default.
    let mcor_cluster = base.mcor.clone().unwrap_or_default().cluster_views;
    let mut synth_without = req.synth_without.clone();
    synth_without.sort();
    synth_without.dedup();
    pin_settings(
        &req.out,
        &FolderSettings {
            mapping_lag,
            vocabulary: settings.vocabulary.identity.clone(),
            loop_closing: loop_closing_on,
            mcor_cluster,
            approximations,
            readings,
            synth_without,
        },
    )?;
    let used: BTreeMap<String, SystemDef> = req
        .kinds
        .iter()
        .filter_map(|k| match k {
            RunConfig::System(name) => Some((name.clone(), req.systems[name].clone())),
            RunConfig::Ours(_) | RunConfig::Reading { .. } => None,
        })
        .collect();
    let recorded = crate::sweep::store::load_dir(&req.out)?;
    crate::external::system::pin_systems(&req.out, &used, |name| {
        recorded.iter().any(|r| r.config == name)
    })?;
    let cache = crate::external::export::cache_root(
        &req.cache_dir
            .clone()
            .unwrap_or_else(|| req.out.join("cache")),
    )?;
    Ok(Folder {
        store,
        cache,
        settings,
    })
}

/// How the sweep's sequences are read.
pub fn load_options(req: &SweepRequest) -> LoadOptions {
    LoadOptions {
        data_dir: datasets::data_root(req.data_dir.as_deref()),
        frames: req.frames,
        synth_seed: req.synth_seed,
        synth_without: req.synth_without.clone(),
        camera: None,
        frame_cache: None,
    }
}

/// Phase 3: a perturbation that does not fit a sequence (its sensor, its camera, its ground
/// truth) is refused before any run; applying a chain reads no frame.
pub fn check_perturbations(
    req: &SweepRequest,
    plan: &Plan,
    catalog: &Catalog,
    opts: &LoadOptions,
) -> Result<()> {
    if plan.points.is_empty() {
        return Ok(());
    }
    for (src, label) in req.sources.iter().zip(&plan.labels) {
        let (seq, frames) = open(src, catalog, opts)?;
        for p in &plan.points {
            p.chain
                .check_sensor(seq.camera.sensor, label)
                .context("--perturb")?;
            perturb::perturb_sequence(&seq, frames.clone(), &p.chain, p.seed)
                .with_context(|| format!("--perturb {} on {label}", p.chain))?;
        }
    }
    Ok(())
}

/// What every phase after the folder's reads: values, not the request.
pub struct Phase<'a> {
    /// The output folder.
    pub out: &'a Path,
    /// This invocation's shard of the runs, if any.
    pub shard: Option<Shard>,
    /// No progress bars or notes.
    pub quiet: bool,
    /// The synthetic seed of realizations that do not vary (without --vary-sequence).
    pub synth_seed: u64,
    /// Whether each run of a synthetic sequence has its own realization (--vary-sequence).
    pub vary_sequence: bool,
    /// The external systems the sweep declares.
    pub systems: &'a BTreeMap<String, SystemDef>,
    /// The catalog of sequences.
    pub catalog: &'a Catalog,
    /// The ready folder.
    pub folder: &'a Folder,
    /// How sequences are read.
    pub opts: &'a LoadOptions,
    /// The worker pool the runs share.
    pub pool: &'a rayon::ThreadPool,
    /// Progress and the run budget.
    pub progress: &'a Progress,
}

/// What one invocation of a sweep did.
pub struct Summary {
    /// What it cost: the runs finished (and recorded) in this invocation, the frames they were
    /// fed, the process's CPU time and the wall time.
    pub cost: Cost,
    /// The file the runs were recorded in.
    pub records: PathBuf,
}

/// Runs the whole sweep (this shard's runs not yet recorded).
pub fn sweep(req: &SweepRequest, catalog: &Catalog) -> Result<Summary> {
    let settings = SweepSettings::resolve(req)?;
    let plan = plan(req, catalog, &settings)?;
    let folder = settle_folder(req, &plan, settings)?;
    // The whole plan, every shard's runs included: the folder is complete when all are recorded.
    crate::sweep::planned::record_plan(&req.out, plan.jobs.iter().map(Job::key))?;
    let mine: Vec<&Job> = plan
        .jobs
        .iter()
        .enumerate()
        .filter(|(i, _)| req.shard.is_none_or(|s| s.contains(*i)))
        .map(|(_, j)| j)
        .collect();
    let todo = mine
        .iter()
        .filter(|j| !folder.store.is_done(&j.key()))
        .count();
    let progress = Progress::new(mine.len(), mine.len() - todo, req.max_runs, req.quiet);
    if !req.quiet {
        let shard_txt = req
            .shard
            .map(|s| format!(" (shard {}/{})", s.index, s.count))
            .unwrap_or_default();
        progress.note(&format!(
            "{} runs in the sweep{shard_txt}, {} already recorded in {}, {todo} to run",
            mine.len(),
            mine.len() - todo,
            folder.store.path().display()
        ));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(req.threads.unwrap_or(0))
        .build()
        .context("starting the worker pool")?;
    let opts = load_options(req);
    check_perturbations(req, &plan, catalog, &opts)?;
    let cx = Phase {
        out: &req.out,
        shard: req.shard,
        quiet: req.quiet,
        synth_seed: req.synth_seed,
        vary_sequence: req.vary_sequence,
        systems: &req.systems,
        catalog,
        folder: &folder,
        opts: &opts,
        pool: &pool,
        progress: &progress,
    };
    for (src, label) in req.sources.iter().zip(&plan.labels) {
        let jobs: Vec<&Job> = mine
            .iter()
            .copied()
            .filter(|j| &j.sequence == label && !folder.store.is_done(&j.key()))
            .collect();
        // One decoded sequence per realization (synthetic with --vary-sequence: one per seed).
        let mut groups: BTreeMap<Option<u64>, Vec<&Job>> = Default::default();
        for j in jobs {
            groups.entry(j.synth_seed).or_default().push(j);
        }
        for (synth_seed, jobs) in groups {
            if progress.exhausted() {
                break;
            }
            let points = points_of(jobs);
            let mut rz = prepare_realization(&cx, src, label, synth_seed, &points)?;
            for (point, jobs) in points {
                if progress.exhausted() {
                    break;
                }
                run_point(&cx, &mut rz, point.as_ref(), jobs)?;
            }
        }
    }
    Ok(Summary {
        cost: progress.finish(),
        records: folder.store.path().to_path_buf(),
    })
}

/// Jobs of one realization grouped by perturbation point in job order (one group, `None`, in
/// a sweep without perturbations).
fn points_of(jobs: Vec<&Job>) -> Vec<PointJobs<'_>> {
    // A point is its printed chain and its draw, each job's key made once.
    let mut keys: Vec<Option<(String, u64)>> = Vec::new();
    let mut out: Vec<PointJobs<'_>> = Vec::new();
    for j in jobs {
        let key = j
            .perturbation
            .as_ref()
            .map(|p| (p.chain.to_string(), p.seed));
        match keys.iter().position(|k| *k == key) {
            Some(i) => out[i].1.push(j),
            None => {
                keys.push(key);
                out.push((j.perturbation.clone(), vec![j]));
            }
        }
    }
    out
}

/// A perturbation point (`None`: unperturbed) and its jobs.
type PointJobs<'a> = (Option<PerturbPoint>, Vec<&'a Job>);

/// Decoded frames a sweep may keep in memory to read them once for all its perturbation points.
const FRAME_MEMORY_BUDGET: usize = 3 << 30;

/// One realization of a sequence, read once for all its points: the sequence, its frames (kept
/// in memory when several points read them), the base configuration of its runs, every ORB
/// setting they use, and the unperturbed frames' ORB once a point that keeps the images asks.
pub struct Realization<'a> {
    /// The source.
    pub src: &'a Source,
    /// Its label.
    pub label: &'a str,
    /// The seed of the realization (synthetic sequences).
    pub synth_seed: Option<u64>,
    /// How it was read.
    pub opts: LoadOptions,
    /// The sequence.
    pub seq: Sequence,
    /// Its frames.
    pub frames: FrameReader,
    /// Our runs' configuration before the job's own settings.
    pub base: Config,
    /// Every ORB setting our runs of the realization use.
    pub orbs: Vec<OrbConfig>,
    /// Whether its jobs are perturbed.
    pub perturbed: bool,
    /// ORB of the unperturbed frames, extracted on first use by a point that keeps the images.
    pub image_frames: Option<Vec<ImageFrames>>,
}

/// Phase 4: reads (or renders) one realization of a sequence, writes its ground truth beside
/// the trajectories (seed 0's realization, for the figures) and sets up its runs' base
/// configuration.
pub fn prepare_realization<'a>(
    cx: &Phase<'_>,
    src: &'a Source,
    label: &'a str,
    synth_seed: Option<u64>,
    points: &[PointJobs<'_>],
) -> Result<Realization<'a>> {
    let jobs: Vec<&Job> = points
        .iter()
        .flat_map(|(_, js)| js.iter().copied())
        .collect();
    let opts = LoadOptions {
        synth_seed: synth_seed.unwrap_or(cx.synth_seed),
        ..cx.opts.clone()
    };
    let (seq, frames) = open(src, cx.catalog, &opts)?;
    if let (Some(gt), true) = (&seq.groundtruth, jobs.iter().any(|j| j.seed == 0)) {
        write_tum(
            &cx.out
                .join("trajectories")
                .join(label)
                .join("groundtruth.txt"),
            gt,
        )?;
    }
    let frames = if points.len() > 1 {
        let (w, h) = (seq.camera.width as usize, seq.camera.height as usize);
        remembering(frames, w * h * 8, FRAME_MEMORY_BUDGET)
    } else {
        frames
    };
    let base = cx.folder.settings.base(seq.camera.sensor).clone();
    let mut orbs: Vec<OrbConfig> = Vec::new();
    for job in jobs.iter().filter(|j| j.config.kind().is_some()) {
        let orb = job_config(&base, job).orb;
        if !orbs.contains(&orb) {
            orbs.push(orb);
        }
    }
    Ok(Realization {
        src,
        label,
        synth_seed,
        opts,
        seq,
        frames,
        base,
        orbs,
        perturbed: jobs.iter().any(|j| j.perturbation.is_some()),
        image_frames: None,
    })
}

/// Phase 5, one perturbation point of a realization: the perturbed sequence, the external
/// systems' runs on it (written once to the cache when perturbed), then our runs on features
/// extracted once.
pub fn run_point(
    cx: &Phase<'_>,
    rz: &mut Realization<'_>,
    point: Option<&PerturbPoint>,
    jobs: Vec<&Job>,
) -> Result<()> {
    let identity = perturb::Chain::default();
    let (chain, pseed) = point.map_or((&identity, 0), |p| (&p.chain, p.seed));
    let (pseq, frames) = perturb::perturb_sequence(&rz.seq, rz.frames.clone(), chain, pseed)
        .with_context(|| format!("perturbing {} by {chain}", rz.label))?;
    let what = if rz.perturbed {
        format!("{} [{chain}]", rz.label)
    } else {
        rz.label.to_string()
    };
    let (ours, theirs): (Vec<&Job>, Vec<&Job>) =
        jobs.into_iter().partition(|j| j.config.kind().is_some());
    if !theirs.is_empty() {
        let perturbed_src;
        let source = if chain.is_identity() {
            rz.src
        } else {
            let folder = perturbed_folder(
                &cx.folder.cache,
                rz.src,
                cx.catalog,
                &rz.opts,
                &pseq,
                &frames,
                chain,
                pseed,
                cx.progress,
            )?;
            perturbed_src = Source::Path(folder);
            &perturbed_src
        };
        run_external_jobs(
            &theirs,
            cx.systems,
            ExternalContext {
                source,
                seq: &pseq,
                frames: frames.len(),
                catalog: cx.catalog,
                opts: &rz.opts,
                cache: &cx.folder.cache,
                out: cx.out,
                store: &cx.folder.store,
            },
            cx.pool,
            cx.progress,
        )?;
    }
    if ours.is_empty() {
        return point_done(cx, &what);
    }
    let mut orbs: Vec<OrbConfig> = Vec::new();
    for job in &ours {
        let orb = job_config(&rz.base, job).orb;
        if !orbs.contains(&orb) {
            orbs.push(orb);
        }
    }
    let point = PointFrames {
        chain,
        seed: pseed,
        seq: &pseq,
        frames,
    };
    let extracted = extract(cx, rz, point, &orbs, &what, ours.len())?;
    run_ours(cx, rz, &pseq, &extracted, &what, &ours)?;
    point_done(cx, &what)
}

/// The end of a point: its line in the log, and its cost in the folder's cost record (the
/// process's CPU and wall time since the previous point ended, so the rendering and reading
/// before a sequence's first point count with it).
fn point_done(cx: &Phase<'_>, what: &str) -> Result<()> {
    cx.progress.log_step(what);
    let c = cx.progress.point_cost();
    if c.runs == 0 {
        return Ok(());
    }
    crate::sweep::cost::append(
        cx.out,
        cx.shard,
        &crate::sweep::cost::CostRow {
            invocation: cx.progress.started_unix.clone(),
            point: what.to_string(),
            runs: c.runs,
            frames: c.frames,
            cpu_s: c.cpu_s,
            wall_s: c.wall_s,
        },
    )
}

/// A perturbation point's sequence: its chain and draw, the perturbed sequence and its frames.
pub struct PointFrames<'a> {
    /// The chain applied.
    pub chain: &'a perturb::Chain,
    /// Seed of its draw.
    pub seed: u64,
    /// The perturbed sequence.
    pub seq: &'a Sequence,
    /// Its frames (perturbed as they are read).
    pub frames: FrameReader,
}

/// Every frame's features once for each ORB setting the point's runs use, shared read-only by
/// them; frames are read (or rendered) and extracted as they go, so the decoded sequence never
/// sits in memory. Depth-only and time perturbations keep the images: their ORB is that of the
/// unperturbed frames (extracted once per realization), with each point's depth and stamps.
pub fn extract(
    cx: &Phase<'_>,
    rz: &mut Realization<'_>,
    point: PointFrames<'_>,
    orbs: &[OrbConfig],
    what: &str,
    runs: usize,
) -> Result<Vec<ExtractedSequence>> {
    let PointFrames {
        chain,
        seed: pseed,
        seq: pseq,
        frames,
    } = point;
    let t_extract = Instant::now();
    let fbar = cx
        .progress
        .bar(frames.len(), format!("{} features", rz.label), "frames");
    let reuse = rz.perturbed && chain.keeps_images();
    let mut how = "extracted";
    let extracted = if reuse {
        if rz.image_frames.is_none() {
            let ibar = cx
                .progress
                .bar(rz.frames.len(), format!("{} ORB", rz.label), "frames");
            let (base_frames, camera, all) = (&rz.frames, &rz.seq.camera, &rz.orbs);
            rz.image_frames = Some(
                cx.pool
                    .install(|| ImageFrames::extract_all(base_frames, camera, all, || ibar.inc(1)))
                    .with_context(|| format!("reading the frames of {}", rz.label))?,
            );
            ibar.finish_and_clear();
        } else {
            how = "reused";
        }
        let perturber = perturb::Perturber::new(
            chain,
            &rz.seq.camera,
            rz.seq
                .depth_factor
                .unwrap_or(perturb::apply::DEFAULT_DEPTH_UNITS),
            pseed,
            rz.frames.len(),
            rz.label,
        )?;
        let image = rz.image_frames.as_ref().expect("extracted above");
        cx.pool
            .install(|| {
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
        cx.pool
            .install(|| ExtractedSequence::extract_all(&frames, &pseq.camera, orbs, || fbar.inc(1)))
            .with_context(|| format!("reading the frames of {what}"))?
    };
    fbar.finish_and_clear();
    if !cx.quiet {
        let n: usize = extracted.iter().map(|e| e.frames.len()).sum();
        let bytes: usize = extracted.iter().map(ExtractedSequence::heap_bytes).sum();
        // The workers' own clocks: the frames' wall times summed would count, on a shared machine,
        // the time a worker waited for its core.
        let cpu: f64 = extracted
            .iter()
            .map(ExtractedSequence::extraction_cpu_s)
            .sum();
        let note = if reuse {
            format!(
                "ORB of the unperturbed frames {how} ({cpu:.1} CPU-s once per sequence), depth and stamps attached"
            )
        } else {
            format!("{cpu:.1} CPU-s")
        };
        cx.progress.note(&format!(
            "{what}: features of {n} frames in {:.1} s ({note}, {:.0} KB per frame, shared by {runs} runs)",
            t_extract.elapsed().as_secs_f64(),
            bytes as f64 / 1024.0 / n.max(1) as f64,
        ));
    }
    Ok(extracted)
}

/// Our runs of one point in parallel (one thread each), each recorded in the store as it ends.
pub fn run_ours(
    cx: &Phase<'_>,
    rz: &Realization<'_>,
    pseq: &Sequence,
    extracted: &[ExtractedSequence],
    what: &str,
    jobs: &[&Job],
) -> Result<()> {
    let prefix = match rz.synth_seed {
        Some(s) if cx.vary_sequence => format!("{what} s{s}"),
        _ => what.to_string(),
    };
    let bar = cx.progress.bar(jobs.len(), prefix, "runs");
    let results: Vec<Result<()>> = cx.pool.install(|| {
        jobs.par_iter()
            .map(|job| {
                if !cx.progress.reserve() {
                    return Ok(());
                }
                let rec = run_job(
                    pseq,
                    extracted,
                    &rz.base,
                    cx.folder.settings.vocabulary.vocabulary.as_ref(),
                    job,
                    cx.out,
                )?;
                cx.folder.store.append(&rec)?;
                cx.progress.done(rec.frames);
                bar.inc(1);
                Ok(())
            })
            .collect()
    });
    bar.finish_and_clear();
    results.into_iter().collect()
}
