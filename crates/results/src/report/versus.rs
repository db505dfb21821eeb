//! Every system against the baseline, with the statistics a claim needs: per sequence and
//! perturbation point, each system's n, mean, median and the 95 % interval of its mean, and its
//! difference from our ORB-SLAM2 baseline in % of the baseline's mean with a 95 % interval and
//! a p-value (paired t where both ran on the same seeds and perturbation draws, Welch's t
//! otherwise), Holm-corrected over every comparison of the table. The Markdown marks a difference
//! only where it survives the correction; the tidy CSV holds every number. With `--paper`, a twin
//! row carries the paper's ORB-SLAM2 figure and the paper's relative difference for the same
//! technique on the sequence the twin imitates, beside ours.

use crate::columns::ConfigKind;
use crate::report::markdown::{counted, render, system_label, Rendered};
use crate::report::stats::{holm, paired, summarize, welch, Comparison, Summary};
use crate::report::tables::{are_default_params, mm_decimals, num, sequence_order};
use crate::store::RunRecord;
use datasets::Catalog;
use std::cmp::Ordering;
use std::collections::BTreeMap;

/// The significance level of the tables' marks (after Holm's correction).
pub const ALPHA: f64 = 0.05;

/// The key that makes two runs a pair: same SLAM seed, perturbation draw and synthetic scene.
pub type PairKey = (u64, Option<u64>, Option<u64>);

/// The pair key of a run.
pub fn pair_key(r: &RunRecord) -> PairKey {
    (r.seed, r.perturb_seed, r.synth_seed)
}

/// The runs of one system at one sequence and point that produced an ATE, by pair key.
fn ates(runs: &[&RunRecord]) -> BTreeMap<PairKey, f64> {
    runs.iter()
        .filter(|r| !r.failed)
        .filter_map(|r| Some((pair_key(r), r.ate_rmse?)))
        .collect()
}

/// A system against the baseline on the runs they share (paired) when at least two pairs
/// exist and every run of each has its partner; Welch's test otherwise; `None` when each
/// system's runs are all identical (one result each, whatever the seeds: no spread to test
/// against).
pub fn compare(
    baseline: &BTreeMap<PairKey, f64>,
    other: &BTreeMap<PairKey, f64>,
) -> Option<Comparison> {
    // Two groups of identical runs are one result each: no spread, nothing to test.
    let constant = |m: &BTreeMap<PairKey, f64>| {
        let mut v = m.values();
        v.next().is_none_or(|first| v.all(|x| x == first))
    };
    if constant(baseline) && constant(other) {
        return None;
    }
    let shared: Vec<&PairKey> = baseline.keys().filter(|k| other.contains_key(k)).collect();
    if shared.len() >= 2 && shared.len() == baseline.len() && shared.len() == other.len() {
        let b: Vec<f64> = shared.iter().map(|k| baseline[k]).collect();
        let o: Vec<f64> = shared.iter().map(|k| other[k]).collect();
        return paired(&b, &o);
    }
    let b: Vec<f64> = baseline.values().copied().collect();
    let o: Vec<f64> = other.values().copied().collect();
    welch(&b, &o)
}

/// A system with its parameters: one column of Table III, or one b of Table I, or one cell of
/// the threshold grid.
#[derive(Clone, Debug, PartialEq)]
struct Variant {
    config: String,
    taus: Option<(f64, f64, f64)>,
    b: Option<f64>,
}

impl Variant {
    fn of(r: &RunRecord) -> Variant {
        Variant {
            config: r.config.clone(),
            taus: match (r.tau_mf, r.tau_gf, r.tau_mg) {
                (Some(a), Some(b), Some(c)) => Some((a, b, c)),
                _ => None,
            },
            b: r.baseline,
        }
    }

    /// Our ORB-SLAM2 baseline, which has no parameters.
    fn baseline() -> Variant {
        Variant {
            config: "orb".into(),
            taus: None,
            b: None,
        }
    }

    /// Whether these are the parameters Table III reports.
    fn is_default(&self) -> bool {
        are_default_params(self.taus, self.b)
    }

