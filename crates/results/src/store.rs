//! The record of a sweep: `runs.csv` (or `runs.shard-K-of-N.csv` for a shard), one row per
//! finished run, appended the moment the run ends. Rows are written whole with one write, a
//! torn last line (a kill mid-write) is dropped and the file rewritten atomically on the next
//! open, and a run whose key is already recorded is not run again — so an interrupted sweep
//! resumes where it stopped and the file never holds a half row.

use crate::keys::{perturbation_key, run_key, Params, Shard};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use slam_core::system::ClusterViews;
use std::collections::BTreeSet;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// One finished run: a row of `runs.csv`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// Sequence label.
    pub sequence: String,
    /// Configuration kind (`orb`, `mcor`, `avc`, `mcor+avc`).
    pub config: String,
    /// MC-OR tau_MF (m), empty when MC-OR is off.
    pub tau_mf: Option<f64>,
    /// MC-OR tau_GF (m).
    pub tau_gf: Option<f64>,
    /// MC-OR tau_MG (m).
    pub tau_mg: Option<f64>,
    /// AVC baseline (m), empty when AVC is off.
    pub baseline: Option<f64>,
    /// Seed.
    pub seed: u64,
    /// ATE RMSE in metres (empty when it could not be computed).
    pub ate_rmse: Option<f64>,
    /// Failure verdict ('F').
    pub failed: bool,
    /// Frames fed.
    pub frames: usize,
    /// Frames with a pose.
    pub tracked: usize,
    /// Keyframes at the end (empty for an external system, which does not say).
    pub keyframes: Option<usize>,
    /// Map points at the end (empty for an external system).
    pub map_points: Option<usize>,
    /// Mean inliers per frame (empty for an external system).
    pub mean_inliers: Option<f64>,
    /// Mean outliers per frame (empty for an external system).
    pub mean_outliers: Option<f64>,
    /// Frames per second (one thread).
    pub fps: f64,
    /// Wall time of the run, seconds.
    pub wall_s: f64,
    /// Synthetic sequences: seed of the sequence realization; empty for real sequences (and
    /// absent from records written before the column existed).
    #[serde(default)]
    pub synth_seed: Option<u64>,
    /// Loops closed (empty in records written before loop closing existed, and for external
    /// systems).
    #[serde(default)]
    pub loops: Option<usize>,
    /// Why the run failed when its program did (an external system: `exit status 1`,
    /// `timeout after 600 s`, `no trajectory`...); empty otherwise.
    #[serde(default)]
    pub reason: Option<String>,
    /// Peak resident memory of an external system's process, MB (from `wait4`).
    #[serde(default)]
    pub peak_rss_mb: Option<f64>,
    /// CPU time (user + system), seconds: of an external system's whole process (above
    /// `wall_s` for a threaded system); of one of ours, its thread plus the CPU time of its
    /// features' extraction, charged in full to every run that shares them as `wall_s` is (the
    /// figures of a run that extracts for itself; below `wall_s` when the run shared its core).
    /// Empty in records of ours written before the column was filled.
    #[serde(default)]
    pub cpu_s: Option<f64>,
    /// The perturbation applied to the sequence (`sweep --perturb`: a chain such as
    /// `depth-axial:2`, or `none` for the unperturbed point); empty in sweeps without one.
    #[serde(default)]
    pub perturbation: Option<String>,
    /// The perturbation axis this run measures (its family); empty for the unperturbed point.
    #[serde(default)]
    pub perturb_family: Option<String>,
    /// The axis level, in the family's unit; empty for the unperturbed point.
    #[serde(default)]
    pub perturb_level: Option<f64>,
    /// Seed of the perturbation's draws.
    #[serde(default)]
    pub perturb_seed: Option<u64>,
}

impl RunRecord {
    /// The run's parameters.
    pub fn params(&self) -> Params {
        Params {
            tau_mf: self.tau_mf,
            tau_gf: self.tau_gf,
            tau_mg: self.tau_mg,
            baseline: self.baseline,
        }
    }

