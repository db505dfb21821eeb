//! The files every folder writer shares: a staging folder renamed into place at the end (so no
//! half-written sequence ever looks complete), text files and PNG images.

use std::fs;
use std::io::{BufWriter, Write};
use std::path::Path;

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};

use crate::DatasetError;

/// Writes the folder `target` whole or not at all ([`atomic_file::write_folder`]: a staging
/// folder beside it, renamed into place, or removed when `write` fails). `target` must not
/// exist or be empty ([`DatasetError::OutputExists`] otherwise), so nothing a user made is
/// overwritten.
pub fn write_atomically<E: From<DatasetError>>(
    target: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    /// The folder writer's error, or the filler's own.
    enum Failed<E> {
        Write(atomic_file::WriteError),
        Fill(E),
    }
    impl<E> From<atomic_file::WriteError> for Failed<E> {
        fn from(e: atomic_file::WriteError) -> Self {
            Failed::Write(e)
        }
    }
    atomic_file::write_folder(target, |tmp| write(tmp).map_err(Failed::Fill)).map_err(|e| match e {
        Failed::Write(w) => DatasetError::from(w).into(),
        Failed::Fill(e) => e,
    })
}

/// Refuses an output folder that exists and is not empty ([`DatasetError::OutputExists`]): what
/// [`write_atomically`] checks first, for a caller that wants to refuse before its work starts.
pub fn refuse_occupied(target: &Path) -> Result<(), DatasetError> {
    Ok(atomic_file::refuse_occupied(target)?)
}

/// Creates a folder and its parents.
pub fn mkdir(path: &Path) -> Result<(), DatasetError> {
    fs::create_dir_all(path).map_err(|e| DatasetError::io(path, e))
}

/// Writes a text file.
pub fn text(path: &Path, content: &str) -> Result<(), DatasetError> {
    let f = fs::File::create(path).map_err(|e| DatasetError::io(path, e))?;
    let mut w = BufWriter::new(f);
    w.write_all(content.as_bytes())
        .and_then(|()| w.flush())
        .map_err(|e| DatasetError::io(path, e))
}

/// Writes a PNG: 8-bit RGB, 8-bit grey, or 16-bit grey given as native-endian bytes. One
/// encoder setting for every writer (fast deflate, adaptive row filters), so the same pixels
/// always give the same bytes.
pub fn png(
    path: &Path,
    data: &[u8],
    width: usize,
    height: usize,
    ty: ExtendedColorType,
) -> Result<(), DatasetError> {
    let f = fs::File::create(path).map_err(|e| DatasetError::io(path, e))?;
    let mut buf = BufWriter::new(f);
    PngEncoder::new_with_quality(&mut buf, CompressionType::Fast, FilterType::Adaptive)
        .write_image(data, width as u32, height as u32, ty)
        .map_err(|e| DatasetError::Encode {
            path: path.to_path_buf(),
            msg: e.to_string(),
        })?;
    buf.flush().map_err(|e| DatasetError::io(path, e))
}

/// A depth image in metres as the 16-bit PNG of the TUM layout: `round(z * units)`, 0 where
/// there is no depth (0, negative, NaN or infinite), saturating at 65535.
pub fn depth_png(
    path: &Path,
    depth: &[f32],
    width: usize,
    height: usize,
    units: f64,
) -> Result<(), DatasetError> {
    let mut bytes = Vec::with_capacity(depth.len() * 2);
    for &z in depth {
        let v = (z as f64 * units).round();
        let v = if v.is_finite() && v > 0.0 {
            v.min(65535.0) as u16
        } else {
            0
        };
        bytes.extend_from_slice(&v.to_ne_bytes());
    }
    png(path, &bytes, width, height, ExtendedColorType::L16)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("ds-write-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn a_failed_write_leaves_nothing_and_a_full_folder_is_refused() {
        let dir = temp("atomic");
        let failed: Result<(), DatasetError> = write_atomically(&dir, |tmp| {
            text(&tmp.join("half.txt"), "half")?;
            Err(DatasetError::invalid(tmp, "the writer failed"))
        });
        assert!(failed.is_err());
        assert!(!dir.exists(), "a failed write left {}", dir.display());
        let parent = dir.parent().unwrap();
        let stray = fs::read_dir(parent).unwrap().flatten().any(|e| {
            e.file_name()
                .to_string_lossy()
                .starts_with(".ds-write-atomic")
        });
        assert!(!stray, "the staging folder was left behind");

        write_atomically::<DatasetError>(&dir, |tmp| text(&tmp.join("a.txt"), "a")).unwrap();
        assert_eq!(fs::read_to_string(dir.join("a.txt")).unwrap(), "a");
        let again = write_atomically::<DatasetError>(&dir, |tmp| text(&tmp.join("b.txt"), "b"));
        assert!(
            matches!(again, Err(DatasetError::OutputExists { .. })),
            "{again:?}"
        );
        assert!(!dir.join("b.txt").exists());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn depth_is_rounded_saturated_and_invalid_depth_is_zero() {
        let dir = temp("depth");
        mkdir(&dir).unwrap();
        let p = dir.join("d.png");
        let z = [0.0, 1.0, 1.00011, -2.0, f32::NAN, f32::INFINITY, 20.0];
        depth_png(&p, &z, 7, 1, 5000.0).unwrap();
        let back = image::open(&p).unwrap().into_luma16().into_raw();
        assert_eq!(back, [0, 5000, 5001, 0, 0, 0, 65535]);
        fs::remove_dir_all(&dir).unwrap();
    }
}
