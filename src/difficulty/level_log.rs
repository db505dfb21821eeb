//! `levels.jsonl`: every level a match has measured, written as each one ends, so a match that
//! stops (a killed process, a session's end, a target out of reach) loses no finished level,
//! and a later match into the same folder with the same setup reuses them. A level's runs
//! depend on the sequence, the chain, the level, the number of runs, the perturbation seed,
//! the system's configuration and the vocabulary, not on the target, the tolerance or the
//! range; so a second match towards another target measures only the levels it has not seen.
//!
//! The first line is the setup (a JSON object); each further line one level, its numbers as
//! text in Rust's shortest round-trip form, so a reused level is bit-identical to the
//! measured one. A line cut short by a killed process is ignored; a file written for another
//! setup is started afresh.

use super::{median_with_failures, LevelOutcome};
use anyhow::{Context, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The file's name inside a match's output folder.
pub const FILE_NAME: &str = "levels.jsonl";

/// The levels measured so far under one setup, and the file they are appended to.
pub struct LevelLog {
    path: PathBuf,
    recorded: Vec<LevelOutcome>,
}

/// What opening a log found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Found {
    /// No log in the folder.
    Nothing,
    /// A log of this setup, with this many levels.
    Levels(usize),
    /// A log of another setup (another sequence, chain, number of runs, seed or
    /// configuration), set aside: its levels cannot be reused.
    OtherSetup,
}

impl LevelLog {
    /// Opens `dir/levels.jsonl` for `setup`: its levels when it was written for the same
    /// setup, otherwise a new file (an existing one of another setup is replaced).
    pub fn open(dir: &Path, setup: &serde_json::Value) -> Result<(Self, Found)> {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let path = dir.join(FILE_NAME);
        let (recorded, found) = match std::fs::read_to_string(&path) {
            Ok(text) => match read(&text, setup) {
                Some(levels) => {
                    let n = levels.len();
                    (levels, Found::Levels(n))
                }
                None => (Vec::new(), Found::OtherSetup),
            },
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => (Vec::new(), Found::Nothing),
            Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
        };
        let log = LevelLog { path, recorded };
        log.rewrite(setup)?;
        Ok((log, found))
    }

    /// The level measured before, if it was.
    pub fn recorded(&self, level: f64) -> Option<&LevelOutcome> {
        self.recorded.iter().find(|o| o.level == level)
    }

    /// Appends a level just measured (flushed to disk before this returns).
    pub fn record(&mut self, outcome: &LevelOutcome) -> Result<()> {
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(&self.path)
            .with_context(|| format!("opening {}", self.path.display()))?;
        let line = level_line(outcome);
        f.write_all(line.as_bytes())
            .and_then(|_| f.sync_data())
            .with_context(|| format!("writing {}", self.path.display()))?;
        self.recorded.push(outcome.clone());
        Ok(())
    }

    /// Writes the setup line and the levels kept (dropping a torn last line, or another
    /// setup's levels), through a temporary file renamed into place.
    fn rewrite(&self, setup: &serde_json::Value) -> Result<()> {
        let mut text = serde_json::to_string(setup)?;
        text.push('\n');
        for o in &self.recorded {
            text.push_str(&level_line(o));
        }
        atomic_file::write(&self.path, text.as_bytes())
            .with_context(|| format!("writing {}", self.path.display()))
    }
}

/// One level's line: `{"level":"0.8125","ates":["0.0123…",null,…]}`.
fn level_line(o: &LevelOutcome) -> String {
    let ates: Vec<serde_json::Value> = o
        .ates
        .iter()
        .map(|a| match a {
            Some(v) => serde_json::Value::String(v.to_string()),
            None => serde_json::Value::Null,
        })
        .collect();
    let mut line = serde_json::json!({ "level": o.level.to_string(), "ates": ates }).to_string();
    line.push('\n');
    line
}

/// The levels of `text` when its first line is `setup` (compared as written, so no number
/// goes through a parser); `None` for another setup or no setup line. Lines that do not parse
/// (a torn last line) are skipped.
fn read(text: &str, setup: &serde_json::Value) -> Option<Vec<LevelOutcome>> {
    let mut lines = text.split_inclusive('\n');
    if lines.next()?.trim_end() != serde_json::to_string(setup).ok()? {
        return None;
    }
    let number = |v: &serde_json::Value| v.as_str().and_then(|s| s.parse::<f64>().ok());
    let levels = lines
        .filter(|l| l.ends_with('\n'))
        .filter_map(|l| {
            let v: serde_json::Value = serde_json::from_str(l.trim_end()).ok()?;
            let level = number(&v["level"])?;
            let ates = v["ates"]
                .as_array()?
                .iter()
                .map(|a| {
                    if a.is_null() {
                        Some(None)
                    } else {
                        number(a).map(Some)
                    }
                })
                .collect::<Option<Vec<Option<f64>>>>()?;
            let median = median_with_failures(&ates);
            Some(LevelOutcome {
                level,
                ates,
                median,
            })
        })
        .collect();
    Some(levels)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outcome(level: f64, ates: Vec<Option<f64>>) -> LevelOutcome {
        let median = median_with_failures(&ates);
        LevelOutcome {
            level,
            ates,
            median,
        }
    }

    #[test]
    fn levels_come_back_bit_for_bit_and_only_for_their_setup() {
        let dir = std::env::temp_dir().join(format!("nf-level-log-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let setup = serde_json::json!({"sequence": "kinect", "runs": 3});
        let (mut log, found) = LevelLog::open(&dir, &setup).unwrap();
        assert_eq!(found, Found::Nothing);
        // Values whose shortest decimal form is long: they must survive exactly.
        let a = outcome(0.0, vec![Some(0.1 + 0.2), None, Some(1.0 / 3.0)]);
        let b = outcome(
            2.5,
            vec![Some(f64::MIN_POSITIVE), Some(0.022_999_999_999_999_9), None],
        );
        log.record(&a).unwrap();
        log.record(&b).unwrap();
        // A process killed while writing leaves a torn line: it is dropped, the rest kept.
        let path = dir.join(FILE_NAME);
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .unwrap();
        f.write_all(br#"{"level":"4","ates":["0.0"#).unwrap();
        drop(f);

        let (log, found) = LevelLog::open(&dir, &setup).unwrap();
        assert_eq!(found, Found::Levels(2));
        assert_eq!(log.recorded(0.0), Some(&a));
        let back = log.recorded(2.5).unwrap();
        for (x, y) in back.ates.iter().zip(&b.ates) {
            assert_eq!(x.map(f64::to_bits), y.map(f64::to_bits));
        }
        assert!(log.recorded(4.0).is_none());
        // The torn line is gone from the file: the next append starts on a line of its own.
        assert!(!std::fs::read_to_string(&path).unwrap().contains("\"4\""));

        // Another setup reuses nothing and replaces the file.
        let other = serde_json::json!({"sequence": "kinect", "runs": 4});
        let (log, found) = LevelLog::open(&dir, &other).unwrap();
        assert_eq!(found, Found::OtherSetup);
        assert!(log.recorded(0.0).is_none());
        let (_, found) = LevelLog::open(&dir, &setup).unwrap();
        assert_eq!(found, Found::OtherSetup);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
