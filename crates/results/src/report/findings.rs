//! The findings: each claim of the paper set against what the committed tables show, with the
//! effect, its 95 % interval and a verdict, and a link to the table behind it. Read from the
//! tables `noisefree table` wrote (`versus-baseline.csv`, `table4.csv`, the analysis's
//! `table2_*.csv`), never from prose, so its numbers cannot drift from them.
//!
//! Verdicts: a technique's difference from the baseline **reproduces** a claimed gain when it is
//! negative (lower ATE) and survives Holm's correction over its table at 0.05; it **contradicts**
//! it when it is positive and survives; otherwise **no difference detected**, with the interval
//! that says how large a difference the data leave room for.

use crate::report::markdown::counted;
use crate::report::stats::holm;
use crate::report::versus::{relative_text, ALPHA};
use anyhow::{Context, Result};
use datasets::Catalog;
use statrs::distribution::{ContinuousCDF, FisherSnedecor};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One row of a folder's `versus-baseline.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct VersusRow {
    /// The folder, as given.
    pub folder: PathBuf,
    /// Sequence.
    pub sequence: String,
    /// The perturbation point (`none`, `family:level`, or a fixed chain).
    pub perturbation: String,
    /// The axis the point lies on (`None`: unperturbed or a fixed chain).
    pub axis: Option<String>,
    /// Configuration name.
    pub config: String,
    /// MC-OR's thresholds where they were a parameter.
    pub taus: Option<(f64, f64, f64)>,
    /// AVC's b where it was a parameter.
    pub b: Option<f64>,
    /// Runs and failed runs.
    pub runs: usize,
    /// Runs that failed.
    pub failed: usize,
    /// Mean ATE (m) and sample std over the runs that did not fail.
    pub mean: Option<f64>,
    /// Sample standard deviation (m).
    pub std: Option<f64>,
    /// Difference from the baseline in % with its 95 % interval (absent for the baseline).
    pub diff_pct: Option<(f64, f64, f64)>,
    /// The test's name (`paired_t`, `Welch_t`).
    pub test: String,
    /// Holm-corrected p-value.
    pub p_holm: Option<f64>,
    /// The test's p-value before any correction.
    pub p: Option<f64>,
}

impl VersusRow {
    /// A row for the tests: ten runs of `config` on `sequence` in `folder`, unperturbed, mean
    /// 0.1 m, no difference or p-value yet (set what a test needs with struct update).
    #[cfg(test)]
    pub fn example(folder: &str, sequence: &str, config: &str) -> VersusRow {
        VersusRow {
            folder: PathBuf::from(folder),
            sequence: sequence.into(),
            perturbation: "none".into(),
            axis: None,
            config: config.into(),
            taus: None,
            b: None,
            runs: 10,
            failed: 0,
            mean: Some(0.1),
            std: Some(0.01),
            diff_pct: None,
            test: "paired_t".into(),
            p_holm: None,
            p: None,
        }
    }

    /// Whether the difference survives Holm's correction.
    pub fn survives(&self) -> bool {
        self.p_holm.is_some_and(|p| p <= ALPHA)
    }

    /// Whether these are the parameters Table III reports.
    pub fn default_params(&self) -> bool {
        crate::report::tables::are_default_params(self.taus, self.b)
    }
}

fn field(r: &csv::StringRecord, h: &csv::StringRecord, name: &str) -> Option<String> {
    let i = h.iter().position(|c| c == name)?;
    r.get(i).filter(|s| !s.is_empty()).map(str::to_string)
}

fn number(r: &csv::StringRecord, h: &csv::StringRecord, name: &str) -> Option<f64> {
    field(r, h, name)?.parse().ok()
}

/// Reads `dir/versus-baseline.csv`; an empty list when the folder has none.
pub fn read_versus(dir: &Path) -> Result<Vec<VersusRow>> {
    let path = dir.join("versus-baseline.csv");
    if !path.is_file() {
        return Ok(Vec::new());
    }
    let mut rdr = csv::Reader::from_path(&path).with_context(|| format!("{}", path.display()))?;
    let h = rdr.headers()?.clone();
    let mut out = Vec::new();
    for (i, rec) in rdr.records().enumerate() {
        let r = rec.with_context(|| format!("{}: line {}", path.display(), i + 2))?;
        let taus = match (
            number(&r, &h, "tau_mf"),
            number(&r, &h, "tau_gf"),
            number(&r, &h, "tau_mg"),
        ) {
            (Some(a), Some(b), Some(c)) => Some((a, b, c)),
            _ => None,
        };
        let diff = match (
            number(&r, &h, "diff_pct"),
            number(&r, &h, "diff_ci95_lo_pct"),
            number(&r, &h, "diff_ci95_hi_pct"),
        ) {
            (Some(d), Some(lo), Some(hi)) => Some((d, lo, hi)),
            _ => None,
        };
        out.push(VersusRow {
            folder: dir.to_path_buf(),
            sequence: field(&r, &h, "sequence").unwrap_or_default(),
            perturbation: field(&r, &h, "perturbation").unwrap_or_default(),
            axis: field(&r, &h, "axis"),
            config: field(&r, &h, "config").unwrap_or_default(),
            taus,
            b: number(&r, &h, "baseline_b"),
            runs: number(&r, &h, "runs").unwrap_or(0.0) as usize,
            failed: number(&r, &h, "failed").unwrap_or(0.0) as usize,
            mean: number(&r, &h, "mean_m"),
            std: number(&r, &h, "std_m"),
            diff_pct: diff,
            test: field(&r, &h, "test").unwrap_or_default(),
            p_holm: number(&r, &h, "p_holm"),
            p: number(&r, &h, "p"),
        });
    }
    Ok(out)
}

/// A row's difference as the findings print it, as its table does: `-12.3 % [-20.1, -4.5]`.
fn diff_text(d: (f64, f64, f64)) -> String {
    relative_text(d.0, (d.1, d.2))
}

/// The verdict on a claimed gain from one comparison.
fn verdict(r: &VersusRow) -> &'static str {
    match (r.diff_pct, r.survives()) {
        (Some((d, _, _)), true) if d < 0.0 => "reproduced",
        (Some(_), true) => "contradicted (worse)",
        (Some(_), false) => "no difference detected",
        (None, _) => "-",
    }
}

