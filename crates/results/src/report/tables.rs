//! Tables in the paper's layout from a sweep's run records: Table III (mean ATE per sequence
//! and configuration, 'F' for failure, the paper's numbers beside ours), Table I (ATE versus the
//! AVC baseline b), Table IV (frames per second), the loops closed and the MC-OR threshold grid.
//! Each table is rendered as Markdown for people (ATE in millimetres, decimals that follow the
//! data, every system under the one heading [`system_label`] gives it, what it leaves out and
//! why in its notes) and as a tidy CSV for notebooks: one row per group of runs (sequence,
//! system, parameters) with numbers, not text (n, failed, mean, std, median, min, max, fps).

use crate::columns::ConfigKind;
use crate::report::markdown::{column_name, render, system_label, Rendered};
use crate::report::stats::{summarize, Summary};
use crate::store::{FolderSettings, RunRecord};
use datasets::{Catalog, Class};
use slam_core::system::ClusterViews;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Default MC-OR thresholds and AVC baseline: the parameter set Table III reports.
const DEFAULT_TAUS: (f64, f64, f64) = (0.7, 0.7, 0.5);
const DEFAULT_BASELINE: f64 = 0.09;

/// Mean / std / failures of a group of runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    /// Mean ATE RMSE (m) over the runs that did not fail.
    pub mean: Option<f64>,
    /// Population std of those ATEs (m).
    pub std: Option<f64>,
    /// Runs in the group.
    pub runs: usize,
    /// Runs that failed.
    pub failed: usize,
    /// Mean frames per second.
    pub fps: f64,
    /// Runs that did not fail and have no ATE: their sequence has no ground truth.
    pub unscored: usize,
}

/// Mean and population standard deviation of `values` (summed in their order), `None` when
/// empty: the statistics of every table's cells.
pub fn mean_std(values: &[f64]) -> Option<(f64, f64)> {
    if values.is_empty() {
        return None;
    }
    let n = values.len() as f64;
    let m = values.iter().sum::<f64>() / n;
    Some((
        m,
        (values.iter().map(|a| (a - m) * (a - m)).sum::<f64>() / n).sqrt(),
    ))
}

impl Cell {
    /// Aggregates runs. The cell is a failure ('F') when more than half of its runs failed.
    pub fn of(runs: &[&RunRecord]) -> Cell {
        let ok: Vec<f64> = runs
            .iter()
            .filter(|r| !r.failed)
            .filter_map(|r| r.ate_rmse)
            .collect();
        let failed = runs.iter().filter(|r| r.failed).count();
        let (mean, std) = match mean_std(&ok) {
            Some((m, s)) => (Some(m), Some(s)),
            None => (None, None),
        };
        let fps = runs.iter().map(|r| r.fps).sum::<f64>() / runs.len().max(1) as f64;
        let unscored = runs
            .iter()
            .filter(|r| !r.failed && r.ate_rmse.is_none())
            .count();
        Cell {
            mean,
            std,
            runs: runs.len(),
            failed,
            fps,
            unscored,
        }
    }

    /// Whether the cell reads 'n/a': its runs tracked, and nothing scores them (no ground
    /// truth), which is not a failure.
    pub fn is_unscored(&self) -> bool {
        self.mean.is_none() && self.unscored > 0 && 2 * self.failed <= self.runs
    }

    /// Whether the cell reads 'F'.
    pub fn is_failure(&self) -> bool {
        self.mean.is_none() || 2 * self.failed > self.runs
    }

    /// Mean ± std in millimetres with `decimals` decimals, `12.34 ± 0.56` (with `(kF)` when
    /// some runs failed), or `F`.
    pub fn text(&self, decimals: usize) -> String {
        if self.is_unscored() {
            return "n/a".into();
        }
        if self.is_failure() {
            return "F".into();
        }
        let mut s = format!(
            "{:.decimals$} ± {:.decimals$}",
            self.mean.unwrap_or(0.0) * 1e3,
            self.std.unwrap_or(0.0) * 1e3
        );
        if self.failed > 0 {
            let _ = write!(s, " ({}F)", self.failed);
        }
        s
    }
}

/// Decimals for ATEs in millimetres shown side by side: three significant digits of the smallest
/// mean (0.970 beside 1.000, 4.61, 12.3), between 1 and 4.
pub fn mm_decimals(means_m: impl IntoIterator<Item = f64>) -> usize {
    let min = means_m
        .into_iter()
        .filter(|m| m.is_finite() && *m > 0.0)
        .fold(f64::INFINITY, f64::min);
    if !min.is_finite() {
        return 2;
    }
    (2 - (min * 1e3).log10().floor() as i64).clamp(1, 4) as usize
}

/// The texts of a row of cells (`None`: no runs, `-`), with the decimals its means need.
fn cell_texts(cells: &[Option<Cell>]) -> Vec<String> {
    let d = mm_decimals(
        cells
            .iter()
            .flatten()
            .filter(|c| !c.is_failure())
            .filter_map(|c| c.mean),
    );
    cells
        .iter()
        .map(|c| c.map_or_else(|| "-".into(), |c| c.text(d)))
        .collect()
}

/// A group of runs summarised in one row of a tidy CSV.
struct Group<'a> {
    sequence: String,
    config: String,
    runs: Vec<&'a RunRecord>,
}

