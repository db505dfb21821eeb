//! A sweep folder written as a report: every table of its run records (Markdown and tidy CSV
//! beside the records), the figures, and an index (`README.md`) that links every table and shows
//! every figure, so the folder reads as a report on GitHub or in any Markdown viewer.

use crate::report::markdown::Rendered;
use crate::report::tables::{loops_table, table1, table3, table4, threshold_grid};
use crate::store::{load_dir, settings_of};
use anyhow::Result;
use atomic_file::write as write_atomic;
use datasets::Catalog;
use std::path::{Path, PathBuf};

fn write_table(dir: &Path, stem: &str, t: &Rendered) -> Result<()> {
    write_atomic(&dir.join(format!("{stem}.md")), t.markdown.as_bytes())?;
    write_atomic(&dir.join(format!("{stem}.csv")), t.csv.as_bytes())?;
    Ok(())
}

/// Writes every table of one sweep folder; returns the combined Markdown.
pub fn tables_for(dir: &Path, catalog: &Catalog, paper: bool) -> Result<String> {
    let all_records = load_dir(dir)?;
    // A perturbation sweep: the paper's tables from its unperturbed point (or, with
    // --perturb-with and no axis, from its one point), the resilience tables from the rest.
    let perturbed = all_records.iter().any(|r| r.perturbation.is_some());
    let records: Vec<_> = if perturbed {
        let zero: Vec<_> = all_records
            .iter()
            .filter(|r| r.perturbation.is_none() || r.perturb_family.is_none())
            .cloned()
            .collect();
        zero
    } else {
        all_records.clone()
    };
    let mut all = format!(
        "# Tables of {}\n\n{} runs recorded.\n\n",
        dir.display(),
        records.len()
    );
    let defs = crate::systems::systems_of(dir)?;
    let vocabularies: std::collections::BTreeMap<String, String> = defs
        .iter()
        .map(|(n, d)| (n.clone(), crate::systems::vocabulary_note(d)))
        .collect();
    let labels: std::collections::BTreeMap<String, String> = defs
        .into_iter()
        .map(|(n, d)| (n.clone(), d.label.unwrap_or(n)))
        .collect();
    let mut index: Vec<(String, String)> = Vec::new();
    let t3 = table3(
        &records,
        catalog,
        paper,
        &settings_of(dir)?,
        &labels,
        &vocabularies,
    );
    write_table(dir, "table3", &t3)?;
    index.push((
        "table3".into(),
        "Table III: ATE RMSE per sequence and system".into(),
    ));
    all.push_str(&t3.markdown);
    if let Some(t1) = table1(&records, catalog, &labels) {
        write_table(dir, "table1", &t1)?;
        index.push((
            "table1".into(),
            "Table I: ATE against AVC's baseline b".into(),
        ));
        all.push('\n');
        all.push_str(&t1.markdown);
    }
    if let Some(t1) = crate::report::tables::table1_camera(&records, catalog, paper, &labels) {
        write_table(dir, "table1-camera", &t1)?;
        index.push((
            "table1-camera".into(),
            "Table I under b_role = \"camera\": ATE against b as the camera's baseline".into(),
        ));
        all.push('\n');
        all.push_str(&t1.markdown);
    }
    if let Some(v) = crate::report::versus::versus_baseline(&all_records, catalog, paper, &labels) {
        write_table(dir, "versus-baseline", &v)?;
        index.push((
            "versus-baseline".into(),
            "each system against the baseline: intervals, p-values, Holm's correction".into(),
        ));
        all.push('\n');
        all.push_str(&v.markdown);
        let rows = crate::report::findings::read_versus(dir)?;
        if let Some(r) = crate::report::readings::readings_table(&rows, catalog, &labels) {
            write_table(dir, "readings", &r)?;
            index.push((
                "readings".into(),
                "the readings: each technique under every reading against the baseline".into(),
            ));
            all.push('\n');
            all.push_str(&r.markdown);
        }
    }
    let t4 = table4(&records, catalog, &labels);
    write_table(dir, "table4", &t4)?;
    index.push(("table4".into(), "Table IV: frames per second".into()));
    all.push('\n');
    all.push_str(&t4.markdown);
    if let Some(v) = crate::report::fps::fps_versus(&records, catalog, &labels) {
        write_table(dir, "table4-versus", &v)?;
        index.push((
            "table4-versus".into(),
            "Table IV: each system's frames per second against the baseline, with intervals".into(),
        ));
        all.push('\n');
        all.push_str(&v.markdown);
    }
    if let Some(l) = loops_table(&records, catalog, &labels) {
        write_table(dir, "loops", &l)?;
        index.push((
            "loops".into(),
            "loops closed per sequence and system".into(),
        ));
        all.push('\n');
        all.push_str(&l.markdown);
    }
    if let Some(g) = threshold_grid(&records, catalog, &labels) {
        write_table(dir, "thresholds", &g)?;
        index.push(("thresholds".into(), "MC-OR's threshold grid".into()));
        all.push('\n');
        all.push_str(&g.markdown);
    }
    if perturbed {
        let curves = crate::report::resilience::curves(&all_records, &labels);
        for (family, list) in &curves {
            let t = crate::report::resilience::table(family, list);
            write_table(dir, &format!("resilience-{family}"), &t)?;
            index.push((
                format!("resilience-{family}"),
                format!("ATE against {family}, and each system's breaking level"),
            ));
            all.push('\n');
            all.push_str(&t.markdown);
            resilience_figures(dir, family, list)?;
        }
        let paper = |seq: &str| {
            let row = catalog.get(seq).ok()?.imitates.as_deref()?;
            let ate = catalog.get(row).ok()?.paper.as_ref()?.orb_slam2?.metres()?;
            Some((row.to_string(), ate))
        };
        for (chain, t) in crate::report::ablation::tables(&curves, paper) {
            let stem = format!("ablation-{}", chain.name());
            write_table(dir, &stem, &t)?;
            index.push((
                stem,
                format!(
                    "what each member of {chain} accounts for: alone, and the chain without it"
                ),
            ));
            all.push('\n');
            all.push_str(&t.markdown);
        }
    }
    write_atomic(&dir.join("tables.md"), all.as_bytes())?;
    figures_for(dir, &records, &labels, paper.then_some(catalog))?;
    write_index(dir, &all_records, &labels, &vocabularies, &index)?;
    Ok(all)
}