    /// The run's identity (same as the job's key).
    pub fn key(&self) -> String {
        let mut k = run_key(
            &self.sequence,
            &self.config,
            &self.params(),
            self.seed,
            self.synth_seed,
        );
        if let Some(p) = &self.perturbation {
            k += &perturbation_key(p, self.perturb_seed.unwrap_or(0));
        }
        k
    }
}

#[cfg(test)]
impl RunRecord {
    /// A finished, unperturbed run of `config` on `sequence` for tests: 100 frames all tracked at
    /// 100 frames/s, 5 keyframes, 500 map points, 300 inliers and 10 outliers a frame, synthetic
    /// seed 0, no loop closed; change what a test is about with struct update syntax.
    pub fn example(sequence: &str, config: &str, seed: u64, ate: f64) -> RunRecord {
        RunRecord {
            sequence: sequence.into(),
            config: config.into(),
            tau_mf: None,
            tau_gf: None,
            tau_mg: None,
            baseline: None,
            seed,
            ate_rmse: Some(ate),
            failed: false,
            frames: 100,
            tracked: 100,
            keyframes: Some(5),
            map_points: Some(500),
            mean_inliers: Some(300.0),
            mean_outliers: Some(10.0),
            fps: 100.0,
            wall_s: 1.0,
            synth_seed: Some(0),
            loops: Some(0),
            reason: None,
            peak_rss_mb: None,
            cpu_s: None,
            perturbation: None,
            perturb_family: None,
            perturb_level: None,
            perturb_seed: None,
        }
    }
}

/// The file that pins a sweep folder's emulated local-mapping lag (`--mapping-lag`). A folder
/// without it was swept synchronously (lag 0), as every sweep before the option existed.
pub const SETTINGS_FILE: &str = "sweep-settings.toml";

/// How every run of a sweep folder was made, beyond what a run's key holds: runs made with
/// other settings would be resumed as the recorded ones and averaged with them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FolderSettings {
    /// The emulated local-mapping lag (`--mapping-lag`).
    pub mapping_lag: u32,
    /// The place-recognition vocabulary (`--vocabulary`): `none` or its name and content hash.
    pub vocabulary: String,
    /// Whether the runs closed loops (loop closing on and a vocabulary loaded).
    pub loop_closing: bool,
    /// MC-OR's cluster reading of the `mcor` and `mcor+avc` runs (the kinds that name their
    /// reading, such as `mcor-keyframes`, say it themselves).
    pub mcor_cluster: ClusterViews,
    /// The synthetic effects switched off in every run (`--synth-without`), sorted; empty: all
    /// on. Runs of one sequence without different effects are different sequences.
    pub synth_without: Vec<String>,
    /// The documented speed approximations the runs were made with (a config file's
    /// `[avc] aim = "direct"`, `[mcor] view_stride = K`; see
    /// [`approximations`](crate::config_file::approximations)), sorted; empty: the reference.
    pub approximations: Vec<String>,
    /// The readings of the paper (issue 72) the sweep's configuration file set away from their
    /// defaults, as its settings (`mcor.sightings = "all"`; see
    /// [`readings`](crate::config_file::readings)), sorted; empty: the defaults. Columns that
    /// name their readings (`mcor:sightings=all`) say them themselves.
    pub readings: Vec<String>,
}

impl Default for FolderSettings {
    /// A folder without [`SETTINGS_FILE`]: synchronous runs from before vocabularies and loop
    /// closing existed (brute-force relocalization: `none`), MC-OR with keyframe clusters.
    fn default() -> Self {
        FolderSettings {
            mapping_lag: 0,
            vocabulary: "none".into(),
            loop_closing: false,
            mcor_cluster: ClusterViews::Keyframes,
            synth_without: Vec::new(),
            approximations: Vec::new(),
            readings: Vec::new(),
        }
    }
}

