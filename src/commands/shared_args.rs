//! Argument groups several commands share (`#[command(flatten)]`): each flag is declared once,
//! with one help text, so `run`, `sweep`, `perturb` and `match` cannot drift apart on what
//! `--frames` or `--mapping-lag` means.

use crate::select::LoadOptions;
use std::path::PathBuf;

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
