//! The figures of `noisefree bench`: what tracking and mapping cost per frame for each
//! configuration on one sequence, on one core, and what a sweep of the paper's four
//! configurations runs at, reading and feature extraction included (the command's own page,
//! `commands/bench.rs`, says how the figures are made fair).
//!
//! Phases: [`Bench::prepare`] reads and extracts the sequence once; [`Bench::track`] is one
//! timed run of a [`BenchConfig`]; [`Bench::measure`] runs the configurations in rounds and
//! keeps each one's fastest run; [`figures_header`] and [`figures_rows`] print them; [`Bench::sweep`] times the
//! sweep figure; [`Report`] is the JSON of it all.

use crate::readings::ReadingColumn;
use crate::regress::cases::trajectory_hash;
use crate::runner::{run_extracted, ExtractedSequence, RunOutcome};
use crate::sweep::job::job_config;
use crate::sweep::plan::{ConfigKind, Job, Params, RunConfig};
use anyhow::{bail, Context, Result};
use datasets::{FrameReader, Sequence};
use serde::Serialize;
use slam_core::place::Vocabulary;
use slam_core::system::{Config, FrameStats};
use slam_core::techniques::params::{AvcAim, ClusterViews};
use std::sync::Arc;
use std::time::Instant;

/// One configuration's figures.
#[derive(Debug, Serialize)]
pub struct ConfigFigures {
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

/// The whole report (`--json`).
#[derive(Debug, Serialize)]
pub struct Report {
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

/// The mean of one per-frame figure over a run's frames.
fn mean(stats: &[FrameStats], f: fn(&FrameStats) -> f64) -> f64 {
    stats.iter().map(f).sum::<f64>() / stats.len().max(1) as f64
}

/// One entry of `--configs`: a configuration, and the documented approximations it runs with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BenchConfig {
    kind: ConfigKind,
    /// `:direct`: AVC under `[avc] aim = "direct"`.
    direct_aim: bool,
    /// `:strideK`: MC-OR's every-frame clusters under `[mcor] view_stride = K`.
    view_stride: Option<u32>,
    /// Readings of the paper (`:sightings=all`, `:paper`, ...; `crate::readings`).
    reading: Option<ReadingColumn>,
}

impl BenchConfig {
    /// The configuration `kind` as the paper's columns run it (no approximation).
    pub fn exact(kind: ConfigKind) -> BenchConfig {
        BenchConfig {
            kind,
            direct_aim: false,
            view_stride: None,
            reading: None,
        }
    }

    /// Parses `NAME`, then any of the variants `:direct` (a configuration with AVC) and
    /// `:strideK` (a configuration with MC-OR's every-frame clusters, K >= 1), each once, and
    /// readings of the paper as a sweep's columns name them (`:sightings=all`, `:paper`).
    pub fn parse(s: &str) -> Result<BenchConfig> {
        let mut parts = s.trim().split(':');
        let base = parts.next().unwrap_or_default();
        let kind = ConfigKind::parse(base)?;
        let mut c = BenchConfig::exact(kind);
        let mut readings = Vec::new();
        for variant in parts {
            if variant == "paper" || variant.contains('=') {
                readings.push(variant);
                continue;
            }
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
                bail!(
                    "\"{s}\": unknown variant \"{variant}\" (known: direct, strideK, and \
                     readings key=value or paper)"
                );
            }
        }
        if !readings.is_empty() {
            let spelled = format!("{base}:{}", readings.join(":"));
            c.reading = ReadingColumn::parse(&spelled).with_context(|| format!("\"{s}\""))?;
        }
        Ok(c)
    }

    /// The column's name: the configuration's, then its variants (`:direct`, `:strideK`).
    pub fn name(self) -> String {
        let mut name = match self.reading {
            Some(r) => r.name(),
            None => self.kind.name().to_string(),
        };
        if self.direct_aim {
            name.push_str(":direct");
        }
        if let Some(k) = self.view_stride {
            name.push_str(&format!(":stride{k}"));
        }
        name
    }
}

/// `--configs` parsed: every entry, at least one.
pub fn parse_configs(list: &[String]) -> Result<Vec<BenchConfig>> {
    let kinds = list
        .iter()
        .map(|c| BenchConfig::parse(c))
        .collect::<Result<Vec<_>>>()
        .context("--configs")?;
    if kinds.is_empty() {
        bail!("--configs: no configuration given");
    }
    Ok(kinds)
}

