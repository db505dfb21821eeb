//! The golden file of the regression suite (`tests/golden/regression.toml`): per case the
//! figures of the last accepted run, the tolerances they may move within, and the spread those
//! tolerances were derived from; the comparison of a new run against it, and the old-vs-new
//! table a reviewer reads.
//!
//! Tolerances come from measurement, not from a guess: `noisefree regress --update --spread K`
//! reruns every case K more times with the camera's focal length perturbed in its 12th
//! significant digit, which changes nothing physical but flips floating-point roundings the way
//! a benign code change (another summation order) or another machine's libm (1-ulp differences
//! in sin / exp) does; the chaotic growth of such flips over a run is the spread a figure shows
//! without any real change. A figure may move by [`SPREAD_FACTOR`] times the largest deviation
//! seen, and never less than the floors below.

use super::cases::{Case, Figures};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// Tolerance = this many times the largest deviation seen under perturbation.
pub const SPREAD_FACTOR: f64 = 3.0;
/// Smallest ATE tolerance, relative to the golden ATE: below this a change is not worth a
/// reviewer's time even where the perturbed runs happened to agree closely.
pub const ATE_REL_FLOOR: f64 = 0.10;
/// Smallest ATE tolerance in metres (0.1 mm): the resolution below which ATE on these short
/// synthetic sequences says nothing.
pub const ATE_ABS_FLOOR_M: f64 = 1e-4;
/// Smallest tolerance of the keyframe and map-point counts, relative to the golden count.
pub const COUNT_REL_FLOOR: f64 = 0.05;

/// How far each figure of a case may move.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Tolerance {
    /// ATE RMSE, metres either way.
    pub ate_tol_m: f64,
    /// Tracked frames, either way.
    pub tracked_tol: usize,
    /// Keyframes, either way.
    pub keyframes_tol: usize,
    /// Map points, either way.
    pub map_points_tol: usize,
    /// Relocalizations, either way.
    pub relocalizations_tol: usize,
    /// Loops closed, either way. (absent in golden files from before loop closing: 0)
    #[serde(default)]
    pub loops_tol: usize,
}

/// The largest deviation from the golden figures seen over the perturbed reruns.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// Number of perturbed reruns.
    pub spread_runs: usize,
    /// Largest |ATE - golden ATE|, metres (a rerun without ATE counts as the golden ATE itself).
    pub spread_ate_m: f64,
    /// Largest |tracked - golden|.
    pub spread_tracked: usize,
    /// Largest |keyframes - golden|.
    pub spread_keyframes: usize,
    /// Largest |map points - golden|.
    pub spread_map_points: usize,
    /// Largest |relocalizations - golden|.
    pub spread_relocalizations: usize,
    /// Largest |loops - golden|. (absent in golden files from before loop closing: 0)
    #[serde(default)]
    pub spread_loops: usize,
    /// Perturbed reruns whose trajectory hash differs from the golden one (0 would mean the
    /// perturbation did not reach the run at all).
    pub spread_changed_hashes: usize,
}

impl Spread {
    /// The spread of `reruns` around `base`.
    pub fn measure(base: &Figures, reruns: &[Figures]) -> Spread {
        let d = |a: usize, b: usize| a.abs_diff(b);
        let mut s = Spread {
            spread_runs: reruns.len(),
            ..Spread::default()
        };
        for r in reruns {
            if let (Some(a), Some(b)) = (base.ate_m, r.ate_m) {
                s.spread_ate_m = s.spread_ate_m.max((a - b).abs());
            } else if let (Some(a), None) = (base.ate_m, r.ate_m) {
                s.spread_ate_m = s.spread_ate_m.max(a);
            }
            s.spread_tracked = s.spread_tracked.max(d(base.tracked, r.tracked));
            s.spread_keyframes = s.spread_keyframes.max(d(base.keyframes, r.keyframes));
            s.spread_map_points = s.spread_map_points.max(d(base.map_points, r.map_points));
            s.spread_relocalizations = s
                .spread_relocalizations
                .max(d(base.relocalizations, r.relocalizations));
            s.spread_loops = s.spread_loops.max(d(base.loops, r.loops));
            s.spread_changed_hashes += usize::from(r.hash != base.hash);
        }
        s
    }

