//! Downloading catalogued sequences: HTTP(S) download into `DATA_ROOT/.downloads/` with resume
//! (an interrupted `.part` file continues with an HTTP `Range` request; a server that ignores
//! the range restarts it), atomic unpacking of `.tgz` / `.tar.gz` / `.zip` into a temporary
//! folder that is renamed into place only once its layout verifies, and a clear error with the
//! manual steps when there is no network. Progress is reported through a callback so the CLI
//! can draw its own bar.

use crate::catalog::{Entry, EntryFormat};
use crate::DatasetError;
use std::fs::{self, File, OpenOptions};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Download settings. `Default`: 10 s connect timeout, 30 s to the first response byte,
/// 3 resumes after a broken transfer, archive deleted after unpacking.
#[derive(Clone, Debug)]
pub struct FetchOptions {
    /// Timeout for opening the connection (and name resolution).
    pub connect_timeout: Duration,
    /// Timeout for the response headers.
    pub response_timeout: Duration,
    /// How many times a transfer that broke after some bytes arrived is resumed.
    pub retries: u32,
    /// Keep the downloaded archive in `DATA_ROOT/.downloads/` after unpacking.
    pub keep_archive: bool,
}

impl Default for FetchOptions {
    fn default() -> Self {
        FetchOptions {
            connect_timeout: Duration::from_secs(10),
            response_timeout: Duration::from_secs(30),
            retries: 3,
            keep_archive: false,
        }
    }
}

/// What `fetch` is doing, for progress display.
#[derive(Clone, Debug, PartialEq)]
pub enum FetchEvent {
    /// The folder is already there and verifies; nothing to do.
    AlreadyPresent(PathBuf),
    /// A complete archive was found in the download folder (e.g. placed by hand).
    UsingArchive(PathBuf),
    /// A transfer starts: `offset` bytes are already on disk (resume), `total` if known.
    Start {
        /// URL being fetched.
        url: String,
        /// Bytes already downloaded (resume point).
        offset: u64,
        /// Full size, when the server says.
        total: Option<u64>,
    },
    /// Bytes on disk so far.
    Progress {
        /// Bytes downloaded.
        done: u64,
        /// Full size, when known.
        total: Option<u64>,
    },
    /// The server ignored the range request; the download starts over.
    Restarted,
    /// The transfer broke; it resumes (attempt number, 1-based).
    Retrying(u32),
    /// Unpacking the archive.
    Unpacking(PathBuf),
    /// The sequence is in place.
    Done(PathBuf),
}

/// What to tell a user who has to fetch `entry` by hand.
pub fn manual_hint(entry: &Entry, root: &Path) -> String {
    let url = entry.url.as_deref().unwrap_or("?");
    let folder = entry.folder.as_deref().unwrap_or("?");
    let layout = match entry.format {
        EntryFormat::Tum => "rgb.txt, depth.txt, rgb/, depth/, groundtruth.txt",
        EntryFormat::Euroc => "mav0/cam0, mav0/cam1, mav0/state_groundtruth_estimate0",
        EntryFormat::Synthetic => "(synthetic: nothing to download)",
    };
    format!(
        "Without network, download {url} on another machine and either put the archive at {} \
         and rerun `noisefree fetch {}`, or unpack it so that {} contains {layout}.",
        archive_path(entry, root).display(),
        entry.name,
        root.join(folder).display(),
    )
}

/// Where the archive of `entry` is downloaded: `root/.downloads/<file name of the URL>`.
pub fn archive_path(entry: &Entry, root: &Path) -> PathBuf {
    let url = entry.url.as_deref().unwrap_or("");
    let file = url
        .rsplit('/')
        .next()
        .filter(|s| !s.is_empty())
        .unwrap_or(&entry.name);
    root.join(".downloads").join(file)
}

