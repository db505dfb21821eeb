//! Resilience tables and curves of a perturbation sweep (`sweep --perturb`): per perturbation
//! family and sequence, each system's ATE (mean ± std over its runs) at every level, and its
//! **breaking level**: the first level, mildest first, whose mean ATE exceeds
//! max(2 x its level-0 ATE, level-0 ATE + 1 cm), or where more than half of its runs fail.

use crate::columns::ConfigKind;
use crate::report::markdown::{system_label, Rendered};
use crate::report::tables::{ate_columns, ATE_COLUMNS};
use crate::store::RunRecord;
use perturb::Family;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// A level's ATE is "broken" above max(BREAK_FACTOR x level-0, level-0 + BREAK_MARGIN_M).
pub const BREAK_FACTOR: f64 = 2.0;
/// See [`BREAK_FACTOR`] (metres).
pub const BREAK_MARGIN_M: f64 = 0.01;
/// Bootstrap resamples behind a breaking level's uncertainty.
pub const BOOTSTRAP_RESAMPLES: usize = 1000;

/// The runs of one system at one level.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelStats {
    /// The level (0 for the unperturbed point).
    pub level: f64,
    /// Runs.
    pub n: usize,
    /// Failed runs ('F').
    pub failed: usize,
    /// ATEs of the runs that did not fail, sorted (m).
    pub ates: Vec<f64>,
    /// Mean frames per second.
    pub fps: f64,
}

impl LevelStats {
    /// Mean ATE of the runs that did not fail.
    pub fn mean(&self) -> Option<f64> {
        crate::report::tables::mean_std(&self.ates).map(|(m, _)| m)
    }

    /// Population standard deviation of those ATEs.
    pub fn std(&self) -> Option<f64> {
        crate::report::tables::mean_std(&self.ates).map(|(_, s)| s)
    }

    /// Median of those ATEs.
    pub fn median(&self) -> Option<f64> {
        crate::report::stats::median(&self.ates)
    }

    /// More than half of the runs failed (or none gave an ATE).
    pub fn is_failure(&self) -> bool {
        self.ates.is_empty() || 2 * self.failed > self.n
    }
}

/// One system's curve along one family on one sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// The sequence.
    pub sequence: String,
    /// The configuration key (`orb`, `mcor+avc`, an external system's name).
    pub system: String,
    /// Its heading.
    pub label: String,
    /// Its levels, mildest first (level 0 first).
    pub levels: Vec<LevelStats>,
}

impl Curve {
    /// The breaking level: the first level after 0 whose mean exceeds the threshold, or which
    /// fails; `None` when the curve holds over every level swept (or has no level 0 to compare).
    pub fn breaking_level(&self) -> Option<f64> {
        let zero = self.levels.first().filter(|l| l.level == 0.0)?;
        let base = zero.mean()?;
        let limit = (BREAK_FACTOR * base).max(base + BREAK_MARGIN_M);
        self.levels[1..]
            .iter()
            .find(|l| l.is_failure() || l.mean().is_some_and(|m| m > limit))
            .map(|l| l.level)
    }

    /// How sure the breaking level is: over [`BOOTSTRAP_RESAMPLES`] resamples of the curve
    /// (each level's runs, failures included, drawn with replacement; seeded by the sequence
    /// and system, so the same records give the same shares), the share whose breaking level
    /// is each level after 0, and the share in which the curve holds over every level. `None`
    /// without a level 0.
    pub fn breaking_shares(&self) -> Option<(Vec<(f64, f64)>, f64)> {
        use rand::{Rng, SeedableRng};
        self.levels.first().filter(|l| l.level == 0.0)?;
        let key = format!("{}\u{1f}{}", self.sequence, self.system);
        let mut rng =
            rand_chacha::ChaCha8Rng::seed_from_u64(slam_core::hash::fnv1a(key.as_bytes()));
        let mut counts = vec![0usize; self.levels.len()];
        let mut holds = 0usize;
        for _ in 0..BOOTSTRAP_RESAMPLES {
            let resampled: Vec<LevelStats> = self
                .levels
                .iter()
                .map(|l| {
                    // The level's runs: ATEs, then its failures.
                    let n = l.n.max(l.ates.len());
                    let mut ates = Vec::with_capacity(n);
                    let mut failed = 0;
                    for _ in 0..n {
                        let k = rng.random_range(0..n);
                        match l.ates.get(k) {
                            Some(a) => ates.push(*a),
                            None => failed += 1,
                        }
                    }
                    ates.sort_by(f64::total_cmp);
                    LevelStats {
                        level: l.level,
                        n,
                        failed,
                        ates,
                        fps: l.fps,
                    }
                })
                .collect();
            let curve = Curve {
                sequence: String::new(),
                system: String::new(),
                label: String::new(),
                levels: resampled,
            };
            match curve.breaking_level() {
                Some(b) => {
                    if let Some(i) = self.levels.iter().position(|l| l.level == b) {
                        counts[i] += 1;
                    }
                }
                None => holds += 1,
            }
        }
        let total = BOOTSTRAP_RESAMPLES as f64;
        Some((
            self.levels[1..]
                .iter()
                .zip(&counts[1..])
                .map(|(l, c)| (l.level, *c as f64 / total))
                .collect(),
            holds as f64 / total,
        ))
    }
}