    /// The tolerances this spread justifies around `base`.
    pub fn tolerance(&self, base: &Figures) -> Tolerance {
        let count = |spread: usize, value: usize, rel_floor: f64| {
            let from_spread = (SPREAD_FACTOR * spread as f64).ceil();
            let floor = (rel_floor * value as f64).ceil().max(1.0);
            from_spread.max(floor) as usize
        };
        let ate = base.ate_m.unwrap_or(0.0);
        Tolerance {
            ate_tol_m: (SPREAD_FACTOR * self.spread_ate_m)
                .max(ATE_REL_FLOOR * ate)
                .max(ATE_ABS_FLOOR_M),
            tracked_tol: count(self.spread_tracked, 0, 0.0),
            keyframes_tol: count(self.spread_keyframes, base.keyframes, COUNT_REL_FLOOR),
            map_points_tol: count(self.spread_map_points, base.map_points, COUNT_REL_FLOOR),
            relocalizations_tol: count(self.spread_relocalizations, 0, 0.0),
            loops_tol: count(self.spread_loops, 0, 0.0),
        }
    }
}

/// One case of the golden file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GoldenCase {
    /// `preset/config`.
    pub name: String,
    /// Frames of the sequence (a changed suite definition is caught, not compared blindly).
    pub frames: usize,
    /// The accepted figures.
    #[serde(flatten)]
    pub figures: Figures,
    /// How far they may move.
    #[serde(flatten)]
    pub tolerance: Tolerance,
    /// The spread the tolerances come from.
    #[serde(flatten)]
    pub spread: Spread,
}

/// The golden file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Golden {
    /// Every case, in suite order.
    #[serde(rename = "case")]
    pub cases: Vec<GoldenCase>,
}

const HEADER: &str = "\
# Golden figures of the regression suite: `noisefree regress` (run by `cargo test`, see
# tests/regression.rs) compares every case against this file and fails when a figure moves
# beyond its tolerance. Regenerate with `make golden` only for an intended change of behaviour,
# and put the old and new figures (the table `noisefree regress` prints) in the commit message.
# Tolerances: the largest deviation over `spread_runs` reruns with the focal length perturbed in
# its 12th digit (floating-point roundings, as a benign code change or another machine's libm
# flips them) times 3, floored at 10 % / 0.1 mm of ATE and 5 % of keyframe / map-point counts.
";

impl Golden {
    /// Reads the golden file.
    pub fn read(path: &Path) -> Result<Golden> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("reading golden file {}", path.display()))?;
        toml::from_str(&text).with_context(|| format!("{}: not a golden file", path.display()))
    }

    /// Writes the golden file atomically, with its explanatory header.
    pub fn write(&self, path: &Path) -> Result<()> {
        let body = toml::to_string(self).context("serialising the golden file")?;
        atomic_file::write(path, format!("{HEADER}\n{body}").as_bytes())?;
        Ok(())
    }

    /// The case named `name`.
    pub fn case(&self, name: &str) -> Option<&GoldenCase> {
        self.cases.iter().find(|c| c.name == name)
    }
}

/// How one case compares with the golden file.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// Bit-identical trajectory.
    Same,
    /// Every figure within tolerance, but the trajectory changed (reported, not failed).
    Moved,
    /// A figure moved beyond its tolerance: the reasons.
    Failed(Vec<String>),
    /// The golden file has no such case (or a different frame count): regenerate it.
    Unknown(String),
}

impl Verdict {
    /// Whether this verdict fails the suite.
    pub fn fails(&self) -> bool {
        matches!(self, Verdict::Failed(_) | Verdict::Unknown(_))
    }
}

/// One row of the comparison.
#[derive(Clone, Debug)]
pub struct Row {
    /// Case name.
    pub name: String,
    /// Golden entry, when there is one.
    pub old: Option<GoldenCase>,
    /// This run's figures.
    pub new: Figures,
    /// The verdict.
    pub verdict: Verdict,
}

