//! The recording's file: checked before a run starts (a bad path is refused naming it, not
//! after minutes of tracking), written under a temporary name and renamed when complete, so a
//! stopped run never leaves a recording that looks whole.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// The name the recording is written under until it is complete.
pub fn partial(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    path.with_file_name(name)
}

/// Refuses a recording path that cannot be written, naming it and why: not ending in `.rrd`
/// (the viewer opens files by their extension), a folder, in a folder that does not exist, or
/// not writable (tried by creating its temporary file, removed again).
pub fn check(path: &Path) -> Result<()> {
    if path.extension().and_then(|e| e.to_str()) != Some("rrd") {
        bail!(
            "--rerun {}: a Rerun recording's name ends in .rrd (the viewer opens it by its \
             extension)",
            path.display()
        );
    }
    if path.is_dir() {
        bail!("--rerun {}: is a folder; name a file", path.display());
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        bail!(
            "--rerun {}: its folder {} does not exist",
            path.display(),
            parent.display()
        );
    }
    let tmp = partial(path);
    std::fs::File::create(&tmp)
        .with_context(|| format!("--rerun {}: cannot write there", path.display()))?;
    std::fs::remove_file(&tmp).with_context(|| format!("removing {}", tmp.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_path_that_cannot_be_written_is_refused_naming_it() {
        let dir = std::env::temp_dir().join(format!("noisefree-rrd-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let no_ext = check(&dir.join("run.txt")).unwrap_err().to_string();
        assert!(
            no_ext.contains("run.txt") && no_ext.contains(".rrd"),
            "{no_ext}"
        );
        let missing = check(&dir.join("nothere/run.rrd")).unwrap_err().to_string();
        assert!(missing.contains("does not exist"), "{missing}");
        let folder = dir.join("a.rrd");
        std::fs::create_dir_all(&folder).unwrap();
        assert!(check(&folder).unwrap_err().to_string().contains("folder"));
        let good = dir.join("run.rrd");
        check(&good).unwrap();
        assert!(!partial(&good).exists(), "the probe file is removed");
        assert!(!good.exists(), "nothing is written before the run");
        let _ = std::fs::remove_dir_all(dir);
    }
}
