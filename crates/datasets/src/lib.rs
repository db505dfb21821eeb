//! datasets: turns a dataset folder into the frames slam-core consumes, names the paper's
//! sequences, and downloads them.
//!
//! - [`tum`]: TUM RGB-D reader (`rgb.txt` / `depth.txt` association, fr1/fr2/fr3 cameras);
//! - [`euroc`]: EuRoC ASL stereo reader, rectified with [`rectify`] (Bouguet's method);
//! - [`synthetic`]: in-memory sequences from the `synth` generator;
//! - [`catalog`]: `datasets.toml` (Table III's 31 sequences with the paper's numbers, and the
//!   synthetic presets), [`data_root`];
//! - [`fetch`]: download with resume, atomic unpack, verification;
//! - [`cameras`]: the TUM cameras and depth factors; [`decode`]: PNG decoding.
//! - [`write`]: the one writer of TUM RGB-D and EuRoC folders (synthetic sequences, perturbed
//!   and exported copies), with one staging-and-rename.
//! - [`settings`]: ORB-SLAM2 / ORB-SLAM3 camera settings files (YAML), written from a
//!   sequence's camera and read back ([`open_path_with_settings`]).
//!
//! Every sequence is decoded once into a [`Sequence`] whose images are `Arc`-shared, so the
//! runs of a sweep share one copy read-only (see [`sequence`] for the memory it takes).

pub mod cameras;
pub mod catalog;
pub mod decode;
pub mod error;
pub mod euroc;
pub mod fetch;
pub mod rectify;
pub mod sequence;
pub mod settings;
pub mod synthetic;
pub mod tum;
pub mod write;

pub use cameras::CameraId;
pub use catalog::{data_root, Ate, Catalog, Class, Entry, EntryFormat, PaperAte};
pub use error::DatasetError;
pub use euroc::{load_euroc, load_euroc_with, open_euroc_with, EurocOptions};
pub use sequence::{Format, FrameReader, Sequence};
pub use synthetic::{from_synth, from_synth_cached, open_synth, open_synth_cached};
pub use tum::{load_tum, load_tum_with, open_tum_with, TumOptions};

use std::path::Path;

/// Which layout a folder has, if any: EuRoC when it holds `mav0/` (or is `mav0`), TUM RGB-D
/// when it holds `rgb.txt` or `associations.txt`.
pub fn detect_format(dir: &Path) -> Option<Format> {
    if dir.join("mav0").is_dir() || (dir.join("cam0").is_dir() && dir.join("cam1").is_dir()) {
        Some(Format::EurocStereo)
    } else if dir.join("rgb.txt").is_file() || dir.join("associations.txt").is_file() {
        Some(Format::TumRgbd)
    } else {
        None
    }
}

/// The name of the camera file a folder noisefree writes carries with it (ORB-SLAM2's settings
/// layout): `synth` and `perturb` write it, and opening the folder reads it.
pub const FOLDER_SETTINGS: &str = "camera-orbslam2.yaml";

/// The camera file folder `dir` carries itself ([`FOLDER_SETTINGS`]), if it has one: a folder
/// that says its own camera is read with it, before any guess from its name or `sensor.yaml`.
pub fn folder_settings(dir: &Path) -> Option<std::path::PathBuf> {
    let p = dir.join(FOLDER_SETTINGS);
    p.is_file().then_some(p)
}

/// Opens any TUM RGB-D or EuRoC folder with the camera of an ORB-SLAM2 / ORB-SLAM3 settings
/// file (`noisefree run --camera`) instead of the one its name or `sensor.yaml` files imply:
/// intrinsics, distortion, `bf`, `ThDepth`, the depth factor (TUM) and the rectification
/// (EuRoC). The folder's layout decides the sensor.
pub fn open_path_with_settings(
    dir: &Path,
    settings: &Path,
) -> Result<(Sequence, FrameReader), DatasetError> {
    if !dir.is_dir() {
        return Err(DatasetError::Missing {
            path: dir.to_path_buf(),
            what: "a TUM RGB-D or EuRoC sequence folder".into(),
        });
    }
    match detect_format(dir) {
        Some(Format::EurocStereo) => {
            let s = settings::read_settings(settings, slam_core::SensorKind::Stereo)?;
            open_euroc_with(
                dir,
                &EurocOptions {
                    th_depth: Some(s.camera.th_depth),
                    settings: Some((settings.to_path_buf(), s)),
                    ..EurocOptions::default()
                },
            )
        }
        Some(Format::TumRgbd) => {
            let s = settings::read_settings(settings, slam_core::SensorKind::Rgbd)?;
            open_tum_with(
                dir,
                &TumOptions {
                    camera: Some(s.camera),
                    depth_factor: s.depth_factor,
                    ..TumOptions::default()
                },
            )
        }
        None => open_path(dir),
    }
}

