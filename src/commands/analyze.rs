//! `noisefree analyze`: the paper's analyses of its two techniques on a synthetic sequence,
//! where the truth is known:
//! - `correlation`: Table II, the correlations of the virtual-camera error terms
//!   (e_ORB,z, e_AVC,zx, e_AVC,zy) with the z-normalised 3-D error, the 2-D projective errors
//!   and the true depth error;
//! - `outliers`: Fig. 8 (inliers / outliers per frame with and without MC-OR) and Fig. 7 (a
//!   frame with MC-OR's rejected features in red).
//!
//! The work is in [`crate::analysis`]; this module parses arguments, writes files and prints.

use super::shared_args::SequenceArgs;
use crate::analysis::correlation::{self as corr, markdown_table, Observation};
use crate::analysis::outliers;
use crate::analysis::report::{
    correlation_markdown, fig8, outliers_markdown, CorrelationRun, Setup,
};
use crate::config_file::{apply_switches, base_config, Switches};
use crate::report::panels::rejected_features_image;
use anyhow::{bail, Context, Result};
use atomic_file::write as write_atomic;
use slam_core::system::{ClusterViews, Config, McorParams};
use std::path::{Path, PathBuf};
use synth::Generator;

/// Arguments of `noisefree analyze`.
#[derive(clap::Args, Debug)]
pub struct AnalyzeArgs {
    /// Which analysis.
    #[command(subcommand)]
    pub analysis: Analysis,
}

/// The analyses.
#[derive(clap::Subcommand, Debug)]
pub enum Analysis {
    /// Table II: correlations of the virtual-camera error terms with the z-normalised 3-D
    /// error, the 2-D projective errors and the true depth error (Markdown + CSV).
    Correlation(CorrelationArgs),
    /// Fig. 8 and Fig. 7: per-frame inliers / outliers with and without MC-OR (CSV + figure)
    /// and one frame with MC-OR's rejected features drawn in red.
    Outliers(OutlierArgs),
}

/// Options shared by the analyses: the synthetic sequence (its truth is what they compare
/// with) and the output folder.
#[derive(clap::Args, Debug)]
pub struct AnalysisSequence {
    /// Synthetic preset or twin (`clean`, `kinect`, `boundary`, `walking`, `twin_fr2_coke`, ...).
    #[arg(long)]
    pub preset: String,
    /// Its length, seed and ablated effects (the flags `run` takes; the data root is unused).
    #[command(flatten)]
    pub sequence: SequenceArgs,
    /// Output folder.
    #[arg(long, default_value = "results/analysis", value_name = "DIR")]
    pub out: PathBuf,
    /// No progress output.
    #[arg(long)]
    pub quiet: bool,
}

impl AnalysisSequence {
    /// Frames analysed: --frames, else the preset's length.
    pub fn frames(&self) -> usize {
        self.sequence.frames.unwrap_or_else(|| {
            synth::Preset::from_name(&self.preset).map_or(300, |p| p.default_frames())
        })
    }

    /// The seed of the synthetic sequence.
    pub fn synth_seed(&self) -> u64 {
        self.sequence.synth_seed
    }
}

/// Arguments of `noisefree analyze correlation`.
#[derive(clap::Args, Debug)]
pub struct CorrelationArgs {
    /// The sequence and output.
    #[command(flatten)]
    pub seq: AnalysisSequence,
    /// Virtual baseline b of both virtual cameras (ORB-SLAM2's static one and AVC's), metres.
    #[arg(long, default_value_t = 0.09)]
    pub baseline: f64,
    /// Run the system with MC-OR on (default: the ORB-SLAM2 baseline).
    #[arg(long)]
    pub mcor: bool,
    /// Run the system with AVC on (default: the ORB-SLAM2 baseline).
    #[arg(long)]
    pub avc: bool,
}