/// The first line of a folder index `noisefree table` writes; a README.md without it is a
/// person's and is never overwritten.
const INDEX_MARK: &str = "<!-- written by `noisefree table`: regenerate it, do not edit it -->";

/// What a figure shows, from its file stem; `None` for a file `noisefree table` did not draw.
fn figure_caption(stem: &str) -> Option<String> {
    if stem == "ate_spread" {
        return Some(
            "ATE RMSE of every run (dots) and the mean (bar) per sequence and system, log scale"
                .into(),
        );
    }
    if stem == "rc_vs_baseline" {
        return Some(format!(
            "rc's ATE of each run over the baseline's mean per sequence, with issue 33's \
             {:.0} % band",
            RC_TOLERANCE * 100.0
        ));
    }
    if let Some(seq) = stem.strip_prefix("trajectory_") {
        return Some(format!(
            "{seq}: top view of seed 0 of each system, aligned to the ground truth (black), \
             its ATE in the legend"
        ));
    }
    if let Some(seq) = stem.strip_prefix("outlier_ratio_") {
        return Some(format!(
            "{seq}: share of the matches rejected as outliers per frame, seed 0 (ours only: \
             external systems do not report it)"
        ));
    }
    let rest = stem.strip_prefix("resilience_")?;
    let (family, seq) = perturb::Family::ALL
        .iter()
        .map(|f| f.name())
        .filter_map(|f| Some((f, rest.strip_prefix(f)?.strip_prefix('_')?)))
        .next()?;
    Some(format!(
        "{seq}: ATE against the {family} level per system, its breaking level in the legend"
    ))
}

