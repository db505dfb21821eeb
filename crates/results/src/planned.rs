//! The runs a sweep folder was asked for: `planned-runs.txt`, one run key per line, the union
//! of every sweep (and every shard) into the folder. A sweep stops early for many reasons
//! (interrupted, `--max-runs`, a shard not yet run, a machine that went away mid-study); its
//! record then holds fewer runs than asked for, and tables made from it would look complete.
//! With the plan beside the record, the folder's index and the findings say what is missing.

use crate::store::RunRecord;
use anyhow::{Context, Result};
use atomic_file::write as write_atomic;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// File name of the plan in a sweep folder.
pub const PLANNED_FILE: &str = "planned-runs.txt";

/// First line of the plan file: what it is, for a reader who opens it.
const HEADER: &str =
    "# the runs this folder's sweeps were asked for (noisefree sweep), one run key \
                      per line: sequence|config|tau_mf|tau_gf|tau_mg|baseline|seed|synth_seed, \
                      then |p=perturbation|ps=draw";

/// Adds `keys` to the plan of folder `dir` (kept sorted, each key once; written to a temporary
/// file and renamed, so a reader never sees half a plan).
pub fn record_plan<I: IntoIterator<Item = String>>(dir: &Path, keys: I) -> Result<()> {
    let mut all = planned(dir)?.unwrap_or_default();
    let before = all.len();
    all.extend(keys);
    if all.len() == before && dir.join(PLANNED_FILE).is_file() {
        return Ok(());
    }
    let mut text = String::with_capacity(all.len() * 48 + HEADER.len() + 1);
    text.push_str(HEADER);
    text.push('\n');
    for k in &all {
        text.push_str(k);
        text.push('\n');
    }
    write_atomic(&dir.join(PLANNED_FILE), text.as_bytes())?;
    Ok(())
}

/// The plan of folder `dir`, or `None` when it has none (made before plans were recorded, or
/// not by a sweep).
pub fn planned(dir: &Path) -> Result<Option<BTreeSet<String>>> {
    let path = dir.join(PLANNED_FILE);
    if !path.is_file() {
        return Ok(None);
    }
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    Ok(Some(
        text.lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .map(str::to_owned)
            .collect(),
    ))
}

/// How much of a folder's plan its record holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Completeness {
    /// Runs planned.
    pub planned: usize,
    /// Planned runs that are recorded.
    pub recorded: usize,
    /// Planned runs not recorded, per sequence.
    pub missing: BTreeMap<String, usize>,
}

impl Completeness {
    /// Whether every planned run is recorded.
    pub fn is_complete(&self) -> bool {
        self.recorded == self.planned
    }

    /// One sentence for a reader: how many planned runs are recorded and which sequences lack
    /// runs (empty when complete).
    pub fn sentence(&self) -> String {
        if self.is_complete() {
            return String::new();
        }
        let missing: Vec<String> = self
            .missing
            .iter()
            .map(|(s, n)| format!("{s} {n}"))
            .collect();
        format!(
            "{} of {} planned runs recorded (missing: {})",
            self.recorded,
            self.planned,
            missing.join(", ")
        )
    }
}

/// How much of the plan of folder `dir` the `records` (the folder's, [`crate::store::load_dir`])
/// hold; `None` when the folder has no plan. Recorded runs outside the plan (copied in from
/// another folder, say) count for nothing either way.
pub fn completeness(dir: &Path, records: &[RunRecord]) -> Result<Option<Completeness>> {
    Ok(planned(dir)?.map(|plan| against(&plan, records)))
}

/// [`completeness`] of folder `dir` from its record files; `None` when it has no plan or no
/// record.
pub fn completeness_of(dir: &Path) -> Result<Option<Completeness>> {
    let Some(plan) = planned(dir)? else {
        return Ok(None);
    };
    if !crate::store::is_sweep_dir(dir) {
        return Ok(None);
    }
    let records = crate::store::load_dir(dir)?;
    Ok(Some(against(&plan, &records)))
}

/// How much of `plan` the `records` hold (a run key's sequence is its first field).
fn against(plan: &BTreeSet<String>, records: &[RunRecord]) -> Completeness {
    let done: BTreeSet<String> = records.iter().map(RunRecord::key).collect();
    let mut missing: BTreeMap<String, usize> = BTreeMap::new();
    for k in plan.iter().filter(|k| !done.contains(*k)) {
        let seq = k.split('|').next().unwrap_or_default();
        *missing.entry(seq.to_owned()).or_default() += 1;
    }
    let absent: usize = missing.values().sum();
    Completeness {
        planned: plan.len(),
        recorded: plan.len() - absent,
        missing,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("nf-planned-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn plans_of_two_sweeps_are_merged_and_read_back() {
        let d = scratch("merge");
        assert_eq!(planned(&d).unwrap(), None);
        record_plan(
            &d,
            ["b|orb||||0.09|1|".to_string(), "a|orb||||0.09|0|".into()],
        )
        .unwrap();
        record_plan(
            &d,
            ["a|orb||||0.09|0|".to_string(), "c|rc||||0.09|0|".into()],
        )
        .unwrap();
        let p = planned(&d).unwrap().unwrap();
        assert_eq!(
            p.into_iter().collect::<Vec<_>>(),
            ["a|orb||||0.09|0|", "b|orb||||0.09|1|", "c|rc||||0.09|0|"]
        );
        let text = std::fs::read_to_string(d.join(PLANNED_FILE)).unwrap();
        assert!(text.starts_with("# the runs"), "{text}");
        let _ = std::fs::remove_dir_all(&d);
    }
}