/// Makes `entry` available under `root` (downloading, unpacking and verifying as needed) and
/// returns its folder. An existing folder that verifies is left alone; one that does not is an
/// error (we never delete a user's files).
pub fn fetch(
    entry: &Entry,
    root: &Path,
    opts: &FetchOptions,
    progress: &mut dyn FnMut(&FetchEvent),
) -> Result<PathBuf, DatasetError> {
    let (Some(url), Some(folder)) = (entry.url.as_deref(), entry.folder.as_deref()) else {
        return Err(DatasetError::invalid(
            root,
            format!(
                "`{}` is synthetic: generate it with `noisefree synth --preset {}`",
                entry.name,
                entry.preset.as_deref().unwrap_or(&entry.name)
            ),
        ));
    };
    let target = root.join(folder);
    if target.exists() {
        verify(&target, entry.format).map_err(|e| {
            DatasetError::invalid(
                &target,
                format!("exists but is incomplete ({e}); move it away and fetch again"),
            )
        })?;
        progress(&FetchEvent::AlreadyPresent(target.clone()));
        return Ok(target);
    }
    let archive = archive_path(entry, root);
    if archive.is_file() {
        progress(&FetchEvent::UsingArchive(archive.clone()));
    } else {
        download(url, &archive, opts, progress)
            .inspect_err(|_| {
                // Leave no empty download folder behind (remove_dir keeps a non-empty one).
                if let Some(d) = archive.parent() {
                    let _ = fs::remove_dir(d);
                }
            })
            .map_err(|e| match e {
                DatasetError::Download { url, msg, .. } => DatasetError::Download {
                    url,
                    msg,
                    hint: manual_hint(entry, root),
                },
                other => other,
            })?;
    }
    progress(&FetchEvent::Unpacking(archive.clone()));
    let dir = unpack(&archive, root, folder, entry.format)?;
    if !opts.keep_archive {
        let _ = fs::remove_file(&archive);
    }
    progress(&FetchEvent::Done(dir.clone()));
    Ok(dir)
}

fn part_path(dest: &Path) -> PathBuf {
    let mut s = dest.as_os_str().to_owned();
    s.push(".part");
    PathBuf::from(s)
}

/// Parses `Content-Range: bytes START-END/TOTAL` into (START, TOTAL?).
fn parse_content_range(v: &str) -> Option<(u64, Option<u64>)> {
    let rest = v.trim().strip_prefix("bytes")?.trim();
    let (range, total) = rest.split_once('/')?;
    let (start, _) = range.split_once('-')?;
    Some((start.trim().parse().ok()?, total.trim().parse().ok()))
}