/// Writes `dir/README.md`: what the folder holds (runs, sequences, systems and their
/// vocabularies), a link to every table and every figure shown with a line on what it shows.
fn write_index(
    dir: &Path,
    records: &[crate::store::RunRecord],
    labels: &std::collections::BTreeMap<String, String>,
    vocabularies: &std::collections::BTreeMap<String, String>,
    tables: &[(String, String)],
) -> Result<()> {
    use std::fmt::Write as _;
    let path = dir.join("README.md");
    if let Ok(old) = std::fs::read_to_string(&path) {
        if !old.starts_with(INDEX_MARK) {
            eprintln!(
                "{}: not written by noisefree table; left as it is (no index written)",
                path.display()
            );
            return Ok(());
        }
    }
    let name = dir
        .canonicalize()
        .ok()
        .and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| dir.display().to_string());
    let mut sequences: Vec<&str> = records.iter().map(|r| r.sequence.as_str()).collect();
    sequences.sort();
    sequences.dedup();
    let mut systems: Vec<&str> = records.iter().map(|r| r.config.as_str()).collect();
    // Our kinds in their order, then readings and external systems by name; each once.
    systems.sort_by_key(|n| {
        let kind = crate::columns::ConfigKind::parse(n).map_or(usize::MAX, |k| {
            crate::columns::ConfigKind::EVERY
                .iter()
                .position(|e| *e == k)
                .unwrap_or(0)
        });
        (kind, *n)
    });
    systems.dedup();
    let mut md = format!("{INDEX_MARK}\n# {name}\n\n");
    let points: std::collections::BTreeSet<&str> = records
        .iter()
        .filter_map(|r| r.perturbation.as_deref())
        .collect();
    let perturbed = if points.is_empty() {
        String::new()
    } else if points.contains("none") {
        format!(
            " at {} perturbation points (the unperturbed one and {} levels; `perturbation` in runs.csv)",
            points.len(),
            points.len() - 1
        )
    } else {
        format!(
            " under {} fixed perturbation{} (`--perturb-with`; `perturbation` in runs.csv)",
            points.len(),
            if points.len() == 1 { "" } else { "s" }
        )
    };
    let _ = writeln!(
        md,
        "{} runs of {} on {}{perturbed} (`runs.csv`: one line per run).\n",
        records.len(),
        systems
            .iter()
            .map(|s| format!("**{}**", crate::report::markdown::system_label(s, labels)))
            .collect::<Vec<_>>()
            .join(", "),
        sequences.join(", ")
    );
    if let Some(c) = crate::planned::completeness(dir, records)? {
        if !c.is_complete() {
            let _ = writeln!(
                md,
                "**Incomplete:** {}. The tables below cover the recorded runs only; the sweep's \
                 command, run again, resumes it (`planned-runs.txt`: the runs asked for).\n",
                c.sentence()
            );
        }
    }
    let cost = crate::cost::load_dir(dir)?;
    if !cost.is_empty() {
        let total = crate::cost::CostTotal::of(&cost);
        let _ = writeln!(md, "{}\n", total.sentence(records.len()));
    }
    let settings = crate::store::settings_of(dir)?;
    let _ = write!(md, "Vocabularies: ours {}", settings.vocabulary);
    for (n, v) in vocabularies {
        if systems.contains(&n.as_str()) {
            let _ = write!(
                md,
                "; {} {v}",
                crate::report::markdown::system_label(n, labels)
            );
        }
    }
    md.push_str(" (`sweep-settings.toml`, `systems.toml`).\n\n## Tables\n\n");
    md.push_str(
        "Each as Markdown and as a tidy CSV (one row per sequence and system: n, failed, mean, \
         std, median, min, max in metres, fps); all of them in [tables.md](tables.md).\n\n",
    );
    for (stem, what) in tables {
        let _ = writeln!(md, "- [{what}]({stem}.md) ([csv]({stem}.csv))");
    }
    let mut figures: Vec<String> = std::fs::read_dir(dir.join("figures"))
        .map(|it| {
            it.filter_map(|e| e.ok())
                .filter_map(|e| e.file_name().to_str().map(str::to_string))
                .filter_map(|n| n.strip_suffix(".png").map(str::to_string))
                .collect()
        })
        .unwrap_or_default();
    figures.sort_by_key(|f| {
        (
            [
                "ate_spread",
                "rc_vs_baseline",
                "trajectory_",
                "outlier_ratio_",
                "resilience_",
            ]
            .iter()
            .position(|p| f.starts_with(p))
            .unwrap_or(usize::MAX),
            f.clone(),
        )
    });
    let shown: Vec<(String, String)> = figures
        .into_iter()
        .filter_map(|f| Some((figure_caption(&f)?, f)))
        .collect();
    if !shown.is_empty() {
        md.push_str("\n## Figures\n\n(PNG shown; each also as SVG beside it.)\n\n");
        for (caption, f) in shown {
            let _ = writeln!(
                md,
                "**{caption}** ([svg](figures/{f}.svg))\n\n![{f}](figures/{f}.png)\n"
            );
        }
    }
    write_atomic(&path, md.as_bytes())?;
    Ok(())
}