/// `v` as a CSV number (every digit an f64 needs), empty when absent.
pub fn num(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

/// The ATE columns every tidy CSV carries, named as [`ate_columns`] fills them.
pub const ATE_COLUMNS: [&str; 8] = [
    "n", "failed", "failure", "mean_m", "std_m", "median_m", "min_m", "max_m",
];

/// The [`ATE_COLUMNS`] of `n` runs of which `failed` failed, `ates` the ATEs (m) of the others
/// in the order their mean sums them: a failure when more than half failed or none gave an ATE.
pub fn ate_columns(n: usize, failed: usize, ates: &[f64]) -> [String; 8] {
    let mut sorted = ates.to_vec();
    sorted.sort_by(f64::total_cmp);
    let stats = mean_std(ates);
    [
        n.to_string(),
        failed.to_string(),
        (ates.is_empty() || 2 * failed > n).to_string(),
        num(stats.map(|(m, _)| m)),
        num(stats.map(|(_, s)| s)),
        num(crate::report::stats::median(&sorted)),
        num(sorted.first().copied()),
        num(sorted.last().copied()),
    ]
}

/// Mean frames per second of a group as Table IV gives it: over every run for ours, over the
/// runs that did not fail for an external system (a crashed program's seconds are no speed).
fn group_fps(config: &str, runs: &[&RunRecord]) -> Option<f64> {
    let ok: Vec<&&RunRecord> = if ConfigKind::parse(config).is_ok() {
        runs.iter().collect()
    } else {
        runs.iter().filter(|r| !r.failed).collect()
    };
    (!ok.is_empty()).then(|| ok.iter().map(|r| r.fps).sum::<f64>() / ok.len() as f64)
}

/// The tidy CSV of `groups`: one row per group, numbers in SI units (ATE in metres).
fn tidy_csv(groups: &[Group], labels: &BTreeMap<String, String>) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record(
        [
            "sequence", "system", "label", "ours", "tau_mf", "tau_gf", "tau_mg", "baseline",
        ]
        .into_iter()
        .chain(ATE_COLUMNS)
        .chain(["fps", "cores", "peak_rss_mb", "loops", "runs_with_loops"]),
    );
    for g in groups {
        let Some(first) = g.runs.first() else {
            continue;
        };
        // In run order, as Cell::of sums them for the tables' cells.
        let ok: Vec<f64> = g
            .runs
            .iter()
            .filter(|r| !r.failed)
            .filter_map(|r| r.ate_rmse)
            .collect();
        let failed = g.runs.iter().filter(|r| r.failed).count();
        let cores: Vec<f64> = g
            .runs
            .iter()
            .filter_map(|r| Some(r.cpu_s? / r.wall_s).filter(|c| c.is_finite()))
            .collect();
        let mem = g.runs.iter().filter_map(|r| r.peak_rss_mb).reduce(f64::max);
        let loops: Vec<usize> = g.runs.iter().filter_map(|r| r.loops).collect();
        let head = [
            g.sequence.clone(),
            g.config.clone(),
            system_label(&g.config, labels),
            ConfigKind::parse(&g.config).is_ok().to_string(),
            num(first.tau_mf),
            num(first.tau_gf),
            num(first.tau_mg),
            num(first.baseline),
        ];
        let tail = [
            num(group_fps(&g.config, &g.runs)),
            num((!cores.is_empty()).then(|| cores.iter().sum::<f64>() / cores.len() as f64)),
            num(mem),
            if loops.is_empty() {
                String::new()
            } else {
                loops.iter().sum::<usize>().to_string()
            },
            if loops.is_empty() {
                String::new()
            } else {
                loops.iter().filter(|&&n| n > 0).count().to_string()
            },
        ];
        let ates = ate_columns(g.runs.len(), failed, &ok);
        let _ = w.write_record(head.into_iter().chain(ates).chain(tail));
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// The groups of Table III and IV: ours at the default parameters, external systems, per
/// sequence in table order.
fn main_groups<'a>(
    records: &'a [RunRecord],
    catalog: &Catalog,
    kinds: &[ConfigKind],
    systems: &[(String, String)],
) -> Vec<Group<'a>> {
    let mut out = Vec::new();
    for seq in sequence_order(records, catalog) {
        let names = kinds
            .iter()
            .map(|k| k.name().to_string())
            .chain(systems.iter().map(|(n, _)| n.clone()));
        for name in names {
            let ours = ConfigKind::parse(&name).is_ok();
            let runs: Vec<&RunRecord> = records
                .iter()
                .filter(|r| r.sequence == seq && r.config == name && (!ours || is_default(r)))
                .collect();
            if !runs.is_empty() {
                out.push(Group {
                    sequence: seq.clone(),
                    config: name,
                    runs,
                });
            }
        }
    }
    out
}