/// Whether `r` is the unperturbed point of a perturbed sweep.
fn is_zero_point(r: &RunRecord) -> bool {
    r.perturbation.is_some() && r.perturb_family.is_none()
}

/// Severity order of a family's levels: ascending, except JPEG quality (descending: a lower
/// quality is a stronger perturbation); level 0 (none) first in both.
fn severity(family: &str, a: f64, b: f64) -> std::cmp::Ordering {
    let desc = family == Family::Jpeg.name();
    match (a == 0.0, b == 0.0) {
        (true, false) => std::cmp::Ordering::Less,
        (false, true) => std::cmp::Ordering::Greater,
        _ if desc => b.total_cmp(&a),
        _ => a.total_cmp(&b),
    }
}

/// Every curve of a folder's records, by family (in the taxonomy's order), then sequence (in
/// record order), then system (ours in the paper's order, then external ones).
pub fn curves(
    records: &[RunRecord],
    labels: &BTreeMap<String, String>,
) -> BTreeMap<String, Vec<Curve>> {
    let mut families: Vec<String> = records
        .iter()
        .filter_map(|r| r.perturb_family.clone())
        .collect();
    families.sort_by_key(|f| {
        Family::parse(f).map_or(usize::MAX, |f| {
            Family::ALL
                .iter()
                .position(|g| *g == f)
                .unwrap_or(usize::MAX)
        })
    });
    families.dedup();
    let mut out = BTreeMap::new();
    for fam in families {
        let mut keys: Vec<(String, String)> = Vec::new();
        for r in records
            .iter()
            .filter(|r| r.perturb_family.as_deref() == Some(&fam))
        {
            let k = (r.sequence.clone(), r.config.clone());
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
        let rank = |c: &str| {
            ConfigKind::parse(c)
                .ok()
                .and_then(|k| ConfigKind::EVERY.iter().position(|e| *e == k))
                .unwrap_or(usize::MAX)
        };
        keys.sort_by(|a, b| {
            a.0.cmp(&b.0)
                .then(rank(&a.1).cmp(&rank(&b.1)))
                .then(a.1.cmp(&b.1))
        });
        let mut list = Vec::new();
        for (seq, sys) in keys {
            let mut by_level: Vec<(f64, Vec<&RunRecord>)> = Vec::new();
            for r in records
                .iter()
                .filter(|r| r.sequence == seq && r.config == sys && r.perturbation.is_some())
            {
                let level = if is_zero_point(r) {
                    0.0
                } else if r.perturb_family.as_deref() == Some(&fam) {
                    r.perturb_level.unwrap_or(0.0)
                } else {
                    continue;
                };
                match by_level.iter_mut().find(|(l, _)| *l == level) {
                    Some((_, v)) => v.push(r),
                    None => by_level.push((level, vec![r])),
                }
            }
            by_level.sort_by(|a, b| severity(&fam, a.0, b.0));
            let levels = by_level
                .into_iter()
                .map(|(level, rs)| {
                    let mut ates: Vec<f64> = rs
                        .iter()
                        .filter(|r| !r.failed)
                        .filter_map(|r| r.ate_rmse)
                        .collect();
                    ates.sort_by(f64::total_cmp);
                    LevelStats {
                        level,
                        n: rs.len(),
                        failed: rs.iter().filter(|r| r.failed).count(),
                        ates,
                        fps: rs.iter().map(|r| r.fps).sum::<f64>() / rs.len().max(1) as f64,
                    }
                })
                .collect();
            list.push(Curve {
                label: system_label(&sys, labels),
                sequence: seq,
                system: sys,
                levels,
            });
        }
        out.insert(fam, list);
    }
    out
}

/// `mean ± std` in millimetres with `d` decimals.
pub fn mm_pair(mean: f64, std: f64, d: usize) -> String {
    format!("{:.d$} ± {:.d$}", mean * 1000.0, std * 1000.0)
}

fn level_text(l: f64) -> String {
    format!("{l}")
}

/// The Markdown table (ATE in mm, mean ± std, breaking level per row) and the tidy CSV (one row
/// per sequence, system and level, in metres) of one family.
pub fn table(family: &str, curves: &[Curve]) -> Rendered {
    let unit = Family::parse(family).ok().map_or("", Family::unit);
    let mut md = format!("## Resilience to {family} ({unit})\n\n");
    let mut sequences: Vec<&str> = curves.iter().map(|c| c.sequence.as_str()).collect();
    sequences.dedup();
    for seq in sequences {
        let rows: Vec<&Curve> = curves.iter().filter(|c| c.sequence == seq).collect();
        md.push_str(&sequence_section(family, seq, &rows));
    }
    md.push_str(&table_notes(curves));
    Rendered {
        markdown: md,
        csv: tidy_csv(family, unit, curves),
    }
}

/// The levels any of `rows` measured, mildest first: the columns of a sequence's table.
fn levels_of(family: &str, rows: &[&Curve]) -> Vec<f64> {
    let mut levels: Vec<f64> = Vec::new();
    for c in rows {
        for l in &c.levels {
            if !levels.contains(&l.level) {
                levels.push(l.level);
            }
        }
    }
    levels.sort_by(|a, b| severity(family, *a, *b));
    levels
}

/// One sequence's part of the Markdown: its heading and a table of one row per system.
fn sequence_section(family: &str, seq: &str, rows: &[&Curve]) -> String {
    let levels = levels_of(family, rows);
    let mut md = String::new();
    let _ = writeln!(md, "### {seq}\n");
    let _ = writeln!(
        md,
        "| system | {} | breaking level |",
        levels
            .iter()
            .map(|l| format!("{family} {}", level_text(*l)))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(md, "|---|{}---|", "---|".repeat(levels.len()));
    for c in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {}{} |",
            c.label,
            level_cells(c, &levels).join(" | "),
            breaking_text(c),
            shares_text(c)
        );
    }
    md.push('\n');
    md
}