/// One figure per sequence of a family's curves: `figures/resilience_<family>_<sequence>`.
fn resilience_figures(
    dir: &Path,
    family: &str,
    curves: &[crate::report::resilience::Curve],
) -> Result<()> {
    let mut sequences: Vec<&str> = curves.iter().map(|c| c.sequence.as_str()).collect();
    sequences.dedup();
    let unit = perturb::Family::parse(family).map_or("", perturb::Family::unit);
    for seq in sequences {
        let lines: Vec<crate::report::figures::ResilienceCurve> = curves
            .iter()
            .filter(|c| c.sequence == seq)
            .map(|c| {
                let label = match c.breaking_level() {
                    Some(b) => format!("{} (breaks at {b})", c.label),
                    None => c.label.clone(),
                };
                let pts = c
                    .levels
                    .iter()
                    .map(|l| {
                        let v = (!l.is_failure()).then(|| {
                            (
                                l.mean().unwrap_or(0.0),
                                l.ates.first().copied().unwrap_or(0.0),
                                l.ates.last().copied().unwrap_or(0.0),
                            )
                        });
                        (l.level, v)
                    })
                    .collect();
                (label, pts)
            })
            .collect();
        crate::report::figures::resilience(
            &dir.join("figures")
                .join(format!("resilience_{family}_{seq}")),
            &format!("{seq}: ATE against {family}"),
            &format!("{family} level ({unit}); x: more than half the runs failed"),
            &lines,
        )?;
    }
    Ok(())
}