/// The settings recorded in sweep folder `dir` ([`SETTINGS_FILE`]; defaults when absent).
pub fn settings_of(dir: &Path) -> Result<FolderSettings> {
    let path = dir.join(SETTINGS_FILE);
    match std::fs::read_to_string(&path) {
        Ok(text) => {
            let v: toml::Value = toml::from_str(&text)
                .with_context(|| format!("{}: not valid TOML", path.display()))?;
            let mapping_lag = match v.get("mapping_lag") {
                None => 0,
                Some(x) => x
                    .as_integer()
                    .and_then(|x| u32::try_from(x).ok())
                    .with_context(|| format!("{}: no valid mapping_lag", path.display()))?,
            };
            let vocabulary = match v.get("vocabulary") {
                None => "none".to_string(),
                Some(x) => x
                    .as_str()
                    .with_context(|| format!("{}: vocabulary is not a string", path.display()))?
                    .to_string(),
            };
            // Absent: the folder predates loop closing.
            let loop_closing = match v.get("loop_closing") {
                None => false,
                Some(x) => x.as_bool().with_context(|| {
                    format!("{}: loop_closing is not true or false", path.display())
                })?,
            };
            // Absent: the folder predates the every-frame default of MC-OR's cluster.
            let mcor_cluster = match v.get("mcor_cluster").map(|x| x.as_str()) {
                None => ClusterViews::Keyframes,
                Some(Some("keyframes")) => ClusterViews::Keyframes,
                Some(Some("every-frame")) => ClusterViews::EveryFrame,
                Some(_) => bail!(
                    "{}: mcor_cluster is not \"keyframes\" or \"every-frame\"",
                    path.display()
                ),
            };
            // Absent: every effect on (folders from before the field had no other runs).
            let synth_without = string_list(&v, "synth_without", "effect names", &path)?;
            // Absent: the reference (folders from before the field had no approximation).
            let approximations = string_list(&v, "approximations", "settings", &path)?;
            // Absent: the default readings (folders from before the readings existed).
            let readings = string_list(&v, "readings", "settings", &path)?;
            Ok(FolderSettings {
                mapping_lag,
                vocabulary,
                loop_closing,
                mcor_cluster,
                synth_without,
                approximations,
                readings,
            })
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(FolderSettings::default()),
        Err(e) => Err(e).with_context(|| format!("reading {}", path.display())),
    }
}

/// The list of strings under `key` of settings file `path` (empty when absent); an error names
/// the file, the key and `what` the strings are.
fn string_list(v: &toml::Value, key: &str, what: &str, path: &Path) -> Result<Vec<String>> {
    match v.get(key) {
        None => Ok(Vec::new()),
        Some(x) => x
            .as_array()
            .and_then(|a| {
                a.iter()
                    .map(|e| e.as_str().map(str::to_string))
                    .collect::<Option<Vec<_>>>()
            })
            .with_context(|| format!("{}: {key} is not a list of {what}", path.display())),
    }
}

/// Makes sure every run recorded in `dir` was made with `settings`. A folder with runs of
/// other settings is an error; a folder without runs takes the new settings (recorded in
/// [`SETTINGS_FILE`]).
pub fn pin_settings(dir: &Path, settings: &FolderSettings) -> Result<()> {
    let path = dir.join(SETTINGS_FILE);
    let recorded = settings_of(dir)?;
    let exists = path.exists();
    if recorded == *settings && exists {
        return Ok(());
    }
    if !load_dir(dir)?.is_empty() {
        if recorded.mapping_lag != settings.mapping_lag {
            bail!(
                "{} holds runs made with --mapping-lag {}; this sweep asks for {}: use another \
                 --out folder (runs of different lags would be resumed as each other and \
                 averaged together)",
                dir.display(),
                recorded.mapping_lag,
                settings.mapping_lag
            );
        }
        if recorded.vocabulary != settings.vocabulary {
            bail!(
                "{} holds runs made with vocabulary {}; this sweep uses {}: use another --out \
                 folder, or pass the vocabulary of those runs with --vocabulary",
                dir.display(),
                recorded.vocabulary,
                settings.vocabulary
            );
        }
        if recorded.loop_closing != settings.loop_closing {
            let says = |on: bool| {
                if on {
                    "loop closing on"
                } else {
                    "loop closing off"
                }
            };
            bail!(
                "{} holds runs made with {}; this sweep has {}: use another --out folder{}",
                dir.display(),
                says(recorded.loop_closing),
                says(settings.loop_closing),
                if recorded.loop_closing {
                    ""
                } else {
                    " (or --no-loop-closing to add to those runs)"
                }
            );
        }
        if recorded.mcor_cluster != settings.mcor_cluster {
            bail!(
                "{} holds mcor runs made with MC-OR's {} clusters; this sweep's mcor uses {} \
                 clusters: use another --out folder, or a config file with [mcor] cluster_views \
                 = {:?} to add to those runs (configurations mcor-keyframes and mcor-frames \
                 name their reading in any folder)",
                dir.display(),
                recorded.mcor_cluster.name(),
                settings.mcor_cluster.name(),
                recorded.mcor_cluster.name()
            );
        }
        if recorded.synth_without != settings.synth_without {
            let says = |w: &[String]| {
                if w.is_empty() {
                    "every synthetic effect on".to_string()
                } else {
                    format!("--synth-without {}", w.join(","))
                }
            };
            bail!(
                "{} holds runs made with {}; this sweep has {}: use another --out folder (the \
                 same sequence without other effects is another sequence)",
                dir.display(),
                says(&recorded.synth_without),
                says(&settings.synth_without)
            );
        }
        if recorded.approximations != settings.approximations {
            let says = |a: &[String]| {
                if a.is_empty() {
                    "the reference (no speed approximation)".to_string()
                } else {
                    format!("the approximations {}", a.join(", "))
                }
            };
            bail!(
                "{} holds runs made with {}; this sweep has {}: use another --out folder (an \
                 approximation's results differ from the reference's)",
                dir.display(),
                says(&recorded.approximations),
                says(&settings.approximations)
            );
        }
        if recorded.readings != settings.readings {
            let says = |r: &[String]| {
                if r.is_empty() {
                    "the default readings".to_string()
                } else {
                    format!("the readings {}", r.join(", "))
                }
            };
            bail!(
                "{} holds runs made with {}; this sweep's configuration has {}: use another \
                 --out folder, or name the readings in the columns (--configs \
                 mcor:sightings=all,...) to compare them side by side",
                dir.display(),
                says(&recorded.readings),
                says(&settings.readings)
            );
        }
    }
    let mut text = format!(
        "# how every run in this folder was made (a sweep with other settings is refused here)\n\
         mapping_lag = {}\nvocabulary = {:?}\nloop_closing = {}\nmcor_cluster = {:?}\n",
        settings.mapping_lag,
        settings.vocabulary,
        settings.loop_closing,
        settings.mcor_cluster.name()
    );
    if !settings.synth_without.is_empty() {
        text += &format!("synth_without = {:?}\n", settings.synth_without);
    }
    if !settings.approximations.is_empty() {
        text += &format!("approximations = {:?}\n", settings.approximations);
    }
    if !settings.readings.is_empty() {
        text += &format!("readings = {:?}\n", settings.readings);
    }
    atomic_file::write(&path, text.as_bytes())
        .with_context(|| format!("writing {}", path.display()))
}

/// File name of the record of a shard (or of an unsharded sweep).
pub fn file_name(shard: Option<Shard>) -> String {
    match shard {
        None => "runs.csv".into(),
        Some(s) => format!("runs.shard-{}-of-{}.csv", s.index, s.count),
    }
}

fn header() -> String {
    let mut w = csv::WriterBuilder::new().from_writer(Vec::new());
    w.write_record([
        "sequence",
        "config",
        "tau_mf",
        "tau_gf",
        "tau_mg",
        "baseline",
        "seed",
        "ate_rmse",
        "failed",
        "frames",
        "tracked",
        "keyframes",
        "map_points",
        "mean_inliers",
        "mean_outliers",
        "fps",
        "wall_s",
        "synth_seed",
        "loops",
        "reason",
        "peak_rss_mb",
        "cpu_s",
        "perturbation",
        "perturb_family",
        "perturb_level",
        "perturb_seed",
    ])
    .expect("in-memory write");
    String::from_utf8(w.into_inner().expect("in-memory")).expect("ascii")
}

fn row(rec: &RunRecord) -> Result<String> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    w.serialize(rec)?;
    Ok(String::from_utf8(w.into_inner()?)?)
}