/// A system's cells at `levels`: `mean ± std` in millimetres (with `(kF)` for k failed runs),
/// `F (k/n)` for a failed level, empty where the system was not run.
fn level_cells(c: &Curve, levels: &[f64]) -> Vec<String> {
    // One number of decimals per row: three significant digits of its smallest mean, so the
    // levels of one system compare digit for digit (as Table III's rows).
    let d = crate::report::tables::mm_decimals(
        c.levels
            .iter()
            .filter(|l| !l.is_failure())
            .filter_map(LevelStats::mean),
    );
    levels
        .iter()
        .map(|lv| match c.levels.iter().find(|l| l.level == *lv) {
            None => "".into(),
            Some(l) if l.is_failure() => format!("F ({}/{})", l.failed, l.n),
            Some(l) => {
                let mut t = mm_pair(l.mean().unwrap_or(0.0), l.std().unwrap_or(0.0), d);
                if l.failed > 0 {
                    let _ = write!(t, " ({}F)", l.failed);
                }
                t
            }
        })
        .collect()
}

/// The breaking-level cell: the level, `none up to L` when the system held, or `no level 0`.
fn breaking_text(c: &Curve) -> String {
    match c.breaking_level() {
        Some(b) => level_text(b),
        None if c.levels.first().is_some_and(|l| l.level == 0.0) => format!(
            "none up to {}",
            c.levels
                .last()
                .map_or(String::new(), |l| level_text(l.level))
        ),
        None => "no level 0".into(),
    }
}

/// How sure the breaking level is, in brackets: the bootstrap shares of 5 % and more that
/// break at each level and that hold; empty without a level 0.
fn shares_text(c: &Curve) -> String {
    c.breaking_shares().map_or_else(String::new, |(at, held)| {
        let mut parts: Vec<String> = at
            .iter()
            .filter(|(_, s)| *s >= 0.05)
            .map(|(l, s)| format!("{} {:.0} %", level_text(*l), s * 100.0))
            .collect();
        if held >= 0.05 {
            parts.push(format!("holds {:.0} %", held * 100.0));
        }
        format!(" ({})", parts.join(", "))
    })
}

