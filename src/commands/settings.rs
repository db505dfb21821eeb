//! `noisefree settings`: a sequence's camera written as the settings file another SLAM system
//! reads (ORB-SLAM2's or ORB-SLAM3's YAML), so it runs on the same files with the same camera.

use super::shared_args::SourceArgs;
use crate::select::{open, LoadOptions};
use anyhow::{Context, Result};
use datasets::settings::{write_settings, CameraSettings, SettingsFormat};
use std::path::PathBuf;

/// Arguments of `noisefree settings`.
#[derive(clap::Args, Debug)]
pub struct SettingsArgs {
    /// The sequence: --seq NAME or --path DIR.
    #[command(flatten)]
    pub source: SourceArgs,
    /// Layout of the file: orbslam2 (ORB-SLAM2's TUM1.yaml / EuRoC.yaml) or orbslam3
    /// (`File.version: "1.0"`).
    #[arg(long, default_value = "orbslam2", value_parser = parse_format)]
    pub format: SettingsFormat,
    /// Output file [default: standard output].
    #[arg(short, long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Data root for catalogued real sequences [default: $NOISEFREE_DATA, else ./data].
    #[arg(long = "data-dir", value_name = "DIR")]
    pub data_dir: Option<PathBuf>,
    /// Synthetic sequences: the seed of the scene (the camera does not depend on it).
    #[arg(long = "synth-seed", default_value_t = 0, value_name = "S")]
    pub synth_seed: u64,
}

/// Parses `--format`.
pub fn parse_format(s: &str) -> std::result::Result<SettingsFormat, String> {
    SettingsFormat::parse(s)
        .ok_or_else(|| format!("unknown settings format {s:?}; expected orbslam2 or orbslam3"))
}

/// Runs `noisefree settings`.
pub fn run(args: SettingsArgs) -> Result<()> {
    let source = args.source.source();
    let opts = LoadOptions {
        data_dir: datasets::data_root(args.data_dir.as_deref()),
        frames: Some(1),
        synth_seed: args.synth_seed,
        synth_without: Vec::new(),
        camera: None,
        frame_cache: None,
    };
    let (seq, _) = open(&source, &datasets::Catalog::embedded(), &opts)?;
    let settings = CameraSettings::of_sequence(&seq);
    let text = write_settings(&settings, args.format, &source.label());
    match &args.out {
        None => print!("{text}"),
        Some(p) => {
            atomic_file::write(p, text.as_bytes())
                .with_context(|| format!("writing {}", p.display()))?;
            eprintln!(
                "wrote the {} settings of {} to {}",
                args.format.name(),
                source.label(),
                p.display()
            );
        }
    }
    Ok(())
}