/// Downloads `url` to `dest` (via `dest.part`, renamed when complete), resuming a `.part` left
/// by an earlier attempt. A connection that cannot be opened fails at once (no retries): that is
/// the no-network case. A transfer that breaks after bytes arrived resumes up to
/// `opts.retries` times.
pub fn download(
    url: &str,
    dest: &Path,
    opts: &FetchOptions,
    progress: &mut dyn FnMut(&FetchEvent),
) -> Result<u64, DatasetError> {
    let fail = |msg: String| DatasetError::Download {
        url: url.to_string(),
        msg,
        hint: String::new(),
    };
    if let Some(parent) = dest.parent() {
        fs::create_dir_all(parent).map_err(|e| DatasetError::io(parent, e))?;
    }
    let part = part_path(dest);
    let agent: ureq::Agent = ureq::Agent::config_builder()
        .timeout_connect(Some(opts.connect_timeout))
        .timeout_resolve(Some(opts.connect_timeout))
        .timeout_recv_response(Some(opts.response_timeout))
        .build()
        .into();
    let mut attempt = 0u32;
    loop {
        let have = fs::metadata(&part).map(|m| m.len()).unwrap_or(0);
        let mut req = agent.get(url);
        if have > 0 {
            req = req.header("Range", format!("bytes={have}-"));
        }
        let resp = match req.call() {
            Ok(r) => r,
            Err(ureq::Error::StatusCode(416)) if have > 0 => {
                // Our partial file does not fit the server's file: start over.
                fs::remove_file(&part).map_err(|e| DatasetError::io(&part, e))?;
                progress(&FetchEvent::Restarted);
                attempt += 1;
                if attempt > opts.retries {
                    return Err(fail("server refuses the resume range".into()));
                }
                continue;
            }
            Err(ureq::Error::StatusCode(code)) => {
                return Err(fail(format!("the server answered HTTP {code}")))
            }
            Err(e) => {
                if have > 0 && attempt < opts.retries {
                    attempt += 1;
                    progress(&FetchEvent::Retrying(attempt));
                    continue;
                }
                return Err(fail(format!(
                    "no connection ({e}); is there network access?"
                )));
            }
        };
        let status = resp.status().as_u16();
        let header = |k: &str| {
            resp.headers()
                .get(k)
                .and_then(|v| v.to_str().ok())
                .map(str::to_string)
        };
        let content_length: Option<u64> = header("content-length").and_then(|v| v.parse().ok());
        let (offset, total) = if status == 206 {
            match header("content-range")
                .as_deref()
                .and_then(parse_content_range)
            {
                Some((start, total)) if start == have => (have, total),
                _ => {
                    fs::remove_file(&part).map_err(|e| DatasetError::io(&part, e))?;
                    progress(&FetchEvent::Restarted);
                    attempt += 1;
                    if attempt > opts.retries {
                        return Err(fail("server sent an unusable range".into()));
                    }
                    continue;
                }
            }
        } else {
            if have > 0 {
                progress(&FetchEvent::Restarted);
            }
            (0, content_length)
        };
        progress(&FetchEvent::Start {
            url: url.to_string(),
            offset,
            total,
        });
        let mut file = OpenOptions::new()
            .create(true)
            .write(true)
            .append(offset > 0)
            .truncate(offset == 0)
            .open(&part)
            .map_err(|e| DatasetError::io(&part, e))?;
        let mut reader = resp.into_body().into_reader();
        let mut done = offset;
        let mut buf = vec![0u8; 1 << 16];
        let mut last_report = 0u64;
        let broken = loop {
            match reader.read(&mut buf) {
                Ok(0) => break None,
                Ok(n) => {
                    file.write_all(&buf[..n])
                        .map_err(|e| DatasetError::io(&part, e))?;
                    done += n as u64;
                    if done - last_report >= 1 << 20 {
                        last_report = done;
                        progress(&FetchEvent::Progress { done, total });
                    }
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => break Some(e),
            }
        };
        file.flush().map_err(|e| DatasetError::io(&part, e))?;
        drop(file);
        progress(&FetchEvent::Progress { done, total });
        let short = total.is_some_and(|t| done < t);
        if broken.is_some() || short {
            if attempt < opts.retries {
                attempt += 1;
                progress(&FetchEvent::Retrying(attempt));
                continue;
            }
            return Err(fail(format!(
                "transfer broke at {done} bytes{} after {} resumes: {}",
                total.map(|t| format!(" of {t}")).unwrap_or_default(),
                opts.retries,
                broken
                    .map(|e| e.to_string())
                    .unwrap_or_else(|| "short body".into())
            )));
        }
        fs::rename(&part, dest).map_err(|e| DatasetError::io(dest, e))?;
        return Ok(done);
    }
}

/// Unpacks `archive` (`.tgz`, `.tar.gz`, `.tar` or `.zip`) into `root/folder` atomically: into
/// a temporary folder under `root` first, then renamed once the layout verifies. The archive
/// may hold the folder itself (TUM: `rgbd_dataset_.../`) or its contents (EuRoC: `mav0/`).
pub fn unpack(
    archive: &Path,
    root: &Path,
    folder: &str,
    format: EntryFormat,
) -> Result<PathBuf, DatasetError> {
    let target = root.join(folder);
    if target.exists() {
        return Err(DatasetError::invalid(
            &target,
            "already exists; not overwriting",
        ));
    }
    fs::create_dir_all(root).map_err(|e| DatasetError::io(root, e))?;
    let tmp = root.join(format!(".unpack-{folder}-{}", std::process::id()));
    if tmp.exists() {
        fs::remove_dir_all(&tmp).map_err(|e| DatasetError::io(&tmp, e))?;
    }
    fs::create_dir_all(&tmp).map_err(|e| DatasetError::io(&tmp, e))?;
    let result = (|| {
        extract(archive, &tmp)?;
        let source = pick_root(&tmp, folder, format);
        verify(&source, format).map_err(|e| DatasetError::Archive {
            path: archive.to_path_buf(),
            msg: format!("unpacked files do not form a sequence: {e}"),
        })?;
        fs::rename(&source, &target).map_err(|e| DatasetError::io(&target, e))?;
        Ok(target.clone())
    })();
    if tmp.exists() {
        let _ = fs::remove_dir_all(&tmp);
    }
    result
}

/// The folder inside an unpacked archive that holds the sequence.
fn pick_root(tmp: &Path, folder: &str, format: EntryFormat) -> PathBuf {
    if tmp.join(folder).is_dir() {
        return tmp.join(folder);
    }
    if verify(tmp, format).is_ok() {
        return tmp.to_path_buf();
    }
    let dirs: Vec<PathBuf> = fs::read_dir(tmp)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .map(|e| e.path())
                .filter(|p| p.is_dir())
                .collect()
        })
        .unwrap_or_default();
    if dirs.len() == 1 {
        dirs[0].clone()
    } else {
        tmp.to_path_buf()
    }
}