/// Reads the complete rows of a record file; a torn final line (no newline) is ignored and
/// reported by the returned flag.
pub fn read_records(path: &Path) -> Result<(Vec<RunRecord>, bool)> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let (complete, torn) = match text.rfind('\n') {
        Some(i) if i + 1 < text.len() => (&text[..=i], true),
        Some(_) => (&text[..], false),
        None => ("", !text.is_empty()),
    };
    let mut rdr = csv::ReaderBuilder::new().from_reader(complete.as_bytes());
    let mut out = Vec::new();
    for (i, r) in rdr.deserialize::<RunRecord>().enumerate() {
        let rec =
            r.with_context(|| format!("{}:{}: malformed run record", path.display(), i + 2))?;
        out.push(rec);
    }
    Ok((out, torn))
}

/// An open record file, shared by the parallel runs of a sweep.
pub struct RunStore {
    path: PathBuf,
    file: Mutex<File>,
    done: BTreeSet<String>,
    /// The advisory lock on the record file (released when the store is dropped or the
    /// process ends, however it ends).
    _lock: File,
}

impl Drop for RunStore {
    /// A sweep that ends leaves no lock file behind: it is removed while still held, so no
    /// other sweep can take a lock on the file being removed. (A sweep killed keeps its file;
    /// the lock itself is released by the system, and the next sweep takes it.)
    fn drop(&mut self) {
        let _ = std::fs::remove_file(self.path.with_extension("csv.lock"));
    }
}