/// "A, B and C".
fn and_list(items: &[String]) -> String {
    match items {
        [] => String::new(),
        [one] => one.clone(),
        [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
    }
}

/// The headings of the systems in `records` other than `shown`, for a table's "left out" note.
fn others(records: &[RunRecord], shown: &[&str], labels: &BTreeMap<String, String>) -> Vec<String> {
    let mut names: Vec<&str> = records
        .iter()
        .map(|r| r.config.as_str())
        .filter(|c| !shown.contains(c))
        .collect();
    names.sort_by_key(|n| {
        (
            ConfigKind::parse(n).map_or(usize::MAX, |k| {
                ConfigKind::EVERY.iter().position(|e| *e == k).unwrap_or(0)
            }),
            n.to_string(),
        )
    });
    names.dedup();
    names.iter().map(|n| system_label(n, labels)).collect()
}

/// Whether a run has the parameters Table III reports.
pub fn is_default(r: &RunRecord) -> bool {
    let taus = match (r.tau_mf, r.tau_gf, r.tau_mg) {
        (None, None, None) => Some(None),
        (Some(a), Some(b), Some(c)) => Some(Some((a, b, c))),
        _ => None,
    };
    taus.is_some_and(|t| are_default_params(t, r.baseline))
}

/// Whether MC-OR's thresholds and AVC's b (absent: not a parameter of the system) are the ones
/// Table III reports.
pub fn are_default_params(taus: Option<(f64, f64, f64)>, b: Option<f64>) -> bool {
    taus.is_none_or(|t| t == DEFAULT_TAUS) && b.is_none_or(|b| b == DEFAULT_BASELINE)
}

/// Sequences in table order: catalog order (easy before hard as the paper groups them), then
/// any other label alphabetically.
pub fn sequence_order(records: &[RunRecord], catalog: &Catalog) -> Vec<String> {
    let mut present: Vec<String> = records.iter().map(|r| r.sequence.clone()).collect();
    present.sort();
    present.dedup();
    let mut out: Vec<String> = Vec::new();
    for e in catalog.entries() {
        if present.contains(&e.name) {
            out.push(e.name.clone());
        }
    }
    for s in present {
        if !out.contains(&s) {
            out.push(s);
        }
    }
    out
}

/// A published figure in millimetres (the paper gives metres to the millimetre).
fn paper_text(v: Option<datasets::Ate>) -> String {
    match v {
        None => "-".into(),
        Some(a) => match a.metres() {
            Some(m) => format!("{:.0}", m * 1e3),
            None => "F".into(),
        },
    }
}

/// Removes the columns from `first` on that hold no value in any row (all `-`); returns their
/// headings.
fn drop_empty_columns(
    header: &mut Vec<String>,
    rows: &mut [Vec<String>],
    first: usize,
) -> Vec<String> {
    let mut dropped = Vec::new();
    let mut c = header.len();
    while c > first {
        c -= 1;
        if !rows.is_empty() && rows.iter().all(|r| r.get(c).is_none_or(|t| t == "-")) {
            dropped.insert(0, header.remove(c));
            for r in rows.iter_mut() {
                if c < r.len() {
                    r.remove(c);
                }
            }
        }
    }
    dropped
}

/// Table III: mean ATE RMSE (mm) ± std over the runs, per sequence and configuration, at the
/// default parameters; with `paper`, the published numbers beside ours. `vocabularies`: the
/// vocabulary each external system was given, in words (named in the notes).
pub fn table3(
    records: &[RunRecord],
    catalog: &Catalog,
    paper: bool,
    settings: &FolderSettings,
    labels: &BTreeMap<String, String>,
    vocabularies: &BTreeMap<String, String>,
) -> Rendered {
    let kinds: Vec<ConfigKind> = ConfigKind::EVERY
        .into_iter()
        .filter(|k| records.iter().any(|r| r.config == k.name()))
        .collect();
    let systems = external_columns(records, labels);
    let mut header = table3_header(&kinds, &systems, labels, paper);
    let mut rows: Vec<Vec<String>> = sequence_order(records, catalog)
        .into_iter()
        .map(|seq| table3_row(&seq, records, catalog, &kinds, &systems, paper))
        .collect();
    rows.sort_by_key(|r| match r[1].as_str() {
        "easy" => 0,
        "hard" => 1,
        _ => 2,
    });
    let dropped = drop_empty_columns(&mut header, &mut rows, 2);
    let notes = table3_protocol_notes(records, &kinds, settings);
    let notes = table3_further_notes(notes, records, &systems, settings, vocabularies, &dropped);
    let notes = match (paper, shorter_than_the_paper(records, catalog)) {
        (true, short) if !short.is_empty() => format!(
            "{notes} Shorter than the paper's runs: ours of {} cover only the first frames of the \
             sequence the paper ran whole, so their figures and the paper's are not comparable.",
            short.join(", ")
        ),
        _ => notes,
    };
    let mut t = render("Table III: ATE RMSE (mm)", &notes, &header, &rows);
    t.csv = tidy_csv(&main_groups(records, catalog, &kinds, &systems), labels);
    t
}

/// The synthetic sequences of `records` run on fewer frames than the whole sequence (under 95 %
/// of the preset's length), each as `name (F of N frames)`: beside the paper's figures, which are of
/// whole sequences, a table must say so.
fn shorter_than_the_paper(records: &[RunRecord], catalog: &Catalog) -> Vec<String> {
    let mut out = Vec::new();
    for seq in sequence_order(records, catalog) {
        let Some(preset) = catalog.get(&seq).ok().and_then(|e| e.preset.clone()) else {
            continue;
        };
        let Ok(p) = synth::Preset::from_name(&preset) else {
            continue;
        };
        let ran = records
            .iter()
            .filter(|r| r.sequence == seq)
            .map(|r| r.frames)
            .max()
            .unwrap_or(0);
        // A whole twin loses a frame or three to pairing colour with depth: short means a
        // run of under 95 % of the frames (`--frames`).
        if ran > 0 && (ran as f64) < 0.95 * p.default_frames() as f64 {
            out.push(format!("{seq} ({ran} of {} frames)", p.default_frames()));
        }
    }
    out
}

/// Table III's headings: sequence, class, our configurations, the external systems, and with
/// `paper` the paper's column of each configuration.
fn table3_header(
    kinds: &[ConfigKind],
    systems: &[(String, String)],
    labels: &BTreeMap<String, String>,
    paper: bool,
) -> Vec<String> {
    let mut header = vec!["sequence".to_string(), "class".to_string()];
    for k in kinds {
        header.push(system_label(k.name(), labels));
    }
    header.extend(systems.iter().map(|(_, label)| label.clone()));
    if paper {
        for k in kinds {
            header.push(format!("{} (paper)", column_name(*k)));
        }
    }
    header
}

/// A sequence's class as Table III prints it: the paper's easy / hard, a twin's "twin of" the
/// class of the sequence it imitates, "synthetic" for another preset, "real" for another
/// catalogued sequence, and "folder" for one the catalog does not name (`--path`).
fn sequence_class(
    entry: Option<&datasets::catalog::Entry>,
    imitated: Option<&datasets::catalog::Entry>,
) -> &'static str {
    match (entry.and_then(|e| e.class), imitated.and_then(|r| r.class)) {
        (Some(Class::Easy), _) => "easy",
        (Some(Class::Hard), _) => "hard",
        (None, Some(Class::Easy)) => "twin of easy",
        (None, Some(Class::Hard)) => "twin of hard",
        (None, None) => match entry {
            Some(e) if e.preset.is_some() => "synthetic",
            Some(_) => "real",
            None => "folder",
        },
    }
}

/// One sequence's row of Table III: its name (the paper's where it has one), class, a cell per
/// configuration (default parameters) and external system, and with `paper` the paper's
/// figures (a twin prints those of the real sequence it imitates).
fn table3_row(
    seq: &str,
    records: &[RunRecord],
    catalog: &Catalog,
    kinds: &[ConfigKind],
    systems: &[(String, String)],
    paper: bool,
) -> Vec<String> {
    let entry = catalog.get(seq).ok();
    let imitated = entry
        .and_then(|e| e.imitates.as_deref())
        .and_then(|name| catalog.get(name).ok());
    let mut row = vec![
        entry
            .and_then(|e| e.paper_name.clone())
            .unwrap_or_else(|| seq.to_string()),
        sequence_class(entry, imitated).into(),
    ];
    let mut cells: Vec<Option<Cell>> = Vec::new();
    for k in kinds {
        let runs: Vec<&RunRecord> = our_runs(records, seq, k.name());
        cells.push((!runs.is_empty()).then(|| Cell::of(&runs)));
    }
    for (name, _) in systems {
        let runs: Vec<&RunRecord> = records
            .iter()
            .filter(|r| r.sequence == seq && &r.config == name)
            .collect();
        cells.push((!runs.is_empty()).then(|| Cell::of(&runs)));
    }
    row.extend(cell_texts(&cells));
    if paper {
        let p = entry
            .and_then(|e| e.paper.as_ref())
            .or_else(|| imitated.and_then(|r| r.paper.as_ref()));
        row.extend(kinds.iter().map(|k| paper_cell(p, *k)));
    }
    row
}

/// The paper's figure for configuration `k` ("-" where it publishes none, as for rc).
fn paper_cell(p: Option<&datasets::catalog::PaperAte>, k: ConfigKind) -> String {
    match (p, k) {
        (None, _) => "-".into(),
        (Some(p), ConfigKind::Orb) => paper_text(p.orb_slam2),
        (Some(p), ConfigKind::Mcor | ConfigKind::McorFrames | ConfigKind::McorKeyframes) => {
            paper_text(p.mcor)
        }
        (Some(p), ConfigKind::Avc) => paper_text(p.avc),
        (
            Some(p),
            ConfigKind::McorAvc | ConfigKind::McorFramesAvc | ConfigKind::McorKeyframesAvc,
        ) => paper_text(p.mcor_avc),
        (Some(_), ConfigKind::Rc) => "-".into(),
    }
}

