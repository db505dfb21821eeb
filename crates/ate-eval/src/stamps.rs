//! What a reader does with stamps that repeat or go back in time.
//!
//! Real trajectory files are not always strictly ordered: the motion-capture ground truth of
//! several TUM RGB-D sequences repeats a stamp now and then (fr2_desk at line 10863), other SLAM
//! systems write repeated stamps, and some tools write out of order. The community tools score
//! such files, each in its own way, and so must we:
//! - `evaluate_ate.py` reads a file into a dictionary from stamp to pose: of repeated stamps the
//!   last line wins, and the order of the lines does not matter ([`StampPolicy::LastWins`]);
//! - `evo` keeps every line, repeated stamps included, and its binary-search association
//!   assumes time order ([`StampPolicy::KeepAll`]: sorted first, repeats kept);
//! - [`StampPolicy::Strict`] refuses anything but strictly increasing stamps, for users who want
//!   their files checked.
//!
//! Whatever was repaired is summed up in one [`Warning`] per file.

use crate::error::{Error, Result, Warning};
use crate::trajectory::Trajectory;
use nalgebra::Isometry3;
use std::path::Path;

/// How repeated and out-of-order stamps are treated when a trajectory is read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StampPolicy {
    /// As `evaluate_ate.py`: lines sorted by stamp, and of lines with the same stamp the last
    /// in the file is kept.
    #[default]
    LastWins,
    /// As `evo`: lines sorted by stamp (stably, so repeats stay in file order), every line kept.
    KeepAll,
    /// Stamps must strictly increase down the file; anything else is an error with its line.
    Strict,
}

impl StampPolicy {
    /// The policy of the tool whose association convention is `mode`, so that both halves of an
    /// evaluation (reading and pairing) reproduce the same tool.
    pub fn for_association(mode: crate::AssociationMode) -> StampPolicy {
        match mode {
            crate::AssociationMode::Tum => StampPolicy::LastWins,
            crate::AssociationMode::Evo => StampPolicy::KeepAll,
        }
    }
}

/// One pose line of a file, before ordering: its 1-based line number (in the file that holds
/// the stamp), stamp in seconds and pose.
#[derive(Clone, Debug)]
pub(crate) struct Row {
    pub line: usize,
    pub stamp: f64,
    pub pose: Isometry3<f64>,
}