fn judge(old: &GoldenCase, new: &Figures) -> Verdict {
    let t = &old.tolerance;
    let o = &old.figures;
    let mut why = Vec::new();
    match (o.ate_m, new.ate_m) {
        (Some(a), Some(b)) if (b - a).abs() > t.ate_tol_m => why.push(format!(
            "ATE {} by {:.2} mm (tolerance {:.2} mm)",
            if b > a { "worse" } else { "better" },
            (b - a).abs() * 1e3,
            t.ate_tol_m * 1e3
        )),
        (Some(_), None) => why.push("no ATE any more".into()),
        (None, Some(_)) => why.push("an ATE where there was none".into()),
        _ => {}
    }
    let mut count = |what: &str, a: usize, b: usize, tol: usize| {
        if a.abs_diff(b) > tol {
            why.push(format!("{what} {a} -> {b} (tolerance {tol})"));
        }
    };
    count("tracked", o.tracked, new.tracked, t.tracked_tol);
    count("keyframes", o.keyframes, new.keyframes, t.keyframes_tol);
    count("map points", o.map_points, new.map_points, t.map_points_tol);
    count(
        "relocalizations",
        o.relocalizations,
        new.relocalizations,
        t.relocalizations_tol,
    );
    count("loops", o.loops, new.loops, t.loops_tol);
    if !why.is_empty() {
        Verdict::Failed(why)
    } else if new.hash != o.hash {
        Verdict::Moved
    } else {
        Verdict::Same
    }
}

/// Compares this run's figures with the golden file, case by case (suite order).
pub fn compare(golden: &Golden, results: &[(Case, Figures)]) -> Vec<Row> {
    results
        .iter()
        .map(|(case, new)| {
            let name = case.name();
            let old = golden.case(&name).cloned();
            let verdict = match &old {
                None => Verdict::Unknown("not in the golden file".into()),
                Some(g) if g.frames != case.sequence.frames => Verdict::Unknown(format!(
                    "golden has {} frames, the suite {}",
                    g.frames, case.sequence.frames
                )),
                Some(g) => judge(g, new),
            };
            Row {
                name,
                old,
                new: new.clone(),
                verdict,
            }
        })
        .collect()
}

/// Golden cases that the suite no longer has (a stale golden file fails too).
pub fn stale_cases(golden: &Golden, results: &[(Case, Figures)]) -> Vec<String> {
    golden
        .cases
        .iter()
        .filter(|g| !results.iter().any(|(c, _)| c.name() == g.name))
        .map(|g| g.name.clone())
        .collect()
}

fn ate_mm(a: Option<f64>) -> String {
    a.map_or("-".into(), |x| format!("{:.3}", x * 1e3))
}

fn counts(f: &Figures) -> String {
    format!(
        "{}/{}/{}/{}/{}",
        f.tracked, f.keyframes, f.map_points, f.relocalizations, f.loops
    )
}

/// The old-vs-new table: one line per case, then the reasons of every failure.
pub fn table(rows: &[Row]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<20} {:>10} {:>10} {:>8}  {:<20} {:<20} {:<6} verdict",
        "case", "ATE mm", "golden", "tol", "trk/kf/mp/rel/loop", "golden", "hash"
    );
    for r in rows {
        let (old_ate, tol, old_counts) = match &r.old {
            Some(g) => (
                ate_mm(g.figures.ate_m),
                format!("{:.3}", g.tolerance.ate_tol_m * 1e3),
                counts(&g.figures),
            ),
            None => ("-".into(), "-".into(), "-".into()),
        };
        let hash = match &r.old {
            Some(g) if g.figures.hash == r.new.hash => "same",
            Some(_) => "CHANGED",
            None => "-",
        };
        let verdict = match &r.verdict {
            Verdict::Same => "ok".to_string(),
            Verdict::Moved => "ok (behaviour changed within tolerance)".to_string(),
            Verdict::Failed(_) => "FAIL".to_string(),
            Verdict::Unknown(why) => format!("FAIL ({why})"),
        };
        let _ = writeln!(
            s,
            "{:<20} {:>10} {:>10} {:>8}  {:<20} {:<20} {:<6} {}",
            r.name,
            ate_mm(r.new.ate_m),
            old_ate,
            tol,
            counts(&r.new),
            old_counts,
            hash,
            verdict
        );
    }
    for r in rows {
        if let Verdict::Failed(why) = &r.verdict {
            let _ = writeln!(s, "{}: {}", r.name, why.join("; "));
        }
    }
    s
}

