//! Turning the command line's sequence choice (`--seq NAME`, `--path DIR`, or nothing: the
//! embedded synthetic default) into a decoded [`Sequence`].

use anyhow::{bail, Context, Result};
use datasets::{Catalog, FrameReader, Sequence};
use std::path::{Path, PathBuf};

/// Synthetic preset of the embedded default (`noisefree run` with no sequence): RGB-D with the
/// Kinect-like depth noise model.
pub const DEFAULT_PRESET: &str = "kinect";

/// Where a sequence comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// A catalogued name (datasets.toml): a downloaded sequence or a synthetic preset.
    Catalog(String),
    /// Any TUM RGB-D or EuRoC folder.
    Path(PathBuf),
}

impl Source {
    /// The source the flags name, or the embedded synthetic default.
    pub fn from_flags(seq: Option<&str>, path: Option<&Path>) -> Source {
        match (seq, path) {
            (_, Some(p)) => Source::Path(p.to_path_buf()),
            (Some(s), None) => Source::Catalog(s.to_string()),
            (None, None) => Source::Catalog(DEFAULT_PRESET.to_string()),
        }
    }

    /// A short label for tables and file names.
    pub fn label(&self) -> String {
        match self {
            Source::Catalog(n) => n.clone(),
            Source::Path(p) => p
                .file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| p.display().to_string()),
        }
    }
}

/// Options of loading that do not name the sequence.
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// Data root for catalogued real sequences.
    pub data_dir: PathBuf,
    /// Synthetic sequences: frames to generate (default: the preset's, see
    /// `synth::Preset::default_frames`); real ones: keep only the first N frames.
    pub frames: Option<usize>,
    /// Seed of a synthetic sequence's noise and scene (the sequence, not the SLAM run).
    pub synth_seed: u64,
    /// Effects switched off in a synthetic sequence (`synth::EFFECTS` names).
    pub synth_without: Vec<String>,
    /// A folder's camera from an ORB-SLAM2 / ORB-SLAM3 settings file instead of its name or
    /// `sensor.yaml` files (`run --camera`).
    pub camera: Option<PathBuf>,
    /// The frame cache a synthetic sequence reads and fills ([`synth::CachedFrames`]); `None`:
    /// the folder `NOISEFREE_SYNTH_CACHE` names, if any. Tests name theirs, so that they share
    /// renders without touching the process's environment.
    pub frame_cache: Option<PathBuf>,
}

#[cfg(test)]
impl LoadOptions {
    /// The first `frames` frames of a preset at the command line's default seed, through the
    /// frame cache the workspace's test processes share (`target/tmp/synth-frames`; cargo
    /// names that folder to integration tests only): what the unit tests that run presets load.
    pub fn for_tests(frames: usize) -> Self {
        LoadOptions {
            data_dir: PathBuf::new(),
            frames: Some(frames),
            synth_seed: 0,
            synth_without: Vec::new(),
            camera: None,
            frame_cache: Some(
                concat!(env!("CARGO_MANIFEST_DIR"), "/target/tmp/synth-frames").into(),
            ),
        }
    }
}

/// Loads (or generates) the sequence of `source`, every frame decoded (the runner's tests).
#[cfg(test)]
pub fn load(source: &Source, catalog: &Catalog, opts: &LoadOptions) -> Result<Sequence> {
    let (mut seq, frames) = open(source, catalog, opts)?;
    seq.frames = frames
        .without_colour()
        .read_all()
        .with_context(|| format!("loading {}", source.label()))?;
    Ok(seq)
}

/// Tells the user, on one line, which camera folder `dir` is read with and where it came from
/// (a warning when nothing stands behind it): a camera is never assumed silently.
fn say_camera(dir: &Path, settings: Option<&Path>) {
    let origin = datasets::CameraOrigin::of(dir, settings);
    eprintln!("{}", origin.describe(dir));
}

/// Opens the sequence of `source`: camera, ground truth and frame list now, the frames when the
/// reader reads (or renders) them; `seq.frames` stays empty. With `--frames N` the reader
/// holds the first N frames.
pub fn open(
    source: &Source,
    catalog: &Catalog,
    opts: &LoadOptions,
) -> Result<(Sequence, FrameReader)> {
    let (seq, mut frames) = match source {
        Source::Path(p) => {
            let opened = match &opts.camera {
                None => datasets::open_path(p),
                Some(c) => datasets::open_path_with_settings(p, c),
            }
            .with_context(|| format!("loading {}", p.display()))?;
            say_camera(p, opts.camera.as_deref());
            opened
        }
        Source::Catalog(name) => {
            let entry = catalog.get(name)?;
            if let Some(preset) = &entry.preset {
                if let Some(c) = &opts.camera {
                    bail!(
                        "--camera {}: {name} is synthetic and has its own camera; --camera is for \
                         folders (--path, or a downloaded real sequence)",
                        c.display()
                    );
                }
                let preset = synth::Preset::from_name(preset)?;
                let mut config = preset.config();
                for effect in &opts.synth_without {
                    config.without(effect.trim())?;
                }
                let generator = synth::Generator::try_new(config, opts.synth_seed)?;
                let n = opts.frames.unwrap_or_else(|| preset.default_frames());
                if n == 0 {
                    bail!("--frames must be at least 1");
                }
                let cache = match &opts.frame_cache {
                    Some(dir) => Some(dir.clone()),
                    None => synth::cache_dir_from_env().map_err(anyhow::Error::msg)?,
                };
                let (mut s, frames) = datasets::open_synth_cached(&generator, n, cache.as_deref());
                s.name = entry.name.clone();
                (s, frames)
            } else {
                let dir = entry
                    .path(&opts.data_dir)
                    .with_context(|| format!("catalog entry {name} has no folder"))?;
                if !dir.is_dir() {
                    bail!(
                        "sequence {name} is not in {} (expected folder {}); run `noisefree fetch {name}` \
                         or pass --data-dir / set NOISEFREE_DATA",
                        opts.data_dir.display(),
                        dir.display()
                    );
                }
                let (mut s, frames) = match &opts.camera {
                    None => datasets::open_path(&dir),
                    Some(c) => datasets::open_path_with_settings(&dir, c),
                }
                .with_context(|| format!("loading {}", dir.display()))?;
                say_camera(&dir, opts.camera.as_deref());
                s.name = entry.name.clone();
                (s, frames)
            }
        }
    };
    let real = match source {
        Source::Path(_) => true,
        Source::Catalog(name) => catalog
            .get(name)
            .map(|e| e.preset.is_none())
            .unwrap_or(false),
    };
    if let (Some(n), true) = (opts.frames, real) {
        frames.truncate(n);
    }
    if frames.is_empty() {
        bail!("sequence {} has no frames", source.label());
    }
    for note in &seq.notes {
        eprintln!("warning: {note}");
    }
    Ok((seq, frames))
}