/// Where links point from: the folder of the file the findings go into.
fn link(base: &Path, folder: &Path, file: &str) -> String {
    let rel = folder.strip_prefix(base).unwrap_or(folder);
    let p = rel.join(file);
    let s = p.to_string_lossy().replace('\\', "/");
    format!("[{}]({s})", rel.to_string_lossy().replace('\\', "/"))
}

/// The paper's relative difference (%) of `config` on the row a sequence is or imitates.
fn paper_gain(catalog: &Catalog, seq: &str, config: &str) -> Option<(String, f64)> {
    let (col, base, row) = crate::report::versus::paper_figures(catalog, seq, config)?;
    Some((row, 100.0 * (col - base) / base))
}

const TECHNIQUES: [&str; 3] = ["mcor", "avc", "mcor+avc"];

fn heading(config: &str) -> &'static str {
    match config {
        "mcor" => "MC-OR",
        "avc" => "AVC",
        "mcor+avc" => "MC-OR+AVC",
        _ => "?",
    }
}

/// Table III row by row: every twin comparison of a paper technique with the baseline at the
/// paper's parameters, unperturbed or under a fixed chain, beside the paper's gain.
fn table3_findings(
    md: &mut String,
    rows: &[VersusRow],
    catalog: &Catalog,
    base: &Path,
) -> [Tally; 2] {
    let mut lines: Vec<(String, String)> = Vec::new();
    // Unperturbed twins, and twins under a fixed camera chain.
    let mut tally = [Tally::default(); 2];
    // The paper's cells (a row and a technique) each tally covers, and the cells where the paper
    // reports no gain (its figure equals ORB-SLAM2's).
    let mut cells: [BTreeSet<(String, &'static str)>; 2] = Default::default();
    let mut no_gain: BTreeSet<(String, &'static str)> = BTreeSet::new();
    for r in rows.iter().filter(|r| {
        r.axis.is_none() && TECHNIQUES.contains(&r.config.as_str()) && r.default_params()
    }) {
        let Some((paper_row, g)) = paper_gain(catalog, &r.sequence, &r.config) else {
            continue;
        };
        let Some(d) = r.diff_pct else { continue };
        let i = usize::from(r.perturbation != "none");
        cells[i].insert((paper_row.clone(), heading(&r.config)));
        if g >= 0.0 {
            no_gain.insert((paper_row.clone(), heading(&r.config)));
        }
        let t = &mut tally[i];
        t.n += 1;
        let v = match (verdict(r), g < 0.0) {
            ("reproduced", true) => {
                t.reproduced += 1;
                "reproduced"
            }
            ("reproduced", false) => "lower (the paper: no gain)",
            ("contradicted (worse)", claimed) => {
                t.worse += 1;
                if claimed {
                    "contradicted (worse)"
                } else {
                    "worse (the paper: no change)"
                }
            }
            (other, _) => other,
        };
        let excluded = g < d.1 || g > d.2;
        if excluded {
            t.outside += 1;
        }
        let v = if excluded {
            format!("{v}; the paper's {g:+.0} % outside our interval")
        } else {
            v.to_string()
        };
        // A verdict from fewer runs than the paper's ten says so.
        let v = if r.runs < 10 {
            format!("{v} (n = {}; the paper's n = 10)", r.runs)
        } else {
            v
        };
        let point = if r.perturbation == "none" {
            "unperturbed".to_string()
        } else {
            format!("under `{}`", short_point(&r.perturbation))
        };
        lines.push((
            paper_row.clone(),
            format!(
                "| {paper_row} | {} | {} {point} | {} | {g:+.0} % | {} | {} |",
                heading(&r.config),
                r.sequence,
                link(base, &r.folder, "versus-baseline.md"),
                diff_text(d),
                v
            ),
        ));
    }
    for (t, c) in tally.iter_mut().zip(&cells) {
        t.cells = c.len();
    }
    let except = if no_gain.is_empty() {
        String::new()
    } else {
        let named: Vec<String> = no_gain
            .iter()
            .map(|(row, tech)| format!("{row} {tech}"))
            .collect();
        format!(
            ", but for {} cells where its figure is not lower ({})",
            no_gain.len(),
            named.join(", ")
        )
    };
    let _ = writeln!(
        md,
        "### Table III, row by row\n\nThe paper reports MC-OR, AVC and both lowering ORB-SLAM2's \
         ATE on every row{except}. On our twins at the paper's parameters: unperturbed, {}; \
         under a real camera's systematic errors (a named chain, e.g. at the level that matches \
         the paper's ORB-SLAM2 figure), {}. Verdicts follow the Holm-corrected p of the \
         comparison's table; the intervals are each comparison's own (uncorrected), so an \
         interval that excludes 0 can still fall short of the correction.\n",
        tally[0].sentence(),
        tally[1].sentence()
    );
    if lines.is_empty() {
        return tally;
    }
    lines.sort_by(|a, b| a.0.cmp(&b.0));
    md.push_str(
        "| Paper row | Technique | Our twin | Table | Paper | Ours [95 % CI] | Verdict |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for (_, l) in lines {
        md.push_str(&l);
        md.push('\n');
    }
    md.push('\n');
    tally
}

/// Counts of Table III comparisons by verdict.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tally {
    /// Comparisons.
    pub n: usize,
    /// The paper's cells (a row and a technique) they cover: fewer than `n` where a cell is
    /// compared again on other runs (another folder's).
    pub cells: usize,
    /// A claimed gain reproduced (lower, surviving Holm).
    pub reproduced: usize,
    /// The technique worse (surviving Holm).
    pub worse: usize,
    /// The paper's figure outside our 95 % interval.
    pub outside: usize,
}

impl Tally {
    /// The tally as a clause: "12 comparisons of 9 paper cells (...): 0 reproduce a gain, ...".
    fn sentence(&self) -> String {
        if self.n == 0 {
            return "no comparison (no twin of a Table III row at the paper's parameters among \
                    the tables read)"
                .into();
        }
        let repeats = self.n.saturating_sub(self.cells);
        let of = if repeats == 0 {
            format!(
                "{} comparisons, one per paper cell (a row and a technique)",
                self.n
            )
        } else {
            format!(
                "{} comparisons of {} paper cells (a row and a technique; {repeats} repeat a cell \
                 on other runs)",
                self.n, self.cells
            )
        };
        format!(
            "{of}: **{} reproduce a gain**, {} find the technique worse, the rest detect no \
             difference; in {} the paper's gain lies outside our 95 % interval",
            self.reproduced, self.worse, self.outside
        )
    }
}

/// A point's name, shortened where a fixed chain expands to many members.
fn short_point(p: &str) -> String {
    if p.len() <= 40 {
        p.to_string()
    } else {
        format!(
            "{}...",
            &p[..p.char_indices().nth(37).map_or(p.len(), |(i, _)| i)]
        )
    }
}

/// A technique against one noise axis (MC-OR against lateral, AVC against axial noise).
fn axis_findings(
    md: &mut String,
    rows: &[VersusRow],
    base: &Path,
    title: &str,
    claim: &str,
    family: &str,
    uses: fn(&str) -> bool,
) -> (usize, usize) {
    let mut by_folder: BTreeMap<PathBuf, Vec<&VersusRow>> = BTreeMap::new();
    for r in rows
        .iter()
        .filter(|r| r.axis.as_deref() == Some(family) && uses(&r.config) && r.diff_pct.is_some())
    {
        by_folder.entry(r.folder.clone()).or_default().push(r);
    }
    let _ = writeln!(md, "### {title}\n\n{claim}\n");
    if by_folder.is_empty() {
        let _ = writeln!(md, "None of the tables read has a `{family}` axis.\n");
        return (0, 0);
    }
    md.push_str(
        "| Table | Comparisons | Gains surviving Holm | Losses surviving Holm | Largest gain [95 % CI] |\n\
         |---|---|---|---|---|\n",
    );
    let mut totals = (0, 0);
    for (folder, list) in &by_folder {
        let gains = list.iter().filter(|r| verdict(r) == "reproduced").count();
        let losses = list
            .iter()
            .filter(|r| verdict(r) == "contradicted (worse)")
            .count();
        let best = list
            .iter()
            .filter_map(|r| Some((r, r.diff_pct?)))
            .min_by(|a, b| a.1 .0.total_cmp(&b.1 .0))
            .map(|(r, d)| {
                let what = format!(
                    "{} ({}, {}, `{}`{})",
                    diff_text(d),
                    r.config,
                    r.sequence,
                    r.perturbation,
                    if r.survives() { ", survives" } else { "" }
                );
                // Every difference above zero: no gain to name, only the smallest loss.
                if d.0 < 0.0 {
                    what
                } else {
                    format!("none; the lowest, {what}")
                }
            })
            .unwrap_or_default();
        totals = (totals.0 + list.len(), totals.1 + gains);
        let _ = writeln!(
            md,
            "| {} | {} | {gains} | {losses} | {best} |",
            link(base, folder, "versus-baseline.md"),
            list.len()
        );
    }
    md.push('\n');
    totals
}

/// The readings (issue 72): every comparison of a column that names readings of the paper,
/// the ones that survive Holm listed with their intervals beside the paper's gain. Returns the
/// glance's clause.
fn readings_findings(
    md: &mut String,
    rows: &[VersusRow],
    catalog: &Catalog,
    base: &Path,
) -> Option<String> {
    let is_reading = |r: &VersusRow| {
        matches!(
            crate::readings::ReadingColumn::parse(&r.config),
            Ok(Some(_))
        )
    };
    // The study: every comparison of every folder that tried a reading, corrected together
    // (trying many readings, and confirming one, are comparisons too).
    let folders: std::collections::BTreeSet<&PathBuf> = rows
        .iter()
        .filter(|r| is_reading(r))
        .map(|r| &r.folder)
        .collect();
    let study: Vec<&VersusRow> = rows
        .iter()
        .filter(|r| folders.contains(&r.folder) && r.diff_pct.is_some() && r.p.is_some())
        .collect();
    if !study.iter().any(|r| is_reading(r)) {
        return None;
    }
    let p: Vec<f64> = study.iter().map(|r| r.p.expect("filtered")).collect();
    let adjusted = crate::report::stats::holm(&p);
    let read: Vec<(&VersusRow, f64)> = study
        .iter()
        .zip(&adjusted)
        .filter(|(r, _)| is_reading(r))
        .map(|(r, p)| (*r, *p))
        .collect();
    let _ = write!(
        md,
        "### The readings of what the paper leaves unsaid\n\nThe paper's techniques under \
         each reading of a choice it does not make (which sightings form a cluster, who decides, \
         where MC-OR acts, AVC's gate and what b is; docs/readings.md), against the baseline on \
         the same runs. Holm's correction here runs over the whole study: all {} of {} that tried \
         a reading, so trying many readings, and confirming one on fresh draws, are counted.\n\n",
        counted(study.len(), "comparison", "comparisons"),
        if folders.len() == 1 {
            "the folder".to_string()
        } else {
            format!("the {} folders", folders.len())
        },
    );
    let survivors: Vec<(&VersusRow, f64)> =
        read.iter().copied().filter(|(_, p)| *p <= ALPHA).collect();
    let lower: Vec<(&VersusRow, f64)> = survivors
        .iter()
        .copied()
        .filter(|(r, _)| r.diff_pct.is_some_and(|d| d.0 < 0.0))
        .collect();
    let higher = survivors.len() - lower.len();
    if survivors.is_empty() {
        md.push_str("No reading differs from the baseline after Holm over the study.\n\n");
    } else {
        md.push_str(
            "| Table | Sequence | Column | Against the baseline [95 % CI] | Holm p (study) | \
             The paper |\n|---|---|---|---|---|---|\n",
        );
        for (r, p) in &survivors {
            let kind = crate::readings::ReadingColumn::parse(&r.config)
                .ok()
                .flatten()
                .map(|c| c.kind.name())
                .unwrap_or_default();
            let paper = paper_gain(catalog, &r.sequence, kind)
                .map_or("-".to_string(), |(row, g)| format!("{g:+.0} % ({row})"));
            let _ = writeln!(
                md,
                "| {} | {} | `{}` | {} | {} | {paper} |",
                link(base, &r.folder, "readings.md"),
                r.sequence,
                r.config,
                diff_text(r.diff_pct.expect("filtered")),
                if *p < 0.001 {
                    "< 0.001".to_string()
                } else {
                    format!("{p:.3}")
                },
            );
        }
        md.push('\n');
    }
    let _ = writeln!(
        md,
        "{} of readings: {} with a lower ATE than the baseline after Holm over the study, \
         {higher} with a higher one, the rest not told apart.\n",
        counted(read.len(), "comparison", "comparisons"),
        lower.len(),
    );
    // The glance names the largest gain only: a list of every one outgrows a line of the README.
    let largest = lower
        .iter()
        .map(|(r, _)| r)
        .min_by(|a, b| {
            let d = |r: &VersusRow| r.diff_pct.map_or(0.0, |d| d.0);
            d(a).total_cmp(&d(b))
        })
        .map(|r| {
            let more = match lower.len() - 1 {
                0 => String::new(),
                n => format!("; {n} more in the findings"),
            };
            format!(
                "largest: `{}` on {} {} ({}){more}",
                r.config,
                r.sequence,
                diff_text(r.diff_pct.expect("filtered")),
                r.folder
                    .file_name()
                    .map_or(String::new(), |f| f.to_string_lossy().into_owned()),
            )
        });
    let named: Vec<String> = largest.into_iter().collect();
    Some(format!(
        "{}: **{} lower ATE after Holm over the study**{}, {higher} higher",
        counted(read.len(), "comparison", "comparisons"),
        lower.len(),
        if named.is_empty() {
            String::new()
        } else {
            format!(" ({})", named.join("; "))
        },
    ))
}

/// Table I: AVC against the baseline at each b.
fn table1_findings(md: &mut String, rows: &[VersusRow], base: &Path) {
    md.push_str(
        "### Table I: AVC's virtual baseline b\n\nThe paper: AVC is tolerant to the choice of b \
         (0.01 to 0.13 m), better than ORB-SLAM2 at each.\n\n",
    );
    let mut groups: BTreeMap<(PathBuf, String, String), Vec<&VersusRow>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.config == "avc" && r.b.is_some()) {
        groups
            .entry((r.folder.clone(), r.sequence.clone(), r.perturbation.clone()))
            .or_default()
            .push(r);
    }
    groups.retain(|_, v| v.len() >= 2);
    if groups.is_empty() {
        md.push_str("None of the tables read varies b with the baseline beside it.\n\n");
        return;
    }
    md.push_str(
        "| Table | Sequence | b (m): AVC against the baseline [95 % CI] |\n|---|---|---|\n",
    );
    for ((folder, seq, point), mut list) in groups {
        list.sort_by(|a, b| a.b.unwrap_or(0.0).total_cmp(&b.b.unwrap_or(0.0)));
        let cells: Vec<String> = list
            .iter()
            .filter_map(|r| {
                let d = r.diff_pct?;
                let t = format!("{}: {}", r.b?, diff_text(d));
                Some(if r.survives() { format!("**{t}**") } else { t })
            })
            .collect();
        let at = if point == "none" {
            String::new()
        } else {
            format!(" under `{}`", short_point(&point))
        };
        let _ = writeln!(
            md,
            "| {} | {seq}{at} | {} |",
            link(base, &folder, "versus-baseline.md"),
            cells.join("; ")
        );
    }
    md.push('\n');
}

/// The two-sided p-value of the variance ratio F = s1^2 / s2^2 with (n1 - 1, n2 - 1) degrees
/// of freedom, and the 95 % interval of the ratio of the two variances.
pub fn variance_ratio_test(s1: f64, n1: usize, s2: f64, n2: usize) -> Option<(f64, f64, f64, f64)> {
    if n1 < 2 || n2 < 2 || s2 <= 0.0 || s1 <= 0.0 {
        return None;
    }
    let (d1, d2) = ((n1 - 1) as f64, (n2 - 1) as f64);
    let f = FisherSnedecor::new(d1, d2).ok()?;
    let ratio = s1 * s1 / (s2 * s2);
    let p = (2.0 * f.cdf(ratio).min(1.0 - f.cdf(ratio))).min(1.0);
    let lo = ratio / f.inverse_cdf(0.975);
    let hi = ratio / f.inverse_cdf(0.025);
    Some((ratio, lo, hi, p))
}

/// Fig. 9: MC-OR's run-to-run spread against the baseline's (F-test of the variances of the
/// runs, Holm over every pair).
fn variance_findings(md: &mut String, rows: &[VersusRow], base: &Path) {
    md.push_str(
        "### Fig. 9: MC-OR's spread over runs\n\nThe paper: MC-OR reduces the variation of ATE \
         over n = 10 runs up to 10x. Ours: the ratio of MC-OR's variance to the baseline's over \
         the runs of one cell (F-test, two-sided; Holm over every pair below; cells where either \
         system's runs are identical are left out, as no ratio exists).\n\n",
    );
    let mut pairs = Vec::new();
    for r in rows
        .iter()
        .filter(|r| r.config == "mcor" && r.default_params() && r.axis.is_none())
    {
        let Some(b) = rows.iter().find(|b| {
            b.folder == r.folder
                && b.sequence == r.sequence
                && b.perturbation == r.perturbation
                && b.config == "orb"
        }) else {
            continue;
        };
        let (Some(sm), Some(sb)) = (r.std, b.std) else {
            continue;
        };
        let (nm, nb) = (r.runs - r.failed, b.runs - b.failed);
        if let Some(t) = variance_ratio_test(sm, nm, sb, nb) {
            pairs.push((r, t));
        }
    }
    if pairs.is_empty() {
        md.push_str(
            "No cell of the tables read has MC-OR and the baseline with spread to compare.\n\n",
        );
        return;
    }
    let adj = holm(&pairs.iter().map(|p| p.1 .3).collect::<Vec<_>>());
    let lower = pairs
        .iter()
        .zip(&adj)
        .filter(|((_, t), a)| t.0 < 1.0 && **a <= ALPHA)
        .count();
    let higher = pairs
        .iter()
        .zip(&adj)
        .filter(|((_, t), a)| t.0 > 1.0 && **a <= ALPHA)
        .count();
    let best = pairs
        .iter()
        .min_by(|a, b| a.1 .0.total_cmp(&b.1 .0))
        .expect("non-empty");
    let _ = writeln!(
        md,
        "{} cells: MC-OR's variance **lower in {lower}**, higher in {higher} (surviving Holm), \
         no difference detected in {}. Smallest ratio: {:.2} [95 % CI {:.2}, {:.2}] on {} \
         ({}).\n",
        pairs.len(),
        pairs.len() - lower - higher,
        best.1 .0,
        best.1 .1,
        best.1 .2,
        best.0.sequence,
        link(base, &best.0.folder, "versus-baseline.md")
    );
}

/// Table II: how well each error term follows the depth error (the analysis's Pearson r).
fn table2_findings(md: &mut String, dirs: &[PathBuf], base: &Path) -> Result<()> {
    md.push_str(
        "### Table II: the error terms against the depth error\n\nThe paper: AVC's error \
         components follow the 3-D depth error e_BASE,z far more closely than ORB-SLAM2's \
         virtual-camera error. Ours (Pearson r over the inlier matches, 95 % interval by \
         Fisher's z):\n\n",
    );
    let mut any = false;
    for dir in dirs {
        let Ok(it) = std::fs::read_dir(dir) else {
            continue;
        };
        let mut files: Vec<PathBuf> = it
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("table2_") && n.ends_with(".csv"))
            })
            .collect();
        files.sort();
        for f in files {
            let mut rdr = csv::Reader::from_path(&f).with_context(|| f.display().to_string())?;
            let h = rdr.headers()?.clone();
            let mut r_of = BTreeMap::new();
            for rec in rdr.records() {
                let rec = rec.with_context(|| f.display().to_string())?;
                if field(&rec, &h, "subset").as_deref() == Some("inliers")
                    && field(&rec, &h, "statistic").as_deref() == Some("pearson")
                    && field(&rec, &h, "row").as_deref() == Some("e_base_z")
                {
                    if let (Some(c), Some(v), Some(n)) = (
                        field(&rec, &h, "column"),
                        number(&rec, &h, "value"),
                        number(&rec, &h, "n"),
                    ) {
                        r_of.insert(c, (v, n));
                    }
                }
            }
            let name = f.file_name().and_then(|n| n.to_str()).unwrap_or_default();
            let cells: Vec<String> = ["e_orb_z", "e_avc_zx", "e_avc_zy"]
                .iter()
                .filter_map(|c| {
                    let (r, n) = r_of.get(*c)?;
                    let (lo, hi) = fisher_ci(*r, *n);
                    Some(format!("{c} {r:.3} [{lo:.3}, {hi:.3}]"))
                })
                .collect();
            if cells.is_empty() {
                continue;
            }
            any = true;
            let rel = dir.strip_prefix(base).unwrap_or(dir).join(name);
            let rel = rel.to_string_lossy().replace('\\', "/");
            let _ = writeln!(md, "- [{rel}]({rel}): {}", cells.join("; "));
        }
    }
    if !any {
        md.push_str(
            "None of the tables read is a Table II (`noisefree analyze correlation` makes one).\n",
        );
    }
    md.push('\n');
    Ok(())
}