    /// Columns in the paper's order, then by parameters.
    fn order(a: &Variant, b: &Variant) -> Ordering {
        let rank = |c: &str| {
            ConfigKind::parse(c).map_or(usize::MAX, |k| {
                ConfigKind::EVERY.iter().position(|e| *e == k).unwrap_or(0)
            })
        };
        let taus = |v: &Variant| v.taus.map_or([f64::NEG_INFINITY; 3], |t| [t.0, t.1, t.2]);
        (rank(&a.config), &a.config)
            .cmp(&(rank(&b.config), &b.config))
            .then_with(|| {
                let (x, y) = (taus(a), taus(b));
                x.iter()
                    .zip(&y)
                    .map(|(p, q)| p.total_cmp(q))
                    .find(|o| o.is_ne())
                    .unwrap_or(Ordering::Equal)
            })
            .then_with(|| {
                a.b.unwrap_or(f64::NEG_INFINITY)
                    .total_cmp(&b.b.unwrap_or(f64::NEG_INFINITY))
            })
    }

    /// The system's heading, with its parameters where they are not Table III's.
    fn label(&self, labels: &BTreeMap<String, String>) -> String {
        let name = system_label(&self.config, labels);
        if self.is_default() {
            return name;
        }
        let mut p = Vec::new();
        if let Some((mf, gf, mg)) = self.taus {
            p.push(format!("τ_MF {mf}, τ_GF {gf}, τ_MG {mg}"));
        }
        if let Some(b) = self.b {
            p.push(format!("b {b}"));
        }
        format!("{name} ({})", p.join("; "))
    }
}

/// One row: a system at one sequence and point.
struct Row {
    sequence: String,
    point: String,
    /// The axis and level of the point (`None`: unperturbed or a fixed chain).
    axis: Option<(String, Option<f64>)>,
    config: String,
    variant: Variant,
    runs: usize,
    failed: usize,
    /// Both this system's runs and the baseline's are each all identical (nothing to test).
    identical: bool,
    summary: Option<Summary>,
    comparison: Option<Comparison>,
    /// The paper's ATE for this system's column on the imitated row (metres), and its
    /// ORB-SLAM2 figure there.
    paper: Option<(f64, f64)>,
}

/// The paper's figure (metres) of `config`'s column for the row `seq` is or imitates, with its
/// ORB-SLAM2 figure and the row's name.
pub fn paper_figures(catalog: &Catalog, seq: &str, config: &str) -> Option<(f64, f64, String)> {
    let entry = catalog.get(seq).ok()?;
    let row = match entry.imitates.as_deref() {
        Some(name) => catalog.get(name).ok()?,
        None => entry,
    };
    let p = row.paper.as_ref()?;
    // A reading of a technique is compared with the paper's figure for that technique.
    let kind = ConfigKind::parse(config).ok().or_else(|| {
        crate::readings::ReadingColumn::parse(config)
            .ok()
            .flatten()
            .map(|r| r.kind)
    })?;
    let col = match kind {
        ConfigKind::Orb => p.orb_slam2,
        ConfigKind::Mcor => p.mcor,
        ConfigKind::Avc => p.avc,
        ConfigKind::McorAvc => p.mcor_avc,
        _ => None,
    }?;
    Some((col.metres()?, p.orb_slam2?.metres()?, row.name.clone()))
}

/// The point a run belongs to, as the table names it: the axis and level where the sweep had
/// one, the whole chain otherwise (`none` unperturbed).
fn point_of(r: &RunRecord) -> String {
    match (&r.perturb_family, &r.perturbation) {
        (Some(f), _) => match r.perturb_level {
            Some(l) => format!("{f}:{l}"),
            None => f.clone(),
        },
        (None, Some(p)) => perturb::Chain::parse(p)
            .ok()
            .and_then(|c| c.named())
            .map_or_else(|| p.clone(), |(c, l)| format!("{}:{l}", c.name())),
        (None, None) => "none".into(),
    }
}

