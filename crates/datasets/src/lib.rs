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

/// Loads any TUM RGB-D or EuRoC folder with default options, detecting its layout.
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