/// The first part of Table III's notes: units, seeds, parameters, association and alignment,
/// what 'F' means, and how the runs were made (mapping lag, varied realizations, MC-OR's
/// clusters).
/// The runs Table III shows: unperturbed, at the parameters it reports (ours), every run of
/// an external system.
fn shown_in_table3(records: &[RunRecord]) -> Vec<RunRecord> {
    records
        .iter()
        .filter(|r| {
            r.perturbation
                .as_deref()
                .is_none_or(|p| p.is_empty() || p == "none")
                && (ConfigKind::parse(&r.config).is_err() || is_default(r))
        })
        .cloned()
        .collect()
}

fn table3_protocol_notes(
    records: &[RunRecord],
    kinds: &[ConfigKind],
    settings: &FolderSettings,
) -> String {
    let first = records.iter().map(|r| r.seed).min().unwrap_or(0);
    let seeds = records
        .iter()
        .map(|r| r.seed)
        .max()
        .map(|m| m + 1)
        .unwrap_or(0);
    format!(
        "ATE RMSE in millimetres, mean ± population std over the runs (seeds {first}..{}), decimals per \
         row: three significant digits of its smallest mean (the tidy table3.csv has every digit, \
         in metres). MC-OR thresholds \
         (tau_MF, tau_GF, tau_MG) = {:?} m, AVC baseline {} m. Association: evaluate_ate.py's (|dt| < 0.02 s, \
         greedy, each stamp once), SE3 Umeyama alignment; EuRoC estimates converted to the body frame. \
         'F': more than half the runs failed (fewer than 80 % of the frames tracked, or no ATE); `(kF)`: k \
         failed runs left out of the mean. {}{}{}{}{}",
        seeds.saturating_sub(1),
        DEFAULT_TAUS,
        DEFAULT_BASELINE,
        match settings.mapping_lag {
            0 => "Runs are synchronous and single-threaded: the seed reaches only the RANSAC of \
                  relocalization, so runs that never relocalize agree to the bit."
                .to_string(),
            n => format!(
                "Runs are single-threaded and emulate concurrent local mapping (--mapping-lag {n}): \
                 each keyframe is mapped 0..={n} frames late, drawn from the run's seed, so runs of \
                 one sequence spread as ORB-SLAM2's threads make them spread."
            ),
        },
        if records.iter().any(|r| !r.failed && r.ate_rmse.is_none()) {
            " 'n/a': the runs tracked, and their sequence has no ground truth to score them \
             (not a failure)."
        } else {
            ""
        },
        match crate::spread::identical_cells(&shown_in_table3(records)) {
            (several, identical) if !identical.is_empty() => format!(
                " In {} of the {several} cells with several runs every run gave the same result: \
                 there the runs are one run (± 0 is no spread, and no test compares them).",
                identical.len()
            ),
            _ => String::new(),
        },
        if varied_realizations(records) {
            " Synthetic sequences were swept with --vary-sequence: run k ran on its own realization of \
             the sequence (textures and noise from synth seed `synth_seed` in runs.csv), so the spread \
             measures the sensitivity to the sensor noise."
        } else {
            ""
        },
        if kinds.contains(&ConfigKind::Mcor) || kinds.contains(&ConfigKind::McorAvc) {
            match settings.mcor_cluster {
                ClusterViews::EveryFrame => {
                    " MC-OR's clusters (w/ MC-OR, w/ MC-OR+AVC): every frame that kept the point \
                     as an inlier, the paper's reading."
                }
                ClusterViews::Keyframes => {
                    " MC-OR's clusters (w/ MC-OR, w/ MC-OR+AVC): the point's keyframe \
                     observations only (made before the paper's every-frame reading became the \
                     default; `mcor-keyframes` reproduces them)."
                }
            }
        } else {
            ""
        },
    )
}

/// The rest of Table III's notes, appended to `notes`: the external systems, our vocabulary
/// beside them, what was left out (runs at other parameters, `dropped` columns) and how the
/// runs differ from the reference's (--synth-without, speed approximations).
fn table3_further_notes(
    notes: String,
    records: &[RunRecord],
    systems: &[(String, String)],
    settings: &FolderSettings,
    vocabularies: &BTreeMap<String, String>,
    dropped: &[String],
) -> String {
    let notes = match external_notes(records, systems, vocabularies) {
        n if n.is_empty() => notes,
        n => format!("{notes} {n}"),
    };
    let notes = if systems.is_empty() || settings.vocabulary == "none" {
        notes
    } else {
        format!(
            "{notes} Ours ran with the vocabulary {}.",
            settings.vocabulary
        )
    };
    let other_params = records
        .iter()
        .filter(|r| ConfigKind::parse(&r.config).is_ok() && !is_default(r))
        .count();
    let notes = if other_params == 0 {
        notes
    } else {
        format!(
            "{notes} Left out: {other_params} runs of ours at other parameters than these (see \
             Table I and the threshold grid)."
        )
    };
    let notes = if dropped.is_empty() {
        notes
    } else {
        format!(
            "{notes} Left out for want of a single value: {} (the paper publishes no figure \
             for it).",
            and_list(dropped)
        )
    };
    let notes = if settings.synth_without.is_empty() {
        notes
    } else {
        format!(
            "{notes} Synthetic sequences rendered without: {} (--synth-without).",
            settings.synth_without.join(", ")
        )
    };
    if settings.approximations.is_empty() {
        notes
    } else {
        format!(
            "{notes} Ours ran with the documented speed approximations {}: not the reference's \
             results.",
            settings.approximations.join(", ")
        )
    }
}

/// Whether some sequence's runs used more than one synthetic realization (--vary-sequence).
fn varied_realizations(records: &[RunRecord]) -> bool {
    let mut seen: BTreeMap<&str, Option<u64>> = BTreeMap::new();
    records
        .iter()
        .any(|r| match seen.insert(&r.sequence, r.synth_seed) {
            Some(prev) => prev != r.synth_seed,
            None => false,
        })
}

/// The external systems with runs in `records` (names not of noisefree's configurations), each
/// with its column heading (`labels`, from the folder's systems.toml, else its name).
pub fn external_columns(
    records: &[RunRecord],
    labels: &BTreeMap<String, String>,
) -> Vec<(String, String)> {
    let mut names: Vec<&str> = records
        .iter()
        .map(|r| r.config.as_str())
        .filter(|c| ConfigKind::parse(c).is_err())
        .collect();
    names.sort();
    names.dedup();
    names
        .into_iter()
        .map(|n| (n.to_string(), system_label(n, labels)))
        .collect()
}

