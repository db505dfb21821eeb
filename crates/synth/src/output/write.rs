//! File helpers shared by the dataset writers: a staging folder renamed into place at the end
//! (so no half-written dataset ever looks complete), text files, and PNG encoding.

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};

use crate::error::SynthError;

/// Wraps an I/O error with its path.
pub fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> SynthError + '_ {
    move |source| SynthError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// A staging folder beside the final output folder.
pub struct Staging {
    /// Where the files are written.
    pub tmp: PathBuf,
    target: PathBuf,
}

impl Staging {
    /// Creates `.<name>.tmp-<pid>` beside `target`; fails if `target` exists and is not empty.
    pub fn new(target: &Path) -> Result<Staging, SynthError> {
        if target.exists() {
            let mut it = fs::read_dir(target).map_err(io_err(target))?;
            if it.next().is_some() {
                return Err(SynthError::OutputExists(target.to_path_buf()));
            }
        }
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "out".into());
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        fs::create_dir_all(&parent).map_err(io_err(&parent))?;
        let tmp = parent.join(format!(".{name}.tmp-{}", std::process::id()));
        if tmp.exists() {
            fs::remove_dir_all(&tmp).map_err(io_err(&tmp))?;
        }
        fs::create_dir_all(&tmp).map_err(io_err(&tmp))?;
        Ok(Staging {
            tmp,
            target: target.to_path_buf(),
        })
    }

    /// Moves the staged folder into place.
    pub fn commit(self) -> Result<(), SynthError> {
        if self.target.exists() {
            // Known to be empty (checked in `new`).
            fs::remove_dir(&self.target).map_err(io_err(&self.target))?;
        }
        fs::rename(&self.tmp, &self.target).map_err(io_err(&self.target))
    }

    /// Removes the staging folder after a failure (best effort).
    pub fn abort(self) {
        let _ = fs::remove_dir_all(&self.tmp);
    }

    /// Writes `target` through a staging folder: `write` fills the folder, which then moves into
    /// place, or is removed if `write` fails, so a half-written sequence never looks complete.
    pub fn write_atomically(
        target: &Path,
        write: impl FnOnce(&Path) -> Result<(), SynthError>,
    ) -> Result<(), SynthError> {
        let staging = Staging::new(target)?;
        match write(&staging.tmp) {
            Ok(()) => staging.commit(),
            Err(e) => {
                staging.abort();
                Err(e)
            }
        }
    }
}

/// Creates a folder (and parents).
pub fn mkdir(path: &Path) -> Result<(), SynthError> {
    fs::create_dir_all(path).map_err(io_err(path))
}

/// Writes a text file.
pub fn text(path: &Path, content: &str) -> Result<(), SynthError> {
    let f = fs::File::create(path).map_err(io_err(path))?;
    let mut w = BufWriter::new(f);
    w.write_all(content.as_bytes()).map_err(io_err(path))?;
    w.flush().map_err(io_err(path))
}

/// Writes a PNG (8-bit RGB, 8-bit grey or 16-bit grey given as native-endian bytes).
pub fn png(
    path: &Path,
    data: &[u8],
    w: usize,
    h: usize,
    ty: ExtendedColorType,
) -> Result<(), SynthError> {
    let f = fs::File::create(path).map_err(io_err(path))?;
    let mut buf = BufWriter::new(f);
    PngEncoder::new_with_quality(&mut buf, CompressionType::Fast, FilterType::Adaptive)
        .write_image(data, w as u32, h as u32, ty)
        .map_err(|source| SynthError::Image {
            path: path.to_path_buf(),
            source,
        })?;
    buf.flush().map_err(io_err(path))
}
