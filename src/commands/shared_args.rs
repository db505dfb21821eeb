//! Argument groups several commands share (`#[command(flatten)]`): each flag is declared once,
//! with one help text, so `run`, `sweep`, `perturb` and `match` cannot drift apart on what
//! `--frames` or `--mapping-lag` means.

use crate::config_file::system_config;
use crate::config_file::{vocabulary_asked, Switches};
use crate::select::{LoadOptions, Source};
use crate::vocab_file::VocabularyChoice;
use anyhow::Result;
use slam_core::system::Config;
use slam_core::SensorKind;
use std::path::PathBuf;

/// Which sequence a command reads: a catalogued name or any folder (`run`, `bench`, `match`,
/// `perturb`, `settings`; `sweep` takes lists of both).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SourceArgs {
    /// Catalogued sequence (datasets.toml): a TUM / EuRoC name such as `fr2_coke` or `mh04`, a
    /// twin of a paper row (`twin_fr1_desk`) or a synthetic preset (`clean`, `kinect`,
    /// `boundary`, `walking`, `stereo`, ...). Without --seq and --path: the embedded synthetic
    /// default (`kinect`).
    #[arg(long, value_name = "NAME", conflicts_with = "path")]
    pub seq: Option<String>,
    /// Any TUM RGB-D or EuRoC ASL folder.
    #[arg(long, value_name = "DIR")]
    pub path: Option<PathBuf>,
}

impl SourceArgs {
    /// The sequence these flags name.
    pub fn source(&self) -> Source {
        Source::from_flags(self.seq.as_deref(), self.path.as_deref())
    }
}

/// How a sequence is realised before anything reads it: its length, and for a synthetic one
/// its seed and the effects switched off; where catalogued real sequences live.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SequenceArgs {
    /// Synthetic sequences: number of frames [default: the preset's: 300, 1650 for `loop`, a
    /// twin's whole sequence]; real ones: only the first N frames.
    #[arg(long, value_name = "N")]
    pub frames: Option<usize>,
    /// Seed of a synthetic sequence's scene, textures and noise (independent of the SLAM run's
    /// --seed).
    #[arg(long = "synth-seed", default_value_t = 0, value_name = "S")]
    pub synth_seed: u64,
    /// Synthetic sequences: effects to switch off, comma-separated (an ablation): lens, blur,
    /// rolling_shutter, vignetting, auto_exposure, sensor_noise, image_noise, tremor, depth_lag,
    /// axial, quantisation, lateral, holes, misregistration, depth_distortion, mocap_noise,
    /// layout, stamp_jitter, mocap_clock.
    #[arg(long = "synth-without", value_name = "EFFECTS", value_delimiter = ',')]
    pub synth_without: Vec<String>,
    /// Data root for catalogued real sequences [default: $NOISEFREE_DATA, else ./data].
    #[arg(long = "data-dir", value_name = "DIR")]
    pub data_dir: Option<PathBuf>,
}

impl SequenceArgs {
    /// The loader's options these flags give, with a folder's `camera` settings file if any.
    pub fn load_options(&self, camera: Option<PathBuf>) -> LoadOptions {
        LoadOptions {
            data_dir: datasets::data_root(self.data_dir.as_deref()),
            frames: self.frames,
            synth_seed: self.synth_seed,
            synth_without: self.synth_without.clone(),
            camera,
            frame_cache: None,
        }
    }
}

/// The SLAM system's options beyond the configuration switches: its settings file, its
/// vocabulary, the emulated mapping lag, and loop closing.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SystemArgs {
    /// TOML configuration overlaid on the sensor's defaults in every run (any subset of the
    /// fields); a sweep also reads the external systems it declares under [systems.NAME].
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
    /// Turn loop closing off in every run (an ablation: ORB-SLAM2, and so the baseline, closes
    /// loops; a sweep's folder records it). Loop closing needs a vocabulary: with --vocabulary
    /// none it is off anyway.
    #[arg(long = "no-loop-closing")]
    pub no_loop_closing: bool,
}

impl SystemArgs {
    /// The vocabulary asked for: `--vocabulary`, else the `--config` file's `vocabulary`;
    /// `None`: the built-in one.
    pub fn vocabulary_flag(&self) -> Result<Option<PathBuf>> {
        vocabulary_asked(self.vocabulary.as_deref(), self.config.as_deref())
    }

    /// The settings of a run, resolved once: the sensor's defaults, `--config` over them, the
    /// command's `switches` with these flags' (mapping lag, loop closing) on top, checked; and
    /// the vocabulary loaded. What `run`, `bench` and `match` hand the system.
    pub fn resolve(&self, sensor: SensorKind, switches: Switches) -> Result<Resolved> {
        let switches = Switches {
            mapping_lag: self.mapping_lag,
            no_loop_closing: self.no_loop_closing,
            ..switches
        };
        let config = system_config(sensor, self.config.as_deref(), switches)?;
        let vocabulary = crate::vocab_file::choose(self.vocabulary_flag()?.as_deref())?;
        Ok(Resolved { config, vocabulary })
    }
}

/// A run's settings as [`SystemArgs::resolve`] gives them.
pub struct Resolved {
    /// The SLAM configuration.
    pub config: Config,
    /// The place-recognition vocabulary and how it is named in a run's records.
    pub vocabulary: VocabularyChoice,
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    /// A command line of one flattened group.
    #[derive(Parser)]
    struct Line {
        #[command(flatten)]
        system: SystemArgs,
    }

    #[test]
    fn system_flags_set_the_lag_and_loop_closing_over_the_commands_switches_and_nothing_else() {
        let l = Line::try_parse_from(["x", "--mapping-lag", "3", "--no-loop-closing"]).unwrap();
        let with_mcor = Switches {
            mcor: true,
            ..Switches::default()
        };
        let r = l.system.resolve(SensorKind::Rgbd, with_mcor).unwrap();
        assert_eq!(r.config.mapping_lag, 3);
        assert!(!r.config.loop_closing.enabled);
        assert!(r.config.mcor.is_some() && r.config.avc.is_none() && r.config.rc.is_none());
        let none = Line::try_parse_from(["x"]).unwrap().system;
        let r = none
            .resolve(SensorKind::Stereo, Switches::default())
            .unwrap();
        assert_eq!(r.config, Config::stereo());
        assert!(r.vocabulary.identity.starts_with("built-in"));
    }

    #[test]
    fn the_vocabulary_flag_beats_the_config_file_which_beats_the_default() {
        let dir = std::env::temp_dir().join(format!("nf-shared-args-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let toml = dir.join("c.toml");
        std::fs::write(&toml, "vocabulary = \"words.voc\"\n").unwrap();
        let config = toml.to_str().unwrap();
        let flag = Line::try_parse_from(["x", "--config", config, "--vocabulary", "none"]).unwrap();
        assert_eq!(flag.system.vocabulary_flag().unwrap(), Some("none".into()));
        let file = Line::try_parse_from(["x", "--config", config]).unwrap();
        assert_eq!(
            file.system.vocabulary_flag().unwrap(),
            Some(dir.join("words.voc"))
        );
        let neither = Line::try_parse_from(["x"]).unwrap();
        assert_eq!(neither.system.vocabulary_flag().unwrap(), None);
        std::fs::remove_dir_all(&dir).ok();
    }
}