/// What the external systems' columns are, which vocabulary each was given, and why their
/// failed runs failed.
fn external_notes(
    records: &[RunRecord],
    systems: &[(String, String)],
    vocabularies: &BTreeMap<String, String>,
) -> String {
    let mut out = Vec::new();
    for (name, label) in systems {
        if let Ok(Some(r)) = crate::readings::ReadingColumn::parse(name) {
            out.push(format!(
                "{label}: noisefree's {} with the paper's open choices set as its name says \
                 (`{name}`; docs/readings.md describes every reading).",
                column_name(r.kind)
            ));
            continue;
        }
        let mut text = format!(
            "{label}: the external system `{name}` run by the harness on the same files (its threads' own run-to-run spread; keyframes and map points not reported)"
        );
        if let Some(v) = vocabularies.get(name) {
            text += &format!(", given the vocabulary {v}");
        }
        let mut reasons: BTreeMap<(&str, &str), usize> = BTreeMap::new();
        for r in records.iter().filter(|r| &r.config == name && r.failed) {
            let why = r
                .reason
                .as_deref()
                .unwrap_or("fewer than 80 % of the frames tracked");
            *reasons.entry((r.sequence.as_str(), why)).or_default() += 1;
        }
        if !reasons.is_empty() {
            let list: Vec<String> = reasons
                .iter()
                .map(|((seq, why), n)| format!("{seq}: {n} x {why}"))
                .collect();
            text += &format!("; failed runs: {}", list.join("; "));
        }
        out.push(text + ".");
    }
    out.join(" ")
}

/// The baselines b that runs of the configurations `swept` ran at, ascending and distinct;
/// `None` unless there are two (a Table I needs a sweep of b).
fn swept_baselines(records: &[RunRecord], swept: impl Fn(&str) -> bool) -> Option<Vec<f64>> {
    let mut baselines: Vec<f64> = records
        .iter()
        .filter(|r| swept(&r.config))
        .filter_map(|r| r.baseline)
        .collect();
    baselines.sort_by(f64::total_cmp);
    baselines.dedup();
    (baselines.len() >= 2).then_some(baselines)
}

/// Table I's cell of `config` on `seq` at baseline `b` (`None` without runs), its runs added
/// to the tidy CSV's `groups`.
fn cell_at_b<'a>(
    records: &'a [RunRecord],
    seq: &str,
    config: &str,
    b: f64,
    groups: &mut Vec<Group<'a>>,
) -> Option<Cell> {
    let runs: Vec<&RunRecord> = records
        .iter()
        .filter(|r| r.sequence == seq && r.config == config && r.baseline == Some(b))
        .collect();
    if runs.is_empty() {
        return None;
    }
    let cell = Cell::of(&runs);
    groups.push(Group {
        sequence: seq.to_string(),
        config: config.to_string(),
        runs,
    });
    Some(cell)
}

/// The paper's Table I (fr3_walking_rpy, ATE in metres): the baselines b (m), then ORB-SLAM2's
/// and AVC's ATE at each.
pub const PAPER_TABLE1: [(f64, f64, f64); 7] = [
    (0.01, 0.60, 0.30),
    (0.03, 0.59, 0.42),
    (0.05, 0.65, 0.37),
    (0.07, 0.58, 0.30),
    (0.09, 0.83, 0.27),
    (0.11, 0.56, 0.34),
    (0.13, 0.72, 0.26),
];

/// Table I under AVC's `b_role = "camera"` reading: b is the RGB-D camera's baseline, so the
/// baseline row moves with b as the paper's does. One row per sequence and column that reads b
/// so (`orb:b_role=camera`, `avc:b_role=camera`, ...), one column per b; with `paper`, the
/// paper's two rows beside the twin of fr3_walking_rpy. `None` without such runs at two b.
pub fn table1_camera(
    records: &[RunRecord],
    catalog: &Catalog,
    paper: bool,
    labels: &BTreeMap<String, String>,
) -> Option<Rendered> {
    let camera_reading = |c: &str| {
        crate::readings::ReadingColumn::parse(c)
            .ok()
            .flatten()
            .is_some_and(|r| r.readings.b_role == Some(slam_core::system::BaselineRole::Camera))
    };
    let mut configs: Vec<&str> = records
        .iter()
        .filter(|r| r.baseline.is_some() && camera_reading(&r.config))
        .map(|r| r.config.as_str())
        .collect();
    // The baseline's rows first, as in the paper's table.
    configs.sort_by_key(|c| (!c.starts_with("orb:"), c.to_string()));
    configs.dedup();
    let baselines = swept_baselines(records, |c| configs.contains(&c))?;
    let mut header = vec!["sequence".to_string(), "system".to_string()];
    header.extend(baselines.iter().map(|b| format!("b={b}")));
    let (mut rows, mut groups) = (Vec::new(), Vec::new());
    for seq in sequence_order(records, catalog) {
        for config in &configs {
            let cells: Vec<Option<Cell>> = baselines
                .iter()
                .map(|b| cell_at_b(records, &seq, config, *b, &mut groups))
                .collect();
            if cells.iter().all(Option::is_none) {
                continue;
            }
            let mut row = vec![seq.clone(), system_label(config, labels)];
            row.extend(cell_texts(&cells));
            rows.push(row);
        }
        let imitates = catalog
            .get(&seq)
            .ok()
            .and_then(|e| e.imitates.clone())
            .unwrap_or_default();
        if paper && imitates == "fr3_w_rpy" {
            for (label, pick) in [("ORB-SLAM2 (paper)", 1usize), ("w/ AVC (paper)", 2usize)] {
                let mut row = vec![seq.clone(), label.to_string()];
                row.extend(baselines.iter().map(|b| {
                    PAPER_TABLE1
                        .iter()
                        .find(|p| (p.0 - b).abs() < 1e-9)
                        .map_or_else(
                            || "-".to_string(),
                            |p| format!("{:.0}", 1e3 * if pick == 1 { p.1 } else { p.2 }),
                        )
                }));
                rows.push(row);
            }
        }
    }
    let notes = "ATE RMSE in millimetres, mean ± population std over the runs; decimals per row: \
                 three significant digits of its smallest mean. Under the `b_role = \"camera\"` \
                 reading b is the RGB-D camera's baseline (bf = b fx): it sets the virtual right \
                 coordinate of every keypoint with depth and the close/far threshold ThDepth x b, \
                 so the baseline's row moves with b as in the paper's Table I. `(paper)`: the \
                 paper's Table I on the real fr3_walking_rpy, in mm.";
    let mut t = render(
        "Table I under b_role = \"camera\": ATE RMSE (mm) versus b (m)",
        notes,
        &header,
        &rows,
    );
    t.csv = tidy_csv(&groups, labels);
    Some(t)
}