/// The table of every system against the baseline (our `orb`) at every sequence and point of
/// a sweep with the default parameters; `None` when no sequence has the baseline and another
/// system side by side.
pub fn versus_baseline(
    records: &[RunRecord],
    catalog: &Catalog,
    paper: bool,
    labels: &BTreeMap<String, String>,
) -> Option<Rendered> {
    let records: Vec<&RunRecord> = records.iter().collect();
    let mut variants: Vec<Variant> = records.iter().map(|r| Variant::of(r)).collect();
    variants.sort_by(Variant::order);
    variants.dedup();
    let owned: Vec<RunRecord> = records.iter().map(|r| (*r).clone()).collect();
    let mut rows: Vec<Row> = Vec::new();
    for seq in sequence_order(&owned, catalog) {
        let mut points: Vec<String> = Vec::new();
        let mut keyed: Vec<(u8, String, f64, String)> = Vec::new();
        for r in records.iter().filter(|r| r.sequence == seq) {
            let p = point_of(r);
            if !points.contains(&p) {
                // The unperturbed point first, then by axis and level.
                let perturbed = u8::from(r.perturbation.is_some() && p != "none");
                let axis = r.perturb_family.clone().unwrap_or_default();
                keyed.push((perturbed, axis, r.perturb_level.unwrap_or(0.0), p.clone()));
                points.push(p);
            }
        }
        keyed.sort_by(|a, b| (a.0, &a.1).cmp(&(b.0, &b.1)).then(a.2.total_cmp(&b.2)));
        let points: Vec<String> = keyed.into_iter().map(|k| k.3).collect();
        for point in points {
            let group = |v: &Variant| -> Vec<&RunRecord> {
                records
                    .iter()
                    .filter(|r| r.sequence == seq && point_of(r) == point && Variant::of(r) == *v)
                    .copied()
                    .collect()
            };
            let baseline = Variant::baseline();
            let base_runs = group(&baseline);
            if base_runs.is_empty()
                || !variants
                    .iter()
                    .any(|v| *v != baseline && !group(v).is_empty())
            {
                continue;
            }
            let base = ates(&base_runs);
            for v in &variants {
                let runs = group(v);
                if runs.is_empty() {
                    continue;
                }
                let these = ates(&runs);
                let values: Vec<f64> = these.values().copied().collect();
                rows.push(Row {
                    sequence: seq.clone(),
                    point: point.clone(),
                    axis: runs[0]
                        .perturb_family
                        .clone()
                        .map(|f| (f, runs[0].perturb_level)),
                    config: v.config.clone(),
                    variant: v.clone(),
                    runs: runs.len(),
                    failed: runs.iter().filter(|r| r.failed).count(),
                    identical: *v != baseline
                        && these.len() > 1
                        && base.len() > 1
                        && compare(&base, &these).is_none(),
                    summary: summarize(&values),
                    comparison: (*v != baseline).then(|| compare(&base, &these)).flatten(),
                    paper: if paper && v.is_default() {
                        paper_figures(catalog, &seq, &v.config).map(|(a, b, _)| (a, b))
                    } else {
                        None
                    },
                });
            }
        }
    }
    if !rows.iter().any(|r| r.config != "orb") {
        return None;
    }
    let p_holm = holm_where_tested(rows.iter().map(|r| r.comparison.as_ref()));
    let tested = p_holm.iter().flatten().count();
    Some(render_rows(&rows, &p_holm, tested, paper, labels))
}

/// Holm's correction over the rows of one table that were tested: each tested row's adjusted
/// p in row order, `None` where nothing was tested.
pub fn holm_where_tested<'a>(
    comparisons: impl Iterator<Item = Option<&'a Comparison>> + Clone,
) -> Vec<Option<f64>> {
    let p: Vec<f64> = comparisons.clone().flatten().map(|c| c.p).collect();
    let mut adjusted = holm(&p).into_iter();
    comparisons
        .map(|c| c.and_then(|_| adjusted.next()))
        .collect()
}

/// A difference in % with its interval, as every table and the findings print it:
/// `+1.2 % [-0.3, +2.7]`, or `+1.2 % [unbounded]` when an end is infinite (Fieller's interval
/// when the baseline's mean is not told from zero).
pub fn relative_text(pct: f64, (lo, hi): (f64, f64)) -> String {
    if lo.is_finite() && hi.is_finite() {
        format!("{pct:+.1} % [{lo:+.1}, {hi:+.1}]")
    } else {
        format!("{pct:+.1} % [unbounded]")
    }
}

/// A difference against the baseline as the tables print it ([`relative_text`]), in bold when
/// it survives Holm's correction.
pub fn difference_text(c: &Comparison, survives: bool) -> String {
    let t = relative_text(c.relative_pct(), c.relative_ci95_pct());
    if survives {
        format!("**{t}**")
    } else {
        t
    }
}