/// Orders the rows of `path` by time under `policy`, returning the trajectory and, when
/// something was repaired, one warning saying what.
pub(crate) fn arrange(
    path: &Path,
    mut rows: Vec<Row>,
    policy: StampPolicy,
) -> Result<(Trajectory, Option<Warning>)> {
    // First line (file order) whose stamp is earlier than the line before it.
    let first_unsorted = rows
        .windows(2)
        .find(|w| w[1].stamp < w[0].stamp)
        .map(|w| w[1].line);
    if policy == StampPolicy::Strict {
        if let Some(w) = rows.windows(2).find(|w| w[1].stamp <= w[0].stamp) {
            return Err(Error::Unsorted {
                path: path.to_path_buf(),
                line: w[1].line,
                stamp: w[1].stamp,
                previous: w[0].stamp,
            });
        }
    }
    // Stable: lines with equal stamps stay in file order, so "last" means last in the file.
    rows.sort_by(|a, b| a.stamp.total_cmp(&b.stamp));
    let mut repeated = 0usize;
    let mut first_repeat: Option<usize> = None;
    let mut kept: Vec<Row> = Vec::with_capacity(rows.len());
    for row in rows {
        match kept.last_mut() {
            Some(prev) if prev.stamp == row.stamp => {
                repeated += 1;
                // Rows of one stamp are in file order, so this row is the repeating line.
                first_repeat = Some(first_repeat.map_or(row.line, |f| f.min(row.line)));
                if policy == StampPolicy::LastWins {
                    *prev = row;
                } else {
                    kept.push(row);
                }
            }
            _ => kept.push(row),
        }
    }
    let mut notes = Vec::new();
    if let Some(line) = first_unsorted {
        notes.push(format!(
            "stamps not in time order (first at line {line}), sorted"
        ));
    }
    if let Some(line) = first_repeat {
        let s = if repeated == 1 { "" } else { "s" };
        let what = match policy {
            StampPolicy::LastWins => "kept the last of each (as evaluate_ate.py)",
            _ => "kept every line (as evo)",
        };
        notes.push(format!(
            "{repeated} repeated stamp{s} (first at line {line}), {what}"
        ));
    }
    let warning = (!notes.is_empty()).then(|| Warning {
        path: path.to_path_buf(),
        line: None,
        message: notes.join("; "),
    });
    let mut traj = Trajectory::new();
    for row in kept {
        traj.push(row.stamp, row.pose);
    }
    Ok((traj, warning))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(stamps: &[(usize, f64)]) -> Vec<Row> {
        stamps
            .iter()
            .map(|&(line, stamp)| Row {
                line,
                stamp,
                pose: Isometry3::translation(line as f64, 0.0, 0.0),
            })
            .collect()
    }

    fn xs(t: &Trajectory) -> Vec<f64> {
        t.poses.iter().map(|p| p.translation.vector.x).collect()
    }

    #[test]
    fn sorted_unique_file_is_untouched_and_silent() {
        let r = rows(&[(1, 1.0), (2, 2.0), (3, 3.0)]);
        for policy in [
            StampPolicy::LastWins,
            StampPolicy::KeepAll,
            StampPolicy::Strict,
        ] {
            let (t, w) = arrange(Path::new("a.txt"), r.clone(), policy).unwrap();
            assert_eq!(t.stamps, vec![1.0, 2.0, 3.0]);
            assert!(w.is_none());
        }
    }

    #[test]
    fn last_wins_keeps_the_last_line_of_a_repeated_stamp_wherever_it_is() {
        // Lines 2 and 5 share stamp 2.0; line 5 comes last in the file and wins.
        let r = rows(&[(1, 1.0), (2, 2.0), (3, 3.0), (4, 0.5), (5, 2.0)]);
        let (t, w) = arrange(Path::new("gt.txt"), r, StampPolicy::LastWins).unwrap();
        assert_eq!(t.stamps, vec![0.5, 1.0, 2.0, 3.0]);
        assert_eq!(xs(&t), vec![4.0, 1.0, 5.0, 3.0]);
        let w = w.unwrap().to_string();
        assert_eq!(
            w,
            "gt.txt: stamps not in time order (first at line 4), sorted; \
             1 repeated stamp (first at line 5), kept the last of each (as evaluate_ate.py)"
        );
    }

    #[test]
    fn keep_all_sorts_stably_and_keeps_repeats_in_file_order() {
        let r = rows(&[(1, 2.0), (2, 1.0), (3, 2.0), (4, 2.0)]);
        let (t, w) = arrange(Path::new("est.txt"), r, StampPolicy::KeepAll).unwrap();
        assert_eq!(t.stamps, vec![1.0, 2.0, 2.0, 2.0]);
        assert_eq!(xs(&t), vec![2.0, 1.0, 3.0, 4.0]);
        let w = w.unwrap().message;
        assert!(w.contains("2 repeated stamps (first at line 3)"), "{w}");
        assert!(w.contains("kept every line"), "{w}");
    }

    #[test]
    fn strict_refuses_repeat_and_reversal_with_line() {
        for (r, line) in [
            (rows(&[(1, 1.0), (3, 1.0)]), 3),
            (rows(&[(1, 1.0), (2, 2.0), (7, 1.5)]), 7),
        ] {
            match arrange(Path::new("s.txt"), r, StampPolicy::Strict).unwrap_err() {
                Error::Unsorted { line: l, .. } => assert_eq!(l, line),
                e => panic!("{e:?}"),
            }
        }
    }
}