/// Takes the advisory lock of record file `path` (`<file>.lock`, holding who took it): one
/// sweep at a time writes a record file, while the shards of one job array, each with its own
/// file, write side by side. A second sweep is refused with the holder's pid and command line.
fn lock(path: &Path) -> Result<File> {
    let lock_path = path.with_extension("csv.lock");
    let mut f = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&lock_path)
        .with_context(|| format!("opening {}", lock_path.display()))?;
    match f.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            let holder = human_holder(
                &std::fs::read_to_string(&lock_path).unwrap_or_default(),
                std::time::SystemTime::now(),
            );
            bail!(
                "another sweep is writing {} ({}): wait for it to finish, or use another --out \
                 folder (shards of one sweep, --shard K/N, each write their own file and run \
                 side by side)",
                path.display(),
                holder.trim()
            );
        }
        Err(std::fs::TryLockError::Error(e)) => {
            return Err(e).with_context(|| format!("locking {}", lock_path.display()))
        }
    }
    let who = format!(
        "pid {}, started {} s after the epoch: {}",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs()),
        std::env::args().collect::<Vec<_>>().join(" ")
    );
    f.set_len(0)?;
    f.write_all(who.as_bytes())?;
    f.flush()?;
    Ok(f)
}

/// The lock file's `started N s after the epoch` (as every version writes it) in a person's
/// time: `started 2026-11-27 10:41:03 UTC, 12 min ago`.
fn human_holder(holder: &str, now: std::time::SystemTime) -> String {
    const MARK: &str = " s after the epoch";
    let holder = holder.trim();
    let Some(end) = holder.find(MARK) else {
        return holder.to_string();
    };
    let start = holder[..end]
        .rfind(|c: char| !c.is_ascii_digit())
        .map_or(0, |i| i + 1);
    let Ok(secs) = holder[start..end].parse::<u64>() else {
        return holder.to_string();
    };
    let now = now
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    format!(
        "{}{}, {}{}",
        &holder[..start],
        utc_text(secs),
        ago_text(now.saturating_sub(secs)),
        &holder[end + MARK.len()..]
    )
}

