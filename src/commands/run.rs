//! `noisefree run`: SLAM over one sequence (a catalogued name, any folder, or the embedded
//! synthetic default), n seeded runs in parallel, writing each run's TUM trajectory, per-frame
//! CSV and a JSON summary, and printing the ATE where ground truth exists.

use super::shared_args::{Resolved, SourceArgs};
use crate::commands::shared_args::{SequenceArgs, SystemArgs};
use crate::config_file::{config_name, Switches};
use crate::seeded_runs::{self, load, record, run_seeds, summarise};
use anyhow::{bail, Context, Result};
use slam_core::system::ClusterViews;
use std::path::PathBuf;

/// Arguments of `noisefree run`.
// The help texts name placeholders like <sequence>, which rustdoc would read as HTML tags.
#[allow(rustdoc::invalid_html_tags)]
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// The sequence: --seq NAME or --path DIR.
    #[command(flatten)]
    pub source: SourceArgs,
    /// The folder's camera from an ORB-SLAM2 or ORB-SLAM3 settings file (YAML: intrinsics,
    /// distortion, bf, ThDepth, DepthMapFactor, a stereo pair's rectification) instead of the
    /// one its name (TUM) or sensor.yaml files (EuRoC) imply; `noisefree settings` writes one.
    #[arg(long, value_name = "FILE.yaml", requires = "path")]
    pub camera: Option<PathBuf>,
    /// The system's settings file, vocabulary, mapping lag and loop closing.
    #[command(flatten)]
    pub system: SystemArgs,
    /// Seed of the first run; run k uses seed + k.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Number of seeded runs (in parallel, one thread each).
    #[arg(long, default_value_t = 1)]
    pub runs: u64,
    /// Parallel runs at once [default: all cores].
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Turn on MC-OR (paper III-A) with its default thresholds (0.7, 0.7, 0.5 m).
    #[arg(long)]
    pub mcor: bool,
    /// MC-OR's cluster (implies --mcor): `every-frame` (the default: every tracked frame that
    /// kept the point as an inlier adds its feature, the paper's "tracked across N camera
    /// views") or `keyframes` (one feature per observing keyframe, the default before issue 18).
    #[arg(long = "mcor-cluster", value_name = "READING", value_parser = parse_cluster_views)]
    pub mcor_cluster: Option<ClusterViews>,
    /// Turn on noisefree's rigid consensus (beyond the paper): only the matches one rigid camera
    /// motion explains enter pose optimization, and keypoints beside rejected ones on the same
    /// body create no map points.
    #[arg(long)]
    pub rc: bool,
    /// Turn on AVC (paper III-B) with its default baseline (0.09 m).
    #[arg(long)]
    pub avc: bool,
    /// Output folder [default: noisefree-out/<sequence>].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// The sequence's length, synthetic seed and ablated effects, and the data root.
    #[command(flatten)]
    pub sequence: SequenceArgs,
    /// Catalog file [default: the datasets.toml compiled into the binary].
    #[arg(long, value_name = "FILE")]
    pub catalog: Option<PathBuf>,
    /// Perturb the sequence before anything reads it: `family:level[+family:level...]`, e.g.
    /// `depth-axial:2+depth-lateral:2` (families and units: `noisefree perturb --list`).
    #[arg(long, value_name = "CHAIN")]
    pub perturb: Option<String>,
    /// Seed of the perturbation's random draws (independent of --seed: every run sees the same
    /// perturbed copy).
    #[arg(long = "perturb-seed", default_value_t = 0, value_name = "S")]
    pub perturb_seed: u64,
    /// Record the run (the first seed's, with --runs > 1) for the Rerun viewer: images,
    /// keypoints by fate, the map, events and per-frame scalars, the estimate on the ground
    /// truth (needs a binary built with `--features rerun`; open it with `rerun FILE.rrd`).
    #[arg(long, value_name = "FILE.rrd")]
    pub rerun: Option<PathBuf>,
    /// No progress bars.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs `noisefree run`: loads (and perturbs) the sequence, builds the configuration and
/// vocabulary, runs the seeds, writes and prints each run and, over several, their mean.
pub fn run(args: RunArgs) -> Result<()> {
    if args.runs == 0 {
        bail!("--runs must be at least 1");
    }
    let catalog = match &args.catalog {
        Some(p) => datasets::Catalog::load(p)?,
        None => datasets::Catalog::embedded(),
    };
    if let Some(file) = &args.rerun {
        crate::recording::output::check(file)?;
        if !crate::recording::AVAILABLE {
            bail!(
                "--rerun {}: {}",
                file.display(),
                crate::recording::HOW_TO_GET_IT
            );
        }
    }
    let source = args.source.source();
    // Checked before anything is read.
    let chain =
        perturb::Chain::parse(args.perturb.as_deref().unwrap_or("")).context("--perturb")?;
    let opts = args.sequence.load_options(args.camera.clone());
    // Several runs share every frame's features, extracted once as the frames are read; a
    // single run decodes the sequence and extracts as it tracks.
    let loaded = load(
        &source,
        &catalog,
        &opts,
        &chain,
        args.perturb_seed,
        args.runs > 1,
        args.quiet,
    )?;
    let label = loaded.label.clone();
    let switches = Switches {
        mcor: args.mcor,
        avc: args.avc,
        mcor_cluster: args.mcor_cluster,
        rc: args.rc,
        ..Switches::default()
    };
    let Resolved { config, vocabulary } =
        args.system.resolve(loaded.seq.camera.sensor, switches)?;
    let cname = config_name(&config);
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| seeded_runs::default_out(&label));
    let seeds: Vec<u64> = (0..args.runs).map(|k| args.seed + k).collect();
    if !args.quiet {
        eprintln!(
            "{label}: {} frames, {} camera, config {cname}, {} run(s), output {}",
            loaded.frames(),
            if loaded.seq.camera.sensor == slam_core::SensorKind::Rgbd {
                "RGB-D"
            } else {
                "stereo"
            },
            seeds.len(),
            out.display()
        );
    }
    let vocabulary = vocabulary.vocabulary.as_ref();
    let results = run_seeds(
        &loaded,
        &config,
        vocabulary,
        &seeds,
        args.jobs,
        args.quiet,
        args.rerun.as_deref(),
    )?;
    // An earlier run's files in the folder (its summary, or a multi-run's per-seed ones) are
    // replaced: said, so that a default `--out` never overwrites a result silently.
    let earlier = out.join("summary.json").exists()
        || seeds
            .iter()
            .any(|s| out.join(format!("seed{s}")).join("summary.json").exists());
    let summaries = record(&loaded, cname, &results, &chain, args.perturb_seed, &out)?;
    summarise(&label, cname, &results, summaries, &out)?;
    if let Some(file) = &args.rerun {
        println!(
            "recording: {} (seed {}); open it with `rerun {}`",
            file.display(),
            seeds[0],
            file.display()
        );
    }
    if earlier {
        eprintln!(
            "note: replaced the files of an earlier run in {} (--out DIR keeps each run apart)",
            out.display()
        );
    }
    Ok(())
}

/// Parses `--mcor-cluster`.
fn parse_cluster_views(s: &str) -> std::result::Result<ClusterViews, String> {
    match s {
        "keyframes" => Ok(ClusterViews::Keyframes),
        "every-frame" => Ok(ClusterViews::EveryFrame),
        other => Err(format!(
            "unknown cluster reading {other:?}; expected keyframes or every-frame"
        )),
    }
}
