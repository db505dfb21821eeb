//! Runs that are one run: the cells of a sweep (sequence, configuration, parameters,
//! perturbation point) whose several seeded runs all gave the same result. A synchronous run is
//! deterministic and its seed only reaches relocalization's RANSAC, so without a source of
//! run-to-run spread (`--mapping-lag`, `--vary-sequence`, per-run perturbation draws) n runs
//! of a cell are usually one; a table's `± 0.000` and an untested comparison then say so.

use crate::store::RunRecord;
use std::collections::BTreeMap;

/// What a cell's runs share, as a printable key.
fn cell(r: &RunRecord) -> String {
    let mut key = format!("{} {}", r.sequence, r.config);
    if let (Some(a), Some(b), Some(c)) = (r.tau_mf, r.tau_gf, r.tau_mg) {
        key += &format!(" tau {a}/{b}/{c}");
    }
    if let Some(b) = r.baseline {
        key += &format!(" b {b}");
    }
    if let Some(p) = r.perturbation.as_deref().filter(|p| !p.is_empty()) {
        key += &format!(" under {p}");
    }
    key
}

/// The cells of `records` with more than one run and at least one ATE, and of those the cells
/// whose runs all gave the same ATE bit for bit, in cell order (a cell whose runs all failed
/// has no spread to speak of).
pub fn identical_cells(records: &[RunRecord]) -> (usize, Vec<String>) {
    let mut cells: BTreeMap<String, Vec<&RunRecord>> = BTreeMap::new();
    for r in records {
        cells.entry(cell(r)).or_default().push(r);
    }
    // Cells without any ATE (every run failed, or nothing to score) have no spread to speak of.
    let several: Vec<(&String, &Vec<&RunRecord>)> = cells
        .iter()
        .filter(|(_, runs)| runs.len() > 1)
        .filter(|(_, runs)| runs.iter().any(|r| r.ate_rmse.is_some()))
        .collect();
    let identical = several
        .iter()
        .filter(|(_, runs)| {
            let first = (runs[0].ate_rmse.map(f64::to_bits), runs[0].failed);
            runs.iter()
                .all(|r| (r.ate_rmse.map(f64::to_bits), r.failed) == first)
        })
        .map(|(k, _)| (*k).clone())
        .collect();
    (several.len(), identical)
}

/// What a sweep says at its end about cells whose runs are one run; `None` when there are none.
pub fn identical_note(records: &[RunRecord]) -> Option<String> {
    let (several, identical) = identical_cells(records);
    if identical.is_empty() {
        return None;
    }
    let shown: Vec<&str> = identical.iter().take(3).map(String::as_str).collect();
    Some(format!(
        "note: in {} of the {several} cells with several runs every run gave the same result \
         ({}{}): a synchronous run is deterministic and its seed only reaches relocalization's \
         RANSAC, so those runs are one. --mapping-lag 3 emulates ORB-SLAM2's thread timing (runs \
         spread as ORB-SLAM2's do); --vary-sequence gives each run of a synthetic sequence its \
         own realization; per-run perturbation draws vary too.",
        identical.len(),
        shown.join("; "),
        if identical.len() > shown.len() {
            "; ..."
        } else {
            ""
        }
    ))
}

/// What a sweep says at its end about runs without a result: failed runs counted by
/// configuration and reason, and runs with no ATE because their sequence has no ground truth
/// (not failures); `None` when every run has an ATE.
pub fn failures_note(records: &[RunRecord]) -> Option<String> {
    let mut reasons: BTreeMap<(String, String), usize> = BTreeMap::new();
    for r in records.iter().filter(|r| r.failed) {
        let why = r
            .reason
            .clone()
            .unwrap_or_else(|| "fewer than 80 % of the frames tracked".into());
        *reasons.entry((r.config.clone(), why)).or_default() += 1;
    }
    let no_truth = records
        .iter()
        .filter(|r| !r.failed && r.ate_rmse.is_none())
        .count();
    if reasons.is_empty() && no_truth == 0 {
        return None;
    }
    let mut parts = Vec::new();
    if !reasons.is_empty() {
        let failed: usize = reasons.values().sum();
        let list: Vec<String> = reasons
            .iter()
            .map(|((config, why), n)| format!("{n} {config}: {why}"))
            .collect();
        parts.push(format!(
            "{failed} of the folder's {} runs failed ({})",
            records.len(),
            list.join("; ")
        ));
    }
    if no_truth > 0 {
        parts.push(format!(
            "{no_truth} ran without an ATE: their sequence has no ground truth (not a failure)"
        ));
    }
    Some(format!("note: {}.", parts.join("; ")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_whose_runs_agree_to_the_bit_are_named_and_spread_ones_are_not() {
        let run = |seq: &str, seed: u64, ate: f64| RunRecord::example(seq, "orb", seed, ate);
        let records = [
            run("kinect", 0, 0.01),
            run("kinect", 1, 0.01),
            run("walking", 0, 0.2),
            run("walking", 1, 0.3),
            run("clean", 0, 0.001),
        ];
        let (several, identical) = identical_cells(&records);
        assert_eq!(several, 2);
        assert_eq!(identical, ["kinect orb"]);
        let note = identical_note(&records).unwrap();
        assert!(note.contains("in 1 of the 2 cells") && note.contains("--mapping-lag 3"));
        assert!(identical_note(&records[2..]).is_none());
        // A cell whose runs all failed is not "identical": it has no ATE to agree on.
        let failed = |seed: u64| RunRecord {
            failed: true,
            ate_rmse: None,
            ..RunRecord::example("kinect", "bad", seed, 0.0)
        };
        let with_failures = [records.to_vec(), vec![failed(0), failed(1)]].concat();
        assert_eq!(
            identical_cells(&with_failures),
            (2, vec!["kinect orb".into()])
        );
    }

    #[test]
    fn failures_are_counted_by_reason_and_a_missing_ground_truth_kept_apart() {
        let mut failed = RunRecord::example("kinect", "orb", 0, 0.01);
        failed.failed = true;
        let mut crashed = RunRecord::example("kinect", "myslam", 0, 0.01);
        (crashed.failed, crashed.reason) = (true, Some("exit status 3".into()));
        let mut no_truth = RunRecord::example("mine", "orb", 0, 0.01);
        no_truth.ate_rmse = None;
        let ok = RunRecord::example("kinect", "orb", 1, 0.01);
        let note = failures_note(&[failed, crashed, no_truth, ok.clone()]).unwrap();
        assert!(note.contains("2 of the folder's 4 runs failed"), "{note}");
        assert!(note.contains("1 myslam: exit status 3"), "{note}");
        assert!(
            note.contains("1 orb: fewer than 80 % of the frames tracked"),
            "{note}"
        );
        assert!(note.contains("1 ran without an ATE: their sequence has no ground truth"));
        assert!(failures_note(&[ok]).is_none());
    }
}