/// The 95 % interval of a Pearson r over n pairs (Fisher's z).
pub fn fisher_ci(r: f64, n: f64) -> (f64, f64) {
    if n <= 3.0 {
        return (-1.0, 1.0);
    }
    let z = r.clamp(-0.999_999_999, 0.999_999_999).atanh();
    let se = 1.0 / (n - 3.0).sqrt();
    (
        (z - 1.959_963_984_540_054 * se).tanh(),
        (z + 1.959_963_984_540_054 * se).tanh(),
    )
}

/// Table IV: each technique's frames per second against the baseline's, from `table4.csv`.
fn table4_findings(md: &mut String, dirs: &[PathBuf], base: &Path) -> Result<()> {
    md.push_str(
        "### Table IV: the techniques' cost\n\nThe paper: both techniques keep ORB-SLAM2 real \
         time. Ours (one thread per run; each technique's frames per second over the \
         baseline's on the same sequence, median and range over the sequences of a table):\n\n",
    );
    let mut any = false;
    for dir in dirs {
        let path = dir.join("table4.csv");
        if !path.is_file() || !dir.ends_with("table4-idle") {
            continue;
        }
        let mut rdr = csv::Reader::from_path(&path).with_context(|| path.display().to_string())?;
        let h = rdr.headers()?.clone();
        let mut fps: BTreeMap<(String, String), f64> = BTreeMap::new();
        for rec in rdr.records() {
            let rec = rec.with_context(|| path.display().to_string())?;
            if let (Some(s), Some(c), Some(f)) = (
                field(&rec, &h, "sequence"),
                field(&rec, &h, "system"),
                number(&rec, &h, "fps"),
            ) {
                fps.insert((s, c), f);
            }
        }
        let mut cells = Vec::new();
        for t in TECHNIQUES {
            let mut ratios: Vec<f64> = fps
                .iter()
                .filter(|((_, c), _)| c == t)
                .filter_map(|((s, _), f)| Some(f / fps.get(&(s.clone(), "orb".into()))?))
                .collect();
            if ratios.is_empty() {
                continue;
            }
            ratios.sort_by(f64::total_cmp);
            let med = crate::report::stats::median(&ratios).unwrap_or(f64::NAN);
            cells.push(format!(
                "{} {:.0} % ({:.0} to {:.0} %, {} sequences)",
                heading(t),
                100.0 * med,
                100.0 * ratios[0],
                100.0 * ratios[ratios.len() - 1],
                ratios.len()
            ));
        }
        if !cells.is_empty() {
            any = true;
            let _ = writeln!(
                md,
                "- {}: {}{}",
                link(base, dir, "table4.md"),
                cells.join("; "),
                fps_tests(dir, base)?
            );
        }
    }
    if !any {
        md.push_str(
            "No Table IV here was measured on an idle machine: the findings read Table IV from \
             a folder named `table4-idle`, a sweep run alone on an otherwise idle machine \
             (`noisefree sweep ... --jobs 1 --out results/table4-idle`); `noisefree bench --seq \
             NAME` measures one sequence's cost per frame.\n",
        );
    }
    md.push('\n');
    Ok(())
}

