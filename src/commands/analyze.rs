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
use crate::analysis::outliers::{self, error_summary, mean_tracked, OutlierData};
use crate::config_file::{apply_switches, base_config, Switches};
use crate::report::panels::{
    per_frame_panels, rejected_features_image, Curve, Panel, BASELINE_COLOR, MCOR_COLOR,
    MOVING_COLOR, REJECTED_COLOR,
};
use anyhow::{bail, Context, Result};
use atomic_file::write as write_atomic;
use slam_core::system::{ClusterViews, Config, McorParams};
use std::fmt::Write as _;
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
    let md = correlation_markdown(&args, system, &data, &inliers, &tables);
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

fn correlation_markdown(
    args: &CorrelationArgs,
    system: &str,
    data: &corr::CorrelationData,
    inliers: &[Observation],
    tables: &[corr::Table],
) -> String {
    let seq = &args.seq;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Table II on synthetic `{}` (synth seed {}, {} frames)\n",
        seq.preset,
        seq.synth_seed(),
        data.frames
    );
    let _ = writeln!(
        s,
        "Generated by `noisefree analyze correlation --preset {} --frames {} --synth-seed {} \
         --baseline {}{}{}`. System: `{system}`; {} of {} frames tracked.\n",
        seq.preset,
        seq.frames(),
        seq.synth_seed(),
        args.baseline,
        if args.mcor { " --mcor" } else { "" },
        if args.avc { " --avc" } else { "" },
        data.tracked_frames,
        data.frames
    );
    let (n_in, med_err, med_base, med_dx) = corr::summary(inliers);
    let (n_all, med_err_all, _, _) = corr::summary(&data.observations);
    let _ = writeln!(
        s,
        "Observations with measured and true depth: {n_all} matches, {n_in} inliers. Inliers: \
         median |Z_D - Z_true| = {:.1} mm (all matches: {:.1} mm), median e_BASE,z = {med_base:.4}, \
         median |dx| = {med_dx:.2} px.\n",
        med_err * 1e3,
        med_err_all * 1e3
    );
    s.push_str("## Definitions\n\n");
    s.push_str(
        "For each observation of a tracked frame — keypoint (u, v), measured depth Z_D, the map \
         point X_w it is matched to in the frame's final pose optimization, and that \
         optimization's pose estimate T_cw — with M = T_cw X_w and D = (u, v) back-projected with \
         Z_D, both in the estimated camera frame, and b the virtual baseline:\n\n\
         - **e_ORB,z**: ORB-SLAM2's static virtual camera, Eq. 7 row 3: (x_M - f_x b / Z_M) - (u - f_x b / Z_D).\n\
         - **e_AVC,zx**, **e_AVC,zy**: Eq. 12 rows 3-4, f_x t_x (1/Z_D' - 1/Z_M), f_y t_y (1/Z_D' - 1/Z_M), \
         virtual camera t = b unit(in-image part of DD'), D' = |D| unit(M).\n\
         - **e_BASE,z**: the z-normalised 3-D error |M - D| / Z_D.\n\
         - **(dx, dy)**: the 2-D projective errors x_M - u, y_M - v (pixels).\n\
         - **true depth error**: |Z_D - Z_true|, Z_true the generator's noiseless depth at the pixel \
         the system read Z_D from (all sensor-model components: axial/lateral noise, quantisation, \
         misregistration, ...); **true z-normalised**: |Z_D - Z_true| / Z_D. Only a synthetic \
         sequence has these; the paper's rows use the estimate M instead of the truth.\n\n\
         Cells are correlations of **magnitudes** (absolute values): a signed AVC row carries \
         sign(t) x sign(range error) with t along the random lateral error, so signed values \
         are uncorrelated with any signed depth error by construction. Pearson's r is the \
         paper's statistic; Spearman's rank correlation is given too because depth errors are \
         heavy-tailed. `-`: undefined (no variance, or a series against itself).\n\n",
    );
    s.push_str("## The paper's Table II (TUM, for comparison)\n\n");
    s.push_str(corr::PAPER_TABLE);
    s.push('\n');
    for t in tables {
        let _ = writeln!(
            s,
            "## {} r, {} (n = {})\n",
            match t.statistic {
                corr::Statistic::Pearson => "Pearson",
                corr::Statistic::Spearman => "Spearman",
            },
            t.subset,
            t.n
        );
        s.push_str(&markdown_table(t));
        s.push('\n');
    }
    s
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
    let md = outliers_markdown(seq, p, &args.technique, label, &data, &fig7_note);
    write(&seq.out.join(format!("outliers_{p}.md")), md.as_bytes())?;
    print!("{md}");
    Ok(())
}

