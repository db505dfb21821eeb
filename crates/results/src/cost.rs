//! What a sweep cost, kept beside its runs: `cost.csv` (`cost.shard-K-of-N.csv` for a shard),
//! one line per finished point of every invocation with the runs it recorded, the frames they
//! were fed, and the CPU time of the whole process (rendering, reading, extraction, the runs)
//! and the wall time it took. A sweep resumed over several invocations, sessions or machines
//! thus keeps its whole cost, and `noisefree table` sums it in the folder's index: frames run
//! per CPU-second is the sweep's throughput per core even on a machine it shared.

use crate::keys::Shard;
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// One finished point of one invocation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CostRow {
    /// When the invocation started, Unix seconds to the nanosecond (whole seconds in records
    /// written before the nanoseconds were kept): the lines of one invocation share it, and it
    /// tells invocations apart. Kept as written, so an older record reads back unchanged.
    pub invocation: String,
    /// The point: a sequence, with its perturbation and draw when it has one.
    pub point: String,
    /// Runs recorded at this point.
    pub runs: usize,
    /// Frames fed to those runs.
    pub frames: usize,
    /// CPU seconds of the whole process since the previous line of the invocation (or its
    /// start).
    pub cpu_s: f64,
    /// Wall seconds over the same span.
    pub wall_s: f64,
}

/// File name of the cost record of a shard (or of an unsharded sweep). Not `runs*`: the run
/// records are every `runs*.csv` of a folder.
pub fn file_name(shard: Option<Shard>) -> String {
    match shard {
        None => "cost.csv".into(),
        Some(s) => format!("cost.shard-{}-of-{}.csv", s.index, s.count),
    }
}

/// Appends `row` to the cost record of `shard` in `dir`, writing the header first when the
/// file is new. One line per write, so a sweep stopped between points leaves whole lines.
pub fn append(dir: &Path, shard: Option<Shard>, row: &CostRow) -> Result<()> {
    let path = dir.join(file_name(shard));
    let new = !path.exists();
    let mut w = csv::WriterBuilder::new()
        .has_headers(new)
        .from_writer(Vec::new());
    w.serialize(row)?;
    let bytes = w.into_inner().context("formatting a cost line")?;
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .with_context(|| format!("opening {}", path.display()))?;
    f.write_all(&bytes)
        .with_context(|| format!("writing {}", path.display()))
}

/// Every cost line of `dir` (all `cost*.csv`), file by file; none when the folder has no
/// cost record (sweeps before the record existed). A line that does not parse is refused with
/// its file and line; a torn last line (a sweep killed while writing it) is skipped.
pub fn load_dir(dir: &Path) -> Result<Vec<CostRow>> {
    let mut files: Vec<PathBuf> = match std::fs::read_dir(dir) {
        Ok(it) => it
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("cost") && n.ends_with(".csv"))
            })
            .collect(),
        Err(_) => return Ok(Vec::new()),
    };
    files.sort();
    let mut out = Vec::new();
    for f in files {
        let text =
            std::fs::read_to_string(&f).with_context(|| format!("reading {}", f.display()))?;
        let whole = match text.rfind('\n') {
            Some(i) => &text[..=i],
            None => "",
        };
        let mut rdr = csv::Reader::from_reader(whole.as_bytes());
        for (i, row) in rdr.deserialize::<CostRow>().enumerate() {
            match row {
                Ok(r) => out.push(r),
                Err(e) => bail!("{} line {}: {e}", f.display(), i + 2),
            }
        }
    }
    Ok(out)
}

/// The sum of a folder's cost lines.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CostTotal {
    /// Invocations that recorded a line.
    pub invocations: usize,
    /// Runs covered.
    pub runs: usize,
    /// Frames fed to them.
    pub frames: usize,
    /// CPU seconds of the sweeps' processes.
    pub cpu_s: f64,
    /// Wall seconds, invocation by invocation (shards running side by side count each).
    pub wall_s: f64,
}

impl CostTotal {
    /// Sums `rows`.
    pub fn of(rows: &[CostRow]) -> CostTotal {
        let mut inv: Vec<&str> = rows.iter().map(|r| r.invocation.as_str()).collect();
        inv.sort_unstable();
        inv.dedup();
        CostTotal {
            invocations: inv.len(),
            runs: rows.iter().map(|r| r.runs).sum(),
            frames: rows.iter().map(|r| r.frames).sum(),
            cpu_s: rows.iter().map(|r| r.cpu_s).sum(),
            wall_s: rows.iter().map(|r| r.wall_s).sum(),
        }
    }