/// What `table4-versus.csv` in `dir` tests: how many differences in frames per second were
/// tested and which survive Holm, with their intervals (empty without the file).
fn fps_tests(dir: &Path, base: &Path) -> Result<String> {
    let path = dir.join("table4-versus.csv");
    if !path.is_file() {
        return Ok(String::new());
    }
    let mut rdr = csv::Reader::from_path(&path).with_context(|| path.display().to_string())?;
    let h = rdr.headers()?.clone();
    let (mut tested, mut survivors) = (0usize, Vec::new());
    for rec in rdr.records() {
        let rec = rec.with_context(|| path.display().to_string())?;
        let Some(survives) = field(&rec, &h, "survives_holm").filter(|s| !s.is_empty()) else {
            continue;
        };
        tested += 1;
        if survives == "1" {
            if let (Some(seq), Some(sys), Some(d), Some(lo), Some(hi)) = (
                field(&rec, &h, "sequence"),
                field(&rec, &h, "system"),
                number(&rec, &h, "diff_pct"),
                number(&rec, &h, "diff_ci95_lo_pct"),
                number(&rec, &h, "diff_ci95_hi_pct"),
            ) {
                survivors.push(format!(
                    "{} on {seq} {d:+.1} % [{lo:+.1}, {hi:+.1}]",
                    heading(&sys)
                ));
            }
        }
    }
    Ok(format!(
        ". In frames per second ({}): {} of {tested} differences survive Holm{}",
        link(base, dir, "table4-versus.md"),
        survivors.len(),
        if survivors.is_empty() {
            ".".to_string()
        } else {
            format!(": {}.", survivors.join("; "))
        }
    ))
}