/// Table I: ATE (mm) versus the AVC baseline b, per sequence, with the baseline's ATE beside.
pub fn table1(
    records: &[RunRecord],
    catalog: &Catalog,
    labels: &BTreeMap<String, String>,
) -> Option<Rendered> {
    let baselines = swept_baselines(records, |c| c == "avc")?;
    let avc = system_label("avc", labels);
    let mut header = vec!["sequence".to_string(), system_label("orb", labels)];
    header.extend(baselines.iter().map(|b| format!("{avc} b={b}")));
    let mut rows = Vec::new();
    let mut groups = Vec::new();
    for seq in sequence_order(records, catalog) {
        let orb: Vec<&RunRecord> = records
            .iter()
            .filter(|r| r.sequence == seq && r.config == "orb")
            .collect();
        let mut cells = vec![(!orb.is_empty()).then(|| Cell::of(&orb))];
        if !orb.is_empty() {
            groups.push(Group {
                sequence: seq.clone(),
                config: "orb".into(),
                runs: orb,
            });
        }
        for b in &baselines {
            cells.push(cell_at_b(records, &seq, "avc", *b, &mut groups));
        }
        let mut row = vec![seq.clone()];
        row.extend(cell_texts(&cells));
        rows.push(row);
    }
    let left = others(records, &["orb", "avc"], labels);
    let notes = format!(
        "ATE RMSE in millimetres, mean ± population std over the runs; decimals per row: three \
         significant digits of its smallest mean.{}",
        if left.is_empty() {
            String::new()
        } else {
            format!(
                " Left out: {} (b is a parameter of AVC alone; they are in Table III).",
                and_list(&left)
            )
        }
    );
    let mut t = render(
        "Table I: ATE RMSE (mm) versus the AVC baseline b (m)",
        &notes,
        &header,
        &rows,
    );
    t.csv = tidy_csv(&groups, labels);
    Some(t)
}

/// Our runs of `config` on `seq` with the parameters Table III reports, in record order.
pub fn our_runs<'a>(records: &'a [RunRecord], seq: &str, config: &str) -> Vec<&'a RunRecord> {
    records
        .iter()
        .filter(|r| r.sequence == seq && r.config == config && is_default(r))
        .collect()
}

/// The frames per second (n, mean, std, median, 95 % interval) of `runs`, `None` without
/// runs: Table IV's cells.
pub fn fps_summary(runs: &[&RunRecord]) -> Option<Summary> {
    summarize(&runs.iter().map(|r| r.fps).collect::<Vec<_>>())
}

/// A Table IV cell: the mean frames per second with its 95 % interval when the runs spread.
pub fn fps_cell(s: &Summary) -> String {
    match s.ci95 {
        Some((lo, hi)) if hi > lo => format!("{:.1} [{:.1}, {:.1}]", s.mean, lo, hi),
        _ => format!("{:.1}", s.mean),
    }
}

/// Table IV: mean frames per second per sequence and configuration (one thread).
pub fn table4(
    records: &[RunRecord],
    catalog: &Catalog,
    labels: &BTreeMap<String, String>,
) -> Rendered {
    let kinds: Vec<ConfigKind> = ConfigKind::EVERY
        .into_iter()
        .filter(|k| records.iter().any(|r| r.config == k.name()))
        .collect();
    let systems = external_columns(records, labels);
    let mut header = vec!["sequence".to_string(), "frames".to_string()];
    header.extend(kinds.iter().map(|k| system_label(k.name(), labels)));
    header.extend(systems.iter().map(|(_, l)| l.clone()));
    let mut rows = Vec::new();
    for seq in sequence_order(records, catalog) {
        let frames = records
            .iter()
            .find(|r| r.sequence == seq)
            .map(|r| r.frames)
            .unwrap_or(0);
        let mut row = vec![seq.clone(), frames.to_string()];
        for k in &kinds {
            let runs: Vec<&RunRecord> = our_runs(records, &seq, k.name());
            row.push(fps_summary(&runs).map_or_else(|| "-".into(), |s| fps_cell(&s)));
        }
        for (name, _) in &systems {
            let runs: Vec<&RunRecord> = records
                .iter()
                .filter(|r| r.sequence == seq && &r.config == name && !r.failed)
                .collect();
            row.push(if runs.is_empty() {
                "-".into()
            } else {
                let n = runs.len() as f64;
                let fps = runs.iter().map(|r| r.fps).sum::<f64>() / n;
                let cpu: Vec<f64> = runs
                    .iter()
                    .filter_map(|r| Some(r.cpu_s? / r.wall_s))
                    .collect();
                let mem: Vec<f64> = runs.iter().filter_map(|r| r.peak_rss_mb).collect();
                let mut t = format!("{fps:.1}");
                if !cpu.is_empty() {
                    t += &format!(
                        " ({:.1} cores, {:.0} MB)",
                        cpu.iter().sum::<f64>() / cpu.len() as f64,
                        mem.iter().cloned().fold(0.0, f64::max)
                    );
                }
                t
            });
        }
        rows.push(row);
    }
    let notes = if systems.is_empty() {
        "Wall-clock frames per second of one run on one core, averaged over the runs, with the \
         95 % interval of the mean (Student's t) where the runs spread; runs of a sweep share \
         the machine's cores, so compare columns within one sweep; each technique against the \
         baseline in table4-versus.md."
            .to_string()
    } else {
        "Wall-clock frames per second of one run, averaged over the runs (ours with the 95 % \
         interval of the mean where the runs spread; each technique against the baseline in \
         table4-versus.md); ours on one core. An \
         external system's figure is its whole process from start to exit (loading its vocabulary, \
         and any real-time pacing of its example program, included), with the cores it kept busy \
         on average (CPU time / wall time) and its peak resident memory; runs of a sweep share \
         the machine's cores, so compare columns within one sweep."
            .to_string()
    };
    let title = if systems.is_empty() {
        "Table IV: frames per second (single thread, whole pipeline)"
    } else {
        "Table IV: frames per second (ours: one thread; external systems: their own threads, \
         whole process)"
    };
    let mut t = render(title, &notes, &header, &rows);
    t.csv = tidy_csv(&main_groups(records, catalog, &kinds, &systems), labels);
    t
}

