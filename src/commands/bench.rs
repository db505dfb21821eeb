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

use super::shared_args::{Resolved, SourceArgs};
use crate::bench::{column_width, figures_header, figures_rows, parse_configs, Bench};
use crate::commands::shared_args::SystemArgs;
use crate::config_file::Switches;
use crate::select::{open, LoadOptions};
use anyhow::{bail, Result};
use atomic_file::write as write_atomic;
use std::path::PathBuf;

/// Arguments of `noisefree bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// The sequence: --seq NAME or --path DIR.
    #[command(flatten)]
    pub source: SourceArgs,
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
    /// The system's settings file, vocabulary, mapping lag and loop closing, as `run` takes
    /// them.
    #[command(flatten)]
    pub system: SystemArgs,
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

/// Runs `noisefree bench`: checks the flags, reads and extracts the sequence once, then
/// `--profile`'s one run, or the configurations in rounds, their table, the sweep figure and
/// `--json`.
pub fn run(args: BenchArgs) -> Result<()> {
    if args.frames == 0 || args.repeat == 0 {
        bail!("--frames and --repeat must be at least 1");
    }
    let kinds = parse_configs(&args.configs)?;
    let catalog = datasets::Catalog::embedded();
    let source = args.source.source();
    let opts = LoadOptions {
        data_dir: datasets::data_root(args.data_dir.as_deref()),
        frames: Some(args.frames),
        synth_seed: args.synth_seed,
        synth_without: Vec::new(),
        camera: None,
        frame_cache: None,
    };
    let (seq, reader) = open(&source, &catalog, &opts)?;
    let Resolved {
        config: base,
        vocabulary,
    } = args
        .system
        .resolve(seq.camera.sensor, Switches::default())?;
    let bench = Bench::prepare(source.label(), seq, &reader, base, vocabulary.vocabulary)?;
    if args.profile {
        println!("{}", bench.profile_line(kinds[0]));
        return Ok(());
    }
    println!("{}", bench.reading_line());
    let w = column_width(&kinds);
    print!("{}", figures_header(w));
    let figures = bench.measure(&kinds, args.repeat)?;
    print!("{}", figures_rows(&figures, w));
    let (line, report) = bench.sweep(args.sweep_seeds, figures);
    if let Some(line) = line {
        println!("{line}");
    }
    if let Some(path) = &args.json {
        write_atomic(path, serde_json::to_string_pretty(&report)?.as_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(configs: &[&str], frames: usize) -> BenchArgs {
        BenchArgs {
            source: SourceArgs {
                seq: Some("clean".into()),
                path: None,
            },
            frames,
            configs: configs.iter().map(|c| c.to_string()).collect(),
            repeat: 2,
            sweep_seeds: 1,
            system: SystemArgs {
                vocabulary: Some("none".into()),
                ..SystemArgs::default()
            },
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
        a.system.config = Some(toml);
        let e = run(a).unwrap_err();
        assert!(format!("{e:#}").contains("scale_factor"), "{e:#}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