/// The rows with every repeat of the same runs dropped: a folder may hold runs of another (a
/// sweep's unperturbed runs copied into a second sweep of the same sequences), and the same
/// runs are one piece of evidence, counted once. Rows are the same runs when their cell and
/// every statistic over the runs are bit for bit equal. Of the copies, the one whose table
/// corrects it most (the largest Holm p, the first of equals) is kept: a comparison copied into
/// a table of fewer comparisons must not survive there while it does not in its own.
fn once_each(rows: Vec<VersusRow>) -> Vec<VersusRow> {
    let bits = |v: Option<f64>| v.map(f64::to_bits);
    type Key = (
        String,
        String,
        String,
        Option<[u64; 3]>,
        Option<u64>,
        (usize, usize),
        [Option<u64>; 2],
        Option<[u64; 3]>,
    );
    let key = |r: &VersusRow| -> Key {
        (
            r.sequence.clone(),
            r.perturbation.clone(),
            r.config.clone(),
            r.taus
                .map(|(a, b, c)| [a.to_bits(), b.to_bits(), c.to_bits()]),
            bits(r.b),
            (r.runs, r.failed),
            [bits(r.mean), bits(r.std)],
            r.diff_pct
                .map(|(d, lo, hi)| [d.to_bits(), lo.to_bits(), hi.to_bits()]),
        )
    };
    // For each set of runs, the index of the copy to keep.
    let mut keep: std::collections::HashMap<Key, usize> = Default::default();
    for (i, r) in rows.iter().enumerate() {
        let k = key(r);
        match keep.get(&k) {
            Some(&j) if rows[j].p_holm.unwrap_or(0.0) >= r.p_holm.unwrap_or(0.0) => {}
            _ => {
                keep.insert(k, i);
            }
        }
    }
    let kept: std::collections::HashSet<usize> = keep.into_values().collect();
    rows.into_iter()
        .enumerate()
        .filter(|(i, _)| kept.contains(i))
        .map(|(_, r)| r)
        .collect()
}

