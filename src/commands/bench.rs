//! `noisefree bench`: what tracking and mapping cost per frame for each configuration (orb,
//! mcor, avc, mcor+avc, rc) on one sequence, on one core, and what a sweep of the paper's four
//! configurations over a few seeds runs at, reading and feature extraction included.
//!
//! Features are extracted once, as a sweep does, so the per-configuration figures are the cost
//! of tracking + local mapping + loop closing alone: the part the paper's techniques change.
//! Each configuration runs `--repeat` times and keeps its fastest run (the machine may be
//! shared); the repeats go round the configurations in turn (orb, mcor, ..., orb, mcor, ...),
//! so that a machine that slows down for a while slows every configuration's rounds alike and
//! the ratios to the baseline stay fair. The trajectory hash of each run is printed, so a change
//! meant to be exact can be checked for bit-identical results on the same command.
//!
//! A configuration with AVC may be written `NAME:direct` (e.g. `avc:direct`): the same run
//! with `[avc] aim = "direct"`, the documented approximation that places the virtual camera
//! without the angle's `atan2` / `sin` / `cos` (off by default; see
//! [`AvcAim`](slam_core::techniques::params::AvcAim)), so exact and approximate AVC are timed in one
//! run. Likewise `NAME:strideK` (e.g. `mcor:stride2`) for a configuration with MC-OR: the run
//! with `[mcor] view_stride = K`, the documented approximation whose map points keep the views
//! of every K-th frame only (off by default; see
//! [`McorParams::view_stride`](slam_core::techniques::params::McorParams::view_stride)). Variants
//! combine: `mcor+avc:direct:stride2`.