fn extract(archive: &Path, dest: &Path) -> Result<(), DatasetError> {
    let name = archive
        .file_name()
        .map(|s| s.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let file = File::open(archive).map_err(|e| DatasetError::io(archive, e))?;
    let bad = |msg: String| DatasetError::Archive {
        path: archive.to_path_buf(),
        msg,
    };
    if name.ends_with(".zip") {
        let mut z = zip::ZipArchive::new(file).map_err(|e| bad(e.to_string()))?;
        z.extract(dest).map_err(|e| bad(e.to_string()))
    } else if name.ends_with(".tgz") || name.ends_with(".tar.gz") {
        tar::Archive::new(flate2::read::GzDecoder::new(file))
            .unpack(dest)
            .map_err(|e| bad(e.to_string()))
    } else if name.ends_with(".tar") {
        tar::Archive::new(file)
            .unpack(dest)
            .map_err(|e| bad(e.to_string()))
    } else {
        Err(bad(
            "unknown archive type (expected .tgz, .tar.gz, .tar or .zip)".into(),
        ))
    }
}

/// Checks that `dir` has the layout of `format`: TUM needs `rgb.txt` and `depth.txt` (or
/// `associations.txt`) and the first listed image; EuRoC needs `mav0/cam{0,1}/data.csv` and
/// `sensor.yaml`.
pub fn verify(dir: &Path, format: EntryFormat) -> Result<(), DatasetError> {
    let need = |p: PathBuf, what: &str| {
        if p.exists() {
            Ok(())
        } else {
            Err(DatasetError::Missing {
                path: p,
                what: what.into(),
            })
        }
    };
    match format {
        EntryFormat::Tum => {
            if dir.join("associations.txt").is_file() {
                return Ok(());
            }
            need(dir.join("rgb.txt"), "the TUM rgb list")?;
            need(dir.join("depth.txt"), "the TUM depth list")?;
            let rgb = crate::tum::read_list(&dir.join("rgb.txt"))?;
            if let Some(first) = rgb.first() {
                need(dir.join(&first.file), "the first listed rgb image")?;
            }
            Ok(())
        }
        EntryFormat::Euroc => {
            for cam in ["cam0", "cam1"] {
                need(
                    dir.join("mav0").join(cam).join("data.csv"),
                    "the EuRoC image list",
                )?;
                need(
                    dir.join("mav0").join(cam).join("sensor.yaml"),
                    "the EuRoC calibration",
                )?;
            }
            Ok(())
        }
        EntryFormat::Synthetic => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn content_range_parses() {
        assert_eq!(
            parse_content_range("bytes 100-199/200"),
            Some((100, Some(200)))
        );
        assert_eq!(parse_content_range("bytes 5-9/*"), Some((5, None)));
        assert_eq!(parse_content_range("items 1-2/3"), None);
    }

    #[test]
    fn archive_goes_to_downloads() {
        let c = crate::Catalog::embedded();
        let e = c.get("fr1_xyz").unwrap();
        assert_eq!(
            archive_path(e, Path::new("/d")),
            Path::new("/d/.downloads/rgbd_dataset_freiburg1_xyz.tgz")
        );
        let h = manual_hint(e, Path::new("/d"));
        assert!(
            h.contains("https://cvg.cit.tum.de") && h.contains("/d/rgbd_dataset_freiburg1_xyz")
        );
    }
}
