//! `noisefree sweep`: sequences x configurations x parameter grids x n seeds, run in parallel
//! (one thread per run), each finished run appended to `<out>/runs.csv` at once, resumable,
//! and shardable over a cluster's job array.

use crate::commands::shared_args::{SequenceArgs, SystemArgs};
use crate::external::system::{systems_in_file, SystemDef};
use crate::select::Source;
use crate::sweep::execute::SweepRequest;
use crate::sweep::plan::{parse_values, ConfigKind, Grids, RunConfig, Shard};
use anyhow::{bail, Context, Result};
use datasets::{Catalog, Class, EntryFormat};
use std::collections::BTreeMap;
use std::path::PathBuf;

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
    /// The paper's Table III on its twins: every row's synthetic twin, in the table's order,
    /// full length, under orb, mcor, avc, mcor+avc and rc unless --configs says otherwise
    /// (rows without a twin are named and left out). `noisefree table --paper` prints the
    /// paper's figure beside each row.
    #[arg(long)]
    pub table3: bool,
    /// Configurations, comma-separated: the paper's orb, mcor, avc, mcor+avc; MC-OR with
    /// every-frame clusters, mcor-frames and mcor-frames+avc; noisefree's rigid consensus, rc;
    /// and any external SLAM system the --config file declares under [systems.NAME] (e.g. the
    /// real ORB-SLAM2, see docs/systems.md).
    /// [default: orb,mcor,avc,mcor+avc; with --table3 orb,mcor,avc,mcor+avc,rc]
    #[arg(long, value_name = "LIST")]
    pub configs: Option<String>,
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
    /// Seeded runs per sequence and parameter set (seeds K..K+n-1, K = --first-seed).
    #[arg(long, default_value_t = 10)]
    pub runs: u64,
    /// The first run's seed K: runs use seeds K..K+n-1, and under per-run perturbation draws
    /// run k draws perturbation --perturb-seed + k. Fresh draws for a comparison that must not
    /// reuse those that chose its setting (e.g. --first-seed 10 after a study on seeds 0..9).
    #[arg(long = "first-seed", value_name = "K", default_value_t = 0)]
    pub first_seed: u64,
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
    /// The system's settings file (and external systems), vocabulary, mapping lag and loop
    /// closing.
    #[command(flatten)]
    pub system: SystemArgs,
    /// The sequences' length, synthetic seed and ablated effects, and the data root.
    #[command(flatten)]
    pub sequence: SequenceArgs,
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
    /// Seed of the perturbations' random draws: run k of every point and system draws seed S + k
    /// (paired across systems), or every run seed S under --perturb-shared.
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

/// The configurations of a sweep without --configs.
const DEFAULT_CONFIGS: &str = "orb,mcor,avc,mcor+avc";
/// The configurations of `--table3`: the paper's four columns and noisefree's rigid consensus.
const TABLE3_CONFIGS: &str = "orb,mcor,avc,mcor+avc,rc";

/// The sequences the flags name, each once, in the order given.
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
    if args.table3 {
        let (twins, missing) = crate::sweep::plan::table3_twins(catalog);
        if !missing.is_empty() && !args.quiet {
            eprintln!(
                "note: Table III rows without a twin, left out: {}",
                missing.join(", ")
            );
        }
        for t in twins {
            push(Source::Catalog(t));
        }
    }
    if out.is_empty() {
        bail!("no sequence given: use --seq, --path, --class, --all-tum, --all-euroc, --all-synthetic or --table3");
    }
    Ok(out)
}

/// Runs `noisefree sweep`: the flags typed and checked, then the sweep's phases
/// (`crate::sweep::execute`).
pub fn run(args: SweepArgs) -> Result<()> {
    let catalog = Catalog::embedded();
    let req = request(&args, &catalog)?;
    let done = crate::sweep::execute::sweep(&req, &catalog)?;
    // Said even when quiet: tables of such cells would show n runs where there is one.
    let records = crate::sweep::store::load_dir(&req.out)?;
    if let Some(note) = crate::sweep::spread::identical_note(&records) {
        eprintln!("{note}");
    }
    if let Some(note) = crate::sweep::spread::failures_note(&records) {
        eprintln!("{note}");
    }
    if !args.quiet {
        // A finished run may be a failed one: say so in the last line too.
        let failed = records.iter().filter(|r| r.failed).count();
        let failed = match failed {
            0 => String::new(),
            n => format!(
                " ({n} of the folder's {} runs failed: see above)",
                records.len()
            ),
        };
        eprintln!(
            "{} runs finished in {:.1} s{failed}, {}; records in {}",
            done.cost.runs,
            done.cost.wall_s,
            done.cost.line(),
            done.records.display()
        );
    }
    Ok(())
}

/// The sweep the flags ask for, every value parsed once.
fn request(args: &SweepArgs, catalog: &Catalog) -> Result<SweepRequest> {
    let sources = sources(args, catalog)?;
    let systems: BTreeMap<String, SystemDef> = match &args.system.config {
        Some(p) => systems_in_file(p)?,
        None => Default::default(),
    };
    let configs = match (&args.configs, args.table3) {
        (Some(c), _) => c.as_str(),
        (None, true) => TABLE3_CONFIGS,
        (None, false) => DEFAULT_CONFIGS,
    };
    let kinds: Vec<RunConfig> = configs
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| match crate::readings::parse_column(s) {
            Ok(Some(c)) => Ok(c),
            Ok(None) if systems.contains_key(s) => Ok(RunConfig::System(s.to_string())),
            Err(e) => Err(e),
            Ok(None) => {
                let ours = ConfigKind::parse(s).unwrap_err();
                Err(if systems.is_empty() {
                    anyhow::anyhow!(
                        "{ours:#} (an external system would be declared under [systems.NAME] in \
                         --config)"
                    )
                } else {
                    anyhow::anyhow!(
                        "{ours:#}, nor one of the systems of the config file ({}){}",
                        systems.keys().cloned().collect::<Vec<_>>().join(", "),
                        crate::suggest::did_you_mean(s, systems.keys().map(String::as_str))
                    )
                })
            }
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
    let mut axes: Vec<perturb::Axis> = args
        .perturb
        .iter()
        .map(|a| perturb::Axis::parse(a).with_context(|| format!("--perturb {a}")))
        .collect::<Result<_>>()?;
    if let Some(a) = &args.ablate {
        axes.extend(ablation(a).with_context(|| format!("--ablate {a}"))?);
    }
    let with = perturb::Chain::parse(args.perturb_with.as_deref().unwrap_or(""))
        .context("--perturb-with")?;
    Ok(SweepRequest {
        sources,
        kinds,
        systems,
        grids,
        runs: args.runs,
        first_seed: args.first_seed,
        threads: args.jobs,
        out: args.out.clone(),
        shard,
        config: args.system.config.clone(),
        vocabulary: args.system.vocabulary.clone(),
        mapping_lag: args.system.mapping_lag,
        no_loop_closing: args.system.no_loop_closing,
        frames: args.sequence.frames,
        synth_seed: args.sequence.synth_seed,
        synth_without: args.sequence.synth_without.clone(),
        data_dir: args.sequence.data_dir.clone(),
        vary_sequence: args.vary_sequence,
        retry_failed: args.retry_failed,
        axes,
        with,
        perturb_seed: args.perturb_seed,
        perturb_shared: args.perturb_shared,
        max_runs: args.max_runs,
        cache_dir: args.cache_dir.clone(),
        quiet: args.quiet,
    })
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
