//! Tables in the paper's layout from a sweep's run records: Table III (mean ATE per sequence
//! and configuration, 'F' for failure, the paper's numbers beside ours), Table I (ATE versus the
//! AVC baseline b), Table IV (frames per second) and the MC-OR threshold grid. Each table is
//! rendered as Markdown and CSV.

use crate::sweep::plan::ConfigKind;
use crate::sweep::store::{FolderSettings, RunRecord};
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
        let (mean, std) = if ok.is_empty() {
            (None, None)
        } else {
            let n = ok.len() as f64;
            let m = ok.iter().sum::<f64>() / n;
            (
                Some(m),
                Some((ok.iter().map(|a| (a - m) * (a - m)).sum::<f64>() / n).sqrt()),
            )
        };
        let fps = runs.iter().map(|r| r.fps).sum::<f64>() / runs.len().max(1) as f64;
        Cell {
            mean,
            std,
            runs: runs.len(),
            failed,
            fps,
        }
    }

    /// Whether the cell reads 'F'.
    pub fn is_failure(&self) -> bool {
        self.mean.is_none() || 2 * self.failed > self.runs
    }

    /// `0.0123 ± 0.0010` (with `(kF)` when some runs failed), or `F`.
    pub fn text(&self) -> String {
        if self.is_failure() {
            return "F".into();
        }
        let mut s = format!(
            "{:.4} ± {:.4}",
            self.mean.unwrap_or(0.0),
            self.std.unwrap_or(0.0)
        );
        if self.failed > 0 {
            let _ = write!(s, " ({}F)", self.failed);
        }
        s
    }
}

fn is_default(r: &RunRecord) -> bool {
    let taus_ok = match (r.tau_mf, r.tau_gf, r.tau_mg) {
        (None, None, None) => true,
        (Some(a), Some(b), Some(c)) => (a, b, c) == DEFAULT_TAUS,
        _ => false,
    };
    taus_ok && r.baseline.is_none_or(|b| b == DEFAULT_BASELINE)
}

