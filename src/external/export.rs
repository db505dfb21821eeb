//! What an external program is given: the sequence as a folder on disk (a real folder as it is;
//! a synthetic sequence or twin written once into the cache in the layout its sensor implies,
//! TUM or EuRoC ASL), the run's frames as an associations file (TUM) or a times file (EuRoC),
//! the camera settings file in the system's layout, and a vocabulary.

use crate::file_name::safe;
use crate::select::{LoadOptions, Source};
use anyhow::{bail, Context, Result};
use datasets::settings::{write_settings, CameraSettings, SettingsFormat};
use datasets::{Catalog, Format, Sequence};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A sequence on disk, with the files that name the run's frames.
#[derive(Clone, Debug)]
pub struct OnDisk {
    /// The folder (TUM: of rgb.txt; EuRoC: of mav0).
    pub folder: PathBuf,
    /// Folder of this sequence's own auxiliary files (associations, times, settings).
    pub aux: PathBuf,
    /// TUM: `t_rgb rgb/... t_depth depth/...` of the run's frames.
    pub associations: Option<PathBuf>,
    /// EuRoC: the run's cam0 stamps in nanoseconds, one a line.
    pub times_ns: Option<PathBuf>,
    /// EuRoC: the same in seconds.
    pub times_s: Option<PathBuf>,
    /// EuRoC: mav0/cam0/data.
    pub cam0: Option<PathBuf>,
    /// EuRoC: mav0/cam1/data.
    pub cam1: Option<PathBuf>,
    /// Frames of the run.
    pub frames: usize,
    /// The sequence's camera settings.
    pub settings: CameraSettings,
    /// A title for the settings files.
    pub label: String,
}

impl OnDisk {
    /// The settings file in `format` (written by [`prepare`], before the runs start).
    pub fn settings_file(&self, format: SettingsFormat) -> PathBuf {
        self.aux.join(format!("settings-{}.yaml", format.name()))
    }

    /// Writes the settings file in every layout (once, before parallel runs read them).
    fn write_settings_files(&self) -> Result<()> {
        for format in [SettingsFormat::Orbslam2, SettingsFormat::Orbslam3] {
            let text = write_settings(&self.settings, format, &self.label);
            atomic_file::write(&self.settings_file(format), text.as_bytes())?;
        }
        Ok(())
    }
}

/// Creates the cache folder, with a `.gitignore` that keeps it out of a repository when it sits
/// inside a committed results folder.
pub fn cache_root(dir: &Path) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let ignore = dir.join(".gitignore");
    if !ignore.exists() {
        atomic_file::write(
            &ignore,
            b"# noisefree's cache of sequences written for external systems\n*\n",
        )?;
    }
    Ok(dir.to_path_buf())
}

/// The folder a real sequence is read from (`None` for a synthetic one).
pub fn source_folder(
    source: &Source,
    catalog: &Catalog,
    opts: &LoadOptions,
) -> Result<Option<PathBuf>> {
    Ok(match source {
        Source::Path(p) => Some(p.clone()),
        Source::Catalog(name) => {
            let entry = catalog.get(name)?;
            match &entry.preset {
                Some(_) => None,
                None => entry.path(&opts.data_dir),
            }
        }
    })
}

