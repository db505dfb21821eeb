//! atomic-file: the one way noisefree writes a file or a folder, whole or not at all. A reader
//! (a table, a resumed sweep, another process) never sees half of one, and a write that fails
//! leaves nothing behind that looks like a result.
//!
//! - [`write`]: a file through a temporary file beside it, renamed into place;
//! - [`write_folder`]: a folder through a staging folder beside it, renamed into place, into a
//!   target that is absent or empty (nothing a user made is overwritten).
//!
//! Every crate that writes results, trajectories, caches or dataset folders calls these; none
//! writes its own.

use std::fmt;
use std::fs;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Why a write failed, naming the path.
#[derive(Debug)]
pub enum WriteError {
    /// Reading or writing `path` failed.
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error: in the message, not a `source` too, so that a chain of errors
        /// printed whole names it once.
        cause: io::Error,
    },
    /// [`write_folder`]'s target exists and is not empty.
    Occupied {
        /// The folder.
        path: PathBuf,
    },
}

impl fmt::Display for WriteError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WriteError::Io { path, cause } => write!(f, "{}: {cause}", path.display()),
            WriteError::Occupied { path } => write!(
                f,
                "{}: exists and is not empty (give a new folder, or remove it first)",
                path.display()
            ),
        }
    }
}

impl std::error::Error for WriteError {}

fn io_error(path: &Path) -> impl FnOnce(io::Error) -> WriteError + '_ {
    move |cause| WriteError::Io {
        path: path.to_path_buf(),
        cause,
    }
}

/// Writes `contents` to `path` (its folders made as needed) through a temporary file beside
/// it, then a rename. The temporary name is the writer's own (process and call), so threads or
/// processes writing the same path at once never write into one temporary file; one of them
/// wins whole. A temporary file that cannot be written whole or renamed is removed.
pub fn write(path: &Path, contents: &[u8]) -> Result<(), WriteError> {
    static CALLS: AtomicU64 = AtomicU64::new(0);
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        fs::create_dir_all(dir).map_err(io_error(dir))?;
    }
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(
        ".tmp{}-{}",
        std::process::id(),
        CALLS.fetch_add(1, Ordering::Relaxed)
    ));
    let tmp = PathBuf::from(tmp);
    let written = fs::write(&tmp, contents)
        .map_err(io_error(&tmp))
        .and_then(|()| fs::rename(&tmp, path).map_err(io_error(path)));
    if written.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    written
}

/// Refuses a target folder that exists and is not empty: what [`write_folder`] checks first,
/// for a caller that wants to refuse before its work starts.
pub fn refuse_occupied(target: &Path) -> Result<(), WriteError> {
    if target.exists() {
        let mut entries = fs::read_dir(target).map_err(io_error(target))?;
        if entries.next().is_some() {
            return Err(WriteError::Occupied {
                path: target.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// Writes the folder `target` through a staging folder `.<name>.tmp-<pid>` beside it: `fill`
/// writes into the staging folder, which then moves into place, or is removed when `fill`
/// fails. `target` must be absent or empty ([`WriteError::Occupied`] otherwise).
pub fn write_folder<E: From<WriteError>>(
    target: &Path,
    fill: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let tmp = stage(target)?;
    match fill(&tmp) {
        Ok(()) => Ok(commit(&tmp, target)?),
        Err(e) => {
            // Best effort: the error that matters is the writer's.
            let _ = fs::remove_dir_all(&tmp);
            Err(e)
        }
    }
}

/// Creates the staging folder of `target` after checking that `target` is absent or empty.
fn stage(target: &Path) -> Result<PathBuf, WriteError> {
    refuse_occupied(target)?;
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let parent = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    fs::create_dir_all(&parent).map_err(io_error(&parent))?;
    let tmp = parent.join(format!(".{name}.tmp-{}", std::process::id()));
    if tmp.exists() {
        fs::remove_dir_all(&tmp).map_err(io_error(&tmp))?;
    }
    fs::create_dir_all(&tmp).map_err(io_error(&tmp))?;
    Ok(tmp)
}

/// Moves the staging folder `tmp` to `target` (an empty `target` is replaced).
fn commit(tmp: &Path, target: &Path) -> Result<(), WriteError> {
    if target.exists() {
        // Known to be empty (checked in `stage`).
        fs::remove_dir(target).map_err(io_error(target))?;
    }
    fs::rename(tmp, target).map_err(io_error(target))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("atomic-file-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        dir
    }

    #[test]
    fn writers_of_one_path_at_once_each_write_a_whole_file() {
        let dir = scratch("race");
        let path = dir.join("out.bin");
        let contents: Vec<Vec<u8>> = (0..8u8).map(|k| vec![k; 1 << 20]).collect();
        std::thread::scope(|s| {
            for c in &contents {
                let path = &path;
                s.spawn(move || {
                    for _ in 0..4 {
                        write(path, c).expect("every write succeeds");
                    }
                });
            }
        });
        let written = fs::read(&path).unwrap();
        assert!(contents.contains(&written), "one writer's whole file");
        let left: Vec<_> = fs::read_dir(&dir).unwrap().collect();
        assert_eq!(left.len(), 1, "no temporary file left");
        let _ = fs::remove_dir_all(dir);
    }

    #[test]
    fn a_file_that_cannot_be_written_names_its_path_and_leaves_nothing() {
        let dir = scratch("fail");
        fs::create_dir_all(dir.join("taken")).unwrap();
        // A folder where the file should go: the rename fails.
        let err = write(&dir.join("taken"), b"x").unwrap_err();
        assert!(err.to_string().contains("taken"), "{err}");
        let left: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left, vec![std::ffi::OsString::from("taken")]);
        let _ = fs::remove_dir_all(dir);
    }

    #[test]
    fn a_folder_is_written_whole_or_not_at_all_and_never_over_a_users_files() {
        let dir = scratch("folder");
        let target = dir.join("seq");
        let failed: Result<(), WriteError> = write_folder(&target, |tmp| {
            fs::write(tmp.join("a.txt"), "a").map_err(io_error(tmp))?;
            Err(WriteError::Io {
                path: tmp.to_path_buf(),
                cause: io::Error::other("fill failed"),
            })
        });
        assert!(failed.is_err());
        assert!(!target.exists(), "nothing that looks like a result");
        assert_eq!(
            fs::read_dir(&dir).unwrap().count(),
            0,
            "no staging folder left"
        );
        write_folder::<WriteError>(&target, |tmp| {
            fs::write(tmp.join("a.txt"), "a").map_err(io_error(tmp))
        })
        .unwrap();
        assert_eq!(fs::read_to_string(target.join("a.txt")).unwrap(), "a");
        let again = write_folder::<WriteError>(&target, |_| Ok(()));
        assert!(matches!(again, Err(WriteError::Occupied { .. })));
        let _ = fs::remove_dir_all(dir);
    }
}