fn fig8(stem: &Path, preset: &str, data: &OutlierData, label: &str) -> Result<()> {
    let series = |s: &[slam_core::system::FrameStats],
                  f: fn(&slam_core::system::FrameStats) -> usize| {
        s.iter().map(|x| f(x) as f64).collect::<Vec<f64>>()
    };
    let inliers = Panel {
        y_desc: "inliers".into(),
        curves: vec![
            Curve {
                label: "ORB-SLAM2".into(),
                color: BASELINE_COLOR,
                values: series(&data.baseline, |s| s.n_inliers),
                thin: false,
            },
            Curve {
                label: label.into(),
                color: MCOR_COLOR,
                values: series(&data.mcor, |s| s.n_inliers),
                thin: false,
            },
        ],
    };
    let outliers = Panel {
        y_desc: "outliers".into(),
        curves: vec![
            Curve {
                label: "ORB-SLAM2".into(),
                color: BASELINE_COLOR,
                values: series(&data.baseline, |s| s.n_outliers),
                thin: false,
            },
            Curve {
                label: format!("{label} (all)"),
                color: MCOR_COLOR,
                values: series(&data.mcor, |s| s.n_outliers),
                thin: false,
            },
        ],
    };
    let mut outliers = outliers;
    if data
        .mcor
        .iter()
        .any(|s| s.n_mcor_rejected_clusters + s.n_mcor_rejected_features > 0)
    {
        outliers.curves.push(Curve {
            label: format!("{label}: rejected by MC-OR"),
            color: REJECTED_COLOR,
            values: series(&data.mcor, |s| {
                s.n_mcor_rejected_clusters + s.n_mcor_rejected_features
            }),
            thin: true,
        });
    }
    let mut inliers = inliers;
    if data.runs.0.moving_inliers.iter().any(|n| *n > 0) {
        inliers.curves.push(Curve {
            label: "ORB-SLAM2: inliers on moving objects".into(),
            color: MOVING_COLOR,
            values: data
                .runs
                .0
                .moving_inliers
                .iter()
                .map(|n| *n as f64)
                .collect(),
            thin: true,
        });
    }
    let centimetres = |e: &[Option<f64>]| {
        e.iter()
            .map(|x| x.map_or(f64::NAN, |m| m * 100.0))
            .collect()
    };
    let position = Panel {
        y_desc: "position error (cm)".into(),
        curves: vec![
            Curve {
                label: "ORB-SLAM2".into(),
                color: BASELINE_COLOR,
                values: centimetres(&data.runs.0.position_errors),
                thin: false,
            },
            Curve {
                label: label.into(),
                color: MCOR_COLOR,
                values: centimetres(&data.runs.1.position_errors),
                thin: false,
            },
        ],
    };
    per_frame_panels(
        stem,
        &format!("Inliers, outliers and position error per frame, synthetic '{preset}'"),
        &[inliers, outliers, position],
    )
}

