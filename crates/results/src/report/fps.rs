//! Table IV's statistics: per sequence and system the frames per second of its runs (n, mean,
//! std, median, the 95 % interval of the mean by Student's t), and each of our techniques
//! against the baseline on the same runs: the difference in % of the baseline's mean with its
//! 95 % interval and p-value (paired t where the runs share seed, draw and scene, Welch
//! otherwise), Holm-corrected over the table. Speed is what the paper's Table IV claims for
//! the techniques, so it gets the intervals the accuracy tables have.

use crate::columns::ConfigKind;
use crate::report::markdown::{counted, render, system_label, Rendered};
use crate::report::stats::{summarize, Comparison, Summary};
use crate::report::tables::{fps_cell, our_runs, sequence_order};
use crate::report::versus::{
    compare, difference_text, holm_where_tested, p_text, pair_key, PairKey, ALPHA,
};
use crate::store::RunRecord;
use datasets::Catalog;
use std::collections::BTreeMap;

/// One system's frames per second on one sequence, with its comparison to the baseline.
struct Row {
    sequence: String,
    config: &'static str,
    summary: Summary,
    comparison: Option<Comparison>,
}

/// Our runs of `config` on `seq` with the default parameters, frames per second by pair key.
fn fps_of(records: &[RunRecord], seq: &str, config: &str) -> BTreeMap<PairKey, f64> {
    our_runs(records, seq, config)
        .into_iter()
        .map(|r| (pair_key(r), r.fps))
        .collect()
}