fn uses_mcor(c: &str) -> bool {
    c.starts_with("mcor")
}

fn uses_avc(c: &str) -> bool {
    c.ends_with("avc")
}

/// The findings of the tables in `dirs`, links relative to `base` (the folder of the file they
/// go into).
pub fn findings(dirs: &[PathBuf], base: &Path, catalog: &Catalog) -> Result<Findings> {
    // A folder whose sweep has not recorded every run it was asked for is left out, and named.
    let mut left_out = Vec::new();
    let mut complete = Vec::new();
    for d in dirs {
        match crate::planned::completeness_of(d)? {
            Some(c) if !c.is_complete() => left_out.push((d.clone(), c)),
            _ => complete.push(d.clone()),
        }
    }
    let dirs = &complete[..];
    let mut rows = Vec::new();
    for d in dirs {
        rows.extend(read_versus(d)?);
    }
    let rows = once_each(rows);
    let folders = dirs
        .iter()
        .filter(|d| d.join("versus-baseline.csv").is_file())
        .count();
    let comparisons = rows.iter().filter(|r| r.diff_pct.is_some()).count();
    let mut md = format!(
        "## Findings\n\nFrom {} with our ORB-SLAM2 baseline in {} (each table's p-values Holm-corrected together at {ALPHA}; a \
         difference's 95 % interval is Fieller's, of the ratio of the means; paired where runs \
         share seed and perturbation draw). Runs that two tables share count once, under the \
         stricter of their corrections, so a table's count here can be below its own. Every \
         number below is read from the table it links.\n\n",
        counted(comparisons, "comparison", "comparisons"),
        counted(folders, "table", "tables"),
    );
    let identical = rows
        .iter()
        .filter(|r| r.config != "orb" && r.diff_pct.is_none() && r.runs > 1)
        .filter(|r| r.std == Some(0.0))
        .count();
    if comparisons == 0 && identical > 0 {
        md.push_str(&format!(
            "Nothing could be compared: in {} every run gave the same result (a synchronous run \
             is deterministic; its seed only reaches relocalization's RANSAC), so n runs are one \
             and no test exists. Sweep with `--mapping-lag 3` (ORB-SLAM2's thread timing, its \
             run-to-run spread) or `--vary-sequence` (a new synthetic realization per run).\n\n",
            counted(identical, "cell", "cells")
        ));
    }
    if !left_out.is_empty() {
        let named: Vec<String> = left_out
            .iter()
            .map(|(d, c)| format!("{} ({})", link(base, d, "README.md"), c.sentence()))
            .collect();
        md.push_str(&format!(
            "Left out until their sweeps finish: {}.\n\n",
            named.join("; ")
        ));
    }
    let [plain, chained] = table3_findings(&mut md, &rows, catalog, base);
    let lateral = axis_findings(
        &mut md,
        &rows,
        base,
        "MC-OR against lateral depth noise",
        "The paper: MC-OR counters lateral noise (depth misregistered across edges). Ours: \
         MC-OR, and MC-OR with AVC, against the baseline at each level of `depth-lateral`.",
        "depth-lateral",
        uses_mcor,
    );
    let axial = axis_findings(
        &mut md,
        &rows,
        base,
        "AVC against axial depth noise",
        "The paper: AVC combats axial noise (depth error along the ray). Ours: AVC, and AVC with \
         MC-OR, against the baseline at each level of `depth-axial`.",
        "depth-axial",
        uses_avc,
    );
    let readings = readings_findings(&mut md, &rows, catalog, base);
    table1_findings(&mut md, &rows, base);
    table2_findings(&mut md, dirs, base)?;
    table4_findings(&mut md, dirs, base)?;
    variance_findings(&mut md, &rows, base);
    let glance = format!(
        "**Results at a glance** (from {} with our baseline in {}, Holm-corrected at {ALPHA}; \
         intervals, verdicts and links in \
         [results/README.md]({}#findings)):\n\n\
         - Table III on the twins, MC-OR, AVC and both against ORB-SLAM2, unperturbed: {}.\n\
         - The same under a real camera's systematic errors: {}.\n\
         - Under depth noise: MC-OR against lateral noise, {} of {} comparisons gain; AVC \
         against axial noise, {} of {} comparisons gain.\n{}",
        counted(comparisons, "comparison", "comparisons"),
        counted(folders, "table", "tables"),
        results_readme(base),
        plain.sentence(),
        chained.sentence(),
        lateral.1,
        lateral.0,
        axial.1,
        axial.0,
        readings.map_or(String::new(), |r| format!(
            "- The readings of what the paper leaves unsaid (docs/readings.md): {r}.\n"
        ))
    );
    Ok(Findings { full: md, glance })
}