/// Puts the sequence of `source` on disk for external programs and writes the files naming
/// its first `frames` frames. `seq` is the sequence as noisefree opened it (its camera is the
/// settings file's); `opts` carries the synthetic realization (seed, effects off).
pub fn prepare(
    source: &Source,
    seq: &Sequence,
    frames: usize,
    catalog: &Catalog,
    opts: &LoadOptions,
    cache: &Path,
) -> Result<OnDisk> {
    let label = source.label();
    let (folder, key) = match source {
        Source::Path(p) => (p.clone(), format!("{}-{frames}f", safe(&label))),
        Source::Catalog(name) => {
            let entry = catalog.get(name)?;
            match &entry.preset {
                None => (
                    entry
                        .path(&opts.data_dir)
                        .with_context(|| format!("catalog entry {name} has no folder"))?,
                    format!("{}-{frames}f", safe(name)),
                ),
                Some(preset) => {
                    let mut without = opts.synth_without.clone();
                    without.sort();
                    without.dedup();
                    // The generator's frames, as in memory: a twin's free-running depth
                    // stream can pair fewer frames than were rendered (a frame drops out as
                    // on real fr1/fr2 data), so the run's frame count is not the rendered one.
                    let rendered = match opts.frames {
                        Some(n) => n,
                        None => synth::Preset::from_name(preset)?.default_frames(),
                    };
                    let mut key = format!("{}-seed{}-{rendered}f", safe(name), opts.synth_seed);
                    if !without.is_empty() {
                        key += &format!("-without-{}", safe(&without.join("-")));
                    }
                    let folder = cache.join("sequences").join(&key);
                    if !folder.is_dir() {
                        let written =
                            write_synthetic(preset, &without, opts.synth_seed, rendered, &folder);
                        // Another shard of the sweep may have put the same folder in place
                        // first (each writes to its own staging folder, then renames).
                        if !folder.is_dir() {
                            written.with_context(|| {
                                format!("writing {name} to {}", folder.display())
                            })?;
                        }
                    }
                    (folder, key)
                }
            }
        }
    };
    let aux = cache.join("aux").join(&key);
    std::fs::create_dir_all(&aux).with_context(|| format!("creating {}", aux.display()))?;
    let mut out = OnDisk {
        folder: folder.clone(),
        aux: aux.clone(),
        associations: None,
        times_ns: None,
        times_s: None,
        cam0: None,
        cam1: None,
        frames,
        settings: CameraSettings::of_sequence(seq),
        label: label.clone(),
    };
    match seq.format {
        Format::TumRgbd => {
            let pairs = datasets::tum::pairs(&folder, datasets::tum::MAX_DIFFERENCE)?;
            if pairs.len() < frames {
                bail!(
                    "{}: {} rgb/depth pairs, fewer than the run's {frames} frames",
                    folder.display(),
                    pairs.len()
                );
            }
            // No comment line: ORB-SLAM2's and ORB-SLAM3's rgbd_tum take every line for a frame.
            let mut text = String::new();
            for (a, b) in &pairs[..frames] {
                let _ = writeln!(text, "{} {} {} {}", a.stamp, a.file, b.stamp, b.file);
            }
            let path = aux.join("associations.txt");
            atomic_file::write(&path, text.as_bytes())?;
            out.associations = Some(path);
        }
        Format::EurocStereo => {
            let mav0 = if folder.join("mav0").is_dir() {
                folder.join("mav0")
            } else {
                folder.clone()
            };
            let rows0 = datasets::euroc::read_camera_csv(&mav0.join("cam0/data.csv"))?;
            let rows1 = datasets::euroc::read_camera_csv(&mav0.join("cam1/data.csv"))?;
            let right: std::collections::BTreeSet<i64> = rows1.iter().map(|r| r.stamp_ns).collect();
            let stamps: Vec<i64> = rows0
                .iter()
                .map(|r| r.stamp_ns)
                .filter(|s| right.contains(s))
                .take(frames)
                .collect();
            if stamps.len() < frames {
                bail!(
                    "{}: {} stereo pairs with the same stamp in cam0 and cam1, fewer than the \
                     run's {frames} frames",
                    mav0.display(),
                    stamps.len()
                );
            }
            let ns: String = stamps.iter().map(|s| format!("{s}\n")).collect();
            let s: String = stamps
                .iter()
                .map(|&s| format!("{}\n", datasets::euroc::ns_to_s(s)))
                .collect();
            let (p_ns, p_s) = (aux.join("times.txt"), aux.join("times_s.txt"));
            atomic_file::write(&p_ns, ns.as_bytes())?;
            atomic_file::write(&p_s, s.as_bytes())?;
            out.times_ns = Some(p_ns);
            out.times_s = Some(p_s);
            out.cam0 = Some(mav0.join("cam0/data"));
            out.cam1 = Some(mav0.join("cam1/data"));
            if folder == mav0 {
                out.folder = mav0.parent().map(Path::to_path_buf).unwrap_or(mav0);
            }
        }
    }
    out.write_settings_files()?;
    Ok(out)
}

/// Renders a synthetic preset into `folder` (TUM layout for RGB-D, EuRoC ASL for stereo).
fn write_synthetic(
    preset: &str,
    without: &[String],
    seed: u64,
    frames: usize,
    folder: &Path,
) -> Result<()> {
    let preset = synth::Preset::from_name(preset)?;
    let mut config = preset.config();
    for effect in without {
        config.without(effect)?;
    }
    let gen = synth::Generator::try_new(config, seed)?;
    eprintln!(
        "writing {} ({frames} frames, seed {seed}) for external systems to {}",
        preset.name(),
        folder.display()
    );
    datasets::write::write_synthetic(&gen, frames, folder, |_| {})?;
    Ok(())
}

/// noisefree's built-in vocabulary as DBoW2 text (what ORB-SLAM2 and ORB-SLAM3 load), written
/// once into the cache.
pub fn vocabulary_text(cache: &Path) -> Result<PathBuf> {
    let path = cache
        .join("vocabulary")
        .join(crate::vocab_file::DEFAULT_NAME.replace(".voc", ".txt"));
    if !path.is_file() {
        let voc = crate::vocab_file::default_vocabulary();
        crate::vocab_file::write(&path, &voc)?;
    }
    Ok(path)
}
