//! The readings study's table (issue 72): per row and technique, the technique under every
//! reading a sweep ran against the baseline, readings with a lower mean first, beside the
//! paper's gain for that technique; and what it adds up to, one sentence per technique. Read
//! from the folder's versus-baseline rows, so its intervals and Holm-corrected p-values are that
//! table's (Holm over every comparison the folder holds, readings included).

use crate::columns::ConfigKind;
use crate::readings::ReadingColumn;
use crate::report::findings::VersusRow;
use crate::report::markdown::{column_name, render, system_label, Rendered};
use crate::report::versus::{paper_figures, relative_text};
use datasets::Catalog;
use std::collections::BTreeMap;

/// The techniques whose readings the table groups: the paper's three.
const TECHNIQUES: [ConfigKind; 3] = [ConfigKind::Mcor, ConfigKind::Avc, ConfigKind::McorAvc];

/// The technique a versus row's column runs (`mcor`, or a reading of it), `None` for other
/// columns.
fn technique_of(config: &str) -> Option<ConfigKind> {
    let kind = match ReadingColumn::parse(config).ok().flatten() {
        Some(r) => r.kind,
        None => ConfigKind::parse(config).ok()?,
    };
    TECHNIQUES.contains(&kind).then_some(kind)
}

/// The readings table of a folder's versus-baseline `rows`; `None` when the folder ran no
/// reading.
pub fn readings_table(
    rows: &[VersusRow],
    catalog: &Catalog,
    labels: &BTreeMap<String, String>,
) -> Option<Rendered> {
    if !rows
        .iter()
        .any(|r| matches!(ReadingColumn::parse(&r.config), Ok(Some(_))))
    {
        return None;
    }
    let comparisons = rows.iter().filter(|r| r.diff_pct.is_some()).count();
    // (sequence, perturbation, technique) -> its rows.
    let mut groups: BTreeMap<(String, String, usize), Vec<&VersusRow>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.diff_pct.is_some()) {
        let Some(t) = technique_of(&r.config) else {
            continue;
        };
        let rank = TECHNIQUES.iter().position(|k| *k == t).unwrap_or(0);
        groups
            .entry((r.sequence.clone(), r.perturbation.clone(), rank))
            .or_default()
            .push(r);
    }
    let header: Vec<String> = [
        "sequence",
        "point",
        "technique",
        "paper",
        "column",
        "n",
        "mean (mm)",
        "difference [95 % interval]",
        "Holm p",
        "verdict",
    ]
    .map(String::from)
    .to_vec();
    let mut table = Vec::new();
    let mut tally: BTreeMap<usize, Tally> = BTreeMap::new();
    for ((seq, point, rank), mut members) in groups {
        let technique = TECHNIQUES[rank];
        members.sort_by(|a, b| {
            let d = |r: &VersusRow| r.diff_pct.map_or(f64::INFINITY, |d| d.0);
            d(a).total_cmp(&d(b)).then_with(|| a.config.cmp(&b.config))
        });
        let paper = paper_figures(catalog, &seq, technique.name())
            .map(|(m, orb, _)| format!("{:+.0} %", (m / orb - 1.0) * 100.0))
            .unwrap_or_else(|| "-".into());
        let t = tally.entry(rank).or_default();
        t.cells += 1;
        for r in members {
            let (d, lo, hi) = r.diff_pct.expect("filtered");
            let verdict = match (r.survives(), d < 0.0) {
                (true, true) => {
                    t.gains.push(format!("{seq} {}", short(&r.config)));
                    "lower ATE"
                }
                (true, false) => {
                    t.losses += 1;
                    "higher ATE"
                }
                _ => "not told apart",
            };
            t.compared += 1;
            table.push(vec![
                seq.clone(),
                point.clone(),
                column_name(technique).to_string(),
                paper.clone(),
                system_label(&r.config, labels),
                format!("{} ({} failed)", r.runs, r.failed),
                r.mean.map_or("-".into(), |m| format!("{:.2}", m * 1e3)),
                relative_text(d, (lo, hi)),
                r.p_holm.map_or("-".into(), |p| format!("{p:.3}")),
                verdict.to_string(),
            ]);
        }
    }
    let sentences: Vec<String> = tally
        .iter()
        .map(|(rank, t)| t.sentence(column_name(TECHNIQUES[*rank])))
        .collect();
    let notes = format!(
        "Every column of a technique (the technique as Table III runs it, and under each reading \
         its name gives) against our baseline on the same runs' seeds, lowest mean difference \
         first. The difference, its interval (Fieller's) and the Holm-corrected p are the \
         folder's versus-baseline table's: Holm over all {comparisons} comparisons of the \
         folder, so trying many readings is counted. `paper`: the paper's gain for the \
         technique on the row the twin imitates. {}",
        sentences.join(" ")
    );
    Some(render(
        "The readings: each technique under every reading against the baseline",
        &notes,
        &header,
        &table,
    ))
}