    /// Frames run per CPU-second: the sweep's throughput per core.
    pub fn frames_per_cpu_s(&self) -> f64 {
        self.frames as f64 / self.cpu_s.max(1e-9)
    }

    /// The index's sentence, `recorded` being the runs the folder holds.
    pub fn sentence(&self, recorded: usize) -> String {
        let covered = if self.runs == recorded {
            "every recorded run".to_string()
        } else {
            format!(
                "{} of the {recorded} recorded runs (the others ran before the sweep kept its cost)",
                self.runs
            )
        };
        format!(
            "Cost (`cost.csv`): {covered}, {} frames run in {:.0} CPU-s of the sweeps' processes \
             (rendering, reading, extraction and runs: {:.1} frames/s per core) and {} of wall \
             time, over {} invocation{}.",
            self.frames,
            self.cpu_s,
            self.frames_per_cpu_s(),
            hms(self.wall_s),
            self.invocations,
            if self.invocations == 1 { "" } else { "s" }
        )
    }
}

/// A duration in seconds as `12s`, `3m05s` or `2h04m09s`: how a sweep's progress and a
/// folder's costs print time.
pub fn hms(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    match (s / 3600, s / 60 % 60, s % 60) {
        (0, 0, sec) => format!("{sec}s"),
        (0, m, sec) => format!("{m}m{sec:02}s"),
        (h, m, sec) => format!("{h}h{m:02}m{sec:02}s"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh, empty folder of this test process.
    fn tmpdir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("nf-cost-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn row(invocation: &str, point: &str, frames: usize, cpu_s: f64) -> CostRow {
        CostRow {
            invocation: invocation.into(),
            point: point.into(),
            runs: 5,
            frames,
            cpu_s,
            wall_s: cpu_s / 2.0,
        }
    }

    #[test]
    fn lines_appended_by_two_invocations_read_back_and_sum() {
        let dir = tmpdir("sum");
        let rows = [
            row("10", "twin_a", 1000, 10.0),
            row("10", "twin_b [depth-axial:2]", 500, 2.5),
            row("20.000000001", "twin_c", 1500, 7.5),
        ];
        for r in &rows {
            append(dir.as_path(), None, r).unwrap();
        }
        let shard = Shard { index: 1, count: 2 };
        append(
            dir.as_path(),
            Some(shard),
            &row("20.000000002", "twin_d", 100, 1.0),
        )
        .unwrap();
        let back = load_dir(dir.as_path()).unwrap();
        assert_eq!(&back[..3], &rows[..]);
        assert_eq!(back.len(), 4);
        let t = CostTotal::of(&back);
        assert_eq!((t.invocations, t.runs, t.frames), (3, 20, 3100));
        assert!((t.frames_per_cpu_s() - 3100.0 / 21.0).abs() < 1e-9);
        assert!(
            t.sentence(20).contains("every recorded run"),
            "{}",
            t.sentence(20)
        );
        assert!(
            t.sentence(35).contains("20 of the 35"),
            "{}",
            t.sentence(35)
        );
    }

    #[test]
    fn a_torn_last_line_is_skipped_and_a_bad_line_refused_with_its_place() {
        let dir = tmpdir("torn");
        append(dir.as_path(), None, &row("1", "a", 10, 1.0)).unwrap();
        let path = dir.as_path().join("cost.csv");
        let mut text = std::fs::read_to_string(&path).unwrap();
        text.push_str("1,b,5,1");
        std::fs::write(&path, &text).unwrap();
        assert_eq!(load_dir(dir.as_path()).unwrap().len(), 1);
        text.push_str("0,x\n1,c,five,10,1.0,0.5\n");
        std::fs::write(&path, &text).unwrap();
        let e = load_dir(dir.as_path()).unwrap_err().to_string();
        assert!(e.contains("cost.csv line 3"), "{e}");
    }

    #[test]
    fn a_folder_without_a_cost_record_has_no_lines() {
        let dir = tmpdir("none");
        assert!(load_dir(dir.as_path()).unwrap().is_empty());
        assert!(load_dir(&dir.as_path().join("missing")).unwrap().is_empty());
    }
}