/// Where results/README.md is from `base`.
fn results_readme(base: &Path) -> String {
    if base.join("results").is_dir() && !base.ends_with("results") {
        "results/README.md".into()
    } else {
        "README.md".into()
    }
}

/// The findings in full (results/README.md's block) and in a few lines (README.md's first
/// screen).
#[derive(Clone, Debug, PartialEq)]
pub struct Findings {
    /// Every claim with its table of verdicts.
    pub full: String,
    /// The counts, for a project's first screen.
    pub glance: String,
}

/// The first and last line of the findings block in a Markdown file.
pub const BEGIN: &str = "<!-- findings: begin (generated by `noisefree report`; do not edit) -->";
/// See [`BEGIN`].
pub const END: &str = "<!-- findings: end -->";
/// The first and last line of the glance block (a few lines of the findings).
pub const GLANCE_BEGIN: &str =
    "<!-- glance: begin (generated by `noisefree report`; do not edit) -->";
/// See [`GLANCE_BEGIN`].
pub const GLANCE_END: &str = "<!-- glance: end -->";

/// `text` with the block between `begin` and `end` replaced by `body`; `None` when `begin` is
/// not in `text`, an error when it is not closed.
fn splice_block(text: &str, begin: &str, end: &str, body: &str) -> Result<Option<String>> {
    let Some((i, after_begin)) = marker_line(text, 0, begin) else {
        return Ok(None);
    };
    let (j, after_end) = marker_line(text, after_begin, end)
        .with_context(|| format!("a block is not closed (`{end}`)"))?;
    let terminator = if text[j..after_end].ends_with('\n') {
        "\n"
    } else {
        ""
    };
    Ok(Some(format!(
        "{}{begin}\n{}\n{end}{terminator}{}",
        &text[..i],
        body.trim_end(),
        &text[after_end..]
    )))
}

/// The first line at or after byte `from` of `text` that is the marker `marker` as a person may
/// type it (spaces anywhere, any words after its name, `-->` closing it): its start, and the
/// byte after it.
fn marker_line(text: &str, from: usize, marker: &str) -> Option<(usize, usize)> {
    let squash = |s: &str| s.chars().filter(|c| !c.is_whitespace()).collect::<String>();
    // `<!-- findings: begin (generated ...) -->` is known by `<!--findings:begin`.
    let key = squash(
        marker
            .split(" (")
            .next()
            .unwrap_or(marker)
            .trim_end_matches("-->"),
    );
    let mut at = from;
    for line in text[from..].split_inclusive('\n') {
        let s = squash(line);
        if s.starts_with(&key) && s.ends_with("-->") {
            return Some((at, at + line.len()));
        }
        at += line.len();
    }
    None
}