/// Loops closed per sequence and configuration: the total over the runs and in how many runs
/// at least one closed, so a false loop on a sequence without a revisit shows at a glance.
/// `None` when no run recorded a loop count (loop closing off, or records from before it).
pub fn loops_table(
    records: &[RunRecord],
    catalog: &Catalog,
    labels: &BTreeMap<String, String>,
) -> Option<Rendered> {
    if !records.iter().any(|r| r.loops.is_some()) {
        return None;
    }
    let kinds: Vec<ConfigKind> = ConfigKind::EVERY
        .into_iter()
        .filter(|k| records.iter().any(|r| r.config == k.name()))
        .collect();
    let mut header = vec!["sequence".to_string()];
    header.extend(kinds.iter().map(|k| system_label(k.name(), labels)));
    let mut rows = Vec::new();
    for seq in sequence_order(records, catalog) {
        let mut row = vec![seq.clone()];
        for k in &kinds {
            let runs: Vec<&RunRecord> = our_runs(records, &seq, k.name());
            let counted: Vec<usize> = runs.iter().filter_map(|r| r.loops).collect();
            row.push(if counted.is_empty() {
                "-".into()
            } else {
                let total: usize = counted.iter().sum();
                let with = counted.iter().filter(|&&n| n > 0).count();
                format!("{total} ({with}/{} runs)", counted.len())
            });
        }
        rows.push(row);
    }
    let systems = external_columns(records, labels);
    let mut notes = String::from(
        "Loops closed in all runs together, and in how many runs at least one closed. On a \
         sequence that never returns to a place it has seen, every loop is a false one.",
    );
    if !systems.is_empty() {
        let names: Vec<String> = systems.iter().map(|(_, l)| l.clone()).collect();
        let _ = write!(
            notes,
            " Left out: {} (an external program does not report its loop closures to the \
             harness).",
            and_list(&names)
        );
    }
    let mut t = render("Loops closed", &notes, &header, &rows);
    let groups: Vec<Group> = main_groups(records, catalog, &kinds, &[]);
    t.csv = tidy_csv(&groups, labels);
    Some(t)
}