fn render_rows(
    rows: &[Row],
    p_holm: &[Option<f64>],
    comparisons: usize,
    paper: bool,
    labels: &BTreeMap<String, String>,
) -> Rendered {
    let d = mm_decimals(rows.iter().filter_map(|r| r.summary.map(|s| s.mean)));
    let mut header: Vec<String> = [
        "Sequence",
        "Perturbation",
        "System",
        "n (failed)",
        "mean [95 % CI] (mm)",
        "median (mm)",
        "vs baseline [95 % CI]",
        "test",
        "p",
        "p (Holm)",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    if paper {
        header.extend(["paper (mm)".into(), "paper vs its ORB-SLAM2".into()]);
    }
    let mut md_rows = Vec::new();
    let mut csv_rows = Vec::new();
    for (r, ph) in rows.iter().zip(p_holm) {
        let mm = |v: f64| format!("{:.d$}", v * 1e3);
        let mean = r.summary.map_or_else(
            || "F".into(),
            |s| match s.ci95 {
                Some((lo, hi)) => format!("{} [{}, {}]", mm(s.mean), mm(lo), mm(hi)),
                None => mm(s.mean),
            },
        );
        let survives = ph.is_some_and(|p| p <= ALPHA);
        let versus = r.comparison.map_or_else(
            || {
                if r.config == "orb" {
                    "(baseline)".into()
                } else if r.identical {
                    "runs identical: no test".into()
                } else {
                    "-".into()
                }
            },
            |c| difference_text(&c, survives),
        );
        let mut row = vec![
            r.sequence.clone(),
            format!("`{}`", r.point),
            r.variant.label(labels),
            if r.failed > 0 {
                format!("{} ({})", r.runs, r.failed)
            } else {
                r.runs.to_string()
            },
            mean,
            r.summary.map_or_else(|| "-".into(), |s| mm(s.median)),
            versus,
            r.comparison
                .map_or_else(|| "-".into(), |c| c.test.name().into()),
            r.comparison.map_or_else(|| "-".into(), |c| p_text(c.p)),
            ph.map_or_else(|| "-".into(), p_text),
        ];
        if paper {
            row.push(
                r.paper
                    .map_or_else(|| "-".into(), |(a, _)| format!("{:.0}", a * 1e3)),
            );
            row.push(match (r.paper, r.config.as_str()) {
                (Some(_), "orb") => "(baseline)".into(),
                (Some((a, b)), _) => format!("{:+.1} %", 100.0 * (a - b) / b),
                (None, _) => "-".into(),
            });
        }
        md_rows.push(row);
        csv_rows.push(csv_row(r, *ph));
    }
    let notes = format!(
        "Mean of the runs that did not fail with the 95 % interval of the mean (Student's t); \
         each system against our ORB-SLAM2 baseline at the same sequence and perturbation: the \
         difference of mean ATEs in % of the baseline's mean (negative: lower ATE), its 95 % \
         interval (Fieller's interval of the ratio of the two means under the same test, so the \
         baseline mean's own uncertainty counts; `[unbounded]` where the baseline's mean is not \
         told from zero) and the two-sided p-value, by the paired t-test where both systems ran \
         on the same seeds and perturbation draws (every run with its partner), Welch's t-test \
         otherwise. {} in this table, Holm-corrected together; a \
         difference in **bold** survives the correction at {ALPHA}. Where both systems' runs \
         are each all identical (one result each), nothing is tested.{}",
        counted(comparisons, "comparison", "comparisons"),
        if paper {
            " `paper`: the paper's figure for the system's column on the sequence a twin \
             imitates, and its difference from the paper's ORB-SLAM2 figure in %."
        } else {
            ""
        }
    );
    let mut t = render(
        "Each system against the baseline",
        &notes,
        &header,
        &md_rows,
    );
    t.csv = write_csv(&csv_rows);
    t
}

/// One row of the tidy CSV: every number of a row, in metres and %.
fn csv_row(r: &Row, ph: Option<f64>) -> Vec<String> {
    let s = r.summary;
    let c = r.comparison;
    vec![
        r.sequence.clone(),
        r.point.clone(),
        r.axis.as_ref().map_or_else(String::new, |a| a.0.clone()),
        num(r.axis.as_ref().and_then(|a| a.1)),
        r.config.clone(),
        num(r.variant.taus.map(|t| t.0)),
        num(r.variant.taus.map(|t| t.1)),
        num(r.variant.taus.map(|t| t.2)),
        num(r.variant.b),
        r.runs.to_string(),
        r.failed.to_string(),
        num(s.map(|s| s.mean)),
        num(s.and_then(|s| s.std)),
        num(s.map(|s| s.median)),
        num(s.and_then(|s| s.ci95.map(|c| c.0))),
        num(s.and_then(|s| s.ci95.map(|c| c.1))),
        c.map_or_else(String::new, |c| c.test.name().replace(' ', "_")),
        num(c.map(|c| c.n.0 as f64)),
        num(c.map(|c| c.diff)),
        num(c.map(|c| c.diff_ci95.0)),
        num(c.map(|c| c.diff_ci95.1)),
        num(c.map(|c| c.relative_pct())),
        num(c.map(|c| c.relative_ci95_pct().0)),
        num(c.map(|c| c.relative_ci95_pct().1)),
        num(c.map(|c| c.df)),
        num(c.map(|c| c.t)),
        num(c.map(|c| c.p)),
        num(ph),
        ph.map_or_else(String::new, |p| u8::from(p <= ALPHA).to_string()),
        num(r.paper.map(|p| p.0)),
        num(r.paper.map(|p| p.1)),
    ]
}

/// The tidy CSV of `rows` under its header.
fn write_csv(rows: &[Vec<String>]) -> String {
    let csv_header = [
        "sequence",
        "perturbation",
        "axis",
        "level",
        "config",
        "tau_mf",
        "tau_gf",
        "tau_mg",
        "baseline_b",
        "runs",
        "failed",
        "mean_m",
        "std_m",
        "median_m",
        "ci95_lo_m",
        "ci95_hi_m",
        "test",
        "pairs_or_baseline_n",
        "diff_m",
        "diff_ci95_lo_m",
        "diff_ci95_hi_m",
        "diff_pct",
        "diff_ci95_lo_pct",
        "diff_ci95_hi_pct",
        "df",
        "t",
        "p",
        "p_holm",
        "survives_holm",
        "paper_m",
        "paper_orb_slam2_m",
    ];
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record(csv_header);
    for r in rows {
        let _ = w.write_record(r);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// A p-value as a table prints it: three significant digits, `< 1e-6` below.
pub fn p_text(p: f64) -> String {
    if p < 1e-6 {
        "< 1e-6".into()
    } else if p < 0.001 {
        format!("{p:.1e}")
    } else {
        format!("{p:.3}")
    }
}

#[cfg(test)]
pub mod tests {
    use super::*;

    /// A run of `config` on `seq` with the given seed, ATE and perturbation point (a test
    /// record the report's other tests build on).
    pub fn record(
        seq: &str,
        config: &str,
        seed: u64,
        ate: f64,
        point: Option<(&str, f64)>,
    ) -> RunRecord {
        RunRecord {
            perturbation: point.map(|(f, l)| format!("{f}:{l}")),
            perturb_family: point.map(|(f, _)| f.to_string()),
            perturb_level: point.map(|(_, l)| l),
            perturb_seed: Some(seed),
            ..RunRecord::example(seq, config, seed, ate)
        }
    }

    /// Two systems, two perturbation levels, four runs: the CSV's numbers equal scipy's and
    /// statsmodels' on the same values (committed below).
    #[test]
    fn small_sweep_matches_scipy_and_holm() {
        let base = [[4.1, 3.9, 4.4, 4.0], [6.0, 6.5, 5.8, 6.3]];
        let mcor = [[3.7, 3.6, 4.0, 3.7], [6.1, 6.4, 6.0, 6.2]];
        let mut recs = Vec::new();
        for (li, level) in [1.0, 2.0].iter().enumerate() {
            for i in 0..4 {
                let p = Some(("depth-axial", *level));
                recs.push(record("s", "orb", i as u64, base[li][i] * 1e-3, p));
                recs.push(record("s", "mcor", i as u64, mcor[li][i] * 1e-3, p));
            }
        }
        let t = versus_baseline(&recs, &Catalog::embedded(), false, &BTreeMap::new()).unwrap();
        let mut rdr = csv::Reader::from_reader(t.csv.as_bytes());
        let h = rdr.headers().unwrap().clone();
        let col = |n: &str| h.iter().position(|c| c == n).unwrap();
        let rows: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
        let mc: Vec<&csv::StringRecord> = rows
            .iter()
            .filter(|r| &r[col("config")] == "mcor")
            .collect();
        assert_eq!(mc.len(), 2);
        let f = |r: &csv::StringRecord, n: &str| r[col(n)].parse::<f64>().unwrap();
        // scipy 1.17.1: ttest_rel(mcor, base) per level (in mm), .confidence_interval(0.95);
        // statsmodels 0.15.0: multipletests([p1, p2], method="holm").
        let want = [
            (
                -0.35,
                -12.124355653,
                0.00120770247027,
                -0.441869311552,
                -0.258130688448,
                0.0024154049405434256,
            ),
            (
                0.025,
                0.333333333333,
                0.760820375515,
                -0.213683472896,
                0.263683472896,
                0.7608203755145092,
            ),
        ];
        for (r, (diff, t, p, lo, hi, ph)) in mc.iter().zip(want) {
            assert_eq!(&r[col("test")], "paired_t");
            assert!((f(r, "diff_m") * 1e3 - diff).abs() < 1e-6);
            assert!((f(r, "t") - t).abs() < 1e-6, "t {}", f(r, "t"));
            assert!((f(r, "p") - p).abs() < 1e-6, "p {}", f(r, "p"));
            assert!((f(r, "diff_ci95_lo_m") * 1e3 - lo).abs() < 1e-6);
            assert!((f(r, "diff_ci95_hi_m") * 1e3 - hi).abs() < 1e-6);
            assert!((f(r, "p_holm") - ph).abs() < 1e-6);
        }
        assert_eq!(&mc[0][col("survives_holm")], "1");
        assert_eq!(&mc[1][col("survives_holm")], "0");
        assert!(t.markdown.contains("2 comparisons"));
        assert!(t.markdown.contains("**-8.5 % ["), "{}", t.markdown);
    }

    #[test]
    fn unpaired_runs_use_welch_and_a_lone_baseline_gives_no_table() {
        let mut recs: Vec<RunRecord> = (0..3)
            .map(|i| record("s", "orb", i, 0.004 + i as f64 * 1e-4, None))
            .collect();
        recs.extend((5..9).map(|i| record("s", "avc", i, 0.005 + i as f64 * 1e-4, None)));
        let t = versus_baseline(&recs, &Catalog::embedded(), false, &BTreeMap::new()).unwrap();
        assert!(t.csv.contains("Welch_t"));
        let only: Vec<RunRecord> = recs.into_iter().filter(|r| r.config == "orb").collect();
        assert!(versus_baseline(&only, &Catalog::embedded(), false, &BTreeMap::new()).is_none());
    }

    /// Three bit-identical runs per system are one result each: no p-value, however far
    /// apart the two results are (issue 55's 144 stereo cells).
    #[test]
    fn an_interval_with_an_infinite_end_prints_as_unbounded() {
        assert_eq!(
            relative_text(-12.34, (-20.06, -4.51)),
            "-12.3 % [-20.1, -4.5]"
        );
        assert_eq!(
            relative_text(69.6, (f64::NEG_INFINITY, f64::INFINITY)),
            "+69.6 % [unbounded]"
        );
        // Two baseline runs far apart: Fieller's interval is unbounded, the table says so.
        let c = crate::report::stats::welch(&[0.1, 10.0], &[1.0, 1.1, 0.9]).unwrap();
        assert_eq!(
            difference_text(&c, false),
            format!("{:+.1} % [unbounded]", c.relative_pct())
        );
    }

    #[test]
    fn identical_runs_are_not_tested() {
        let mut recs: Vec<RunRecord> = (0..3).map(|i| record("s", "orb", i, 0.004, None)).collect();
        recs.extend((0..3).map(|i| record("s", "avc", i, 0.005, None)));
        let t = versus_baseline(&recs, &Catalog::embedded(), false, &BTreeMap::new()).unwrap();
        assert!(
            t.markdown.contains("runs identical: no test"),
            "{}",
            t.markdown
        );
        assert!(t.markdown.contains("0 comparisons"), "{}", t.markdown);
        // One varying run makes it a comparison again.
        recs[5].ate_rmse = Some(0.0051);
        let t = versus_baseline(&recs, &Catalog::embedded(), false, &BTreeMap::new()).unwrap();
        assert!(
            t.markdown.contains("1 comparison in this table"),
            "{}",
            t.markdown
        );
    }
}