/// Arguments of `noisefree analyze outliers`.
#[derive(clap::Args, Debug)]
pub struct OutlierArgs {
    /// The sequence and output.
    #[command(flatten)]
    pub seq: AnalysisSequence,
    /// Frame drawn for Fig. 7 [default: the one with most MC-OR rejections].
    #[arg(long, value_name = "N")]
    pub frame: Option<usize>,
    /// What runs beside the baseline: `mcor` (the paper's MC-OR with the configuration's
    /// cluster reading, every frame by default), `mcor-frames` (every-frame clusters named
    /// explicitly), `mcor-keyframes` (keyframe clusters, the default before issue 18) or `rc`
    /// (noisefree's rigid consensus). Outputs of a technique other than `mcor` carry its name
    /// (`outliers_P_rc.csv`, ...).
    #[arg(long, default_value = "mcor", value_parser = ["mcor", "mcor-frames", "mcor-keyframes", "rc"])]
    pub technique: String,
}

/// The technique `analyze outliers` runs beside the baseline: its configuration, its label in
/// tables and figures, and the suffix of its output files.
fn technique(name: &str, base: &Config) -> (Config, &'static str, String) {
    let mut c = base.clone();
    match name {
        "mcor-frames" => {
            c.mcor = Some(McorParams {
                cluster_views: ClusterViews::EveryFrame,
                ..base.mcor.clone().unwrap_or_default()
            });
            (c, "w/ MC-OR (every frame)", "_mcor-frames".into())
        }
        "mcor-keyframes" => {
            c.mcor = Some(McorParams {
                cluster_views: ClusterViews::Keyframes,
                ..base.mcor.clone().unwrap_or_default()
            });
            (c, "w/ MC-OR (keyframes)", "_mcor-keyframes".into())
        }
        "rc" => {
            c.mcor = None;
            c.rc = Some(base.rc.clone().unwrap_or_default());
            (c, "rigid consensus", "_rc".into())
        }
        _ => {
            c.mcor = Some(base.mcor.clone().unwrap_or_default());
            (c, "w/ MC-OR", String::new())
        }
    }
}

/// Runs `noisefree analyze`.
pub fn run(args: AnalyzeArgs) -> Result<()> {
    match args.analysis {
        Analysis::Correlation(a) => run_correlation(a),
        Analysis::Outliers(a) => run_outliers(a),
    }
}

fn generator(seq: &AnalysisSequence) -> Result<Generator> {
    if seq.frames() < 2 {
        bail!("--frames must be at least 2");
    }
    let mut config = synth::SynthConfig::preset(&seq.preset)?;
    for effect in &seq.sequence.synth_without {
        config.without(effect.trim())?;
    }
    Ok(Generator::try_new(config, seq.synth_seed())?)
}

fn progress(quiet: bool, total: usize, what: &'static str) -> impl FnMut(usize) {
    let mut next = 0;
    move |done| {
        if !quiet && (done >= next || done == total) {
            eprintln!("{what}: frame {done}/{total}");
            next = done + 50;
        }
    }
}

fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, bytes).with_context(|| format!("writing {}", path.display()))
}