/// Fails with the table when any row fails or the golden file has cases the suite lost.
pub fn verdict(rows: &[Row], stale: &[String]) -> Result<()> {
    let failed: Vec<&str> = rows
        .iter()
        .filter(|r| r.verdict.fails())
        .map(|r| r.name.as_str())
        .collect();
    if !failed.is_empty() || !stale.is_empty() {
        let mut msg = String::new();
        if !failed.is_empty() {
            msg.push_str(&format!(
                "{} of {} regression cases moved beyond tolerance: {}",
                failed.len(),
                rows.len(),
                failed.join(", ")
            ));
        }
        if !stale.is_empty() {
            if !msg.is_empty() {
                msg.push_str("; ");
            }
            msg.push_str(&format!(
                "the golden file has cases the suite lacks: {}",
                stale.join(", ")
            ));
        }
        bail!("{msg}. If the change is intended, run `make golden` and cite the table above in the commit message");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regress::cases::all_cases;

    fn figures(ate: f64, kf: usize, hash: &str) -> Figures {
        Figures {
            ate_m: Some(ate),
            tracked: 150,
            keyframes: kf,
            map_points: 1200,
            relocalizations: 0,
            loops: 0,
            hash: hash.into(),
        }
    }

    fn golden_for(case: &Case, f: Figures, spread: Spread) -> GoldenCase {
        GoldenCase {
            name: case.name(),
            frames: case.sequence.frames,
            tolerance: spread.tolerance(&f),
            figures: f,
            spread,
        }
    }

    #[test]
    fn tolerance_is_three_spreads_with_floors() {
        let base = figures(0.002, 20, "a");
        let s = Spread {
            spread_runs: 6,
            spread_ate_m: 0.0005,
            spread_keyframes: 2,
            ..Spread::default()
        };
        let t = s.tolerance(&base);
        assert!((t.ate_tol_m - 0.0015).abs() < 1e-12);
        assert_eq!(t.keyframes_tol, 6);
        // Map points did not move: the 5 % floor (60 of 1200).
        assert_eq!(t.map_points_tol, 60);
        assert_eq!(t.tracked_tol, 1);
        // A quiet case gets the relative ATE floor.
        let t = Spread::default().tolerance(&figures(0.05, 20, "a"));
        assert!((t.ate_tol_m - 0.005).abs() < 1e-12);
    }

    #[test]
    fn worse_ate_fails_with_a_readable_table_and_same_hash_passes() {
        let case = all_cases()[0];
        let golden = Golden {
            cases: vec![golden_for(
                &case,
                figures(0.001, 10, "h1"),
                Spread::default(),
            )],
        };
        let rows = compare(&golden, &[(case, figures(0.001, 10, "h1"))]);
        assert_eq!(rows[0].verdict, Verdict::Same);
        let rows = compare(&golden, &[(case, figures(0.00105, 10, "h2"))]);
        assert_eq!(rows[0].verdict, Verdict::Moved);
        assert!(verdict(&rows, &[]).is_ok());
        let rows = compare(&golden, &[(case, figures(0.010, 13, "h3"))]);
        assert!(rows[0].verdict.fails());
        let t = table(&rows);
        assert!(t.contains("kinect/orb"), "{t}");
        assert!(t.contains("CHANGED"), "{t}");
        assert!(
            t.contains("ATE worse by 9.00 mm (tolerance 0.10 mm)"),
            "{t}"
        );
        assert!(t.contains("keyframes 10 -> 13 (tolerance 1)"), "{t}");
        let e = verdict(&rows, &[]).unwrap_err().to_string();
        assert!(
            e.contains("1 of 1 regression cases") && e.contains("make golden"),
            "{e}"
        );
    }

    #[test]
    fn unknown_and_stale_cases_fail() {
        let cases = all_cases();
        let golden = Golden {
            cases: vec![golden_for(
                &cases[1],
                figures(0.001, 10, "h"),
                Spread::default(),
            )],
        };
        let results = vec![(cases[0], figures(0.001, 10, "h"))];
        let rows = compare(&golden, &results);
        assert!(matches!(rows[0].verdict, Verdict::Unknown(_)));
        let stale = stale_cases(&golden, &results);
        assert_eq!(stale, vec![cases[1].name()]);
        assert!(verdict(&rows, &stale).is_err());
    }

    #[test]
    fn golden_file_round_trips() {
        let case = all_cases()[5];
        let mut f = figures(0.0123, 10, "00ff");
        f.ate_m = None;
        let golden = Golden {
            cases: vec![
                golden_for(&case, f, Spread::default()),
                golden_for(&all_cases()[6], figures(0.1, 3, "ab"), Spread::default()),
            ],
        };
        let dir = std::env::temp_dir().join(format!("nf-golden-{}", std::process::id()));
        let p = dir.join("g.toml");
        golden.write(&p).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.starts_with("# Golden figures"), "{text}");
        assert_eq!(Golden::read(&p).unwrap(), golden);
        let _ = std::fs::remove_dir_all(dir);
    }
}