/// A column's name without its technique, for the sentences: `sightings=all` or `as Table III`.
fn short(config: &str) -> String {
    match config.split_once(':') {
        Some((_, readings)) => readings.to_string(),
        None => "as Table III".to_string(),
    }
}

/// What one technique's comparisons add up to.
#[derive(Default)]
struct Tally {
    /// (row, point) cells.
    cells: usize,
    /// Comparisons.
    compared: usize,
    /// The (row, reading) pairs with a lower ATE after Holm.
    gains: Vec<String>,
    /// Comparisons with a higher ATE after Holm.
    losses: usize,
}

impl Tally {
    /// The technique's sentence: only what the table shows.
    fn sentence(&self, technique: &str) -> String {
        let gains = if self.gains.is_empty() {
            "none has a lower ATE after Holm".to_string()
        } else {
            format!(
                "{} {} a lower ATE after Holm ({})",
                self.gains.len(),
                if self.gains.len() == 1 { "has" } else { "have" },
                self.gains.join("; ")
            )
        };
        format!(
            "{technique}: of {} comparisons over {} rows and points, {gains}, and {} {} a higher \
             one.",
            self.compared,
            self.cells,
            self.losses,
            if self.losses == 1 { "has" } else { "have" }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(seq: &str, config: &str, diff: Option<f64>, p_holm: Option<f64>) -> VersusRow {
        VersusRow {
            diff_pct: diff.map(|d| (d, d - 5.0, d + 5.0)),
            p_holm,
            p: p_holm,
            ..VersusRow::example("f", seq, config)
        }
    }

    #[test]
    fn readings_are_grouped_by_technique_best_first_and_summed_up_as_the_table_says() {
        let catalog = Catalog::embedded();
        let rows = [
            row("twin_fr2_coke", "orb", None, None),
            row("twin_fr2_coke", "mcor", Some(1.0), Some(0.9)),
            row(
                "twin_fr2_coke",
                "mcor:sightings=all",
                Some(-30.0),
                Some(0.01),
            ),
            row(
                "twin_fr2_coke",
                "mcor:verdict=consensus",
                Some(40.0),
                Some(0.001),
            ),
            row("twin_fr2_coke", "avc", Some(-2.0), Some(0.5)),
            row("twin_fr2_coke", "rc", Some(-2.0), Some(0.5)),
        ];
        let t = readings_table(&rows, &catalog, &BTreeMap::new()).unwrap();
        let body: Vec<&str> = t
            .markdown
            .lines()
            .filter(|l| l.starts_with("| twin"))
            .collect();
        // MC-OR's three columns, the lowest first, then AVC's one; rc is no technique of the paper.
        assert_eq!(body.len(), 4, "{}", t.markdown);
        assert!(
            body[0].contains("w/ MC-OR [sightings all] (ours)"),
            "{}",
            body[0]
        );
        assert!(body[0].contains("lower ATE") && body[0].contains("| -55 % |"));
        assert!(body[2].contains("verdict consensus") && body[2].contains("higher ATE"));
        assert!(body[3].contains("w/ AVC (ours)") && body[3].contains("not told apart"));
        assert!(
            t.markdown.contains(
                "w/ MC-OR: of 3 comparisons over 1 rows and points, 1 has a lower ATE after \
                 Holm (twin_fr2_coke sightings=all), and 1 has a higher one."
            ),
            "{}",
            t.markdown
        );
        assert!(t.markdown.contains("Holm over all 5 comparisons"));
        // A folder without readings has no such table.
        assert!(readings_table(&rows[..2], &catalog, &BTreeMap::new()).is_none());
    }
}