/// `YYYY-MM-DD HH:MM:SS UTC` of a Unix time (the proleptic Gregorian calendar; H. Hinnant's
/// days-to-civil).
fn utc_text(secs: u64) -> String {
    let (days, rem) = ((secs / 86_400) as i64, secs % 86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02} {:02}:{:02}:{:02} UTC",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// How long `secs` is, roughly, in the largest unit that fits: `40 s ago`, `12 min ago`,
/// `3 h 5 min ago`, `2 days 4 h ago`.
fn ago_text(secs: u64) -> String {
    match secs {
        0..=119 => format!("{secs} s ago"),
        120..=3599 => format!("{} min ago", secs / 60),
        3600..=86_399 => format!("{} h {} min ago", secs / 3600, secs % 3600 / 60),
        _ => format!("{} days {} h ago", secs / 86_400, secs % 86_400 / 3600),
    }
}

impl RunStore {
    /// Opens (or creates) the record in `dir` for `shard`, repairing a torn last line.
    #[cfg(test)]
    pub fn open(dir: &Path, shard: Option<Shard>) -> Result<RunStore> {
        RunStore::open_dropping(dir, shard, |_| false)
    }

    /// Opens (or creates) the record in `dir` for `shard`, repairing a torn last line, first removing from this record file the runs `drop` picks, so
    /// they run again (`sweep --retry-failed`: the runs an external program failed, after its
    /// definition was fixed).
    pub fn open_dropping(
        dir: &Path,
        shard: Option<Shard>,
        drop: impl Fn(&RunRecord) -> bool,
    ) -> Result<RunStore> {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let path = dir.join(file_name(shard));
        let lock = lock(&path)?;
        let mut done = BTreeSet::new();
        if path.exists() {
            let (mut records, mut torn) = read_records(&path)?;
            let before = records.len();
            records.retain(|r| !drop(r));
            // Rewritten whole (atomically) when runs were dropped.
            torn |= records.len() != before;
            // A record from before a column was added gets the current header (rows re-written
            // with the new column empty), so appended rows match it.
            let old_header = std::fs::read_to_string(&path)
                .map(|t| !t.starts_with(&header()))
                .unwrap_or(false);
            if torn || old_header {
                let mut text = header();
                for r in &records {
                    text.push_str(&row(r)?);
                }
                atomic_file::write(&path, text.as_bytes())?;
            }
            done = records.iter().map(RunRecord::key).collect();
        } else {
            atomic_file::write(&path, header().as_bytes())?;
        }
        let file = OpenOptions::new()
            .append(true)
            .open(&path)
            .with_context(|| format!("opening {} for appending", path.display()))?;
        Ok(RunStore {
            path,
            file: Mutex::new(file),
            done,
            _lock: lock,
        })
    }

    /// Whether a run with this key is already recorded.
    pub fn is_done(&self, key: &str) -> bool {
        self.done.contains(key)
    }

    /// Number of recorded runs when the store was opened.
    #[cfg(test)]
    pub fn done_count(&self) -> usize {
        self.done.len()
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Appends one finished run: a single write of a whole row, then a flush to the disk.
    pub fn append(&self, rec: &RunRecord) -> Result<()> {
        let line = row(rec)?;
        let mut f = self.file.lock().unwrap_or_else(|e| e.into_inner());
        f.write_all(line.as_bytes())
            .with_context(|| format!("appending to {}", self.path.display()))?;
        f.sync_data()
            .with_context(|| format!("syncing {}", self.path.display()))?;
        Ok(())
    }
}

/// Every run recorded in `dir` (all `runs*.csv`: the unsharded record and every shard's),
/// merged, duplicates (the same key in two files) dropped, in key order.
pub fn load_dir(dir: &Path) -> Result<Vec<RunRecord>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .map(|n| n.starts_with("runs") && n.ends_with(".csv"))
                .unwrap_or(false)
        })
        .collect();
    files.sort();
    if files.is_empty() {
        bail!(
            "{}: no runs*.csv record (run `noisefree sweep --out {}` first)",
            dir.display(),
            dir.display()
        );
    }
    let mut by_key = std::collections::BTreeMap::new();
    for f in files {
        for r in read_records(&f)?.0 {
            by_key.entry(r.key()).or_insert(r);
        }
    }
    Ok(by_key.into_values().collect())
}