fn outliers_markdown(
    seq: &AnalysisSequence,
    p: &str,
    technique: &str,
    label: &str,
    data: &OutlierData,
    fig7_note: &str,
) -> String {
    let preset = &seq.preset;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Outliers of ORB-SLAM2 and {label} on synthetic `{preset}` (synth seed {}, {} frames)\n",
        seq.synth_seed(),
        seq.frames()
    );
    let _ = writeln!(
        s,
        "Generated by `noisefree analyze outliers --preset {preset} --frames {} --synth-seed {} \
         --technique {technique}`. Counts are of each frame's final pose optimization (local-map \
         tracking); a gated run's outliers include the matches its gate excluded. Per-frame \
         data: `outliers_{p}.csv`; Fig. 8: `fig8_{p}.png` / `.svg`.\n",
        seq.frames(),
        seq.synth_seed()
    );
    let ate = |x: Option<f64>| x.map_or("F".to_string(), |v| format!("{v:.4}"));
    let tracked =
        |st: &[slam_core::system::FrameStats]| st.iter().filter(|x| x.state.is_tracked()).count();
    s.push_str(
        "| run | tracked frames | mean inliers | mean outliers | mean MC-OR rejected (clusters + features) | ATE RMSE (m) |\n|---|---|---|---|---|---|\n",
    );
    for (name, st, a) in [
        ("ORB-SLAM2", &data.baseline, data.ate.0),
        (label, &data.mcor, data.ate.1),
    ] {
        let _ = writeln!(
            s,
            "| {name} | {}/{} | {:.1} | {:.1} | {:.1} + {:.1} | {} |",
            tracked(st),
            st.len(),
            mean_tracked(st, |x| x.n_inliers),
            mean_tracked(st, |x| x.n_outliers),
            mean_tracked(st, |x| x.n_mcor_rejected_clusters),
            mean_tracked(st, |x| x.n_mcor_rejected_features),
            ate(a)
        );
    }
    association_markdown(&mut s, data, label);
    if technique == "rc" {
        let _ = writeln!(s, "\n{fig7_note}");
        return s;
    }
    let t = &data.truth;
    let th = 0.05;
    s.push_str(
        "\n## MC-OR's verdicts against the truth\n\nTrue depth error |Z_D - Z_true| of the \
         MC-OR run's matches by verdict (last gating of every tracked frame's final pose \
         optimization):\n\n| verdict | matches | median true depth error (mm) | share > 5 cm |\n|---|---|---|---|\n",
    );
    for (name, e) in [
        ("kept", &t.kept_depth_errors),
        ("rejected, feature (FL)", &t.feature_depth_errors),
        ("rejected, cluster (CL)", &t.cluster_depth_errors),
    ] {
        let (median, above) = error_summary(e, th);
        let _ = writeln!(
            s,
            "| {name} | {} | {:.1} | {:.1} % |",
            e.len(),
            median * 1e3,
            above * 100.0
        );
    }
    if t.kept_on_moving.1 + t.rejected_on_moving.1 > 0 {
        let share = |(a, b): (usize, usize)| {
            if b == 0 {
                f64::NAN
            } else {
                100.0 * a as f64 / b as f64
            }
        };
        let _ = writeln!(
            s,
            "\nOn moving objects: {:.1} % of rejected matches ({} of {}), {:.1} % of kept ones ({} of {}).",
            share(t.rejected_on_moving),
            t.rejected_on_moving.0,
            t.rejected_on_moving.1,
            share(t.kept_on_moving),
            t.kept_on_moving.0,
            t.kept_on_moving.1
        );
    }
    let _ = writeln!(s, "\n{fig7_note}");
    s
}

/// The section on what the matches were (ground truth) and where the cameras were.
fn association_markdown(s: &mut String, data: &OutlierData, label: &str) {
    use crate::analysis::association::Association::{Correct, Moving, Unknown, Wrong};
    s.push_str(
        "\n## What the matches were (ground truth)\n\nEvery match of every tracked frame's final \
         pose optimization, checked against the synthetic truth: *correct* when the map point's \
         reference observation (earliest keyframe still observing it) is the same surface point as \
         the matched keypoint (within 3 px x octave scale in the image and 3 cm + 3 % of depth in \
         3-D), *mismatch* otherwise, *moving* when either lies on a moving object, *unknown* \
         without true depth. Position error: distance of the estimated camera centre from the \
         true one (the system's world is its first camera), over tracked frames.\n\n\
         | run | inliers: correct / mismatch / moving / unknown | outliers: correct / mismatch / moving / unknown | matches on moving objects kept as inliers | position error mean / max (m) |\n|---|---|---|---|---|\n",
    );
    for (name, run) in [("ORB-SLAM2", &data.runs.0), (label, &data.runs.1)] {
        let c = &run.associations;
        let split = |inlier: bool| {
            let total = c.total(inlier).max(1) as f64;
            [Correct, Wrong, Moving, Unknown]
                .iter()
                .map(|a| format!("{:.1} %", 100.0 * c.get(inlier, *a) as f64 / total))
                .collect::<Vec<_>>()
                .join(" / ")
                + &format!(" (of {})", c.total(inlier))
        };
        let errors: Vec<f64> = run.position_errors.iter().flatten().copied().collect();
        let mean = errors.iter().sum::<f64>() / errors.len().max(1) as f64;
        let max = errors.iter().copied().fold(0.0, f64::max);
        let (kept, dropped) = (c.get(true, Moving), c.get(false, Moving));
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {:.1} % ({kept} of {}) | {mean:.3} / {max:.3} |",
            split(true),
            split(false),
            100.0 * kept as f64 / (kept + dropped).max(1) as f64,
            kept + dropped
        );
    }
}