/// Sequences in table order: catalog order (easy before hard as the paper groups them), then
/// any other label alphabetically.
fn sequence_order(records: &[RunRecord], catalog: &Catalog) -> Vec<String> {
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

/// A rendered table: Markdown and CSV of the same content.
#[derive(Clone, Debug, Default)]
pub struct Rendered {
    /// Markdown (with a heading and notes).
    pub markdown: String,
    /// CSV.
    pub csv: String,
}

fn render(title: &str, notes: &str, header: &[String], rows: &[Vec<String>]) -> Rendered {
    let mut md = format!("## {title}\n\n");
    let _ = writeln!(md, "| {} |", header.join(" | "));
    let _ = writeln!(
        md,
        "|{}|",
        header.iter().map(|_| "---").collect::<Vec<_>>().join("|")
    );
    for r in rows {
        let _ = writeln!(md, "| {} |", r.join(" | "));
    }
    if !notes.is_empty() {
        let _ = write!(md, "\n{notes}\n");
    }
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record(header);
    for r in rows {
        let _ = w.write_record(r);
    }
    let csv = String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default();
    Rendered { markdown: md, csv }
}

fn paper_text(v: Option<datasets::Ate>) -> String {
    match v {
        None => "-".into(),
        Some(a) => match a.metres() {
            Some(m) => format!("{m:.3}"),
            None => "F".into(),
        },
    }
}

/// Table III: mean ATE RMSE (m) ± std over the runs, per sequence and configuration, at the
/// default parameters; with `paper`, the published numbers beside ours.
pub fn table3(
    records: &[RunRecord],
    catalog: &Catalog,
    paper: bool,
    settings: &FolderSettings,
    labels: &BTreeMap<String, String>,
) -> Rendered {
    let mapping_lag = settings.mapping_lag;
    let kinds: Vec<ConfigKind> = ConfigKind::EVERY
        .into_iter()
        .filter(|k| records.iter().any(|r| r.config == k.name()))
        .collect();
    let systems = external_columns(records, labels);
    let mut header = vec!["sequence".to_string(), "class".to_string()];
    for k in &kinds {
        header.push(format!("{} (ours)", column_name(*k)));
    }
    header.extend(systems.iter().map(|(_, label)| label.clone()));
    if paper {
        for k in &kinds {
            header.push(format!("{} (paper)", column_name(*k)));
        }
    }
    let mut rows = Vec::new();
    for seq in sequence_order(records, catalog) {
        let entry = catalog.get(&seq).ok();
        // A twin prints the paper's figures of the real sequence it imitates.
        let imitated = entry
            .and_then(|e| e.imitates.as_deref())
            .and_then(|name| catalog.get(name).ok());
        let class = match (entry.and_then(|e| e.class), imitated.and_then(|r| r.class)) {
            (Some(Class::Easy), _) => "easy",
            (Some(Class::Hard), _) => "hard",
            (None, Some(Class::Easy)) => "twin of easy",
            (None, Some(Class::Hard)) => "twin of hard",
            (None, None) => "synthetic",
        };
        let mut row = vec![
            entry
                .and_then(|e| e.paper_name.clone())
                .unwrap_or_else(|| seq.clone()),
            class.into(),
        ];
        for k in &kinds {
            let runs: Vec<&RunRecord> = records
                .iter()
                .filter(|r| r.sequence == seq && r.config == k.name() && is_default(r))
                .collect();
            row.push(if runs.is_empty() {
                "-".into()
            } else {
                Cell::of(&runs).text()
            });
        }
        for (name, _) in &systems {
            let runs: Vec<&RunRecord> = records
                .iter()
                .filter(|r| r.sequence == seq && &r.config == name)
                .collect();
            row.push(if runs.is_empty() {
                "-".into()
            } else {
                Cell::of(&runs).text()
            });
        }
        if paper {
            for k in &kinds {
                let p = entry
                    .and_then(|e| e.paper.as_ref())
                    .or_else(|| imitated.and_then(|r| r.paper.as_ref()));
                row.push(match (p, k) {
                    (None, _) => "-".into(),
                    (Some(p), ConfigKind::Orb) => paper_text(p.orb_slam2),
                    (
                        Some(p),
                        ConfigKind::Mcor | ConfigKind::McorFrames | ConfigKind::McorKeyframes,
                    ) => paper_text(p.mcor),
                    (Some(p), ConfigKind::Avc) => paper_text(p.avc),
                    (
                        Some(p),
                        ConfigKind::McorAvc
                        | ConfigKind::McorFramesAvc
                        | ConfigKind::McorKeyframesAvc,
                    ) => paper_text(p.mcor_avc),
                    (Some(_), ConfigKind::Rc) => "-".into(),
                });
            }
        }
        rows.push(row);
    }
    rows.sort_by_key(|r| match r[1].as_str() {
        "easy" => 0,
        "hard" => 1,
        _ => 2,
    });
    let seeds = records
        .iter()
        .map(|r| r.seed)
        .max()
        .map(|m| m + 1)
        .unwrap_or(0);
    let notes = format!(
        "ATE RMSE in metres, mean ± population std over the runs (seeds 0..{}), MC-OR thresholds \
         (tau_MF, tau_GF, tau_MG) = {:?} m, AVC baseline {} m. Association: evaluate_ate.py's (|dt| < 0.02 s, \
         greedy, each stamp once), SE3 Umeyama alignment; EuRoC estimates converted to the body frame. \
         'F': more than half the runs failed (fewer than 80 % of the frames tracked, or no ATE); `(kF)`: k \
         failed runs left out of the mean. {}{}{}",
        seeds.saturating_sub(1),
        DEFAULT_TAUS,
        DEFAULT_BASELINE,
        match mapping_lag {
            0 => "Runs are synchronous and single-threaded: the seed reaches only the RANSAC of \
                  relocalization, so runs that never relocalize agree to the bit."
                .to_string(),
            n => format!(
                "Runs are single-threaded and emulate concurrent local mapping (--mapping-lag {n}): \
                 each keyframe is mapped 0..={n} frames late, drawn from the run's seed, so runs of \
                 one sequence spread as ORB-SLAM2's threads make them spread."
            ),
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
    );
    let notes = match external_notes(records, &systems) {
        n if n.is_empty() => notes,
        n => format!("{notes} {n}"),
    };
    let notes = if settings.synth_without.is_empty() {
        notes
    } else {
        format!(
            "{notes} Synthetic sequences rendered without: {} (--synth-without).",
            settings.synth_without.join(", ")
        )
    };
    render("Table III: ATE RMSE (m)", &notes, &header, &rows)
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
        .map(|n| {
            (
                n.to_string(),
                labels.get(n).cloned().unwrap_or_else(|| n.to_string()),
            )
        })
        .collect()
}

/// What the external systems' columns are and why their failed runs failed.
fn external_notes(records: &[RunRecord], systems: &[(String, String)]) -> String {
    let mut out = Vec::new();
    for (name, label) in systems {
        let mut text = format!(
            "{label}: the external system `{name}` run by the harness on the same files (its threads' own run-to-run spread; keyframes and map points not reported)"
        );
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

pub(crate) fn column_name(k: ConfigKind) -> &'static str {
    match k {
        ConfigKind::Orb => "ORB-SLAM2",
        ConfigKind::Mcor => "w/ MC-OR",
        ConfigKind::Avc => "w/ AVC",
        ConfigKind::McorAvc => "w/ MC-OR+AVC",
        ConfigKind::McorFrames => "w/ MC-OR (every frame)",
        ConfigKind::McorFramesAvc => "w/ MC-OR (every frame)+AVC",
        ConfigKind::McorKeyframes => "w/ MC-OR (keyframes)",
        ConfigKind::McorKeyframesAvc => "w/ MC-OR (keyframes)+AVC",
        ConfigKind::Rc => "noisefree: rigid consensus",
    }
}

/// Table I: ATE (m) versus the AVC baseline b, per sequence, with the baseline's ATE beside.
pub fn table1(records: &[RunRecord], catalog: &Catalog) -> Option<Rendered> {
    let mut baselines: Vec<f64> = records
        .iter()
        .filter(|r| r.config == "avc")
        .filter_map(|r| r.baseline)
        .collect();
    baselines.sort_by(f64::total_cmp);
    baselines.dedup();
    if baselines.len() < 2 {
        return None;
    }
    let mut header = vec!["sequence".to_string(), "ORB-SLAM2".to_string()];
    header.extend(baselines.iter().map(|b| format!("AVC b={b}")));
    let mut rows = Vec::new();
    for seq in sequence_order(records, catalog) {
        let orb: Vec<&RunRecord> = records
            .iter()
            .filter(|r| r.sequence == seq && r.config == "orb")
            .collect();
        let mut row = vec![
            seq.clone(),
            if orb.is_empty() {
                "-".into()
            } else {
                Cell::of(&orb).text()
            },
        ];
        for b in &baselines {
            let runs: Vec<&RunRecord> = records
                .iter()
                .filter(|r| r.sequence == seq && r.config == "avc" && r.baseline == Some(*b))
                .collect();
            row.push(if runs.is_empty() {
                "-".into()
            } else {
                Cell::of(&runs).text()
            });
        }
        rows.push(row);
    }
    Some(render(
        "Table I: ATE RMSE (m) versus the AVC baseline b (m)",
        "",
        &header,
        &rows,
    ))
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
    header.extend(kinds.iter().map(|k| column_name(*k).to_string()));
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
            let runs: Vec<&RunRecord> = records
                .iter()
                .filter(|r| r.sequence == seq && r.config == k.name() && is_default(r))
                .collect();
            row.push(if runs.is_empty() {
                "-".into()
            } else {
                format!("{:.1}", Cell::of(&runs).fps)
            });
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
        "Wall-clock frames per second of one run on one core, averaged over the runs; runs of a sweep \
         share the machine's cores, so compare columns within one sweep."
            .to_string()
    } else {
        "Wall-clock frames per second of one run, averaged over the runs; ours on one core. An \
         external system's figure is its whole process from start to exit (loading its vocabulary, \
         and any real-time pacing of its example program, included), with the cores it kept busy \
         on average (CPU time / wall time) and its peak resident memory; runs of a sweep share \
         the machine's cores, so compare columns within one sweep."
            .to_string()
    };
    render(
        "Table IV: frames per second (single thread, whole pipeline)",
        &notes,
        &header,
        &rows,
    )
}

/// Loops closed per sequence and configuration: the total over the runs and in how many runs
/// at least one closed, so a false loop on a sequence without a revisit shows at a glance.
/// `None` when no run recorded a loop count (loop closing off, or records from before it).
pub fn loops_table(records: &[RunRecord], catalog: &Catalog) -> Option<Rendered> {
    if !records.iter().any(|r| r.loops.is_some()) {
        return None;
    }
    let kinds: Vec<ConfigKind> = ConfigKind::EVERY
        .into_iter()
        .filter(|k| records.iter().any(|r| r.config == k.name()))
        .collect();
    let mut header = vec!["sequence".to_string()];
    header.extend(kinds.iter().map(|k| column_name(*k).to_string()));
    let mut rows = Vec::new();
    for seq in sequence_order(records, catalog) {
        let mut row = vec![seq.clone()];
        for k in &kinds {
            let runs: Vec<&RunRecord> = records
                .iter()
                .filter(|r| r.sequence == seq && r.config == k.name() && is_default(r))
                .collect();
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
    Some(render(
        "Loops closed",
        "Loops closed in all runs together, and in how many runs at least one closed. On a \
         sequence that never returns to a place it has seen, every loop is a false one.",
        &header,
        &rows,
    ))
}

/// The MC-OR threshold grid: mean ATE per (tau_MF, tau_GF, tau_MG) and sequence, the best triple
/// per sequence and overall (lowest mean over sequences of the per-sequence mean ATE).
pub fn threshold_grid(records: &[RunRecord], catalog: &Catalog) -> Option<Rendered> {
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
    for t in &triples {
        let mut row = vec![t.0.to_string(), t.1.to_string(), t.2.to_string()];
        let mut means = Vec::new();
        for s in &seqs {
            let runs: Vec<&RunRecord> = records
                .iter()
                .filter(|r| {
                    &r.sequence == s
                        && r.config == "mcor"
                        && (r.tau_mf, r.tau_gf, r.tau_mg) == (Some(t.0), Some(t.1), Some(t.2))
                })
                .collect();
            let c = Cell::of(&runs);
            row.push(if runs.is_empty() {
                "-".into()
            } else {
                c.text()
            });
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
            row.push(format!("{m:.4}"));
            if best_overall.is_none_or(|(b, _)| m < b) {
                best_overall = Some((m, *t));
            }
        } else {
            row.push("F".into());
        }
        rows.push(row);
    }
    let mut notes = String::from("Best triple per sequence: ");
    notes.push_str(
        &best_per_seq
            .iter()
            .map(|(s, (m, t))| format!("{s} {t:?} ({m:.4} m)"))
            .collect::<Vec<_>>()
            .join("; "),
    );
    if let Some((m, t)) = best_overall {
        let _ = write!(notes, ". Best overall: {t:?} (mean {m:.4} m).");
    }
    Some(render(
        "MC-OR threshold grid: ATE RMSE (m)",
        &notes,
        &header,
        &rows,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::store::RunRecord;

    fn record(sequence: &str, ate: f64) -> RunRecord {
        RunRecord {
            sequence: sequence.into(),
            config: "orb".into(),
            tau_mf: None,
            tau_gf: None,
            tau_mg: None,
            baseline: None,
            seed: 0,
            ate_rmse: Some(ate),
            failed: false,
            frames: 700,
            tracked: 700,
            keyframes: Some(20),
            map_points: Some(1500),
            mean_inliers: Some(300.0),
            mean_outliers: Some(100.0),
            fps: 100.0,
            wall_s: 7.0,
            synth_seed: Some(0),
            loops: Some(0),
            reason: None,
            peak_rss_mb: None,
            cpu_s: None,
            perturbation: None,
            perturb_family: None,
            perturb_level: None,
            perturb_seed: None,
        }
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
            twin.contains("twin of hard") && twin.contains("0.215"),
            "{twin}"
        );
        let kinect = line("kinect");
        assert!(
            kinect.contains("synthetic") && !kinect.contains("0.215"),
            "{kinect}"
        );
    }
}