fn run_correlation(args: CorrelationArgs) -> Result<()> {
    let seq = &args.seq;
    let generator = generator(seq)?;
    let config = apply_switches(
        base_config(generator.camera().sensor),
        Switches {
            mcor: args.mcor,
            avc: args.avc,
            mapping_lag: None,
            no_loop_closing: false,
            mcor_cluster: None,
            rc: false,
        },
    );
    let data = corr::collect(
        &generator,
        seq.frames(),
        &config,
        args.baseline,
        progress(seq.quiet, seq.frames(), "correlation"),
    )?;
    if data.observations.is_empty() {
        bail!(
            "no tracked observation with depth in {} frames of {}: nothing to correlate",
            seq.frames(),
            seq.preset
        );
    }
    let tables = corr::tables(&data);
    if !tables.iter().all(corr::cells_valid) {
        bail!("internal error: a correlation outside [-1, 1]: {tables:?}");
    }
    let system = crate::config_file::config_name(&config);
    let stem = format!("table2_{}", seq.preset);
    std::fs::create_dir_all(&seq.out).with_context(|| format!("creating {}", seq.out.display()))?;
    write(
        &seq.out.join(format!("{stem}.csv")),
        &corr::csv_bytes(&tables)?,
    )?;
    let inliers: Vec<Observation> = data
        .observations
        .iter()
        .copied()
        .filter(|o| o.inlier)
        .collect();
    let setup = Setup {
        preset: &args.seq.preset,
        synth_seed: args.seq.synth_seed(),
        frames: args.seq.frames(),
    };
    let run = CorrelationRun {
        baseline: args.baseline,
        mcor: args.mcor,
        avc: args.avc,
    };
    let md = correlation_markdown(&setup, &run, system, &data, &inliers, &tables);
    write(&seq.out.join(format!("{stem}.md")), md.as_bytes())?;
    println!(
        "Table II on synthetic '{}' (seed {}, {} frames, {} tracked, system {system}, b = {} m), \
         Pearson r of magnitudes over {} inlier observations:",
        seq.preset,
        seq.synth_seed(),
        data.frames,
        data.tracked_frames,
        args.baseline,
        inliers.len()
    );
    print!("{}", markdown_table(&tables[0]));
    println!(
        "(Spearman and all-match tables in {})",
        seq.out.join(format!("{stem}.md")).display()
    );
    Ok(())
}

fn run_outliers(args: OutlierArgs) -> Result<()> {
    let seq = &args.seq;
    let generator = generator(seq)?;
    if let Some(k) = args.frame {
        if k >= seq.frames() {
            bail!(
                "--frame {k} is not a frame of the {} generated",
                seq.frames()
            );
        }
    }
    let base = base_config(generator.camera().sensor);
    let (config, label, suffix) = technique(&args.technique, &base);
    let mut data = outliers::collect(
        &generator,
        seq.frames(),
        &base,
        &config,
        args.frame,
        progress(seq.quiet, seq.frames(), "outliers"),
    );
    if config.mcor.is_none() {
        // Fig. 7 and the verdict truth show MC-OR's verdicts; a technique without MC-OR has
        // none to show (its rejections are in the association table).
        data.fig7 = None;
    }
    let p = &format!("{}{suffix}", seq.preset);
    std::fs::create_dir_all(&seq.out).with_context(|| format!("creating {}", seq.out.display()))?;
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in outliers::rows(&data) {
        w.serialize(r)?;
    }
    write(&seq.out.join(format!("outliers_{p}.csv")), &w.into_inner()?)?;
    fig8(&seq.out.join(format!("fig8_{p}")), p, &data, label)?;
    let fig7_note = match &data.fig7 {
        Some(f) => {
            let n_kept = f.features.len() - f.n_rejected();
            let caption = format!(
                "synthetic '{p}' (seed {}), frame {}: {} matches, {} kept, {} rejected by MC-OR (last gating of the final pose optimization)",
                seq.synth_seed(),
                f.index,
                f.features.len(),
                n_kept,
                f.n_rejected()
            );
            let path = seq.out.join(format!("fig7_{p}.png"));
            rejected_features_image(&path, &f.image, f.moving.as_deref(), &f.features, &caption)?;
            format!(
                "Fig. 7: `fig7_{p}.png`, frame {} ({} matches, {} rejected by MC-OR).",
                f.index,
                f.features.len(),
                f.n_rejected()
            )
        }
        None if config.mcor.is_none() => "Fig. 7: drawn for MC-OR only.".to_string(),
        None => "Fig. 7: no tracked frame to draw.".to_string(),
    };
    let setup = Setup {
        preset: &seq.preset,
        synth_seed: seq.synth_seed(),
        frames: seq.frames(),
    };
    let md = outliers_markdown(&setup, p, &args.technique, label, &data, &fig7_note);
    write(&seq.out.join(format!("outliers_{p}.md")), md.as_bytes())?;
    print!("{md}");
    Ok(())
}