/// The MC-OR threshold grid: mean ATE per (tau_MF, tau_GF, tau_MG) and sequence, the best triple
/// per sequence and overall (lowest mean over sequences of the per-sequence mean ATE).
pub fn threshold_grid(
    records: &[RunRecord],
    catalog: &Catalog,
    labels: &BTreeMap<String, String>,
) -> Option<Rendered> {
    let mut triples: Vec<(f64, f64, f64)> = records
        .iter()
        .filter(|r| r.config == "mcor")
        .filter_map(|r| Some((r.tau_mf?, r.tau_gf?, r.tau_mg?)))
        .collect();
    triples.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    triples.dedup();
    if triples.len() < 2 {
        return None;
    }
    let seqs = sequence_order(records, catalog);
    let mut header = vec!["tau_MF".to_string(), "tau_GF".into(), "tau_MG".into()];
    header.extend(seqs.iter().cloned());
    header.push("mean".into());
    let mut rows = Vec::new();
    let mut best_per_seq: BTreeMap<String, (f64, (f64, f64, f64))> = BTreeMap::new();
    let mut best_overall: Option<(f64, (f64, f64, f64))> = None;
    let runs_of = |s: &str, t: &(f64, f64, f64)| -> Vec<&RunRecord> {
        records
            .iter()
            .filter(|r| {
                r.sequence == s
                    && r.config == "mcor"
                    && (r.tau_mf, r.tau_gf, r.tau_mg) == (Some(t.0), Some(t.1), Some(t.2))
            })
            .collect()
    };
    // One precision for the whole grid: its cells are compared across rows.
    let d = mm_decimals(triples.iter().flat_map(|t| {
        seqs.iter().filter_map(move |s| {
            let c = Cell::of(&runs_of(s, t));
            (!c.is_failure()).then_some(c.mean).flatten()
        })
    }));
    let mut groups = Vec::new();
    for t in &triples {
        let mut row = vec![t.0.to_string(), t.1.to_string(), t.2.to_string()];
        let mut means = Vec::new();
        for s in &seqs {
            let runs = runs_of(s, t);
            let c = Cell::of(&runs);
            row.push(if runs.is_empty() {
                "-".into()
            } else {
                c.text(d)
            });
            if !runs.is_empty() {
                groups.push(Group {
                    sequence: s.clone(),
                    config: "mcor".into(),
                    runs,
                });
            }
            if let (false, Some(m)) = (c.is_failure(), c.mean) {
                means.push(m);
                let e = best_per_seq.entry(s.clone()).or_insert((f64::INFINITY, *t));
                if m < e.0 {
                    *e = (m, *t);
                }
            }
        }
        if means.len() == seqs.len() && !means.is_empty() {
            let m = means.iter().sum::<f64>() / means.len() as f64;
            row.push(format!("{:.d$}", m * 1e3));
            if best_overall.is_none_or(|(b, _)| m < b) {
                best_overall = Some((m, *t));
            }
        } else {
            row.push("F".into());
        }
        rows.push(row);
    }
    let mut notes = String::from(
        "ATE RMSE in millimetres, mean ± population std over the runs of w/ MC-OR (ours) at \
         each (tau_MF, tau_GF, tau_MG) (m). Best triple per sequence: ",
    );
    notes.push_str(
        &best_per_seq
            .iter()
            .map(|(s, (m, t))| format!("{s} {t:?} ({:.d$} mm)", m * 1e3))
            .collect::<Vec<_>>()
            .join("; "),
    );
    if let Some((m, t)) = best_overall {
        let _ = write!(notes, ". Best overall: {t:?} (mean {:.d$} mm).", m * 1e3);
    }
    let left = others(records, &["mcor"], labels);
    if !left.is_empty() {
        let _ = write!(
            notes,
            " Left out: {} (the thresholds are MC-OR's; they are in Table III).",
            and_list(&left)
        );
    }
    let mut t = render(
        "MC-OR threshold grid: ATE RMSE (mm)",
        &notes,
        &header,
        &rows,
    );
    t.csv = tidy_csv(&groups, labels);
    Some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::RunRecord;

    fn record(sequence: &str, ate: f64) -> RunRecord {
        RunRecord {
            frames: 700,
            tracked: 700,
            keyframes: Some(20),
            map_points: Some(1500),
            mean_outliers: Some(100.0),
            wall_s: 7.0,
            ..RunRecord::example(sequence, "orb", 0, ate)
        }
    }

    /// A run of the first 150 of a twin's 702 frames is named beside the paper's whole-sequence
    /// figures; a whole run (short of a frame or two of pairing) and a folder are not.
    #[test]
    fn runs_shorter_than_the_paper_s_are_named() {
        let catalog = Catalog::embedded();
        let short = RunRecord {
            frames: 150,
            ..record("twin_fr1_desk", 0.01)
        };
        let whole = record("twin_fr1_xyz", 0.01);
        let whole = RunRecord {
            frames: 900,
            ..whole
        };
        let folder = record("mine", 0.01);
        let named = shorter_than_the_paper(&[short, whole, folder], &catalog);
        assert_eq!(named, vec!["twin_fr1_desk (150 of 702 frames)".to_string()]);
    }

    #[test]
    fn table1_under_the_camera_reading_moves_the_baseline_row_with_b_beside_the_papers() {
        let catalog = Catalog::embedded();
        let mut records = Vec::new();
        for (config, b, ate) in [
            ("orb:b_role=camera", 0.05, 0.2),
            ("orb:b_role=camera", 0.09, 0.3),
            ("avc:b_role=camera", 0.05, 0.1),
            ("avc:b_role=camera", 0.09, 0.15),
        ] {
            records.push(RunRecord {
                config: config.into(),
                baseline: Some(b),
                ..record("twin_fr3_w_rpy", ate)
            });
        }
        // Runs of the residual reading are not this table's.
        records.push(RunRecord {
            config: "avc".into(),
            baseline: Some(0.05),
            ..record("twin_fr3_w_rpy", 0.5)
        });
        let t = table1_camera(&records, &catalog, true, &BTreeMap::new()).unwrap();
        let rows: Vec<&str> = t
            .markdown
            .lines()
            .filter(|l| l.starts_with("| twin"))
            .collect();
        assert_eq!(rows.len(), 4, "{}", t.markdown);
        assert!(rows[0].contains("ORB-SLAM2 [b role camera] (ours) | 200.0 ± 0.0 | 300.0"));
        assert!(rows[1].contains("w/ AVC [b role camera] (ours) | 100.0 ± 0.0 | 150.0"));
        assert!(
            rows[2].ends_with("ORB-SLAM2 (paper) | 650 | 830 |"),
            "{}",
            rows[2]
        );
        assert!(
            rows[3].ends_with("w/ AVC (paper) | 370 | 270 |"),
            "{}",
            rows[3]
        );
        assert!(table1_camera(&records[..1], &catalog, true, &BTreeMap::new()).is_none());
    }

    /// A twin's row carries the paper's figure of the sequence it imitates; a plain preset's
    /// has none.
    #[test]
    fn twins_print_the_paper_figures_of_the_sequence_they_imitate() {
        let catalog = Catalog::embedded();
        let records = [record("twin_fr1_360", 0.036), record("kinect", 0.001)];
        let t = table3(
            &records,
            &catalog,
            true,
            &FolderSettings::default(),
            &BTreeMap::new(),
            &BTreeMap::new(),
        );
        let line = |name: &str| {
            t.markdown
                .lines()
                .find(|l| l.starts_with(&format!("| {name} |")))
                .unwrap_or_else(|| panic!("no row {name} in\n{}", t.markdown))
                .to_string()
        };
        let twin = line("twin_fr1_360");
        assert!(
            twin.contains("twin of hard") && twin.contains("| 215 |"),
            "{twin}"
        );
        let kinect = line("kinect");
        assert!(
            kinect.contains("synthetic") && !kinect.contains("215"),
            "{kinect}"
        );
        // A folder the catalog does not name is not called synthetic.
        let catalog = Catalog::embedded();
        assert_eq!(sequence_class(catalog.get("mine").ok(), None), "folder");
        assert_eq!(
            sequence_class(catalog.get("kinect").ok(), None),
            "synthetic"
        );
        // rc has no published figure: its paper column would be all dashes, and is left out.
        let mut with_rc = records.to_vec();
        with_rc.push(RunRecord {
            config: "rc".into(),
            ..record("kinect", 0.001)
        });
        let t = table3(
            &with_rc,
            &catalog,
            true,
            &FolderSettings::default(),
            &BTreeMap::new(),
            &BTreeMap::new(),
        );
        let header = t
            .markdown
            .lines()
            .find(|l| l.starts_with("| sequence"))
            .unwrap();
        assert!(
            !header.contains("rigid consensus (paper)") && header.contains("ORB-SLAM2 (paper)"),
            "{header}"
        );
        assert!(
            t.markdown.contains("Left out for want of a single value"),
            "{}",
            t.markdown
        );
    }

    /// Two systems 3 % apart at 1 mm read differently in the Markdown (issue 44: both printed
    /// 0.0010 at 0.1 mm).
    #[test]
    fn millimetre_results_three_percent_apart_are_told_apart() {
        let catalog = Catalog::embedded();
        let mut records: Vec<RunRecord> = (0..3)
            .map(|k| RunRecord {
                seed: k,
                ..record("kinect", 0.00097)
            })
            .collect();
        records.extend((0..3).map(|k| RunRecord {
            seed: k,
            config: "other".into(),
            ..record("kinect", 0.00100)
        }));
        let labels = BTreeMap::from([("other".to_string(), "Other (real)".to_string())]);
        let t = table3(
            &records,
            &catalog,
            false,
            &FolderSettings::default(),
            &labels,
            &BTreeMap::new(),
        );
        let row = t
            .markdown
            .lines()
            .find(|l| l.starts_with("| kinect |"))
            .unwrap();
        assert!(
            row.contains("| 0.970 ± 0.000 |") && row.contains("| 1.000 ± 0.000 |"),
            "{row}"
        );
        assert_eq!(mm_decimals([0.0046]), 2);
        assert_eq!(mm_decimals([0.0123, 0.3]), 1);
        assert_eq!(mm_decimals([0.00004]), 4);
    }

    /// table3.csv is tidy: it loads into numbers equal to the statistics of runs.csv's
    /// records, one row per sequence and system, with ours and external systems labelled as
    /// in every table.
    #[test]
    fn the_tidy_csv_holds_the_statistics_of_the_runs_as_numbers() {
        let catalog = Catalog::embedded();
        let ates = [0.0041, 0.0039, 0.0047, 0.0050];
        let mut records: Vec<RunRecord> = ates
            .iter()
            .enumerate()
            .map(|(k, &a)| RunRecord {
                seed: k as u64,
                fps: 100.0 + k as f64,
                ..record("kinect", a)
            })
            .collect();
        records.push(RunRecord {
            seed: 4,
            failed: true,
            ate_rmse: None,
            ..record("kinect", 0.0)
        });
        let t = table3(
            &records,
            &catalog,
            false,
            &FolderSettings::default(),
            &BTreeMap::new(),
            &BTreeMap::new(),
        );
        let mut rdr = csv::Reader::from_reader(t.csv.as_bytes());
        let h = rdr.headers().unwrap().clone();
        let rows: Vec<csv::StringRecord> = rdr.records().map(Result::unwrap).collect();
        assert_eq!(rows.len(), 1);
        let get = |k: &str| rows[0][h.iter().position(|c| c == k).unwrap()].to_string();
        let f = |k: &str| get(k).parse::<f64>().unwrap();
        let mean = ates.iter().sum::<f64>() / 4.0;
        let std = (ates.iter().map(|a| (a - mean) * (a - mean)).sum::<f64>() / 4.0).sqrt();
        assert_eq!(get("system"), "orb");
        assert_eq!(get("label"), "ORB-SLAM2 (ours)");
        assert_eq!((get("n"), get("failed")), ("5".into(), "1".into()));
        assert_eq!(f("mean_m"), mean);
        assert_eq!(f("std_m"), std);
        assert_eq!(f("median_m"), 0.5 * (0.0041 + 0.0047));
        assert_eq!((f("min_m"), f("max_m")), (0.0039, 0.0050));
        assert_eq!(f("fps"), (100.0 + 101.0 + 102.0 + 103.0 + 100.0) / 5.0);
    }
}