/// `text` with its findings block and its glance block (whichever it has) replaced; an error
/// when it has neither.
pub fn splice(text: &str, findings: &Findings) -> Result<String> {
    let mut out = text.to_string();
    let mut any = false;
    if let Some(t) = splice_block(&out, BEGIN, END, &findings.full)? {
        out = t;
        any = true;
    }
    if let Some(t) = splice_block(&out, GLANCE_BEGIN, GLANCE_END, &findings.glance)? {
        out = t;
        any = true;
    }
    if !any {
        anyhow::bail!(
            "no findings block (the line `<!-- findings: begin ... -->`) and no glance block \
             (`<!-- glance: begin ... -->`)"
        );
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reading_row(seq: &str, config: &str, d: f64, p_holm: f64) -> VersusRow {
        VersusRow {
            diff_pct: Some((d, d - 3.0, d + 3.0)),
            p_holm: Some(p_holm),
            p: Some(p_holm / 2.0),
            ..VersusRow::example("results/readings/x", seq, config)
        }
    }

    #[test]
    fn the_readings_findings_list_what_survives_holm_and_count_the_rest() {
        let catalog = Catalog::embedded();
        let rows = [
            reading_row("twin_fr3_w_static", "mcor:verdict=consensus", -60.0, 0.003),
            reading_row("twin_fr2_coke", "mcor:verdict=consensus", 29.0, 0.001),
            reading_row("twin_fr2_coke", "mcor:sightings=all", 1.0, 0.9),
            reading_row("twin_fr2_coke", "mcor", -1.0, 0.001),
        ];
        let mut md = String::new();
        let glance = readings_findings(&mut md, &rows, &catalog, Path::new("results")).unwrap();
        assert!(md.contains("| twin_fr3_w_static | `mcor:verdict=consensus` | -60.0 % [-63.0, -57.0] | 0.003 | -96 % (fr3_w_static) |"), "{md}");
        assert!(
            !md.contains("`mcor:sightings=all`"),
            "not told apart: counted, not listed"
        );
        assert!(
            md.contains("3 comparisons of readings: 1 with a lower ATE"),
            "{md}"
        );
        assert!(
            md.contains("all 4 comparisons of the folder that tried"),
            "{md}"
        );
        assert!(
            glance.starts_with("3 comparisons: **1 lower ATE after Holm over the study**"),
            "{glance}"
        );
        assert!(glance.ends_with(", 1 higher"), "{glance}");
        assert!(
            glance.contains("(largest: `mcor:verdict=consensus` on twin_fr3_w_static -60.0 %"),
            "{glance}"
        );
        // Without reading columns there is nothing to say.
        assert!(
            readings_findings(&mut String::new(), &rows[3..], &catalog, Path::new("r")).is_none()
        );
    }

    #[test]
    fn variance_ratio_matches_scipy() {
        // scipy 1.17.1: F = 0.5**2 / 1.0**2 with (9, 9) degrees of freedom;
        // p = 2 * min(f.cdf(F, 9, 9), f.sf(F, 9, 9)) = 0.0510033, interval
        // F / f.ppf(0.975, 9, 9), F / f.ppf(0.025, 9, 9).
        let (ratio, lo, hi, p) = variance_ratio_test(0.5, 10, 1.0, 10).unwrap();
        assert!((ratio - 0.25).abs() < 1e-12);
        assert!((p - 0.051_003_260_706_950_84).abs() < 1e-9, "{p}");
        assert!((lo - 0.062_096_463_673_613_725).abs() < 1e-9, "{lo}");
        assert!((hi - 1.006_498_539_570_744_6).abs() < 1e-9, "{hi}");
        assert!(variance_ratio_test(0.0, 10, 1.0, 10).is_none());
    }

    #[test]
    fn fisher_interval_matches_its_definition() {
        // r = 0.5, n = 28: z = atanh(0.5), se = 0.2; numpy: tanh(z -+ 1.959964 se).
        let (lo, hi) = fisher_ci(0.5, 28.0);
        assert!((lo - 0.156_028_362_529_086).abs() < 1e-9, "{lo}");
        assert!((hi - 0.735_818_479_443_937_6).abs() < 1e-9, "{hi}");
    }

    #[test]
    fn the_same_runs_in_two_folders_count_once() {
        let row = |folder: &str, config: &str, mean: f64, diff: Option<f64>| VersusRow {
            mean: Some(mean),
            std: Some(0.0001),
            diff_pct: diff.map(|d| (d, d - 1.0, d + 1.0)),
            p_holm: Some(1.0),
            ..VersusRow::example(folder, "twin_fr2_coke", config)
        };
        let rows = vec![
            row("a", "orb", 0.0035, None),
            row("a", "avc", 0.0036, Some(2.9)),
            // The same runs copied into folder b: dropped, folder a's kept.
            row("b", "orb", 0.0035, None),
            row("b", "avc", 0.0036, Some(2.9)),
            // Another system (b, mcor) and other runs of a cell, one bit apart (c): kept.
            row("b", "mcor", 0.0036, Some(2.9)),
            row(
                "c",
                "avc",
                f64::from_bits(0.0036f64.to_bits() + 1),
                Some(2.9),
            ),
            // The same runs in a table of fewer comparisons (d, surviving there) and of more
            // (e, not surviving): e's copy is kept, wherever it comes.
            VersusRow {
                p_holm: Some(0.01),
                ..row("d", "rc", 0.0040, Some(-5.0))
            },
            VersusRow {
                p_holm: Some(0.3),
                ..row("e", "rc", 0.0040, Some(-5.0))
            },
        ];
        let kept = once_each(rows);
        let names: Vec<(String, String)> = kept
            .iter()
            .map(|r| (r.folder.display().to_string(), r.config.clone()))
            .collect();
        let pair = |f: &str, c: &str| (f.to_string(), c.to_string());
        assert_eq!(
            names,
            [
                pair("a", "orb"),
                pair("a", "avc"),
                pair("b", "mcor"),
                pair("c", "avc"),
                pair("e", "rc")
            ]
        );
    }

    #[test]
    fn an_axis_table_without_a_gain_names_none() {
        let row = |folder: &str, diff: f64| VersusRow {
            perturbation: "depth-axial:512".into(),
            axis: Some("depth-axial".into()),
            diff_pct: Some((diff, diff - 5.0, diff + 5.0)),
            p_holm: Some(1.0),
            ..VersusRow::example(folder, "twin_fr2_coke", "avc")
        };
        let rows = [
            row("gains", -4.0),
            row("gains", 3.0),
            row("losses", 3.0),
            row("losses", 11.0),
        ];
        let mut md = String::new();
        axis_findings(
            &mut md,
            &rows,
            Path::new("."),
            "t",
            "c",
            "depth-axial",
            uses_avc,
        );
        assert!(md.contains("| -4.0 % [-9.0, +1.0] (avc,"), "{md}");
        assert!(
            md.contains("| none; the lowest, +3.0 % [-2.0, +8.0] (avc,"),
            "{md}"
        );
    }

    #[test]
    fn the_block_is_replaced_between_its_markers_only() {
        let f = Findings {
            full: "## Findings\n\nnew\n".into(),
            glance: "**at a glance**\n".into(),
        };
        let text = format!("# R\n\nintro\n{BEGIN}\nold\n{END}\n\n## rest\n");
        let out = splice(&text, &f).unwrap();
        assert_eq!(
            out,
            format!("# R\n\nintro\n{BEGIN}\n## Findings\n\nnew\n{END}\n\n## rest\n")
        );
        let both = format!("{GLANCE_BEGIN}\nold\n{GLANCE_END}\nmid\n{BEGIN}\n{END}\n");
        assert_eq!(
            splice(&both, &f).unwrap(),
            format!(
                "{GLANCE_BEGIN}\n**at a glance**\n{GLANCE_END}\nmid\n{BEGIN}\n## Findings\n\nnew\n{END}\n"
            )
        );
        assert!(splice("no block", &f).is_err());
        assert!(splice(&format!("{BEGIN}\nnever closed"), &f).is_err());
    }

    #[test]
    fn markers_are_known_as_a_person_types_them() {
        let f = Findings {
            full: "## Findings\n".into(),
            glance: "g\n".into(),
        };
        // Without the note in brackets, spaced differently: the canonical lines come back.
        let typed = "a\n<!--findings: begin -->\nold\n  <!-- findings:end-->\nb";
        assert_eq!(
            splice(typed, &f).unwrap(),
            format!("a\n{BEGIN}\n## Findings\n{END}\nb")
        );
        // A line that merely mentions the marker is not one.
        assert!(splice("see <!-- findings: begin --> in text\n", &f).is_err());
    }
}