/// Whether a folder looks like a sweep output (has a runs*.csv).
pub fn is_sweep_dir(dir: &Path) -> bool {
    std::fs::read_dir(dir)
        .map(|it| {
            it.filter_map(|e| e.ok()).any(|e| {
                let n = e.file_name();
                let n = n.to_string_lossy();
                n.starts_with("runs") && n.ends_with(".csv")
            })
        })
        .unwrap_or(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(seq: &str, seed: u64) -> RunRecord {
        RunRecord {
            tau_mf: Some(0.7),
            tau_gf: Some(0.7),
            tau_mg: Some(0.5),
            keyframes: Some(10),
            map_points: Some(1000),
            mean_inliers: Some(300.5),
            mean_outliers: Some(10.25),
            fps: 80.0,
            wall_s: 1.25,
            synth_seed: Some(1),
            ..RunRecord::example(seq, "mcor", seed, 0.0123)
        }
    }

    fn tmpdir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("nf-store-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn append_reopen_and_skip() {
        let d = tmpdir("reopen");
        let s = RunStore::open(&d, None).unwrap();
        s.append(&rec("a", 0)).unwrap();
        s.append(&rec("a", 1)).unwrap();
        drop(s);
        let s = RunStore::open(&d, None).unwrap();
        assert!(s.is_done(&rec("a", 0).key()) && s.is_done(&rec("a", 1).key()));
        assert!(!s.is_done(&rec("a", 2).key()));
        let all = load_dir(&d).unwrap();
        assert_eq!(all, vec![rec("a", 0), rec("a", 1)]);
    }

    #[test]
    fn dropped_runs_leave_the_record_and_run_again() {
        let d = tmpdir("drop");
        let s = RunStore::open(&d, None).unwrap();
        let mut failed = rec("a", 1);
        failed.failed = true;
        failed.reason = Some("exit status 1".into());
        s.append(&rec("a", 0)).unwrap();
        s.append(&failed).unwrap();
        drop(s);
        let s = RunStore::open_dropping(&d, None, |r| r.reason.is_some()).unwrap();
        assert!(s.is_done(&rec("a", 0).key()));
        assert!(!s.is_done(&failed.key()), "a dropped run is not done");
        drop(s);
        assert_eq!(load_dir(&d).unwrap().len(), 1);
    }

    #[test]
    fn a_record_file_is_written_by_one_sweep_at_a_time() {
        let dir = tmpdir("lock");
        let first = RunStore::open(&dir, None).unwrap();
        let e = format!("{:#}", RunStore::open(&dir, None).err().unwrap());
        assert!(
            e.contains("another sweep") && e.contains(&format!("pid {}", std::process::id())),
            "{e}"
        );
        // Shards keep their own files and locks.
        let shard = RunStore::open(&dir, Some(Shard { index: 1, count: 2 })).unwrap();
        drop(first);
        RunStore::open(&dir, None).expect("free again once the first store is gone");
        drop(shard);
    }

    #[test]
    fn torn_last_line_is_dropped_on_open() {
        let d = tmpdir("torn");
        let s = RunStore::open(&d, None).unwrap();
        s.append(&rec("a", 0)).unwrap();
        drop(s);
        let p = d.join("runs.csv");
        let mut text = std::fs::read_to_string(&p).unwrap();
        text.push_str("a,mcor,0.7,0.7,0.5,,1,0.01");
        std::fs::write(&p, text).unwrap();
        let s = RunStore::open(&d, None).unwrap();
        assert_eq!(s.done_count(), 1);
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.ends_with('\n'));
        assert_eq!(text.lines().count(), 2);
    }

    #[test]
    fn shards_merge_without_duplicates() {
        let d = tmpdir("merge");
        let s1 = RunStore::open(&d, Some(Shard { index: 1, count: 2 })).unwrap();
        let s2 = RunStore::open(&d, Some(Shard { index: 2, count: 2 })).unwrap();
        s1.append(&rec("a", 0)).unwrap();
        s2.append(&rec("a", 1)).unwrap();
        s2.append(&rec("a", 0)).unwrap(); // the same run recorded twice
        assert_eq!(load_dir(&d).unwrap().len(), 2);
    }

    #[test]
    fn a_folder_pins_mcor_s_cluster_reading() {
        let d = tmpdir("pin-cluster");
        let s = RunStore::open(&d, None).unwrap();
        let every = FolderSettings {
            mapping_lag: 3,
            vocabulary: "v".into(),
            loop_closing: true,
            mcor_cluster: ClusterViews::EveryFrame,
            synth_without: Vec::new(),
            approximations: Vec::new(),
            readings: Vec::new(),
        };
        pin_settings(&d, &every).unwrap();
        assert_eq!(settings_of(&d).unwrap(), every);
        s.append(&rec("a", 0)).unwrap();
        drop(s);
        let keyframes = FolderSettings {
            mcor_cluster: ClusterViews::Keyframes,
            ..every.clone()
        };
        let e = format!("{:#}", pin_settings(&d, &keyframes).unwrap_err());
        assert!(e.contains("every-frame clusters"), "{e}");
        pin_settings(&d, &every).unwrap();
        // A folder from before the field: keyframe clusters.
        let old = tmpdir("pin-cluster-old");
        std::fs::create_dir_all(&old).unwrap();
        std::fs::write(
            old.join(SETTINGS_FILE),
            "mapping_lag = 3\nvocabulary = \"v\"\nloop_closing = true\n",
        )
        .unwrap();
        assert_eq!(settings_of(&old).unwrap(), keyframes);
        std::fs::write(old.join(SETTINGS_FILE), "mcor_cluster = \"often\"\n").unwrap();
        let e = format!("{:#}", settings_of(&old).unwrap_err());
        assert!(
            e.contains(SETTINGS_FILE) && e.contains("mcor_cluster"),
            "{e}"
        );
    }

    #[test]
    fn a_folder_pins_the_effects_switched_off_and_the_speed_approximations() {
        let cases = [
            (
                "synth_without",
                FolderSettings {
                    synth_without: vec!["blur".into(), "lens".into()],
                    ..FolderSettings::default()
                },
                ["--synth-without blur,lens", "every synthetic effect on"],
            ),
            (
                "approximations",
                FolderSettings {
                    approximations: vec!["mcor.view_stride = 2".into()],
                    ..FolderSettings::default()
                },
                [
                    "the approximations mcor.view_stride = 2",
                    "this sweep has the reference",
                ],
            ),
        ];
        for (key, pinned, says) in cases {
            let d = tmpdir(&format!("pin-{key}"));
            let s = RunStore::open(&d, None).unwrap();
            pin_settings(&d, &pinned).unwrap();
            assert_eq!(settings_of(&d).unwrap(), pinned);
            s.append(&rec("a", 0)).unwrap();
            drop(s);
            let plain = FolderSettings::default();
            let e = format!("{:#}", pin_settings(&d, &plain).unwrap_err());
            assert!(e.contains(says[0]) && e.contains(says[1]), "{e}");
            pin_settings(&d, &pinned).unwrap();
            // A folder with the list empty does not record the field, and reads back as such.
            let empty = tmpdir(&format!("pin-{key}-empty"));
            drop(RunStore::open(&empty, None).unwrap());
            pin_settings(&empty, &plain).unwrap();
            let text = std::fs::read_to_string(empty.join(SETTINGS_FILE)).unwrap();
            assert!(!text.contains(key), "{text}");
            assert_eq!(settings_of(&empty).unwrap(), plain);
            std::fs::write(empty.join(SETTINGS_FILE), format!("{key} = \"blur\"\n")).unwrap();
            let e = format!("{:#}", settings_of(&empty).unwrap_err());
            assert!(e.contains(key) && e.contains("is not a list"), "{e}");
        }
    }

    /// The lock's holder in a person's time (issue 44: "started 1795711463 s after the epoch").
    #[test]
    fn the_lock_holder_reads_in_utc_and_how_long_ago() {
        let at = std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_795_711_463 + 750);
        let t = human_holder(
            "pid 7, started 1795711463 s after the epoch: noisefree sweep --out x\n",
            at,
        );
        assert_eq!(
            t,
            "pid 7, started 2026-11-26 16:44:23 UTC, 12 min ago: noisefree sweep --out x"
        );
        assert_eq!(utc_text(0), "1970-01-01 00:00:00 UTC");
        assert_eq!(utc_text(951_782_400), "2000-02-29 00:00:00 UTC");
        assert_eq!(human_holder("garbage", at), "garbage");
    }
}