/// Each of our techniques against the baseline in frames per second, one row per sequence and
/// system, Holm-corrected over the table; `None` without a baseline and another of our columns.
pub fn fps_versus(
    records: &[RunRecord],
    catalog: &Catalog,
    labels: &BTreeMap<String, String>,
) -> Option<Rendered> {
    let mut rows: Vec<Row> = Vec::new();
    for seq in sequence_order(records, catalog) {
        let base = fps_of(records, &seq, "orb");
        if base.is_empty() {
            continue;
        }
        for kind in ConfigKind::EVERY {
            let config = kind.name();
            let runs = fps_of(records, &seq, config);
            let Some(summary) = summarize(&runs.values().copied().collect::<Vec<_>>()) else {
                continue;
            };
            rows.push(Row {
                sequence: seq.clone(),
                config,
                summary,
                comparison: (config != "orb").then(|| compare(&base, &runs)).flatten(),
            });
        }
    }
    if !rows.iter().any(|r| r.config != "orb") {
        return None;
    }
    let p_holm = holm_where_tested(rows.iter().map(|r| r.comparison.as_ref()));
    let tested = p_holm.iter().flatten().count();
    let header: Vec<String> = [
        "sequence",
        "system",
        "n",
        "frames/s, mean [95 % CI]",
        "median",
        "vs baseline [95 % CI]",
        "test",
        "p",
        "p (Holm)",
    ]
    .map(String::from)
    .to_vec();
    let mut md_rows = Vec::new();
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record([
        "sequence",
        "system",
        "label",
        "n",
        "fps_mean",
        "fps_std",
        "fps_median",
        "fps_ci95_lo",
        "fps_ci95_hi",
        "test",
        "diff_pct",
        "diff_ci95_lo_pct",
        "diff_ci95_hi_pct",
        "p",
        "p_holm",
        "survives_holm",
    ]);
    for (r, ph) in rows.iter().zip(&p_holm) {
        let survives = ph.is_some_and(|p| p <= ALPHA);
        let versus = match (&r.comparison, r.config) {
            (_, "orb") => "(baseline)".to_string(),
            (None, _) => "runs identical: no test".to_string(),
            (Some(c), _) => difference_text(c, survives),
        };
        md_rows.push(vec![
            r.sequence.clone(),
            system_label(r.config, labels),
            r.summary.n.to_string(),
            fps_cell(&r.summary),
            format!("{:.1}", r.summary.median),
            versus,
            r.comparison
                .map_or_else(|| "-".into(), |c| c.test.name().into()),
            r.comparison.map_or_else(|| "-".into(), |c| p_text(c.p)),
            ph.map_or_else(|| "-".into(), p_text),
        ]);
        let num = |v: Option<f64>| v.map(|x| x.to_string()).unwrap_or_default();
        let rel = r
            .comparison
            .map(|c| (c.relative_pct(), c.relative_ci95_pct()));
        let _ = w.write_record([
            r.sequence.clone(),
            r.config.to_string(),
            system_label(r.config, labels),
            r.summary.n.to_string(),
            r.summary.mean.to_string(),
            num(r.summary.std),
            r.summary.median.to_string(),
            num(r.summary.ci95.map(|c| c.0)),
            num(r.summary.ci95.map(|c| c.1)),
            r.comparison
                .map_or_else(String::new, |c| c.test.name().to_string()),
            num(rel.map(|x| x.0)),
            num(rel.map(|x| x.1 .0)),
            num(rel.map(|x| x.1 .1)),
            num(r.comparison.map(|c| c.p)),
            num(*ph),
            if r.comparison.is_some() {
                u8::from(survives).to_string()
            } else {
                String::new()
            },
        ]);
    }
    let notes = format!(
        "Wall-clock frames per second of one run on one core: mean of the runs with the 95 % \
         interval of the mean (Student's t) and the median; each technique against our ORB-SLAM2 \
         baseline on the same sequence: the difference of mean frames per second in % of the \
         baseline's (positive: faster), its 95 % interval and two-sided p, by the paired t-test \
         where both ran the same seeds and draws, Welch's otherwise. {} in this table, \
         Holm-corrected together; **bold** survives at 0.05. Runs of a sweep share the \
         machine's cores, so these compare columns of one sweep, not machines.",
        counted(tested, "comparison", "comparisons")
    );
    let mut t = render(
        "Table IV: each system's frames per second against the baseline",
        &notes,
        &header,
        &md_rows,
    );
    t.csv = String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default();
    Some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::versus::tests::record;

    fn run(seq: &str, config: &str, seed: u64, fps: f64) -> RunRecord {
        RunRecord {
            fps,
            ..record(seq, config, seed, 0.01, None)
        }
    }

    #[test]
    fn a_technique_a_tenth_faster_on_every_run_is_plus_ten_percent_and_survives() {
        let base = [100.0, 104.0, 96.0, 101.0, 99.0];
        let mut records = Vec::new();
        for (seed, &f) in base.iter().enumerate() {
            records.push(run("kinect", "orb", seed as u64, f));
            records.push(run("kinect", "avc", seed as u64, 1.1 * f));
            // MC-OR: the baseline's figures in another order, so only a paired test sees them.
            records.push(run("kinect", "mcor", seed as u64, base[(seed + 1) % 5]));
        }
        let t = fps_versus(&records, &Catalog::embedded(), &BTreeMap::new()).unwrap();
        let rows: Vec<csv::StringRecord> = csv::Reader::from_reader(t.csv.as_bytes())
            .records()
            .map(|r| r.unwrap())
            .collect();
        let get = |config: &str, col: usize| -> String {
            rows.iter().find(|r| &r[1] == config).unwrap()[col].to_string()
        };
        // Columns: sequence, system, label, n, fps_mean, ..., test 9, diff_pct 10, lo 11, hi 12,
        // p 13, p_holm 14, survives_holm 15.
        assert_eq!(get("orb", 3), "5");
        assert!((get("orb", 4).parse::<f64>().unwrap() - 100.0).abs() < 1e-9);
        let pct: f64 = get("avc", 10).parse().unwrap();
        assert!((pct - 10.0).abs() < 1e-9, "{pct}");
        assert_eq!(get("avc", 9), "paired t");
        assert_eq!(get("avc", 15), "1");
        let (lo, hi): (f64, f64) = (
            get("avc", 11).parse().unwrap(),
            get("avc", 12).parse().unwrap(),
        );
        assert!(lo < 10.0 && 10.0 < hi && hi - lo < 2.0, "[{lo}, {hi}]");
        // The same figures shuffled: no difference in the mean, and none survives.
        assert!(get("mcor", 10).parse::<f64>().unwrap().abs() < 1e-9);
        assert_eq!(get("mcor", 15), "0");
        assert!(t.markdown.contains("**+10.0 % ["), "{}", t.markdown);
        assert!(t.markdown.contains("2 comparisons in this table"));
        // The Table IV cell carries the interval of the mean.
        let runs = our_runs(&records, "kinect", "orb");
        let s = crate::report::tables::fps_summary(&runs).unwrap();
        assert!(fps_cell(&s).starts_with("100.0 ["), "{}", fps_cell(&s));
    }
}