/// A sequence read and its features extracted once, on one core, with what that cost: what
/// every timed run starts from.
pub struct Bench {
    label: String,
    seq: Sequence,
    extracted: ExtractedSequence,
    base: Config,
    vocabulary: Option<Arc<Vocabulary>>,
    reading_s: f64,
    extraction_s: f64,
}

/// One configuration's runs so far: their times, the trajectory's hash (every repeat must
/// give it) and the fastest run.
struct Measured {
    runs_s: Vec<f64>,
    hash: String,
    fastest: (f64, RunOutcome),
}

impl Bench {
    /// Reads (decodes or renders) the frames of `reader` and extracts their features with
    /// `base`'s ORB, frame by frame on one core, as a sweep does it once per sequence; the
    /// extractor times itself, the rest is reading.
    pub fn prepare(
        label: String,
        seq: Sequence,
        reader: &FrameReader,
        base: Config,
        vocabulary: Option<Arc<Vocabulary>>,
    ) -> Result<Bench> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .context("starting the worker pool")?;
        let t = Instant::now();
        let extracted = pool
            .install(|| {
                ExtractedSequence::extract_all(
                    reader,
                    &seq.camera,
                    std::slice::from_ref(&base.orb),
                    || {},
                )
            })
            .with_context(|| format!("reading {label}"))?
            .remove(0);
        let extraction_s = extracted.extraction_s();
        let reading_s = (t.elapsed().as_secs_f64() - extraction_s).max(0.0);
        Ok(Bench {
            label,
            seq,
            extracted,
            base,
            vocabulary,
            reading_s,
            extraction_s,
        })
    }

    /// Frames of the sequence.
    pub fn frames(&self) -> usize {
        self.extracted.frames.len()
    }

    /// One timed run of `bench` with SLAM seed `seed` (tracking + mapping + loop closing):
    /// its wall time in seconds and its outcome.
    pub fn track(&self, bench: BenchConfig, seed: u64) -> (f64, RunOutcome) {
        let config = run_config(&self.base, &self.label, bench, seed);
        let t = Instant::now();
        let o = run_extracted(
            &self.seq,
            &self.extracted,
            &config,
            self.vocabulary.as_ref(),
            |_| {},
        );
        (t.elapsed().as_secs_f64(), o)
    }

    /// `--profile`: one run of `bench`, its speed and trajectory hash in a line.
    pub fn profile_line(&self, bench: BenchConfig) -> String {
        let n = self.frames();
        let (s, o) = self.track(bench, 0);
        format!(
            "{}: {n} frames tracked in {s:.3} s ({:.1} frames/s), trajectory {}",
            format_args!("{} [{}]", self.label, bench.name()),
            n as f64 / s,
            trajectory_hash(&o.trajectory)
        )
    }

    /// The first line of the report: frames, reading and extraction per frame.
    pub fn reading_line(&self) -> String {
        let n = self.frames();
        format!(
            "{}: {n} frames; reading {:.2} ms/frame, ORB extraction {:.2} ms/frame (one core, once)",
            self.label,
            self.reading_s * 1e3 / n as f64,
            self.extraction_s * 1e3 / n as f64
        )
    }

    /// Runs every configuration `repeat` times in rounds (every configuration's repeat r in
    /// round r, so that a machine slowing down for a while slows them alike), checks each
    /// repeat gives the same trajectory, and keeps each configuration's fastest run.
    pub fn measure(&self, kinds: &[BenchConfig], repeat: usize) -> Result<Vec<ConfigFigures>> {
        let mut measured: Vec<Option<Measured>> = kinds.iter().map(|_| None).collect();
        for _ in 0..repeat {
            for (&kind, m) in kinds.iter().zip(&mut measured) {
                let (s, o) = self.track(kind, 0);
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
        let n = self.frames();
        Ok(kinds
            .iter()
            .zip(measured)
            .map(|(&kind, m)| {
                let m = m.expect("at least one run");
                let (s, o) = m.fastest;
                ConfigFigures {
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
                }
            })
            .collect())
    }

    /// The sweep figure: the paper's four configurations x seeds `0..seeds` on one core, and
    /// its line (none for 0 seeds); then the report of everything as JSON.
    pub fn sweep(&self, seeds: u64, figures: Vec<ConfigFigures>) -> (Option<String>, Report) {
        let mut sweep_tracking_s = 0.0;
        let mut sweep_runs = 0;
        for seed in 0..seeds {
            for kind in ConfigKind::ALL {
                sweep_tracking_s += self.track(BenchConfig::exact(kind), seed).0;
                sweep_runs += 1;
            }
        }
        let n = self.frames();
        let once = self.reading_s + self.extraction_s;
        let sweep_fps =
            (sweep_runs > 0).then(|| (sweep_runs * n) as f64 / (once + sweep_tracking_s));
        let line = sweep_fps.map(|fps| {
            format!(
                "sweep (orb, mcor, avc, mcor+avc x seeds 0..{seeds}, one core): {sweep_runs} runs, {} frames \
                 in {:.1} s = {fps:.1} frames/s (reading {:.1} s and extraction {:.1} s once, \
                 tracking {:.1} s)",
                sweep_runs * n,
                once + sweep_tracking_s,
                self.reading_s,
                self.extraction_s,
                sweep_tracking_s
            )
        });
        let report = Report {
            sequence: self.label.clone(),
            frames: n,
            reading_s: self.reading_s,
            extraction_s: self.extraction_s,
            configs: figures,
            sweep_runs,
            sweep_tracking_s,
            sweep_fps,
        };
        (line, report)
    }
}

/// The width of the configuration column: the longest name, at least 16 (variants make
/// names long).
pub fn column_width(kinds: &[BenchConfig]) -> usize {
    kinds
        .iter()
        .map(|k| k.name().len())
        .max()
        .unwrap_or(0)
        .max(16)
}

/// The heading line of the figures' table, printed before the runs start.
pub fn figures_header(w: usize) -> String {
    format!(
        "{:<w$} {:>9} {:>9} {:>8} {:>9} {:>8} {:>8} {:>8}  {:<16} {:>4} {:>6} {:>9}\n",
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
    )
}

/// A row per configuration under [`figures_header`]: frames/s, its share of orb's, ms/frame
/// and its split, trajectory hash, keyframes, map points, ATE in mm.
pub fn figures_rows(figures: &[ConfigFigures], w: usize) -> String {
    let mut s = String::new();
    let orb_fps = figures.iter().find(|c| c.config == "orb").map(|c| c.fps);
    for f in figures {
        s.push_str(&format!(
            "{:<w$} {:>9.1} {:>9} {:>8.3} {:>9.3} {:>8.3} {:>8.3} {:>8.3}  {:<16} {:>4} {:>6} {:>9}\n",
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
        ));
    }
    s
}

/// The configuration a bench column runs with seed `seed` on sequence `label`: the sweep's
/// (`job_config` over `base`, readings included), then the column's approximations.
fn run_config(base: &Config, label: &str, bench: BenchConfig, seed: u64) -> Config {
    let job = Job {
        sequence: label.to_string(),
        config: match bench.reading {
            Some(r) => r.run_config(),
            None => RunConfig::Ours(bench.kind),
        },
        params: Params::default(),
        seed,
        synth_seed: None,
        perturbation: None,
    };
    let mut config = job_config(base, &job);
    if bench.direct_aim {
        if let Some(avc) = config.avc.as_mut() {
            avc.aim = AvcAim::Direct;
        }
    }
    if let (Some(k), Some(mcor)) = (bench.view_stride, config.mcor.as_mut()) {
        mcor.view_stride = k;
    }
    config
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reading_column_benches_the_configuration_under_its_readings() {
        let c = BenchConfig::parse("mcor:stride2:verdict=consensus:sightings=all").unwrap();
        assert_eq!(c.name(), "mcor:sightings=all:verdict=consensus:stride2");
        let run = run_config(&Config::default(), "kinect", c, 3);
        let m = run.mcor.unwrap();
        assert_eq!(m.verdict, slam_core::system::Verdict::Consensus);
        assert_eq!(m.sightings, slam_core::system::Sightings::All);
        assert_eq!(m.view_stride, 2);
        assert_eq!(run.seed, 3);
        let plain = run_config(
            &Config::default(),
            "kinect",
            BenchConfig::parse("mcor").unwrap(),
            3,
        );
        assert_eq!(
            plain.mcor.unwrap().verdict,
            slam_core::system::Verdict::Filter
        );
        let e = format!(
            "{:#}",
            BenchConfig::parse("avc:scope=tracking+mapping").unwrap_err()
        );
        assert!(e.contains("MC-OR"), "{e}");
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
}