/// Folders of `dir`, sorted by name.
fn subdirs(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|it| {
            it.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_dir())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// (frame index, outliers / (inliers + outliers)) from a per-frame CSV of the system.
fn outlier_ratio(path: &Path) -> Result<Vec<(f64, f64)>> {
    let mut rdr = csv::Reader::from_path(path)?;
    let h = rdr.headers()?.clone();
    let col = |name: &str| {
        h.iter()
            .position(|c| c == name)
            .ok_or_else(|| anyhow::anyhow!("{}: no column {name}", path.display()))
    };
    let (ci, co) = (col("n_inliers")?, col("n_outliers")?);
    let mut out = Vec::new();
    for (i, r) in rdr.records().enumerate() {
        let r = r?;
        let inl: f64 = r.get(ci).unwrap_or("0").parse().unwrap_or(0.0);
        let outl: f64 = r.get(co).unwrap_or("0").parse().unwrap_or(0.0);
        if inl + outl > 0.0 {
            out.push((i as f64, outl / (inl + outl)));
        }
    }
    Ok(out)
}

/// Issue 33's static-scene tolerance of rc against the baseline (3 % of the mean ATE), drawn as a
/// band in `rc_vs_baseline`.
const RC_TOLERANCE: f64 = 0.03;

/// Writes the figures of a sweep folder into `<dir>/figures/`: the ATE spread over runs
/// (Fig. 9), rc's ATE relative to the baseline's where both ran, and per sequence the top-view trajectories of seed 0 aligned to the ground truth
/// (Fig. 1) and the outlier ratio over frames (Fig. 8).
pub fn figures_for(
    dir: &Path,
    records: &[crate::store::RunRecord],
    labels: &std::collections::BTreeMap<String, String>,
    catalog: Option<&Catalog>,
) -> Result<()> {
    let fig = dir.join("figures");
    spread_figures(&fig, records, labels, catalog)?;
    trajectory_figures(&fig, dir, records, labels)
}

/// The figures over runs: the ATE spread per sequence and system (Fig. 9, the paper's figure
/// marked where it has one), and rc's ATE relative to the baseline's where both ran.
fn spread_figures(
    fig: &Path,
    records: &[crate::store::RunRecord],
    labels: &std::collections::BTreeMap<String, String>,
    catalog: Option<&Catalog>,
) -> Result<()> {
    use crate::columns::ConfigKind;
    use crate::report::markdown::system_label;
    // Every system is drawn under its heading in the tables; groups are keyed by configuration
    // here and take their headings when drawn.
    let mut groups: Vec<(String, String, Vec<f64>)> = Vec::new();
    for r in records.iter().filter(|r| !r.failed) {
        let Some(a) = r.ate_rmse else { continue };
        let config = r.config.clone();
        match groups
            .iter_mut()
            .find(|g| g.0 == r.sequence && g.1 == config)
        {
            Some(g) => g.2.push(a),
            None => groups.push((r.sequence.clone(), config, vec![a])),
        }
    }
    // rc against the baseline, where a folder has both: issue 33's tolerance band.
    let relative: Vec<crate::report::figures::RelativeAte> = groups
        .iter()
        .filter(|g| g.1 == "rc")
        .filter_map(|g| {
            let base = groups.iter().find(|b| b.0 == g.0 && b.1 == "orb")?;
            Some(crate::report::figures::RelativeAte {
                sequence: g.0.clone(),
                baseline_mean: base.2.iter().sum::<f64>() / base.2.len() as f64,
                runs: g.2.clone(),
            })
        })
        .collect();
    if !relative.is_empty() {
        crate::report::figures::relative_ate(
            &fig.join("rc_vs_baseline"),
            "rc against the baseline: ATE of each run / baseline's mean",
            "rc",
            RC_TOLERANCE,
            &relative,
        )?;
    }
    if !groups.is_empty() {
        let order = |c: &str| {
            ConfigKind::parse(c).map_or(usize::MAX, |k| {
                ConfigKind::EVERY.iter().position(|e| *e == k).unwrap_or(0)
            })
        };
        let mut sorted = groups.clone();
        sorted.sort_by(|a, b| order(&a.1).cmp(&order(&b.1)).then(a.1.cmp(&b.1)));
        let mut named: Vec<crate::report::figures::SpreadGroup> = sorted
            .into_iter()
            .map(
                |(sequence, config, ates)| crate::report::figures::SpreadGroup {
                    paper: catalog.and_then(|c| {
                        crate::report::versus::paper_figures(c, &sequence, &config).map(|p| p.0)
                    }),
                    label: system_label(&config, labels),
                    sequence,
                    config,
                    ates,
                },
            )
            .collect();
        // Sequences keep the order of the records.
        let seq_order: Vec<&String> = {
            let mut v: Vec<&String> = Vec::new();
            for g in &groups {
                if !v.contains(&&g.0) {
                    v.push(&g.0);
                }
            }
            v
        };
        named.sort_by_key(|g| seq_order.iter().position(|s| **s == g.sequence));
        crate::report::figures::ate_spread(
            &fig.join("ate_spread"),
            "ATE RMSE over seeded runs",
            &named,
        )?;
    }
    Ok(())
}

/// Per sequence, from seed 0's files: the top-view trajectories aligned to the ground truth
/// (Fig. 1) and the outlier ratio over frames (Fig. 8), one colour and heading per system.
fn trajectory_figures(
    fig: &Path,
    dir: &Path,
    records: &[crate::store::RunRecord],
    labels: &std::collections::BTreeMap<String, String>,
) -> Result<()> {
    use crate::report::markdown::system_label;
    // Trajectory folders are named by configuration with '+' as '-'.
    let configs: Vec<&str> = {
        let mut v: Vec<&str> = records.iter().map(|r| r.config.as_str()).collect();
        v.sort();
        v.dedup();
        v
    };
    let of_tag = |tag: &str| config_of_tag(tag, &configs);
    let heading = |tag: &str| -> String {
        match of_tag(tag) {
            Some((c, p)) if p.is_empty() => system_label(c, labels),
            Some((c, p)) => format!("{}, {p}", system_label(c, labels)),
            None => tag.to_string(),
        }
    };
    let colour =
        |tag: &str| crate::report::figures::system_colour(of_tag(tag).map_or(tag, |(c, _)| c));
    let traj_root = dir.join("trajectories");
    for seq_dir in subdirs(&traj_root) {
        let seq = seq_dir
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let gt = ate_eval::io::read_tum(&seq_dir.join("groundtruth.txt")).ok();
        let mut curves = Vec::new();
        let mut ratios = Vec::new();
        for cfg_dir in subdirs(&seq_dir) {
            let tag = cfg_dir
                .file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            if let (Some(gt), Ok(est)) = (&gt, ate_eval::io::read_tum(&cfg_dir.join("seed0.txt"))) {
                if let Ok(a) = ate_eval::evaluate_ate(gt, &est, &ate_eval::AteOptions::default()) {
                    curves.push((
                        heading(&tag),
                        a.stats.rmse,
                        est.transformed(a.alignment.scale, &a.alignment.rt),
                        colour(&tag),
                    ));
                }
            }
            if let Ok(r) = outlier_ratio(&cfg_dir.join("frames_seed0.csv")) {
                ratios.push((heading(&tag), r, colour(&tag)));
            }
        }
        // Legends in millimetres, with the digits that tell the curves apart.
        let d = crate::report::tables::mm_decimals(curves.iter().map(|c| c.1));
        let colours: Vec<_> = curves.iter().map(|c| c.3).collect();
        let curves: Vec<(String, ate_eval::Trajectory)> = curves
            .into_iter()
            .map(|(name, rmse, t, _)| (format!("{name} (ATE {:.d$} mm)", rmse * 1e3), t))
            .collect();
        if let (Some(gt), false) = (&gt, curves.is_empty()) {
            crate::report::figures::trajectories(
                &fig.join(format!("trajectory_{seq}")),
                &format!("{seq}: top view, seed 0"),
                gt,
                &curves,
                &colours,
            )?;
        }
        if !ratios.is_empty() {
            let colours: Vec<_> = ratios.iter().map(|r| r.2).collect();
            let ratios: Vec<(String, Vec<(f64, f64)>)> =
                ratios.into_iter().map(|(n, r, _)| (n, r)).collect();
            crate::report::figures::per_frame(
                &fig.join(format!("outlier_ratio_{seq}")),
                &format!("{seq}: outliers / matches per frame, seed 0"),
                "outlier ratio",
                &ratios,
                &colours,
            )?;
        }
    }
    Ok(())
}

/// The configuration of `configs` whose trajectories' folder is `tag`, with the parameters the
/// tag adds, in words: the tag is the configuration's (`sweep::job::job_tag`) with MC-OR's
/// thresholds (`_t0.7-0.7-0.5`) or AVC's b (`_b0.09`) where they were swept, read back so a
/// figure's legend never shows the key.
fn config_of_tag<'a>(tag: &str, configs: &[&'a str]) -> Option<(&'a str, String)> {
    configs.iter().find_map(|c| {
        let key = c
            .replace('+', "-")
            .replace(':', "_")
            .replace(['=', '/'], "-");
        let rest = tag.strip_prefix(key.as_str())?;
        let number = |x: &str| x.parse::<f64>().is_ok();
        let params: Option<Vec<String>> = rest
            .split('_')
            .skip(1)
            .map(|p| match (p.strip_prefix('t'), p.strip_prefix('b')) {
                (Some(t), _) if t.split('-').count() == 3 && t.split('-').all(number) => {
                    Some(format!("tau {} m", t.replace('-', "/")))
                }
                (_, Some(b)) if number(b) => Some(format!("b = {b} m")),
                _ => None,
            })
            .collect();
        (rest.is_empty() || rest.starts_with('_'))
            .then_some(())
            .and(params)
            .map(|p| (*c, p.join(", ")))
    })
}

#[cfg(test)]
mod tag_tests {
    use super::config_of_tag;

    #[test]
    fn a_trajectory_folder_reads_back_as_its_configuration_and_parameters() {
        let configs = ["avc", "mcor", "mcor+avc", "orb", "orb:b_role=camera"];
        assert_eq!(
            config_of_tag("avc_b0.09", &configs),
            Some(("avc", "b = 0.09 m".into()))
        );
        assert_eq!(
            config_of_tag("mcor_t0.7-0.7-0.5", &configs),
            Some(("mcor", "tau 0.7/0.7/0.5 m".into()))
        );
        assert_eq!(
            config_of_tag("mcor-avc", &configs),
            Some(("mcor+avc", String::new()))
        );
        assert_eq!(
            config_of_tag("orb_b_role-camera_b0.05", &configs),
            Some(("orb:b_role=camera", "b = 0.05 m".into()))
        );
        assert_eq!(config_of_tag("orbslam3", &configs), None);
    }
}