use crate::config_file::{base_config, overlay_file};
use crate::regress::cases::trajectory_hash;
use crate::runner::{run_extracted, ExtractedSequence};
use crate::select::{open, LoadOptions, Source};
use crate::sweep::job::job_config;
use crate::sweep::plan::{ConfigKind, Job, Params, RunConfig};
use anyhow::{bail, Context, Result};
use ate_eval::io::write_atomic;
use serde::Serialize;
use slam_core::system::FrameStats;
use slam_core::techniques::params::{AvcAim, ClusterViews};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `noisefree bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Catalogued sequence (a synthetic preset or a downloaded one) [default: `kinect`].
    #[arg(long, value_name = "NAME", conflicts_with = "path")]
    pub seq: Option<String>,
    /// Any TUM RGB-D or EuRoC ASL folder (then "reading" is decoding its image files).
    #[arg(long, value_name = "DIR")]
    pub path: Option<PathBuf>,
    /// Frames (synthetic: generated; real: the first N).
    #[arg(long, default_value_t = 300, value_name = "N")]
    pub frames: usize,
    /// Configurations timed, comma-separated; `NAME:direct` is a configuration with AVC under
    /// the direct-aim approximation (`[avc] aim = "direct"`), `NAME:strideK` one with MC-OR's
    /// every-frame clusters under the view-stride approximation (`[mcor] view_stride = K`);
    /// both may be given (`mcor+avc:direct:stride2`).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "orb,mcor,avc,mcor+avc,rc,avc:direct,mcor:stride2,mcor+avc:direct,mcor+avc:direct:stride2",
        value_name = "LIST"
    )]
    pub configs: Vec<String>,
    /// Runs of each configuration (in rounds over the configurations); the fastest counts.
    #[arg(long, default_value_t = 2, value_name = "N")]
    pub repeat: usize,
    /// Seeds of the sweep figure (the paper's four configurations x seeds 0..N on one core);
    /// 0 leaves the sweep figure out.
    #[arg(long = "sweep-seeds", default_value_t = 3, value_name = "N")]
    pub sweep_seeds: u64,
    /// Emulated local-mapping lag (`run --mapping-lag`).
    #[arg(long = "mapping-lag", value_name = "N")]
    pub mapping_lag: Option<u32>,
    /// TOML configuration overlaid on the sensor's defaults.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Place-recognition vocabulary, or `none` [default: the built-in one].
    #[arg(long, value_name = "FILE|none")]
    pub vocabulary: Option<PathBuf>,
    /// Seed of a synthetic sequence's scene and noise.
    #[arg(long = "synth-seed", default_value_t = 0, value_name = "S")]
    pub synth_seed: u64,
    /// Data root for catalogued real sequences [default: $NOISEFREE_DATA, else ./data].
    #[arg(long = "data-dir", value_name = "DIR")]
    pub data_dir: Option<PathBuf>,
    /// Also write the figures as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Only track: one run of the first configuration, nothing else timed (for a profiler,
    /// e.g. `valgrind --tool=callgrind --toggle-collect='*run_extracted*'`).
    #[arg(long)]
    pub profile: bool,
}

/// One configuration's figures.
#[derive(Debug, Serialize)]
struct ConfigFigures {
    config: String,
    /// Frames per second of tracking + mapping (fastest run).
    fps: f64,
    /// Milliseconds a frame (fastest run), and its split from the per-frame statistics.
    ms_per_frame: f64,
    tracking_ms: f64,
    mapping_ms: f64,
    ba_ms: f64,
    loop_ms: f64,
    /// Every run's wall time, seconds.
    runs_s: Vec<f64>,
    /// The trajectory's FNV-1a hash (the same in every run, or the bench fails).
    hash: String,
    keyframes: usize,
    map_points: usize,
    ate_m: Option<f64>,
}

/// The whole report.
#[derive(Debug, Serialize)]
struct Report {
    sequence: String,
    frames: usize,
    reading_s: f64,
    extraction_s: f64,
    configs: Vec<ConfigFigures>,
    sweep_runs: usize,
    sweep_tracking_s: f64,
    /// Frames tracked per second of one core over the sweep, reading and extraction included.
    sweep_fps: Option<f64>,
}

fn mean(stats: &[FrameStats], f: fn(&FrameStats) -> f64) -> f64 {
    stats.iter().map(f).sum::<f64>() / stats.len().max(1) as f64
}

/// One entry of `--configs`: a configuration, and the documented approximations it runs with.
#[derive(Clone, Copy, Debug, PartialEq)]
struct BenchConfig {
    kind: ConfigKind,
    /// `:direct`: AVC under `[avc] aim = "direct"`.
    direct_aim: bool,
    /// `:strideK`: MC-OR's every-frame clusters under `[mcor] view_stride = K`.
    view_stride: Option<u32>,
}

impl BenchConfig {
    /// The configuration `kind` as the paper's columns run it (no approximation).
    fn exact(kind: ConfigKind) -> BenchConfig {
        BenchConfig {
            kind,
            direct_aim: false,
            view_stride: None,
        }
    }

    /// Parses `NAME`, then any of the variants `:direct` (a configuration with AVC) and
    /// `:strideK` (a configuration with MC-OR's every-frame clusters, K >= 1), each once.
    fn parse(s: &str) -> Result<BenchConfig> {
        let mut parts = s.trim().split(':');
        let kind = ConfigKind::parse(parts.next().unwrap_or_default())?;
        let mut c = BenchConfig::exact(kind);
        for variant in parts {
            if variant == "direct" {
                if !kind.avc() {
                    bail!("\"{s}\": `:direct` is an approximation of AVC, and {kind} has no AVC");
                }
                if c.direct_aim {
                    bail!("\"{s}\": `:direct` given twice");
                }
                c.direct_aim = true;
            } else if let Some(k) = variant.strip_prefix("stride") {
                let stride = k.parse::<u32>().ok().filter(|k| *k >= 1).with_context(|| {
                    format!("\"{s}\": `:{variant}` needs a whole number of frames >= 1 (e.g. `:stride2`)")
                })?;
                if !kind.mcor() || kind.cluster_views() == Some(ClusterViews::Keyframes) {
                    bail!(
                        "\"{s}\": `:{variant}` is an approximation of MC-OR's every-frame \
                         clusters, and {kind} has none"
                    );
                }
                if c.view_stride.is_some() {
                    bail!("\"{s}\": `:stride` given twice");
                }
                c.view_stride = Some(stride);
            } else {
                bail!("\"{s}\": unknown variant \"{variant}\" (known: direct, strideK)");
            }
        }
        Ok(c)
    }

    /// The column's name: the configuration's, then its variants (`:direct`, `:strideK`).
    fn name(self) -> String {
        let mut name = self.kind.name().to_string();
        if self.direct_aim {
            name.push_str(":direct");
        }
        if let Some(k) = self.view_stride {
            name.push_str(&format!(":stride{k}"));
        }
        name
    }
}

/// Runs `noisefree bench`.
pub fn run(args: BenchArgs) -> Result<()> {
    if args.frames == 0 || args.repeat == 0 {
        bail!("--frames and --repeat must be at least 1");
    }
    let kinds = args
        .configs
        .iter()
        .map(|c| BenchConfig::parse(c))
        .collect::<Result<Vec<_>>>()
        .context("--configs")?;
    if kinds.is_empty() {
        bail!("--configs: no configuration given");
    }
    let catalog = datasets::Catalog::embedded();
    let source = Source::from_flags(args.seq.as_deref(), args.path.as_deref());
    let label = source.label();
    let opts = LoadOptions {
        data_dir: datasets::data_root(args.data_dir.as_deref()),
        frames: Some(args.frames),
        synth_seed: args.synth_seed,
        synth_without: Vec::new(),
        camera: None,
    };
    let (seq, reader) = open(&source, &catalog, &opts)?;
    let mut base = base_config(seq.camera.sensor);
    if let Some(p) = &args.config {
        base = overlay_file(&base, p)?;
    }
    if let Some(lag) = args.mapping_lag {
        base.mapping_lag = lag;
    }
    base.check()
        .map_err(|e| anyhow::anyhow!("{e} (from the command line or --config)"))?;
    let vocabulary = crate::vocab_file::choose(args.vocabulary.as_deref())?;
    let vocabulary = vocabulary.vocabulary.as_ref();

    // One core for everything: reading and extraction too.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .context("starting the worker pool")?;
    // Reading (decoding or rendering) and extraction, frame by frame, as a sweep does it once
    // per sequence; the extractor times itself, the rest is reading.
    let t = Instant::now();
    let extracted = pool
        .install(|| {
            ExtractedSequence::extract_all(&reader, &seq.camera, &[base.orb.clone()], || {})
        })
        .with_context(|| format!("reading {label}"))?
        .remove(0);
    let extraction_s = extracted.extraction_s();
    let reading_s = (t.elapsed().as_secs_f64() - extraction_s).max(0.0);
    let n = extracted.frames.len();

    let job = |kind: ConfigKind, seed: u64| Job {
        sequence: label.clone(),
        config: RunConfig::Ours(kind),
        params: Params::default(),
        seed,
        synth_seed: None,
        perturbation: None,
    };
    let track = |bench: BenchConfig, seed: u64| {
        let mut config = job_config(&base, &job(bench.kind, seed));
        if bench.direct_aim {
            if let Some(avc) = config.avc.as_mut() {
                avc.aim = AvcAim::Direct;
            }
        }
        if let (Some(k), Some(mcor)) = (bench.view_stride, config.mcor.as_mut()) {
            mcor.view_stride = k;
        }
        let t = Instant::now();
        let o = run_extracted(&seq, &extracted, &config, vocabulary, |_| {});
        (t.elapsed().as_secs_f64(), o)
    };

    if args.profile {
        let (s, o) = track(kinds[0], 0);
        println!(
            "{label} [{}]: {n} frames tracked in {s:.3} s ({:.1} frames/s), trajectory {}",
            kinds[0].name(),
            n as f64 / s,
            trajectory_hash(&o.trajectory)
        );
        return Ok(());
    }

    println!(
        "{label}: {n} frames; reading {:.2} ms/frame, ORB extraction {:.2} ms/frame (one core, once)",
        reading_s * 1e3 / n as f64,
        extraction_s * 1e3 / n as f64
    );
    // The configuration column fits the longest name (variants make names long).
    let w = kinds
        .iter()
        .map(|k| k.name().len())
        .max()
        .unwrap_or(0)
        .max(16);
    println!(
        "{:<w$} {:>9} {:>9} {:>8} {:>9} {:>8} {:>8} {:>8}  {:<16} {:>4} {:>6} {:>9}",
        "config",
        "frames/s",
        "of orb",
        "ms/frame",
        "tracking",
        "mapping",
        "BA",
        "loop",
        "trajectory",
        "KFs",
        "points",
        "ATE mm"
    );
    // Rounds over the configurations: every configuration's repeat r runs in round r. Each
    // keeps its run times, its trajectory's hash (every repeat must give it) and its fastest run.
    struct Measured {
        runs_s: Vec<f64>,
        hash: String,
        fastest: (f64, crate::runner::RunOutcome),
    }
    let mut measured: Vec<Option<Measured>> = kinds.iter().map(|_| None).collect();
    for _ in 0..args.repeat {
        for (&kind, m) in kinds.iter().zip(&mut measured) {
            let (s, o) = track(kind, 0);
            let hash = trajectory_hash(&o.trajectory);
            match m {
                None => {
                    *m = Some(Measured {
                        runs_s: vec![s],
                        hash,
                        fastest: (s, o),
                    })
                }
                Some(m) => {
                    if hash != m.hash {
                        bail!(
                            "{}: two runs of the same seed gave different trajectories",
                            kind.name()
                        );
                    }
                    m.runs_s.push(s);
                    if s < m.fastest.0 {
                        m.fastest = (s, o);
                    }
                }
            }
        }
    }
    let mut figures = Vec::new();
    for (&kind, m) in kinds.iter().zip(measured) {
        let m = m.expect("at least one run");
        let (s, o) = m.fastest;
        figures.push(ConfigFigures {
            config: kind.name(),
            fps: n as f64 / s,
            ms_per_frame: s * 1e3 / n as f64,
            tracking_ms: mean(&o.stats, |x| x.time_tracking_ms),
            mapping_ms: mean(&o.stats, |x| x.time_mapping_ms),
            ba_ms: mean(&o.stats, |x| x.time_ba_ms),
            loop_ms: mean(&o.stats, |x| x.time_loop_ms),
            runs_s: m.runs_s,
            hash: m.hash,
            keyframes: o.keyframes,
            map_points: o.map_points,
            ate_m: o.ate_rmse(),
        });
    }
    let orb_fps = figures.iter().find(|c| c.config == "orb").map(|c| c.fps);
    for f in &figures {
        println!(
            "{:<w$} {:>9.1} {:>9} {:>8.3} {:>9.3} {:>8.3} {:>8.3} {:>8.3}  {:<16} {:>4} {:>6} {:>9}",
            f.config,
            f.fps,
            orb_fps.map_or("-".to_string(), |b| format!("{:.0} %", 100.0 * f.fps / b)),
            f.ms_per_frame,
            f.tracking_ms,
            f.mapping_ms,
            f.ba_ms,
            f.loop_ms,
            f.hash,
            f.keyframes,
            f.map_points,
            f.ate_m.map_or("-".to_string(), |a| format!("{:.3}", a * 1e3))
        );
    }

    let mut sweep_tracking_s = 0.0;
    let mut sweep_runs = 0;
    if args.sweep_seeds > 0 {
        for seed in 0..args.sweep_seeds {
            for kind in ConfigKind::ALL {
                sweep_tracking_s += track(BenchConfig::exact(kind), seed).0;
                sweep_runs += 1;
            }
        }
    }
    let sweep_fps = (sweep_runs > 0)
        .then(|| (sweep_runs * n) as f64 / (reading_s + extraction_s + sweep_tracking_s));
    if let Some(fps) = sweep_fps {
        println!(
            "sweep (orb, mcor, avc, mcor+avc x seeds 0..{}, one core): {sweep_runs} runs, {} frames \
             in {:.1} s = {fps:.1} frames/s (reading {:.1} s and extraction {:.1} s once, \
             tracking {:.1} s)",
            args.sweep_seeds,
            sweep_runs * n,
            reading_s + extraction_s + sweep_tracking_s,
            reading_s,
            extraction_s,
            sweep_tracking_s
        );
    }
    if let Some(path) = &args.json {
        let report = Report {
            sequence: label,
            frames: n,
            reading_s,
            extraction_s,
            configs: figures,
            sweep_runs,
            sweep_tracking_s,
            sweep_fps,
        };
        write_atomic(path, serde_json::to_string_pretty(&report)?.as_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(configs: &[&str], frames: usize) -> BenchArgs {
        BenchArgs {
            seq: Some("clean".into()),
            path: None,
            frames,
            configs: configs.iter().map(|c| c.to_string()).collect(),
            repeat: 2,
            sweep_seeds: 1,
            mapping_lag: None,
            config: None,
            vocabulary: Some("none".into()),
            synth_seed: 0,
            data_dir: None,
            json: None,
            profile: false,
        }
    }

    #[test]
    fn bench_reports_every_configuration_with_its_trajectory_and_the_sweep() {
        let dir = std::env::temp_dir().join(format!("nf-bench-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let json = dir.join("bench.json");
        let timed = [
            "orb",
            "mcor",
            "avc",
            "mcor+avc",
            "rc",
            "mcor+avc:direct",
            "mcor:stride2",
        ];
        let mut a = args(&timed, 30);
        a.json = Some(json.clone());
        run(a).unwrap();
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        assert_eq!(report["frames"], 30);
        let configs = report["configs"].as_array().unwrap();
        let names: Vec<&str> = configs
            .iter()
            .map(|c| c["config"].as_str().unwrap())
            .collect();
        assert_eq!(names, timed);
        for c in configs {
            // Two runs each, the fastest kept, the same trajectory (checked by the bench).
            assert_eq!(c["runs_s"].as_array().unwrap().len(), 2);
            let fps = c["fps"].as_f64().unwrap();
            let fastest = c["runs_s"]
                .as_array()
                .unwrap()
                .iter()
                .map(|s| s.as_f64().unwrap())
                .fold(f64::INFINITY, f64::min);
            assert!((fps - 30.0 / fastest).abs() < 1e-6 * fps);
            assert_eq!(c["hash"].as_str().unwrap().len(), 16);
            // The clean preset is tracked to well under a centimetre by every configuration.
            assert!(c["ate_m"].as_f64().unwrap() < 0.01, "{c}");
        }
        assert_eq!(report["sweep_runs"], 4);
        let sweep = report["sweep_fps"].as_f64().unwrap();
        assert!(sweep > 0.0 && sweep.is_finite());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_direct_variant_is_the_configuration_with_avc_aimed_directly() {
        let c = BenchConfig::parse(" mcor+avc:direct").unwrap();
        assert_eq!(c.kind, ConfigKind::McorAvc);
        assert!(c.direct_aim);
        assert_eq!(c.name(), "mcor+avc:direct");
        let c = BenchConfig::parse("avc").unwrap();
        assert!(!c.direct_aim);
        assert_eq!(c.name(), "avc");
    }

    #[test]
    fn a_stride_variant_is_the_configuration_with_mcor_views_every_kth_frame() {
        let c = BenchConfig::parse("mcor+avc:stride2:direct").unwrap();
        assert_eq!(c.kind, ConfigKind::McorAvc);
        assert!(c.direct_aim);
        assert_eq!(c.view_stride, Some(2));
        assert_eq!(c.name(), "mcor+avc:direct:stride2");
        assert_eq!(
            BenchConfig::parse("mcor:stride3").unwrap().name(),
            "mcor:stride3"
        );
        for (bad, says) in [
            (
                "avc:stride2",
                "approximation of MC-OR's every-frame clusters, and avc has none",
            ),
            ("mcor-keyframes:stride2", "and mcor-keyframes has none"),
            ("mcor:stride0", "needs a whole number of frames >= 1"),
            ("mcor:stride", "needs a whole number of frames >= 1"),
            ("mcor:stride2:stride2", "`:stride` given twice"),
            ("avc:direct:direct", "`:direct` given twice"),
        ] {
            let e = BenchConfig::parse(bad).unwrap_err();
            assert!(format!("{e:#}").contains(says), "{bad}: {e:#}");
        }
    }

    #[test]
    fn bad_arguments_are_refused_before_anything_runs() {
        let e = run(args(&["orb", "mcorr"], 40)).unwrap_err();
        assert!(
            format!("{e:#}").contains("unknown configuration \"mcorr\""),
            "{e:#}"
        );
        let e = run(args(&["orb", "orb:direct"], 40)).unwrap_err();
        assert!(
            format!("{e:#}").contains("\"orb:direct\": `:direct` is an approximation of AVC"),
            "{e:#}"
        );
        let e = run(args(&["avc:fast"], 40)).unwrap_err();
        assert!(
            format!("{e:#}").contains("unknown variant \"fast\""),
            "{e:#}"
        );
        let e = run(args(&["orb"], 0)).unwrap_err();
        assert!(format!("{e:#}").contains("--frames"), "{e:#}");
        let dir = std::env::temp_dir().join(format!("nf-bench-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let toml = dir.join("bad.toml");
        std::fs::write(&toml, "[orb]\nscale_factor = 0.5\n").unwrap();
        let mut a = args(&["orb"], 10);
        a.config = Some(toml);
        let e = run(a).unwrap_err();
        assert!(format!("{e:#}").contains("scale_factor"), "{e:#}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