/// Where the camera of a folder comes from when it is opened: what a command tells its user,
/// so that a camera is never assumed silently.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CameraOrigin {
    /// An ORB-SLAM2 / ORB-SLAM3 settings file given with the folder (`--camera`).
    Settings(std::path::PathBuf),
    /// The folder's own camera file ([`FOLDER_SETTINGS`]), written with it.
    FolderSettings(std::path::PathBuf),
    /// A TUM folder whose name says its freiburg camera.
    TumName(CameraId),
    /// A TUM folder whose name says no freiburg camera: freiburg3's is assumed.
    TumGuess,
    /// An EuRoC folder's `sensor.yaml` files.
    EurocSensorFiles,
}

impl CameraOrigin {
    /// The origin of the camera of folder `dir`, opened with the settings file `settings` if any.
    pub fn of(dir: &Path, settings: Option<&Path>) -> CameraOrigin {
        if let Some(s) = settings {
            return CameraOrigin::Settings(s.to_path_buf());
        }
        if let (Some(_), Some(s)) = (detect_format(dir), folder_settings(dir)) {
            return CameraOrigin::FolderSettings(s);
        }
        match detect_format(dir) {
            Some(Format::EurocStereo) => CameraOrigin::EurocSensorFiles,
            _ => match CameraId::detect_tum(&tum::folder_name(dir)) {
                Some(id) => CameraOrigin::TumName(id),
                None => CameraOrigin::TumGuess,
            },
        }
    }

    /// Whether nothing stands behind the camera (a guess).
    pub fn is_guess(&self) -> bool {
        *self == CameraOrigin::TumGuess
    }

    /// One line for the user: the camera and where it came from; for a guess, how to give it.
    pub fn describe(&self, dir: &Path) -> String {
        match self {
            CameraOrigin::Settings(s) => {
                format!("camera of {}: from {}", dir.display(), s.display())
            }
            CameraOrigin::FolderSettings(s) => format!(
                "camera of {}: from its own {} (written with the folder)",
                dir.display(),
                s.file_name()
                    .map_or(String::new(), |f| f.to_string_lossy().into_owned())
            ),
            CameraOrigin::TumName(id) => format!(
                "camera of {}: TUM {id:?}'s (ORB-SLAM2's TUM settings and depth factor), from the \
                 folder's name",
                dir.display()
            ),
            CameraOrigin::EurocSensorFiles => format!(
                "camera of {}: from its sensor.yaml files (EuRoC)",
                dir.display()
            ),
            CameraOrigin::TumGuess => {
                let written = ["camera-orbslam2.yaml", "camera-orbslam3.yaml"]
                    .iter()
                    .map(|f| dir.join(f))
                    .find(|p| p.is_file());
                format!(
                    "warning: {} names no TUM camera (freiburg1/2/3): assuming freiburg3's \
                     intrinsics and depth factor; give the camera with --camera FILE.yaml{}",
                    dir.display(),
                    match written {
                        Some(p) => format!(" (this folder has one: --camera {})", p.display()),
                        None => " (`noisefree settings` writes one)".to_string(),
                    }
                )
            }
        }
    }
}

/// Loads any TUM RGB-D or EuRoC folder with default options, detecting its layout; a folder
/// with its own camera file ([`folder_settings`]) is read with that camera.
pub fn load_path(dir: &Path) -> Result<Sequence, DatasetError> {
    let (mut seq, frames) = open_path(dir)?;
    seq.frames = frames.without_colour().read_all()?;
    Ok(seq)
}

/// As [`load_path`], leaving the images to the returned reader (the sequence's `frames` stay
/// empty): for callers that turn frames into something smaller as they go.
pub fn open_path(dir: &Path) -> Result<(Sequence, FrameReader), DatasetError> {
    if !dir.is_dir() {
        return Err(DatasetError::Missing {
            path: dir.to_path_buf(),
            what: "a TUM RGB-D or EuRoC sequence folder".into(),
        });
    }
    if let (Some(_), Some(settings)) = (detect_format(dir), folder_settings(dir)) {
        return open_path_with_settings(dir, &settings);
    }
    match detect_format(dir) {
        Some(Format::EurocStereo) => open_euroc_with(dir, &EurocOptions::default()),
        Some(Format::TumRgbd) => open_tum_with(dir, &TumOptions::default()),
        None => Err(DatasetError::invalid(
            dir,
            "neither a TUM RGB-D folder (rgb.txt, depth.txt) nor an EuRoC folder (mav0/); \
             for TUM the rgb.txt list is missing",
        )),
    }
}