/// The paragraph under the tables: units, what 'F' and the breaking level mean.
fn table_notes(curves: &[Curve]) -> String {
    let runs = curves
        .iter()
        .flat_map(|c| c.levels.iter().map(|l| l.n))
        .max()
        .unwrap_or(0);
    format!(
        "ATE RMSE in millimetres, mean ± std over the runs that did not fail (up to {runs} per cell); \
         'F (k/n)': more than half of the n runs failed (under 80 % of the frames tracked, or no ATE). \
         Breaking level: the first level whose mean ATE exceeds max({BREAK_FACTOR} x the level-0 ATE, \
         level-0 ATE + {} cm), or that fails; 'none up to L': the system held over every level swept. \
         In brackets, how sure that is: the share of {BOOTSTRAP_RESAMPLES} bootstrap resamples of \
         the runs (each level's drawn with replacement, failures included) that break at each \
         level, and that hold (shares under 5 % left out; the CSV has every one).\n",
        BREAK_MARGIN_M * 100.0
    )
}

/// The tidy CSV of one family: a row per sequence, system and level, ATEs in metres, with the
/// curve's breaking level (or the highest level swept, flagged `held`) and its bootstrap shares.
fn tidy_csv(family: &str, unit: &str, curves: &[Curve]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record(
        [
            "sequence", "system", "label", "ours", "family", "level", "unit",
        ]
        .into_iter()
        .chain(ATE_COLUMNS)
        .chain([
            "fps",
            "breaking_level",
            "held",
            "breaks_here_share",
            "holds_share",
        ]),
    );
    let opt = |v: Option<f64>| v.map(|x| format!("{x}")).unwrap_or_default();
    for c in curves {
        // A curve that held reports the highest level swept, flagged `held`.
        let has_zero = c.levels.first().is_some_and(|l| l.level == 0.0);
        let held = has_zero && c.breaking_level().is_none();
        let b = if has_zero {
            opt(c
                .breaking_level()
                .or_else(|| c.levels.last().map(|l| l.level)))
        } else {
            String::new()
        };
        let held = if has_zero {
            held.to_string()
        } else {
            String::new()
        };
        let shares = c.breaking_shares();
        for l in &c.levels {
            let here = shares
                .as_ref()
                .and_then(|(at, _)| at.iter().find(|(lv, _)| *lv == l.level).map(|(_, s)| *s));
            let head = [
                c.sequence.clone(),
                c.system.clone(),
                c.label.clone(),
                ConfigKind::parse(&c.system).is_ok().to_string(),
                family.to_string(),
                format!("{}", l.level),
                unit.to_string(),
            ];
            let tail = [
                format!("{:.2}", l.fps),
                b.clone(),
                held.clone(),
                opt(here),
                opt(shares.as_ref().map(|(_, h)| *h)),
            ];
            let ates = ate_columns(l.n, l.failed, &l.ates);
            let _ = w.write_record(head.into_iter().chain(ates).chain(tail));
        }
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(
        config: &str,
        family: Option<&str>,
        level: f64,
        seed: u64,
        ate: f64,
        failed: bool,
    ) -> RunRecord {
        RunRecord {
            failed,
            keyframes: None,
            map_points: None,
            mean_inliers: None,
            mean_outliers: None,
            synth_seed: None,
            loops: None,
            perturbation: Some(family.map_or("none".into(), |f| format!("{f}:{level}"))),
            perturb_family: family.map(String::from),
            perturb_level: family.map(|_| level),
            perturb_seed: Some(0),
            ..RunRecord::example("s", config, seed, ate)
        }
    }

    #[test]
    fn a_borderline_breaking_level_is_uncertain_and_a_clear_one_is_not() {
        let mut r = Vec::new();
        for seed in 0..10 {
            r.push(rec("orb", None, 0.0, seed, 0.002, false));
            // Level 1: half the runs far above the 12 mm limit, half below: the mean (about
            // 13 mm) breaks, a resample may not.
            let a = if seed % 2 == 0 { 0.019 } else { 0.007 };
            r.push(rec("orb", Some("depth-axial"), 1.0, seed, a, false));
            // Level 2: every run far above.
            r.push(rec("orb", Some("depth-axial"), 2.0, seed, 0.05, false));
        }
        let c = curves(&r, &BTreeMap::new());
        let curve = &c["depth-axial"][0];
        assert_eq!(curve.breaking_level(), Some(1.0));
        let (at, holds) = curve.breaking_shares().unwrap();
        assert_eq!(at.len(), 2);
        let (s1, s2) = (at[0].1, at[1].1);
        assert!(s1 > 0.5 && s1 < 0.95, "level 1: {s1}");
        assert!(
            (s1 + s2 + holds - 1.0).abs() < 1e-12 && holds == 0.0,
            "{s2} {holds}"
        );
        // Seeded: the same records give the same shares.
        assert_eq!(
            curve.breaking_shares(),
            c["depth-axial"][0].breaking_shares()
        );
        let t = table("depth-axial", &c["depth-axial"]);
        let mut rdr = csv::Reader::from_reader(t.csv.as_bytes());
        let h = rdr.headers().unwrap().clone();
        let col = |n: &str| h.iter().position(|x| x == n).unwrap();
        let rows: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
        let one = rows.iter().find(|r| &r[col("level")] == "1").unwrap();
        assert_eq!(one[col("breaks_here_share")].parse::<f64>().unwrap(), s1);
        assert_eq!(&one[col("held")], "false");
    }

    #[test]
    fn breaking_levels_follow_the_definition() {
        let mut r = Vec::new();
        for seed in 0..2 {
            // orb: 2 mm at 0, 3.9 at 1 (under 2x and +1 cm), 12.5 at 2 (over 2 mm + 1 cm).
            r.push(rec("orb", None, 0.0, seed, 0.002, false));
            r.push(rec("orb", Some("depth-axial"), 1.0, seed, 0.0039, false));
            r.push(rec("orb", Some("depth-axial"), 2.0, seed, 0.0125, false));
            // avc: 30 mm at 0; 59 mm at 2 (under 2x): holds; fails at 4 in 2 of 2 runs.
            r.push(rec("avc", None, 0.0, seed, 0.030, false));
            r.push(rec("avc", Some("depth-axial"), 2.0, seed, 0.059, false));
            r.push(rec("avc", Some("depth-axial"), 4.0, seed, 0.5, true));
        }
        let c = curves(&r, &BTreeMap::new());
        let axial = &c["depth-axial"];
        assert_eq!(axial[0].system, "orb");
        assert_eq!(axial[0].breaking_level(), Some(2.0));
        assert_eq!(axial[1].breaking_level(), Some(4.0));
        let t = table("depth-axial", axial);
        assert!(
            t.markdown.contains(
                "| ORB-SLAM2 (ours) | 2.00 ± 0.00 | 3.90 ± 0.00 | 12.50 ± 0.00 |  | 2 (2 100 %) |"
            ),
            "{}",
            t.markdown
        );
        assert!(t.markdown.contains("F (2/2)"));
        // The tidy CSV holds numbers equal to the records' statistics.
        let mut rdr = csv::Reader::from_reader(t.csv.as_bytes());
        let rows: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
        let orb2 = rows
            .iter()
            .find(|r| &r[1] == "orb" && &r[5] == "2")
            .unwrap();
        assert_eq!(&orb2[3], "true");
        assert_eq!(orb2[10].parse::<f64>().unwrap(), 0.0125);
        assert_eq!(&orb2[16], "2");
        // A curve that held: the highest level swept, flagged, a number not an empty cell.
        let avc0 = rows.iter().find(|r| &r[1] == "avc").unwrap();
        assert_eq!((&avc0[16], &avc0[17]), ("4", "false"));
        // JPEG: lower quality is stronger.
        let mut j = vec![rec("orb", None, 0.0, 0, 0.002, false)];
        for q in [90.0, 30.0, 60.0] {
            j.push(rec(
                "orb",
                Some("jpeg"),
                q,
                0,
                0.002 + (100.0 - q) * 0.001,
                false,
            ));
        }
        let c = curves(&j, &BTreeMap::new());
        let lv: Vec<f64> = c["jpeg"][0].levels.iter().map(|l| l.level).collect();
        assert_eq!(lv, [0.0, 90.0, 60.0, 30.0]);
        assert_eq!(c["jpeg"][0].breaking_level(), Some(60.0));
    }
}
